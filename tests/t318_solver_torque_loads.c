// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Torques in the frames' loads (frame_load[3..5]): a dead torque has no
// potential on the rotations, so the step objective takes its work along
// the step's own rotation increments (sim/point/frame.h,
// fascia_pt_frame_step_rotation). On the cantilever with a torque about y
// on its end frames, gravity off:
//  - the static solve converges, and at equilibrium the clamp carries the
//    torque: the internal moments on the fixed frames, sum (x g_x + g_theta),
//    add up to minus the applied torque (the internal energy is invariant
//    under rotation), and the end bends about y;
//  - 40 dynamic steps of 0.01 s converge, and the energy rule holds (the
//    torque's work counted): the end swings about the static deflection;
//  - twice the torque, twice the static deflection, within the beam's
//    geometric nonlinearity (under 1 %).
// Before the objective counted the torque's work, the line search saw a
// descent direction raise the objective, and neither solve moved.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "backend_arg.h"
#include "check.h"
#include "point/linalg.h"
#include "scenes.h"
#include "solve/solver_internal.h"

static fascia_model *loaded_beam(fascia_ctx *ctx, double torque) {
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 8, def.frames[1] = 2, def.frames[2] = 2, def.length = 4;
  def.gravity[2] = 0;
  fascia_model *m = NULL;
  if (fascia_scene_beam_build(ctx, &def, &m) != FASCIA_OK) return NULL;
  int loaded = 0;
  for (int i = 0; i < m->frame_count; ++i) loaded += m->frame_position[3 * i] > 4 - 1e-9;
  for (int i = 0; i < m->frame_count; ++i)
    if (m->frame_position[3 * i] > 4 - 1e-9) m->frame_load[6 * i + 4] = torque / loaded;
  return m;
}

// The end's deflection along z after a static solve; the clamp's moment check.
static double static_tip(fascia_ctx *ctx, const char *backend, double torque) {
  fascia_model *m = loaded_beam(ctx, torque);
  CHECK(m != NULL);
  if (!m) return NAN;
  fascia_solver_def sd = fascia_solver_def_default();
  sd.newton_tolerance = 1e-10;
  sd.backend = backend;
  fascia_solver *s = NULL;
  fascia_solve_report r;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  CHECK_OK(fascia_solver_solve_static(s, &r), ctx);
  printf("t318 %s: torque %g N m: static solve %s in %d Newton iterations\n", backend, torque,
         r.converged ? "converged" : "NOT converged", r.newton_iterations);
  CHECK(r.converged);
  // internal moments on the clamp (about the origin) against the applied torque
  double *g = calloc(6 * (size_t)m->frame_count, sizeof(double));
  const double *x = fascia_solver_frame_positions(s);
  fascia_system_set_state(s->sys, x, fascia_solver_frame_rotations(s));
  CHECK_OK(fascia_system_evaluate(s->sys, g, NULL), ctx);
  double clamp[3] = {0, 0, 0};
  for (int i = 0; i < m->frame_count; ++i)
    if (m->frame_kind[i] == FASCIA_FRAME_FIXED) {
      double arm[3];
      fascia_pt_cross(x + 3 * i, g + 6 * i, arm);
      for (int c = 0; c < 3; ++c) clamp[c] += arm[c] + g[6 * i + 3 + c];
    }
  CHECK_NEAR(clamp[1], -torque, 1e-6, 1e-9);
  CHECK(fabs(clamp[0]) < 1e-6 * torque && fabs(clamp[2]) < 1e-6 * torque);
  const int tip = fascia_model_find_probe(m, "tip");
  double p[3];
  fascia_solver_probe_position(s, tip, p);
  const double uz = p[2] - m->probe_position[3 * tip + 2];
  free(g);
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  return uz;
}

int main(int argc, char **argv) {
  const char *backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(backend);
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  const double torque = 10; // N m about y: the end bends down (-z)
  const double one = static_tip(ctx, backend, torque), two = static_tip(ctx, backend, 2 * torque);
  printf("t318 %s: end deflection %.6g m, %.6g m at twice the torque (ratio %.4f)\n", backend, one, two, two / one);
  CHECK(one < -1e-3);
  CHECK_NEAR(two / one, 2, 0.005, 0);
  // dynamic steps from rest: every one converges, the end swings about the static deflection
  fascia_model *m = loaded_beam(ctx, torque);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = backend;
  sd.time_step = 0.01;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  int converged = 0, newton = 0;
  double lowest = 0;
  const int tip = fascia_model_find_probe(m, "tip");
  for (int k = 0; s && k < 40; ++k) {
    fascia_solve_report r;
    const fascia_status st = fascia_solver_step(s, &r);
    if (st != FASCIA_OK) {
      fprintf(stderr, "t318 %s: step %d: %s\n", backend, k, fascia_ctx_message(ctx));
      break;
    }
    converged += r.converged, newton += r.newton_iterations;
    double p[3];
    fascia_solver_probe_position(s, tip, p);
    lowest = fmin(lowest, p[2] - m->probe_position[3 * tip + 2]);
  }
  printf("t318 %s: 40 steps of 0.01 s: %d converged, %d Newton iterations; lowest end %.6g m (static %.6g)\n",
         backend, converged, newton, lowest, one);
  CHECK(converged == 40);
  CHECK(lowest < 0.5 * one && lowest > 2.5 * one); // it swings past the static deflection, not away
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
