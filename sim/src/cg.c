// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Projected preconditioned conjugate gradients for one Newton iteration.
// Constrained DOFs are kept at zero by the mask. The tangent of the frame
// scheme can be singular or indefinite (zero-energy rotation modes, buckling,
// compressed StVK), so CG stops at the first direction of non-positive
// curvature (Steihaug) and returns what it has, which is a descent direction
// for the line search.
#include <string.h>

#include "solver_internal.h"

#define ROUNDOFF 1e-14 // relative residual at which CG has converged as far as doubles go

void fascia_operator_apply(const fascia_operator *op, const fascia_real *v, fascia_real *out) {
  if (op->organs) { // rigid organs: reduced coordinates (organs.c)
    fascia_organs_operator_apply(op, v, out);
    return;
  }
  fascia_system *sys = op->sys;
  const int64_t n = 6 * (int64_t)sys->frame_count;
  if (op->assembled && op->single) {
    fascia_bsr_apply_single(op->assembled, sys->threads, v, out);
  } else if (op->assembled) {
    fascia_bsr_apply(op->assembled, sys->threads, v, out);
  } else {
    fascia_system_hessian_apply(sys, v, out);
  }
  if (op->mass_coefficient != 0 && !op->assembled) {
    if (op->mass == FASCIA_MASS_LUMPED) {
      for (int32_t i = 0; i < sys->frame_count; ++i) {
        const fascia_real *B = op->mass_blocks + 36 * (int64_t)i, *vi = v + 6 * (int64_t)i;
        for (int r = 0; r < 6; ++r) {
          fascia_real s = 0;
          for (int c = 0; c < 6; ++c) s += B[6 * r + c] * vi[c];
          out[6 * (int64_t)i + r] += op->mass_coefficient * s;
        }
      }
    } else {
      fascia_system_mass_apply(sys, v, op->scratch);
      for (int64_t k = 0; k < n; ++k) out[k] += op->mass_coefficient * op->scratch[k];
    }
  }
  if (op->shift != 0)
    for (int64_t k = 0; k < n; ++k) out[k] += op->shift * op->damping_diagonal[k] * v[k];
  for (int64_t k = 0; k < n; ++k)
    if (!op->mask[k]) out[k] = 0;
}

fascia_cg_result fascia_cg_solve(const fascia_operator *op, const fascia_preconditioner *pc, const fascia_real *b,
                                 fascia_real *p, int max_iterations, int fixed, fascia_real tolerance,
                                 fascia_real *work) {
  const int64_t n = 6 * (int64_t)op->sys->frame_count;
  fascia_real *r = work, *z = work + n, *dir = work + 2 * n, *Ad = work + 3 * n;
  fascia_cg_result result = {0, 0, 0};
  memset(p, 0, (size_t)n * sizeof(fascia_real));
  for (int64_t k = 0; k < n; ++k) r[k] = op->mask[k] ? b[k] : 0;
  const fascia_real bnorm = sqrt(fascia_dot(r, r, n, op->sys->threads));
  if (bnorm == 0) return result;
  fascia_precond_apply(pc, op->mask, r, z);
  memcpy(dir, z, (size_t)n * sizeof(fascia_real));
  fascia_real rz = fascia_dot(r, z, n, op->sys->threads), rnorm = bnorm;
  for (int it = 0; it < max_iterations; ++it) {
    fascia_operator_apply(op, dir, Ad);
    const fascia_real curvature = fascia_dot(dir, Ad, n, op->sys->threads);
    const fascia_real dd = fascia_dot(dir, dir, n, op->sys->threads);
    if (!(curvature > 1e-12 * op->scale * dd) || !isfinite(curvature)) {
      // non-positive curvature: keep p, or the preconditioned gradient if
      // nothing was done yet (a descent direction either way)
      result.negative_curvature = 1;
      if (it == 0) memcpy(p, z, (size_t)n * sizeof(fascia_real));
      break;
    }
    const fascia_real alpha = rz / curvature;
    for (int64_t k = 0; k < n; ++k) {
      p[k] += alpha * dir[k];
      r[k] -= alpha * Ad[k];
    }
    result.iterations = it + 1;
    rnorm = sqrt(fascia_dot(r, r, n, op->sys->threads));
    // A fixed iteration count still ends at round-off: past it the
    // iterations only churn noise (and underflow into slow subnormals)
    if (rnorm <= ROUNDOFF * bnorm || (!fixed && rnorm <= tolerance * bnorm)) break;
    fascia_precond_apply(pc, op->mask, r, z);
    const fascia_real rz_next = fascia_dot(r, z, n, op->sys->threads);
    if (rz_next <= 0) break; // preconditioner not positive: stop with p
    const fascia_real beta = rz_next / rz;
    rz = rz_next;
    for (int64_t k = 0; k < n; ++k) dir[k] = z[k] + beta * dir[k];
  }
  result.residual = rnorm / bnorm;
  return result;
}
