// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The paper's cantilever in lower dimensions: a strand (20 frames on the
// axis, the section carried by their rotations) and a sheet (20 x 3 frames
// in the mid-plane, the thickness carried by their rotations), built with
// fascia beam's defaults (fascia_scene_beam_def_of_shape), agree with the
// converged 3-D CalculiX reference (data/reference/): tip uz within 1 % at
// E = 40 kPa (large deflection) and within 2 % at E = 4 MPa (small), nu =
// 0.3. Their volume and mass are the beam's, the beam does not twist,
// and a finer strand and sheet stay within the same bounds.
#include <string.h>

#include "beam_calculix.h"
#include "check.h"
#include "fascia/solver.h"
#include "scenes.h"

// Static tip uz of the def's beam; *twist the largest rotation about x of
// a frame and its mirror image in y = 0 together (0 for a solution
// symmetric in y: a sheet's frames turn about x apart, the anticlastic
// bending, but not together).
static int solve(fascia_ctx *ctx, const fascia_scene_beam_def *def, double *uz, double *twist) {
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, def, &m), ctx);
  CHECK_NEAR(fascia_model_volume(m), 16.0, 1e-12, 0);
  CHECK_NEAR(fascia_model_mass(m), 5.0, 1e-12, 0);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.newton_iterations = 100;
  sd.newton_tolerance = 1e-8;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  fascia_solve_report report;
  CHECK_OK(fascia_solver_solve_static(s, &report), ctx);
  CHECK(report.converged);
  const int tip = fascia_model_find_probe(m, "tip");
  double p[3] = {0, 0, 0};
  fascia_solver_probe_position(s, tip, p);
  *uz = p[2] - m->probe_position[3 * tip + 2];
  const fascia_real *q = fascia_solver_frame_rotations(s);
  *twist = 0;
  const fascia_real *x = m->frame_position;
  for (int32_t i = 0; i < m->frame_count; ++i)
    for (int32_t j = 0; j < m->frame_count; ++j) // x components of the rotation vectors, small angles
      if (x[3 * j] == x[3 * i] && x[3 * j + 1] == -x[3 * i + 1])
        *twist = fmax(*twist, fabs(2 * q[4 * i + 1] + 2 * q[4 * j + 1]));
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  return 0;
}

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  const int shapes[2] = {FASCIA_SCENE_STRAND, FASCIA_SCENE_SHEET};
  const double moduli[2] = {40000, 4e6}, bound[2] = {0.01, 0.02};
  const int32_t fine[2][3] = {{40, 1, 1}, {40, 5, 1}};
  for (int a = 0; a < 2; ++a)
    for (int e = 0; e < 2; ++e)
      for (int refine = 0; refine < 2; ++refine) {
        fascia_scene_beam_def def = fascia_scene_beam_def_of_shape(shapes[a]);
        def.youngs_modulus = moduli[e];
        if (refine) memcpy(def.frames, fine[a], sizeof def.frames);
        const fascia_ccx_reference *ref = fascia_ccx_reference_find(&def);
        CHECK(ref != NULL);
        if (!ref) return 1;
        double uz = 0, twist = 0;
        if (solve(ctx, &def, &uz, &twist)) return 1;
        const double error = (uz - ref->tip_uz) / fabs(ref->tip_uz);
        printf("%-6s %dx%d E %-7g tip uz %.6f m, reference %.6f: %+.3f %%, twist %.2g rad\n",
               fascia_scene_shape_name(shapes[a]), (int)def.frames[0], (int)def.frames[1], moduli[e], uz,
               ref->tip_uz, 100 * error, twist);
        CHECK(fabs(error) < bound[e]);
        CHECK(twist < 1e-6);
      }
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
