// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Shared driver of the stability suite (t31x, stability at the
// extremes): runs implicit Euler steps on a small model and checks, step by
// step, what every extreme case must satisfy: the state stays finite; the
// total energy E_kin + E_pot does not grow once nothing from outside does
// work (implicit Euler dissipates); a step the solver cannot take comes back
// as FASCIA_ERR_NUMERIC with a message and the state, velocities and time
// exactly as before the step, never as garbage. On every backend: a test
// sets stab_backend from its --backend (tests/backend_arg.h) and takes its
// solver settings from stab_solver_def().
#ifndef FASCIA_TESTS_STABILITY_H
#define FASCIA_TESTS_STABILITY_H

#include <stdlib.h>
#include <string.h>

#include "backend_arg.h"
#include "check.h"
#include "fascia/solver.h"
#include "scenes.h"

/// Relative energy growth per step tolerated, against the energy scale
/// m |g| L + |E_pot| + E_kin. Implicit Euler is dissipative for a converged
/// step; what is left is the Newton tolerance (1e-6 of the load) and the
/// lumped rotational inertia taken at the step's start (measured over
/// t310..t316: at most 4e-14 in any monotone case); 1e-6 leaves room for that
/// and is far below a real instability (the crudest inexact solve of t315
/// rises by 2e-4 in single steps).
#define STAB_ENERGY_RTOL 1e-6

/// What a run did.
typedef struct stab_result {
  int steps;           ///< steps taken (status OK)
  int numeric_errors;  ///< steps refused with FASCIA_ERR_NUMERIC (run stops at the first)
  int bad;             ///< non-finite state, changed state after an error, empty message, energy growth
  int max_inverted;    ///< largest inverted_samples of any step's report
  int substeps;        ///< sum of the reports' substeps
  int converged;       ///< steps whose Newton solve converged
  double energy_start, energy_end, max_rise; ///< E_kin + E_pot (J); largest growth in one step over the scale
  double max_above_start; ///< largest E_kin + E_pot - energy_start over the scale
} stab_result;

/// The backend every solver of the test runs on.
static const char *stab_backend = "cpu";

/// The default solver settings, on stab_backend.
static inline fascia_solver_def stab_solver_def(void) {
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = stab_backend;
  return sd;
}

static inline fascia_ctx *stab_ctx(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1; // small models; the machine is shared
  fascia_ctx *ctx = NULL;
  return fascia_ctx_create(&cd, &ctx) == FASCIA_OK ? ctx : NULL;
}

/// A short beam: 4 m x 1 m x 1 m, nx x 2 x 2 frames, clamped at x = 0.
static inline fascia_scene_beam_def stab_beam_def(int nx, int law) {
  fascia_scene_beam_def d = fascia_scene_beam_def_default();
  d.frames[0] = nx, d.frames[1] = 2, d.frames[2] = 2;
  d.length = 4;
  d.law = law;
  return d;
}

static inline int stab_finite(const fascia_solver *s, int32_t frames) {
  const fascia_real *x = fascia_solver_frame_positions(s), *q = fascia_solver_frame_rotations(s);
  const fascia_real *u = fascia_solver_frame_velocities(s);
  for (int32_t k = 0; k < 3 * frames; ++k)
    if (!isfinite(x[k])) return 0;
  for (int32_t k = 0; k < 4 * frames; ++k)
    if (!isfinite(q[k])) return 0;
  for (int32_t k = 0; k < 6 * frames; ++k)
    if (!isfinite(u[k])) return 0;
  return 1;
}

static inline double stab_energy(fascia_solver *s) {
  fascia_real pe = NAN;
  if (fascia_solver_potential_energy(s, &pe) != FASCIA_OK) return NAN;
  return pe + fascia_solver_kinetic_energy(s);
}

/// Runs `steps` steps of `sd` on `m`. The energy is checked on every step
/// that starts at time >= work_until (s): before it, prescribed motions may
/// do work. monotone: E_kin + E_pot must not grow in any step (a converged
/// implicit Euler step dissipates); else only stay below its start (all an
/// inexact step that is not the minimizer can promise). `name` labels
/// failure messages. Stops at the first refused step.
static inline stab_result stab_run(fascia_ctx *ctx, const char *name, const fascia_model *m,
                                   const fascia_solver_def *sd, int steps, double work_until, int monotone) {
  stab_result r;
  memset(&r, 0, sizeof r);
  fascia_solver *s = NULL;
  if (fascia_solver_create(ctx, m, sd, &s) != FASCIA_OK) {
    fprintf(stderr, "%s: solver_create: %s\n", name, fascia_ctx_message(ctx));
    r.bad = 1;
    return r;
  }
  const int32_t N = m->frame_count;
  double weight_scale = 0; // m |g| L: the gravity energy of the whole body over its size
  {
    const double g = sqrt(m->gravity[0] * m->gravity[0] + m->gravity[1] * m->gravity[1] + m->gravity[2] * m->gravity[2]);
    double lo = INFINITY, hi = -INFINITY;
    for (int32_t i = 0; i < N; ++i) lo = fmin(lo, m->frame_position[3 * i]), hi = fmax(hi, m->frame_position[3 * i]);
    weight_scale = fascia_model_mass(m) * g * (hi - lo);
  }
  fascia_real *before = malloc((size_t)N * 13 * sizeof(fascia_real));
  r.energy_start = r.energy_end = stab_energy(s);
  for (int n = 0; n < steps && before; ++n) {
    memcpy(before, fascia_solver_frame_positions(s), 3 * (size_t)N * sizeof(fascia_real));
    memcpy(before + 3 * N, fascia_solver_frame_rotations(s), 4 * (size_t)N * sizeof(fascia_real));
    memcpy(before + 7 * N, fascia_solver_frame_velocities(s), 6 * (size_t)N * sizeof(fascia_real));
    const double t_before = fascia_solver_time(s), e_before = stab_energy(s);
    fascia_ctx_clear(ctx);
    fascia_solve_report rep;
    const fascia_status st = fascia_solver_step(s, &rep);
    if (st == FASCIA_ERR_NUMERIC) {
      // refused: said so, and nothing moved
      ++r.numeric_errors;
      const int same = !memcmp(before, fascia_solver_frame_positions(s), 3 * (size_t)N * sizeof(fascia_real)) &&
                       !memcmp(before + 3 * N, fascia_solver_frame_rotations(s), 4 * (size_t)N * sizeof(fascia_real)) &&
                       !memcmp(before + 7 * N, fascia_solver_frame_velocities(s), 6 * (size_t)N * sizeof(fascia_real)) &&
                       fascia_solver_time(s) == t_before;
      if (!same || !fascia_ctx_message(ctx)[0]) {
        fprintf(stderr, "%s: step %d refused but the state changed (%d) or the message is empty\n", name, n, !same);
        r.bad = 1;
      }
      break;
    }
    if (st != FASCIA_OK) {
      fprintf(stderr, "%s: step %d returned %s: %s\n", name, n, fascia_status_name(st), fascia_ctx_message(ctx));
      r.bad = 1;
      break;
    }
    ++r.steps;
    r.substeps += rep.substeps;
    r.converged += rep.converged != 0;
    if (rep.inverted_samples > r.max_inverted) r.max_inverted = rep.inverted_samples;
    const double e = stab_energy(s);
    if (!stab_finite(s, N) || !isfinite(e)) {
      fprintf(stderr, "%s: step %d left a non-finite state (energy %g)\n", name, n, e);
      r.bad = 1;
      break;
    }
    if (t_before >= work_until) {
      const double scale = weight_scale + fabs(e_before) + fascia_solver_kinetic_energy(s);
      const double rise = (e - e_before) / (scale > 0 ? scale : 1);
      const double above = (e - r.energy_start) / (scale > 0 ? scale : 1);
      if (rise > r.max_rise) r.max_rise = rise;
      if (above > r.max_above_start) r.max_above_start = above;
      if (!monotone && above > STAB_ENERGY_RTOL && work_until == 0) {
        fprintf(stderr, "%s: step %d (t = %g s) raised E_kin + E_pot above its start, %.9g J to %.9g J\n", name, n,
                t_before, r.energy_start, e);
        r.bad = 1;
      }
      if (monotone && rise > STAB_ENERGY_RTOL) {
        fprintf(stderr, "%s: step %d (t = %g s) raised E_kin + E_pot from %.9g to %.9g J (%.3g of the scale %.3g)\n",
                name, n, t_before, e_before, e, rise, scale);
        r.bad = 1;
      }
    }
    r.energy_end = e;
  }
  if (!before) r.bad = 1;
  free(before);
  if (getenv("FASCIA_STAB_VERBOSE")) // measurements behind the tolerances
    fprintf(stderr, "%-32s steps %3d substeps %3d converged %3d refused %d inverted %4d max rise %.2e above start %.2e E %.6g -> %.6g\n",
            name, r.steps, r.substeps, r.converged, r.numeric_errors, r.max_inverted, r.max_rise, r.max_above_start,
            r.energy_start, r.energy_end);
  fascia_solver_destroy(&s);
  return r;
}

/// A copy of src with room for extra frames, samples, pairs, materials
/// (at least src's) and `motions` motions: everything of src copied (frames first, samples first), the
/// extra entries zeroed; the caller fills them and builds the reverse table.
static inline fascia_model *stab_copy_model(fascia_ctx *ctx, const fascia_model *src, int extra_frames,
                                            int extra_samples, int extra_pairs, int materials, int motions) {
  fascia_model_sizes z = {src->frame_count + extra_frames, src->sample_count + extra_samples,
                          src->pair_count + extra_pairs, materials, motions, src->probe_count,
                          src->probe_pair_count, 0, 0};
  fascia_model *m = NULL;
  if (fascia_model_alloc(ctx, &z, &m) != FASCIA_OK) return NULL;
  const size_t N = (size_t)src->frame_count, S = (size_t)src->sample_count, P = (size_t)src->pair_count;
  memcpy(m->frame_position, src->frame_position, 3 * N * sizeof(fascia_real));
  memcpy(m->frame_rotation, src->frame_rotation, 4 * N * sizeof(fascia_real));
  memcpy(m->frame_kind, src->frame_kind, N * sizeof(int32_t));
  memcpy(m->frame_motion, src->frame_motion, N * sizeof(int32_t));
  memcpy(m->sample_position, src->sample_position, 3 * S * sizeof(fascia_real));
  memcpy(m->sample_volume, src->sample_volume, S * sizeof(fascia_real));
  memcpy(m->sample_material, src->sample_material, S * sizeof(int32_t));
  memcpy(m->sample_offsets, src->sample_offsets, (S + 1) * sizeof(int32_t));
  memcpy(m->pair_frame, src->pair_frame, P * sizeof(int32_t));
  memcpy(m->pair_weight, src->pair_weight, P * sizeof(fascia_real));
  memcpy(m->pair_gradient, src->pair_gradient, 3 * P * sizeof(fascia_real));
  memcpy(m->materials, src->materials, (size_t)src->material_count * sizeof(fascia_material));
  memcpy(m->gravity, src->gravity, sizeof m->gravity);
  m->allow_floating = src->allow_floating;
  const size_t Q = (size_t)src->probe_count, QP = (size_t)src->probe_pair_count;
  memcpy(m->probe_name, src->probe_name, Q * sizeof *m->probe_name);
  memcpy(m->probe_position, src->probe_position, 3 * Q * sizeof(fascia_real));
  memcpy(m->probe_offsets, src->probe_offsets, (Q + 1) * sizeof(int32_t));
  memcpy(m->probe_frame, src->probe_frame, QP * sizeof(int32_t));
  memcpy(m->probe_weight, src->probe_weight, QP * sizeof(fascia_real));
  for (int k = 0; k <= extra_samples; ++k) m->sample_offsets[S + (size_t)k] = (int32_t)P;
  return m;
}

/// Tip (probe "tip") displacement along z after a static solve of at most
/// `newton` iterations, or NAN.
static inline double stab_static_tip(fascia_ctx *ctx, const fascia_model *m, int newton, fascia_status *status) {
  fascia_solver_def sd = stab_solver_def();
  sd.newton_iterations = newton;
  fascia_solver *s = NULL;
  *status = fascia_solver_create(ctx, m, &sd, &s);
  if (*status != FASCIA_OK) return NAN;
  *status = fascia_solver_solve_static(s, NULL);
  const int32_t tip = fascia_model_find_probe(m, "tip");
  fascia_real p[3] = {NAN, NAN, NAN};
  if (tip >= 0) fascia_solver_probe_position(s, tip, p);
  fascia_solver_destroy(&s);
  return tip >= 0 ? p[2] - m->probe_position[3 * tip + 2] : NAN;
}

// The 6 x 2 x 2 beam without gravity, frames at x = 0 fixed, frames at
// x = plane moving by -push along x over motion_end (s).
static inline fascia_model *stab_pushed_beam(fascia_ctx *ctx, int law, double plane, double push,
                                             double motion_end) {
  fascia_scene_beam_def bd = stab_beam_def(6, law);
  bd.gravity[2] = 0;
  fascia_model *src = NULL;
  if (fascia_scene_beam_build(ctx, &bd, &src) != FASCIA_OK) return NULL;
  fascia_model *m = stab_copy_model(ctx, src, 0, 0, 0, 1, 1);
  fascia_model_destroy(&src);
  if (!m) return NULL;
  fascia_motion *mo = &m->motions[0];
  strcpy(mo->name, "push");
  if (fascia_motion_alloc(ctx, mo, 2) != FASCIA_OK) {
    fascia_model_destroy(&m);
    return NULL;
  }
  mo->key_time[0] = 0, mo->key_time[1] = motion_end;
  mo->key_translation[3] = -push;
  mo->key_rotation[0] = mo->key_rotation[4] = 1;
  for (int32_t i = 0; i < m->frame_count; ++i) {
    const double x = m->frame_position[3 * i];
    m->frame_kind[i] = x < 1e-9 ? FASCIA_FRAME_FIXED : fabs(x - plane) < 1e-9 ? FASCIA_FRAME_PRESCRIBED : FASCIA_FRAME_FREE;
    m->frame_motion[i] = m->frame_kind[i] == FASCIA_FRAME_PRESCRIBED ? 0 : -1;
  }
  if (fascia_model_build_reverse(ctx, m) != FASCIA_OK || fascia_model_validate(ctx, m, "pushed beam") != FASCIA_OK)
    fascia_model_destroy(&m);
  return m;
}

#endif
