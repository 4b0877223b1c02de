// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Strands attached by areas and strands along curves (issue 43; data/scenes/
// README.md, "Strands and sheets"). Boxes A (fixed, x in [-30, -10] mm) and
// B (x in [10, 30] mm), 20 mm wide:
//  - a strand to a sphere region on B's face, spread: its end is a fan of
//    free fibres to at least three frames of B's face, all coupled to B; on
//    a deformable B hanging from it (gravity along +x), its load is spread
//    over those frames: B's largest sample strain is well under the one a
//    point end gives (which loads one frame of B), and the static solve
//    converges in a few Newton iterations (B hung at one frame nearly
//    turns about it at no cost: many);
//  - a strand through three points (a polyline above the boxes): its
//    frames on the polyline, its volume exactly length x area, its weights
//    well posed (each sample's weights sum to one, their gradients span its
//    interval's axis alone), and it holds B when pulled;
//  - refusals, one line naming the key: a region on no organ, a region
//    with nothing facing the strand, a curve through an organ, a through
//    point repeated, a label on a mesh organ, point and region both.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "prep_fixture.h"

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 5, \"gravity\": [%s],\n"
    " \"materials\": {\"organ\": {\"youngs_modulus\": 20000, \"poisson_ratio\": 0.3, \"density\": 1000},\n"
    "               \"lig\": {\"youngs_modulus\": 1000000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"b.obj\", %s}],\n"
    " \"tissues\": [%s]}\n";

static const char deformable_b[] =
    "\"model\": \"deformable\", \"material\": \"organ\", \"frame_spacing\": 0.004, \"sample_spacing\": 0.002";
static const char pulled_b[] = "\"model\": \"prescribed\", \"motion\": {\"pivot\": [0, 0, 0], \"keys\": [{\"time\": "
                               "0}, {\"time\": 1, \"translation\": [0.001, 0, 0]}]}";

// The strand from A's face to B's, its end on B given by `to`.
static const char strand_format[] =
    "{\"name\": \"lig\", \"form\": \"strand\", \"from\": {\"organ\": \"A\", \"point\": [-0.01, 0, 0]},\n"
    " \"to\": %s, \"radius\": 0.001, \"material\": \"lig\", \"frame_spacing\": 0.002%s}";

static const char to_point[] = "{\"organ\": \"B\", \"point\": [0.01, 0, 0]}";
static const char to_region[] = "{\"organ\": \"B\", \"region\": {\"sphere\": {\"center\": [0.01, 0, 0], \"radius\": "
                                "0.006}}}";

static int write_scene(const char *dir, const char *gravity, const char *b, const char *to, const char *extra,
                       char *path) {
  char tissue[2048], text[8192];
  snprintf(tissue, sizeof tissue, strand_format, to, extra);
  snprintf(text, sizeof text, scene_format, gravity, b, tissue);
  snprintf(path, 512, "%s/scene.json", dir);
  return fixture_write(dir, "scene.json", text);
}

static int newton_iterations_ = 0; // of the last static solve

static int static_solve(fascia_ctx *ctx, const fascia_model *m, fascia_solver **solver) {
  fascia_solver_def def = fascia_solver_def_default();
  def.backend = "cpu";
  def.threads = 1;
  def.newton_iterations = 400;
  fascia_solve_report report = {0};
  const int ok = fascia_solver_create(ctx, m, &def, solver) == FASCIA_OK &&
                 fascia_solver_set_time(*solver, 1) == FASCIA_OK &&
                 fascia_solver_solve_static(*solver, &report) == FASCIA_OK && report.converged;
  if (!ok) fprintf(stderr, "static solve: %s (%d Newton iterations)\n", fascia_ctx_message(ctx), report.newton_iterations);
  newton_iterations_ = report.newton_iterations;
  return ok;
}

// Frames that both the strand's samples and deformable organ b's weigh on:
// where the strand loads the organ.
static int strand_frames_on_b(const fascia_model *m, int32_t b) {
  unsigned char *use = calloc((size_t)m->frame_count, 1);
  if (!use) return -1;
  for (int32_t s = 0; s < m->sample_count; ++s)
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k)
      use[m->pair_frame[k]] |= m->sample_organ[s] == b ? 1 : m->sample_organ[s] < 0 ? 2 : 0;
  int n = 0;
  for (int32_t i = 0; i < m->frame_count; ++i) n += use[i] == 3;
  free(use);
  return n;
}

// B deformable hangs from the strand (gravity along +x); the largest strain
// of B's samples after the static solve into *largest; frames of B the
// strand loads into *loaded. 0 on failure.
static int hang_deformable(const char *dir, const char *to, double *largest, int *loaded, int *iterations) {
  char path[512];
  CHECK(write_scene(dir, "9.81, 0, 0", deformable_b, to, "", path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep(ctx, path, &r);
  if (st != FASCIA_OK) fprintf(stderr, "hang: %s\n", fascia_ctx_message(ctx));
  int ok = st == FASCIA_OK;
  fascia_solver *solver = NULL;
  if (ok) {
    const fascia_model *m = r.model;
    const int32_t b = fascia_model_find_organ(m, "B");
    *loaded = strand_frames_on_b(m, b);
    ok = static_solve(ctx, m, &solver);
    *iterations = newton_iterations_;
    fascia_real *strain = ok ? malloc((size_t)m->sample_count * sizeof *strain) : NULL;
    *largest = 0;
    if (strain) {
      fascia_solver_sample_strain(solver, strain, NULL);
      for (int32_t s = 0; s < m->sample_count; ++s)
        if (m->sample_organ[s] == b) *largest = fmax(*largest, strain[s]);
    }
    ok = ok && strain;
    free(strain);
  }
  fascia_solver_destroy(&solver);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return ok;
}

static void check_spread(const char *dir) {
  // on a rigid B: a fan of fibres to B's face
  char path[512];
  CHECK(write_scene(dir, "0, 0, 0", pulled_b, to_region, "", path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  fascia_status st = fixture_prep(ctx, path, &r);
  if (st != FASCIA_OK) fprintf(stderr, "region: %s\n", fascia_ctx_message(ctx));
  CHECK(st == FASCIA_OK);
  if (st == FASCIA_OK) {
    const fascia_model *m = r.model;
    int on_b = 0, on_face = 0;
    for (int32_t c = 0; c < m->coupling_count; ++c) {
      if (m->coupling_organ[c] != 1) continue;
      const double *x = m->frame_position + 3 * m->coupling_frame[c];
      ++on_b;
      on_face += fabs(x[0] - 0.01) < 1e-6 && x[1] * x[1] + x[2] * x[2] <= 0.006 * 0.006 + 1e-12;
    }
    fprintf(stderr, "region on B: %d frames coupled to B, %d on the sphere's disc of its face\n", on_b, on_face);
    CHECK(on_b >= 3 && on_face == on_b);
    fascia_solver *solver = NULL;
    CHECK(static_solve(ctx, m, &solver));
    fascia_solver_destroy(&solver);
  }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  // on a deformable B hanging from it: the strand's load spread
  double strain_point = 0, strain_area = 0;
  int loaded_point = 0, loaded_area = 0, newton_point = 0, newton_area = 0;
  CHECK(hang_deformable(dir, to_point, &strain_point, &loaded_point, &newton_point));
  CHECK(hang_deformable(dir, to_region, &strain_area, &loaded_area, &newton_area));
  fprintf(stderr, "deformable B hanging: point end loads %d frame(s) of B, largest strain in B %.4g, %d Newton "
                  "iterations; region end loads %d, largest strain %.4g (%.2f of the point's), %d Newton iterations\n",
          loaded_point, strain_point, newton_point, loaded_area, strain_area, strain_area / strain_point, newton_area);
  CHECK(loaded_point == 1 && loaded_area >= 3);
  CHECK(strain_area > 0 && strain_area < 0.5 * strain_point);
  CHECK(newton_area < 30); // held over an area, B is no near-mechanism about one frame
}

// The polyline from A's face over the gap to B's face.
static const double polyline[4][3] = {{-0.01, 0, 0}, {-0.006, 0, 0.008}, {0.006, 0, 0.008}, {0.01, 0, 0}};
static const char through[] = ", \"through\": [[-0.006, 0, 0.008], [0.006, 0, 0.008]]";

static void check_curve(const char *dir) {
  char path[512];
  CHECK(write_scene(dir, "0, 0, 0", pulled_b, to_point, through, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep(ctx, path, &r);
  if (st != FASCIA_OK) fprintf(stderr, "curve: %s\n", fascia_ctx_message(ctx));
  CHECK(st == FASCIA_OK);
  if (st == FASCIA_OK) {
    const fascia_model *m = r.model;
    double length = 0;
    int frames = 1;
    for (int k = 0; k < 3; ++k) {
      double d2 = 0;
      for (int a = 0; a < 3; ++a) d2 += (polyline[k + 1][a] - polyline[k][a]) * (polyline[k + 1][a] - polyline[k][a]);
      length += sqrt(d2);
      frames += (int)ceil(sqrt(d2) / 0.002 - 1e-9);
    }
    double volume = 0;
    for (int32_t s = 0; s < m->sample_count; ++s) volume += m->sample_volume[s];
    const double expected = length * acos(-1.0) * 1e-6;
    // every frame on the polyline
    double off = 0;
    for (int32_t i = 0; i < m->frame_count; ++i) {
      const double *x = m->frame_position + 3 * i;
      double best = INFINITY;
      for (int k = 0; k < 3; ++k) {
        double d[3], e[3], t = 0, n = 0;
        for (int a = 0; a < 3; ++a) d[a] = polyline[k + 1][a] - polyline[k][a], e[a] = x[a] - polyline[k][a];
        for (int a = 0; a < 3; ++a) t += d[a] * e[a], n += d[a] * d[a];
        t = fmin(1, fmax(0, t / n));
        double o = 0;
        for (int a = 0; a < 3; ++a) o += (e[a] - t * d[a]) * (e[a] - t * d[a]);
        best = fmin(best, sqrt(o));
      }
      off = fmax(off, best);
    }
    // weights: sum 1, gradients along the interval's axis only (sum x_i (x) grad w = t t^T)
    double worst_sum = 0, worst_grad = 0;
    for (int32_t s = 0; s < m->sample_count; ++s) {
      const int32_t k0 = m->sample_offsets[s], k1 = m->sample_offsets[s + 1];
      CHECK(k1 - k0 == 2);
      if (k1 - k0 != 2) continue;
      const double *x0 = m->frame_position + 3 * m->pair_frame[k0], *x1 = m->frame_position + 3 * m->pair_frame[k0 + 1];
      double t[3], len = 0, w = 0, G[9] = {0};
      for (int a = 0; a < 3; ++a) t[a] = x1[a] - x0[a], len += t[a] * t[a];
      len = sqrt(len);
      for (int a = 0; a < 3; ++a) t[a] /= len;
      for (int32_t k = k0; k < k1; ++k) {
        const double *x = m->frame_position + 3 * m->pair_frame[k], *g = m->pair_gradient + 3 * k;
        w += m->pair_weight[k];
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) G[3 * a + b] += x[a] * g[b];
      }
      worst_sum = fmax(worst_sum, fabs(w - 1));
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) worst_grad = fmax(worst_grad, fabs(G[3 * a + b] - t[a] * t[b]));
    }
    fprintf(stderr, "curve: %d frames (%d expected), %.3g mm off the polyline at most; volume %.9g, length x area "
                    "%.9g m^3; weights: |sum - 1| %.2g, |sum x (x) grad w - t t| %.2g\n",
            (int)m->frame_count, frames, 1e3 * off, volume, expected, worst_sum, worst_grad);
    CHECK(m->frame_count == frames && off < 1e-6);
    CHECK(fabs(volume - expected) < 1e-6 * expected); // the boxes are read as float32
    CHECK(worst_sum < 1e-9 && worst_grad < 1e-9);
    fascia_solver *solver = NULL;
    CHECK(static_solve(ctx, m, &solver));
    fascia_solver_destroy(&solver);
  }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
}

// The scene must be refused with one line holding key and what.
static void refused(const char *dir, const char *to, const char *extra, const char *key, const char *what) {
  char path[512];
  CHECK(write_scene(dir, "0, 0, 0", pulled_b, to, extra, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep(ctx, path, &r);
  const char *message = fascia_ctx_message(ctx);
  const int ok = st != FASCIA_OK && strstr(message, key) && strstr(message, what) && !strchr(message, '\n');
  if (!ok) fprintf(stderr, "expected a refusal naming '%s' ('%s'), got %d: %s\n", key, what, (int)st, message);
  else fprintf(stderr, "refused: %s\n", message);
  CHECK(ok);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
}

static void check_refusals(const char *dir) {
  refused(dir, "{\"organ\": \"B\", \"region\": {\"sphere\": {\"center\": [0, 0, 0.03], \"radius\": 0.005}}}", "",
          "tissues[0].to.region", "lies on no organ");
  refused(dir, "{\"organ\": \"B\", \"region\": {\"box\": {\"min\": [0, 0.02, 0.02], \"max\": [0.005, 0.03, 0.03]}}}",
          "", "tissues[0].to.region", "lies on no organ");
  // over B's top and down into it
  refused(dir, to_point, ", \"through\": [[0, 0, 0.015], [0.02, 0, 0.015], [0.02, 0, 0.005]]", "tissues[0].through",
          "pass through organ 'B'");
  refused(dir, to_point, ", \"through\": [[0, 0, 0.015], [0, 0, 0.015]]", "tissues[0].through[1]", "same point");
  // spread over B's far face only: nothing of it faces the strand
  refused(dir, "{\"organ\": \"B\", \"region\": {\"box\": {\"min\": [0.029, -0.005, -0.005], \"max\": [0.031, 0.005, "
               "0.005]}}}",
          "", "tissues[0].to.region", "faces the strand");
  refused(dir, "{\"organ\": \"B\", \"label\": \"liver\"}", "", "tissues[0].to.label", "is a mesh");
  refused(dir, "{\"organ\": \"B\", \"point\": [0.01, 0, 0], \"region\": {\"sphere\": {\"center\": [0.01, 0, 0], "
               "\"radius\": 0.006}}}",
          "", "tissues[0].to", "not both");
}

int main(void) {
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  const double a_lo[3] = {-0.03, -0.01, -0.01}, a_hi[3] = {-0.01, 0.01, 0.01};
  const double b_lo[3] = {0.01, -0.01, -0.01}, b_hi[3] = {0.03, 0.01, 0.01};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && fixture_box(dir, "b.obj", b_lo, b_hi));
  check_curve(dir);
  check_refusals(dir);
  check_spread(dir);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
