// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The outside-simulator API round-trips: (1) a rigid organ loaded by a force
// finds its static equilibrium, where the tissue's reaction on its coupling
// frames balances the load (force and moment); (2) an outside simulator that
// sets the same frames (fascia_solver_organ_set_frames) and solves reads back
// the same reaction, equal and opposite to the load; (3) the reaction is
// minus the derivative of the potential energy (central differences), and
// follows the state and the loads, not a kept state's; (4) in
// dynamic steps the frames land exactly on the targets, and a released organ
// is a rigid body again.
#include "backend_arg.h"
#include "check.h"
#include "fascia/organs.h"
#include "organ_fixture.h"
#include "point/linalg.h"

static const char *backend = "cpu"; // --backend (tests/backend_arg.h)

#define C 9 // coupling frames per organ in the fixture

int main(int argc, char **argv) {
  backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(backend);
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1; // small model: threads cost more than they give
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  organ_fixture_def fd = organ_fixture_def_default(); // A fixed, B rigid, no gravity
  fascia_model *m = NULL;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = backend;
  sd.newton_tolerance = 1e-11;
  sd.newton_iterations = 200;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  CHECK(fascia_model_find_organ(m, "b") == 1 && fascia_model_find_organ(m, "liver") == -1);
  int32_t fb[C], fa[C];
  CHECK(fascia_solver_organ_frame_count(s, 1) == C);
  CHECK_OK(fascia_solver_organ_frames(s, 1, fb), ctx);
  CHECK_OK(fascia_solver_organ_frames(s, 0, fa), ctx);
  // a load on B: 0.05 N down and 0.02 N sideways on two of its frames
  double total[3] = {0, 0, 0};
  m->frame_load[6 * fb[0] + 2] = -0.03, m->frame_load[6 * fb[0] + 1] = 0.02;
  m->frame_load[6 * fb[8] + 2] = -0.02;
  for (int k = 0; k < C; ++k)
    for (int c = 0; c < 3; ++c) total[c] += m->frame_load[6 * fb[k] + c];

  // (1) B as a rigid body: equilibrium, reaction + load = 0 in force and moment
  CHECK_OK(fascia_solver_solve_static(s, NULL), ctx);
  double f1[3 * C], t1[3 * C], x1[3 * C], q1[4 * C];
  CHECK_OK(fascia_solver_organ_reaction(s, 1, f1, t1), ctx);
  const double *x = fascia_solver_frame_positions(s), *q = fascia_solver_frame_rotations(s);
  double fsum[3] = {0, 0, 0}, msum[3] = {0, 0, 0};
  for (int k = 0; k < C; ++k) {
    memcpy(x1 + 3 * k, x + 3 * fb[k], 3 * sizeof(double));
    memcpy(q1 + 4 * k, q + 4 * fb[k], 4 * sizeof(double));
    double f[3], rf[3];
    for (int c = 0; c < 3; ++c) f[c] = f1[3 * k + c] + m->frame_load[6 * fb[k] + c], fsum[c] += f[c];
    fascia_pt_cross(x + 3 * fb[k], f, rf); // moment about the origin
    for (int c = 0; c < 3; ++c) msum[c] += rf[c] + t1[3 * k + c];
  }
  for (int c = 0; c < 3; ++c) {
    CHECK_NEAR(fsum[c], 0, 0, 1e-8);  // Newton tolerance 1e-11 of |load| 0.04 N, and rounding
    CHECK_NEAR(msum[c], 0, 0, 1e-9);  // lever arms below 0.1 m
  }
  CHECK(x1[3 * 0 + 2] < m->frame_position[3 * fb[0] + 2] - 1e-3); // it sagged

  // (2) the outside simulator puts B's frames there: same reaction, equal and opposite to the load
  fascia_solver *s2 = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s2), ctx);
  CHECK_OK(fascia_solver_organ_set_frames(s2, 1, x1, q1), ctx);
  double pose[7];
  CHECK(fascia_solver_organ_pose(s2, 1, pose, pose + 3) == FASCIA_ERR_UNSUPPORTED);
  CHECK_OK(fascia_solver_solve_static(s2, NULL), ctx);
  double f2[3 * C], t2[3 * C];
  CHECK_OK(fascia_solver_organ_reaction(s2, 1, f2, t2), ctx);
  double f2sum[3] = {0, 0, 0};
  for (int k = 0; k < C; ++k)
    for (int c = 0; c < 3; ++c) {
      CHECK_NEAR(f2[3 * k + c], f1[3 * k + c], 0, 1e-7); // both states converged to 1e-11 relative
      CHECK_NEAR(t2[3 * k + c], t1[3 * k + c], 0, 1e-8);
      f2sum[c] += f2[3 * k + c];
    }
  for (int c = 0; c < 3; ++c) CHECK_NEAR(f2sum[c], -total[c], 0, 1e-7);
  const double *x2 = fascia_solver_frame_positions(s2);
  for (int64_t k = 0; k < 3 * (int64_t)m->frame_count; ++k) CHECK_NEAR(x2[k], x[k], 0, 1e-8);

  // (3) reaction = -dE/dx at an A frame and a B frame (E: the potential energy
  // of the tissue, B's frames driven so that no body term enters)
  {
    double *xs = malloc(3 * sizeof(double) * m->frame_count), *qs = malloc(4 * sizeof(double) * m->frame_count);
    memcpy(xs, x2, 3 * sizeof(double) * m->frame_count);
    memcpy(qs, fascia_solver_frame_rotations(s2), 4 * sizeof(double) * m->frame_count);
    double fa_r[3 * C];
    CHECK_OK(fascia_solver_organ_reaction(s2, 0, fa_r, NULL), ctx);
    const int32_t probe[2] = {fa[4], fb[4]};
    const double *expect[2] = {fa_r + 12, f2 + 12};
    const double eps = 1e-6;
    for (int p = 0; p < 2; ++p)
      for (int c = 0; c < 3; ++c) {
        double e_plus, e_minus;
        const double keep = xs[3 * probe[p] + c];
        xs[3 * probe[p] + c] = keep + eps;
        CHECK_OK(fascia_solver_set_state(s2, xs, qs, NULL), ctx);
        CHECK_OK(fascia_solver_potential_energy(s2, &e_plus), ctx);
        xs[3 * probe[p] + c] = keep - eps;
        CHECK_OK(fascia_solver_set_state(s2, xs, qs, NULL), ctx);
        CHECK_OK(fascia_solver_potential_energy(s2, &e_minus), ctx);
        xs[3 * probe[p] + c] = keep;
        // the energy holds -load.x too: add the load back
        const double load = m->frame_load[6 * probe[p] + c];
        CHECK_NEAR(-(e_plus - e_minus) / (2 * eps) - load, expect[p][c], 1e-5, 1e-9);
      }
    CHECK_OK(fascia_solver_set_state(s2, xs, qs, NULL), ctx);
    // the reaction follows the state and the loads (the solver keeps one
    // gradient for the queries of one state): a load added on a coupling
    // frame leaves it as it was (it is the tissue's force alone), a frame
    // moved changes it, and moved back gives it again
    double r0[3 * C], r1[3 * C], r2[3 * C];
    CHECK_OK(fascia_solver_organ_reaction(s2, 1, r0, NULL), ctx);
    m->frame_load[6 * fb[2]] += 0.5;
    CHECK_OK(fascia_solver_organ_reaction(s2, 1, r1, NULL), ctx);
    m->frame_load[6 * fb[2]] -= 0.5;
    for (int k = 0; k < 3 * C; ++k) CHECK_NEAR(r1[k], r0[k], 1e-12, 1e-15);
    xs[3 * fb[4]] += 1e-4;
    CHECK_OK(fascia_solver_set_state(s2, xs, qs, NULL), ctx);
    CHECK_OK(fascia_solver_organ_reaction(s2, 1, r2, NULL), ctx);
    double moved = 0;
    for (int k = 0; k < 3 * C; ++k) moved = fmax(moved, fabs(r2[k] - r0[k]));
    CHECK(moved > 1e-9);
    xs[3 * fb[4]] -= 1e-4;
    CHECK_OK(fascia_solver_set_state(s2, xs, qs, NULL), ctx);
    CHECK_OK(fascia_solver_organ_reaction(s2, 1, r2, NULL), ctx);
    for (int k = 0; k < 3 * C; ++k) CHECK_NEAR(r2[k], r0[k], 1e-12, 1e-15);
    free(xs), free(qs);
  }

  // (4) dynamic: the frames land on the targets; released, B is a rigid body again
  fascia_solver_destroy(&s2);
  sd.time_step = 0.01;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s2), ctx);
  double target[3 * C], rot[4 * C];
  for (int step = 1; step <= 3; ++step) {
    for (int k = 0; k < C; ++k) {
      for (int c = 0; c < 3; ++c) target[3 * k + c] = m->frame_position[3 * fb[k] + c];
      target[3 * k + 0] += 0.001 * step; // the outside organ pushes B's face 1 mm per step
      rot[4 * k] = 1, rot[4 * k + 1] = rot[4 * k + 2] = rot[4 * k + 3] = 0;
    }
    CHECK_OK(fascia_solver_organ_set_frames(s2, 1, target, rot), ctx);
    CHECK_OK(fascia_solver_step(s2, NULL), ctx);
    const double *xd = fascia_solver_frame_positions(s2);
    for (int k = 0; k < C; ++k)
      for (int c = 0; c < 3; ++c) CHECK_NEAR(xd[3 * fb[k] + c], target[3 * k + c], 0, 1e-15);
    double f[3 * C], push = 0;
    CHECK_OK(fascia_solver_organ_reaction(s2, 1, f, NULL), ctx);
    for (int k = 0; k < C; ++k) push += f[3 * k];
    CHECK(push < 0); // compressed tissue pushes back on the outside organ
  }
  CHECK_OK(fascia_solver_organ_release(s2, 1), ctx);
  CHECK_OK(fascia_solver_organ_pose(s2, 1, pose, pose + 3), ctx);
  CHECK_NEAR(pose[0], 0.003, 0, 1e-12);
  for (int n = 0; n < 3; ++n) CHECK_OK(fascia_solver_step(s2, NULL), ctx);
  double v[3], w[3];
  CHECK_OK(fascia_solver_organ_velocity(s2, 1, v, w), ctx);
  CHECK(v[0] != 0);
  // bad input: nothing changes
  target[5] = NAN;
  CHECK(fascia_solver_organ_set_frames(s2, 1, target, rot) == FASCIA_ERR_ARGUMENT);
  CHECK(fascia_solver_organ_set_frames(s2, 7, target, rot) == FASCIA_ERR_ARGUMENT);
  CHECK_OK(fascia_solver_organ_pose(s2, 1, pose, pose + 3), ctx);
  fascia_solver_destroy(&s2);
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
