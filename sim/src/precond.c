// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Preconditioners of the Newton systems: Jacobi (inverse diagonal) and block
// Jacobi (inverse of each frame's 6x6 diagonal block). The tangent may be
// indefinite, so each block is inverted by Cholesky after a shift that makes
// it positive definite: the preconditioner must stay positive for CG.
#include <string.h>

#include "solver_internal.h"

// Cholesky of a 6x6 block in place (lower triangle); 0 if not positive.
static int cholesky6(fascia_real *a) {
  for (int j = 0; j < 6; ++j) {
    fascia_real d = a[6 * j + j];
    for (int k = 0; k < j; ++k) d -= a[6 * j + k] * a[6 * j + k];
    if (!(d > 0)) return 0;
    d = sqrt(d);
    a[6 * j + j] = d;
    for (int i = j + 1; i < 6; ++i) {
      fascia_real s = a[6 * i + j];
      for (int k = 0; k < j; ++k) s -= a[6 * i + k] * a[6 * j + k];
      a[6 * i + j] = s / d;
    }
  }
  return 1;
}

// Inverse of an SPD block from its Cholesky factor L: solve L L^T X = I.
static void cholesky6_inverse(const fascia_real *L, fascia_real *inv) {
  for (int col = 0; col < 6; ++col) {
    fascia_real y[6];
    for (int i = 0; i < 6; ++i) {
      fascia_real s = (i == col);
      for (int k = 0; k < i; ++k) s -= L[6 * i + k] * y[k];
      y[i] = s / L[6 * i + i];
    }
    for (int i = 5; i >= 0; --i) {
      fascia_real s = y[i];
      for (int k = i + 1; k < 6; ++k) s -= L[6 * k + i] * inv[6 * k + col];
      inv[6 * i + col] = s / L[6 * i + i];
    }
  }
}

void fascia_precond_build(fascia_preconditioner *pc, const fascia_operator *op, fascia_real *blocks) {
  fascia_system *sys = op->sys;
  if (pc->kind == FASCIA_PRECOND_NONE) return;
  const int32_t N = sys->frame_count;
  if (op->assembled) { // the assembled matrix has them, mass included
    for (int32_t i = 0; i < N; ++i)
      memcpy(blocks + 36 * (int64_t)i, op->assembled->values + 36 * (int64_t)op->assembled->diagonal[i],
             36 * sizeof(fascia_real));
  } else {
    fascia_system_hessian_diagonal(sys, blocks);
  }
  if (op->mass_coefficient != 0 && !op->assembled) {
    // consistent mass: its diagonal blocks are bounded by the lumped ones; the
    // lumped blocks are a good, positive stand-in for the preconditioner
    for (int64_t k = 0; k < 36 * (int64_t)N; ++k) blocks[k] += op->mass_coefficient * op->mass_blocks[k];
  }
  for (int32_t i = 0; i < N; ++i) {
    fascia_real *B = blocks + 36 * (int64_t)i, *inv = pc->inverse + 36 * (int64_t)i;
    fascia_real trace = 0;
    for (int c = 0; c < 6; ++c) {
      B[7 * c] += op->shift * op->damping_diagonal[6 * (int64_t)i + c];
      trace += fabs(B[7 * c]);
    }
    if (trace == 0 || !isfinite(trace)) trace = 1;
    if (pc->kind == FASCIA_PRECOND_JACOBI) {
      memset(inv, 0, 36 * sizeof(fascia_real));
      for (int c = 0; c < 6; ++c) {
        const fascia_real d = fabs(B[7 * c]);
        inv[7 * c] = d > 1e-12 * trace ? 1 / d : 6 / trace;
      }
      continue;
    }
    fascia_real shift = 0;
    for (int attempt = 0; attempt < 60; ++attempt) {
      fascia_real L[36];
      memcpy(L, B, sizeof L);
      for (int c = 0; c < 6; ++c) L[7 * c] += shift;
      if (cholesky6(L)) {
        cholesky6_inverse(L, inv);
        break;
      }
      shift = shift == 0 ? 1e-10 * trace : 4 * shift;
    }
  }
}

void fascia_precond_apply(const fascia_preconditioner *pc, const unsigned char *mask, const fascia_real *r,
                          fascia_real *z) {
  const int32_t N = pc->frame_count;
  if (pc->kind == FASCIA_PRECOND_NONE) {
    for (int64_t k = 0; k < 6 * (int64_t)N; ++k) z[k] = mask[k] ? r[k] : 0;
    return;
  }
  for (int32_t i = 0; i < N; ++i) {
    const fascia_real *inv = pc->inverse + 36 * (int64_t)i, *ri = r + 6 * (int64_t)i;
    const unsigned char *mi = mask + 6 * (int64_t)i;
    fascia_real *zi = z + 6 * (int64_t)i;
    for (int a = 0; a < 6; ++a) {
      fascia_real s = 0;
      for (int c = 0; c < 6; ++c) s += inv[6 * a + c] * (mi[c] ? ri[c] : 0);
      zi[a] = mi[a] ? s : 0;
    }
  }
}
