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
// Globalization: each direction comes from projected PCG that stops at
// negative curvature; a backtracking (Armijo) line search on Phi accepts it,
// and when even tiny steps fail, a Levenberg shift of the tangent grows
// (damped Newton). This is what lets the solver cross the singular or
// indefinite tangents of the frame scheme (zero-energy rotation modes,
// buckling, compressed StVK).
#define _POSIX_C_SOURCE 200809L // clock_gettime (strict C11 hides it; gcc's OpenMP header happened to define it)
#include <string.h>
#include <time.h>

#include "organs.h"
#include "solver_internal.h"

double fascia_now_ms(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

static void mass_apply(fascia_solver *S, const fascia_real *v, fascia_real *out) {
  if (S->def.mass == FASCIA_MASS_LUMPED) {
    for (int32_t i = 0; i < S->frame_count; ++i) {
      const fascia_real *B = S->mass_blocks + 36 * (int64_t)i, *vi = v + 6 * (int64_t)i;
      for (int r = 0; r < 6; ++r) {
        fascia_real s = 0;
        for (int c = 0; c < 6; ++c) s += B[6 * r + c] * vi[c];
        out[6 * (int64_t)i + r] = s;
      }
    }
  } else {
    fascia_system_mass_apply(S->sys, v, out);
  }
}

typedef struct step_terms {
  fascia_real c1, c2;      // inertia and damping coefficients
  fascia_real *target_M;   // M (h u) [6N]
  fascia_real target_norm; // (h u).M(h u)
  int jacobian;            // 1: gradient with respect to d (anchored); 0: local (static, re-anchored)
} step_terms;

// Phi and its projected gradient (may be NULL) at increments d.
static fascia_status objective(fascia_solver *S, const step_terms *terms, const fascia_real *d, fascia_real *phi,
                               fascia_real *gradient) {
  const int32_t N = S->frame_count;
  const int64_t n = 6 * (int64_t)N;
  for (int32_t i = 0; i < N; ++i) {
    for (int c = 0; c < 3; ++c) S->x[3 * i + c] = S->x_base[3 * i + c] + d[6 * i + c];
    memcpy(S->q + 4 * i, S->q_base + 4 * i, 4 * sizeof(fascia_real));
    fascia_pt_quat_rotate_by(d + 6 * i + 3, S->q + 4 * i);
  }
  fascia_system_set_state(S->sys, S->x, S->q);
  fascia_real energy;
  FASCIA_TRY(fascia_system_evaluate(S->sys, gradient, &energy));
  if (gradient && terms->jacobian)
    for (int32_t i = 0; i < N; ++i) {
      fascia_real g[3] = {gradient[6 * i + 3], gradient[6 * i + 4], gradient[6 * i + 5]};
      fascia_pt_left_jacobian_t(d + 6 * i + 3, g, gradient + 6 * i + 3);
    }
  if (terms->c1 != 0 || terms->c2 != 0) {
    // c1/2 (d - hu).M(d - hu) + c2/2 d.M d with M(hu) precomputed
    mass_apply(S, d, S->scratch);
    const int threads = S->sys->threads;
    const fascia_real dMd = fascia_dot(d, S->scratch, n, threads), dz = fascia_dot(d, terms->target_M, n, threads);
    energy += FASCIA_R(0.5) * terms->c1 * (dMd - 2 * dz + terms->target_norm) + FASCIA_R(0.5) * terms->c2 * dMd;
    if (gradient)
      for (int64_t k = 0; k < n; ++k)
        gradient[k] += (terms->c1 + terms->c2) * S->scratch[k] - terms->c1 * terms->target_M[k];
  }
  // rigid organs: the bodies' own terms, gradient restricted to their masters
  energy += fascia_organs_reduce(S->organs, S, terms->c1, terms->c2, terms->jacobian, d, gradient);
  if (gradient)
    for (int64_t k = 0; k < n; ++k)
      if (!S->mask[k]) gradient[k] = 0;
  *phi = energy;
  return isfinite(energy) ? FASCIA_OK
                          : FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC, "solver: the energy is not finite");
}

// K = H (+ (c1 + c2) M for a dynamic step) at the current iterate, and its
// float copy when the products use one
static fascia_status assemble(fascia_solver *S, const step_terms *terms) {
  fascia_system_hessian_assemble(S->sys, &S->K);
  const fascia_real c = terms->c1 + terms->c2;
  if (c != 0 && S->def.mass == FASCIA_MASS_CONSISTENT) {
    fascia_system_mass_assemble_add(S->sys, c, &S->K);
  } else if (c != 0) {
    for (int32_t i = 0; i < S->frame_count; ++i) {
      fascia_real *D = S->K.values + 36 * (int64_t)S->K.diagonal[i];
      for (int q = 0; q < 36; ++q) D[q] += c * S->mass_blocks[36 * (int64_t)i + q];
    }
  }
  if (S->def.single_precision_matrix && !S->use_direct) return fascia_bsr_make_single(S->ctx, &S->K, S->sys->threads);
  return FASCIA_OK;
}

// Size of the rounding error of an energy evaluation, J: an absolute error of
// a few ulps of sum_s v_s (lambda_s + 2 mu_s) whatever the energy's value
// (StVK's E = (F^T F - I)/2 loses the digits of F^T F near rest; the
// Neo-Hookean law is written free of such cancellation, material.h). 8 ulps
// is the margin. Without this term a stiff StVK model (E = 1e8 Pa, t311)
// cannot see its energy decrease near the minimum and a step fails to
// converge in its line search.
// (Its quotient by the model's size is the round-off of the forces: a
// residual below it is converged whatever the tolerance asks, as when
// nothing loads the tissue and the reference itself is round-off.)
fascia_real fascia_newton_energy_roundoff(const fascia_solver *S) {
  const fascia_system *sys = S->sys;
  fascia_real sum = 0;
  for (int32_t s = 0; s < S->model->sample_count; ++s)
    sum += S->model->sample_volume[s] * (fabs(sys->sample_lambda[s]) + 2 * fabs(sys->sample_mu[s]));
  return 8 * FASCIA_R(2.220446049250313e-16) * sum;
}

int fascia_newton_accepts(const fascia_solver_def *def, fascia_real phi, fascia_real phi_trial, fascia_real alpha,
                          fascia_real slope, fascia_real gnorm, fascia_real gg_trial, fascia_real energy_size,
                          fascia_real material_roundoff) {
  if (!def->line_search || phi_trial <= phi + FASCIA_NEWTON_ARMIJO * alpha * slope) return 1;
  // near the minimum the energy decrease drowns in round-off: there a step
  // that lowers the gradient is accepted instead
  const fascia_real roundoff = 1e-13 * (fabs(phi) + energy_size) + material_roundoff;
  return phi_trial <= phi + roundoff && gg_trial < gnorm * gnorm;
}

fascia_status fascia_newton_no_decrease(const fascia_solver *S, int iteration, fascia_real gnorm,
                                        fascia_real tolerance) {
  return FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                     "solver: Newton iteration %d found no decrease of the energy (|gradient| %.3g, tolerance %.3g); "
                     "the model may be unstable or the time step too large",
                     iteration, gnorm, tolerance);
}

// |external load| over free DOFs: the scale of the Newton tolerance
fascia_real fascia_newton_load_norm(const fascia_solver *S) {
  const fascia_system *sys = S->sys;
  fascia_real sum = 0;
  for (int32_t i = 0; i < S->frame_count; ++i)
    for (int c = 0; c < 3; ++c) {
      const fascia_real f = sys->gravity_scale * (sys->frame_mass[i] * sys->gravity[c] + S->model->frame_load[6 * i + c]);
      if (S->mask[6 * i + c]) sum += f * f;
      const fascia_real t = sys->gravity_scale * S->model->frame_load[6 * i + 3 + c];
      if (S->mask[6 * i + 3 + c]) sum += t * t;
    }
  return sqrt(sum + fascia_organs_load_norm2(S->organs, S));
}

// Beyond this magnitude an energy or a residual norm is taken for an
// overflow: its square (in the norms and the line search) would not be
// finite, and comparisons against the tolerance would pass vacuously.
#define NEWTON_OVERFLOW 1e150

fascia_status fascia_newton_check_range(fascia_solver *S, fascia_real phi, fascia_real g0, fascia_real reference) {
  if (fabs(phi) < NEWTON_OVERFLOW && g0 < NEWTON_OVERFLOW && reference < NEWTON_OVERFLOW) return FASCIA_OK;
  return FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                     "solver: the energy (%.3g J), forces (%.3g) or loads (%.3g) overflow the arithmetic: a modulus, "
                     "density, load or gravity is out of any physical range; check the values and their units (SI)",
                     phi, g0, reference);
}

fascia_status fascia_newton_minimize(fascia_solver *S, int dynamic, int max_iterations, fascia_solve_report *rep) {
  const int32_t N = S->frame_count;
  const int64_t n = 6 * (int64_t)N;
  const fascia_solver_def *def = &S->def;
  step_terms terms = {0, 0, S->work, 0, dynamic};
  double t0 = fascia_now_ms(), t;
  if (dynamic) {
    const fascia_real h = def->time_step;
    terms.c1 = 1 / (h * h);
    terms.c2 = def->mass_damping / h;
    terms.target_M = S->inertia_target + n; // second half of the buffer holds M(hu)
    mass_apply(S, S->inertia_target, terms.target_M);
    terms.target_norm = fascia_dot(S->inertia_target, terms.target_M, n, S->sys->threads);
  }
  fascia_operator op = {S->sys,  terms.c1 + terms.c2, def->mass, S->mass_blocks, S->damping_diagonal, 0, 1,
                        S->use_assembled ? &S->K : NULL, S->mask, S->scratch + n, NULL, 0};
  if (fascia_organs_body_count(S->organs) > 0) op.organs = S->organs;
  op.single = S->use_assembled && !S->use_direct && def->single_precision_matrix;
  rep->direct = S->use_direct;
  rep->assembled = S->use_assembled;
  fascia_real phi, *g = S->gradient, *p = S->direction, *g_trial = S->rhs;
  t = fascia_now_ms();
  FASCIA_TRY(objective(S, &terms, S->d, &phi, g));
  rep->profile.evaluate_ms += fascia_now_ms() - t;
  const fascia_real g0 = sqrt(fascia_dot(g, g, n, S->sys->threads));
  fascia_real reference = fascia_newton_load_norm(S);
  if (dynamic || reference == 0) reference = reference > g0 ? reference : g0;
  if (reference == 0) reference = 1;
  rep->reference_norm = reference;
  FASCIA_TRY(fascia_newton_check_range(S, phi, g0, reference));
  const fascia_real material_roundoff = fascia_newton_energy_roundoff(S);
  const fascia_real force_roundoff = material_roundoff / S->model_size; // a residual no iteration can lower
  int iteration = 0, converged = 0;
  fascia_real gnorm = g0;
  for (; iteration <= max_iterations; ++iteration) {
    gnorm = sqrt(fascia_dot(g, g, n, S->sys->threads));
    if (gnorm <= def->newton_tolerance * reference || gnorm <= force_roundoff) {
      converged = 1;
      break;
    }
    if (iteration == max_iterations) break;
    // the assembled matrix, the preconditioner and the Levenberg scale
    t = fascia_now_ms();
    if (S->use_assembled) {
      FASCIA_TRY(assemble(S, &terms));
      rep->profile.assemble_ms += fascia_now_ms() - t;
      t = fascia_now_ms();
    }
    if (!S->use_direct) fascia_precond_build(&S->pc, &op, S->blocks);
    if (op.organs) fascia_organs_precond(S->organs, &op, &S->pc, S->blocks);
    fascia_real scale = 0;
    for (int32_t i = 0; i < N; ++i)
      for (int c = 0; c < 6; ++c) {
        const fascia_real diag = S->use_direct ? fabs(S->K.values[36 * (int64_t)S->K.diagonal[i] + 7 * c])
                                               : fabs(S->blocks[36 * (int64_t)i + 7 * c]);
        S->damping_diagonal[6 * (int64_t)i + c] = diag;
        scale += diag;
      }
    op.scale = scale > 0 ? scale / (fascia_real)n : 1;
    for (int64_t k = 0; k < n; ++k)
      if (S->damping_diagonal[k] < 1e-8 * op.scale) S->damping_diagonal[k] = 1e-8 * op.scale;
    rep->profile.precond_ms += fascia_now_ms() - t;
    int accepted = 0;
    fascia_real phi_trial = phi;
    while (!accepted) {
      // direction: A p = -g
      t = fascia_now_ms();
      for (int64_t k = 0; k < n; ++k) g_trial[k] = -g[k];
      if (S->use_direct) {
        // not positive definite: raise the Levenberg shift until it is
        int factored;
        while ((factored = fascia_direct_factor(S->direct, S->ctx, &S->K, S->mask, S->damping_diagonal, op.shift)) ==
               0) {
          ++rep->negative_curvature;
          op.shift = op.shift == 0 ? FASCIA_R(1e-8) : 10 * op.shift;
          if (op.shift > FASCIA_NEWTON_MAX_SHIFT)
            return FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC,
                               "solver: Newton iteration %d: the tangent stays singular under any damping (a NaN, "
                               "or a frame with no sample?)",
                               iteration);
        }
        if (factored < 0) return FASCIA_ERR_MEMORY; // the new analysis failed; the message says why
        fascia_direct_solve(S->direct, g_trial, p);
      } else {
        const fascia_cg_result cg = fascia_cg_solve(&op, &S->pc, g_trial, p, def->cg_iterations, def->cg_fixed,
                                                    def->cg_tolerance, S->work + 2 * n);
        rep->cg_iterations += cg.iterations;
        rep->negative_curvature += cg.negative_curvature;
      }
      rep->profile.cg_ms += fascia_now_ms() - t;
      fascia_real slope = fascia_dot(p, g, n, S->sys->threads);
      if (!(slope < 0)) { // not a descent direction: preconditioned gradient
        fascia_precond_apply(&S->pc, S->mask, g, p);
        for (int64_t k = 0; k < n; ++k) p[k] = -p[k];
        slope = fascia_dot(p, g, n, S->sys->threads);
      }
      // backtracking line search on Phi
      fascia_real alpha = 1;
      for (int cut = 0; cut <= (def->line_search ? FASCIA_NEWTON_MAX_CUTS : 0); ++cut) {
        for (int64_t k = 0; k < n; ++k) S->d_trial[k] = S->d[k] + alpha * p[k];
        fascia_organs_expand(S->organs, S, S->d_trial); // slaves of rigid organs follow their master
        t = fascia_now_ms();
        fascia_status st = objective(S, &terms, S->d_trial, &phi_trial, g_trial);
        rep->profile.evaluate_ms += fascia_now_ms() - t;
        if (st == FASCIA_OK &&
            fascia_newton_accepts(def, phi, phi_trial, alpha, slope, gnorm,
                                  fascia_dot(g_trial, g_trial, n, S->sys->threads),
                                  fabs(S->sys->energy_internal) + fabs(S->sys->energy_external), material_roundoff)) {
          accepted = 1;
          break;
        }
        if (st != FASCIA_OK && st != FASCIA_ERR_NUMERIC) return st;
        ++rep->line_search_cuts;
        alpha *= FASCIA_R(0.5);
      }
      if (!accepted) {
        // even tiny steps fail: damp the tangent (Levenberg) and try again
        op.shift = op.shift == 0 ? FASCIA_R(1e-4) : 10 * op.shift;
        if (op.shift > FASCIA_NEWTON_MAX_SHIFT) {
          fascia_real restore;
          (void)objective(S, &terms, S->d, &restore, NULL);
          rep->newton_iterations = iteration;
          rep->gradient_norm = gnorm;
          rep->energy = phi;
          return fascia_newton_no_decrease(S, iteration, gnorm, def->newton_tolerance * reference);
        }
        t = fascia_now_ms();
        FASCIA_TRY(objective(S, &terms, S->d, &phi, g)); // restores the cache of the current iterate
        rep->profile.evaluate_ms += fascia_now_ms() - t;
        if (S->use_assembled) FASCIA_TRY(assemble(S, &terms));
        if (!S->use_direct) fascia_precond_build(&S->pc, &op, S->blocks);
        if (op.organs) fascia_organs_precond(S->organs, &op, &S->pc, S->blocks);
        continue;
      }
      if (alpha == 1 && op.shift > 0) op.shift = op.shift < FASCIA_R(1e-3) ? 0 : op.shift / 10;
    }
    memcpy(g, g_trial, (size_t)n * sizeof(fascia_real));
    phi = phi_trial;
    if (dynamic) {
      memcpy(S->d, S->d_trial, (size_t)n * sizeof(fascia_real));
    } else {
      // static: re-anchor at the accepted state, so d = 0 and the Hessian
      // of the next iteration is exact (no Jacobian of the rotation map)
      memcpy(S->x_base, S->x, 3 * (size_t)N * sizeof(fascia_real));
      memcpy(S->q_base, S->q, 4 * (size_t)N * sizeof(fascia_real));
      memset(S->d, 0, (size_t)n * sizeof(fascia_real));
    }
  }
  rep->converged = converged;
  rep->newton_iterations += iteration;
  rep->gradient_norm = gnorm;
  rep->energy = phi;
  rep->inverted_samples = S->sys->inverted_count;
  rep->profile.total_ms += fascia_now_ms() - t0;
  return FASCIA_OK;
}
