// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Prep's volumetric patches (Poisson-disk patches of the frame spacing,
// from a Poisson ratio of 0.3) keep a prepared tissue from locking, for
// both of prep's shape function kinds: a tissue layer between two fixed
// organs sags under gravity with mu fixed while lambda / mu goes from 10
// to 10^4 (nu 0.4545 to 0.49995). A discretization that does not lock has
// a finite incompressible limit: the mean sag of the free frames changes by
// under 5 % over the last decade (measured: mls 42.95 -> 42.92 um, tet
// 11.56 -> 11.39 um), and keeps more than 60 % of its sag at lambda =
// 10 mu (mls 0.97, tet 0.73: the tetrahedra's coarse linear fields are the
// stiffer near incompressibility). With the patches switched off
// (patch_radius 0) the same tissue locks, its sag falling with 1 / lambda
// (mls 5.68 -> 0.70 um, tet 0.26 -> 0.03 um): the checks are able to fail.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>
#include <stdio.h>

#include "check.h"
#include "fascia/solver.h"
#include "prep_fixture.h"

#define MU 1000.0

// The static sag (mean |displacement| of the free frames, m) of the layer
// with lambda = ratio mu, shape functions `kind`, and patch_radius given
// (text of the key and its value, or "" for prep's rule).
static double sag_of(fascia_ctx *ctx, const char *dir, double ratio, const char *kind, const char *patch) {
  const double lambda = ratio * MU, nu = lambda / (2 * (lambda + MU)), E = 2 * MU * (1 + nu);
  char scene[2048], path[512];
  snprintf(scene, sizeof scene,
           "{\"fascia_scene\": 1, \"voxel_size\": 0.0005, \"seed\": 5, \"gravity\": [0, -9.81, 0],\n"
           " \"materials\": {\"soft\": {\"law\": \"neohookean\", \"youngs_modulus\": %.17g, \"poisson_ratio\": %.17g,\n"
           "                          \"density\": 1000}},\n"
           " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\"}, {\"name\": \"B\", \"mesh\": \"b.obj\"}],\n"
           " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008,\n"
           "  \"region\": {\"box\": {\"min\": [-0.005, -0.008, -0.008], \"max\": [0.005, 0.008, 0.008]}},\n"
           "  \"shape_functions\": {\"kind\": \"%s\"}, %s\n"
           "  \"material\": \"soft\", \"frame_spacing\": 0.0025, \"sample_spacing\": 0.00125}]}\n",
           E, nu, kind, patch);
  CHECK(fixture_two_boxes(dir, 0.0031, scene, path));
  fixture_run r;
  double sag = NAN;
  const fascia_status st = fixture_prep(ctx, path, &r);
  CHECK_OK(st, ctx);
  int32_t patched = 0;
  if (st == FASCIA_OK) {
    const fascia_model *m = r.model;
    for (int32_t s = 0; s < m->sample_count; ++s) patched += m->sample_patch[s] >= 0;
    fascia_solver_def def = fascia_solver_def_default();
    def.backend = "cpu";
    def.newton_iterations = 100; // fascia run --static's limit
    fascia_solver *solver = NULL;
    CHECK_OK(fascia_solver_create(ctx, m, &def, &solver), ctx);
    fascia_solve_report report = {0};
    if (solver) CHECK_OK(fascia_solver_solve_static(solver, &report), ctx);
    CHECK(report.converged);
    if (solver && report.converged) {
      const fascia_real *x = fascia_solver_frame_positions(solver);
      double sum = 0;
      int32_t count = 0;
      for (int32_t i = 0; i < m->frame_count; ++i) {
        if (m->frame_kind[i] == FASCIA_FRAME_FIXED) continue;
        double d2 = 0;
        for (int a = 0; a < 3; ++a)
          d2 += (x[3 * i + a] - m->frame_position[3 * i + a]) * (x[3 * i + a] - m->frame_position[3 * i + a]);
        sum += sqrt(d2);
        ++count;
      }
      CHECK(count > 0);
      sag = count > 0 ? sum / count : NAN;
    }
    fascia_solver_destroy(&solver);
    printf("t508: %-3s lambda/mu %6g, %-19s %5d samples in patches, %3d Newton iterations, sag %.3f um\n", kind, ratio,
           patch[0] ? patch : "patches by the rule", (int)patched, report.newton_iterations, 1e6 * sag);
    CHECK(patch[0] ? patched == 0 : patched == m->sample_count);
  }
  fixture_free(&r);
  return sag;
}

int main(void) {
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  fascia_ctx *ctx = fixture_ctx();
  static const char *const kinds[] = {"mls", "tet"};
  for (int k = 0; k < 2; ++k) {
    const double soft = sag_of(ctx, dir, 10, kinds[k], ""), near = sag_of(ctx, dir, 1e3, kinds[k], "");
    const double limit = sag_of(ctx, dir, 1e4, kinds[k], "");
    CHECK(soft > 0 && near > 0 && limit > 0);
    CHECK(fabs(limit / near - 1) < 0.05); // a finite incompressible limit
    CHECK(near / soft > 0.6);
    // without patches the same tissue locks: its sag goes with 1 / lambda
    const double full_near = sag_of(ctx, dir, 1e3, kinds[k], "\"patch_radius\": 0,");
    const double full_limit = sag_of(ctx, dir, 1e4, kinds[k], "\"patch_radius\": 0,");
    CHECK(full_limit / full_near < 0.3);
    CHECK(full_near < 0.5 * near);
  }
  fascia_ctx_destroy(&ctx);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
