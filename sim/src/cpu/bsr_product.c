// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The block-sparse matrix times a vector, the CG's product when the matrix is
// assembled (most of a paper-mode step). A 6x6 block is 36 consecutive
// numbers, row-major: two block rows are 12 numbers, three vectors of 4, so
// each block is 9 four-wide products against the pattern (x0..x3), (x4 x5 x0
// x1), (x2..x5), summed per row of the matrix and folded to 6 numbers once
// per row. Multiplies and adds are separate (no fused multiply-add), so the
// AVX2 and baseline builds of these loops give the same bits.
//
// The float copy keeps the upper blocks only, and its product applies each
// off-diagonal block twice: as itself to its row, and transposed (the same 9
// vectors against the row's own numbers spread as (x0 x0 x0 x0), (x0 x0 x1
// x1), ...) to its column's row. That reads half the bytes. A task of rows
// adds the transposed terms to its own rows as it goes; those for rows past
// its end wait in its slots, which a second pass adds to their rows in task
// order, so the sums do not depend on the thread count either.
#include <stdlib.h>
#include <string.h>

#include "cpu/assemble.h"

typedef double wide_real __attribute__((vector_size(32), aligned(8)));
typedef float wide_float __attribute__((vector_size(16), aligned(4)));

// acc += the four numbers at p times x (pointers, not vector values: a
// vector passed by value would change the baseline build's calling convention)
static inline void add_product(wide_real *acc, const double *p, const wide_real *x) {
  wide_real w;
  memcpy(&w, p, sizeof w);
  *acc += w * *x;
}

// The four floats at p, widened element by element: gcc may compile
// __builtin_convertvector of four floats as two halves through the stack
// instead of one vcvtps2pd, in the innermost loop of CG's products.
static inline void widen(const float *p, wide_real *out) {
  wide_float w;
  memcpy(&w, p, sizeof w);
  const wide_real wide = {w[0], w[1], w[2], w[3]};
  *out = wide;
}

// acc[3q..3q+2] hold block rows 2q and 2q+1 (see the top of the file).
static inline void fold_rows(const wide_real acc[9], fascia_real *out) {
  for (int q = 0; q < 3; ++q) {
    const wide_real a = acc[3 * q], b = acc[3 * q + 1], c = acc[3 * q + 2];
    out[2 * q] = ((a[0] + a[1]) + (a[2] + a[3])) + (b[0] + b[1]);
    out[2 * q + 1] = (b[2] + b[3]) + ((c[0] + c[1]) + (c[2] + c[3]));
  }
}

// Rows [begin, end) of B v (compiled for AVX2 and for the baseline).
WIDE_CLONES static void rows(const fascia_bsr *B, const unsigned char *moves, int32_t begin, int32_t end,
                             const fascia_real *v, fascia_real *out) {
  for (int32_t i = begin; i < end; ++i) {
    wide_real acc[9] = {0};
    const int32_t end_block = fascia_frame_moving(moves, i) ? B->row_offsets[i + 1] : B->row_offsets[i];
    for (int32_t b = B->row_offsets[i]; b < end_block; ++b) {
      if (!fascia_frame_moving(moves, B->cols[b])) continue;
      const fascia_real *x = v + 6 * (int64_t)B->cols[b];
      const wide_real x0 = {x[0], x[1], x[2], x[3]}, x1 = {x[4], x[5], x[0], x[1]}, x2 = {x[2], x[3], x[4], x[5]};
      for (int q = 0; q < 3; ++q) {
        const int64_t at = 36 * (int64_t)b + 12 * q;
        add_product(&acc[3 * q], B->values + at, &x0);
        add_product(&acc[3 * q + 1], B->values + at + 4, &x1);
        add_product(&acc[3 * q + 2], B->values + at + 8, &x2);
      }
    }
    fold_rows(acc, out + 6 * (int64_t)i);
  }
}

void fascia_bsr_apply(const fascia_bsr *B, int threads, const unsigned char *moves, const fascia_real *v,
                      fascia_real *out) {
  const int32_t tasks = (B->rows + FASCIA_BSR_TASK_ROWS - 1) / FASCIA_BSR_TASK_ROWS;
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int32_t t = 0; t < tasks; ++t) {
    const int32_t begin = t * FASCIA_BSR_TASK_ROWS;
    rows(B, moves, begin, begin + FASCIA_BSR_TASK_ROWS < B->rows ? begin + FASCIA_BSR_TASK_ROWS : B->rows, v, out);
  }
}

// ---------------------------------------------------------- the float copy --

// Numbers each task's slots: one per row past the task's end that its upper
// blocks reach, in order of first use; then, per row, the slots that add
// to it, ascending (so in task order). A banded ordering needs few slots,
// any other at most one per upper block.
static fascia_status plan_single(fascia_ctx *ctx, fascia_bsr *B) {
  const int32_t N = B->rows, tasks = (N + FASCIA_BSR_TASK_ROWS - 1) / FASCIA_BSR_TASK_ROWS;
  B->single_offsets = fascia_calloc((int64_t)N + 1, sizeof *B->single_offsets);
  B->task_slots = fascia_calloc((int64_t)tasks + 1, sizeof *B->task_slots);
  B->row_slot_offsets = fascia_calloc((int64_t)N + 1, sizeof *B->row_slot_offsets);
  int32_t *last_task = fascia_calloc((int64_t)N + 1, sizeof *last_task), *slot_of = fascia_calloc((int64_t)N + 1, sizeof *slot_of);
  int fine = B->single_offsets && B->task_slots && B->row_slot_offsets && last_task && slot_of;
  if (fine) {
    B->single_offsets[0] = 0;
    for (int32_t i = 0; i < N; ++i)
      B->single_offsets[i + 1] = B->single_offsets[i] + (B->row_offsets[i + 1] - B->diagonal[i]);
    B->single_slot = fascia_calloc(B->single_offsets[N], sizeof *B->single_slot);
    fine = B->single_slot != NULL;
  }
  int32_t slots = 0;
  for (int32_t i = 0; fine && i <= N; ++i) last_task[i] = -1;
  for (int32_t t = 0; fine && t < tasks; ++t) {
    const int32_t begin = t * FASCIA_BSR_TASK_ROWS, end = begin + FASCIA_BSR_TASK_ROWS < N ? begin + FASCIA_BSR_TASK_ROWS : N;
    B->task_slots[t] = slots;
    for (int32_t i = begin; i < end; ++i)
      for (int32_t b = B->diagonal[i]; b < B->row_offsets[i + 1]; ++b) {
        const int32_t j = B->cols[b];
        int32_t slot = -1;
        if (j >= end) {
          if (last_task[j] != t) {
            last_task[j] = t;
            slot_of[j] = slots++;
            ++B->row_slot_offsets[j + 1];
          }
          slot = slot_of[j];
        }
        B->single_slot[B->single_offsets[i] + b - B->diagonal[i]] = slot;
      }
  }
  if (fine) {
    B->task_slots[tasks] = slots;
    for (int32_t i = 0; i < N; ++i) B->row_slot_offsets[i + 1] += B->row_slot_offsets[i];
    B->row_slots = fascia_calloc(slots, sizeof *B->row_slots);
    B->slot_sums = fascia_calloc(6 * (int64_t)slots, sizeof *B->slot_sums);
    B->values_single = fascia_calloc(36 * B->single_offsets[N], sizeof *B->values_single);
    fine = B->row_slots && B->slot_sums && B->values_single;
  }
  if (fine) { // slots ascend within a task and tasks in order: filling in slot order sorts each row's list
    int32_t *cursor = last_task; // no longer needed as such
    for (int32_t i = 0; i <= N; ++i) cursor[i] = B->row_slot_offsets[i];
    for (int32_t t = 0; t < tasks; ++t) {
      const int32_t begin = t * FASCIA_BSR_TASK_ROWS, end = begin + FASCIA_BSR_TASK_ROWS < N ? begin + FASCIA_BSR_TASK_ROWS : N;
      for (int32_t i = begin; i < end; ++i)
        for (int32_t b = B->diagonal[i]; b < B->row_offsets[i + 1]; ++b) {
          const int32_t slot = B->single_slot[B->single_offsets[i] + b - B->diagonal[i]], j = B->cols[b];
          if (slot >= 0 && (cursor[j] == B->row_slot_offsets[j] || B->row_slots[cursor[j] - 1] != slot))
            B->row_slots[cursor[j]++] = slot; // a task's blocks of row j share one slot
        }
    }
  }
  free(last_task);
  free(slot_of);
  if (fine) return FASCIA_OK;
  fascia_bsr_single_release(B); // planned again on the next call
  return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "assembly: out of memory for a float copy of %lld blocks",
                     (long long)B->blocks);
}

void fascia_bsr_single_release(fascia_bsr *B) {
  free(B->values_single), free(B->single_offsets), free(B->single_slot), free(B->task_slots);
  free(B->row_slot_offsets), free(B->row_slots), free(B->slot_sums);
  B->values_single = NULL, B->single_offsets = NULL, B->single_slot = NULL, B->task_slots = NULL;
  B->row_slot_offsets = NULL, B->row_slots = NULL, B->slot_sums = NULL;
}

fascia_status fascia_bsr_make_single(fascia_ctx *ctx, fascia_bsr *B, int threads) {
  if (!B->values_single) {
    const fascia_status status = plan_single(ctx, B);
    if (status != FASCIA_OK) return status;
  }
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int32_t i = 0; i < B->rows; ++i) {
    const int64_t n = 36 * (int64_t)(B->row_offsets[i + 1] - B->diagonal[i]);
    const fascia_real *from = B->values + 36 * (int64_t)B->diagonal[i];
    float *to = B->values_single + 36 * B->single_offsets[i];
    for (int64_t k = 0; k < n; ++k) to[k] = (float)from[k];
  }
  return FASCIA_OK;
}

// Task t of the float copy's product: its rows' own sums plus the
// transposed terms of its earlier rows; the others' go to its slots.
WIDE_CLONES static void single_task(const fascia_bsr *B, const unsigned char *moves, int32_t t, const fascia_real *v,
                                    fascia_real *out) {
  const int32_t begin = t * FASCIA_BSR_TASK_ROWS;
  const int32_t end = begin + FASCIA_BSR_TASK_ROWS < B->rows ? begin + FASCIA_BSR_TASK_ROWS : B->rows;
  fascia_real own[6 * FASCIA_BSR_TASK_ROWS];
  memset(own, 0, sizeof own);
  memset(B->slot_sums + 6 * (int64_t)B->task_slots[t], 0,
         6 * (size_t)(B->task_slots[t + 1] - B->task_slots[t]) * sizeof *B->slot_sums);
  for (int32_t i = begin; i < end; ++i) {
    wide_real acc[9] = {0};
    const fascia_real *y = v + 6 * (int64_t)i;
    // row i's numbers spread against the 9 vectors of a block (named, not
    // an array: gcc 12 then warns they may be uninitialized)
    const wide_real y0 = {y[0], y[0], y[0], y[0]}, y01 = {y[0], y[0], y[1], y[1]}, y1 = {y[1], y[1], y[1], y[1]};
    const wide_real y2 = {y[2], y[2], y[2], y[2]}, y23 = {y[2], y[2], y[3], y[3]}, y3 = {y[3], y[3], y[3], y[3]};
    const wide_real y4 = {y[4], y[4], y[4], y[4]}, y45 = {y[4], y[4], y[5], y[5]}, y5 = {y[5], y[5], y[5], y[5]};
    const int32_t end_block = fascia_frame_moving(moves, i) ? B->row_offsets[i + 1] : B->diagonal[i];
    for (int32_t b = B->diagonal[i]; b < end_block; ++b) {
      const int32_t j = B->cols[b];
      if (!fascia_frame_moving(moves, j)) continue;
      const int64_t u = B->single_offsets[i] + b - B->diagonal[i];
      const float *p = B->values_single + 36 * u;
      wide_real w[9];
      for (int k = 0; k < 9; ++k) widen(p + 4 * k, &w[k]);
      const fascia_real *x = v + 6 * (int64_t)j;
      const wide_real x0 = {x[0], x[1], x[2], x[3]}, x1 = {x[4], x[5], x[0], x[1]}, x2 = {x[2], x[3], x[4], x[5]};
      for (int q = 0; q < 3; ++q) {
        acc[3 * q] += w[3 * q] * x0;
        acc[3 * q + 1] += w[3 * q + 1] * x1;
        acc[3 * q + 2] += w[3 * q + 2] * x2;
      }
      if (j == i) continue;
      // transposed: T0 holds columns 0-3, T1 columns (4 5 0 1), T2 columns 2-5
      const wide_real T0 = (w[0] * y0 + w[3] * y2) + w[6] * y4;
      const wide_real T1 = (w[1] * y01 + w[4] * y23) + w[7] * y45;
      const wide_real T2 = (w[2] * y1 + w[5] * y3) + w[8] * y5;
      const int32_t slot = B->single_slot[u];
      fascia_real *o = slot < 0 ? own + 6 * (j - begin) : B->slot_sums + 6 * (int64_t)slot;
      o[0] += T0[0] + T1[2];
      o[1] += T0[1] + T1[3];
      o[2] += T0[2] + T2[0];
      o[3] += T0[3] + T2[1];
      o[4] += T1[0] + T2[2];
      o[5] += T1[1] + T2[3];
    }
    fascia_real sum[6];
    fold_rows(acc, sum);
    for (int c = 0; c < 6; ++c) out[6 * (int64_t)i + c] = sum[c] + own[6 * (i - begin) + c];
  }
}

void fascia_bsr_apply_single(const fascia_bsr *B, int threads, const unsigned char *moves, const fascia_real *v,
                             fascia_real *out) {
  const int32_t tasks = (B->rows + FASCIA_BSR_TASK_ROWS - 1) / FASCIA_BSR_TASK_ROWS;
#pragma omp parallel num_threads(threads)
  {
#pragma omp for schedule(static)
    for (int32_t t = 0; t < tasks; ++t) single_task(B, moves, t, v, out);
    // the slots, each row's in task order
#pragma omp for schedule(static)
    for (int32_t i = 0; i < B->rows; ++i)
      for (int32_t k = B->row_slot_offsets[i]; k < B->row_slot_offsets[i + 1]; ++k)
        for (int c = 0; c < 6; ++c) out[6 * (int64_t)i + c] += B->slot_sums[6 * (int64_t)B->row_slots[k] + c];
  }
}
