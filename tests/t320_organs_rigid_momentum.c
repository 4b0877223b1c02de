// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A force on one coupling frame of a free rigid organ moves the organ with
// exact momentum balance: over n implicit steps m (v_n - v_0) equals the
// impulse n h F, and each step's angular momentum change about the centre
// equals h J_l(h w)^T (r x F) (the torque of the load at the step's end,
// through the rotation map of the step); the coupling frames stay rigid.
#include "backend_arg.h"
#include "check.h"
#include "fascia/organs.h"
#include "organ_fixture.h"
#include "point/linalg.h"

static const char *backend = "cpu"; // --backend (tests/backend_arg.h)

#define STEPS 5
#define H 0.01

// J_l(phi)^T g, transposed left Jacobian of the exponential map.
static void jlt(const double *phi, const double *g, double *out) {
  const double t2 = fascia_pt_dot3(phi, phi), t = sqrt(t2);
  const double a = t < 1e-4 ? 0.5 - t2 / 24 : (1 - cos(t)) / t2;
  const double b = t < 1e-4 ? 1.0 / 6 - t2 / 120 : (t - sin(t)) / (t2 * t);
  double pg[3], ppg[3];
  fascia_pt_cross(phi, g, pg);
  fascia_pt_cross(phi, pg, ppg);
  for (int c = 0; c < 3; ++c) out[c] = g[c] - a * pg[c] + b * ppg[c];
}

int main(int argc, char **argv) {
  backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(backend);
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1; // small model: threads cost more than they give
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  // B is rigid and nothing touches it (cut), no gravity: the load alone acts
  organ_fixture_def fd = organ_fixture_def_default();
  fd.cut = 1;
  fascia_model *m = NULL;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = backend;
  sd.time_step = H;
  sd.newton_tolerance = 1e-13; // the balance holds to the Newton tolerance: make it rounding
  sd.newton_iterations = 50;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  const int32_t count = fascia_solver_organ_frame_count(s, 1);
  CHECK(count == 9);
  int32_t frames[9];
  CHECK_OK(fascia_solver_organ_frames(s, 1, frames), ctx);
  // load on a corner frame: force and torque about the centre
  const int32_t loaded = frames[0];
  const double F[3] = {0.02, -0.01, 0.03}; // N
  for (int c = 0; c < 3; ++c) m->frame_load[6 * loaded + c] = F[c];
  double mass, centre[3], inertia[9];
  CHECK_OK(fascia_solver_organ_mass(s, 1, &mass, centre, inertia), ctx);
  CHECK_NEAR(mass, 1000 * FIX_A * FIX_W * FIX_W, 1e-12, 0);             // box volume x 1000 kg/m^3
  CHECK_NEAR(inertia[0], mass * 2 * FIX_W * FIX_W / 12, 1e-10, 0);       // m (b^2 + c^2) / 12
  CHECK_NEAR(inertia[4], mass * (FIX_A * FIX_A + FIX_W * FIX_W) / 12, 1e-10, 0);
  CHECK_NEAR(centre[0], FIX_L + FIX_A / 2, 0, 1e-15);
  double v_prev[3] = {0, 0, 0}, w_prev[3] = {0, 0, 0};
  for (int n = 1; n <= STEPS; ++n) {
    double t0[3], q0[4], R0[9];
    CHECK_OK(fascia_solver_organ_pose(s, 1, t0, q0), ctx);
    fascia_pt_quat_to_mat(q0, R0);
    fascia_solve_report rep;
    CHECK_OK(fascia_solver_step(s, &rep), ctx);
    CHECK(rep.converged);
    double v[3], w[3], t1[3], q1[4], R1[9], c1[3];
    CHECK_OK(fascia_solver_organ_velocity(s, 1, v, w), ctx);
    CHECK_OK(fascia_solver_organ_pose(s, 1, t1, q1), ctx);
    // linear momentum: m v_n = n h F
    for (int c = 0; c < 3; ++c) CHECK_NEAR(mass * v[c], n * H * F[c], 1e-9, 1e-15);
    // angular momentum about the centre: I_w(q_{n-1}) (w_n - w_{n-1}) = h J_l(h w_n)^T (r x F)
    fascia_pt_quat_to_mat(q1, R1);
    fascia_pt_mat_vec(R1, centre, c1);
    for (int c = 0; c < 3; ++c) c1[c] += t1[c];
    const double *x = fascia_solver_frame_positions(s);
    double r[3], tau[3], jt[3], phi[3], dw[3], tmp[3], Iw[3];
    for (int c = 0; c < 3; ++c) r[c] = x[3 * loaded + c] - c1[c], phi[c] = H * w[c], dw[c] = w[c] - w_prev[c];
    fascia_pt_cross(r, F, tau);
    jlt(phi, tau, jt);
    fascia_pt_mat_tvec(R0, dw, tmp); // I_w = R0 I R0^T
    fascia_pt_mat_vec(inertia, tmp, Iw);
    fascia_pt_mat_vec(R0, Iw, tmp);
    for (int c = 0; c < 3; ++c) CHECK_NEAR(tmp[c], H * jt[c], 1e-8, 1e-17);
    // the coupling frames are rigid: distances to the loaded frame kept
    for (int k = 1; k < count; ++k) {
      double d0 = 0, d1 = 0;
      for (int c = 0; c < 3; ++c) {
        const double a = m->frame_position[3 * frames[k] + c] - m->frame_position[3 * loaded + c];
        const double b = x[3 * frames[k] + c] - x[3 * loaded + c];
        d0 += a * a, d1 += b * b;
      }
      CHECK_NEAR(sqrt(d1), sqrt(d0), 1e-12, 0);
    }
    memcpy(v_prev, v, sizeof v);
    memcpy(w_prev, w, sizeof w);
  }
  // it moved: the centre travelled about n^2 h^2 F / (2m) along F
  double t1[3], q1[4];
  CHECK_OK(fascia_solver_organ_pose(s, 1, t1, q1), ctx);
  CHECK(fabs(q1[0]) < 1 - 1e-9);
  CHECK(t1[2] > 0);
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
