// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Volumetric patches (fascia beam's default from nu = 0.3: each cell's
// samples keep lambda mu / (lambda + mu) of lambda on their own dilatation,
// the cell the rest on its mean) cure volumetric locking for every shape
// kind: on the 20x3x3 cantilever, against the converged CalculiX references
// (data/reference/),
//  - with full integration each kind locks: from nu = 0.3 to 0.49 its error
//    grows by more than 10 points (hex +5 -> +28 %, tet +9.5 -> +23 %,
//    meshless k = 8 +4.5 -> +31 %);
//  - with cell patches the error at nu = 0.3 and 0.49 stays within 2 points
//    of the error at nu = 0, where no volumetric energy acts and what is
//    left is the shape functions' own: neither locked nor too soft (the
//    patch's mean alone, with no share on the samples, was 3.1-5.1 points
//    softer: hex -1.4 / -1.9 % against +2.2 % at nu = 0), and at nu = 0.3
//    no larger than full integration's;
//  - every kind is within 1 % at nu = 0.3 and 2 % at 0.49 (issue 13's
//    goals): meshless k = 8 with its patches alone (the mean alone gave
//    -3.0 / -3.4 %); hex and tet with the enhanced strain modes fascia
//    beam's rule puts on their patches, hex the three normal ones (-0.66 /
//    -0.98 %; +1.58 / +1.55 % without), tet the nine with its rotation
//    smoothing of 0.05 (-0.13 / +0.93 %; +0.92 / +1.94 % with 0.1, +7.2 /
//    +8.6 % without the modes);
//  - the stiff beams (E = 4 MPa, small deflection) within 2 % at both
//    (issue 13's goal): hex -0.94 / -1.42 % (the mean alone gave -3.9 /
//    -4.4 %), tet -0.21 / +1.07 % (+1.18 / +2.40 % with the smoothing of
//    hex, +11.7 / +13.2 % without the modes), meshless k = 8 -1.16 /
//    -1.16 % with its patches alone. Each kind's own error, the
//    reference for "neither locked nor too soft", is its error at nu = 0
//    with the same patches and modes (no volumetric energy);
//  - under refinement (hex, 10x2x2, 20x3x3, 40x5x5 at nu = 0.3) the error
//    falls, and is below full integration's at every resolution (measured
//    -4.8, -0.66, -0.04 % against +15, +5.0, +1.5 %; without the modes
//    +4.6, +1.6, +0.51 %).
// - the static solve at nu = 0.49 with the solver's defaults (fascia run
//   --static) converges in at most 25 Newton iterations for every kind,
//   meshless k = 16 included (issue 13's goal): the Levenberg shift weighs
//   the rotations only (fascia_pt_levenberg_weight). With the shift on every
//   unknown: hex 24, tet 16, meshless k = 8 33, k = 16 95; then 12-14;
//   now 10-11, since a full step's successor starts from an unshifted
//   tangent (at nu = 0.3: at most 8, hex 7, tet 7, meshless 8).
// On a device backend (CG only), where the static solves at nu = 0.49 do
// not converge: the coarse grid at nu = 0.3, the patches no worse than full
// integration there and the same tip as the CPU's.
#include <stdlib.h>
#include <string.h>

#include "beam_calculix.h"
#include "beam_tip.h"
#include "check.h"
#include "fascia/solver.h"
#include "scenes.h"

// Relative error (%) of the static tip uz, positive too stiff.
static double tip_error_of(fascia_ctx *ctx, int shape, const int32_t frames[3], double E, double nu, int patch) {
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  memcpy(def.frames, frames, sizeof def.frames);
  def.shape = shape;
  def.youngs_modulus = E;
  def.poisson_ratio = nu;
  def.volumetric_patch = patch;
  def.enhanced_modes = -1; // fascia beam's rule: on the hexahedra's and tetrahedra's patches
  const fascia_ccx_reference *ref = fascia_ccx_reference_find(&def);
  CHECK(ref != NULL);
  double uz = NAN, mass;
  if (beam_tip_uz_of(ctx, &def, &uz, &mass)) return NAN;
  const double error = ref ? 100 * (uz - ref->tip_uz) / fabs(ref->tip_uz) : NAN;
  printf("%-8s %dx%dx%d E %g nu %.2f %-6s tip error %+.2f %%\n", fascia_scene_shape_name(shape), (int)frames[0],
         (int)frames[1], (int)frames[2], E, nu, !patch ? "full" : shape != FASCIA_SCENE_MESHLESS ? "cell+m" : "cell", error);
  return error;
}

// The same for the default beam (E = 40 kPa, large deflection).
static double tip_error(fascia_ctx *ctx, int shape, const int32_t frames[3], double nu, int patch) {
  return tip_error_of(ctx, shape, frames, fascia_scene_beam_def_default().youngs_modulus, nu, patch);
}

// Newton iterations of the static solve with fascia run --static's settings
// (the solver's defaults, 100 iterations at most), or 1000 when it does not
// converge.
static int static_newton_iterations(fascia_ctx *ctx, int shape, int neighbours, double nu) {
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.shape = shape;
  def.neighbours = neighbours;
  def.poisson_ratio = nu;
  def.volumetric_patch = FASCIA_SCENE_PATCH_AUTO;
  def.enhanced_modes = -1;
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &def, &m), ctx);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.newton_iterations = 100; // fascia run --static's limit
  sd.backend = beam_tip_backend;
  fascia_solver *s = NULL;
  if (m) CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  fascia_solve_report report = {0};
  const int solved = s && fascia_solver_solve_static(s, &report) == FASCIA_OK && report.converged;
  printf("%-8s k %2d nu %.2f static solve, defaults: %d Newton iterations%s\n", fascia_scene_shape_name(shape),
         neighbours, nu, report.newton_iterations, solved ? "" : ", not converged");
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  return solved ? report.newton_iterations : 1000;
}

int main(int argc, char **argv) {
  const int all = beam_tip_backend_arg(argc, argv);
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  const int32_t grid[3] = {20, 3, 3}, coarse[3] = {10, 2, 2}, fine[3] = {40, 5, 5};
  const int kinds[3] = {FASCIA_SCENE_HEX, FASCIA_SCENE_TET, FASCIA_SCENE_MESHLESS};
  const int CELL = FASCIA_SCENE_PATCH_CELL, FULL = FASCIA_SCENE_PATCH_NONE;
  if (!all) {
    const double cell = tip_error(ctx, FASCIA_SCENE_HEX, coarse, 0.3, CELL);
    const double full = tip_error(ctx, FASCIA_SCENE_HEX, coarse, 0.3, FULL);
    const char *device = beam_tip_backend;
    beam_tip_backend = "cpu";
    const double cell_cpu = tip_error(ctx, FASCIA_SCENE_HEX, coarse, 0.3, CELL);
    CHECK(fabs(cell) <= fabs(full));
    CHECK_NEAR(cell, cell_cpu, 0, 1e-4); // percent: the tips agree to 1e-6
    printf("%s against cpu, cell patches: %+.6f %% and %+.6f %%\n", device, cell, cell_cpu);
    fascia_ctx_destroy(&ctx);
    return CHECK_RESULT();
  }
  for (int k = 0; k < 3; ++k) {
    const double own = tip_error(ctx, kinds[k], grid, 0, CELL); // no volumetric energy
    const double full_030 = tip_error(ctx, kinds[k], grid, 0.3, FULL), full_049 = tip_error(ctx, kinds[k], grid, 0.49, FULL);
    const double cell_030 = tip_error(ctx, kinds[k], grid, 0.3, CELL), cell_049 = tip_error(ctx, kinds[k], grid, 0.49, CELL);
    CHECK(full_049 - full_030 > 10);           // full integration locks
    CHECK(fabs(cell_030 - own) < 2);           // the patches neither lock
    CHECK(fabs(cell_049 - own) < 2);           // nor soften past the shape functions' own error
    CHECK(fabs(cell_030) <= fabs(full_030));   // nor make nu = 0.3 worse
    CHECK(fabs(cell_030) < 1 && fabs(cell_049) < 2);
  }
  // the stiff beam, small deflection (the defaults: cell patches); at
  // nu = 0.49 its gradient stops at 3.5e-8 of the load (round-off)
  beam_tip_tolerance = 1e-7;
  CHECK(fabs(tip_error_of(ctx, FASCIA_SCENE_HEX, grid, 4e6, 0.3, CELL)) < 2);
  CHECK(fabs(tip_error_of(ctx, FASCIA_SCENE_HEX, grid, 4e6, 0.49, CELL)) < 2);
  CHECK(fabs(tip_error_of(ctx, FASCIA_SCENE_TET, grid, 4e6, 0.3, CELL)) < 2);
  CHECK(fabs(tip_error_of(ctx, FASCIA_SCENE_TET, grid, 4e6, 0.49, CELL)) < 2);
  CHECK(fabs(tip_error_of(ctx, FASCIA_SCENE_MESHLESS, grid, 4e6, 0.3, CELL)) < 2);
  CHECK(fabs(tip_error_of(ctx, FASCIA_SCENE_MESHLESS, grid, 4e6, 0.49, CELL)) < 2);
  beam_tip_tolerance = 1e-8;
  // Newton near incompressibility: at most 25 iterations for every kind
  // (the goal), and no more than the 10-11 that full steps taking their
  // next tangent unshifted give (12, 11, 13, 14 when the shift decayed by tenths)
  CHECK(static_newton_iterations(ctx, FASCIA_SCENE_HEX, 8, 0.49) <= 11);
  CHECK(static_newton_iterations(ctx, FASCIA_SCENE_TET, 8, 0.49) <= 11);
  CHECK(static_newton_iterations(ctx, FASCIA_SCENE_MESHLESS, 8, 0.49) <= 11);
  CHECK(static_newton_iterations(ctx, FASCIA_SCENE_MESHLESS, 16, 0.49) <= 11);
  // and at nu = 0.3 at most 8 (9, 10, 9 with the decaying shift; CalculiX
  // takes 6 with its looser residual test)
  CHECK(static_newton_iterations(ctx, FASCIA_SCENE_HEX, 8, 0.3) <= 8);
  CHECK(static_newton_iterations(ctx, FASCIA_SCENE_TET, 8, 0.3) <= 8);
  CHECK(static_newton_iterations(ctx, FASCIA_SCENE_MESHLESS, 8, 0.3) <= 8);
  // refinement, hex, nu = 0.3: the patches' error falls, below full integration's
  const double cell_coarse = tip_error(ctx, FASCIA_SCENE_HEX, coarse, 0.3, CELL);
  const double cell_grid = tip_error(ctx, FASCIA_SCENE_HEX, grid, 0.3, CELL);
  const double cell_fine = tip_error(ctx, FASCIA_SCENE_HEX, fine, 0.3, CELL);
  const double full_coarse = tip_error(ctx, FASCIA_SCENE_HEX, coarse, 0.3, FULL);
  const double full_fine = tip_error(ctx, FASCIA_SCENE_HEX, fine, 0.3, FULL);
  CHECK(fabs(cell_fine) < fabs(cell_grid) && fabs(cell_grid) < fabs(cell_coarse));
  CHECK(fabs(cell_coarse) < fabs(full_coarse) && fabs(cell_fine) < fabs(full_fine));
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
