// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The static tip uz of fascia's cantilever (fascia_scene_beam_build: a def,
// or hex frames nx x nyz x nyz) in tests, solved tightly; *mass the model's
// mass.
// The model's volume is checked to be the box's.
#ifndef FASCIA_TESTS_BEAM_TIP_H
#define FASCIA_TESTS_BEAM_TIP_H

#include "backend_arg.h"
#include "check.h"
#include "fascia/solver.h"
#include "scenes.h"

/// The backend the solves run on ("cpu" unless a test's --backend says otherwise).
static const char *beam_tip_backend = "cpu";
/// The static solves' Newton tolerance (relative to the load).
static double beam_tip_tolerance = 1e-8;

/// Sets beam_tip_backend from --backend for the tests of locking (t306,
/// t307); 1 when their cases at nu = 0.49 run on it. On the device backends
/// they do not, saying why: by CG, a device's only solver, those static
/// solves do not converge (nor on the CPU's CG), and each at 20x3x3 takes
/// 10 s or more in the emulation; the tests then check what CG solves.
static inline int beam_tip_backend_arg(int argc, char **argv) {
  beam_tip_backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(beam_tip_backend);
  return backend_runs_cpu_case(beam_tip_backend, "the cases at nu = 0.49 and at 20x3x3",
                               "by CG, a device's only solver, the static solves at nu = 0.49 do not converge (nor "
                               "on the CPU's CG), and each at 20x3x3 takes 10 s or more in the emulation");
}

// The static tip uz of the beam of def, solved tightly; *mass its model's mass.
static inline int beam_tip_uz_of(fascia_ctx *ctx, const fascia_scene_beam_def *def, double *uz, double *mass) {
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, def, &m), ctx);
  if (!m) return 1;
  *mass = fascia_model_mass(m);
  CHECK_NEAR(fascia_model_volume(m), 16.0, 1e-12, 0); // the volumetric samples overlap, not add
  fascia_solver_def sd = fascia_solver_def_default();
  sd.newton_iterations = 150;
  sd.newton_tolerance = beam_tip_tolerance;
  sd.backend = beam_tip_backend;
  backend_static_cg(&sd);
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  CHECK_OK(fascia_solver_solve_static(s, NULL), ctx);
  const int tip = fascia_model_find_probe(m, "tip");
  double p[3] = {0, 0, 0};
  if (s) fascia_solver_probe_position(s, tip, p);
  *uz = p[2] - m->probe_position[3 * tip + 2];
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  return 0;
}

static inline int beam_tip_uz(fascia_ctx *ctx, int nx, int nyz, double nu, int reduced, double *uz, double *mass) {
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = nx, def.frames[1] = def.frames[2] = nyz;
  def.poisson_ratio = nu;
  def.reduced_volumetric = reduced;
  return beam_tip_uz_of(ctx, &def, uz, mass);
}

#endif
