// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Direct solution of the Newton systems: the assembled tangent (plus mass and
// Levenberg shift) copied into a band under a reverse Cuthill-McKee ordering
// of the frames, factored by Cholesky. A failed factorization means the
// system is not positive definite; the caller raises the shift and retries.
#ifndef FASCIA_SRC_BANDED_H
#define FASCIA_SRC_BANDED_H

#include "assemble.h"

typedef struct fascia_banded {
  int64_t n;          ///< unknowns (6 per frame)
  int64_t bandwidth;  ///< lower bandwidth in unknowns
  int32_t *order;     ///< [N] frame at each position of the ordering
  int32_t *position;  ///< [N] position of each frame
  fascia_real *band;  ///< [n (bandwidth + 1)]: row r holds columns r-bandwidth .. r
} fascia_banded;

/// Ordering and band size for a block pattern; fails with FASCIA_ERR_MEMORY
/// naming the size when the band would exceed max_bytes.
FASCIA_INTERN fascia_status fascia_banded_create(fascia_ctx *ctx, const fascia_bsr *pattern, int64_t max_bytes,
                                                 fascia_banded *out);
FASCIA_INTERN void fascia_banded_destroy(fascia_banded *b);
/// Estimated factorization cost (flops) of a band: n b^2.
FASCIA_INTERN double fascia_banded_cost(const fascia_banded *b);
/// Loads K + diag(shift * damping) with masked unknowns replaced by identity
/// rows, and factors it in place. Returns 1 on success, 0 if not positive
/// definite.
FASCIA_INTERN int fascia_banded_factor(fascia_banded *b, const fascia_bsr *K, const unsigned char *mask,
                                       const fascia_real *damping, fascia_real shift);
/// Solves the factored system: x = A^-1 rhs (x may alias rhs), [n].
FASCIA_INTERN void fascia_banded_solve(const fascia_banded *b, const fascia_real *rhs, fascia_real *x,
                                       fascia_real *work);

#endif
