// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The public solver: checks settings, holds the state (positions, rotations,
// velocities, time), sets prescribed and fixed frames, and runs the static
// solve and implicit Euler steps through newton.c.
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "solve/backend.h"
#include "cpu/dilatation.h"
#include "cpu/modes.h"
#include "model/model_arrays.h"
#include "organs/organs.h"
#include "point/frame.h"
#include "point/linalg.h"
#include "solve/solver_internal.h"

fascia_solver_def fascia_solver_def_default(void) {
  fascia_solver_def d;
  memset(&d, 0, sizeof d);
  d.backend = "auto";
  d.time_step = FASCIA_R(0.01);
  d.newton_iterations = 20;
  d.newton_tolerance = FASCIA_R(1e-6);
  d.cg_iterations = 200;
  d.cg_tolerance = FASCIA_R(1e-3);
  d.precond = FASCIA_PRECOND_BLOCK_JACOBI;
  d.linear_solver = FASCIA_LINEAR_AUTO;
  d.assembled = FASCIA_ASSEMBLED_AUTO;
  d.single_precision_matrix = FASCIA_SINGLE_AUTO;
  d.mass = FASCIA_MASS_LUMPED;
  d.line_search = 1;
  d.load_steps = 1;
  d.step_retries = 4;
  d.require_convergence = 1;
  d.blow_up_strain = 10;
  d.cookie_ = FASCIA_DEF_COOKIE;
  return d;
}

void fascia_profile_add(fascia_profile *sum, const fascia_profile *p) {
  sum->evaluate_ms += p->evaluate_ms;
  sum->precond_ms += p->precond_ms;
  sum->assemble_ms += p->assemble_ms;
  sum->cg_ms += p->cg_ms;
  sum->total_ms += p->total_ms;
}

static fascia_status check_time_step(fascia_ctx *ctx, fascia_real time_step) {
  FASCIA_CHECK(isfinite(time_step) && time_step > 0, ctx, FASCIA_ERR_ARGUMENT,
               "solver: time step %g s is impossible; give a positive number of seconds", time_step);
  FASCIA_CHECK(time_step >= FASCIA_MIN_TIME_STEP, ctx, FASCIA_ERR_ARGUMENT,
               "solver: time step %g s is below the shortest one, %g s (the inertia term would swamp the tissue's "
               "stiffness beyond double precision); give a longer time step", time_step, FASCIA_MIN_TIME_STEP);
  return FASCIA_OK;
}

static fascia_status check_def(fascia_ctx *ctx, const fascia_solver_def *d) {
  FASCIA_CHECK(d->cookie_ == FASCIA_DEF_COOKIE, ctx, FASCIA_ERR_ARGUMENT,
               "solver: the settings were not made by fascia_solver_def_default()");
  FASCIA_TRY(check_time_step(ctx, d->time_step));
  FASCIA_CHECK(isfinite(d->blow_up_strain) && d->blow_up_strain >= 0, ctx, FASCIA_ERR_ARGUMENT,
               "solver: blow-up strain %g must be >= 0 (0: off)", d->blow_up_strain);
  FASCIA_CHECK(d->newton_iterations >= 1 && d->newton_iterations <= 100000, ctx, FASCIA_ERR_ARGUMENT,
               "solver: %d Newton iterations; give 1 to 100000", d->newton_iterations);
  // relative to the load: at 1 or more the starting state, carrying the
  // whole load as its residual, would count as converged
  FASCIA_CHECK(isfinite(d->newton_tolerance) && d->newton_tolerance >= 0 && d->newton_tolerance < 1, ctx,
               FASCIA_ERR_ARGUMENT,
               "solver: Newton tolerance %g must be in [0, 1): it is relative to the load, and at 1 or more a state "
               "carrying the whole load unbalanced counts as converged; give e.g. 1e-6",
               d->newton_tolerance);
  FASCIA_CHECK(d->cg_iterations >= 1 && d->cg_iterations <= 10000000, ctx, FASCIA_ERR_ARGUMENT,
               "solver: %d CG iterations; give at least 1", d->cg_iterations);
  FASCIA_CHECK(isfinite(d->cg_tolerance) && d->cg_tolerance >= 0 && d->cg_tolerance < 1, ctx, FASCIA_ERR_ARGUMENT,
               "solver: CG tolerance %g must be in [0, 1)", d->cg_tolerance);
  FASCIA_CHECK(d->precond >= FASCIA_PRECOND_NONE && d->precond <= FASCIA_PRECOND_BLOCK_JACOBI, ctx,
               FASCIA_ERR_ARGUMENT, "solver: unknown preconditioner %d", (int)d->precond);
  FASCIA_CHECK(d->linear_solver >= FASCIA_LINEAR_AUTO && d->linear_solver <= FASCIA_LINEAR_DIRECT, ctx,
               FASCIA_ERR_ARGUMENT, "solver: unknown linear solver %d", (int)d->linear_solver);
  FASCIA_CHECK(d->assembled >= FASCIA_ASSEMBLED_AUTO && d->assembled <= 1, ctx, FASCIA_ERR_ARGUMENT,
               "solver: assembled %d; give 0 (matrix-free), 1 or FASCIA_ASSEMBLED_AUTO", d->assembled);
  FASCIA_CHECK(d->single_precision_matrix >= FASCIA_SINGLE_AUTO && d->single_precision_matrix <= 1, ctx,
               FASCIA_ERR_ARGUMENT, "solver: single precision matrix %d; give 0 (double), 1 (float) or FASCIA_SINGLE_AUTO",
               d->single_precision_matrix);
  FASCIA_CHECK(d->mass == FASCIA_MASS_CONSISTENT || d->mass == FASCIA_MASS_LUMPED, ctx, FASCIA_ERR_ARGUMENT,
               "solver: unknown mass kind %d", (int)d->mass);
  FASCIA_CHECK(isfinite(d->mass_damping) && d->mass_damping >= 0, ctx, FASCIA_ERR_ARGUMENT,
               "solver: mass damping %g 1/s must be >= 0", d->mass_damping);
  FASCIA_CHECK(d->load_steps >= 1 && d->load_steps <= 100000, ctx, FASCIA_ERR_ARGUMENT,
               "solver: %d load steps; give at least 1", d->load_steps);
  FASCIA_CHECK(d->step_retries >= 0 && d->step_retries <= 30, ctx, FASCIA_ERR_ARGUMENT,
               "solver: %d step retries; give 0 to 30 (each halves the time step)", d->step_retries);
  FASCIA_CHECK(d->threads >= 0, ctx, FASCIA_ERR_ARGUMENT, "solver: %d threads", d->threads);
  return FASCIA_OK;
}

// Every free tissue frame must carry mass: a frame no sample puts mass on
// has no inertia and, having no sample, no stiffness either, so the implicit
// step has no unique solution. (A rigid organ's frames move with its body,
// whose mass is the organ's.) The lumped blocks cannot be indefinite: their
// shares are never negative (system.c); t340 checks that the blocks of
// prepared models are positive definite.
static fascia_status check_mass(fascia_solver *S) {
  const fascia_model *m = S->model;
  for (int32_t i = 0; i < m->frame_count; ++i) {
    if (!S->mask[6 * (int64_t)i] || fascia_organs_frame_body(S->organs, i) >= 0) continue;
    if (S->sys->frame_lumped_moments[13 * (int64_t)i] > 0) continue; // its lumped mass, sum of its pairs' shares
    const fascia_real *x = m->frame_position + 3 * (int64_t)i;
    return FASCIA_FAIL(S->ctx, FASCIA_ERR_FORMAT,
                       "model: free frame %d (rest position %.4g %.4g %.4g m) has no mass: no sample puts weight on "
                       "it, so nothing holds it; re-run 'fascia prep', or make the frame fixed",
                       (int)i, x[0], x[1], x[2]);
  }
  return FASCIA_OK;
}

// What the blow-up rule needs of the model: whether any frame is prescribed
// (then the motion does work the rule cannot account for), and the energy
// scale m |g| L (L the diagonal of the frames' bounding box).
static void energy_scale(fascia_solver *S) {
  const fascia_model *m = S->model;
  fascia_real lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  S->closed = 1;
  for (int32_t i = 0; i < m->frame_count; ++i) {
    S->closed &= m->frame_kind[i] != FASCIA_FRAME_PRESCRIBED;
    for (int c = 0; c < 3; ++c)
      lo[c] = fmin(lo[c], m->frame_position[3 * i + c]), hi[c] = fmax(hi[c], m->frame_position[3 * i + c]);
  }
  fascia_real size2 = 0;
  for (int c = 0; m->frame_count > 0 && c < 3; ++c) size2 += (hi[c] - lo[c]) * (hi[c] - lo[c]);
  S->model_size = size2 > 0 ? sqrt(size2) : 1;
  S->weight_scale = fascia_model_mass(m) * sqrt(fascia_pt_dot3(m->gravity, m->gravity)) * S->model_size;
}

fascia_status fascia_solver_create(fascia_ctx *ctx, const fascia_model *model, const fascia_solver_def *def,
                                   fascia_solver **out) {
  FASCIA_CHECK(out && model && def, ctx, FASCIA_ERR_ARGUMENT, "fascia_solver_create: NULL argument");
  *out = NULL;
  FASCIA_TRY(check_def(ctx, def));
  fascia_solver *S = calloc(1, sizeof *S);
  FASCIA_CHECK(S, ctx, FASCIA_ERR_MEMORY, "solver: out of memory");
  fascia_status status = FASCIA_OK;
  S->ctx = ctx;
  S->model = model;
  S->def = *def;
  S->frame_count = model->frame_count;
  FASCIA_TRY_GOTO(fascia_system_create(ctx, model, def->threads > 0 ? def->threads : fascia_ctx_threads(ctx), &S->sys));
  const int64_t N = model->frame_count, n = 6 * N;
  S->x = fascia_calloc(3 * N, sizeof(fascia_real));
  S->q = fascia_calloc(4 * N, sizeof(fascia_real));
  S->u = fascia_calloc(n, sizeof(fascia_real));
  S->mask = fascia_calloc(n, 1);
  // the arrays a GPU backend copies at every step's begin are on pages of their own
  S->x_base = fascia_calloc_pages(3 * N, sizeof(fascia_real));
  S->q_base = fascia_calloc_pages(4 * N, sizeof(fascia_real));
  S->d = fascia_calloc_pages(n, sizeof(fascia_real));
  S->inertia_target = fascia_calloc_pages(n, sizeof(fascia_real));
  S->gradient = fascia_calloc(n, sizeof(fascia_real));
  S->kinetic_blocks = fascia_calloc(36 * N, sizeof(fascia_real));
  S->scratch = fascia_calloc(n, sizeof(fascia_real));
  S->reaction = fascia_calloc(n, sizeof(fascia_real));
  S->reaction_at = fascia_calloc(13 * N, sizeof(fascia_real));
  if (!S->x || !S->q || !S->u || !S->mask || !S->x_base || !S->q_base || !S->d || !S->inertia_target ||
      !S->gradient || !S->kinetic_blocks || !S->scratch || !S->reaction || !S->reaction_at) {
    status = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "solver: out of memory for %lld frames", (long long)N);
    goto cleanup;
  }
  FASCIA_TRY_GOTO(fascia_organs_create(ctx, model, &S->organs));
  memcpy(S->x, model->frame_position, 3 * (size_t)N * sizeof(fascia_real));
  memcpy(S->q, model->frame_rotation, 4 * (size_t)N * sizeof(fascia_real));
  fascia_organs_masks(model, S->organs, S->mask);
  FASCIA_TRY_GOTO(check_mass(S));
  energy_scale(S);
  S->load_factor = 1;
  S->first_inverted = S->first_nonfinite = -1;
  static const fascia_pt_patches no_patches;
  const fascia_dilatation *patches = S->sys->dilatation;
  // the arrays a backend uploads, by row of the contract's tables
  fascia_model_view views[FASCIA_MA_COUNT];
  fascia_array_data model_arrays[FASCIA_MA_COUNT], system_arrays[FASCIA_SA_COUNT];
  fascia_model_views(model, views);
  for (int k = 0; k < FASCIA_MA_COUNT; ++k)
    model_arrays[k] = (fascia_array_data){views[k].data, fascia_model_view_bytes(views + k)};
  fascia_system_arrays(S->sys, system_arrays);
  fascia_backend_setup setup = {ctx,
                                model,
                                model_arrays,
                                system_arrays,
                                S->sys->max_neighbours,
                                {S->sys->gravity[0], S->sys->gravity[1], S->sys->gravity[2]},
                                S->sys->threads,
                                S->sys,
                                S->mask,
                                &S->def,
                                &S->linear_epoch,
                                S->organs,
                                fascia_organs_body_count(S->organs),
                                fascia_organs_bodies(S->organs),
                                S->organs ? fascia_organs_full_mask(S->organs) : S->mask,
                                patches ? &patches->view : &no_patches,
                                patches ? patches->table.entry_count : 0,
                                S->sys->modes ? &S->sys->modes->view : NULL,
                                {0},
                                {0},
                                0};
  void *const crossing[] = {S->x_base, S->q_base, S->d, S->inertia_target};
  const size_t sizes[] = {3, 4, 6, 6};
  for (size_t k = 0; k < sizeof crossing / sizeof crossing[0]; ++k) {
    setup.crossing[k] = crossing[k];
    setup.crossing_bytes[k] = sizes[k] * (size_t)N * sizeof(fascia_real);
  }
  setup.crossing_count = (int)(sizeof crossing / sizeof crossing[0]);
  FASCIA_TRY_GOTO(fascia_backend_pick(&setup, &S->backend, S->device_text, sizeof S->device_text));
  snprintf(S->backend_name, sizeof S->backend_name, "%s", S->backend->ops->name);
  *out = S;
  return FASCIA_OK;
cleanup:
  fascia_solver_destroy(&S);
  return status;
}

void fascia_solver_destroy(fascia_solver **solver) {
  if (!solver || !*solver) return;
  fascia_solver *S = *solver;
  if (S->backend) S->backend->ops->destroy(S->backend); // first: a device unpins the solver's arrays
  fascia_system_destroy(&S->sys);
  fascia_organs_destroy(&S->organs);
  free(S->x), free(S->q), free(S->u), free(S->mask), free(S->x_base), free(S->q_base), free(S->d);
  free(S->inertia_target), free(S->gradient), free(S->kinetic_blocks), free(S->scratch);
  free(S->reaction), free(S->reaction_at);
  free(S);
  *solver = NULL;
}

// Puts prescribed frames where their motion says at time t (fixed frames
// never move: their DOFs are masked).
static void place_prescribed(fascia_solver *S, fascia_real t) {
  const fascia_model *m = S->model;
  for (int32_t i = 0; i < S->frame_count; ++i)
    if (m->frame_kind[i] == FASCIA_FRAME_PRESCRIBED) fascia_motion_frame(m, i, t, S->x + 3 * i, S->q + 4 * i);
  fascia_organs_place(S->organs, S->x, S->q);
  S->placed_time = t;
}

static fascia_status save_state(fascia_solver *S, fascia_real **backup) {
  const size_t N = (size_t)S->frame_count;
  *backup = malloc(((3 + 4 + 6) * N + fascia_organs_state_size(S->organs)) * sizeof(fascia_real));
  FASCIA_CHECK(*backup, S->ctx, FASCIA_ERR_MEMORY, "solver: out of memory");
  memcpy(*backup, S->x, 3 * N * sizeof(fascia_real));
  memcpy(*backup + 3 * N, S->q, 4 * N * sizeof(fascia_real));
  memcpy(*backup + 7 * N, S->u, 6 * N * sizeof(fascia_real));
  fascia_organs_save(S->organs, *backup + 13 * N);
  return FASCIA_OK;
}

// The system (the host's evaluation of the model) at the solver's state,
// for what the host reads between steps: the output queries, the organs'
// reactions, the blow-up message. With the CPU backend's trial states, the
// only writer of the system's state; it is the solver's state of this
// moment (a query is read from where the state is now, never from a stale
// copy), so nothing else needs to keep the two in step.
static fascia_system *host_system(const fascia_solver *S) {
  fascia_system_set_state(S->sys, S->x, S->q);
  S->sys->gravity_scale = S->load_factor;
  return S->sys;
}

fascia_status fascia_solver_loads_gradient(fascia_solver *S, const fascia_real **gradient) {
  const size_t N = (size_t)S->frame_count;
  fascia_real *at = S->reaction_at;
  if (!(S->reaction_known && !memcmp(at, S->x, 3 * N * sizeof *at) && !memcmp(at + 3 * N, S->q, 4 * N * sizeof *at) &&
        !memcmp(at + 7 * N, S->model->frame_load, 6 * N * sizeof *at))) {
    S->reaction_known = 0;
    const fascia_backend_ops *ops = S->backend->ops;
    if (ops->energy_gradient) {
      FASCIA_TRY(ops->energy_gradient(S->backend, S->x, S->q, 1, S->reaction));
    } else {
      fascia_system *sys = host_system(S);
      fascia_real energy;
      sys->gravity_scale = 1; // the reactions' full load
      const fascia_status status = fascia_system_evaluate(sys, S->reaction, &energy);
      sys->gravity_scale = S->load_factor;
      FASCIA_TRY(status);
    }
    memcpy(at, S->x, 3 * N * sizeof *at);
    memcpy(at + 3 * N, S->q, 4 * N * sizeof *at);
    memcpy(at + 7 * N, S->model->frame_load, 6 * N * sizeof *at);
    S->reaction_known = 1;
  }
  *gradient = S->reaction;
  return FASCIA_OK;
}

static void restore_state(fascia_solver *S, fascia_real *backup) {
  const size_t N = (size_t)S->frame_count;
  memcpy(S->x, backup, 3 * N * sizeof(fascia_real));
  memcpy(S->q, backup + 3 * N, 4 * N * sizeof(fascia_real));
  memcpy(S->u, backup + 7 * N, 6 * N * sizeof(fascia_real));
  fascia_organs_restore(S->organs, backup + 13 * N);
}

// Whether every frame sample s takes weight from is fixed, prescribed or in
// a rigid organ: then their motion alone deforms it, and no time step or
// solver setting changes that, so a failure there must not blame the step.
static int sample_held(const fascia_solver *S, int32_t s) {
  const fascia_model *m = S->model;
  if (s < 0 || s >= m->sample_count) return 0;
  for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k) {
    const int32_t i = m->pair_frame[k];
    if (S->mask[6 * (int64_t)i] && fascia_organs_frame_body(S->organs, i) < 0) return 0;
  }
  return 1;
}

#define HELD_CAUSE                                                                                                 \
  "its frames are all fixed, prescribed or in rigid organs, so their motion alone deforms it and no time step "    \
  "or solver setting changes that: the tissue there needs free frames (finer spacings: prep gives a layer "       \
  "thinner than two sample spacings none) or more room between the organs (a thicker interface layer)"

static fascia_status check_blow_up(fascia_solver *S, const fascia_solve_report *r, int energy_before_known,
                                   fascia_real energy_before);

// Whether the last attempt's evaluation had a sample whose energy is not
// finite and whose frames are all held (sample_held)
static int nonfinite_held(const fascia_solver *S) {
  return S->nonfinite_count > 0 && sample_held(S, S->first_nonfinite);
}

// The Newton minimization of a step's objective: a static one (h = 0) or
// an implicit Euler step of length h
static fascia_status minimize(fascia_solver *S, fascia_real h, fascia_solve_report *report) {
  const fascia_step_values values = {h > 0, h > 0 ? 1 / (h * h) : 0, h > 0 ? S->def.mass_damping / h : 0,
                                     S->load_factor, S->x_base, S->q_base, S->d, S->inertia_target};
  return fascia_newton_minimize(S, &values, S->def.newton_iterations, report);
}

fascia_status fascia_solver_solve_static(fascia_solver *S, fascia_solve_report *report) {
  FASCIA_CHECK(S, NULL, FASCIA_ERR_ARGUMENT, "NULL solver");
  fascia_solve_report local;
  if (!report) report = &local;
  memset(report, 0, sizeof *report);
  const int32_t N = S->frame_count;
  S->sys->threads = fascia_threads_free(S->sys->threads_max, S->sys->pair_count);
  fascia_status status = FASCIA_OK;
  const int steps = S->def.load_steps;
  int mechanism = 0; // the tangent where the solve started was not positive definite
  // the prescribed motion comes in the same increments as the loads, along
  // its own path from where its frames were placed: moved at once, a large
  // motion inverts the tissue beside it before Newton starts
  const fascia_real from = S->placed_time, to = S->time;
  for (int l = 1; l <= steps && status == FASCIA_OK; ++l) {
    S->load_factor = (fascia_real)l / steps;
    place_prescribed(S, l == steps ? to : from + (to - from) * (fascia_real)l / steps);
    memcpy(S->x_base, S->x, 3 * (size_t)N * sizeof(fascia_real));
    memcpy(S->q_base, S->q, 4 * (size_t)N * sizeof(fascia_real));
    memset(S->d, 0, 6 * (size_t)N * sizeof(fascia_real));
    char detail[96];
    snprintf(detail, sizeof detail, "load step %d of %d", l, steps);
    fascia_ctx_progress(S->ctx, "static solve", (double)(l - 1) / steps, detail);
    status = minimize(S, 0, report);
    if (status == FASCIA_ERR_NUMERIC && nonfinite_held(S)) {
      char cause[1024];
      snprintf(cause, sizeof cause, "%s", fascia_ctx_message(S->ctx));
      status = FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC, "static solve, load step %d of %d: %s; sample %d: %s", l,
                           steps, cause, (int)S->first_nonfinite, HELD_CAUSE);
    }
    if (l == 1) mechanism = S->start_indefinite;
    // the blow-up rule of a dynamic step, on each converged load step (an
    // unconverged one is judged below); no energy rule: nothing to compare with
    if (status == FASCIA_OK && report->converged && check_blow_up(S, report, 0, 0) != FASCIA_OK) {
      char cause[1024];
      snprintf(cause, sizeof cause, "%s", fascia_ctx_message(S->ctx));
      status = FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                           "static solve, load step %d of %d: %s; the load or the prescribed motion is more than "
                           "the tissue can take (or raise the blow-up strain limit; 0 turns that rule off)",
                           l, steps, cause);
    }
  }
  S->load_factor = 1;
  S->energy_known = 0;
  memset(S->u, 0, 6 * (size_t)N * sizeof(fascia_real));
  if (status != FASCIA_OK) return status;
  fascia_ctx_progress(S->ctx, "static solve", 1.0, report->converged ? "converged" : "not converged");
  // an unconverged solve whose starting tangent was singular or indefinite:
  // a deformation that costs no energy, which no iteration limit or load
  // step cures, or a load that makes the start unstable (the loads' own
  // second derivative through the frames' rotations: the 20x3x3 beam at
  // 10^5 times its weight)
  if (!report->converged && mechanism)
    return FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                       "static solve: %s after %d Newton iterations (|gradient| %.3g, load %.3g), and its tangent at "
                       "the start was not positive definite: either the model has a deformation that costs no energy "
                       "(a mechanism: too few samples per cell or per frame, or frame rotations nothing holds), which "
                       "neither more iterations nor load steps cure, or the load is large enough to make the start "
                       "unstable (use more load steps)",
                       report->gradient_norm <= report->reference_norm ? "not converged" : "diverged",
                       report->newton_iterations, report->gradient_norm, report->reference_norm);
  if (!report->converged && !(report->gradient_norm <= report->reference_norm))
    return FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                       "static solve: diverged: after %d Newton iterations the residual %.3g is above the load %.3g; "
                       "a piece of tissue may be held by nothing, or the load is too large for one step (use more "
                       "load steps)", report->newton_iterations, report->gradient_norm, report->reference_norm);
  if (!report->converged)
    return FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                       "static solve: not converged after %d Newton iterations (|gradient| %.3g, load %.3g, "
                       "tolerance %.3g relative); raise the iteration limit or use more load steps",
                       report->newton_iterations, report->gradient_norm, report->reference_norm,
                       S->def.newton_tolerance);
  return FASCIA_OK;
}

// The rule for a step that has blown up (docs/mechanics.md, "When a run has
// diverged"), applied to every dynamic step the Newton solve returns from,
// and (1 to 3) to every converged load step of a static solve:
//  1. a number in the state is not finite;
//  2. the solve ended unconverged with a residual above the load it started
//     from: it made the step worse, so the state is no approximation at all;
//  3. some sample's strain passed def.blow_up_strain;
//  4. where nothing outside does work (no prescribed frame, no driven
//     organ), the total energy E_kin + E_pot rose by more than ENERGY_RISE
//     of its scale in one step: implicit Euler dissipates, a converged step
//     never gains energy, and an inexact one gains a little, far below
//     this bound even in the crudest solves of the stability suite (t315).
// Returns FASCIA_ERR_NUMERIC with the cause, so the step is split or refused
// like one the Newton solve could not take.
#define ENERGY_RISE 0.1

// E_kin + E_pot at the current state: the potential of the Newton solve's
// last evaluation, at the accepted state, which every backend's finish
// hands back (nothing is evaluated twice).
static fascia_real total_energy(fascia_solver *S) {
  const fascia_real potential =
      S->energy_internal + S->energy_external + fascia_organs_potential_energy(S->organs, S->x, S->q, S->sys->gravity);
  return potential + fascia_solver_kinetic_energy(S);
}

static fascia_status check_blow_up(fascia_solver *S, const fascia_solve_report *r, int energy_before_known,
                                   fascia_real energy_before) {
  const int64_t N = S->frame_count;
  for (int64_t k = 0; k < 6 * N; ++k)
    if (!isfinite(S->d[k]) || (k < 3 * N && !isfinite(S->x[k])) || (k < 4 * N && !isfinite(S->q[k])))
      return FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC, "the state of frame %lld is not finite (overflow)",
                         (long long)(k / 6));
  if (!r->converged && !(r->gradient_norm <= r->reference_norm))
    return FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                       "the Newton solve diverged: after %d iterations the residual %.3g is above the load %.3g it "
                       "started from", r->newton_iterations, r->gradient_norm, r->reference_norm);
  int past = 0;
  const fascia_backend_ops *ops = S->backend->ops;
  if (S->def.blow_up_strain > 0 && ops->strain_past) {
    FASCIA_TRY(ops->strain_past(S->backend, S->def.blow_up_strain, &past));
  } else if (S->def.blow_up_strain > 0) {
    past = !(fascia_system_largest_strain(host_system(S), NULL) <= S->def.blow_up_strain);
  }
  if (past) { // where and how much, on the host: only on the way to the message
    int32_t s = -1;
    const fascia_real strain = fascia_system_largest_strain(host_system(S), &s);
    S->held_failure = sample_held(S, s);
    return FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                       "the solution blew up: sample %d reached a strain of %.3g, past the limit %.3g%s%s", (int)s,
                       strain, S->def.blow_up_strain, S->held_failure ? "; " : "", S->held_failure ? HELD_CAUSE : "");
  }
  if (energy_before_known) {
    // the backends count the loads' torques' work along the step, W, in the
    // external energy (they have no potential): after + W is the energy
    // now, and after - before the rise beyond the work done
    fascia_real work = 0;
    for (int32_t i = 0; i < S->frame_count; ++i)
      work += fascia_pt_dot3(S->model->frame_load + 6 * i + 3, S->d + 6 * i + 3);
    work *= S->load_factor;
    const fascia_real after = total_energy(S);
    const fascia_real scale = fabs(energy_before) + S->weight_scale + fabs(work);
    if (!(after - energy_before <= ENERGY_RISE * scale))
      return FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                         "the solution blew up: the energy rose from %.4g J to %.4g J in one step, %.4g J more than "
                         "the loads' work on the tissue", energy_before, after + work, after - energy_before);
    S->energy_last = after + work; // kept by the caller only if the step is accepted
  }
  return FASCIA_OK;
}

// One implicit Euler step of length h from the current state (prescribed
// frames at time + h). Returns FASCIA_ERR_NUMERIC with the state restored
// when the Newton solve fails, or ends unconverged under
// require_convergence (then with a message saying so).
static fascia_status step_once(fascia_solver *S, fascia_real h, fascia_solve_report *report) {
  memset(report, 0, sizeof *report);
  S->held_failure = 0;
  const int32_t N = S->frame_count;
  const int64_t n = 6 * (int64_t)N;
  const fascia_real t1 = S->time + h;
  fascia_real *backup = NULL;
  FASCIA_TRY(save_state(S, &backup));
  // the energy rule needs E at the start: the last accepted step's, or now
  const int energy_rule = S->closed && !fascia_organs_any_driven(S->organs);
  if (energy_rule && !S->energy_known) {
    fascia_status st = fascia_solver_potential_energy(S, &S->energy_last);
    if (st != FASCIA_OK) {
      free(backup);
      return st;
    }
    S->energy_last += fascia_solver_kinetic_energy(S);
    S->energy_known = 1;
  }
  const fascia_real energy_before = S->energy_last;
  // anchor at q_n, mass at q_n
  memcpy(S->x_base, S->x, 3 * (size_t)N * sizeof(fascia_real));
  memcpy(S->q_base, S->q, 4 * (size_t)N * sizeof(fascia_real));
  // initial increments: the explicit prediction h u for free frames, the
  // motion for prescribed ones, nothing for fixed ones
  const fascia_model *m = S->model;
  for (int32_t i = 0; i < N; ++i) {
    fascia_real *d = S->d + 6 * i, *target = S->inertia_target + 6 * i;
    for (int c = 0; c < 6; ++c) target[c] = d[c] = m->frame_kind[i] == FASCIA_FRAME_FREE ? h * S->u[6 * i + c] : 0;
    if (m->frame_kind[i] == FASCIA_FRAME_PRESCRIBED) {
      fascia_real x1[3], q1[4], qc[4], rel[4];
      fascia_motion_frame(m, i, t1, x1, q1);
      for (int c = 0; c < 3; ++c) d[c] = x1[c] - S->x_base[3 * i + c];
      const fascia_real *qb = S->q_base + 4 * i;
      qc[0] = qb[0], qc[1] = -qb[1], qc[2] = -qb[2], qc[3] = -qb[3];
      fascia_pt_quat_mul(q1, qc, rel);
      fascia_pt_quat_log(rel, d + 3);
    }
  }
  const fascia_organs_state organs_state = {S->x, S->q, S->u, S->d, S->x_base, S->q_base};
  fascia_organs_step_begin(S->organs, &organs_state, h); // rigid bodies, frames driven by the caller
  fascia_status status = minimize(S, h, report);
  if (status == FASCIA_OK && S->def.require_convergence && !report->converged)
    status = FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                         "Newton solve not converged after %d iterations (|gradient| %.3g, tolerance %.3g)",
                         report->newton_iterations, report->gradient_norm,
                         S->def.newton_tolerance * report->reference_norm);
  if (status == FASCIA_OK) { // the new velocities, then the blow-up rule on the new state
    for (int64_t k = 0; k < n; ++k) S->u[k] = S->d[k] / h;
    fascia_organs_step_end(S->organs, &organs_state, S->sys->gravity, h);
    status = check_blow_up(S, report, energy_rule, energy_before);
  }
  if (status != FASCIA_OK) {
    S->energy_last = energy_before;
    restore_state(S, backup);
    free(backup);
    return status;
  }
  free(backup);
  S->time = S->placed_time = t1;
  report->substeps = 1;
  return FASCIA_OK;
}

// Adds the work of one (sub)step to the step's report: the counts and the
// times add up; the end-of-step values (convergence, the linear solver,
// gradient, energy, inversions) are the last one's.
static void merge_report(fascia_solve_report *sum, const fascia_solve_report *r) {
  fascia_solve_report last = *r;
  last.newton_iterations += sum->newton_iterations;
  last.cg_iterations += sum->cg_iterations;
  last.line_search_cuts += sum->line_search_cuts;
  last.watchdog_returns += sum->watchdog_returns;
  last.factorizations += sum->factorizations;
  last.negative_curvature += sum->negative_curvature;
  last.substeps += sum->substeps;
  last.rejected += sum->rejected; // a substep rejects none: step_split counts them
  fascia_profile_add(&last.profile, &sum->profile);
  *sum = last;
}

// A step of length h, rejected and redone as two steps of h/2 when it
// fails, at most step_retries - depth halvings deeper. On failure the state
// may be partway (the caller restores it); *smallest gets the shortest step
// tried.
static fascia_status step_split(fascia_solver *S, fascia_real h, int depth, fascia_solve_report *report,
                                fascia_real *smallest) {
  fascia_solve_report r;
  if (h < *smallest) *smallest = h;
  fascia_status status = step_once(S, h, &r);
  merge_report(report, &r);
  if (status != FASCIA_ERR_NUMERIC || depth >= S->def.step_retries) return status;
  ++report->rejected;
  status = step_split(S, h / 2, depth + 1, report, smallest);
  if (status == FASCIA_OK) status = step_split(S, h / 2, depth + 1, report, smallest);
  return status;
}

// Where a failed attempt went wrong, for the message: the free frames with
// the largest residual force and torque, and the lowest inverted sample if
// any (the state of the last attempt, before it is restored).
static void describe_failure(fascia_solver *S, char *text, size_t size) {
  int32_t worst[2] = {-1, -1}; // force, torque
  fascia_real worst_norm[2] = {-1, -1};
  for (int32_t i = 0; i < S->frame_count; ++i)
    for (int part = 0; part < 2; ++part) {
      if (!S->mask[6 * (int64_t)i + 3 * part]) continue;
      const fascia_real *g = S->gradient + 6 * (int64_t)i + 3 * part;
      const fascia_real norm = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
      if (norm > worst_norm[part] || (worst[part] < 0 && !isfinite(norm))) worst[part] = i, worst_norm[part] = norm;
    }
  int n = 0;
  for (int part = 0; part < 2; ++part) {
    const int32_t w = worst[part];
    if (w < 0 || n < 0 || (size_t)n >= size) continue;
    n += snprintf(text + n, size - (size_t)n, "; largest residual %s %.3g %s at frame %d (rest position %.4g %.4g %.4g m)",
                  part ? "torque" : "force", worst_norm[part], part ? "N m" : "N", (int)w, S->model->frame_position[3 * w],
                  S->model->frame_position[3 * w + 1], S->model->frame_position[3 * w + 2]);
  }
  if (n >= 0 && (size_t)n < size && !S->held_failure && nonfinite_held(S)) {
    n += snprintf(text + n, size - (size_t)n, "; sample %d, whose energy is not finite: %s", (int)S->first_nonfinite,
                  HELD_CAUSE);
    S->held_failure = 1;
  }
  if (n < 0 || (size_t)n >= size || S->inverted_count <= 0) return;
  // the cause named is one the first inverted sample's own law has
  const int32_t first = S->first_inverted;
  if (sample_held(S, first)) {
    snprintf(text + n, size - (size_t)n, "; %d inverted samples, the first sample %d (%s)", (int)S->inverted_count,
             (int)first, S->held_failure ? "its frames too are all fixed, prescribed or in rigid organs" : HELD_CAUSE);
    S->held_failure = 1;
  } else if (first >= 0 && S->sys->sample_law[first] == FASCIA_LAW_STVK)
    snprintf(text + n, size - (size_t)n, "; %d inverted samples, the first sample %d (StVK; likely cause: the "
             "material is crushed; StVK loses stiffness in compression, the stable Neo-Hookean does not)",
             (int)S->inverted_count, (int)first);
  else
    snprintf(text + n, size - (size_t)n, "; %d inverted samples, the first sample %d (Neo-Hookean; likely cause: "
             "the step moves the tissue farther than its Newton iterations follow, so the last iterate crushes it)",
             (int)S->inverted_count, (int)first);
}

fascia_status fascia_solver_step(fascia_solver *S, fascia_solve_report *report) {
  FASCIA_CHECK(S, NULL, FASCIA_ERR_ARGUMENT, "NULL solver");
  fascia_solve_report local;
  if (!report) report = &local;
  memset(report, 0, sizeof *report);
  S->sys->threads = fascia_threads_free(S->sys->threads_max, S->sys->pair_count); // fewer on busy cores if passes are short
  const fascia_real t0 = S->time, h = S->def.time_step;
  // a step whose end overflows, or that a double cannot tell from its start,
  // would evaluate the motions and loads at a time that is not the step's
  const int overflows = !isfinite(t0 + h);
  FASCIA_CHECK(!overflows && t0 + h > t0, S->ctx, FASCIA_ERR_ARGUMENT,
               "solver: a step of %.6g s from t = %.6g s ends at %.6g s: the time %s; use a %s time step", h, t0,
               t0 + h, overflows ? "overflows" : "does not advance in double precision",
               overflows ? "shorter" : "longer");
  fascia_real *backup = NULL;
  FASCIA_TRY(save_state(S, &backup));
  fascia_real smallest = h;
  fascia_status status = step_split(S, h, 0, report, &smallest);
  if (status == FASCIA_OK) {
    S->time = t0 + h; // the sum of the sub-steps, without their rounding
    char detail[96];
    snprintf(detail, sizeof detail, "t = %.6g s, %d Newton iterations%s", S->time, report->newton_iterations,
             report->substeps > 1 ? " (split)" : "");
    fascia_ctx_progress(S->ctx, "step", -1, detail);
  } else {
    char where[768] = "";
    if (status == FASCIA_ERR_NUMERIC) describe_failure(S, where, sizeof where);
    restore_state(S, backup);
    S->time = t0;
    if (status == FASCIA_ERR_NUMERIC) {
      char cause[1024];
      snprintf(cause, sizeof cause, "%s", fascia_ctx_message(S->ctx));
      status = FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                           "solver: the step from t = %.6g s failed%s (shortest step tried %.3g s, %d rejected): %s%s; "
                           "the state is the one before the step%s",
                           t0, S->def.step_retries > 0 ? " even split" : "", smallest, report->rejected, cause, where,
                           S->held_failure ? "" : "; use a shorter time step, more Newton iterations or step retries");
    }
  }
  free(backup);
  return status;
}

fascia_real fascia_solver_time(const fascia_solver *S) { return S->time; }

fascia_status fascia_solver_set_time(fascia_solver *S, fascia_real time) {
  FASCIA_CHECK(S, NULL, FASCIA_ERR_ARGUMENT, "NULL solver");
  FASCIA_CHECK(isfinite(time) && time >= 0, S->ctx, FASCIA_ERR_ARGUMENT,
               "fascia_solver_set_time: time %g s is not a finite number >= 0", time);
  S->time = time;
  ++S->linear_epoch;
  return FASCIA_OK;
}
fascia_real fascia_solver_time_step(const fascia_solver *S) { return S->def.time_step; }

fascia_status fascia_solver_set_time_step(fascia_solver *S, fascia_real time_step) {
  FASCIA_CHECK(S, NULL, FASCIA_ERR_ARGUMENT, "NULL solver");
  FASCIA_TRY(check_time_step(S->ctx, time_step));
  S->def.time_step = time_step;
  return FASCIA_OK;
}

int32_t fascia_solver_frame_count(const fascia_solver *S) { return S ? S->model->frame_count : 0; }
int32_t fascia_solver_sample_count(const fascia_solver *S) { return S ? S->model->sample_count : 0; }

const char *fascia_solver_backend(const fascia_solver *S) { return S->backend_name; }
const char *fascia_solver_device(const fascia_solver *S) { return S->device_text; }
const fascia_real *fascia_solver_frame_positions(const fascia_solver *S) { return S->x; }
const fascia_real *fascia_solver_frame_rotations(const fascia_solver *S) { return S->q; }
const fascia_real *fascia_solver_frame_velocities(const fascia_solver *S) { return S->u; }

void fascia_frame_axes(const fascia_real *rotations, int64_t count, fascia_real *axes) {
  for (int64_t i = 0; i < count; ++i) {
    fascia_real R[9];
    fascia_pt_quat_to_mat(rotations + 4 * i, R);
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) axes[9 * i + 3 * c + r] = R[3 * r + c];
  }
}

fascia_status fascia_solver_set_state(fascia_solver *S, const fascia_real *x, const fascia_real *q,
                                      const fascia_real *u) {
  FASCIA_CHECK(S && x && q, S ? S->ctx : NULL, FASCIA_ERR_ARGUMENT, "fascia_solver_set_state: NULL argument");
  const int64_t N = S->frame_count;
  for (int64_t k = 0; k < 3 * N; ++k)
    FASCIA_CHECK(isfinite(x[k]), S->ctx, FASCIA_ERR_ARGUMENT, "set state: frame %lld position is not finite",
                 (long long)(k / 3));
  for (int64_t k = 0; k < 4 * N; ++k)
    FASCIA_CHECK(isfinite(q[k]), S->ctx, FASCIA_ERR_ARGUMENT, "set state: frame %lld rotation is not finite",
                 (long long)(k / 4));
  for (int64_t k = 0; u && k < 6 * N; ++k)
    FASCIA_CHECK(isfinite(u[k]), S->ctx, FASCIA_ERR_ARGUMENT, "set state: frame %lld velocity is not finite",
                 (long long)(k / 6));
  memcpy(S->x, x, 3 * (size_t)N * sizeof(fascia_real));
  memcpy(S->q, q, 4 * (size_t)N * sizeof(fascia_real));
  for (int64_t i = 0; i < N; ++i) {
    fascia_real *qi = S->q + 4 * i;
    const fascia_real norm = sqrt(qi[0] * qi[0] + qi[1] * qi[1] + qi[2] * qi[2] + qi[3] * qi[3]);
    FASCIA_CHECK(norm > 1e-12, S->ctx, FASCIA_ERR_ARGUMENT, "set state: frame %lld rotation is zero",
                 (long long)i);
    for (int c = 0; c < 4; ++c) qi[c] /= norm;
  }
  if (u) memcpy(S->u, u, 6 * (size_t)N * sizeof(fascia_real));
  else memset(S->u, 0, 6 * (size_t)N * sizeof(fascia_real));
  const fascia_organs_state organs_state = {S->x, S->q, S->u, S->d, S->x_base, S->q_base};
  fascia_organs_sync(S->organs, &organs_state);
  S->energy_known = 0;
  ++S->linear_epoch;
  return FASCIA_OK;
}

void fascia_solver_take_result(fascia_solver *S, const fascia_step_result *r) {
  const size_t N = (size_t)S->frame_count;
  memcpy(S->x, r->x, 3 * N * sizeof(fascia_real));
  memcpy(S->q, r->q, 4 * N * sizeof(fascia_real));
  memcpy(S->d, r->d, 6 * N * sizeof(fascia_real));
  memcpy(S->gradient, r->gradient, 6 * N * sizeof(fascia_real));
  S->energy_internal = r->energy_internal;
  S->energy_external = r->energy_external;
  S->inverted_count = r->inverted_count;
  S->first_inverted = r->first_inverted;
  S->nonfinite_count = r->nonfinite_count;
  S->first_nonfinite = r->nonfinite_count > 0 ? r->first_nonfinite : -1;
}

void fascia_solver_resume(fascia_solver *S, const fascia_real *x, const fascia_real *q, const fascia_real *u,
                          fascia_real time, const fascia_real *organs_state) {
  const size_t N = (size_t)S->frame_count;
  memcpy(S->x, x, 3 * N * sizeof(fascia_real));
  memcpy(S->q, q, 4 * N * sizeof(fascia_real));
  memcpy(S->u, u, 6 * N * sizeof(fascia_real));
  S->time = S->placed_time = time;
  if (organs_state) fascia_organs_restore(S->organs, organs_state);
  ++S->linear_epoch;
}

// A probe moves as a sample does, with its own frames' positions and
// rotations: read from the state, nothing evaluated.
void fascia_solver_probe_position(const fascia_solver *S, int32_t probe, fascia_real *out) {
  const fascia_model *m = S->model;
  out[0] = out[1] = out[2] = 0;
  for (int32_t k = m->probe_offsets[probe]; k < m->probe_offsets[probe + 1]; ++k) {
    const int32_t i = m->probe_frame[k];
    fascia_real A[9], d[3], a[3];
    fascia_pt_frame_A(S->q + 4 * (int64_t)i, m->frame_rotation + 4 * (int64_t)i, A);
    for (int c = 0; c < 3; ++c) d[c] = m->probe_position[3 * probe + c] - m->frame_position[3 * i + c];
    fascia_pt_mat_vec(A, d, a);
    for (int c = 0; c < 3; ++c) out[c] += m->probe_weight[k] * (S->x[3 * i + c] + a[c]);
  }
}

// Whether the backend answered an output query where it keeps the state
// (a device); else the host answers it.
static int backend_outputs(const fascia_solver *S, fascia_real *positions, fascia_real *strain, fascia_real *stress) {
  const fascia_backend_ops *ops = S->backend->ops;
  return ops->sample_outputs && ops->sample_outputs(S->backend, S->x, S->q, positions, strain, stress) == FASCIA_OK;
}

void fascia_solver_sample_positions(const fascia_solver *S, fascia_real *out) {
  if (!backend_outputs(S, out, NULL, NULL)) fascia_system_sample_positions(host_system(S), out);
}

void fascia_solver_sample_strain(const fascia_solver *S, fascia_real *strain, fascia_real *stress) {
  if (!backend_outputs(S, NULL, strain, stress)) fascia_system_sample_strain(host_system(S), strain, stress);
}

fascia_real fascia_solver_kinetic_energy(fascia_solver *S) {
  const int64_t n = 6 * (int64_t)S->frame_count;
  fascia_system_mass_snapshot(host_system(S));
  if (S->def.mass == FASCIA_MASS_LUMPED) {
    fascia_system_mass_lumped(S->sys, S->kinetic_blocks);
    fascia_real e = 0;
    for (int32_t i = 0; i < S->frame_count; ++i)
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c)
          e += S->u[6 * i + r] * S->kinetic_blocks[36 * (int64_t)i + 6 * r + c] * S->u[6 * i + c];
    return FASCIA_R(0.5) * e + fascia_organs_kinetic_energy(S->organs, S->q);
  }
  fascia_system_mass_apply(S->sys, S->u, S->scratch);
  return FASCIA_R(0.5) * fascia_dot(S->u, S->scratch, n, S->sys->threads) + fascia_organs_kinetic_energy(S->organs, S->q);
}

fascia_status fascia_solver_potential_energy(fascia_solver *S, fascia_real *energy) {
  FASCIA_TRY(fascia_system_evaluate(host_system(S), NULL, energy));
  *energy += fascia_organs_potential_energy(S->organs, S->x, S->q, S->sys->gravity);
  return FASCIA_OK;
}
