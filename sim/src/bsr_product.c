// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The block-sparse matrix times a vector, the CG's product when the matrix is
// assembled (most of a paper-mode step). A 6x6 block is 36 consecutive
// numbers, row-major: two block rows are 12 numbers, three vectors of 4, so
// each block is 9 four-wide products against the pattern (x0..x3), (x4 x5 x0
// x1), (x2..x5), summed per row of the matrix and folded to 6 numbers once
// per row. Multiplies and adds are separate (no fused multiply-add), so the
// AVX2 and baseline builds of this loop give the same bits.
#include <string.h>

#include "assemble.h"

typedef double wide_real __attribute__((vector_size(32), aligned(8)));
typedef float wide_float __attribute__((vector_size(16), aligned(4)));

#define ROWS_PER_TASK 64 // rows per unit of work: a thread's rows are contiguous

// acc += the four numbers at p times x (pointers, not vector values: a
// vector passed by value would change the baseline build's calling convention)
static inline void add_product(wide_real *acc, const double *p, const wide_real *x) {
  wide_real w;
  memcpy(&w, p, sizeof w);
  *acc += w * *x;
}

// Widened element by element: gcc 12 compiles __builtin_convertvector of
// four floats as two halves through the stack, not one vcvtps2pd (t3-s34610's
// 60 products: 29 cycles a block in cache, most of it those halves).
static inline void add_product_float(wide_real *acc, const float *p, const wide_real *x) {
  wide_float w;
  memcpy(&w, p, sizeof w);
  const wide_real wide = {w[0], w[1], w[2], w[3]};
  *acc += wide * *x;
}

// acc[3q..3q+2] hold block rows 2q and 2q+1 (see the top of the file).
static inline void fold_rows(const wide_real acc[9], fascia_real *out) {
  for (int q = 0; q < 3; ++q) {
    const wide_real a = acc[3 * q], b = acc[3 * q + 1], c = acc[3 * q + 2];
    out[2 * q] = ((a[0] + a[1]) + (a[2] + a[3])) + (b[0] + b[1]);
    out[2 * q + 1] = (b[2] + b[3]) + ((c[0] + c[1]) + (c[2] + c[3]));
  }
}

// Rows [begin, end) of B v, with the float copy of the values where single
// (compiled for AVX2 and for the baseline).
WIDE_CLONES static void rows(const fascia_bsr *B, int single, const unsigned char *moves, int32_t begin, int32_t end,
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
        if (single) {
          add_product_float(&acc[3 * q], B->values_single + at, &x0);
          add_product_float(&acc[3 * q + 1], B->values_single + at + 4, &x1);
          add_product_float(&acc[3 * q + 2], B->values_single + at + 8, &x2);
        } else {
          add_product(&acc[3 * q], B->values + at, &x0);
          add_product(&acc[3 * q + 1], B->values + at + 4, &x1);
          add_product(&acc[3 * q + 2], B->values + at + 8, &x2);
        }
      }
    }
    fold_rows(acc, out + 6 * (int64_t)i);
  }
}

static void apply(const fascia_bsr *B, int single, int threads, const unsigned char *moves, const fascia_real *v,
                  fascia_real *out) {
  const int32_t tasks = (B->rows + ROWS_PER_TASK - 1) / ROWS_PER_TASK;
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int32_t t = 0; t < tasks; ++t) {
    const int32_t begin = t * ROWS_PER_TASK, end = begin + ROWS_PER_TASK < B->rows ? begin + ROWS_PER_TASK : B->rows;
    rows(B, single, moves, begin, end, v, out);
  }
}

void fascia_bsr_apply(const fascia_bsr *B, int threads, const unsigned char *moves, const fascia_real *v,
                      fascia_real *out) {
  apply(B, 0, threads, moves, v, out);
}

void fascia_bsr_apply_single(const fascia_bsr *B, int threads, const unsigned char *moves, const fascia_real *v,
                             fascia_real *out) {
  apply(B, 1, threads, moves, v, out);
}
