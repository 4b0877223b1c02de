// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The CPU backend of the Newton loop (backend.h): the step objective on the
// host system (system.c), the tangent as products or an assembled block
// matrix (assemble.c), directions by projected PCG (cg.c) or by banded
// Cholesky (direct.c), and rigid organs as bodies whose frames follow them
// (organs.c, on the solver's state).
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "solve/backend.h"
#include "organs/organs.h"
#include "point/frame.h"
#include "solve/solver_internal.h"

typedef struct cpu_backend {
  fascia_backend base;
  fascia_solver *S; ///< the state the trials write (x, q) and the rigid organs read
  fascia_system *sys;
  const fascia_model *model;
  const fascia_solver_def *def;
  const unsigned char *mask;
  int32_t frame_count;
  // the step
  fascia_step_values values;
  fascia_real *x_base, *q_base, *d; ///< the solver's anchor and iterate (the organs read them there)
  fascia_real *gradient;            ///< the current gradient: the solver's
  fascia_real *target_M;            ///< M (h u) [6N]
  fascia_real target_norm;          ///< (h u).M(h u)
  // work
  fascia_real *d_trial, *gradient_trial, *direction, *rhs, *work, *blocks, *mass_blocks, *damping, *scratch;
  fascia_real *saved; ///< [13N] the watched iterate (cpu_save): anchor x, q and increments
  const fascia_pt_bodies *bodies; ///< rigid organs (point/body.h), NULL for none
  const unsigned char *full_mask; ///< [6N] every frame the tissue moves (the bodies' slaves too)
  fascia_real *prolonged;         ///< [6N] the operator's P v for rigid organs
  unsigned char *frame_moves;     ///< [N] a frame with a free unknown, a body's slave included (assembly)
  fascia_operator op;
  fascia_preconditioner pc;
  int use_direct;    ///< this step's linear systems by sparse Cholesky (direct.h)
  int direct_dynamic_only; ///< auto with rigid organs: the direct solver for dynamic steps, CG for static solves
  int direct_on_stall;     ///< auto above AUTO_MAX_FLOPS: CG, and a solve takes the direct solver once a CG solve
                           ///< stops at its iteration cap
  int cg_stalled[2];       ///< it did, in a static [0] or dynamic [1] solve: later ones take the direct solver at once
  int use_assembled; ///< the block matrix K is assembled every Newton iteration
  int use_single;    ///< CG multiplies by K's float copy (fascia_solver_def.single_precision_matrix)
  fascia_bsr K;
  int reduced;  ///< rigid organs with the direct solver: it factors R = P^T K P (organs.c), not K
  fascia_bsr R;
  fascia_direct *direct;
  // the factorization's reuse (cpu_prepare): valid while the mask, the mass
  // coefficient and the shift it was made with hold
  int factor_valid, reusing, first_prepare;
  fascia_real factor_shift;   ///< the Levenberg shift it was factored with
  fascia_real factor_mass;    ///< the mass coefficient c1 + c2 it was factored with
  uint64_t factor_epoch;      ///< the solver's linear_epoch then (the state set or restored since: stale)
  fascia_real prepared_norm2; ///< |gradient|^2 at the last prepare
  fascia_real gradient_norm2, trial_norm2; ///< of the current and the trial gradient (cpu_evaluate)
  char text[96];
} cpu_backend;

/// The direct solver's chord steps: a Newton iteration keeps the last
/// factorization when the last direction lowered |gradient| at least this
/// many times (the tangent then barely moved: Newton converges
/// quadratically there, and a stale tangent still gives linear convergence
/// at a rate the next prepare checks again); a step's first iteration tries
/// the last step's, when it was made for the same mask and mass coefficient
/// and the state was not set or restored since (a checkpoint carries it:
/// linear_state_save), and a second iteration may follow to check it.
/// Assembly and factorization are most of a direct iteration, the solve
/// with the factor a small part. Dynamic steps only: a static solve keeps
/// exact Newton, whose iteration count the accuracy study reports (chord
/// steps there saved little time for more iterations).
#define REUSE_REDUCTION 10

static int cpu_available(char *detail, size_t size) {
  if (detail) snprintf(detail, size, "the CPU reference backend");
  return 1;
}

static int cpu_supports(const fascia_backend_setup *setup, char *why, size_t size) {
  (void)setup, (void)why, (void)size;
  return 1;
}

static void cpu_destroy(fascia_backend *backend) {
  cpu_backend *B = (cpu_backend *)backend;
  if (!B) return;
  fascia_bsr_destroy(&B->K);
  fascia_bsr_destroy(&B->R);
  fascia_direct_destroy(&B->direct);
  free(B->target_M), free(B->d_trial), free(B->gradient_trial), free(B->direction), free(B->rhs), free(B->work);
  free(B->blocks), free(B->mass_blocks), free(B->damping), free(B->scratch), free(B->pc.inverse);
  free(B->saved), free(B->prolonged), free(B->frame_moves);
  free(B);
}

// The automatic choices, by measured cost (docs/mechanics.md, "Choosing the
// linear solver"): the direct solver up to this factorization cost (about
// 0.1-0.2 s on one core); CG's products on the assembled matrix where it
// fits FASCIA_AUTO_MAX_MATRIX_BYTES. Above that cost, where the factor fits
// the same bound, the analysis is kept for solves whose CG stalls: a CG
// solve that stops at its iteration cap short of its tolerance hands the
// rest of the solve, and the later ones of its kind (static or dynamic), to
// the direct solver. A slender beam's large deflection needs about a
// thousand CG iterations per solve (the 60x8x8 cantilever, 8.2e9 flops per
// factorization: statically not converged after 100 Newton iterations of
// 200 CG iterations, 14.6 s, 20 iterations and 8.6 s with a cap of 3000,
// direct 7 iterations, 3.3 s; a dynamic step of 0.1 s 54 Newton iterations
// and 17 s), where a tissue's static solve needs a few dozen (the pelvis
// tissue at 1.3 mm frames, 2,490 frames: 3 iterations and 117 CG
// iterations, 0.45 s; direct 1.7 s). Not with one Newton iteration per step
// (the interactive preset), whose CG cap bounds a step's cost.
#define AUTO_MAX_FLOPS 2e9

// Bytes of the assembled matrix and its assembly plan, bounded from the
// model: per ordered pair of frames of a sample 36 values, and per
// unordered pair an index into the matrix, one into the plan and a flag.
static double assembled_bytes(const fascia_model *m) {
  double pairs = 0, upper = 0, shares = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    const double n = m->sample_offsets[s + 1] - m->sample_offsets[s];
    pairs += n * n;
    upper += n * (n + 1) / 2;
    if (m->sample_modes[s]) shares += 81 + 54 * n; // the enhanced strain modes' shares (modes.h)
  }
  return (pairs * 36 + shares) * sizeof(fascia_real) + upper * (sizeof(int32_t) + sizeof(int64_t) + 1);
}

static fascia_status choose_linear_solver(cpu_backend *B, fascia_ctx *ctx, const fascia_organs *organs) {
  fascia_linear_solver kind = B->def->linear_solver;
  // rigid organs: the direct solver factors the reduced matrix P^T K P, on the masters' unknowns. auto
  // takes it for dynamic steps only (the organ scenes' steps: 1.3-2.4x faster than CG) and keeps CG for
  // static solves: where the tangent is indefinite (frame rotations near a hanging body, t321) CG's
  // truncation at negative curvature converges in 14 Newton iterations where the Levenberg-shifted
  // factorization does not in 20
  const int bodies = fascia_organs_body_count(organs) > 0;
  B->direct_dynamic_only = bodies && kind == FASCIA_LINEAR_AUTO;
  const int assembled = B->def->assembled == FASCIA_ASSEMBLED_AUTO
                            ? assembled_bytes(B->model) <= FASCIA_AUTO_MAX_MATRIX_BYTES
                            : B->def->assembled;
  if (kind == FASCIA_LINEAR_CG && !assembled) return FASCIA_OK;
  FASCIA_TRY(fascia_bsr_create(ctx, B->model, &B->K));
  B->use_assembled = 1;
  if (kind == FASCIA_LINEAR_CG) return FASCIA_OK;
  const int automatic = kind == FASCIA_LINEAR_AUTO;
  B->reduced = bodies;
  if (B->reduced) FASCIA_TRY(fascia_organs_reduced_pattern(ctx, organs, &B->K, &B->R));
  fascia_status st = fascia_direct_create(ctx, B->reduced ? &B->R : &B->K, B->mask, &B->direct);
  if (st == FASCIA_OK && (!automatic || fascia_direct_flops(B->direct) <= AUTO_MAX_FLOPS)) {
    B->use_direct = 1;
    return FASCIA_OK;
  }
  if (!automatic) return st;
  // above the bound: CG, the analysis kept for a solve whose CG stalls
  if (st == FASCIA_OK && !bodies && assembled &&
      fascia_direct_factor_nonzeros(B->direct) * sizeof(double) <= FASCIA_AUTO_MAX_MATRIX_BYTES) {
    B->direct_on_stall = 1;
    return FASCIA_OK;
  }
  // automatic: CG, with the product chosen above
  B->direct_dynamic_only = 0;
  fascia_ctx_clear(ctx);
  fascia_direct_destroy(&B->direct);
  fascia_bsr_destroy(&B->R);
  B->reduced = 0;
  if (!assembled) {
    fascia_bsr_destroy(&B->K);
    B->use_assembled = 0;
  }
  return FASCIA_OK;
}

static fascia_status cpu_create(const fascia_backend_setup *setup, fascia_backend **out) {
  *out = NULL;
  cpu_backend *B = calloc(1, sizeof *B);
  FASCIA_CHECK(B, setup->ctx, FASCIA_ERR_MEMORY, "solver: out of memory");
  B->base.ops = &fascia_backend_cpu;
  B->S = setup->solver;
  B->sys = setup->sys;
  B->model = setup->model;
  B->def = setup->def;
  B->mask = setup->mask;
  B->bodies = setup->bodies;
  B->full_mask = setup->full_mask;
  B->frame_count = setup->model->frame_count;
  const int64_t N = B->frame_count, n = 6 * N;
  B->target_M = fascia_calloc(n, sizeof(fascia_real));
  B->d_trial = fascia_calloc(n, sizeof(fascia_real));
  B->gradient_trial = fascia_calloc(n, sizeof(fascia_real));
  B->direction = fascia_calloc(n, sizeof(fascia_real));
  B->rhs = fascia_calloc(n, sizeof(fascia_real));
  B->work = fascia_calloc(6 * n, sizeof(fascia_real));
  B->blocks = fascia_calloc(36 * N, sizeof(fascia_real));
  B->mass_blocks = fascia_calloc(36 * N, sizeof(fascia_real));
  B->damping = fascia_calloc(n, sizeof(fascia_real));
  B->scratch = fascia_calloc(2 * n, sizeof(fascia_real));
  B->saved = fascia_calloc(13 * N, sizeof(fascia_real));
  B->prolonged = fascia_calloc(n, sizeof(fascia_real));
  B->frame_moves = fascia_calloc(N, 1);
  B->pc.kind = setup->def->precond;
  B->pc.frame_count = B->frame_count;
  B->pc.inverse = fascia_calloc(36 * N, sizeof(fascia_real));
  if (!B->target_M || !B->d_trial || !B->gradient_trial || !B->direction || !B->rhs || !B->work || !B->blocks ||
      !B->mass_blocks || !B->damping || !B->scratch || !B->saved || !B->prolonged || !B->frame_moves ||
      !B->pc.inverse) {
    cpu_destroy(&B->base);
    return FASCIA_FAIL(setup->ctx, FASCIA_ERR_MEMORY, "solver: out of memory for %lld frames", (long long)N);
  }
  const fascia_status st = choose_linear_solver(B, setup->ctx, setup->organs);
  if (st != FASCIA_OK) {
    cpu_destroy(&B->base);
    return st;
  }
  const int threads = B->sys->threads_max;
  snprintf(B->text, sizeof B->text, "cpu, %d thread%s", threads, threads == 1 ? "" : "s");
  *out = &B->base;
  return FASCIA_OK;
}

static const char *cpu_describe(const fascia_backend *backend) { return ((const cpu_backend *)backend)->text; }

static void mass_apply(cpu_backend *B, const fascia_real *v, fascia_real *out) {
  if (B->def->mass == FASCIA_MASS_LUMPED) {
    for (int32_t i = 0; i < B->frame_count; ++i) {
      const fascia_real *M = B->mass_blocks + 36 * (int64_t)i, *vi = v + 6 * (int64_t)i;
      for (int r = 0; r < 6; ++r) {
        fascia_real s = 0;
        for (int c = 0; c < 6; ++c) s += M[6 * r + c] * vi[c];
        out[6 * (int64_t)i + r] = s;
      }
    }
  } else {
    fascia_system_mass_apply(B->sys, v, out);
  }
}

// Anchor and first iterate are the solver's own arrays (the rigid organs
// read them there); the mass at the anchor for a dynamic step.
static fascia_status cpu_begin(fascia_backend *backend, const fascia_step_values *v, fascia_solve_report *report) {
  cpu_backend *B = (cpu_backend *)backend;
  fascia_solver *S = B->S;
  FASCIA_CHECK(v->x_base == S->x_base && v->q_base == S->q_base && v->d == S->d, S->ctx, FASCIA_ERR_INTERNAL,
               "cpu backend: the step's arrays are not the solver's");
  B->values = *v;
  if (B->direct)
    B->use_direct = B->direct_on_stall ? B->cg_stalled[v->dynamic != 0] : v->dynamic || !B->direct_dynamic_only;
  // the last factorization fits this step when the mask and the mass coefficient are the same
  // (and a second Newton iteration to check it: with one per step, as the
  // interactive preset has, a kept factorization would never be checked)
  B->factor_valid = B->factor_valid && B->use_direct && v->c1 + v->c2 == B->factor_mass &&
                    B->factor_epoch == S->linear_epoch && fascia_direct_mask_is(B->direct, B->mask) &&
                    B->def->newton_iterations > 1;
  B->first_prepare = 1;
  B->x_base = S->x_base, B->q_base = S->q_base, B->d = S->d, B->gradient = S->gradient;
  B->sys->gravity_scale = v->gravity_scale;
  const int64_t n = 6 * (int64_t)B->frame_count;
  B->target_norm = 0;
  if (v->dynamic) {
    fascia_system_set_state(B->sys, v->x_base, v->q_base);
    fascia_system_mass_snapshot(B->sys);
    fascia_system_mass_lumped(B->sys, B->mass_blocks);
    mass_apply(B, v->inertia_target, B->target_M);
    B->target_norm = fascia_dot(v->inertia_target, B->target_M, n, B->sys->threads);
  }
  // the masks may change between steps: the frames that move, from them
  for (int32_t i = 0; i < B->frame_count; ++i) {
    unsigned char moves = 0;
    for (int c = 0; c < 6; ++c)
      moves |= B->mask[6 * (int64_t)i + c] | (B->full_mask ? B->full_mask[6 * (int64_t)i + c] : 0);
    B->frame_moves[i] = moves != 0;
  }
  const fascia_real c = v->c1 + v->c2;
  fascia_operator op = {.sys = B->sys,
                        .mass_coefficient = c,
                        .mass = B->def->mass,
                        .mass_blocks = B->mass_blocks,
                        .damping_diagonal = B->damping,
                        .scale = 1,
                        .assembled = B->use_assembled ? &B->K : NULL,
                        .frame_moves = B->frame_moves,
                        .mask = B->mask,
                        .scratch = B->scratch + n};
  // rigid organs: the table says which bodies move in this step (the caller may drive one)
  op.bodies = fascia_organs_body_count(S->organs) > 0 ? B->bodies : NULL;
  op.full_mask = B->full_mask;
  op.prolonged = B->prolonged;
  // float products: half the memory traffic of CG's products, which bound a paper-mode step; the rounding
  // stays far below the CG tolerance
  const int single = B->def->single_precision_matrix == FASCIA_SINGLE_AUTO
                         ? B->def->cg_fixed || B->def->cg_tolerance >= FASCIA_SINGLE_MIN_CG_TOLERANCE
                         : B->def->single_precision_matrix;
  B->use_single = B->use_assembled && !B->use_direct && single;
  op.single = B->use_single;
  B->op = op;
  report->direct = B->use_direct;
  report->assembled = B->use_assembled;
  report->single_precision_matrix = B->use_single;
  return FASCIA_OK;
}

// Phi and its projected gradient at increments d (newton.c's header has the
// objective).
static fascia_status objective(cpu_backend *B, const fascia_real *d, fascia_real *phi, fascia_real *gradient) {
  fascia_solver *S = B->S;
  const fascia_step_values *v = &B->values;
  const int32_t N = B->frame_count;
  const int64_t n = 6 * (int64_t)N;
  for (int32_t i = 0; i < N; ++i) {
    for (int c = 0; c < 3; ++c) S->x[3 * i + c] = B->x_base[3 * i + c] + d[6 * i + c];
    memcpy(S->q + 4 * i, B->q_base + 4 * i, 4 * sizeof(fascia_real));
    fascia_pt_quat_rotate_by(d + 6 * i + 3, S->q + 4 * i);
  }
  fascia_system_set_state(B->sys, S->x, S->q);
  fascia_real energy;
  FASCIA_TRY(fascia_system_evaluate(B->sys, gradient, &energy));
  if (v->dynamic)
    for (int32_t i = 0; i < N; ++i) {
      fascia_real g[3] = {gradient[6 * i + 3], gradient[6 * i + 4], gradient[6 * i + 5]};
      fascia_pt_left_jacobian_t(d + 6 * i + 3, g, gradient + 6 * i + 3);
    }
  if (v->c1 != 0 || v->c2 != 0) {
    // c1/2 (d - hu).M(d - hu) + c2/2 d.M d with M(hu) precomputed
    mass_apply(B, d, B->scratch);
    const int threads = B->sys->threads;
    const fascia_real dMd = fascia_dot(d, B->scratch, n, threads), dz = fascia_dot(d, B->target_M, n, threads);
    energy += FASCIA_R(0.5) * v->c1 * (dMd - 2 * dz + B->target_norm) + FASCIA_R(0.5) * v->c2 * dMd;
    for (int64_t k = 0; k < n; ++k) gradient[k] += (v->c1 + v->c2) * B->scratch[k] - v->c1 * B->target_M[k];
  }
  // rigid organs: the bodies' own terms, gradient restricted to their masters
  const fascia_pt_body_step body_step = {v->c1, v->c2, v->gravity_scale, v->dynamic,
                                         {B->sys->gravity[0], B->sys->gravity[1], B->sys->gravity[2]}};
  energy += fascia_organs_reduce(S->organs, &body_step, S->x, S->q, B->x_base, B->q_base, d, gradient);
  for (int64_t k = 0; k < n; ++k)
    if (!B->mask[k]) gradient[k] = 0;
  *phi = energy;
  return isfinite(energy) ? FASCIA_OK
                          : FASCIA_FAIL(S->ctx, FASCIA_ERR_NUMERIC, "solver: the energy is not finite");
}

static fascia_status cpu_evaluate(fascia_backend *backend, fascia_real alpha, int current, fascia_trial_values *out) {
  cpu_backend *B = (cpu_backend *)backend;
  const int64_t n = 6 * (int64_t)B->frame_count;
  const fascia_real *d = B->d;
  fascia_real *g = current ? B->gradient : B->gradient_trial;
  if (!current) {
    for (int64_t k = 0; k < n; ++k) B->d_trial[k] = B->d[k] + alpha * B->direction[k];
    fascia_organs_expand(B->S->organs, B->x_base, B->q_base, B->d_trial); // slaves of rigid organs follow their master
    d = B->d_trial;
  }
  FASCIA_TRY(objective(B, d, &out->phi, g));
  out->gradient_norm2 = fascia_dot(g, g, n, B->sys->threads);
  *(current ? &B->gradient_norm2 : &B->trial_norm2) = out->gradient_norm2;
  out->energy_size = fabs(B->sys->energy_internal) + fabs(B->sys->energy_external);
  return FASCIA_OK;
}

// K = H (+ (c1 + c2) M for a dynamic step) at the current iterate, and its
// float copy when the products use one
static fascia_status assemble(cpu_backend *B) {
  FASCIA_CHECK(fascia_system_hessian_assemble(B->sys, B->frame_moves, &B->K), B->sys->ctx, FASCIA_ERR_MEMORY,
               "assembly: out of memory for a thread's scratch");
  const fascia_real c = B->values.c1 + B->values.c2;
  if (c != 0 && B->def->mass == FASCIA_MASS_CONSISTENT) {
    fascia_system_mass_assemble_add(B->sys, B->frame_moves, c, &B->K);
  } else if (c != 0) {
    for (int32_t i = 0; i < B->frame_count; ++i) {
      fascia_real *D = B->K.values + 36 * (int64_t)B->K.diagonal[i];
      for (int q = 0; q < 36; ++q) D[q] += c * B->mass_blocks[36 * (int64_t)i + q];
    }
  }
  if (B->use_direct && B->reduced) fascia_organs_reduce_matrix(B->S->organs, B->sys, B->frame_moves, c, &B->K, &B->R);
  if (B->use_single)
    return fascia_bsr_make_single(B->S->ctx, &B->K, B->sys->threads);
  return FASCIA_OK;
}

// The assembled matrix, the preconditioner and the Levenberg scale at the
// current iterate (a kept factorization no longer fits)
static void levenberg_damping(cpu_backend *B);

static fascia_status prepare_tangent(cpu_backend *B, fascia_solve_report *report) {
  B->factor_valid = B->reusing = 0;
  double t = fascia_now_ms();
  if (B->use_assembled) {
    FASCIA_TRY(assemble(B));
    report->profile.assemble_ms += fascia_now_ms() - t;
    t = fascia_now_ms();
  }
  if (!B->use_direct) fascia_precond_build(&B->pc, &B->op, B->blocks);
  levenberg_damping(B);
  report->profile.precond_ms += fascia_now_ms() - t;
  return FASCIA_OK;
}

// The Levenberg shift's weights and scale, from the diagonal of what the
// linear solver works on (the factored matrix, or the preconditioner's blocks)
static void levenberg_damping(cpu_backend *B) {
  const int32_t N = B->frame_count;
  const int64_t n = 6 * (int64_t)N;
  fascia_real scale = 0;
  const fascia_bsr *factored = B->reduced ? &B->R : &B->K; // what the direct solver factors
  for (int32_t i = 0; i < N; ++i)
    for (int c = 0; c < 6; ++c) {
      const fascia_real diag = B->use_direct ? fabs(factored->values[36 * (int64_t)factored->diagonal[i] + 7 * c])
                                             : fabs(B->blocks[36 * (int64_t)i + 7 * c]);
      B->damping[6 * (int64_t)i + c] = diag;
      scale += diag;
    }
  B->op.scale = scale > 0 ? scale / (fascia_real)n : 1;
  for (int64_t k = 0; k < n; ++k) B->damping[k] = fascia_pt_levenberg_weight(B->damping[k], (int)(k % 6), B->op.scale);
}

// A new tangent, or the kept factorization where the last direction lowered
// the gradient REUSE_REDUCTION times (a chord step)
static fascia_status cpu_prepare(fascia_backend *backend, fascia_solve_report *report) {
  cpu_backend *B = (cpu_backend *)backend;
  const fascia_real norm2 = B->gradient_norm2;
  B->reusing = B->use_direct && B->values.dynamic && B->factor_valid &&
               (B->first_prepare || norm2 * REUSE_REDUCTION * REUSE_REDUCTION <= B->prepared_norm2);
  B->prepared_norm2 = norm2;
  B->first_prepare = 0;
  return B->reusing ? FASCIA_OK : prepare_tangent(B, report);
}

static fascia_status cpu_direction(fascia_backend *backend, fascia_real *shift, fascia_real *slope,
                                   fascia_solve_report *report) {
  cpu_backend *B = (cpu_backend *)backend;
  const int64_t n = 6 * (int64_t)B->frame_count;
  fascia_real *p = B->direction, *g = B->gradient;
  for (int64_t k = 0; k < n; ++k) B->rhs[k] = -g[k];
  if (B->reusing && *shift != B->factor_shift) // the loop changed the shift: a new tangent after all
    FASCIA_TRY(prepare_tangent(B, report));
  B->op.shift = *shift;
  if (B->reusing) {
    fascia_direct_solve(B->direct, B->rhs, p);
  } else if (B->use_direct) {
    // not positive definite: raise the Levenberg shift until it is
    int factored;
    const fascia_bsr *A = B->reduced ? &B->R : &B->K;
    ++report->factorizations;
    // an unshifted tangent that fails goes on from a tenth of the last
    // factored shift, not from 1e-8: one that needed a shift is likely
    // to need one again, and a failed factorization can cost nearly a whole one
    const fascia_real restart = B->factor_shift / 10 > FASCIA_R(1e-8) ? B->factor_shift / 10 : FASCIA_R(1e-8);
    factored = fascia_direct_factor(B->direct, B->S->ctx, A, B->mask, B->damping, B->op.shift);
    while (factored == 0) { // the same matrix with a larger shift: only its diagonal is written again
      ++report->negative_curvature;
      B->op.shift = B->op.shift == 0 ? restart : 10 * B->op.shift;
      if (B->op.shift > FASCIA_NEWTON_MAX_SHIFT)
        return FASCIA_FAIL(B->S->ctx, FASCIA_ERR_NUMERIC,
                           "solver: the tangent stays singular under any damping (a NaN, or a frame with no sample?)");
      factored = fascia_direct_refactor(B->direct, B->damping, B->op.shift);
    }
    if (factored < 0) return FASCIA_ERR_MEMORY; // the new analysis failed; the message says why
    *shift = B->factor_shift = B->op.shift;
    B->factor_mass = B->values.c1 + B->values.c2;
    B->factor_epoch = B->S->linear_epoch;
    B->factor_valid = 1;
    fascia_direct_solve(B->direct, B->rhs, p);
  } else {
    const fascia_cg_result cg = fascia_cg_solve(&B->op, &B->pc, B->rhs, p, B->def->cg_iterations,
                                                B->def->cg_fixed, B->def->cg_tolerance, B->work + 2 * n);
    report->cg_iterations += cg.iterations;
    report->negative_curvature += cg.negative_curvature;
    if (B->direct_on_stall && !B->def->cg_fixed && B->def->newton_iterations > 1 && !cg.negative_curvature &&
        cg.iterations >= B->def->cg_iterations && cg.residual > B->def->cg_tolerance) {
      // CG stopped at its cap: the direct solver for the rest of this solve and the later ones of its kind
      B->use_direct = B->cg_stalled[B->values.dynamic != 0] = report->direct = 1;
      B->use_single = B->op.single = 0;
      levenberg_damping(B); // from the factored diagonal; K was assembled for this iteration's CG
      return cpu_direction(backend, shift, slope, report);
    }
  }
  *slope = fascia_dot(p, g, n, B->sys->threads);
  if (!(*slope < 0)) { // not a descent direction: preconditioned gradient
    fascia_precond_apply(&B->pc, B->mask, g, p);
    for (int64_t k = 0; k < n; ++k) p[k] = -p[k];
    *slope = fascia_dot(p, g, n, B->sys->threads);
  }
  return FASCIA_OK;
}

static void cpu_accept(fascia_backend *backend) {
  cpu_backend *B = (cpu_backend *)backend;
  const int32_t N = B->frame_count;
  const size_t n = 6 * (size_t)N;
  memcpy(B->gradient, B->gradient_trial, n * sizeof(fascia_real));
  B->gradient_norm2 = B->trial_norm2;
  if (B->values.dynamic) {
    memcpy(B->d, B->d_trial, n * sizeof(fascia_real));
  } else {
    // static: re-anchor at the accepted state, so d = 0 and the Hessian
    // of the next iteration is exact (no Jacobian of the rotation map)
    memcpy(B->x_base, B->S->x, 3 * (size_t)N * sizeof(fascia_real));
    memcpy(B->q_base, B->S->q, 4 * (size_t)N * sizeof(fascia_real));
    memset(B->d, 0, n * sizeof(fascia_real));
  }
}

// The iterate is the anchor and the increments (rigid organs follow them)
static void cpu_save(fascia_backend *backend) {
  cpu_backend *B = (cpu_backend *)backend;
  const size_t N = (size_t)B->frame_count;
  memcpy(B->saved, B->x_base, 3 * N * sizeof(fascia_real));
  memcpy(B->saved + 3 * N, B->q_base, 4 * N * sizeof(fascia_real));
  memcpy(B->saved + 7 * N, B->d, 6 * N * sizeof(fascia_real));
}

static void cpu_restore(fascia_backend *backend) {
  cpu_backend *B = (cpu_backend *)backend;
  const size_t N = (size_t)B->frame_count;
  memcpy(B->x_base, B->saved, 3 * N * sizeof(fascia_real));
  memcpy(B->q_base, B->saved + 3 * N, 4 * N * sizeof(fascia_real));
  memcpy(B->d, B->saved + 7 * N, 6 * N * sizeof(fascia_real));
}

// The trials wrote the solver's own arrays: nothing to copy
static fascia_status cpu_finish(fascia_backend *backend, const fascia_step_result *result) {
  cpu_backend *B = (cpu_backend *)backend;
  FASCIA_CHECK(result->x == B->S->x && result->q == B->S->q && result->d == B->d && result->gradient == B->gradient,
               B->S->ctx, FASCIA_ERR_INTERNAL, "cpu backend: the result's arrays are not the solver's");
  return FASCIA_OK;
}

static fascia_status cpu_gradient(fascia_backend *backend, const fascia_real *x, const fascia_real *q,
                                  fascia_real *gradient, fascia_real *energy) {
  cpu_backend *B = (cpu_backend *)backend;
  fascia_system_set_state(B->sys, x, q);
  FASCIA_TRY(fascia_system_evaluate(B->sys, gradient, energy));
  for (int64_t k = 0; k < 6 * (int64_t)B->frame_count; ++k)
    if (!B->mask[k]) gradient[k] = 0;
  return FASCIA_OK;
}

static fascia_status cpu_hessian_apply(fascia_backend *backend, const fascia_real *v, fascia_real *out) {
  cpu_backend *B = (cpu_backend *)backend;
  fascia_system_hessian_apply(B->sys, v, out);
  for (int64_t k = 0; k < 6 * (int64_t)B->frame_count; ++k)
    if (!B->mask[k]) out[k] = 0;
  return FASCIA_OK;
}

static fascia_status cpu_hessian_diagonal(fascia_backend *backend, fascia_real *blocks) {
  fascia_system_hessian_diagonal(((cpu_backend *)backend)->sys, blocks);
  return FASCIA_OK;
}

// The kept factorization, for checkpoints: the mass coefficient and the
// shift it was made with, then the values it factored (direct.h).
static int64_t cpu_linear_state_size(fascia_backend *backend) {
  cpu_backend *B = (cpu_backend *)backend;
  if (!B->factor_valid || !B->direct || B->factor_epoch != B->S->linear_epoch) return 0;
  return 2 + fascia_direct_values_count(B->direct);
}

static void cpu_linear_state_save(fascia_backend *backend, fascia_real *out) {
  cpu_backend *B = (cpu_backend *)backend;
  out[0] = B->factor_mass;
  out[1] = B->factor_shift;
  fascia_direct_values_save(B->direct, B->reduced ? &B->R : &B->K, out + 2);
}

static int cpu_linear_state_load(fascia_backend *backend, const fascia_real *in, int64_t count) {
  cpu_backend *B = (cpu_backend *)backend;
  B->factor_valid = 0;
  if (!B->direct || !fascia_direct_mask_is(B->direct, B->mask) || count != 2 + fascia_direct_values_count(B->direct) ||
      !fascia_direct_values_load(B->direct, B->reduced ? &B->R : &B->K, in + 2))
    return 0;
  B->factor_mass = in[0];
  B->factor_shift = in[1];
  B->factor_epoch = B->S->linear_epoch;
  B->factor_valid = 1;
  // a kept factorization of a solver that takes CG first was made after its CG stalled (checkpoints are
  // of dynamic runs): the resumed run goes on with the direct solver, as the run it continues did
  if (B->direct_on_stall) B->cg_stalled[1] = 1;
  return 1;
}

const fascia_backend_ops fascia_backend_cpu = {
    .name = "cpu",
    .automatic = 1,
    .available = cpu_available,
    .supports = cpu_supports,
    .create = cpu_create,
    .destroy = cpu_destroy,
    .describe = cpu_describe,
    .host_evaluates = 1,
    .begin = cpu_begin,
    .evaluate = cpu_evaluate,
    .prepare = cpu_prepare,
    .direction = cpu_direction,
    .accept = cpu_accept,
    .save = cpu_save,
    .restore = cpu_restore,
    .finish = cpu_finish,
    .linear_state_size = cpu_linear_state_size,
    .linear_state_save = cpu_linear_state_save,
    .linear_state_load = cpu_linear_state_load,
    .gradient = cpu_gradient,
    .hessian_apply = cpu_hessian_apply,
    .hessian_diagonal = cpu_hessian_diagonal,
};
