// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// No weight reaches across an organ: a thin plate M between boxes L and R
// splits the tissue joining L and R into two pieces 2 mm apart; every sample
// takes frames from its own side only (a straight-line nearest-frame search
// would reach through the plate), and the frames on the plate's two faces are
// shared with the plate. The same scene gives bit-identical points and
// weights on 1 and on 2 threads (determinism).
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "prep_fixture.h"

static const char scene[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.0005, \"seed\": 3,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"L\", \"mesh\": \"l.obj\"}, {\"name\": \"M\", \"mesh\": \"m.obj\"},\n"
    "             {\"name\": \"R\", \"mesh\": \"r.obj\"}],\n"
    " \"tissues\": [{\"name\": \"split\", \"connects\": [\"L\", \"R\"], \"max_gap\": 0.01,\n"
    "  \"region\": {\"box\": {\"min\": [-0.006, -0.006, -0.006], \"max\": [0.006, 0.006, 0.006]}},\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.002, \"sample_spacing\": 0.001,\n"
    "  \"shape_functions\": {\"neighbours\": 8}}]}\n";

int main(void) {
  char dir[256], path[512];
  if (!fixture_tmpdir(dir)) return 1;
  // L: x < -4.1 mm, M: |x| < 1.05 mm (wider than the region box in y, z), R: x > 4.1 mm
  const double l_lo[3] = {-0.015, -0.008, -0.008}, l_hi[3] = {-0.0041, 0.008, 0.008};
  const double m_lo[3] = {-0.00105, -0.012, -0.012}, m_hi[3] = {0.00105, 0.012, 0.012};
  const double r_lo[3] = {0.0041, -0.008, -0.008}, r_hi[3] = {0.015, 0.008, 0.008};
  CHECK(fixture_box(dir, "l.obj", l_lo, l_hi) && fixture_box(dir, "m.obj", m_lo, m_hi) &&
        fixture_box(dir, "r.obj", r_lo, r_hi) && fixture_write(dir, "scene.json", scene));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  const fascia_model *m = r.model;
  CHECK(r.volume->tissues[0].components == 2);
  int32_t crossing = 0, near_plate = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    const double side = m->sample_position[3 * s] < 0 ? -1 : 1;
    CHECK(fabs(m->sample_position[3 * s]) > 0.00105);
    near_plate += fabs(m->sample_position[3 * s]) < 0.002;
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k)
      if (side * m->frame_position[3 * m->pair_frame[k]] <= 0) ++crossing;
  }
  CHECK(crossing == 0);
  CHECK(near_plate > 0); // samples close to the plate exist, so the test can fail
  // the plate shares frames on both faces
  int32_t left = 0, right = 0;
  for (int32_t c = 0; c < m->coupling_count; ++c)
    if (m->coupling_organ[c] == 1) {
      const double x = m->frame_position[3 * m->coupling_frame[c]];
      CHECK(fabs(fabs(x) - 0.00105) < 1e-9); // the face, to the float precision of the mesh file
      left += x < 0, right += x > 0;
    }
  CHECK(left > 0 && right > 0);
  // determinism: again on one thread, compare bit for bit
  fascia_ctx_def def = fascia_ctx_def_default();
  def.threads = 1;
  fascia_ctx *one = NULL;
  CHECK_OK(fascia_ctx_create(&def, &one), one);
  fixture_run again;
  CHECK_OK(fixture_prep(one, path, &again), one);
  const fascia_model *a = again.model;
  CHECK(a->frame_count == m->frame_count && a->sample_count == m->sample_count && a->pair_count == m->pair_count);
  if (a->frame_count == m->frame_count && a->sample_count == m->sample_count && a->pair_count == m->pair_count) {
    CHECK(!memcmp(a->frame_position, m->frame_position, 3 * sizeof(double) * (size_t)m->frame_count));
    CHECK(!memcmp(a->sample_position, m->sample_position, 3 * sizeof(double) * (size_t)m->sample_count));
    CHECK(!memcmp(a->sample_volume, m->sample_volume, sizeof(double) * (size_t)m->sample_count));
    CHECK(!memcmp(a->pair_frame, m->pair_frame, sizeof(int32_t) * (size_t)m->pair_count));
    CHECK(!memcmp(a->pair_weight, m->pair_weight, sizeof(double) * (size_t)m->pair_count));
    CHECK(!memcmp(a->pair_gradient, m->pair_gradient, 3 * sizeof(double) * (size_t)m->pair_count));
  }
  fixture_free(&again);
  fascia_ctx_destroy(&one);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  static const char *const files[] = {"l.obj", "m.obj", "r.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
