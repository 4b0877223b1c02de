// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A prepared tissue between two fixed organs reaches static equilibrium under
// gravity in the simulator core: the solve converges, shared frames stay
// where they were, the free frames sag downwards by about the shear-layer
// estimate rho g L^2 / (8 mu) (a layer of width L clamped on both faces).
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "fascia/solver.h"
#include "prep_fixture.h"

static const char scene[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.0005, \"seed\": 5, \"gravity\": [0, -9.81, 0],\n"
    " \"materials\": {\"soft\": {\"law\": \"neohookean\", \"youngs_modulus\": 3000, \"poisson_ratio\": 0.3,\n"
    "                          \"density\": 1000}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\"}, {\"name\": \"B\", \"mesh\": \"b.obj\"}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008,\n"
    "  \"region\": {\"box\": {\"min\": [-0.005, -0.008, -0.008], \"max\": [0.005, 0.008, 0.008]}},\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.0025, \"sample_spacing\": 0.00125}]}\n";

int main(void) {
  char dir[256], path[512];
  if (!fixture_tmpdir(dir)) return 1;
  CHECK(fixture_two_boxes(dir, 0.0031, scene, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  const fascia_model *m = r.model;
  fascia_solver_def def = fascia_solver_def_default();
  def.backend = "cpu";
  fascia_solver *solver = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &def, &solver), ctx);
  fascia_solve_report report;
  CHECK_OK(fascia_solver_solve_static(solver, &report), ctx);
  CHECK(report.converged);
  const fascia_real *x = fascia_solver_frame_positions(solver);
  double sag = 0, mean_dy = 0;
  int32_t free_count = 0;
  for (int32_t i = 0; i < m->frame_count; ++i) {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) d2 += (x[3 * i + a] - m->frame_position[3 * i + a]) * (x[3 * i + a] - m->frame_position[3 * i + a]);
    if (m->frame_kind[i] == FASCIA_FRAME_FIXED) {
      CHECK(d2 == 0);
    } else {
      sag = fmax(sag, sqrt(d2));
      mean_dy += x[3 * i + 1] - m->frame_position[3 * i + 1];
      ++free_count;
    }
  }
  CHECK(free_count > 0);
  mean_dy /= free_count > 0 ? free_count : 1;
  // shear layer clamped at x = +-3.1 mm: largest sag rho g L^2 / (8 mu), L = 6.2 mm
  const double mu = 3000 / (2 * 1.3), estimate = 1000 * 9.81 * 0.0062 * 0.0062 / (8 * mu);
  CHECK(mean_dy < 0);
  CHECK(sag > 0.3 * estimate && sag < 3 * estimate); // frame scheme and free side faces: same order, not equal
  fascia_solver_destroy(&solver);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
