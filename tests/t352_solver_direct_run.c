// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A run with the direct solver ends where the same run with CG solved to
// round-off ends: dynamic steps of a cantilever falling under its own
// weight (large rotations) and its static sag, both to a tight Newton
// tolerance, agree to 1e-7 of the largest displacement. The same with a
// rigid organ hanging from tissue under gravity: the direct solver factors
// the reduced matrix P^T K P with the body's mass and geometric terms
// (organs.c), CG applies the same operator by products. The direct dynamic
// runs keep a factorization for some Newton iterations (chord steps, where
// the last step lowered the gradient tenfold) and still end where CG ends;
// the static solves factor at every iteration.
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "fascia/solver.h"
#include "organ_fixture.h"
#include "scenes.h"

static int run(fascia_ctx *ctx, const fascia_model *m, fascia_linear_solver linear, int dynamic, double dt,
               double *x, int *newton, int *factorizations) {
  fascia_solver_def sd = fascia_solver_def_default();
  sd.linear_solver = linear;
  sd.assembled = 1; // CG: the same matrix, faster products
  sd.time_step = dt;
  sd.newton_tolerance = 1e-11;
  sd.newton_iterations = 60;
  sd.cg_iterations = 20000;
  sd.cg_tolerance = 1e-12;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  if (!s) return 1;
  fascia_solve_report rep;
  *newton = *factorizations = 0;
  for (int k = 0; k < (dynamic ? 3 : 1); ++k) {
    CHECK_OK(dynamic ? fascia_solver_step(s, &rep) : fascia_solver_solve_static(s, &rep), ctx);
    CHECK(rep.direct == (linear == FASCIA_LINEAR_DIRECT));
    CHECK(rep.factorizations == 0 || linear == FASCIA_LINEAR_DIRECT);
    *newton += rep.newton_iterations;
    *factorizations += rep.factorizations;
  }
  memcpy(x, fascia_solver_frame_positions(s), 3 * sizeof(double) * (size_t)m->frame_count);
  fascia_solver_destroy(&s);
  return 0;
}

// Direct against CG, dynamic and static; the largest displacement must pass least.
static void compare(fascia_ctx *ctx, const fascia_model *m, double dt, double least, const char *what) {
  const int N = m->frame_count;
  double *direct = malloc(3 * sizeof(double) * (size_t)N), *cg = malloc(3 * sizeof(double) * (size_t)N);
  for (int dynamic = 0; dynamic <= 1; ++dynamic) {
    int newton, factorizations, cg_newton, none;
    if (run(ctx, m, FASCIA_LINEAR_DIRECT, dynamic, dt, direct, &newton, &factorizations) ||
        run(ctx, m, FASCIA_LINEAR_CG, dynamic, dt, cg, &cg_newton, &none))
      break;
    double diff = 0, largest = 0;
    for (int i = 0; i < N; ++i) {
      double d2 = 0, u2 = 0;
      for (int c = 0; c < 3; ++c) {
        d2 += (direct[3 * i + c] - cg[3 * i + c]) * (direct[3 * i + c] - cg[3 * i + c]);
        const double u = direct[3 * i + c] - m->frame_position[3 * i + c];
        u2 += u * u;
      }
      diff = fmax(diff, sqrt(d2));
      largest = fmax(largest, sqrt(u2));
    }
    fprintf(stderr, "%s, %s: largest displacement %.6g m, direct - CG %.3g m; direct: %d Newton, %d factorizations\n",
            what, dynamic ? "dynamic" : "static", largest, diff, newton, factorizations);
    CHECK(largest > least);
    CHECK(dynamic ? factorizations >= 3 && factorizations < newton : factorizations == newton);
    CHECK(diff <= 1e-7 * largest);
  }
  free(direct), free(cg);
}

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 6, def.frames[1] = 2, def.frames[2] = 2;
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &def, &m), ctx);
  if (!m) return 1;
  compare(ctx, m, 0.05, 0.1, "cantilever");
  fascia_model_destroy(&m);
  // organ b rigid, held by the tissue from the fixed a, under gravity across the tissue
  organ_fixture_def fd = organ_fixture_def_default();
  fd.gravity[1] = -9.81, fd.gravity[2] = 3;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  if (m) compare(ctx, m, 0.01, 1e-4, "rigid organ");
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
