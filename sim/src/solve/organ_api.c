// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The C API of fascia/organs.h for an outside simulator: the solver's
// state handed to the organs (organs/organs.c), which know no solver.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/organs.h"
#include "organs/organs.h"
#include "solve/solver_internal.h"
#include "point/linalg.h"

static fascia_status check_organ(const fascia_solver *S, int32_t organ, const char *what) {
  FASCIA_CHECK(S, NULL, FASCIA_ERR_ARGUMENT, "%s: NULL solver", what);
  FASCIA_CHECK(organ >= 0 && organ < S->model->organ_count, S->ctx, FASCIA_ERR_ARGUMENT,
               "%s: organ %d does not exist (the model has %d organs)", what, (int)organ, (int)S->model->organ_count);
  return FASCIA_OK;
}

fascia_status fascia_solver_organ_mass(const fascia_solver *S, int32_t organ, fascia_real *mass, fascia_real *centre,
                                       fascia_real *inertia) {
  FASCIA_TRY(check_organ(S, organ, "organ mass"));
  fascia_real mm, cc[3], II[9];
  const fascia_organ *o = S->model->organs + organ;
  FASCIA_CHECK(fascia_organs_mass_properties(o, &mm, cc, II), S->ctx, FASCIA_ERR_ARGUMENT,
               "organ '%s': its surface encloses no volume", o->name);
  if (mass) *mass = mm;
  if (centre) memcpy(centre, cc, sizeof cc);
  if (inertia) memcpy(inertia, II, sizeof II);
  return FASCIA_OK;
}

fascia_status fascia_solver_organ_pose(const fascia_solver *S, int32_t organ, fascia_real *translation,
                                       fascia_real *rotation) {
  FASCIA_TRY(check_organ(S, organ, "organ pose"));
  FASCIA_CHECK(fascia_organs_pose(S->organs, organ, S->time, S->x, S->q, translation, rotation), S->ctx,
               FASCIA_ERR_UNSUPPORTED, "organ '%s' is driven frame by frame by the caller: it has no pose of its own",
               S->model->organs[organ].name);
  return FASCIA_OK;
}

fascia_status fascia_solver_organ_velocity(const fascia_solver *S, int32_t organ, fascia_real *linear,
                                           fascia_real *angular) {
  FASCIA_TRY(check_organ(S, organ, "organ velocity"));
  fascia_organs_velocity(S->organs, organ, linear, angular);
  return FASCIA_OK;
}

int32_t fascia_solver_organ_frame_count(const fascia_solver *S, int32_t organ) {
  const int32_t *frames;
  if (!S || organ < 0 || organ >= S->model->organ_count) return 0;
  return fascia_organs_frames(S->organs, organ, &frames);
}

fascia_status fascia_solver_organ_frames(const fascia_solver *S, int32_t organ, int32_t *frames) {
  FASCIA_TRY(check_organ(S, organ, "organ frames"));
  const int32_t *own;
  const int32_t count = fascia_organs_frames(S->organs, organ, &own);
  memcpy(frames, own, (size_t)count * sizeof(int32_t));
  return FASCIA_OK;
}

// Drives the organ's frames after checking every one (nothing changes on an error).
static fascia_status drive(fascia_solver *S, int32_t organ, const fascia_real *positions,
                           const fascia_real *rotations, const fascia_real *pose) {
  const char *name = S->model->organs[organ].name;
  const int32_t *frames;
  const int32_t count = fascia_organs_frames(S->organs, organ, &frames);
  FASCIA_CHECK(positions && rotations, S->ctx, FASCIA_ERR_ARGUMENT, "set organ '%s' frames: NULL array", name);
  for (int32_t k = 0; k < count; ++k) {
    const fascia_real *x = positions + 3 * k, *q = rotations + 4 * k;
    const fascia_real norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    FASCIA_CHECK(isfinite(x[0]) && isfinite(x[1]) && isfinite(x[2]) && isfinite(norm) && norm > 1e-12, S->ctx,
                 FASCIA_ERR_ARGUMENT,
                 "set organ '%s' frames: coupling frame %d (frame %d) has a non-finite position or a zero or "
                 "non-finite rotation; nothing changed",
                 name, (int)k, (int)frames[k]);
  }
  fascia_organs_drive(S->organs, organ, positions, rotations, pose, S->mask);
  return FASCIA_OK;
}

fascia_status fascia_solver_organ_set_frames(fascia_solver *S, int32_t organ, const fascia_real *positions,
                                             const fascia_real *rotations) {
  FASCIA_TRY(check_organ(S, organ, "set organ frames"));
  return drive(S, organ, positions, rotations, NULL);
}

fascia_status fascia_solver_organ_release(fascia_solver *S, int32_t organ) {
  FASCIA_TRY(check_organ(S, organ, "release organ"));
  const fascia_organs_state st = {S->x, S->q, S->u, S->d, S->x_base, S->q_base};
  if (fascia_organs_release(S->organs, organ, &st, S->mask)) ++S->linear_epoch;
  return FASCIA_OK;
}

fascia_status fascia_solver_organ_reaction(fascia_solver *S, int32_t organ, fascia_real *forces,
                                           fascia_real *torques) {
  FASCIA_TRY(check_organ(S, organ, "organ reaction"));
  FASCIA_CHECK(forces, S->ctx, FASCIA_ERR_ARGUMENT, "organ reaction: NULL forces");
  const fascia_real *gradient;
  FASCIA_TRY(fascia_solver_loads_gradient(S, &gradient));
  fascia_organs_reaction(S->organs, organ, gradient, forces, torques);
  return FASCIA_OK;
}

fascia_status fascia_solver_organ_set_pose(fascia_solver *S, int32_t organ, const fascia_real *translation,
                                           const fascia_real *rotation) {
  FASCIA_TRY(check_organ(S, organ, "set organ pose"));
  const char *name = S->model->organs[organ].name;
  FASCIA_CHECK(translation && rotation, S->ctx, FASCIA_ERR_ARGUMENT, "set organ '%s' pose: NULL array", name);
  const fascia_real norm =
      sqrt(rotation[0] * rotation[0] + rotation[1] * rotation[1] + rotation[2] * rotation[2] + rotation[3] * rotation[3]);
  FASCIA_CHECK(isfinite(translation[0]) && isfinite(translation[1]) && isfinite(translation[2]) && isfinite(norm) &&
                   norm > 1e-12,
               S->ctx, FASCIA_ERR_ARGUMENT,
               "set organ '%s' pose: translation (%g %g %g) m and rotation (%g %g %g %g) must be finite, the rotation "
               "a nonzero quaternion w x y z; nothing changed",
               name, translation[0], translation[1], translation[2], rotation[0], rotation[1], rotation[2], rotation[3]);
  const int32_t *frames;
  const int32_t count = fascia_organs_frames(S->organs, organ, &frames);
  fascia_real *x = malloc(7 * ((size_t)count + 1) * sizeof(fascia_real)), *q = x + 3 * ((size_t)count + 1);
  FASCIA_CHECK(x, S->ctx, FASCIA_ERR_MEMORY, "set organ '%s' pose: out of memory", name);
  fascia_real pose[7], R[9];
  memcpy(pose, translation, 3 * sizeof(fascia_real));
  for (int c = 0; c < 4; ++c) pose[3 + c] = rotation[c] / norm;
  fascia_pt_quat_to_mat(pose + 3, R);
  const fascia_model *m = S->model;
  for (int32_t k = 0; k < count; ++k) { // x = R x_rest + t, q = Q q_rest
    const int32_t i = frames[k];
    fascia_pt_mat_vec(R, m->frame_position + 3 * (int64_t)i, x + 3 * k);
    for (int c = 0; c < 3; ++c) x[3 * k + c] += translation[c];
    fascia_pt_quat_mul(pose + 3, m->frame_rotation + 4 * (int64_t)i, q + 4 * k);
  }
  const fascia_status st = drive(S, organ, x, q, pose);
  free(x);
  return st;
}

fascia_status fascia_solver_organ_wrench(fascia_solver *S, int32_t organ, fascia_real *force, fascia_real *torque,
                                         fascia_real *point) {
  FASCIA_TRY(check_organ(S, organ, "organ wrench"));
  FASCIA_CHECK(force, S->ctx, FASCIA_ERR_ARGUMENT, "organ wrench: NULL force");
  const int32_t *frames;
  const int32_t count = fascia_organs_frames(S->organs, organ, &frames);
  fascia_real p[3];
  fascia_organs_reference_point(S->organs, organ, S->time, S->x, S->q, p);
  fascia_real F[3] = {0, 0, 0}, M[3] = {0, 0, 0};
  if (count > 0) {
    fascia_real *f = malloc(6 * (size_t)count * sizeof(fascia_real));
    FASCIA_CHECK(f, S->ctx, FASCIA_ERR_MEMORY, "organ wrench: out of memory");
    const fascia_status st = fascia_solver_organ_reaction(S, organ, f, f + 3 * count);
    for (int32_t k = 0; st == FASCIA_OK && k < count; ++k) {
      const fascia_real *x = S->x + 3 * (int64_t)frames[k], *fk = f + 3 * k;
      fascia_real arm[3], moment[3];
      for (int c = 0; c < 3; ++c) arm[c] = x[c] - p[c];
      fascia_pt_cross(arm, fk, moment);
      for (int c = 0; c < 3; ++c) F[c] += fk[c], M[c] += f[3 * count + 3 * k + c] + moment[c];
    }
    free(f);
    FASCIA_TRY(st);
  }
  memcpy(force, F, sizeof F);
  if (torque) memcpy(torque, M, sizeof M);
  if (point) memcpy(point, p, sizeof p);
  return FASCIA_OK;
}
