// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Constant external forces on frames (frame_load) are carried to the clamp:
// at static equilibrium the internal energy gradients on the fixed frames
// add up to minus the applied load (the internal energy is invariant under
// translation), and the loaded end moves along the load.
#include <stdlib.h>
#include <string.h>

#include "backend_arg.h"
#include "check.h"
#include "scenes.h"
#include "solve/solver_internal.h"

int main(int argc, char **argv) {
  const char *backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(backend);
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 8, def.frames[1] = 2, def.frames[2] = 2, def.length = 4;
  def.gravity[2] = 0;
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &def, &m), ctx);
  const double load[3] = {3.0, -1.0, -20.0}; // N, spread over the end frames
  int loaded = 0;
  for (int i = 0; i < m->frame_count; ++i)
    if (m->frame_position[3 * i] > 4 - 1e-9) ++loaded;
  for (int i = 0; i < m->frame_count; ++i)
    if (m->frame_position[3 * i] > 4 - 1e-9)
      for (int c = 0; c < 3; ++c) m->frame_load[6 * i + c] = load[c] / loaded;
  fascia_solver_def sd = fascia_solver_def_default();
  sd.newton_tolerance = 1e-10;
  sd.backend = backend;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  CHECK_OK(fascia_solver_solve_static(s, NULL), ctx);
  // internal forces at the solution: gradient minus the external part
  double *g = calloc(6 * (size_t)m->frame_count, sizeof(double));
  fascia_system_set_state(s->sys, fascia_solver_frame_positions(s), fascia_solver_frame_rotations(s));
  CHECK_OK(fascia_system_evaluate(s->sys, g, NULL), ctx);
  double clamp[3] = {0, 0, 0};
  for (int i = 0; i < m->frame_count; ++i)
    if (m->frame_kind[i] == FASCIA_FRAME_FIXED)
      for (int c = 0; c < 3; ++c) clamp[c] += g[6 * i + c]; // no load there: all internal
  // free frames: grad E_int = load (equilibrium); all frames: sum grad E_int
  // = 0 (translation invariance); so the clamp carries grad E_int = -load
  for (int c = 0; c < 3; ++c) CHECK_NEAR(clamp[c], -load[c], 1e-6, 1e-8);
  const int tip = fascia_model_find_probe(m, "tip");
  double p[3];
  fascia_solver_probe_position(s, tip, p);
  CHECK(p[2] - m->probe_position[3 * tip + 2] < -0.01); // moved along the load
  free(g);
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
