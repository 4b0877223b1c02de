// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The plate and the bowl solved by fascia (shell_calculix.h): the scene in
// a temporary folder, prep's stages, one static solve, the probe read
// through the wall's own interpolation.
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/fascia.h"
#include "fascia/organs.h"
#include "fascia/prep.h"
#include "scene_util.h"
#include "shell_calculix.h"
#include "tissue_calculix.h"


// Barycentric coordinates of p's projection on triangle (a, b, c) and its
// distance from the triangle's plane; 0 if the triangle has no area.
static int barycentric(const double *a, const double *b, const double *c, const double *p, double w[3],
                       double *off) {
  double e1[3], e2[3], d[3], n[3];
  for (int r = 0; r < 3; ++r) e1[r] = b[r] - a[r], e2[r] = c[r] - a[r], d[r] = p[r] - a[r];
  n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  if (!(nn > 0)) return 0;
  double c1[3], c2[3]; // d x e2, e1 x d: the sub-areas
  c1[0] = d[1] * e2[2] - d[2] * e2[1], c1[1] = d[2] * e2[0] - d[0] * e2[2], c1[2] = d[0] * e2[1] - d[1] * e2[0];
  c2[0] = e1[1] * d[2] - e1[2] * d[1], c2[1] = e1[2] * d[0] - e1[0] * d[2], c2[2] = e1[0] * d[1] - e1[1] * d[0];
  w[1] = (c1[0] * n[0] + c1[1] * n[1] + c1[2] * n[2]) / nn;
  w[2] = (c2[0] * n[0] + c2[1] * n[1] + c2[2] * n[2]) / nn;
  w[0] = 1 - w[1] - w[2];
  *off = fabs(d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / sqrt(nn);
  return 1;
}

// Displacement at rest point p of the shell organ: the wall triangle (a
// sample's three frames) whose projection holds p, nearest p; there the
// wall maps p as its samples' weights do, sum_i w_i (x_i + R_i (p - X_i)).
// Near a vertex of the convex, faceted wall p may project outside every
// triangle around it: then the triangle it projects closest to, its
// weights clamped to the triangle.
static fascia_status probe_displacement(fascia_ctx *ctx, const fascia_model *m, const fascia_solver *solver,
                                        int32_t organ, const double p[3], double u[3]) {
  int32_t best = -1;
  double best_w[3] = {0, 0, 0}, best_off = INFINITY;
  int32_t best_frame[3] = {-1, -1, -1};
  for (int pass = 0; pass < 2 && best < 0; ++pass) {
    for (int32_t s = 0; s < m->sample_count; ++s) {
      if (m->sample_organ[s] != organ) continue;
      int32_t frame[3], k = 0; // its triangle: the frames it weighs (its other pairs carry gradients alone)
      for (int32_t j = m->sample_offsets[s]; j < m->sample_offsets[s + 1]; ++j)
        if (m->pair_weight[j] != 0 && k < 3) frame[k++] = m->pair_frame[j];
      if (k != 3) continue;
      const double *X[3];
      double x3[3][3];
      for (int j = 0; j < 3; ++j) {
        for (int r = 0; r < 3; ++r) x3[j][r] = m->frame_position[3 * frame[j] + r];
        X[j] = x3[j];
      }
      double w[3], off;
      if (!barycentric(X[0], X[1], X[2], p, w, &off)) continue;
      const double tol = pass ? -0.1 : -1e-9;
      if (w[0] < tol || w[1] < tol || w[2] < tol || off >= best_off) continue;
      best = s, best_off = off;
      double sum = 0;
      for (int j = 0; j < 3; ++j) sum += best_w[j] = fmax(w[j], 0);
      for (int j = 0; j < 3; ++j) best_w[j] /= sum;
      memcpy(best_frame, frame, sizeof frame);
    }
  }
  SCENE_CHECK(best >= 0, ctx, FASCIA_ERR_INTERNAL,
              "shell case: no triangle of the wall lies under the probe (%.4g %.4g %.4g) m", p[0], p[1], p[2]);
  const fascia_real *x = fascia_solver_frame_positions(solver), *q = fascia_solver_frame_rotations(solver);
  u[0] = u[1] = u[2] = 0;
  for (int j = 0; j < 3; ++j) {
    const int32_t i = best_frame[j];
    fascia_real axes[9];
    fascia_frame_axes(q + 4 * (int64_t)i, 1, axes); // columns: R's x, y, z axes
    double d[3];
    for (int r = 0; r < 3; ++r) d[r] = p[r] - m->frame_position[3 * i + r];
    for (int r = 0; r < 3; ++r)
      u[r] += best_w[j] * (x[3 * i + r] + axes[r] * d[0] + axes[3 + r] * d[1] + axes[6 + r] * d[2] - p[r]);
  }
  return FASCIA_OK;
}

fascia_status fascia_shell_fascia(fascia_ctx *ctx, const fascia_shell_def *def, fascia_shell_result *out) {
  SCENE_CHECK(out && def, ctx, FASCIA_ERR_ARGUMENT, "shell case: NULL argument");
  memset(out, 0, sizeof *out);
  fascia_prep_stages st;
  fascia_solver *solver = NULL;
  fascia_status status = FASCIA_OK;
  SCENE_TRY_GOTO(fascia_tissue_prepare(ctx, fascia_shell_write_scene, def, &st));
  const fascia_model *m = st.model;
  const int32_t organ = fascia_model_find_organ(m, "shell");
  if (organ < 0) {
    status = SCENE_FAIL(ctx, FASCIA_ERR_INTERNAL, "shell case: the model lacks organ 'shell'");
    goto cleanup;
  }
  fascia_solve_report report;
  SCENE_TRY_GOTO(fascia_tissue_solve_static(ctx, m, &solver, &report, &out->ms));
  const double s = def->scale;
  const double probe[3] = {def->kind == FASCIA_SHELL_PLATE ? s * def->length : 0, 0,
                           def->kind == FASCIA_SHELL_PLATE ? 0 : -s * def->length};
  SCENE_TRY_GOTO(probe_displacement(ctx, m, solver, organ, probe, out->probe));
  for (int r = 0; r < 3; ++r) out->probe[r] /= s;
  for (int32_t i = 0; i < m->frame_count; ++i) out->nodes += m->frame_organ[i] == organ;
  out->newton = report.newton_iterations;
cleanup:
  fascia_solver_destroy(&solver);
  fascia_prep_stages_free(&st);
  return status;
}
