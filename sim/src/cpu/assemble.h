// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The tangent and mass as assembled 6x6-block sparse matrices (block CSR over
// frames). Blocks come from the per-sample terms of the matrix-free
// operator (sim/point/sample.h), in closed form or applied to unit vectors,
// and the rotation smoothing's from its frame graph (system.h); tests/t112
// checks the two operators agree. Each row is filled by one thread, in a
// fixed order (determinism).
#ifndef FASCIA_SRC_ASSEMBLE_H
#define FASCIA_SRC_ASSEMBLE_H

#include "cpu/system.h"
#include "cpu/wide.h"

/// Block CSR: row i has blocks cols[row_offsets[i] .. row_offsets[i+1]-1]
/// (ascending frame indices), values 36 per block, row-major.
typedef struct fascia_bsr {
  int32_t rows;
  int32_t *row_offsets; ///< [rows+1]
  int32_t *cols;        ///< [blocks]
  int32_t *diagonal;    ///< [rows] position of the diagonal block
  fascia_real *values;  ///< [36 blocks]
  int64_t blocks;
  // The float copy for products, when asked for (NULL otherwise): the upper
  // blocks alone (the matrix is symmetric), row i's blocks diagonal[i] ..
  // row_offsets[i+1]-1 from single_offsets[i] on. Its product runs over
  // fixed tasks of FASCIA_BSR_TASK_ROWS rows. What a task's blocks add,
  // transposed, to a row past its end goes to a slot of the task's own (one
  // per such row) and is added to the row once all tasks are done.
  float *values_single;      ///< [36 upper blocks]
  int64_t *single_offsets;   ///< [rows+1]
  int32_t *single_slot;      ///< [upper blocks] slot of a block's transposed term, -1: none or in its task
  int32_t *task_slots;       ///< [tasks+1] each task's slots, in task order
  int32_t *row_slot_offsets; ///< [rows+1] the slots that add to each row, ascending
  int32_t *row_slots;        ///< [slots]
  fascia_real *slot_sums;    ///< [6 slots]
  // Assembly plan: every sample's local blocks (a, b), a <= b, numbered e =
  // local_offsets[s] + fascia_pt_upper_block(n, a, b) (sample order), are
  // summed into their upper BSR block (i <= j) in ascending e, so the sums
  // do not depend on the thread count; the lower blocks are their mirror.
  // A chunk's local blocks are listed by the BSR block they add to, in
  // the order they are added: read in sequence, not looked up per block.
  int64_t *local_offsets;            ///< [S+1]
  int32_t *local_block;              ///< [E] BSR block of local block e
  int32_t *mirror;                   ///< [blocks] the upper block a lower block is the transpose of, -1: upper
  int32_t *block_row;                ///< [blocks] the row of each block
  int32_t chunk_count;               ///< passes: chunks of whole samples whose local blocks fit the scratch
  int32_t *chunk_samples;            ///< [chunk_count+1] first sample of each chunk
  int64_t *chunk_block_offsets;      ///< [chunk_count+1]
  int32_t *chunk_blocks;             ///< [T] the upper BSR blocks each chunk adds to, ascending
  int64_t *chunk_entry_offsets;      ///< [T+1] the entries of chunk_blocks[t]
  int32_t *chunk_entries;            ///< [E] local blocks of each, ascending e, counted from the chunk's first
  unsigned char *chunk_entry_transposed; ///< [E] whether an entry adds transposed (its frames in falling order)
  fascia_real *chunk;                ///< [36 chunk_capacity] local blocks of one chunk of samples
  int64_t chunk_capacity;            ///< FASCIA_ASSEMBLY_CHUNK, or the largest sample's n (n + 1) / 2
  // Who adds what, for a team of adds_team threads: thread u of a team
  // of T computes the u-th of T near-equal runs of each chunk's samples
  // (team_share in assemble.c), then adds the chunk's blocks whose entries it
  // wrote the most of, up to its share of the chunk's entries (plan_adds),
  // so that few of the entries it reads were written by another core (a
  // cache line that changes cores costs far more than its arithmetic: on
  // t3-s34610, 60 % of the entries crossed with both loops split in order,
  // and 2 threads computed the local blocks slower than one). Who adds a
  // block does not change its sum: it adds in ascending e.
  int32_t adds_team;                 ///< the team (> 1) the lists are for, 0: none yet
  int64_t *add_offsets;              ///< [chunk_count adds_team + 1] each chunk's, then thread's, list
  int32_t *add_blocks;               ///< [T] positions t - chunk_block_offsets[k] in chunk k's blocks
} fascia_bsr;

/// Whether frame i moves, for the moves arrays below (NULL: every frame).
static inline int fascia_frame_moving(const unsigned char *moves, int32_t i) { return !moves || moves[i]; }

/// Local blocks computed per pass of the assembly (bounds its scratch to
/// 0.6 MB, which a core's own cache keeps between the loop that writes the
/// blocks and the one that adds them up). Each pass visits only the blocks
/// its samples add to, so small passes cost little and a smaller bound
/// is not slower than a larger one.
#define FASCIA_ASSEMBLY_CHUNK 2048

/// Pattern of frame pairs that share a sample (every frame has its diagonal).
FASCIA_INTERN fascia_status fascia_bsr_create(fascia_ctx *ctx, const fascia_model *model, fascia_bsr *out);
FASCIA_INTERN void fascia_bsr_destroy(fascia_bsr *bsr);
/// out = B v; with moves ([rows], NULL: all), only the rows and columns of
/// moving frames (the others are not assembled): out is 0 on other rows.
FASCIA_INTERN void fascia_bsr_apply(const fascia_bsr *bsr, int threads, const unsigned char *moves,
                                    const fascia_real *v, fascia_real *out);
/// Rows per task of the products: fixed, so that their sums do not depend
/// on the thread count.
#define FASCIA_BSR_TASK_ROWS 64
/// Rounds the upper blocks of the values to the float copy (allocated on
/// first use); FASCIA_ERR_MEMORY if it cannot be.
FASCIA_INTERN fascia_status fascia_bsr_make_single(fascia_ctx *ctx, fascia_bsr *bsr, int threads);
/// Frees the float copy and its plan (fascia_bsr_destroy does too).
FASCIA_INTERN void fascia_bsr_single_release(fascia_bsr *bsr);
/// out = B v with the float copy (products summed in double; each upper
/// block applied as itself and as its transpose); moves as above.
FASCIA_INTERN void fascia_bsr_apply_single(const fascia_bsr *bsr, int threads, const unsigned char *moves,
                                           const fascia_real *v, fascia_real *out);

/// Fills bsr->values with the symmetric Hessian H at the state of the last
/// fascia_system_evaluate (what fascia_system_hessian_apply applies).
/// moves: [frames] nonzero for a frame the step may move; a block of any
/// other frame is left zero, and no work is spent on it (in organ scenes
/// most blocks couple a fixed frame). NULL: every frame. Returns 0, the
/// matrix incomplete, when out of memory for a thread's scratch.
FASCIA_INTERN int fascia_system_hessian_assemble(fascia_system *sys, const unsigned char *moves, fascia_bsr *bsr);
/// Adds coefficient * M (consistent mass at the snapshot) to bsr->values, on
/// the blocks of moving frames (moves as above).
FASCIA_INTERN void fascia_system_mass_assemble_add(fascia_system *sys, const unsigned char *moves,
                                                   fascia_real coefficient, fascia_bsr *bsr);

#endif
