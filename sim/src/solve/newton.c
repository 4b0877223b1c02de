// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Newton minimization of a step's objective over the free DOFs, the solver's
// one nonlinear loop (implicit backward Euler with Newton
// iterations, docs/mechanics.md; the static solve is the same loop without inertia).
//
//   static:  Phi(d) = E(q (+) d), re-anchored at every accepted iterate, so
//            the Hessian used is exact.
//   dynamic: Phi(d) = c1/2 |d - h u|_M^2 + c2/2 |d|_M^2 + E(q_n (+) d),
//            c1 = 1/h^2, c2 = alpha/h (Rayleigh mass damping): its minimizer
//            is the backward Euler step; d is anchored at q_n and the
//            gradient carries the exact left Jacobian of the rotation map.
//
// The loop runs on any backend (backend.h): the backend evaluates, solves
// for directions and keeps the vectors; the loop decides with scalars.
//
// Globalization: each direction comes from projected PCG that stops at
// negative curvature (or a direct solve of the shifted tangent); a backtracking (Armijo) line search on Phi accepts it,
// and when even tiny steps fail, a Levenberg shift of the tangent grows
// (damped Newton). This is what lets the solver cross the singular or
// indefinite tangents of the frame scheme (zero-energy rotation modes,
// buckling, compressed StVK).
//
// Watchdog (Chamberlain, Powell, Lemarechal and Pedersen 1982), where the
// backend can save and restore an iterate: from a watched iterate the loop
// takes full Newton steps without a line search; the first may raise Phi,
// each following one must lower it, and once Phi is below the watched value
// by the Armijo amount of the first step, the iterate there is watched next.
// If a full step raises Phi again, or FASCIA_NEWTON_WATCHDOG of them do not
// get there, or one is not finite, the loop goes back to the watched
// iterate, takes the line-searched step from there and keeps to the
// monotone search for the rest of the solve. Full steps through a rise of Phi are what
// Newton needs on large rotations of nearly incompressible material (each
// linearization stretches the material to second order, and lambda makes
// that costly: the monotone search takes about a quarter step each time);
// going back keeps the descent guarantee of the monotone search.
#define _POSIX_C_SOURCE 200809L // clock_gettime (strict C11 hides it; gcc's OpenMP header happened to define it)
#include <string.h>
#include <time.h>

#include "solve/backend.h"
#include "cpu/dilatation.h"
#include "organs/organs.h"
#include "solve/solver_internal.h"

double fascia_now_ms(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

// Size of the rounding error of an energy evaluation, J: an absolute error of
// a few ulps of sum_s v_s (lambda_s + 2 mu_s) + sum_p V_p lambda_p (the
// volumetric patches') whatever the energy's value
// (StVK's E = (F^T F - I)/2 loses the digits of F^T F near rest; the
// Neo-Hookean law is written free of such cancellation, material.h). 8 ulps
// is the margin. Without this term a stiff StVK model (E = 1e8 Pa, t311)
// cannot see its energy decrease near the minimum and a step fails to
// converge in its line search.
// (Its quotient by the model's size is the round-off of the forces: a
// residual below it is converged whatever the tolerance asks, as when
// nothing loads the tissue and the reference itself is round-off.)
// The patches' energy V_p lambda_p thetabar_p^2 / 2 counts with its own
// lambda_p (the samples keep only their share): at nu = 0.49 most of the
// stiffness, and of the forces' round-off, is there (tests/t357).
static fascia_real energy_roundoff(const fascia_solver *S) {
  fascia_real sum = 0;
  for (int32_t s = 0; s < S->model->sample_count; ++s) sum += fascia_pt_sample_energy_scale(&S->sys->pm, s);
  const fascia_dilatation *d = S->sys->dilatation;
  for (int32_t p = 0; d && p < d->table.patch_count; ++p) sum += d->patch_volume[p] * fabs(d->patch_lambda[p]);
  return fascia_pt_energy_roundoff(sum);
}

// The line search's verdict on a trial step alpha along a direction of
// slope p.g: sufficient (Armijo) decrease of Phi, or, near the minimum, a
// lower |gradient|^2 (gg_trial against gg, both as summed: against the
// square of a rounded square root, a step too small to move anything passed)
// without a rise beyond the round-off of the energy (energy_size:
// |internal| + |external| energy).
static int accepts(const fascia_solver_def *def, fascia_real phi, fascia_real phi_trial, fascia_real alpha,
                   fascia_real slope, fascia_real gg, fascia_real gg_trial, fascia_real energy_size,
                   fascia_real material_roundoff) {
  if (!def->line_search || phi_trial <= phi + FASCIA_NEWTON_ARMIJO * alpha * slope) return 1;
  // near the minimum the energy decrease drowns in round-off: there a step
  // that lowers the gradient is accepted instead
  const fascia_real roundoff = 1e-13 * (fabs(phi) + energy_size) + material_roundoff;
  return phi_trial <= phi + roundoff && gg_trial < gg;
}

// The failure of a Newton iteration that no damping could make descend
static fascia_status no_decrease(const fascia_solver *S, int iteration, fascia_real gnorm, fascia_real tolerance) {
  return FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                     "solver: Newton iteration %d found no decrease of the energy (|gradient| %.3g, tolerance %.3g); "
                     "the model may be unstable or the step too large",
                     iteration, gnorm, tolerance);
}

// |external load| over free DOFs at load factor gs: the scale of the Newton tolerance
static fascia_real load_norm(const fascia_solver *S, fascia_real gs) {
  const fascia_system *sys = S->sys;
  fascia_real sum = 0;
  for (int32_t i = 0; i < S->frame_count; ++i)
    for (int c = 0; c < 3; ++c) {
      const fascia_real f = gs * (sys->frame_mass[i] * sys->gravity[c] + S->model->frame_load[6 * i + c]);
      if (S->mask[6 * i + c]) sum += f * f;
      const fascia_real t = gs * S->model->frame_load[6 * i + 3 + c];
      if (S->mask[6 * i + 3 + c]) sum += t * t;
    }
  return sqrt(sum + fascia_organs_load_norm2(S->organs, S->sys, gs));
}

// Beyond this magnitude an energy or a residual norm is taken for an
// overflow: its square (in the norms and the line search) would not be
// finite, and comparisons against the tolerance would pass vacuously.
#define NEWTON_OVERFLOW 1e150

// FASCIA_ERR_NUMERIC when the starting energy, residual or load of a solve
// is not finite or past NEWTON_OVERFLOW
static fascia_status check_range(fascia_solver *S, fascia_real phi, fascia_real g0, fascia_real reference) {
  if (fabs(phi) < NEWTON_OVERFLOW && g0 < NEWTON_OVERFLOW && reference < NEWTON_OVERFLOW) return FASCIA_OK;
  return FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                     "solver: the energy (%.3g J), forces (%.3g) or loads (%.3g) overflow the arithmetic: a modulus, "
                     "density, load, gravity or prescribed motion is out of any physical range; check the values and "
                     "their units (SI)",
                     phi, g0, reference);
}

// A solve whose start failed to evaluate: the backend's state there still
// goes to the solver, whose failure message reads it (which sample is not
// finite or inverted)
static fascia_status failed_start(fascia_solver *S, fascia_status status) {
  fascia_step_result result;
  if (status == FASCIA_ERR_NUMERIC && S->backend->ops->finish(S->backend, &result) == FASCIA_OK)
    fascia_solver_take_result(S, &result);
  return status;
}

fascia_status fascia_newton_minimize(fascia_solver *S, const fascia_step_values *values, int max_iterations,
                                    fascia_solve_report *rep) {
  fascia_backend *be = S->backend;
  const fascia_backend_ops *ops = be->ops;
  const fascia_solver_def *def = &S->def;
  const double t0 = fascia_now_ms();
  double t = t0;
  FASCIA_TRY(ops->begin(be, values, rep));
  fascia_trial_values now, trial;
  fascia_status status = ops->evaluate(be, 0, 1, &now);
  if (status != FASCIA_OK) return failed_start(S, status);
  rep->profile.evaluate_ms += fascia_now_ms() - t;
  const fascia_real g0 = sqrt(now.gradient_norm2);
  const fascia_real load = load_norm(S, values->gravity_scale);
  fascia_real reference = load;
  if (values->dynamic || reference == 0) reference = reference > g0 ? reference : g0;
  if (reference == 0) reference = 1;
  rep->reference_norm = reference;
  FASCIA_TRY(check_range(S, now.phi, g0, reference));
  const fascia_real material_roundoff = energy_roundoff(S);
  const fascia_real force_roundoff = material_roundoff / S->model_size; // a residual no iteration can lower
  int iteration = 0, converged = 0;
  fascia_real gnorm = g0, shift = 0; // the Levenberg shift carries over from a line-searched iteration to the next
  // watchdog: full steps taken since the watched iterate (Phi watch_phi,
  // the slope of its first step watch_slope); -1: none allowed this iteration
  const int watchdog = def->line_search && ops->save && ops->restore;
  int relaxed = 0;
  fascia_real watch_phi = now.phi, watch_slope = 0, watch_gg = now.gradient_norm2, watch_shift = 0;
  fascia_real last_phi = now.phi; // Phi of the previous iterate
  // whether a static solve's first tangent was positive definite (the
  // solver's failure message names a mechanism where it was not)
  int first_direction = !values->dynamic;
  if (first_direction) S->start_indefinite = 0;
  // the round-off estimate is rough (within a few times, either way): a
  // |gradient| that has stopped halving near it has reached the floor
  fascia_real best = g0;
  int stalled = 0;
  for (; iteration <= max_iterations; ++iteration) {
    gnorm = sqrt(now.gradient_norm2);
    if (gnorm < FASCIA_R(0.5) * best) {
      best = gnorm;
      stalled = 0;
    } else if (iteration > 0) {
      ++stalled;
    }
    // the start is converged only against the load itself (a reference
    // taken from its own residual would pass it vacuously) or the floor
    const int small = gnorm <= def->newton_tolerance * (iteration == 0 ? load : reference) ||
                      gnorm <= force_roundoff ||
                      (stalled >= FASCIA_NEWTON_STALL && gnorm <= FASCIA_NEWTON_STALL_FLOOR * force_roundoff);
    if (relaxed > 0 && accepts(def, watch_phi, now.phi, 1, watch_slope, watch_gg, now.gradient_norm2, now.energy_size,
                               material_roundoff))
      relaxed = 0; // Phi came down enough: watch this iterate
    if (small && relaxed <= 0) {
      converged = 1;
      break;
    }
    // after the first full step, the following ones must each lower Phi
    const int rising = relaxed >= 2 && !(now.phi < last_phi);
    if (relaxed > 0 &&
        (rising || relaxed >= FASCIA_NEWTON_WATCHDOG || small || max_iterations - iteration <= FASCIA_NEWTON_WATCHDOG)) {
      // the full steps did not bring Phi down enough (or ended at a
      // stationary point above it, or the iterations run out): back to the
      // watched iterate, and a line-searched step from there
      ops->restore(be);
      t = fascia_now_ms();
      FASCIA_TRY(ops->evaluate(be, 0, 1, &now));
      rep->profile.evaluate_ms += fascia_now_ms() - t;
      gnorm = sqrt(now.gradient_norm2);
      relaxed = -1; // and the monotone search for the rest of this solve: its full steps do not pay here
      shift = watch_shift; // the full steps' tangents may have raised it
      ++rep->watchdog_returns;
    }
    if (iteration == max_iterations) break;
    FASCIA_TRY(ops->prepare(be, rep));
    int accepted = 0;
    while (!accepted) {
      t = fascia_now_ms();
      fascia_real slope;
      const int curvature_before = rep->negative_curvature;
      FASCIA_TRY(ops->direction(be, &shift, &slope, rep));
      rep->profile.cg_ms += fascia_now_ms() - t;
      if (first_direction) S->start_indefinite = rep->negative_curvature > curvature_before;
      first_direction = 0;
      // full steps only with iterations left to come back (a capped solve ends line-searched)
      if (watchdog && relaxed >= 0 && slope < 0 && max_iterations - iteration > FASCIA_NEWTON_WATCHDOG) {
        if (relaxed == 0) { // a new watched iterate
          ops->save(be);
          watch_phi = now.phi;
          watch_slope = slope;
          watch_gg = now.gradient_norm2;
          watch_shift = shift;
        }
        t = fascia_now_ms();
        const fascia_status st = ops->evaluate(be, 1, 0, &trial);
        rep->profile.evaluate_ms += fascia_now_ms() - t;
        if (st != FASCIA_OK && st != FASCIA_ERR_NUMERIC) return st;
        if (st == FASCIA_OK && isfinite(trial.phi)) {
          ++relaxed;
          accepted = 1;
          // a full step starts the next tangent unshifted: the shift that made
          // an overshot iterate's tangent factor would slow the next iterations
          // while it decayed by tenths; a tangent that is still indefinite
          // fails its factorization once and the direct solver goes on from a
          // tenth of its last shift (cpu/linear_solver.c)
          shift = 0;
          break;
        }
        relaxed = FASCIA_NEWTON_WATCHDOG; // not finite: back at the next iteration
        t = fascia_now_ms();
        FASCIA_TRY(ops->evaluate(be, 0, 1, &now)); // the iterate's caches again
        rep->profile.evaluate_ms += fascia_now_ms() - t;
        break;
      }
      // backtracking line search on Phi; along a direction that does not
      // descend (where even the backend's fallback failed) there is none
      fascia_real alpha = 1;
      for (int cut = 0; slope < 0 && cut <= (def->line_search ? FASCIA_NEWTON_MAX_CUTS : 0); ++cut) {
        t = fascia_now_ms();
        const fascia_status st = ops->evaluate(be, alpha, 0, &trial);
        rep->profile.evaluate_ms += fascia_now_ms() - t;
        if (st == FASCIA_OK && accepts(def, now.phi, trial.phi, alpha, slope, now.gradient_norm2,
                                                     trial.gradient_norm2, trial.energy_size, material_roundoff)) {
          accepted = 1;
          break;
        }
        if (st != FASCIA_OK && st != FASCIA_ERR_NUMERIC) return st;
        ++rep->line_search_cuts;
        alpha *= FASCIA_R(0.5);
      }
      if (accepted) {
        if (alpha == 1 && shift > 0) shift = shift < FASCIA_R(1e-3) ? 0 : shift / 10;
        break;
      }
      // even tiny steps fail: damp the tangent (Levenberg) and try again
      // from the iterate (its evaluation restores the caches)
      shift = shift == 0 ? FASCIA_R(1e-4) : 10 * shift;
      t = fascia_now_ms();
      const fascia_status back = ops->evaluate(be, 0, 1, &now);
      rep->profile.evaluate_ms += fascia_now_ms() - t;
      if (shift > FASCIA_NEWTON_MAX_SHIFT) {
        status = no_decrease(S, iteration, gnorm, def->newton_tolerance * reference);
        break;
      }
      FASCIA_TRY(back);
      FASCIA_TRY(ops->prepare(be, rep));
    }
    if (relaxed >= FASCIA_NEWTON_WATCHDOG && !accepted) continue; // a full step failed: go back
    if (!accepted) break;
    ops->accept(be);
    last_phi = now.phi;
    now = trial;
  }
  t = fascia_now_ms();
  fascia_step_result result;
  const fascia_status down = ops->finish(be, &result);
  if (down == FASCIA_OK) fascia_solver_take_result(S, &result); // a failed solve's too: its message reads it
  rep->profile.evaluate_ms += fascia_now_ms() - t;
  rep->newton_iterations += iteration;
  rep->gradient_norm = gnorm;
  rep->energy = now.phi;
  if (status != FASCIA_OK) return status;
  FASCIA_TRY(down);
  rep->converged = converged;
  rep->inverted_samples = S->inverted_count;
  rep->profile.total_ms += fascia_now_ms() - t0;
  return FASCIA_OK;
}
