// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Boundary conditions propagate from one organ to another through the
// tissue (paper sec. 4.2, Figs. 5-7): pulling organ A (prescribed) moves the
// free rigid organ B; at static equilibrium B has followed A's translation
// exactly (nothing else holds it); with the tissue between them removed, B
// does not move at all.
#include "backend_arg.h"
#include "check.h"
#include "fascia/organs.h"
#include "organ_fixture.h"

static const char *backend = "cpu"; // --backend (tests/backend_arg.h)

#define PULL 0.01 // m along x (away from B: a traction) and 0.005 m down

static fascia_status run(fascia_ctx *ctx, int cut, double *moved) {
  organ_fixture_def fd = organ_fixture_def_default();
  fd.kind_a = FASCIA_ORGAN_PRESCRIBED;
  fd.cut = cut;
  fd.pull_a[0] = -PULL, fd.pull_a[2] = -PULL / 2;
  fascia_model *m = NULL;
  fascia_status st = organ_fixture_build(ctx, &fd, &m);
  if (st != FASCIA_OK) return st;
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = backend;
  sd.time_step = 0.05;
  fascia_solver *s = NULL;
  st = fascia_solver_create(ctx, m, &sd, &s);
  for (int n = 0; n < 30 && st == FASCIA_OK; ++n) st = fascia_solver_step(s, NULL); // 1 s pull, 0.5 s hold
  double t[3], r[4];
  if (st == FASCIA_OK) st = fascia_solver_organ_pose(s, 1, t, r);
  if (st == FASCIA_OK) memcpy(moved, t, sizeof t);
  if (st == FASCIA_OK && !cut) {
    st = fascia_solver_solve_static(s, NULL);
    if (st == FASCIA_OK) st = fascia_solver_organ_pose(s, 1, t, r);
    if (st == FASCIA_OK) memcpy(moved + 3, t, sizeof t), memcpy(moved + 6, r, sizeof r);
  }
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  return st;
}

int main(int argc, char **argv) {
  backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(backend);
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1; // small model: threads cost more than they give
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  double with[10] = {0}, without[3] = {1, 1, 1};
  CHECK_OK(run(ctx, 0, with), ctx);
  CHECK_OK(run(ctx, 1, without), ctx);
  // dynamic: B followed A through the tissue (a spring of about 75 N/m on 27 g)
  CHECK(with[0] < -0.5 * PULL);
  CHECK(with[2] < -0.25 * PULL);
  // static: the whole tissue and B translate with A, no rotation
  CHECK_NEAR(with[3], -PULL, 1e-6, 0);
  CHECK_NEAR(with[4], 0, 0, 1e-9);
  CHECK_NEAR(with[5], -PULL / 2, 1e-6, 0);
  CHECK_NEAR(fabs(with[6]), 1, 0, 1e-9);
  // without the tissue between them nothing reaches B
  CHECK(without[0] == 0 && without[1] == 0 && without[2] == 0);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
