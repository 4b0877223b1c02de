// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A Newton tolerance below the forces' round-off does not fail steps at
// random. Nearly incompressible tissue (nu = 0.49) in volumetric patches
// keeps most of its stiffness in the patches' lambda, not the samples':
// the forces' round-off floor of the Newton solver must count it. A floor
// from the samples' lambda share only is 50 times too low here: the 10 x 2
// x 2 cantilever's steps at a tolerance of 1e-10 would reach round-off,
// bounce on it until the iteration limit, and be rejected and split, or
// not, by rounding luck, so that linear solvers agreeing on everything else
// end far apart. Every linear solver must take each of the three steps whole,
// in a few iterations, and all must end at the same state. And where the
// estimate falls short, a |gradient| that stops falling near it is the
// floor: a static solve to 1e-14 converges there.
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "fascia/solver.h"
#include "scenes.h"

// The CPU solver with this linear solver, double products, and a Newton
// tolerance below the round-off floor
static fascia_solver_def tight(fascia_linear_solver linear, int assembled, double newton_tolerance) {
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = "cpu";
  sd.linear_solver = linear;
  sd.assembled = assembled;
  sd.single_precision_matrix = 0;
  sd.newton_tolerance = newton_tolerance;
  return sd;
}

static int run(fascia_ctx *ctx, const fascia_model *m, fascia_linear_solver linear, int assembled, double *x) {
  fascia_solver_def sd = tight(linear, assembled, 1e-10);
  sd.cg_tolerance = 1e-6;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  if (!s) return 1;
  for (int k = 0; k < 3; ++k) {
    fascia_solve_report rep;
    CHECK_OK(fascia_solver_step(s, &rep), ctx);
    fprintf(stderr, "%s%s, step %d: %d Newton iterations, %d rejected, |gradient| %.3g\n",
            linear == FASCIA_LINEAR_DIRECT ? "direct" : "CG", assembled ? " (assembled)" : "", k + 1,
            rep.newton_iterations, rep.rejected, rep.gradient_norm);
    CHECK(rep.converged && rep.rejected == 0 && rep.substeps == 1);
    CHECK(rep.newton_iterations <= 12);
  }
  memcpy(x, fascia_solver_frame_positions(s), 3 * sizeof(double) * (size_t)m->frame_count);
  fascia_solver_destroy(&s);
  return 0;
}

// A static solve asked for a tolerance far below round-off (1e-14 of the
// load) ends converged where |gradient| stops falling, near the round-off
// estimate (the estimate is rough: the sanitized build's 6 x 2 x 2
// cantilever stalled at 1.4e-10 where it gives 9.5e-11, and failed after
// 60 iterations at a tolerance of 1e-11), with every linear solver.
static int static_floor(fascia_ctx *ctx, int shape, fascia_linear_solver linear, int assembled) {
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 6, def.frames[1] = 2, def.frames[2] = 2;
  def.shape = shape;
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &def, &m), ctx);
  if (!m) return 1;
  fascia_solver_def sd = tight(linear, assembled, 1e-14);
  sd.newton_iterations = 60;
  sd.cg_tolerance = 1e-12;
  sd.cg_iterations = 20000;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  fascia_solve_report rep;
  if (s) {
    CHECK_OK(fascia_solver_solve_static(s, &rep), ctx);
    fprintf(stderr, "static %s, %s%s: %d Newton iterations, |gradient| %.3g (load %.3g)\n",
            shape == FASCIA_SCENE_TET ? "tet" : "hex", linear == FASCIA_LINEAR_DIRECT ? "direct" : "CG",
            assembled ? " (assembled)" : "", rep.newton_iterations, rep.gradient_norm, rep.reference_norm);
    CHECK(rep.converged && rep.newton_iterations < 40);
    CHECK(rep.gradient_norm <= 1e-7 * rep.reference_norm);
  }
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  return 0;
}

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 10, def.frames[1] = 2, def.frames[2] = 2;
  def.volumetric_patch = FASCIA_SCENE_PATCH_CELL;
  def.poisson_ratio = 0.49;
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &def, &m), ctx);
  if (!m) return 1;
  const int N = m->frame_count;
  double *x[3];
  for (int v = 0; v < 3; ++v) x[v] = malloc(3 * sizeof(double) * (size_t)N);
  if (!run(ctx, m, FASCIA_LINEAR_DIRECT, 1, x[0]) && !run(ctx, m, FASCIA_LINEAR_CG, 1, x[1]) &&
      !run(ctx, m, FASCIA_LINEAR_CG, 0, x[2])) {
    double largest = 0, diff = 0;
    for (int i = 0; i < 3 * N; ++i) {
      largest = fmax(largest, fabs(x[0][i] - m->frame_position[i]));
      diff = fmax(diff, fmax(fabs(x[1][i] - x[0][i]), fabs(x[2][i] - x[0][i])));
    }
    fprintf(stderr, "largest displacement %.3g m, solvers apart %.3g m\n", largest, diff);
    CHECK(largest > 1e-3);
    CHECK(diff <= 1e-6 * largest);
  }
  for (int v = 0; v < 3; ++v) free(x[v]);
  fascia_model_destroy(&m);
  for (int shape = FASCIA_SCENE_HEX; shape <= FASCIA_SCENE_TET; ++shape)
    if (static_floor(ctx, shape, FASCIA_LINEAR_DIRECT, 1) || static_floor(ctx, shape, FASCIA_LINEAR_CG, 1) ||
        static_floor(ctx, shape, FASCIA_LINEAR_CG, 0))
      break;
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
