// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The paper's cantilever (sec. 4.1) solved statically converges to the
// converged CalculiX reference (data/reference/) as the frame grid is refined (10x2x2 -> 20x3x3 ->
// 40x5x5), the finest within 2 %, and the equilibrium is the physical one:
// no twist about the beam axis, symmetric in y. The paper's scheme without
// rotation smoothing is also solved at 20x3x3 on a mirrored half beam and
// must match the independent prototype's -6.208 m. On every backend
// (`--backend`); the device backends solve the coarsest grid alone (in the
// emulation the finer ones take minutes) and the half beam, whose symmetry
// plane fixes DOFs after the solver is made.
#include <stdlib.h>
#include <string.h>

#include "backend_arg.h"
#include "beam_calculix.h"
#include "check.h"
#include "scenes.h"
#include "solve/solver_internal.h"

static const char *backend = "cpu";

static int solve(fascia_ctx *ctx, fascia_scene_beam_def *def, int mirror, double *u, double *twist, double *max_uy) {
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, def, &m), ctx);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.newton_iterations = 60;
  sd.newton_tolerance = 1e-9;
  sd.backend = backend;
  backend_static_cg(&sd);
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  if (mirror) // symmetry plane at the lowest y: no y motion, no rotation about x or z
    for (int i = 0; i < m->frame_count; ++i)
      if (m->frame_position[3 * i + 1] < -0.5 * def->width + 1e-9) s->mask[6 * i + 1] = s->mask[6 * i + 3] = s->mask[6 * i + 5] = 0;
  fascia_solve_report rep;
  CHECK_OK(fascia_solver_solve_static(s, &rep), ctx);
  const int tip = fascia_model_find_probe(m, "tip");
  CHECK(tip >= 0);
  double p[3];
  fascia_solver_probe_position(s, tip, p);
  for (int c = 0; c < 3; ++c) u[c] = p[c] - m->probe_position[3 * tip + c];
  *twist = 0;
  *max_uy = 0;
  const double *q = fascia_solver_frame_rotations(s), *x = fascia_solver_frame_positions(s);
  for (int i = 0; i < m->frame_count; ++i) {
    double t[3];
    fascia_pt_quat_log(q + 4 * i, t);
    *twist = fmax(*twist, fabs(t[0]));
    // mirror symmetry in y: a frame at y moves like its mirror image; the
    // centre line (y = 0) must not move sideways
    if (fabs(m->frame_position[3 * i + 1]) < 1e-9) *max_uy = fmax(*max_uy, fabs(x[3 * i + 1]));
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
  // the converged CalculiX reference, StVK (data/reference/)
  const fascia_scene_beam_def beam = fascia_scene_beam_def_default();
  const fascia_ccx_reference *ref = fascia_ccx_reference_find(&beam);
  if (!ref) return 1;
  const int grids[3][3] = {{10, 2, 2}, {20, 3, 3}, {40, 5, 5}};
  const int refine = backend_runs_cpu_case(backend, "the 20x3x3 and 40x5x5 grids, the refinement",
                                           "by CG the emulation takes 10 s to a minute for 20x3x3, minutes for 40x5x5");
  const int grid_count = refine ? 3 : 1;
  double errors[3];
  for (int g = 0; g < grid_count; ++g) {
    fascia_scene_beam_def def = fascia_scene_beam_def_default();
    memcpy(def.frames, grids[g], sizeof def.frames);
    double u[3], twist, uy;
    if (solve(ctx, &def, 0, u, &twist, &uy)) return 1;
    errors[g] = fabs(u[2] - ref->tip_uz) / fabs(ref->tip_uz);
    // the physical branch: rotations about the beam axis stay at rounding
    // level of the large bending rotations (~1 rad), and nothing moves sideways
    CHECK(twist < 0.05);
    CHECK(uy < 1e-6);
    CHECK(u[2] > ref->tip_uz); // the frame scheme is stiff, never soft
    if (g == 2) CHECK_NEAR(u[0], ref->tip_ux, 0.05, 0);
  }
  if (refine) {
    CHECK(errors[1] < errors[0]);
    CHECK(errors[2] < errors[1]);
    CHECK(errors[2] < 0.02); // the accuracy asked of the method: the finest affordable grid within 2 %
  }
  // the paper's scheme itself, mirrored half beam: the independent prototype's
  // -6.208 m at 20x3x3 (hex, 2x2x2 samples), to the prototype's 3 digits
  {
    fascia_scene_beam_def half = fascia_scene_beam_def_default();
    half.frames[0] = 20, half.frames[1] = 2, half.frames[2] = 3;
    half.width = 0.5, half.mass = 2.5, half.rotation_smoothing = 0, half.rotation_coupling = 0;
    double u[3], twist, uy;
    if (solve(ctx, &half, 1, u, &twist, &uy)) return 1;
    CHECK_NEAR(u[2], -6.208, 0, 1.5e-3);
  }
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
