// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// CG multiplies by a float copy of the assembled matrix by default where the
// CG tolerance is FASCIA_SINGLE_MIN_CG_TOLERANCE or looser, or the CG count
// is fixed (the paper's mode), and by the double matrix where a tighter
// tolerance is asked for; an explicit choice is kept, and the device (which
// has no matrix) takes the default but refuses an explicit float matrix.
// Float products change only the linear solves: dynamic steps of a falling
// cantilever solved to a tight Newton tolerance end where the double ones
// end, to 1e-8 of the largest displacement, within one Newton iteration of
// them (the last iterations of a quadratic Newton sit at the tolerance,
// where the linear solves' rounding decides one more or not).
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "fascia/solver.h"
#include "scenes.h"

typedef struct choice {
  const char *backend;
  fascia_linear_solver linear;
  int assembled, single, cg_fixed;
  double cg_tolerance;
} choice;

// Three steps of 0.05 s; the report of the last, the positions into x (may be NULL).
// Returns the status of the solver's creation.
static fascia_status run(fascia_ctx *ctx, const fascia_model *m, choice c, fascia_solve_report *rep, int *newton,
                         double *x) {
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = c.backend;
  sd.linear_solver = c.linear;
  sd.assembled = c.assembled;
  if (c.single != 2) sd.single_precision_matrix = c.single; // 2: leave the default
  sd.cg_fixed = c.cg_fixed;
  sd.cg_iterations = c.cg_fixed ? 60 : 20000;
  sd.cg_tolerance = c.cg_tolerance;
  sd.time_step = 0.05;
  sd.newton_tolerance = 1e-10;
  sd.newton_iterations = 60;
  fascia_solver *s = NULL;
  const fascia_status st = fascia_solver_create(ctx, m, &sd, &s);
  if (st != FASCIA_OK) {
    fascia_ctx_clear(ctx);
    return st;
  }
  *newton = 0;
  for (int k = 0; k < 3; ++k) {
    CHECK_OK(fascia_solver_step(s, rep), ctx);
    *newton += rep->newton_iterations;
  }
  if (x) memcpy(x, fascia_solver_frame_positions(s), 3 * sizeof(double) * (size_t)m->frame_count);
  fascia_solver_destroy(&s);
  return FASCIA_OK;
}

// Whether the run's CG multiplied by the float copy.
static int float_products(fascia_ctx *ctx, const fascia_model *m, choice c) {
  fascia_solve_report rep;
  int newton;
  CHECK(run(ctx, m, c, &rep, &newton, NULL) == FASCIA_OK);
  return rep.single_precision_matrix;
}

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 8, def.frames[1] = 2, def.frames[2] = 2;
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &def, &m), ctx);
  if (!m) return 1;
  const fascia_linear_solver CG = FASCIA_LINEAR_CG;
  const int AUTO = FASCIA_ASSEMBLED_AUTO, DEFAULT = 2;
  CHECK(fascia_solver_def_default().single_precision_matrix == FASCIA_SINGLE_AUTO);
  // the automatic choice
  CHECK(float_products(ctx, m, (choice){"cpu", CG, AUTO, DEFAULT, 0, 1e-3}) == 1);
  CHECK(float_products(ctx, m, (choice){"cpu", CG, AUTO, DEFAULT, 0, FASCIA_SINGLE_MIN_CG_TOLERANCE}) == 1);
  CHECK(float_products(ctx, m, (choice){"cpu", CG, AUTO, DEFAULT, 0, 1e-8}) == 0);
  CHECK(float_products(ctx, m, (choice){"cpu", CG, AUTO, DEFAULT, 1, 1e-8}) == 1); // the paper's mode
  CHECK(float_products(ctx, m, (choice){"cpu", CG, 0, DEFAULT, 0, 1e-3}) == 0);    // matrix-free: no matrix
  CHECK(float_products(ctx, m, (choice){"cpu", FASCIA_LINEAR_DIRECT, AUTO, DEFAULT, 0, 1e-3}) == 0);
  // an explicit choice is kept
  CHECK(float_products(ctx, m, (choice){"cpu", CG, AUTO, 0, 0, 1e-3}) == 0);
  CHECK(float_products(ctx, m, (choice){"cpu", CG, AUTO, 1, 0, 1e-8}) == 1);
  // the device: the default is fine, an explicit float matrix is not
  fascia_solve_report rep;
  int newton;
  CHECK(run(ctx, m, (choice){"emulated", CG, AUTO, DEFAULT, 0, 1e-3}, &rep, &newton, NULL) == FASCIA_OK);
  CHECK(rep.single_precision_matrix == 0);
  CHECK(run(ctx, m, (choice){"emulated", CG, AUTO, 1, 0, 1e-3}, &rep, &newton, NULL) != FASCIA_OK);
  CHECK(run(ctx, m, (choice){"cpu", CG, AUTO, 3, 0, 1e-3}, &rep, &newton, NULL) == FASCIA_ERR_ARGUMENT);
  // float and double products, each step solved to a tight Newton tolerance: the same states
  const int N = m->frame_count;
  double *single = malloc(3 * sizeof(double) * (size_t)N), *dbl = malloc(3 * sizeof(double) * (size_t)N);
  int newton_single = 0, newton_double = 0;
  CHECK(run(ctx, m, (choice){"cpu", CG, AUTO, 1, 0, 1e-3}, &rep, &newton_single, single) == FASCIA_OK);
  CHECK(rep.converged && rep.single_precision_matrix == 1);
  CHECK(run(ctx, m, (choice){"cpu", CG, AUTO, 0, 0, 1e-3}, &rep, &newton_double, dbl) == FASCIA_OK);
  CHECK(rep.converged && rep.single_precision_matrix == 0);
  double diff = 0, largest = 0;
  for (int i = 0; i < N; ++i) {
    double d2 = 0, u2 = 0;
    for (int c = 0; c < 3; ++c) {
      d2 += (single[3 * i + c] - dbl[3 * i + c]) * (single[3 * i + c] - dbl[3 * i + c]);
      u2 += (dbl[3 * i + c] - m->frame_position[3 * i + c]) * (dbl[3 * i + c] - m->frame_position[3 * i + c]);
    }
    diff = fmax(diff, sqrt(d2));
    largest = fmax(largest, sqrt(u2));
  }
  fprintf(stderr, "largest displacement %.6g m, float - double products %.3g m; Newton iterations %d and %d\n", largest,
          diff, newton_single, newton_double);
  CHECK(largest > 0.1);
  CHECK(diff <= 1e-8 * largest);
  CHECK(abs(newton_single - newton_double) <= 1);
  free(single), free(dbl);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
