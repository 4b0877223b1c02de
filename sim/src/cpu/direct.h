// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Direct solution of the Newton systems by CHOLMOD's supernodal sparse
// Cholesky (SuiteSparse) on OpenBLAS. The pattern of the assembled tangent
// and the free unknowns are fixed for a run, so the ordering and the
// symbolic factorization are done once, at creation; every Newton iteration
// then only refactors the numbers. A failed factorization means the system
// (K + mass + Levenberg shift) is not positive definite; the caller raises
// the shift and retries.
#ifndef FASCIA_SRC_DIRECT_H
#define FASCIA_SRC_DIRECT_H

#include "cpu/assemble.h"

typedef struct fascia_direct fascia_direct;

/// Orders the free unknowns (mask[k] != 0; the rest are kept at zero) of a
/// block pattern, AMD or METIS on the frame graph, and analyses the
/// factorization. FASCIA_ERR_MEMORY naming the size when it cannot be done.
FASCIA_INTERN fascia_status fascia_direct_create(fascia_ctx *ctx, const fascia_bsr *pattern,
                                                 const unsigned char *mask, fascia_direct **out);
FASCIA_INTERN void fascia_direct_destroy(fascia_direct **d);
/// Floating-point operations of one factorization, from the analysis.
FASCIA_INTERN double fascia_direct_flops(const fascia_direct *d);
/// Whether the factor is supernodal (else simplicial: CHOLMOD's choice from
/// the fronts' density; each kind is given the triangle it reads as it is).
FASCIA_INTERN int fascia_direct_supernodal(const fascia_direct *d);
/// Nonzeros of the factor.
FASCIA_INTERN double fascia_direct_factor_nonzeros(const fascia_direct *d);
/// Whether the last analysis was for this mask (a factorization then still fits it).
FASCIA_INTERN int fascia_direct_mask_is(const fascia_direct *d, const unsigned char *mask);
/// The values the last fascia_direct_factor factored (the matrix with its
/// shift), to store them: their count, and the values in the walk of the
/// creation's pattern (frame i's row a, then its blocks with frames j >= i),
/// which does not depend on the ordering; and factoring such values again:
/// the same bits give the same factor (1; 0 if not positive definite).
FASCIA_INTERN int64_t fascia_direct_values_count(const fascia_direct *d);
FASCIA_INTERN void fascia_direct_values_save(const fascia_direct *d, const fascia_bsr *pattern, double *out);
FASCIA_INTERN int fascia_direct_values_load(fascia_direct *d, const fascia_bsr *pattern, const double *in);
/// Factors K + diag(shift * damping) over the unknowns with mask set (K of
/// the creation's pattern; one triangle of it is read; a mask other than the
/// analysed one is analysed first). Returns 1 on success, 0 when it is not
/// positive definite (or not finite), -1 when the new analysis failed (the
/// message is in ctx).
FASCIA_INTERN int fascia_direct_factor(fascia_direct *d, fascia_ctx *ctx, const fascia_bsr *K,
                                       const unsigned char *mask, const fascia_real *damping, fascia_real shift);
/// Factors the matrix of the last fascia_direct_factor again with another
/// shift: only its diagonal is written again, from the unshifted one kept
/// (the same values as fascia_direct_factor with the same K; a retry costs
/// the factorization alone). 1 on success, 0 when not positive definite,
/// not finite, or nothing was factored since the creation or a values load.
FASCIA_INTERN int fascia_direct_refactor(fascia_direct *d, const fascia_real *damping, fascia_real shift);
/// x = A^-1 rhs on the free unknowns of the last successful factorization,
/// 0 on the others; x may alias rhs. [6N]
FASCIA_INTERN void fascia_direct_solve(fascia_direct *d, const fascia_real *rhs, fascia_real *x);

#endif
