// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The CPU backend's linear algebra of one Newton iteration: the operator
// (tangent, mass, Levenberg shift, rigid organs' reduction), its
// preconditioners (precond.c) and projected preconditioned CG (cg.c).
#ifndef FASCIA_SRC_OPERATOR_H
#define FASCIA_SRC_OPERATOR_H

#include "fascia/solver.h"
#include "cpu/direct.h"
#include "cpu/system.h"

/// The linear operator of one Newton iteration:
///   A v = mass_coefficient M v + H v + shift * (D v)
/// restricted to the free DOFs (mask), D the diagonal of |H| + M used for
/// Levenberg damping.
typedef struct fascia_operator {
  fascia_system *sys;
  fascia_real mass_coefficient;
  fascia_mass_kind mass;
  const fascia_real *mass_blocks; ///< [36N] lumped blocks when mass == LUMPED
  const fascia_real *damping_diagonal; ///< [6N]
  fascia_real shift;
  fascia_real scale; ///< mean absolute diagonal: curvature below 1e-12 scale counts as none
  const fascia_bsr *assembled; ///< when set: H + mass_coefficient M assembled, used instead of products
  const unsigned char *frame_moves; ///< [N] the frames assembled (fascia_system_hessian_assemble)
  const unsigned char *mask; ///< [6N] 1 free, 0 constrained
  fascia_real *scratch;      ///< [6N]
  /// when set: P^T A P on the reduced coordinates of rigid organs (point/body.h), the
  /// inner operator on every frame the tissue moves (full_mask), of v prolonged to them
  const struct fascia_pt_bodies *bodies;
  const unsigned char *full_mask;
  fascia_real *prolonged; ///< [6N] P v
  int single;                  ///< products with the assembled matrix's float copy
} fascia_operator;

FASCIA_INTERN void fascia_operator_apply(const fascia_operator *op, const fascia_real *v, fascia_real *out);

/// Preconditioner: inverse blocks [36N] (block Jacobi) or inverse diagonal
/// [6N] (Jacobi) or nothing.
typedef struct fascia_preconditioner {
  fascia_precond kind;
  int32_t frame_count;
  fascia_real *inverse; ///< [36N]
} fascia_preconditioner;

/// Builds the preconditioner of op at the state of the last evaluate.
FASCIA_INTERN void fascia_precond_build(fascia_preconditioner *pc, const fascia_operator *op, fascia_real *blocks);
FASCIA_INTERN void fascia_precond_apply(const fascia_preconditioner *pc, const unsigned char *mask,
                                        const fascia_real *r, fascia_real *z);
/// The same on frames [begin, end) only.
FASCIA_INTERN void fascia_precond_apply_frames(const fascia_preconditioner *pc, const unsigned char *mask,
                                               const fascia_real *r, fascia_real *z, int32_t begin, int32_t end);

typedef struct fascia_cg_result {
  int iterations;
  int negative_curvature; ///< stopped on a direction of non-positive curvature
  fascia_real residual;   ///< final |r| / |b|
} fascia_cg_result;

/// Solves A p = b on the free DOFs by preconditioned CG from p = 0; stops at
/// tolerance (or after exactly max_iterations when fixed), or at the first
/// direction of non-positive curvature, keeping the iterate so far (or the
/// preconditioned residual when that happens at once) so that p stays a
/// descent direction. work: [4 * 6N].
FASCIA_INTERN fascia_cg_result fascia_cg_solve(const fascia_operator *op, const fascia_preconditioner *pc,
                                               const fascia_real *b, fascia_real *p, int max_iterations, int fixed,
                                               fascia_real tolerance, fascia_real *work);

#endif
