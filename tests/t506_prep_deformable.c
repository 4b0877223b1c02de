// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A frame-based deformable organ: box B of a two-box scene gets its own frames
// and samples inside it, sample volumes that add up to the box's volume within
// half a voxel per face, weights that are a partition of unity reproducing
// linear fields, and frames on its face shared with the tissue (each used by
// tissue samples and by organ samples, the only frames the two sides have in
// common); with box A fixed the model reaches static equilibrium under gravity.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "fascia/solver.h"
#include "prep_fixture.h"

// Box A spans x in [-20, -3.1] mm (fixed), box B x in [3.1, 20] mm
// (deformable), both y, z in [-10.2, 10.2] mm; the tissue is the slab between
// them, cut to |y|, |z| < 8 mm.
#define FACE 0.0031
#define FAR 0.02
#define HALF 0.0102
#define H 0.001

static const char scene[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 3, \"gravity\": [0, -9.81, 0],\n"
    " \"materials\": {\"soft\": {\"law\": \"neohookean\", \"youngs_modulus\": 10000, \"poisson_ratio\": 0.3,\n"
    "                          \"density\": 1000},\n"
    "               \"organ\": {\"law\": \"neohookean\", \"youngs_modulus\": 30000, \"poisson_ratio\": 0.3,\n"
    "                          \"density\": 500}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "  {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"deformable\", \"material\": \"organ\",\n"
    "   \"frame_spacing\": 0.005, \"sample_spacing\": 0.0025, \"shape_functions\": {\"neighbours\": 8}}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008,\n"
    "  \"region\": {\"box\": {\"min\": [-0.005, -0.008, -0.008], \"max\": [0.005, 0.008, 0.008]}},\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.0025, \"sample_spacing\": 0.00125}]}\n";

// Weights of every sample: sum w = 1, sum grad w = 0, sum w x_i = p,
// sum x_i (x) grad w = I (1e-9: MLS solves a 4x4 system in double per sample).
static int check_weights(const fascia_model *m) {
  double worst[3];
  fixture_weight_errors(m, worst);
  CHECK(worst[0] < 1e-9);
  CHECK(worst[1] < 1e-12); // metres: 1e-9 of a millimetre
  CHECK(worst[2] < 1e-8);
  return 0;
}

// Organ samples inside box B, their volumes adding up to it; organ frames
// inside it too.
static int check_organ_points(const fixture_run *r) {
  const fascia_prep_points *pts = r->points;
  const int32_t label = r->volume->organ_label[1];
  CHECK(label == 2 && r->volume->organ_label[0] == 0);
  double sum = 0;
  int32_t organ_samples = 0, organ_frames = 0;
  for (int32_t s = 0; s < pts->sample_count; ++s) {
    const double *p = pts->sample_position + 3 * s;
    if (pts->sample_inside_organ[s] != 1) {
      CHECK(pts->sample_inside_organ[s] == -1 && pts->sample_tissue[s] == 0);
      continue;
    }
    CHECK(pts->sample_tissue[s] == -1);
    CHECK(fascia_prep_volume_region_at(r->volume, p) == label);
    // voxel centres inside the box, cell centroids of them too (1e-12: round-off)
    CHECK(p[0] >= FACE - 1e-12 && p[0] <= FAR + 1e-12 && fabs(p[1]) <= HALF + 1e-12 && fabs(p[2]) <= HALF + 1e-12);
    sum += pts->sample_volume[s];
    ++organ_samples;
  }
  for (int32_t i = 0; i < pts->frame_count; ++i)
    if (pts->frame_inside_organ[i] == 1) {
      const double *x = pts->frame_position + 3 * i;
      // interior frames are jittered within their voxel: up to h/2 beyond a centre
      CHECK(x[0] >= FACE - H && x[0] <= FAR + H && fabs(x[1]) <= HALF + H && fabs(x[2]) <= HALF + H);
      CHECK(pts->frame_tissue[i] == -1 && pts->frame_organ_voxel[i] == -1);
      ++organ_frames;
    }
  CHECK(organ_samples > 100 && organ_frames >= 20);
  // each of the 6 faces moves by at most h/2 when voxel centres decide membership
  const double lx = FAR - FACE, ly = 2 * HALF;
  const double exact = lx * ly * ly, area = 2 * ly * ly + 4 * lx * ly;
  CHECK_NEAR(sum, exact, 0, 0.5 * H * area);
  CHECK_NEAR(sum, r->volume->organ_regions[1].volume, 1e-12, 0);
  return 0;
}

// Shared frames: on B's face, FREE, each used by tissue and organ samples;
// no other frame is used by both sides.
static int check_sharing(const fixture_run *r) {
  const fascia_model *m = r->model;
  const fascia_prep_points *pts = r->points;
  uint8_t *used = calloc((size_t)m->frame_count, 1); // bit 1: by a tissue sample, bit 2: by an organ sample
  CHECK(used);
  for (int32_t s = 0; s < m->sample_count; ++s)
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k)
      used[m->pair_frame[k]] |= pts->sample_inside_organ[s] == 1 ? 2 : 1;
  int32_t shared_b = 0;
  uint8_t *is_shared = calloc((size_t)m->frame_count, 1);
  CHECK(is_shared);
  for (int32_t c = 0; c < m->coupling_count; ++c) {
    const int32_t i = m->coupling_frame[c];
    if (m->coupling_organ[c] != 1) {
      CHECK(m->frame_kind[i] == FASCIA_FRAME_FIXED);
      continue;
    }
    CHECK_NEAR(m->frame_position[3 * i], FACE, 0, 1e-9); // assimp reads floats: 0.0031 is 0.00310000009
    CHECK(m->frame_kind[i] == FASCIA_FRAME_FREE);
    CHECK(pts->frame_organ_voxel[i] >= 0 && pts->frame_tissue[i] == 0);
    CHECK(used[i] == 3);
    is_shared[i] = 1;
    ++shared_b;
  }
  CHECK(shared_b >= 4 && r->coupling->per_organ[1] == shared_b);
  for (int32_t i = 0; i < m->frame_count; ++i) {
    if (used[i] == 3) CHECK(is_shared[i]);
    if (pts->frame_inside_organ[i] == 1) CHECK(m->frame_kind[i] == FASCIA_FRAME_FREE);
  }
  CHECK(m->organs[1].kind == FASCIA_ORGAN_DEFORMABLE && m->organs[0].kind == FASCIA_ORGAN_FIXED);
  for (int32_t s = 0; s < m->sample_count; ++s)
    CHECK(m->sample_material[s] == (pts->sample_inside_organ[s] == 1 ? 1 : 0));
  free(used);
  free(is_shared);
  return 0;
}

// Static equilibrium under gravity: converged, A's frames where they were,
// the organ hanging from the tissue moved down.
static int check_equilibrium(fascia_ctx *ctx, const fixture_run *r) {
  const fascia_model *m = r->model;
  fascia_solver_def def = fascia_solver_def_default();
  def.backend = "cpu";
  fascia_solver *solver = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &def, &solver), ctx);
  fascia_solve_report report;
  CHECK_OK(fascia_solver_solve_static(solver, &report), ctx);
  CHECK(report.converged);
  CHECK(report.inverted_samples == 0);
  const fascia_real *x = fascia_solver_frame_positions(solver);
  double organ_dy = 0, worst = 0;
  int32_t organ_frames = 0;
  for (int32_t i = 0; i < m->frame_count; ++i) {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) d2 += (x[3 * i + a] - m->frame_position[3 * i + a]) * (x[3 * i + a] - m->frame_position[3 * i + a]);
    if (m->frame_kind[i] == FASCIA_FRAME_FIXED) CHECK(d2 == 0);
    worst = fmax(worst, sqrt(d2));
    if (r->points->frame_inside_organ[i] == 1) organ_dy += x[3 * i + 1] - m->frame_position[3 * i + 1], ++organ_frames;
  }
  organ_dy /= organ_frames > 0 ? organ_frames : 1;
  CHECK(organ_dy < 0);
  CHECK(isfinite(worst) && worst < 0.01); // sags, does not fall: within the 17 mm box's size
  fascia_solver_destroy(&solver);
  return 0;
}

// Scene errors of the deformable keys name the key.
static int check_scene_errors(fascia_ctx *ctx) {
  static const char *const bad[] = {
      // deformable without its sampling keys
      "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"materials\": {\"m\": {\"youngs_modulus\": 1, "
      "\"poisson_ratio\": 0.3}}, \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"deformable\", "
      "\"material\": \"m\"}], \"tissues\": []}",
      // sampling keys on a fixed organ
      "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"materials\": {\"m\": {\"youngs_modulus\": 1, "
      "\"poisson_ratio\": 0.3}}, \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"frame_spacing\": 0.01}], "
      "\"tissues\": []}"};
  static const char *const key[] = {"organs[0].frame_spacing", "organs[0].frame_spacing"};
  for (int k = 0; k < 2; ++k) {
    fascia_prep_scene *s = NULL;
    CHECK(fascia_prep_scene_parse(ctx, bad[k], "bad.json", NULL, &s) == FASCIA_ERR_FORMAT && !s);
    CHECK(strstr(fascia_ctx_message(ctx), key[k]) != NULL);
  }
  return 0;
}

int main(void) {
  char dir[256], path[512];
  if (!fixture_tmpdir(dir)) return 1;
  const double a_lo[3] = {-FAR, -HALF, -HALF}, a_hi[3] = {-FACE, HALF, HALF};
  const double b_lo[3] = {FACE, -HALF, -HALF}, b_hi[3] = {FAR, HALF, HALF};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && fixture_box(dir, "b.obj", b_lo, b_hi) &&
        fixture_write(dir, "scene.json", scene));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  int failed = check_organ_points(&r);
  failed |= check_weights(r.model);
  failed |= check_sharing(&r);
  failed |= check_equilibrium(ctx, &r);
  failed |= check_scene_errors(ctx);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return failed || CHECK_RESULT();
}
