// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The hanging organ and the pulled sheet solved by fascia
// (tissue_calculix.h): the scene written to a temporary folder, prep's
// stages as `fascia prep` runs them, one static solve.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "fascia/fascia.h"
#include "fascia/organs.h"
#include "fascia/prep.h"
#include "scene_util.h"
#include "tissue_calculix.h"

#define DIR_SIZE 512
#define PATH_SIZE (DIR_SIZE + 64)

static void remove_scene(const char *dir) {
  static const char *const names[] = {FASCIA_TISSUE_BOX_A, FASCIA_TISSUE_BOX_B, FASCIA_TISSUE_SHEET,
                                      FASCIA_TISSUE_SCENE};
  char path[PATH_SIZE];
  for (size_t k = 0; k < sizeof names / sizeof names[0]; ++k) {
    snprintf(path, sizeof path, "%s/%s", dir, names[k]);
    remove(path);
  }
  rmdir(dir);
}

static fascia_status make_folder(fascia_ctx *ctx, char *dir) {
  const char *tmp = getenv("TMPDIR");
  const int n = snprintf(dir, DIR_SIZE, "%s/fascia-tissue-XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
  SCENE_CHECK(n > 0 && n < DIR_SIZE && mkdtemp(dir), ctx, FASCIA_ERR_IO, "cannot make a folder %s", dir);
  return FASCIA_OK;
}

fascia_status fascia_tissue_prepare(fascia_ctx *ctx, fascia_tissue_scene_writer write, const void *def,
                                    fascia_prep_stages *stages) {
  memset(stages, 0, sizeof *stages);
  char dir[DIR_SIZE], path[PATH_SIZE];
  SCENE_TRY(make_folder(ctx, dir));
  fascia_status status = write(ctx, def, dir);
  snprintf(path, sizeof path, "%s/%s", dir, FASCIA_TISSUE_SCENE);
  if (status == FASCIA_OK) status = fascia_prep_stages_run(ctx, path, NULL, stages);
  remove_scene(dir);
  return status;
}

// The static equilibrium at time 1 (the end of B's motion, if any): in one
// increment, or where that fails, with the motion in 4 and then in 16
// (ms: all the tries).
fascia_status fascia_tissue_solve_static(fascia_ctx *ctx, const fascia_model *m, fascia_solver **solver,
                                         fascia_solve_report *report, double *ms) {
  fascia_solver_def def = fascia_solver_def_default();
  def.backend = "cpu";
  def.threads = 1;
  def.newton_iterations = 100;
  def.newton_tolerance = 1e-10;
  const double t0 = scene_now_ms();
  fascia_status status = FASCIA_OK;
  for (def.load_steps = 1; def.load_steps <= 16; def.load_steps *= 4) {
    fascia_solver_destroy(solver);
    SCENE_TRY(fascia_solver_create(ctx, m, &def, solver));
    SCENE_TRY(fascia_solver_set_time(*solver, 1));
    status = fascia_solver_solve_static(*solver, report);
    if (status == FASCIA_OK && !report->converged)
      status = FASCIA_FAIL(ctx, FASCIA_ERR_NUMERIC, "static solve: not converged in %d Newton iterations",
                           report->newton_iterations);
    if (status == FASCIA_OK) break;
  }
  *ms = scene_now_ms() - t0;
  return status;
}

static fascia_status solve(fascia_ctx *ctx, const fascia_model *m, fascia_solver **solver, double *ms,
                           fascia_tissue_pull_result *pull) {
  fascia_solve_report report;
  memset(&report, 0, sizeof report);
  const fascia_status st = fascia_tissue_solve_static(ctx, m, solver, &report, ms);
  if (pull) pull->newton_iterations = report.newton_iterations, pull->negative_curvature = report.negative_curvature;
  return st;
}

// Sum of the tissue's forces on an organ's coupling frames (N).
static fascia_status organ_force(fascia_ctx *ctx, fascia_solver *solver, int32_t organ, double force[3]) {
  const int32_t n = fascia_solver_organ_frame_count(solver, organ);
  fascia_real *f = malloc(3 * (size_t)(n > 0 ? n : 1) * sizeof *f);
  SCENE_CHECK(f, ctx, FASCIA_ERR_MEMORY, "out of memory");
  const fascia_status st = fascia_solver_organ_reaction(solver, organ, f, NULL);
  force[0] = force[1] = force[2] = 0;
  for (int32_t i = 0; st == FASCIA_OK && i < n; ++i)
    for (int a = 0; a < 3; ++a) force[a] += f[3 * i + a];
  free(f);
  return st;
}

// v rotated by the unit quaternion q (w, x, y, z).
static void rotate(const fascia_real q[4], const double v[3], double out[3]) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double t[3] = {2 * (y * v[2] - z * v[1]), 2 * (z * v[0] - x * v[2]), 2 * (x * v[1] - y * v[0])};
  out[0] = v[0] + w * t[0] + (y * t[2] - z * t[1]);
  out[1] = v[1] + w * t[1] + (z * t[0] - x * t[2]);
  out[2] = v[2] + w * t[2] + (x * t[1] - y * t[0]);
}

static fascia_status hang_from_model(fascia_ctx *ctx, const fascia_model *m, fascia_tissue_hang_result *out) {
  const int32_t A = fascia_model_find_organ(m, "A"), B = fascia_model_find_organ(m, "B");
  SCENE_CHECK(A >= 0 && B >= 0, ctx, FASCIA_ERR_INTERNAL, "hanging organ: the model lacks organ A or B");
  fascia_solver *solver = NULL;
  fascia_status status = FASCIA_OK;
  SCENE_TRY_GOTO(solve(ctx, m, &solver, &out->ms, NULL));
  fascia_real translation[3], q[4], mass, centre[3];
  SCENE_TRY_GOTO(fascia_solver_organ_pose(solver, B, translation, q));
  SCENE_TRY_GOTO(fascia_solver_organ_mass(solver, B, &mass, centre, NULL));
  const double c[3] = {centre[0], centre[1], centre[2]};
  double moved[3];
  rotate(q, c, moved);
  for (int a = 0; a < 3; ++a) out->centre[a] = moved[a] + translation[a] - c[a];
  out->angle = 2 * atan2(q[2], q[0]); // about y: the only axis the load turns it about
  int32_t end = -1;
  SCENE_CHECK(fascia_solver_organ_frame_count(solver, B) == 1, ctx, FASCIA_ERR_INTERNAL,
              "hanging organ: %d frames on B, expected the strand's end alone",
              (int)fascia_solver_organ_frame_count(solver, B));
  SCENE_TRY_GOTO(fascia_solver_organ_frames(solver, B, &end));
  const fascia_real *x = fascia_solver_frame_positions(solver);
  for (int a = 0; a < 3; ++a) out->end[a] = x[3 * end + a] - m->frame_position[3 * end + a];
  SCENE_TRY_GOTO(organ_force(ctx, solver, A, out->force));
  out->nodes = m->frame_count;
cleanup:
  fascia_solver_destroy(&solver);
  return status;
}

fascia_status fascia_tissue_hang_fascia(fascia_ctx *ctx, const fascia_tissue_hang_def *def,
                                        fascia_tissue_hang_result *out) {
  SCENE_CHECK(out, ctx, FASCIA_ERR_ARGUMENT, "hanging organ: NULL result");
  memset(out, 0, sizeof *out);
  fascia_prep_stages s;
  fascia_status status = fascia_tissue_prepare(ctx, fascia_tissue_hang_write_scene, def, &s);
  if (status == FASCIA_OK) status = hang_from_model(ctx, s.model, out);
  fascia_prep_stages_free(&s);
  return status;
}

// The frame nearest p at rest.
static int32_t nearest_frame(const fascia_model *m, const double p[3]) {
  int32_t best = -1;
  double best_d2 = INFINITY;
  for (int32_t i = 0; i < m->frame_count; ++i) {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) d2 += (m->frame_position[3 * i + a] - p[a]) * (m->frame_position[3 * i + a] - p[a]);
    if (d2 < best_d2) best_d2 = d2, best = i;
  }
  return best;
}

static fascia_status pull_from_model(fascia_ctx *ctx, const fascia_tissue_pull_def *def, const fascia_model *m,
                                     fascia_tissue_pull_result *out) {
  const int32_t B = fascia_model_find_organ(m, "B");
  SCENE_CHECK(B >= 0, ctx, FASCIA_ERR_INTERNAL, "pulled sheet: the model lacks organ B");
  fascia_solver *solver = NULL;
  fascia_status status = FASCIA_OK;
  SCENE_TRY_GOTO(solve(ctx, m, &solver, &out->ms, out));
  const double edge_at[3] = {0, def->width / 2, 0}, centre_at[3] = {0, 0, 0};
  const int32_t edge = nearest_frame(m, edge_at), centre = nearest_frame(m, centre_at);
  const fascia_real *x = fascia_solver_frame_positions(solver);
  for (int a = 0; a < 3; ++a) {
    out->centre[a] = x[3 * centre + a] - m->frame_position[3 * centre + a];
    out->edge[a] = x[3 * edge + a] - m->frame_position[3 * edge + a] - out->centre[a];
  }
  SCENE_TRY_GOTO(organ_force(ctx, solver, B, out->force));
  out->nodes = m->frame_count;
cleanup:
  fascia_solver_destroy(&solver);
  return status;
}

fascia_status fascia_tissue_pull_fascia(fascia_ctx *ctx, const fascia_tissue_pull_def *def,
                                        fascia_tissue_pull_result *out) {
  SCENE_CHECK(out, ctx, FASCIA_ERR_ARGUMENT, "pulled sheet: NULL result");
  memset(out, 0, sizeof *out);
  fascia_prep_stages s;
  fascia_status status = fascia_tissue_prepare(ctx, fascia_tissue_pull_write_scene, def, &s);
  if (status == FASCIA_OK) status = pull_from_model(ctx, def, s.model, out);
  fascia_prep_stages_free(&s);
  return status;
}
