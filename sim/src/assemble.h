// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The tangent and mass as assembled 6x6-block sparse matrices (block CSR over
// frames). Blocks come from the same per-sample products as the matrix-free
// operator (sim/point/sample.h applied to unit vectors), so the two can never
// disagree; each row is filled by one thread from the reverse table, in a
// fixed order (determinism).
#ifndef FASCIA_SRC_ASSEMBLE_H
#define FASCIA_SRC_ASSEMBLE_H

#include "system.h"

/// Block CSR: row i has blocks cols[row_offsets[i] .. row_offsets[i+1]-1]
/// (ascending frame indices), values 36 per block, row-major.
typedef struct fascia_bsr {
  int32_t rows;
  int32_t *row_offsets; ///< [rows+1]
  int32_t *cols;        ///< [blocks]
  int32_t *diagonal;    ///< [rows] position of the diagonal block
  fascia_real *values;  ///< [36 blocks]
  float *values_single; ///< [36 blocks] a float copy for products, when asked for (NULL otherwise)
  int64_t blocks;
  // Assembly plan: every sample's n x n local blocks, numbered e =
  // local_offsets[s] + a n + b (sample order), are summed into their BSR
  // block in ascending e, so the sums do not depend on the thread count.
  int64_t *local_offsets;    ///< [S+1]
  int32_t *local_block;      ///< [E] BSR block of local block e
  int64_t *contrib_offsets;  ///< [blocks+1]
  int64_t *contrib;          ///< [E] local blocks of each BSR block, ascending
  int64_t *cursor;           ///< [blocks] scratch
  fascia_real *chunk;        ///< [36 chunk_capacity] local blocks of one chunk of samples
  int64_t chunk_capacity;    ///< FASCIA_ASSEMBLY_CHUNK, or the largest sample's n^2
} fascia_bsr;

/// Whether frame i moves, for the moves arrays below (NULL: every frame).
static inline int fascia_frame_moving(const unsigned char *moves, int32_t i) { return !moves || moves[i]; }

/// Local blocks computed per pass of the assembly (bounds its scratch: 4.7 MB,
/// which the last-level cache keeps between the pass that writes the blocks
/// and the one that adds them up: the static 20x3x3 hex cantilever 28 -> 22
/// ms of assembly against 32768; t3-s34610 31-33 ms either way; smaller
/// chunks cost the paper rows more passes, 8192: 38 ms).
#define FASCIA_ASSEMBLY_CHUNK 16384

/// Pattern of frame pairs that share a sample (every frame has its diagonal).
FASCIA_INTERN fascia_status fascia_bsr_create(fascia_ctx *ctx, const fascia_model *model, fascia_bsr *out);
FASCIA_INTERN void fascia_bsr_destroy(fascia_bsr *bsr);
/// out = B v; with moves ([rows], NULL: all), only the rows and columns of
/// moving frames (the others are not assembled): out is 0 on other rows.
FASCIA_INTERN void fascia_bsr_apply(const fascia_bsr *bsr, int threads, const unsigned char *moves,
                                    const fascia_real *v, fascia_real *out);
/// Rounds the values to the float copy (allocated on first use); FASCIA_ERR_MEMORY if it cannot be.
FASCIA_INTERN fascia_status fascia_bsr_make_single(fascia_ctx *ctx, fascia_bsr *bsr, int threads);
/// out = B v with the float copy (products summed in double); moves as above.
FASCIA_INTERN void fascia_bsr_apply_single(const fascia_bsr *bsr, int threads, const unsigned char *moves,
                                           const fascia_real *v, fascia_real *out);

/// Fills bsr->values with the symmetric Hessian H at the state of the last
/// fascia_system_evaluate (what fascia_system_hessian_apply applies).
/// moves: [frames] nonzero for a frame the step may move; a block of any
/// other frame is left zero, and no work is spent on it (in organ scenes
/// most blocks couple a fixed frame). NULL: every frame.
FASCIA_INTERN void fascia_system_hessian_assemble(fascia_system *sys, const unsigned char *moves, fascia_bsr *bsr);
/// Adds coefficient * M (consistent mass at the snapshot) to bsr->values, on
/// the blocks of moving frames (moves as above).
FASCIA_INTERN void fascia_system_mass_assemble_add(fascia_system *sys, const unsigned char *moves,
                                                   fascia_real coefficient, fascia_bsr *bsr);

#endif
