// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// 6x6 frame blocks, shared by the CPU backend and the device kernels
// (cuda/): the product of a block (a lumped mass block) with a frame's
// vector, and the preconditioners' (Jacobi, block Jacobi): Cholesky,
// inverse, and the masked block product z = B r.
#ifndef FASCIA_POINT_BLOCK6_H
#define FASCIA_POINT_BLOCK6_H

#include "linalg.h"

/// out = B v for a 6x6 block B (row-major) and one frame's 6 entries v.
static inline FASCIA_HD void fascia_pt_block6_mul(const fascia_real *B, const fascia_real *v, fascia_real *out) {
  for (int r = 0; r < 6; ++r) {
    fascia_real s = 0;
    for (int c = 0; c < 6; ++c) s += B[6 * r + c] * v[c];
    out[r] = s;
  }
}

/// Cholesky factor of a 6x6 block in place (lower triangle); 0 if the block
/// is not positive definite.
static inline FASCIA_HD int fascia_pt_cholesky6(fascia_real *a) { return fascia_pt_cholesky(a, 6); }

/// Inverse of an SPD block from its Cholesky factor L: solves L L^T X = I.
static inline FASCIA_HD void fascia_pt_cholesky6_inverse(const fascia_real *L, fascia_real *inv) {
  fascia_pt_cholesky_inverse(L, 6, inv);
}

/// Preconditioner block of one frame from its (shifted) diagonal block B of
/// the tangent: the inverse diagonal (jacobi) or the inverse block, after
/// the smallest shift that makes the block positive definite (the tangent
/// may be indefinite; the preconditioner must stay positive for CG).
static inline FASCIA_HD void fascia_pt_block6_precond(const fascia_real *B, int jacobi, fascia_real *inv) {
  fascia_real trace = 0;
  for (int c = 0; c < 6; ++c) trace += fabs(B[7 * c]);
  if (trace == 0 || !isfinite(trace)) trace = 1;
  if (jacobi) {
    for (int k = 0; k < 36; ++k) inv[k] = 0;
    for (int c = 0; c < 6; ++c) {
      const fascia_real d = fabs(B[7 * c]);
      inv[7 * c] = d > 1e-12 * trace ? 1 / d : 6 / trace;
    }
    return;
  }
  fascia_real shift = 0;
  for (int attempt = 0; attempt < 60; ++attempt) {
    fascia_real L[36];
    for (int k = 0; k < 36; ++k) L[k] = B[k];
    for (int c = 0; c < 6; ++c) L[7 * c] += shift;
    if (fascia_pt_cholesky6(L)) {
      fascia_pt_cholesky6_inverse(L, inv);
      return;
    }
    shift = shift == 0 ? 1e-10 * trace : 4 * shift;
  }
}

/// z = inv r on the free entries of one frame (mask), 0 on the others;
/// inv NULL: no preconditioner (z = masked r).
static inline FASCIA_HD void fascia_pt_block6_apply(const fascia_real *inv, const unsigned char *mask,
                                                    const fascia_real *r, fascia_real *z) {
  fascia_real masked[6]; // r on the free entries: the mask read once, not per product term
  for (int c = 0; c < 6; ++c) masked[c] = mask[c] ? r[c] : 0;
  if (!inv) {
    for (int a = 0; a < 6; ++a) z[a] = masked[a];
    return;
  }
  for (int a = 0; a < 6; ++a) {
    fascia_real s = 0;
    for (int c = 0; c < 6; ++c) s += inv[6 * a + c] * masked[c];
    z[a] = mask[a] ? s : 0;
  }
}

#endif
