// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Every row of the paper's Tables 2 and 3 builds a valid cantilever model
// with exactly the requested sample count, a frame count within 10 % of the
// request, the requested neighbours per sample, sample volumes summing to the
// body volume, the x = 0 frames clamped, linear-reproducing weights, and the
// same model every time (fixed seed); and a solver takes every row: a frame
// no sample weighs on (rows with more frames than their samples reach) is
// fixed, as nothing would hold it.
#include <string.h>

#include "check.h"
#include "fascia/fascia.h"
#include "scenes.h"

static int check_row(fascia_ctx *ctx, const fascia_scene_paper_row *row) {
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_paper_build(ctx, row, NULL, &m), ctx);
  CHECK_OK(fascia_model_validate(ctx, m, row->name), ctx);
  int bad = 0;
  bad |= m->sample_count != row->samples;
  bad |= !(fabs((double)m->frame_count - row->frames) <= 0.1 * row->frames);
  for (int32_t s = 0; s < m->sample_count; ++s) bad |= m->sample_offsets[s + 1] - m->sample_offsets[s] != row->neighbours;
  // volumes: a sum of up to 35000 positive terms, rounding ~1e-13 relative
  bad |= !(fabs(fascia_model_volume(m) - 16) <= 1e-11 * 16);
  bad |= !(fabs(fascia_model_mass(m) - 5) <= 1e-11 * 5);
  // samples inside the body, weights reproducing their position (rounding of
  // the barycentric or MLS solve on coordinates up to 16: 1e-11)
  double worst = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    const double *p = m->sample_position + 3 * s;
    bad |= !(p[0] >= 0 && p[0] <= 16 && fabs(p[1]) <= 0.5 && fabs(p[2]) <= 0.5);
    double q[3] = {0, 0, 0};
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k)
      for (int r = 0; r < 3; ++r) q[r] += m->pair_weight[k] * m->frame_position[3 * m->pair_frame[k] + r];
    for (int r = 0; r < 3; ++r) worst = fmax(worst, fabs(q[r] - p[r]));
  }
  bad |= !(worst <= 1e-11);
  int32_t fixed = 0, at_root = 0;
  for (int32_t i = 0; i < m->frame_count; ++i) {
    const int weighed = m->frame_offsets[i + 1] > m->frame_offsets[i];
    fixed += m->frame_kind[i] == FASCIA_FRAME_FIXED;
    at_root += m->frame_position[3 * i] == 0;
    bad |= (m->frame_kind[i] == FASCIA_FRAME_FIXED) != (m->frame_position[3 * i] == 0 || !weighed);
  }
  bad |= !(fixed >= 4 && at_root >= 4);
  // the solver takes it (matrix-free CG: no factorization analysis for the large rows)
  fascia_solver_def sd = fascia_solver_def_default();
  sd.linear_solver = FASCIA_LINEAR_CG;
  sd.assembled = 0;
  fascia_solver *solver = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &solver), ctx);
  fascia_solver_destroy(&solver);
  bad |= fascia_model_find_probe(m, "tip") < 0;
  if (bad)
    fprintf(stderr, "row %s: %d samples (want %d), %d frames (want %d), volume %.15g, mass %.15g, %d fixed, "
                    "reproduction error %.3g\n",
            row->name, (int)m->sample_count, (int)row->samples, (int)m->frame_count, (int)row->frames,
            fascia_model_volume(m), fascia_model_mass(m), (int)fixed, worst);
  CHECK(!bad);
  fascia_model_destroy(&m);
  return 0;
}

int main(void) {
  fascia_ctx_def cdef = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cdef, &ctx) != FASCIA_OK) return 1;
  int count = 0, fail = 0, table2 = 0, table3 = 0;
  const fascia_scene_paper_row *rows = fascia_scene_paper_rows(&count);
  for (int k = 0; k < count; ++k) {
    fail |= check_row(ctx, &rows[k]);
    table2 += rows[k].table == 2;
    table3 += rows[k].table == 3;
    CHECK(rows[k].paper_cpu_ms > 0 && (rows[k].table == 2 || rows[k].paper_gpu_ms > 0));
    CHECK(fascia_scene_paper_find(rows[k].name) == &rows[k]);
  }
  // 12 beam rows and the coupling row of Table 2, 8 rows of Table 3
  CHECK(table2 == 13 && table3 == 8);
  const fascia_scene_paper_row *big = fascia_scene_paper_find("t3-s34610");
  CHECK(big && big->samples == 34610 && big->neighbours == 4);
  CHECK_NEAR(big ? big->paper_gpu_ms : 0, 66.1, 0, 0);

  // the same row twice gives the same model (fixed seed)
  const fascia_scene_paper_row *row = fascia_scene_paper_find("t2-f72-s400-k8");
  fascia_model *a = NULL, *b = NULL;
  CHECK_OK(fascia_scene_paper_build(ctx, row, NULL, &a), ctx);
  CHECK_OK(fascia_scene_paper_build(ctx, row, NULL, &b), ctx);
  CHECK(!memcmp(a->sample_position, b->sample_position, 3 * sizeof(double) * a->sample_count));
  CHECK(!memcmp(a->pair_weight, b->pair_weight, sizeof(double) * a->pair_count));
  fascia_model_destroy(&a);
  fascia_model_destroy(&b);

  // a body def carries the material; rows ask for impossible counts in vain
  fascia_scene_beam_def body = fascia_scene_beam_def_default();
  body.youngs_modulus = 1e5;
  CHECK_OK(fascia_scene_paper_build(ctx, &rows[0], &body, &a), ctx);
  CHECK_NEAR(a->materials[0].youngs_modulus, 1e5, 0, 0);
  fascia_model_destroy(&a);
  fascia_scene_paper_row silly = rows[0];
  silly.neighbours = 2;
  CHECK(fascia_scene_paper_build(ctx, &silly, NULL, &a) == FASCIA_ERR_ARGUMENT && a == NULL);

  fascia_ctx_destroy(&ctx);
  return fail | CHECK_RESULT();
}
