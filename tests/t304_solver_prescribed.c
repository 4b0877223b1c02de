// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Frames with a prescribed rigid motion follow it exactly at every step
// (translation linear, rotation interpolated along the shorter arc, about a
// pivot), fixed frames do not move at all, and the motion reaches the free
// frames through the material. A step whose time would not advance (t =
// 1e20 s, dt 0.1 s) or would overflow is refused with a message that says
// so, and leaves the time and the frames as they were. A static solve
// brings the motion in its load steps, along the motion's path.
#include <stdlib.h>
#include <string.h>

#include "backend_arg.h"
#include "check.h"
#include "fascia/solver.h"
#include "point/linalg.h"
#include "scenes.h"

#define ANGLE 0.6 // rad about x at t = 1 s
#define LIFT 0.4  // m along z at t = 1 s
#define PUSH 0.9 // m along x at t = 1 s in the static part: past the free frames at x = 0.8
#define LOAD_STEPS 8

// The static equilibrium reached by solving at t = 1/path, 2/path, .. 1 in
// turn, each with load_steps load steps; 0 if a solve fails. *inverted: the
// samples with det F <= 0 at the end.
static int static_path(fascia_ctx *ctx, const fascia_model *m, const char *backend, int load_steps, int path,
                       double *x, int *inverted) {
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = backend;
  sd.load_steps = load_steps;
  sd.newton_iterations = 100;
  sd.newton_tolerance = 1e-10;
  fascia_solver *s = NULL;
  int ok = fascia_solver_create(ctx, m, &sd, &s) == FASCIA_OK;
  for (int k = 1; ok && k <= path; ++k) {
    fascia_solve_report r;
    ok = fascia_solver_set_time(s, (double)k / path) == FASCIA_OK && fascia_solver_solve_static(s, &r) == FASCIA_OK &&
         r.converged;
    *inverted = r.inverted_samples;
  }
  if (ok) memcpy(x, fascia_solver_frame_positions(s), 3 * sizeof(double) * (size_t)m->frame_count);
  fascia_solver_destroy(&s);
  return ok;
}

int main(int argc, char **argv) {
  const char *backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(backend);
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 6, def.frames[1] = 2, def.frames[2] = 2, def.length = 4;
  fascia_model *src = NULL, *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &def, &src), ctx);
  // same model with one motion: the clamped end (x = 0) becomes prescribed,
  // the frames at x = 4 stay fixed
  fascia_model_sizes z = {src->frame_count, src->sample_count, src->pair_count, src->material_count, 1, 0, 0, 0, 0};
  CHECK_OK(fascia_model_alloc(ctx, &z, &m), ctx);
  memcpy(m->frame_position, src->frame_position, 3 * sizeof(double) * src->frame_count);
  memcpy(m->frame_rotation, src->frame_rotation, 4 * sizeof(double) * src->frame_count);
  memcpy(m->sample_position, src->sample_position, 3 * sizeof(double) * src->sample_count);
  memcpy(m->sample_volume, src->sample_volume, sizeof(double) * src->sample_count);
  memcpy(m->sample_material, src->sample_material, sizeof(int32_t) * src->sample_count);
  memcpy(m->sample_offsets, src->sample_offsets, sizeof(int32_t) * (src->sample_count + 1));
  memcpy(m->pair_frame, src->pair_frame, sizeof(int32_t) * src->pair_count);
  memcpy(m->pair_weight, src->pair_weight, sizeof(double) * src->pair_count);
  memcpy(m->pair_gradient, src->pair_gradient, 3 * sizeof(double) * src->pair_count);
  memcpy(m->materials, src->materials, sizeof(fascia_material) * src->material_count);
  m->gravity[2] = -9.81;
  strcpy(m->motions[0].name, "lift");
  CHECK_OK(fascia_motion_alloc(ctx, &m->motions[0], 2), ctx);
  fascia_motion *mo = &m->motions[0];
  mo->pivot[0] = 0, mo->pivot[1] = 0.2, mo->pivot[2] = -0.1;
  mo->key_time[0] = 0, mo->key_time[1] = 1;
  mo->key_translation[5] = LIFT;
  mo->key_rotation[4] = cos(ANGLE / 2), mo->key_rotation[5] = sin(ANGLE / 2);
  for (int i = 0; i < m->frame_count; ++i) {
    const double x = m->frame_position[3 * i];
    m->frame_kind[i] = x < 1e-9 ? FASCIA_FRAME_PRESCRIBED : x > 4 - 1e-9 ? FASCIA_FRAME_FIXED : FASCIA_FRAME_FREE;
    m->frame_motion[i] = m->frame_kind[i] == FASCIA_FRAME_PRESCRIBED ? 0 : -1;
  }
  CHECK_OK(fascia_model_build_reverse(ctx, m), ctx);
  CHECK_OK(fascia_model_validate(ctx, m, "prescribed test"), ctx);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.time_step = 0.1;
  sd.backend = backend;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  for (int step = 1; step <= 13; ++step) { // past the last key: the pose holds
    CHECK_OK(fascia_solver_step(s, NULL), ctx);
    const double t = fmin(step * sd.time_step, 1.0), angle = ANGLE * t, c = cos(angle), sn = sin(angle);
    const double *x = fascia_solver_frame_positions(s), *q = fascia_solver_frame_rotations(s);
    for (int i = 0; i < m->frame_count; ++i) {
      const double *xr = m->frame_position + 3 * i;
      if (m->frame_kind[i] == FASCIA_FRAME_PRESCRIBED) {
        const double ry = xr[1] - mo->pivot[1], rz = xr[2] - mo->pivot[2];
        CHECK_NEAR(x[3 * i], xr[0], 0, 1e-12);
        CHECK_NEAR(x[3 * i + 1], mo->pivot[1] + c * ry - sn * rz, 0, 1e-12);
        CHECK_NEAR(x[3 * i + 2], mo->pivot[2] + LIFT * t + sn * ry + c * rz, 0, 1e-12);
        CHECK_NEAR(fabs(q[4 * i]), cos(angle / 2), 0, 1e-12);
        CHECK_NEAR(fabs(q[4 * i + 1]), sin(angle / 2), 0, 1e-12);
      } else if (m->frame_kind[i] == FASCIA_FRAME_FIXED) {
        for (int k = 0; k < 3; ++k) CHECK(x[3 * i + k] == xr[k]);
        for (int k = 0; k < 4; ++k) CHECK(q[4 * i + k] == m->frame_rotation[4 * i + k]);
      }
    }
  }
  // the lift reached the free frames next to the prescribed end
  const double *x = fascia_solver_frame_positions(s);
  double lift = 0;
  for (int i = 0; i < m->frame_count; ++i)
    if (fabs(m->frame_position[3 * i] - 0.8) < 1e-9) lift += (x[3 * i + 2] - m->frame_position[3 * i + 2]) / 4;
  CHECK(lift > 0.1 * LIFT);
  // a step that cannot move the time on is refused, the state kept
  const size_t bytes = 3 * sizeof(double) * (size_t)m->frame_count;
  double *before = malloc(bytes);
  static const struct {
    double time, dt;
    const char *says;
  } stalls[] = {{1e20, 0.1, "does not advance"}, {1.7e308, 1e308, "overflows"}};
  for (int k = 0; k < 2 && before; ++k) {
    fascia_solver_def stalled = fascia_solver_def_default();
    stalled.time_step = stalls[k].dt;
    stalled.backend = backend;
    fascia_solver *t = NULL;
    CHECK_OK(fascia_solver_create(ctx, m, &stalled, &t), ctx);
    if (!t) break;
    CHECK_OK(fascia_solver_set_time(t, stalls[k].time), ctx);
    memcpy(before, fascia_solver_frame_positions(t), bytes);
    CHECK(fascia_solver_step(t, NULL) == FASCIA_ERR_ARGUMENT);
    printf("t304: %s\n", fascia_ctx_message(ctx));
    CHECK(strstr(fascia_ctx_message(ctx), stalls[k].says) != NULL);
    CHECK(fascia_solver_time(t) == stalls[k].time);
    CHECK(!memcmp(before, fascia_solver_frame_positions(t), bytes));
    fascia_solver_destroy(&t);
  }
  free(before);
  // the static solve at time 1 in LOAD_STEPS load steps ends where the
  // solves at each step's time in turn end, nothing inverted; the end pushed
  // at once past the frames beside it folds the beam through them
  mo->key_translation[3] = PUSH;
  m->gravity[2] = 0;
  double *stepped = malloc(bytes), *walked = malloc(bytes), *at_once = malloc(bytes);
  CHECK(stepped && walked && at_once);
  if (stepped && walked && at_once) {
    int inverted = -1, walked_inverted = -1, once_inverted = -1;
    if (static_path(ctx, m, backend, 1, 1, at_once, &once_inverted))
      printf("t304: the end pushed %.1f m at once: %d samples inverted\n", PUSH, once_inverted);
    CHECK(static_path(ctx, m, backend, LOAD_STEPS, 1, stepped, &inverted));
    CHECK(static_path(ctx, m, backend, 1, LOAD_STEPS, walked, &walked_inverted));
    double worst = 0;
    for (int k = 0; k < 3 * m->frame_count; ++k) worst = fmax(worst, fabs(stepped[k] - walked[k]));
    printf("t304: %d load steps against %d static solves in turn: largest difference %.2e m, %d and %d samples "
           "inverted\n",
           LOAD_STEPS, LOAD_STEPS, worst, inverted, walked_inverted);
    CHECK(worst < 1e-9 * def.length);
    CHECK(inverted == 0 && walked_inverted == 0);
  }
  free(stepped), free(walked), free(at_once);
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  fascia_model_destroy(&src);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
