// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// An organ posed from outside and its wrench: (1) fascia_solver_organ_set_pose
// puts a prescribed and a fixed organ's coupling frames at R x_rest + t
// (rotations Q q_rest) by the end of the next step, and the organ's pose
// reads back; (2) the wrench is the sum of the frame reactions, its torque
// about the point it returns, which is the organ's box centre carried by the
// pose; (3) at a static equilibrium under gravity the wrenches on the two
// organs carry the tissue's weight, force and moment (an oracle apart from
// the reactions: the samples' masses at their deformed positions); (4) bad
// poses and organs are refused with nothing changed, and an organ driven
// frame by frame has no pose but a wrench about its first frame's motion.
#include "backend_arg.h"
#include "check.h"
#include "fascia/organs.h"
#include "organ_fixture.h"
#include "point/linalg.h"

#define C 9 // coupling frames per organ in the fixture

// The wrench about the origin from the frames' reactions: force, moment.
static int wrench_at_origin(fascia_ctx *ctx, fascia_solver *s, int32_t organ, double *force, double *moment) {
  int32_t frames[C];
  double f[3 * C], t[3 * C];
  CHECK_OK(fascia_solver_organ_frames(s, organ, frames), ctx);
  CHECK_OK(fascia_solver_organ_reaction(s, organ, f, t), ctx);
  const double *x = fascia_solver_frame_positions(s);
  for (int c = 0; c < 3; ++c) force[c] = moment[c] = 0;
  for (int k = 0; k < C; ++k) {
    double xf[3];
    fascia_pt_cross(x + 3 * frames[k], f + 3 * k, xf);
    for (int c = 0; c < 3; ++c) force[c] += f[3 * k + c], moment[c] += t[3 * k + c] + xf[c];
  }
  return 0;
}

// Checks the wrench of organ against the reactions (moved to the origin:
// M_0 = M_p + p x F); returns the point in p.
static int check_wrench(fascia_ctx *ctx, fascia_solver *s, int32_t organ, double *p) {
  double F[3], M[3], F0[3], M0[3], pf[3];
  CHECK_OK(fascia_solver_organ_wrench(s, organ, F, M, p), ctx);
  if (wrench_at_origin(ctx, s, organ, F0, M0)) return 1;
  fascia_pt_cross(p, F, pf);
  const double scale = fabs(F0[0]) + fabs(F0[1]) + fabs(F0[2]) + 1e-12;
  for (int c = 0; c < 3; ++c) {
    CHECK_NEAR(F[c], F0[c], 0, 1e-14 * scale);       // the same sum, in the same order
    CHECK_NEAR(M[c] + pf[c], M0[c], 0, 1e-14 * scale); // lever arms below 0.1 m, rounding only
  }
  return 0;
}

int main(int argc, char **argv) {
  const char *backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(backend);
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1; // small model
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  organ_fixture_def fd = organ_fixture_def_default();
  fd.kind_a = FASCIA_ORGAN_FIXED, fd.kind_b = FASCIA_ORGAN_PRESCRIBED; // B's motion: none (pull 0)
  fd.gravity[2] = -9.81;
  fascia_model *m = NULL;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  CHECK(fascia_model_organ_count(m) == 2 && !strcmp(fascia_model_organ_name(m, 1), "b"));
  CHECK(!strcmp(fascia_model_organ_name(m, 2), ""));
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = backend;
  sd.newton_tolerance = 1e-10;
  sd.newton_iterations = 200;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);

  // (3) first, at rest under gravity: both organs hold the tissue
  CHECK_OK(fascia_solver_solve_static(s, NULL), ctx);
  {
    double F[3] = {0, 0, 0}, M[3] = {0, 0, 0}, W[3] = {0, 0, 0}, MW[3] = {0, 0, 0};
    for (int32_t organ = 0; organ < 2; ++organ) {
      double f[3], t[3], p[3], pf[3];
      CHECK_OK(fascia_solver_organ_wrench(s, organ, f, t, p), ctx);
      fascia_pt_cross(p, f, pf);
      for (int c = 0; c < 3; ++c) F[c] += f[c], M[c] += t[c] + pf[c];
    }
    double *xs = malloc(3 * sizeof(double) * (size_t)m->sample_count);
    fascia_solver_sample_positions(s, xs);
    for (int32_t k = 0; k < m->sample_count; ++k) {
      const double mass = m->materials[m->sample_material[k]].density * m->sample_volume[k];
      double w[3], xw[3];
      for (int c = 0; c < 3; ++c) w[c] = mass * m->gravity[c], W[c] += w[c];
      fascia_pt_cross(xs + 3 * k, w, xw);
      for (int c = 0; c < 3; ++c) MW[c] += xw[c];
    }
    free(xs);
    const double weight = fabs(W[2]);
    CHECK(weight > 0);
    for (int c = 0; c < 3; ++c) {
      CHECK_NEAR(F[c], W[c], 0, 1e-8 * weight); // Newton tolerance 1e-10 of the load
      CHECK_NEAR(M[c], MW[c], 0, 1e-9 * weight); // the same, times lever arms below 0.1 m
    }
  }

  // (1) B (prescribed) and A (fixed) posed from outside: 5 degrees about z and a shift
  const double angle = 5 * 3.14159265358979323846 / 180;
  const double tb[3] = {0.002, -0.001, 0.0015}, qb[4] = {cos(angle / 2), 0, 0, sin(angle / 2)};
  const double ta[3] = {-0.001, 0, 0}, qa[4] = {2, 0, 0, 0}; // normalized by the call
  CHECK_OK(fascia_solver_organ_set_pose(s, 1, tb, qb), ctx);
  CHECK_OK(fascia_solver_organ_set_pose(s, 0, ta, qa), ctx);
  CHECK_OK(fascia_solver_step(s, NULL), ctx);
  CHECK_OK(fascia_solver_step(s, NULL), ctx); // and they stay
  double R[9];
  fascia_pt_quat_to_mat(qb, R);
  int32_t fb[C], fa[C];
  CHECK_OK(fascia_solver_organ_frames(s, 1, fb), ctx);
  CHECK_OK(fascia_solver_organ_frames(s, 0, fa), ctx);
  const double *x = fascia_solver_frame_positions(s), *q = fascia_solver_frame_rotations(s);
  for (int k = 0; k < C; ++k) {
    double rx[3];
    fascia_pt_mat_vec(R, m->frame_position + 3 * fb[k], rx);
    for (int c = 0; c < 3; ++c) CHECK_NEAR(x[3 * fb[k] + c], rx[c] + tb[c], 0, 1e-15);
    for (int c = 0; c < 4; ++c) CHECK_NEAR(q[4 * fb[k] + c], qb[c], 0, 1e-15); // rest rotations: identity
    for (int c = 0; c < 3; ++c) CHECK_NEAR(x[3 * fa[k] + c], m->frame_position[3 * fa[k] + c] + ta[c], 0, 1e-15);
  }
  double pose[7];
  CHECK_OK(fascia_solver_organ_pose(s, 1, pose, pose + 3), ctx);
  for (int c = 0; c < 3; ++c) CHECK(pose[c] == tb[c]);
  for (int c = 0; c < 4; ++c) CHECK_NEAR(pose[3 + c], qb[c], 0, 1e-16);
  CHECK_OK(fascia_solver_organ_pose(s, 0, pose, pose + 3), ctx);
  CHECK(pose[3] == 1 && pose[4] == 0); // (2, 0, 0, 0) normalized

  // (2) the wrench: the reactions' sum, about B's box centre carried by the pose
  double p[3], centre[3] = {FIX_L + FIX_A / 2, 0, 0}, expect[3];
  if (check_wrench(ctx, s, 1, p)) return 1;
  fascia_pt_mat_vec(R, centre, expect);
  for (int c = 0; c < 3; ++c) CHECK_NEAR(p[c], expect[c] + tb[c], 0, 1e-15);
  double F[3], M[3];
  CHECK_OK(fascia_solver_organ_wrench(s, 1, F, NULL, NULL), ctx); // torque and point may be NULL
  CHECK(F[0] < 0); // B pulled away along +x: the tissue pulls it back

  // (4) refused, nothing changed
  const double bad_t[3] = {0, NAN, 0}, zero_q[4] = {0, 0, 0, 0};
  CHECK(fascia_solver_organ_set_pose(s, 1, bad_t, qb) == FASCIA_ERR_ARGUMENT);
  CHECK(fascia_solver_organ_set_pose(s, 1, tb, zero_q) == FASCIA_ERR_ARGUMENT);
  CHECK(strstr(fascia_ctx_message(ctx), "'b'") != NULL);
  CHECK(fascia_solver_organ_set_pose(s, 5, tb, qb) == FASCIA_ERR_ARGUMENT);
  CHECK(fascia_solver_organ_wrench(s, -1, F, M, p) == FASCIA_ERR_ARGUMENT);
  CHECK_OK(fascia_solver_organ_pose(s, 1, pose, pose + 3), ctx);
  for (int c = 0; c < 3; ++c) CHECK(pose[c] == tb[c]);
  // driven frame by frame (here: where the pose put them): no pose, the same wrench point
  double xb[3 * C], qbk[4 * C], p2[3];
  for (int k = 0; k < C; ++k) {
    memcpy(xb + 3 * k, x + 3 * fb[k], 3 * sizeof(double));
    memcpy(qbk + 4 * k, q + 4 * fb[k], 4 * sizeof(double));
  }
  CHECK_OK(fascia_solver_organ_set_frames(s, 1, xb, qbk), ctx);
  CHECK(fascia_solver_organ_pose(s, 1, pose, pose + 3) == FASCIA_ERR_UNSUPPORTED);
  if (check_wrench(ctx, s, 1, p2)) return 1;
  for (int c = 0; c < 3; ++c) CHECK_NEAR(p2[c], p[c], 0, 1e-15);
  // released, B follows its motion again: pose at rest
  CHECK_OK(fascia_solver_organ_release(s, 1), ctx);
  CHECK_OK(fascia_solver_organ_pose(s, 1, pose, pose + 3), ctx);
  CHECK(pose[0] == 0 && pose[3] == 1);

  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
