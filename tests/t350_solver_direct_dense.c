// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The sparse direct solver (CHOLMOD) against a dense Cholesky of the same
// system: random symmetric positive definite matrices on the block patterns
// of random models, with fixed frames, single fixed unknowns and a
// Levenberg shift, solved to round-off; the fixed unknowns come out zero.
// Refactoring the same analysis with other numbers gives that system's
// solution (the symbolic factorization is reused).
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "cpu/direct.h"
#include "random_model.h"
#include "scenes.h"

// Random symmetric values on the pattern, diagonally dominant (so positive
// definite) by `margin` on each row.
static void random_spd(fascia_bsr *K, unsigned long long *st, double margin) {
  memset(K->values, 0, 36 * (size_t)K->blocks * sizeof(double));
  for (int32_t i = 0; i < K->rows; ++i)
    for (int32_t b = K->row_offsets[i]; b < K->row_offsets[i + 1]; ++b) {
      const int32_t j = K->cols[b];
      if (j < i) continue;
      double *v = K->values + 36 * (int64_t)b;
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c)
          if (j > i || c > r) v[6 * r + c] = rnd_uniform(st, -1, 1);
      if (j == i)
        for (int r = 0; r < 6; ++r)
          for (int c = 0; c < r; ++c) v[6 * r + c] = v[6 * c + r];
      else { // the transposed block of row j
        int32_t t = K->row_offsets[j];
        while (K->cols[t] != i) ++t;
        for (int r = 0; r < 6; ++r)
          for (int c = 0; c < 6; ++c) K->values[36 * (int64_t)t + 6 * c + r] = v[6 * r + c];
      }
    }
  for (int32_t i = 0; i < K->rows; ++i)
    for (int r = 0; r < 6; ++r) {
      double sum = 0;
      for (int32_t b = K->row_offsets[i]; b < K->row_offsets[i + 1]; ++b)
        for (int c = 0; c < 6; ++c) sum += fabs(K->values[36 * (int64_t)b + 6 * r + c]);
      K->values[36 * (int64_t)K->diagonal[i] + 7 * r] = sum + margin;
    }
}

// x = A^-1 b over the unknowns with mask set, A = K + shift diag(damping), by
// a dense Cholesky; 0 elsewhere. Returns 0 if A is not positive definite.
static int dense_solve(const fascia_bsr *K, const unsigned char *mask, const double *damping, double shift,
                       const double *b, double *x) {
  const int n = 6 * K->rows;
  double *A = calloc((size_t)n * n, sizeof(double)), *y = calloc((size_t)n, sizeof(double));
  for (int32_t i = 0; i < K->rows; ++i)
    for (int32_t blk = K->row_offsets[i]; blk < K->row_offsets[i + 1]; ++blk)
      for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c) A[(6 * i + r) * n + 6 * K->cols[blk] + c] = K->values[36 * (int64_t)blk + 6 * r + c];
  for (int k = 0; k < n; ++k) {
    A[k * n + k] += shift * damping[k];
    if (!mask[k]) // identity row and column: the fixed unknown stays 0
      for (int l = 0; l < n; ++l) A[k * n + l] = A[l * n + k] = l == k;
  }
  int ok = 1;
  for (int j = 0; j < n && ok; ++j) { // A = L L^T in the lower triangle
    double d = A[j * n + j];
    for (int k = 0; k < j; ++k) d -= A[j * n + k] * A[j * n + k];
    if (!(d > 0)) ok = 0;
    A[j * n + j] = sqrt(d);
    for (int i = j + 1; i < n && ok; ++i) {
      double s = A[i * n + j];
      for (int k = 0; k < j; ++k) s -= A[i * n + k] * A[j * n + k];
      A[i * n + j] = s / A[j * n + j];
    }
  }
  for (int i = 0; i < n && ok; ++i) {
    double s = mask[i] ? b[i] : 0;
    for (int k = 0; k < i; ++k) s -= A[i * n + k] * y[k];
    y[i] = s / A[i * n + i];
  }
  for (int i = n - 1; i >= 0 && ok; --i) {
    double s = y[i];
    for (int k = i + 1; k < n; ++k) s -= A[k * n + i] * x[k];
    x[i] = s / A[i * n + i];
  }
  free(A);
  free(y);
  return ok;
}

static void check_against_dense(fascia_ctx *ctx, fascia_direct *d, const fascia_bsr *K, const unsigned char *mask,
                                const double *damping, double shift, const double *b) {
  const int n = 6 * K->rows;
  double *x = malloc((size_t)n * sizeof(double)), *ref = malloc((size_t)n * sizeof(double));
  CHECK(dense_solve(K, mask, damping, shift, b, ref));
  CHECK(fascia_direct_factor(d, ctx, K, mask, damping, shift) == 1);
  fascia_direct_solve(d, b, x);
  double diff = 0, size = 0;
  for (int k = 0; k < n; ++k) {
    diff += (x[k] - ref[k]) * (x[k] - ref[k]);
    size += ref[k] * ref[k];
    if (!mask[k]) CHECK(x[k] == 0);
  }
  CHECK(size > 0);
  CHECK(sqrt(diff / size) <= 1e-12);
  free(x);
  free(ref);
}

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  int kinds[2] = {0, 0}; // simplicial and supernodal factors seen
  for (unsigned long long seed = 1; seed <= 7; ++seed) {
    // random models (banded patterns: simplicial factors), and a hexahedral
    // beam of 12 x 3 x 3 frames, whose fronts are dense enough for a
    // supernodal factor
    fascia_model *m = NULL;
    int frames = 8 + 7 * (int)seed;
    if (seed < 7) {
      m = random_model(ctx, seed, frames, 2 * frames, 0, 0, 0);
    } else {
      fascia_scene_beam_def def = fascia_scene_beam_def_default();
      def.frames[0] = 12;
      CHECK_OK(fascia_scene_beam_build(ctx, &def, &m), ctx);
      frames = m ? m->frame_count : 0;
    }
    CHECK(m != NULL);
    if (!m) break;
    fascia_bsr K;
    CHECK_OK(fascia_bsr_create(ctx, m, &K), ctx);
    const int n = 6 * frames;
    unsigned char *mask = malloc((size_t)n);
    double *damping = malloc((size_t)n * sizeof(double)), *b = malloc((size_t)n * sizeof(double));
    unsigned long long st = seed * 977 + 3;
    for (int i = 0; i < frames; ++i) {
      const int fixed_frame = i % 5 == 1; // some frames fixed, a few single unknowns too
      for (int c = 0; c < 6; ++c) mask[6 * i + c] = !fixed_frame && !(i % 7 == 3 && c == 4);
    }
    for (int k = 0; k < n; ++k) damping[k] = rnd_uniform(&st, 0.5, 2), b[k] = rnd_uniform(&st, -1, 1);
    fascia_direct *d = NULL;
    CHECK_OK(fascia_direct_create(ctx, &K, mask, &d), ctx);
    if (!d) break;
    CHECK(fascia_direct_flops(d) > 0);
    printf("seed %llu: %d frames, %s factor\n", seed, frames, fascia_direct_supernodal(d) ? "supernodal" : "simplicial");
    ++kinds[fascia_direct_supernodal(d)];
    random_spd(&K, &st, 0.1);
    check_against_dense(ctx, d, &K, mask, damping, 0, b);
    random_spd(&K, &st, 1e-3); // other numbers, the same analysis, a shift
    check_against_dense(ctx, d, &K, mask, damping, 0.25, b);
    fascia_direct_destroy(&d);
    CHECK(d == NULL);
    fascia_bsr_destroy(&K);
    free(mask), free(damping), free(b);
    fascia_model_destroy(&m);
  }
  CHECK(kinds[0] > 0 && kinds[1] > 0); // each kind reads its own triangle: both are checked
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
