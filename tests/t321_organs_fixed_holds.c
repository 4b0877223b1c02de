// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A fixed organ holds its coupling frames exactly (bit for bit, positions
// and rotations) while the tissue it holds carries a rigid organ sagging
// under gravity, in dynamic steps and in a static solve; its pose stays the
// identity, and the rigid organ's coupling frames stay rigid. On the CPU
// the automatic linear solver takes the direct solver for the dynamic steps
// and CG for the static solve, whose tangent is indefinite here (the
// shifted factorization does not converge in 20 Newton iterations).
#include <string.h>

#include "backend_arg.h"
#include "check.h"
#include "fascia/organs.h"
#include "organ_fixture.h"
#include "point/linalg.h"

static const char *backend = "cpu"; // --backend (tests/backend_arg.h)

static int check_fixed(const fascia_model *m, const fascia_solver *s) {
  int bad = 0;
  const double *x = fascia_solver_frame_positions(s), *q = fascia_solver_frame_rotations(s);
  int32_t frames[9];
  if (fascia_solver_organ_frame_count(s, 0) != 9 || fascia_solver_organ_frames(s, 0, frames) != FASCIA_OK) return 1;
  for (int k = 0; k < 9; ++k) {
    const int32_t i = frames[k];
    for (int c = 0; c < 3; ++c) bad += x[3 * i + c] != m->frame_position[3 * i + c];
    for (int c = 0; c < 4; ++c) bad += q[4 * i + c] != m->frame_rotation[4 * i + c];
  }
  double t[3], r[4];
  if (fascia_solver_organ_pose(s, 0, t, r) != FASCIA_OK) return 1;
  bad += t[0] != 0 || t[1] != 0 || t[2] != 0 || r[0] != 1 || r[1] != 0 || r[2] != 0 || r[3] != 0;
  return bad;
}

int main(int argc, char **argv) {
  backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(backend);
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1; // small model: threads cost more than they give
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  organ_fixture_def fd = organ_fixture_def_default(); // A fixed, B rigid
  fd.gravity[2] = -9.81;
  fascia_model *m = NULL;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = backend;
  sd.time_step = 0.01;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  const int cpu = !strcmp(backend, "cpu");
  fascia_solve_report rep;
  for (int n = 0; n < 20; ++n) {
    CHECK_OK(fascia_solver_step(s, &rep), ctx);
    CHECK(check_fixed(m, s) == 0);
    CHECK(rep.direct == cpu);
  }
  CHECK_OK(fascia_solver_solve_static(s, &rep), ctx);
  CHECK(check_fixed(m, s) == 0);
  CHECK(rep.direct == 0);
  // B hangs below its rest place (the tissue is soft: 5 kPa)
  double t[3], r[4], R[9], centre[3], cw[3];
  CHECK_OK(fascia_solver_organ_pose(s, 1, t, r), ctx);
  CHECK_OK(fascia_solver_organ_mass(s, 1, NULL, centre, NULL), ctx);
  fascia_pt_quat_to_mat(r, R);
  fascia_pt_mat_vec(R, centre, cw);
  CHECK(cw[2] + t[2] < -1e-3);
  // B's coupling frames stay on the rigid body: x_i = R x_i,rest + t
  int32_t frames[9];
  CHECK_OK(fascia_solver_organ_frames(s, 1, frames), ctx);
  const double *x = fascia_solver_frame_positions(s);
  for (int k = 0; k < 9; ++k) {
    double p[3];
    fascia_pt_mat_vec(R, m->frame_position + 3 * frames[k], p);
    for (int c = 0; c < 3; ++c) CHECK_NEAR(x[3 * frames[k] + c], p[c] + t[c], 0, 1e-14);
  }
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
