// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The direct solver reports a system that is not positive definite instead
// of returning a solution: a negative pivot, a zero one, and a NaN or an
// infinity in the matrix (which the BLAS's own Cholesky lets through); the
// Levenberg shift the Newton loop then adds makes the same analysis factor
// again; fixing more unknowns after the analysis analyses again. A retry
// with a larger shift (fascia_direct_refactor, which writes the diagonal
// alone) solves to the same bits as a fresh factorization at that shift,
// and still refuses a NaN under any shift, a diagonal the shift overflows,
// and a solver that has factored nothing.
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "cpu/direct.h"
#include "random_model.h"

// A diagonal matrix with `diagonal` on every unknown and weak symmetric
// couplings between the diagonal blocks' unknowns.
static void fill(fascia_bsr *K, double diagonal) {
  memset(K->values, 0, 36 * (size_t)K->blocks * sizeof(double));
  for (int32_t i = 0; i < K->rows; ++i) {
    double *D = K->values + 36 * (int64_t)K->diagonal[i];
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) D[6 * r + c] = r == c ? diagonal : 0.01;
  }
}

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  const int frames = 20, n = 6 * frames;
  fascia_model *m = random_model(ctx, 11, frames, 40, 0, 0, 0);
  CHECK(m != NULL);
  if (!m) return 1;
  fascia_bsr K;
  CHECK_OK(fascia_bsr_create(ctx, m, &K), ctx);
  unsigned char *mask = malloc((size_t)n);
  double *damping = malloc((size_t)n * sizeof(double)), *x = malloc((size_t)n * sizeof(double));
  for (int k = 0; k < n; ++k) mask[k] = k >= 6, damping[k] = 1; // frame 0 fixed
  fascia_direct *d = NULL;
  CHECK_OK(fascia_direct_create(ctx, &K, mask, &d), ctx);
  if (!d) return 1;
  const int64_t middle = 36 * (int64_t)K.diagonal[frames / 2];

  fill(&K, 1);
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 0) == 1);
  K.values[middle + 7 * 2] = -3; // a negative pivot
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 0) == 0);
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 1) == 0);  // still -2
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 10) == 1); // shifted past it
  fascia_direct_solve(d, damping, x);
  CHECK_NEAR(x[6 * (frames / 2) + 2], 1.0 / 7, 1e-2, 0); // about 1 / (10 - 3)
  // the same by retries: the diagonal alone written again, the same bits
  double *retried = malloc((size_t)n * sizeof(double));
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 0) == 0);
  CHECK(fascia_direct_refactor(d, damping, 1) == 0);
  CHECK(fascia_direct_refactor(d, damping, 10) == 1);
  fascia_direct_solve(d, damping, retried);
  CHECK(!memcmp(retried, x, (size_t)n * sizeof(double)));
  free(retried);
  fill(&K, 1);
  K.values[middle + 7 * 3] = 0; // a zero pivot
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 0) == 0);
  fill(&K, 1);
  K.values[middle + 1] = K.values[middle + 6] = NAN; // a NaN off the diagonal
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 0) == 0);
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 1e6) == 0); // no shift cures it
  CHECK(fascia_direct_refactor(d, damping, 1e6) == 0);             // nor a retry's
  fill(&K, 1e308);
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 0) == 1);
  CHECK(fascia_direct_refactor(d, damping, 1e308) == 0); // the shifted diagonal overflows
  fascia_direct *fresh = NULL;
  CHECK_OK(fascia_direct_create(ctx, &K, mask, &fresh), ctx);
  CHECK(fresh && fascia_direct_refactor(fresh, damping, 1) == 0); // nothing factored to retry
  fascia_direct_destroy(&fresh);
  fill(&K, 1);
  K.values[middle + 7 * 5] = INFINITY;
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 0) == 0);
  fill(&K, 1);
  K.values[middle] = NAN; // on a fixed frame's block it would not matter; here it does
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 0) == 0);
  fill(&K, 1);
  K.values[36 * (int64_t)K.diagonal[0]] = NAN; // frame 0 is fixed: not part of the system
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 0) == 1);
  // a frame fixed after the analysis: analysed again, its NaN no longer read
  K.values[middle + 7 * 5] = NAN;
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 0) == 0);
  memset(mask + 6 * (frames / 2), 0, 6);
  CHECK(fascia_direct_factor(d, ctx, &K, mask, damping, 0) == 1);
  fascia_direct_solve(d, damping, x);
  CHECK(x[6 * (frames / 2) + 5] == 0);
  CHECK(x[6 * (frames / 2) + 6] != 0);

  fascia_direct_destroy(&d);
  fascia_bsr_destroy(&K);
  free(mask), free(damping), free(x);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
