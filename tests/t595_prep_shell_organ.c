// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A hollow organ as a shell (docs/organs.md, "Shell organs"): box A fixed,
// a sphere B of radius 10 mm 5 mm from it, a "shell" with a 1 mm wall and
// frames 4 mm apart, the tissue between them:
//  - B's own frames lie on its surface, its wall's samples add up to about
//    its area x thickness, and the tissue's frames on B are the wall's too
//    (coupled to B, weighed on by B's samples);
//  - the wall takes the section's plane-stress moduli (a material of its
//    own), and its hold region fixes the frames in it;
//  - hanging from A under gravity, the static solve converges and B sags;
//  - an open bowl (B's lower half, frames 2.5 mm apart) held along its rim:
//    no wall triangle stands across the surface at the rim (8 did before
//    prep dropped them, 6 with gradients over 5 / spacing), and each wall
//    sample's gradients give a linear field along its plane its slope;
//  - the same bowl with samples at a third of the frame spacing: 9 points
//    per triangle, the same volume, each point's gradients its own;
//  - a cube's wall is built (its edges are no sign of a too-thick wall);
//  - every refusal is one line naming the key: a wall not thinner than its
//    frame spacing, a wall thicker than the organ (a 2 mm slab), a sample
//    spacing out of range, a volume's key, shell keys on another model.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "prep_fixture.h"

#define PI 3.14159265358979323846
#define RADIUS 0.01
static const double centre[3] = {0.015, 0, 0};

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 5, \"gravity\": [0, 0, -9.81],\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3},\n"
    "               \"wall\": {\"youngs_modulus\": 30000, \"poisson_ratio\": 0.45}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"%s\", %s}],\n"
    " \"tissues\": [{\"name\": \"t\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008, \"material\": \"soft\",\n"
    "               \"frame_spacing\": 0.003, \"sample_spacing\": 0.0015}]}\n";

static const char shell[] =
    "\"model\": \"shell\", \"material\": \"wall\", \"thickness\": 0.001, \"frame_spacing\": 0.004";

// An icosphere of RADIUS about centre, refined 3 times (1280 triangles).
static int write_sphere(const char *dir, const char *name) {
  enum { MAXV = 700, MAXT = 1280 };
  static double v[3 * MAXV];
  static int t[3 * MAXT], t2[3 * MAXT];
  const double g = (1 + sqrt(5.0)) / 2;
  const double v0[12][3] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                            {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  const int t0[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                         {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                         {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  int nv = 12, nt = 20;
  for (int i = 0; i < 12; ++i)
    for (int r = 0; r < 3; ++r) v[3 * i + r] = v0[i][r];
  for (int k = 0; k < 20; ++k)
    for (int r = 0; r < 3; ++r) t[3 * k + r] = t0[k][r];
  for (int level = 0; level < 3; ++level) {
    int n2 = 0;
    for (int k = 0; k < nt; ++k) {
      int mid[3];
      for (int e = 0; e < 3; ++e) {
        const int a = t[3 * k + e], b = t[3 * k + (e + 1) % 3];
        double p[3];
        for (int r = 0; r < 3; ++r) p[r] = 0.5 * (v[3 * a + r] + v[3 * b + r]);
        int found = -1; // midpoints are shared by two triangles: look them up
        for (int i = 0; i < nv && found < 0; ++i)
          if (fabs(v[3 * i] - p[0]) + fabs(v[3 * i + 1] - p[1]) + fabs(v[3 * i + 2] - p[2]) < 1e-12) found = i;
        if (found < 0) {
          memcpy(v + 3 * nv, p, sizeof p);
          found = nv++;
        }
        mid[e] = found;
      }
      const int c[4][3] = {{t[3 * k], mid[0], mid[2]}, {mid[0], t[3 * k + 1], mid[1]},
                           {mid[2], mid[1], t[3 * k + 2]}, {mid[0], mid[1], mid[2]}};
      for (int j = 0; j < 4; ++j, ++n2)
        for (int r = 0; r < 3; ++r) t2[3 * n2 + r] = c[j][r];
    }
    nt = n2;
    memcpy(t, t2, 3 * sizeof(int) * (size_t)nt);
  }
  static char text[65536];
  int n = 0;
  for (int i = 0; i < nv; ++i) {
    const double len = sqrt(v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] + v[3 * i + 2] * v[3 * i + 2]);
    n += snprintf(text + n, sizeof text - (size_t)n, "v %.9f %.9f %.9f\n", centre[0] + RADIUS * v[3 * i] / len,
                  centre[1] + RADIUS * v[3 * i + 1] / len, centre[2] + RADIUS * v[3 * i + 2] / len);
  }
  for (int k = 0; k < nt; ++k)
    n += snprintf(text + n, sizeof text - (size_t)n, "f %d %d %d\n", t[3 * k] + 1, t[3 * k + 1] + 1, t[3 * k + 2] + 1);
  return fixture_write(dir, name, text);
}

// The lower half of a sphere of RADIUS about centre, open along its rim
// (the circle z = centre z): RINGS rings of SEGMENTS vertices from the rim
// down, then the bottom.
static int write_bowl(const char *dir, const char *name) {
  enum { RINGS = 12, SEGMENTS = 48 };
  static char text[65536];
  int n = 0;
  for (int i = 0; i < RINGS; ++i)
    for (int j = 0; j < SEGMENTS; ++j) {
      const double polar = 0.5 * PI * (1 + (double)i / RINGS), azimuth = 2 * PI * j / SEGMENTS;
      n += snprintf(text + n, sizeof text - (size_t)n, "v %.9f %.9f %.9f\n",
                    centre[0] + RADIUS * sin(polar) * cos(azimuth), centre[1] + RADIUS * sin(polar) * sin(azimuth),
                    centre[2] + RADIUS * cos(polar));
    }
  n += snprintf(text + n, sizeof text - (size_t)n, "v %.9f %.9f %.9f\n", centre[0], centre[1], centre[2] - RADIUS);
  for (int i = 0; i < RINGS; ++i)
    for (int j = 0; j < SEGMENTS; ++j) { // outward: seen from below the bowl, counter-clockwise
      const int a = 1 + i * SEGMENTS + j, b = 1 + i * SEGMENTS + (j + 1) % SEGMENTS;
      if (i == RINGS - 1) {
        n += snprintf(text + n, sizeof text - (size_t)n, "f %d %d %d\n", a, 1 + RINGS * SEGMENTS, b);
        continue;
      }
      const int c = a + SEGMENTS, d = b + SEGMENTS;
      n += snprintf(text + n, sizeof text - (size_t)n, "f %d %d %d\nf %d %d %d\n", a, c, d, a, d, b);
    }
  return fixture_write(dir, name, text);
}

static int write_scene(const char *dir, const char *mesh, const char *organ, char *path) {
  char text[4096];
  snprintf(text, sizeof text, scene_format, mesh, organ);
  snprintf(path, 512, "%s/scene.json", dir);
  return fixture_write(dir, "scene.json", text);
}

static int check_shell(const char *dir) {
  char path[512];
  CHECK(write_scene(dir, "b.obj", shell, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  const fascia_model *m = r.model;
  if (!m) goto done;
  // own frames on the sphere (the icosphere lies within 0.1 mm of it)
  int own = 0, on_sphere = 0;
  for (int32_t i = 0; i < m->frame_count; ++i) {
    double d2 = 0;
    for (int c = 0; c < 3; ++c) d2 += (m->frame_position[3 * i + c] - centre[c]) * (m->frame_position[3 * i + c] - centre[c]);
    on_sphere += fabs(sqrt(d2) - RADIUS) < 0.1e-3;
    if (m->frame_organ[i] != 1) continue;
    ++own;
    CHECK_NEAR(sqrt(d2), RADIUS, 0, 0.1e-3);
  }
  // about pi (2 r)^2 / (0.87 spacing^2) frames on it, its own and those it
  // shares with the tissue: a Poisson disk keeps one per ~0.87 spacing^2 to
  // 1.3 spacing^2 (the shared ones are 3 mm apart, denser)
  CHECK(own > 20 && on_sphere > 40 && on_sphere < 120);
  // the wall's volume: area x thickness, the area of its frames' triangles:
  // chords of the sphere, 52 frames on it give about 7 % less
  double wall = 0;
  int tissue_frames_in_wall = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    if (m->sample_organ[s] != 1) continue;
    wall += m->sample_volume[s];
    CHECK(m->materials[m->sample_material[s]].poisson_ratio < 0.45); // the section's moduli, not the 3-D law's
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k)
      tissue_frames_in_wall += m->frame_organ[m->pair_frame[k]] < 0;
  }
  printf("t595: %d own frames, wall %.4g of area x thickness\n", own, wall / (4 * PI * RADIUS * RADIUS * 0.001));
  CHECK(wall > 0.9 * 4 * PI * RADIUS * RADIUS * 0.001 && wall < 4 * PI * RADIUS * RADIUS * 0.001);
  int coupled = 0;
  for (int32_t c = 0; c < m->coupling_count; ++c) coupled += m->coupling_organ[c] == 1;
  CHECK(coupled > 5);
  CHECK(tissue_frames_in_wall > 5); // the tissue's frames on B carry B's wall too
  // hanging from A: the static solve converges and B sags
  {
    fascia_solver_def def = fascia_solver_def_default();
    def.backend = "cpu";
    def.threads = 1;
    fascia_solver *solver = NULL;
    fascia_solve_report report;
    CHECK_OK(fascia_solver_create(ctx, m, &def, &solver), ctx);
    CHECK_OK(solver ? fascia_solver_solve_static(solver, &report) : FASCIA_ERR_ARGUMENT, ctx);
    const fascia_real *x = solver ? fascia_solver_frame_positions(solver) : NULL;
    double sag = 0;
    for (int32_t i = 0; x && i < m->frame_count; ++i)
      if (m->frame_organ[i] == 1) sag = fmin(sag, x[3 * i + 2] - m->frame_position[3 * i + 2]);
    CHECK(sag < -1e-5);
    fascia_solver_destroy(&solver);
  }
done:
  fixture_free(&r);
  // a hold region fixes the wall's frames in it (the far half of the sphere)
  char organ[512];
  snprintf(organ, sizeof organ, "%s, \"hold\": {\"box\": {\"min\": [0.016, -0.02, -0.02], \"max\": [0.03, 0.02, 0.02]}}",
           shell);
  CHECK(write_scene(dir, "b.obj", organ, path));
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  int fixed = 0, free_far = 0;
  for (int32_t i = 0; r.model && i < r.model->frame_count; ++i)
    if (r.model->frame_organ[i] == 1) {
      const int far = r.model->frame_position[3 * i] > 0.016;
      fixed += far && r.model->frame_kind[i] == FASCIA_FRAME_FIXED;
      free_far += far && r.model->frame_kind[i] != FASCIA_FRAME_FIXED;
    }
  CHECK(fixed > 10 && free_far == 0);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return 0;
}

// An open bowl (the sphere's lower half) held along its rim: every wall
// triangle lies along the surface (the rim's frames make no sliver standing
// across it, whose gradients would be many times 1 / spacing), and every
// wall sample's gradients reproduce linear fields in its triangle's plane.
// With a sample spacing of a third of the frames', each triangle gives 9
// points: 9 times as many, the same volume, each point's gradients its own
// (a quadratic field flat at the point, f = ((x - p) . t)^2 with t in the
// plane, has no slope there: only the share of the linear triangle's
// gradients, SHELL_LINEAR_SHARE = 0.1 in prep, answers it). The split
// point's gradients were the centroid's before: 2 (c - p) . t off.
#define BOWL_SPACING 0.0025
#define LINEAR_SHARE 0.1
typedef struct wall_counts {
  int samples;
  double volume;
} wall_counts;
static int check_open_wall(const char *dir, int split, wall_counts *counts) {
  char path[512], organ[512];
  snprintf(organ, sizeof organ,
           "\"model\": \"shell\", \"material\": \"wall\", \"thickness\": 0.0005, \"frame_spacing\": %g, "
           "\"sample_spacing\": %g, \"hold\": {\"box\": {\"min\": [0, -0.02, -0.0005], \"max\": [0.03, 0.02, 0.0005]}}",
           BOWL_SPACING, BOWL_SPACING / split);
  CHECK(write_scene(dir, "bowl.obj", organ, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  const fascia_model *m = r.model;
  int wall = 0, across = 0, steep = 0, unreproduced = 0, sloped = 0;
  double volume = 0;
  for (int32_t s = 0; m && s < m->sample_count; ++s) {
    if (m->sample_organ[s] != 1) continue;
    ++wall;
    volume += m->sample_volume[s];
    int32_t corner[3], k = 0;
    double gx[9] = {0}, largest = 0;
    for (int32_t j = m->sample_offsets[s]; j < m->sample_offsets[s + 1]; ++j) {
      if (m->pair_weight[j] != 0 && k < 3) corner[k++] = m->pair_frame[j];
      const fascia_real *g = m->pair_gradient + 3 * j, *x = m->frame_position + 3 * m->pair_frame[j];
      largest = fmax(largest, sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]));
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) gx[3 * a + b] += x[a] * g[b];
    }
    if (k != 3) continue;
    const fascia_real *p0 = m->frame_position + 3 * corner[0], *p1 = m->frame_position + 3 * corner[1],
                      *p2 = m->frame_position + 3 * corner[2];
    double e1[3], e2[3], n[3], radial[3];
    for (int a = 0; a < 3; ++a)
      e1[a] = p1[a] - p0[a], e2[a] = p2[a] - p0[a], radial[a] = (p0[a] + p1[a] + p2[a]) / 3 - centre[a];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double nn = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]),
                 rr = sqrt(radial[0] * radial[0] + radial[1] * radial[1] + radial[2] * radial[2]);
    across += fabs(n[0] * radial[0] + n[1] * radial[1] + n[2] * radial[2]) < 0.5 * nn * rr;
    steep += largest * BOWL_SPACING > 5;
    // P (sum_i x_i g_i^T) P = P, P the projector on the triangle's plane:
    // a linear field along the plane has its slope (the frames off the
    // plane, on the curved wall, add a part along n)
    double P[9], pg[9] = {0}, pgp[9] = {0};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) P[3 * a + b] = (a == b) - n[a] * n[b] / (nn * nn);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        for (int q = 0; q < 3; ++q) pg[3 * a + b] += P[3 * a + q] * gx[3 * q + b];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        for (int q = 0; q < 3; ++q) pgp[3 * a + b] += pg[3 * a + q] * P[3 * q + b];
    for (int a = 0; a < 9; ++a) unreproduced += fabs(pgp[a] - P[a]) > 1e-9;
    // f = ((x - p) . t)^2, t = e1 / |e1|: the slope the points' gradients
    // give it, less the linear triangle's share, is none
    const fascia_real *p = m->sample_position + 3 * s;
    double t[3], slope[3] = {0}, linear[3] = {0}, len = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (int a = 0; a < 3; ++a) t[a] = e1[a] / len;
    for (int32_t j = m->sample_offsets[s]; j < m->sample_offsets[s + 1]; ++j) {
      const fascia_real *g = m->pair_gradient + 3 * j, *x = m->frame_position + 3 * m->pair_frame[j];
      double along = 0;
      for (int a = 0; a < 3; ++a) along += (x[a] - p[a]) * t[a];
      for (int a = 0; a < 3; ++a) slope[a] += along * along * g[a];
    }
    const fascia_real *c[3] = {p0, p1, p2};
    for (int i = 0; i < 3; ++i) { // grad of corner i's linear weight: n x (x_k - x_j) / |n|^2
      const fascia_real *xj = c[(i + 1) % 3], *xk = c[(i + 2) % 3];
      const double d[3] = {xk[0] - xj[0], xk[1] - xj[1], xk[2] - xj[2]};
      const double grad[3] = {n[1] * d[2] - n[2] * d[1], n[2] * d[0] - n[0] * d[2], n[0] * d[1] - n[1] * d[0]};
      double along = 0;
      for (int a = 0; a < 3; ++a) along += (c[i][a] - p[a]) * t[a];
      for (int a = 0; a < 3; ++a) linear[a] += along * along * grad[a] / (nn * nn);
    }
    double off = 0;
    for (int a = 0; a < 3; ++a) off += (slope[a] - LINEAR_SHARE * linear[a]) * (slope[a] - LINEAR_SHARE * linear[a]);
    sloped += sqrt(off) > 1e-6 * BOWL_SPACING;
  }
  printf("t595: open bowl split %d: %d wall samples, %d across its surface, %d with gradients over 5 / spacing, %d "
         "not reproducing linear fields, %d giving a flat quadratic a slope\n",
         split, wall, across, steep, unreproduced, sloped);
  CHECK(wall > 50);
  CHECK(across == 0);
  CHECK(steep == 0);
  CHECK(unreproduced == 0);
  CHECK(sloped == 0);
  counts->samples = wall, counts->volume = volume;
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return 0;
}

// The scene must be refused with one line holding key and what.
static void refused(const char *dir, const char *mesh, const char *organ, const char *key, const char *what) {
  char path[512];
  CHECK(write_scene(dir, mesh, organ, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep(ctx, path, &r);
  const char *message = fascia_ctx_message(ctx);
  const int ok = st != FASCIA_OK && strstr(message, key) && strstr(message, what) && !strchr(message, '\n');
  if (!ok) fprintf(stderr, "expected a refusal naming '%s' ('%s'), got %d: %s\n", key, what, (int)st, message);
  CHECK(ok);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
}

// A cube as a shell (a box-shaped organ): its frames on the edges are no
// sign of a wall thicker than the organ, though the wall's inner face
// meets the adjacent side there.
static int check_cube(const char *dir) {
  char path[512];
  CHECK(write_scene(dir, "cube.obj", shell, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  double wall = 0;
  for (int32_t s = 0; r.model && s < r.model->sample_count; ++s)
    if (r.model->sample_organ[s] == 1) wall += r.model->sample_volume[s];
  printf("t595: cube: wall %.4g of its area x thickness\n", wall / (6 * 0.02 * 0.02 * 0.001));
  CHECK_NEAR(wall, 6 * 0.02 * 0.02 * 0.001, 1e-6, 0);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return 0;
}

static void check_refusals(const char *dir) {
  refused(dir, "b.obj",
          "\"model\": \"shell\", \"material\": \"wall\", \"thickness\": 0.004, \"frame_spacing\": 0.004",
          "organs[1].thickness", "not thinner than frame_spacing");
  refused(dir, "slab.obj",
          "\"model\": \"shell\", \"material\": \"wall\", \"thickness\": 0.003, \"frame_spacing\": 0.004",
          "organs[1].thickness", "thicker than the organ");
  char organ[512];
  snprintf(organ, sizeof organ, "%s, \"sample_spacing\": 0.0004", shell);
  refused(dir, "b.obj", organ, "organs[1].sample_spacing", "outside [frame_spacing / 8, frame_spacing]");
  snprintf(organ, sizeof organ, "%s, \"sample_spacing\": 0.005", shell);
  refused(dir, "b.obj", organ, "organs[1].sample_spacing", "outside [frame_spacing / 8, frame_spacing]");
  snprintf(organ, sizeof organ, "%s, \"patch_radius\": 0.004", shell);
  refused(dir, "b.obj", organ, "organs[1].patch_radius", "leave patch_radius out");
  refused(dir, "b.obj", "\"model\": \"fixed\", \"thickness\": 0.001", "organs[1].thickness", "only a \"shell\"");
  refused(dir, "b.obj", "\"model\": \"shell\", \"thickness\": 0.001, \"frame_spacing\": 0.004", "organs[1].material",
          "missing");
}

int main(void) {
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  const double a_lo[3] = {-0.03, -0.012, -0.012}, a_hi[3] = {-0.0005, 0.012, 0.012};
  const double slab_lo[3] = {0.005, -0.012, -0.012}, slab_hi[3] = {0.007, 0.012, 0.012};
  const double cube_lo[3] = {0.005, -0.01, -0.01}, cube_hi[3] = {0.025, 0.01, 0.01};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && write_sphere(dir, "b.obj") &&
        write_bowl(dir, "bowl.obj") && fixture_box(dir, "slab.obj", slab_lo, slab_hi) &&
        fixture_box(dir, "cube.obj", cube_lo, cube_hi));
  const int stopped = check_shell(dir); // 1: a stage failed (printed)
  wall_counts one, nine;
  const int open_stopped = check_open_wall(dir, 1, &one) || check_open_wall(dir, 3, &nine);
  if (!open_stopped) {
    CHECK(nine.samples == 9 * one.samples);
    CHECK_NEAR(nine.volume, one.volume, 1e-12, 0);
  }
  const int cube_stopped = check_cube(dir);
  check_refusals(dir);
  static const char *const files[] = {"a.obj", "b.obj", "bowl.obj", "slab.obj", "cube.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return stopped || open_stopped || cube_stopped || CHECK_RESULT();
}
