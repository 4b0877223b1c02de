// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// An unconstrained body falls freely under gravity: every frame accelerates
// at g and no frame rotates, with consistent and lumped mass, for implicit
// Euler steps (the exact discrete solution is x_n = x_0 + g h^2 n(n+1)/2).
#include <stdlib.h>
#include <string.h>

#include "backend_arg.h"
#include "check.h"
#include "scenes.h"
#include "fascia/solver.h"

static const char *backend = "cpu";

static int fall(fascia_ctx *ctx, fascia_mass_kind mass, int shape) {
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  // with the consistent mass, rotating all frames together (positions kept)
  // has neither inertia nor stiffness; the rotation coupling removes that
  // mode (docs/mechanics.md), the lumped mass gives it inertia. 1e-5: with
  // 1e-6 the CG backends' inexact solves turned the tetrahedral frames at
  // 3e-7 rad/s once their rotation smoothing was 0.05 (fascia beam's rule)
  if (mass == FASCIA_MASS_CONSISTENT) def.rotation_coupling = 1e-5;
  def.frames[0] = 5, def.frames[1] = 2, def.frames[2] = 2, def.length = 4, def.shape = shape;
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &def, &m), ctx);
  for (int i = 0; i < m->frame_count; ++i) m->frame_kind[i] = FASCIA_FRAME_FREE; // unclamp
  fascia_solver_def sd = fascia_solver_def_default();
  sd.mass = mass;
  sd.backend = backend;
  sd.time_step = 0.01;
  sd.newton_tolerance = 1e-10;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  const int steps = 10;
  for (int n = 0; n < steps; ++n) CHECK_OK(fascia_solver_step(s, NULL), ctx);
  const double h = sd.time_step, drop = -9.81 * h * h * steps * (steps + 1) / 2, vz = -9.81 * h * steps;
  const double *x = fascia_solver_frame_positions(s), *q = fascia_solver_frame_rotations(s);
  const double *u = fascia_solver_frame_velocities(s);
  for (int i = 0; i < m->frame_count; ++i) {
    // a rigid translation has no internal force: exact up to solver tolerance
    CHECK_NEAR(x[3 * i + 2] - m->frame_position[3 * i + 2], drop, 0, 1e-9);
    CHECK_NEAR(x[3 * i], m->frame_position[3 * i], 0, 1e-9);
    CHECK_NEAR(u[6 * i + 2], vz, 0, 1e-7);
    for (int c = 0; c < 3; ++c) CHECK_NEAR(u[6 * i + 3 + c], 0, 0, 1e-7);
    for (int c = 0; c < 4; ++c) CHECK_NEAR(q[4 * i + c], m->frame_rotation[4 * i + c], 0, 1e-9);
  }
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  return 0;
}

int main(int argc, char **argv) {
  backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(backend);
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  int failed = 0;
  failed |= fall(ctx, FASCIA_MASS_CONSISTENT, FASCIA_SCENE_HEX);
  failed |= fall(ctx, FASCIA_MASS_LUMPED, FASCIA_SCENE_HEX);
  failed |= fall(ctx, FASCIA_MASS_CONSISTENT, FASCIA_SCENE_TET);
  failed |= fall(ctx, FASCIA_MASS_LUMPED, FASCIA_SCENE_TET);
  fascia_ctx_destroy(&ctx);
  return failed | CHECK_RESULT();
}
