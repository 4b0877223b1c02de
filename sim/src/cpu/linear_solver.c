// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The CPU backend's linear solver (linear_solver.h): the choice among CG on
// products, CG on the assembled matrix or its float copy and the direct
// solver, the kept factorization and its reuse, and the switch from a
// stalled CG to the direct solver.
#include <stdlib.h>

#include "contract/backend.h"
#include "cpu/linear_solver.h"
#include "organs/organs.h"
#include "point/frame.h"

struct fascia_linear {
  fascia_ctx *ctx;
  const fascia_model *model;
  const fascia_solver_def *def;
  const unsigned char *mask;
  const fascia_organs *organs;
  int32_t frame_count;
  fascia_operator op; ///< the step's operator with the damping and the matrix set here
  fascia_preconditioner pc;
  fascia_real *blocks;  ///< [36N] the tangent's diagonal blocks (the preconditioner's)
  fascia_real *damping; ///< [6N] the Levenberg shift's weights
  fascia_real *work;    ///< [4 * 6N] CG's
  int dynamic;          ///< of the step
  uint64_t epoch;       ///< the solver's linear_epoch in this step
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
  // the factorization's reuse (fascia_linear_prepare): valid while the mask,
  // the mass coefficient and the shift it was made with hold
  int factor_valid, reusing, first_prepare;
  fascia_real factor_shift;   ///< the Levenberg shift it was factored with
  fascia_real factor_mass;    ///< the mass coefficient c1 + c2 it was factored with
  uint64_t factor_epoch;      ///< the solver's linear_epoch then (the state set or restored since: stale)
  fascia_real prepared_norm2; ///< |gradient|^2 at the last prepare
};

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

void fascia_linear_destroy(fascia_linear **linear) {
  if (!linear || !*linear) return;
  fascia_linear *L = *linear;
  fascia_bsr_destroy(&L->K);
  fascia_bsr_destroy(&L->R);
  fascia_direct_destroy(&L->direct);
  free(L->pc.inverse), free(L->blocks), free(L->damping), free(L->work);
  free(L);
  *linear = NULL;
}

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

static fascia_status choose(fascia_linear *L) {
  fascia_linear_solver kind = L->def->linear_solver;
  // rigid organs: the direct solver factors the reduced matrix P^T K P, on the masters' unknowns. auto
  // takes it for dynamic steps only (the organ scenes' steps: 1.3-2.4x faster than CG) and keeps CG for
  // static solves: where the tangent is indefinite (frame rotations near a hanging body, t321) CG's
  // truncation at negative curvature converges in 14 Newton iterations where the Levenberg-shifted
  // factorization does not in 20
  const int bodies = fascia_organs_body_count(L->organs) > 0;
  L->direct_dynamic_only = bodies && kind == FASCIA_LINEAR_AUTO;
  const int assembled = L->def->assembled == FASCIA_ASSEMBLED_AUTO
                            ? assembled_bytes(L->model) <= FASCIA_AUTO_MAX_MATRIX_BYTES
                            : L->def->assembled;
  if (kind == FASCIA_LINEAR_CG && !assembled) return FASCIA_OK;
  FASCIA_TRY(fascia_bsr_create(L->ctx, L->model, &L->K));
  L->use_assembled = 1;
  if (kind == FASCIA_LINEAR_CG) return FASCIA_OK;
  const int automatic = kind == FASCIA_LINEAR_AUTO;
  L->reduced = bodies;
  if (L->reduced) FASCIA_TRY(fascia_organs_reduced_pattern(L->ctx, L->organs, &L->K, &L->R));
  fascia_status st = fascia_direct_create(L->ctx, L->reduced ? &L->R : &L->K, L->mask, &L->direct);
  if (st == FASCIA_OK && (!automatic || fascia_direct_flops(L->direct) <= AUTO_MAX_FLOPS)) {
    L->use_direct = 1;
    return FASCIA_OK;
  }
  if (!automatic) return st;
  // above the bound: CG, the analysis kept for a solve whose CG stalls
  if (st == FASCIA_OK && !bodies && assembled &&
      fascia_direct_factor_nonzeros(L->direct) * sizeof(double) <= FASCIA_AUTO_MAX_MATRIX_BYTES) {
    L->direct_on_stall = 1;
    return FASCIA_OK;
  }
  // automatic: CG, with the product chosen above
  L->direct_dynamic_only = 0;
  fascia_ctx_clear(L->ctx);
  fascia_direct_destroy(&L->direct);
  fascia_bsr_destroy(&L->R);
  L->reduced = 0;
  if (!assembled) {
    fascia_bsr_destroy(&L->K);
    L->use_assembled = 0;
  }
  return FASCIA_OK;
}

fascia_status fascia_linear_create(fascia_ctx *ctx, const fascia_model *model, const fascia_solver_def *def,
                                   const unsigned char *mask, const fascia_organs *organs, fascia_linear **out) {
  *out = NULL;
  fascia_linear *L = calloc(1, sizeof *L);
  FASCIA_CHECK(L, ctx, FASCIA_ERR_MEMORY, "solver: out of memory");
  L->ctx = ctx;
  L->model = model;
  L->def = def;
  L->mask = mask;
  L->organs = organs;
  L->frame_count = model->frame_count;
  const int64_t N = L->frame_count, n = 6 * N;
  L->pc.kind = def->precond;
  L->pc.frame_count = L->frame_count;
  L->pc.inverse = fascia_calloc(36 * N, sizeof(fascia_real));
  L->blocks = fascia_calloc(36 * N, sizeof(fascia_real));
  L->damping = fascia_calloc(n, sizeof(fascia_real));
  L->work = fascia_calloc(4 * n, sizeof(fascia_real));
  if (!L->pc.inverse || !L->blocks || !L->damping || !L->work) {
    fascia_linear_destroy(&L);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "solver: out of memory for %lld frames", (long long)N);
  }
  const fascia_status st = choose(L);
  if (st != FASCIA_OK) {
    fascia_linear_destroy(&L);
    return st;
  }
  *out = L;
  return FASCIA_OK;
}

void fascia_linear_begin(fascia_linear *L, const fascia_operator *op, int dynamic, uint64_t epoch,
                         fascia_solve_report *report) {
  L->dynamic = dynamic;
  L->epoch = epoch;
  if (L->direct) L->use_direct = L->direct_on_stall ? L->cg_stalled[dynamic != 0] : dynamic || !L->direct_dynamic_only;
  // the last factorization fits this step when the mask and the mass coefficient are the same
  // (and a second Newton iteration to check it: with one per step, as the
  // interactive preset has, a kept factorization would never be checked)
  L->factor_valid = L->factor_valid && L->use_direct && op->mass_coefficient == L->factor_mass &&
                    L->factor_epoch == epoch && fascia_direct_mask_is(L->direct, L->mask) &&
                    L->def->newton_iterations > 1;
  L->first_prepare = 1;
  // float products: half the memory traffic of CG's products, which bound a paper-mode step; the rounding
  // stays far below the CG tolerance
  const int single = L->def->single_precision_matrix == FASCIA_SINGLE_AUTO
                         ? L->def->cg_fixed || L->def->cg_tolerance >= FASCIA_SINGLE_MIN_CG_TOLERANCE
                         : L->def->single_precision_matrix;
  L->use_single = L->use_assembled && !L->use_direct && single;
  L->op = *op;
  L->op.damping_diagonal = L->damping;
  L->op.shift = 0;
  L->op.scale = 1;
  L->op.assembled = L->use_assembled ? &L->K : NULL;
  L->op.single = L->use_single;
  report->direct = L->use_direct;
  report->assembled = L->use_assembled;
  report->single_precision_matrix = L->use_single;
}

// K = H (+ (c1 + c2) M for a dynamic step) at the current iterate, and its
// float copy when the products use one
static fascia_status assemble(fascia_linear *L) {
  fascia_system *sys = L->op.sys;
  FASCIA_CHECK(fascia_system_hessian_assemble(sys, L->op.frame_moves, &L->K), sys->ctx, FASCIA_ERR_MEMORY,
               "assembly: out of memory for a thread's scratch");
  const fascia_real c = L->op.mass_coefficient;
  if (c != 0 && L->def->mass == FASCIA_MASS_CONSISTENT) {
    fascia_system_mass_assemble_add(sys, L->op.frame_moves, c, &L->K);
  } else if (c != 0) {
    for (int32_t i = 0; i < L->frame_count; ++i) {
      fascia_real *D = L->K.values + 36 * (int64_t)L->K.diagonal[i];
      for (int q = 0; q < 36; ++q) D[q] += c * L->op.mass_blocks[36 * (int64_t)i + q];
    }
  }
  if (L->use_direct && L->reduced) fascia_organs_reduce_matrix(L->organs, sys, L->op.frame_moves, c, &L->K, &L->R);
  if (L->use_single) return fascia_bsr_make_single(L->ctx, &L->K, sys->threads);
  return FASCIA_OK;
}

// The Levenberg shift's weights and scale, from the diagonal of what the
// linear solver works on (the factored matrix, or the preconditioner's blocks)
static void levenberg_damping(fascia_linear *L) {
  const int32_t N = L->frame_count;
  const int64_t n = 6 * (int64_t)N;
  fascia_real scale = 0;
  const fascia_bsr *factored = L->reduced ? &L->R : &L->K; // what the direct solver factors
  for (int32_t i = 0; i < N; ++i)
    for (int c = 0; c < 6; ++c) {
      const fascia_real diag = L->use_direct ? fabs(factored->values[36 * (int64_t)factored->diagonal[i] + 7 * c])
                                             : fabs(L->blocks[36 * (int64_t)i + 7 * c]);
      L->damping[6 * (int64_t)i + c] = diag;
      scale += diag;
    }
  L->op.scale = scale > 0 ? scale / (fascia_real)n : 1;
  for (int64_t k = 0; k < n; ++k) L->damping[k] = fascia_pt_levenberg_weight(L->damping[k], (int)(k % 6), L->op.scale);
}

// The assembled matrix, the preconditioner and the Levenberg scale at the
// current iterate (a kept factorization no longer fits)
static fascia_status prepare_tangent(fascia_linear *L, fascia_solve_report *report) {
  L->factor_valid = L->reusing = 0;
  double t = fascia_now_ms();
  if (L->use_assembled) {
    FASCIA_TRY(assemble(L));
    report->profile.assemble_ms += fascia_now_ms() - t;
    t = fascia_now_ms();
  }
  if (!L->use_direct) fascia_precond_build(&L->pc, &L->op, L->blocks);
  levenberg_damping(L);
  report->profile.precond_ms += fascia_now_ms() - t;
  return FASCIA_OK;
}

// A new tangent, or the kept factorization where the last direction lowered
// the gradient REUSE_REDUCTION times (a chord step)
fascia_status fascia_linear_prepare(fascia_linear *L, fascia_real norm2, fascia_solve_report *report) {
  L->reusing = L->use_direct && L->dynamic && L->factor_valid &&
               (L->first_prepare || norm2 * REUSE_REDUCTION * REUSE_REDUCTION <= L->prepared_norm2);
  L->prepared_norm2 = norm2;
  L->first_prepare = 0;
  return L->reusing ? FASCIA_OK : prepare_tangent(L, report);
}

fascia_status fascia_linear_solve(fascia_linear *L, const fascia_real *rhs, fascia_real *p, fascia_real *shift,
                                  fascia_solve_report *report) {
  if (L->reusing && *shift != L->factor_shift) // the loop changed the shift: a new tangent after all
    FASCIA_TRY(prepare_tangent(L, report));
  L->op.shift = *shift;
  if (L->reusing) {
    fascia_direct_solve(L->direct, rhs, p);
  } else if (L->use_direct) {
    // not positive definite: raise the Levenberg shift until it is
    int factored;
    const fascia_bsr *A = L->reduced ? &L->R : &L->K;
    ++report->factorizations;
    // an unshifted tangent that fails goes on from a tenth of the last
    // factored shift, not from 1e-8: one that needed a shift is likely
    // to need one again, and a failed factorization can cost nearly a whole one
    const fascia_real restart = L->factor_shift / 10 > FASCIA_R(1e-8) ? L->factor_shift / 10 : FASCIA_R(1e-8);
    factored = fascia_direct_factor(L->direct, L->ctx, A, L->mask, L->damping, L->op.shift);
    while (factored == 0) { // the same matrix with a larger shift: only its diagonal is written again
      ++report->negative_curvature;
      L->op.shift = L->op.shift == 0 ? restart : 10 * L->op.shift;
      if (L->op.shift > FASCIA_NEWTON_MAX_SHIFT)
        return FASCIA_FAIL(L->ctx, FASCIA_ERR_NUMERIC,
                           "solver: the tangent stays singular under any damping (a NaN, or a frame with no sample?)");
      factored = fascia_direct_refactor(L->direct, L->damping, L->op.shift);
    }
    if (factored < 0) return FASCIA_ERR_MEMORY; // the new analysis failed; the message says why
    *shift = L->factor_shift = L->op.shift;
    L->factor_mass = L->op.mass_coefficient;
    L->factor_epoch = L->epoch;
    L->factor_valid = 1;
    fascia_direct_solve(L->direct, rhs, p);
  } else {
    const fascia_solver_def *def = L->def;
    const fascia_cg_result cg =
        fascia_cg_solve(&L->op, &L->pc, rhs, p, def->cg_iterations, def->cg_fixed, def->cg_tolerance, L->work);
    report->cg_iterations += cg.iterations;
    report->negative_curvature += cg.negative_curvature;
    if (L->direct_on_stall && !def->cg_fixed && def->newton_iterations > 1 && !cg.negative_curvature &&
        cg.iterations >= def->cg_iterations && cg.residual > def->cg_tolerance) {
      // CG stopped at its cap: the direct solver for the rest of this solve and the later ones of its kind
      L->use_direct = L->cg_stalled[L->dynamic != 0] = report->direct = 1;
      L->use_single = L->op.single = 0;
      levenberg_damping(L); // from the factored diagonal; K was assembled for this iteration's CG
      return fascia_linear_solve(L, rhs, p, shift, report);
    }
  }
  return FASCIA_OK;
}

void fascia_linear_precondition(const fascia_linear *L, const fascia_real *r, fascia_real *z) {
  fascia_precond_apply(&L->pc, L->mask, r, z);
}

// The kept factorization, for checkpoints: the mass coefficient and the
// shift it was made with, then the values it factored (direct.h).
int64_t fascia_linear_state_size(const fascia_linear *L, uint64_t epoch) {
  if (!L->factor_valid || !L->direct || L->factor_epoch != epoch) return 0;
  return 2 + fascia_direct_values_count(L->direct);
}

void fascia_linear_state_save(const fascia_linear *L, fascia_real *out) {
  out[0] = L->factor_mass;
  out[1] = L->factor_shift;
  fascia_direct_values_save(L->direct, L->reduced ? &L->R : &L->K, out + 2);
}

int fascia_linear_state_load(fascia_linear *L, const fascia_real *in, int64_t count, uint64_t epoch) {
  L->factor_valid = 0;
  if (!L->direct || !fascia_direct_mask_is(L->direct, L->mask) || count != 2 + fascia_direct_values_count(L->direct) ||
      !fascia_direct_values_load(L->direct, L->reduced ? &L->R : &L->K, in + 2))
    return 0;
  L->factor_mass = in[0];
  L->factor_shift = in[1];
  L->factor_epoch = epoch;
  L->factor_valid = 1;
  // a kept factorization of a solver that takes CG first was made after its CG stalled (checkpoints are
  // of dynamic runs): the resumed run goes on with the direct solver, as the run it continues did
  if (L->direct_on_stall) L->cg_stalled[1] = 1;
  return 1;
}
