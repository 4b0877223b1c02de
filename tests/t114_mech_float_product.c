// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The float copy keeps the upper blocks of a symmetric block matrix and
// applies each one as itself and transposed, in tasks of rows whose terms
// for later rows wait in slots (sim/src/cpu/bsr_product.c). On random symmetric
// patterns of several tasks, banded and scattered (slots far from their
// task), rows of only a diagonal, and row counts that are and are not a
// multiple of a task: its product is the double product of the same float
// values to the rounding of a sum in another order, the same bits for 1 to
// 5 threads, 0 on frames that do not move and, on those that do, what the
// whole matrix gives a vector zero elsewhere; made again after the values
// change, it multiplies by the new values.
#include <stdlib.h>
#include <string.h>

#include "cpu/assemble.h"
#include "check.h"
#include "random_model.h"

// A random symmetric pattern of N rows: each row the diagonal and, with
// `band` > 0, up to 6 neighbours within band rows, else anywhere; some rows
// only the diagonal. Values random, the lower blocks the upper transposed.
static int make_matrix(int32_t N, int32_t band, unsigned long long seed, fascia_bsr *B) {
  memset(B, 0, sizeof *B);
  unsigned long long st = seed;
  unsigned char *link = calloc((size_t)N * N, 1);
  if (!link) return 1;
  for (int32_t i = 0; i < N; ++i) {
    link[(size_t)i * N + i] = 1;
    if (rnd_uniform(&st, 0, 1) < 0.1) continue; // only the diagonal (unless a later row links it)
    for (int k = 0; k < 6; ++k) {
      int32_t j = band > 0 ? i + (int32_t)rnd_uniform(&st, -band, band + 1) : (int32_t)rnd_uniform(&st, 0, N);
      if (j < 0 || j >= N) continue;
      link[(size_t)i * N + j] = link[(size_t)j * N + i] = 1;
    }
  }
  B->rows = N;
  B->row_offsets = calloc((size_t)N + 1, sizeof(int32_t));
  B->diagonal = calloc((size_t)N, sizeof(int32_t));
  for (int32_t i = 0; i < N; ++i)
    for (int32_t j = 0; j < N; ++j) B->row_offsets[i + 1] += link[(size_t)i * N + j];
  for (int32_t i = 0; i < N; ++i) B->row_offsets[i + 1] += B->row_offsets[i];
  B->blocks = B->row_offsets[N];
  B->cols = calloc((size_t)B->blocks, sizeof(int32_t));
  B->values = calloc(36 * (size_t)B->blocks, sizeof(double));
  for (int32_t i = 0, b = 0; i < N; ++i)
    for (int32_t j = 0; j < N; ++j)
      if (link[(size_t)i * N + j]) {
        if (j == i) B->diagonal[i] = b;
        B->cols[b++] = j;
      }
  for (int32_t i = 0; i < N; ++i) // upper blocks random (diagonal ones symmetric)
    for (int32_t b = B->diagonal[i]; b < B->row_offsets[i + 1]; ++b)
      for (int r = 0; r < 6; ++r)
        for (int c = B->cols[b] == i ? r : 0; c < 6; ++c)
          B->values[36 * (int64_t)b + 6 * r + c] = B->values[36 * (int64_t)b + 6 * c + r] = rnd_uniform(&st, -1, 1);
  for (int32_t i = 0; i < N; ++i) // lower blocks: the upper ones transposed
    for (int32_t b = B->row_offsets[i]; b < B->diagonal[i]; ++b) {
      const int32_t j = B->cols[b];
      int32_t u = B->diagonal[j];
      while (B->cols[u] != i) ++u;
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c) B->values[36 * (int64_t)b + 6 * r + c] = B->values[36 * (int64_t)u + 6 * c + r];
    }
  free(link);
  return 0;
}

static int run_case(fascia_ctx *ctx, int32_t N, int32_t band, unsigned long long seed) {
  fascia_bsr B;
  CHECK(make_matrix(N, band, seed, &B) == 0);
  const int64_t n = 6 * (int64_t)N;
  double *v = malloc(n * sizeof(double)), *ref = malloc(n * sizeof(double)), *out = malloc(n * sizeof(double));
  double *other = malloc(n * sizeof(double)), *bound = malloc(n * sizeof(double));
  unsigned char *moves = malloc((size_t)N);
  unsigned long long st = seed * 17 + 3;
  for (int64_t k = 0; k < n; ++k) v[k] = rnd_uniform(&st, -1, 1);
  for (int round = 0; round < 2; ++round) {
    if (round == 1) // new values in the same pattern: the copy follows them
      for (int64_t e = 0; e < 36 * B.blocks; ++e) B.values[e] *= -0.5;
    CHECK_OK(fascia_bsr_make_single(ctx, &B, 2), ctx);
    // the reference: the double product of the values the float copy holds
    double *exact = malloc(36 * (size_t)B.blocks * sizeof(double));
    memcpy(exact, B.values, 36 * (size_t)B.blocks * sizeof(double));
    for (int64_t e = 0; e < 36 * B.blocks; ++e) B.values[e] = (float)B.values[e];
    fascia_bsr_apply(&B, 1, NULL, v, ref);
    for (int64_t e = 0; e < 36 * B.blocks; ++e) B.values[e] = fabs(B.values[e]);
    for (int64_t k = 0; k < n; ++k) other[k] = fabs(v[k]);
    fascia_bsr_apply(&B, 1, NULL, other, bound); // sum of |terms| per row
    memcpy(B.values, exact, 36 * (size_t)B.blocks * sizeof(double));
    free(exact);
    fascia_bsr_apply_single(&B, 1, NULL, v, out);
    for (int64_t k = 0; k < n; ++k) CHECK_NEAR(out[k], ref[k], 0, 1e-13 * bound[k]);
    for (int threads = 2; threads <= 5; ++threads) {
      fascia_bsr_apply_single(&B, threads, NULL, v, other);
      CHECK(memcmp(out, other, n * sizeof(double)) == 0);
    }
  }
  // frames that move: the rows of the others are 0, the moving rows are the
  // whole product of v zeroed on the others (the sums skip only zeros)
  for (int32_t i = 0; i < N; ++i) moves[i] = rnd_uniform(&st, 0, 1) < 0.6;
  for (int64_t k = 0; k < n; ++k) other[k] = moves[k / 6] ? v[k] : 0;
  fascia_bsr_apply_single(&B, 3, NULL, other, ref);
  fascia_bsr_apply_single(&B, 3, moves, v, out);
  for (int64_t k = 0; k < n; ++k) CHECK(out[k] == (moves[k / 6] ? ref[k] : 0));
  free(v), free(ref), free(out), free(other), free(bound), free(moves);
  fascia_bsr_destroy(&B);
  return 0;
}

int main(void) {
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&def, &ctx) != FASCIA_OK) return 1;
  int failed = 0;
  failed |= run_case(ctx, 1, 0, 1);                          // one row
  failed |= run_case(ctx, FASCIA_BSR_TASK_ROWS, 3, 2);       // one whole task
  failed |= run_case(ctx, 5 * FASCIA_BSR_TASK_ROWS, 20, 3);  // banded, whole tasks
  failed |= run_case(ctx, 5 * FASCIA_BSR_TASK_ROWS + 17, 90, 4); // banded past one task, a part task
  failed |= run_case(ctx, 300, 0, 5);                        // scattered: slots far from their task
  failed |= run_case(ctx, 700, 0, 6);
  fascia_ctx_destroy(&ctx);
  return failed | CHECK_RESULT();
}
