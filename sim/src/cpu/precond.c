// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Preconditioners of the Newton systems: Jacobi (inverse diagonal) and block
// Jacobi (inverse of each frame's 6x6 diagonal block). The tangent may be
// indefinite, so each block is inverted by Cholesky after a shift that makes
// it positive definite: the preconditioner must stay positive for CG.
#include <string.h>

#include "point/block6.h"
#include "point/body.h"
#include "cpu/operator.h"

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
    fascia_real *B = blocks + 36 * (int64_t)i;
    for (int c = 0; c < 6; ++c) B[7 * c] += op->shift * op->damping_diagonal[6 * (int64_t)i + c];
  }
  // rigid organs: a master's block becomes its body's block of P^T A P
  for (int32_t b = 0; op->bodies && b < op->bodies->count; ++b)
    if (op->bodies->active[b]) fascia_pt_body_diagonal(op->bodies, b, op->mass_coefficient, sys->x, sys->q, blocks);
  const int jacobi = pc->kind == FASCIA_PRECOND_JACOBI;
  for (int32_t i = 0; i < N; ++i)
    fascia_pt_block6_precond(blocks + 36 * (int64_t)i, jacobi, pc->inverse + 36 * (int64_t)i);
}

void fascia_precond_apply(const fascia_preconditioner *pc, const unsigned char *mask, const fascia_real *r,
                          fascia_real *z) {
  fascia_precond_apply_frames(pc, mask, r, z, 0, pc->frame_count);
}

void fascia_precond_apply_frames(const fascia_preconditioner *pc, const unsigned char *mask, const fascia_real *r,
                                 fascia_real *z, int32_t begin, int32_t end) {
  for (int32_t i = begin; i < end; ++i)
    fascia_pt_block6_apply(pc->kind == FASCIA_PRECOND_NONE ? NULL : pc->inverse + 36 * (int64_t)i,
                           mask + 6 * (int64_t)i, r + 6 * (int64_t)i, z + 6 * (int64_t)i);
}
