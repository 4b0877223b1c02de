// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Banded Cholesky under a reverse Cuthill-McKee frame ordering (see
// direct.h). Band storage keeps the code short and the memory predictable:
// for the elongated bodies of this project (beams, tissue sheets between
// organs) the bandwidth stays a small multiple of a cross-section.
#include <stdlib.h>
#include <string.h>

#include "banded.h"

// Reverse Cuthill-McKee on the frame graph; start from a frame of least
// degree in each connected component (a cheap pseudo-peripheral choice).
static fascia_status rcm(fascia_ctx *ctx, const fascia_bsr *B, int32_t *order) {
  const int32_t N = B->rows;
  char *seen = calloc((size_t)N, 1);
  int32_t *degree = fascia_calloc(N, sizeof(int32_t));
  FASCIA_CHECK(seen && degree, ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for the ordering");
  for (int32_t i = 0; i < N; ++i) degree[i] = B->row_offsets[i + 1] - B->row_offsets[i];
  int32_t head = 0, tail = 0;
  while (tail < N) {
    int32_t start = -1;
    for (int32_t i = 0; i < N; ++i)
      if (!seen[i] && (start < 0 || degree[i] < degree[start])) start = i;
    seen[start] = 1;
    order[tail++] = start;
    while (head < tail) {
      const int32_t i = order[head++], first = tail;
      for (int32_t b = B->row_offsets[i]; b < B->row_offsets[i + 1]; ++b) {
        const int32_t j = B->cols[b];
        if (!seen[j]) {
          seen[j] = 1;
          order[tail++] = j;
        }
      }
      // neighbours by increasing degree (insertion sort: rows are short)
      for (int32_t a = first + 1; a < tail; ++a)
        for (int32_t c = a; c > first && degree[order[c]] < degree[order[c - 1]]; --c) {
          const int32_t t = order[c];
          order[c] = order[c - 1];
          order[c - 1] = t;
        }
    }
  }
  for (int32_t a = 0, c = N - 1; a < c; ++a, --c) {
    const int32_t t = order[a];
    order[a] = order[c];
    order[c] = t;
  }
  free(seen);
  free(degree);
  return FASCIA_OK;
}

fascia_status fascia_banded_create(fascia_ctx *ctx, const fascia_bsr *B, int64_t max_bytes, fascia_banded *out) {
  memset(out, 0, sizeof *out);
  const int32_t N = B->rows;
  out->order = fascia_calloc(N, sizeof(int32_t));
  out->position = fascia_calloc(N, sizeof(int32_t));
  if (!out->order || !out->position) {
    fascia_banded_destroy(out);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for %d frames", (int)N);
  }
  fascia_status st = rcm(ctx, B, out->order);
  if (st != FASCIA_OK) {
    fascia_banded_destroy(out);
    return st;
  }
  for (int32_t p = 0; p < N; ++p) out->position[out->order[p]] = p;
  int32_t frame_band = 0;
  for (int32_t i = 0; i < N; ++i)
    for (int32_t b = B->row_offsets[i]; b < B->row_offsets[i + 1]; ++b) {
      const int32_t d = out->position[i] - out->position[B->cols[b]];
      if (d > frame_band) frame_band = d;
    }
  out->n = 6 * (int64_t)N;
  out->bandwidth = 6 * (int64_t)frame_band + 5;
  const double bytes = (double)out->n * (double)(out->bandwidth + 1) * sizeof(fascia_real);
  if (bytes > (double)max_bytes) {
    const int64_t bw = out->bandwidth;
    fascia_banded_destroy(out);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY,
                       "direct solver: the band would take %.0f MB (%d frames, bandwidth %lld); use the CG solver",
                       bytes / 1048576.0, (int)N, (long long)bw);
  }
  out->band = fascia_calloc(out->n * (out->bandwidth + 1), sizeof(fascia_real));
  if (!out->band) {
    fascia_banded_destroy(out);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for a %.0f MB band", bytes / 1048576.0);
  }
  return FASCIA_OK;
}

void fascia_banded_destroy(fascia_banded *b) {
  free(b->order);
  free(b->position);
  free(b->band);
  memset(b, 0, sizeof *b);
}

double fascia_banded_cost(const fascia_banded *b) { return (double)b->n * (double)b->bandwidth * (double)b->bandwidth; }

#define BAND(b, r, c) ((b)->band[(r) * ((b)->bandwidth + 1) + ((c) - (r) + (b)->bandwidth)])

int fascia_banded_factor(fascia_banded *b, const fascia_bsr *K, const unsigned char *mask, const fascia_real *damping,
                         fascia_real shift) {
  const int64_t n = b->n, w = b->bandwidth;
  memset(b->band, 0, (size_t)(n * (w + 1)) * sizeof(fascia_real));
  // lower triangle of the permuted matrix; masked unknowns become identity
  for (int32_t i = 0; i < K->rows; ++i)
    for (int32_t blk = K->row_offsets[i]; blk < K->row_offsets[i + 1]; ++blk) {
      const int32_t j = K->cols[blk];
      const fascia_real *v = K->values + 36 * (int64_t)blk;
      for (int a = 0; a < 6; ++a)
        for (int c = 0; c < 6; ++c) {
          const int64_t gi = 6 * (int64_t)i + a, gj = 6 * (int64_t)j + c;
          const int64_t r = 6 * (int64_t)b->position[i] + a, col = 6 * (int64_t)b->position[j] + c;
          if (col > r || !mask[gi] || !mask[gj]) continue;
          BAND(b, r, col) += v[6 * a + c];
        }
    }
  for (int32_t i = 0; i < K->rows; ++i)
    for (int a = 0; a < 6; ++a) {
      const int64_t gi = 6 * (int64_t)i + a, r = 6 * (int64_t)b->position[i] + a;
      BAND(b, r, r) = mask[gi] ? BAND(b, r, r) + shift * damping[gi] : 1;
    }
  // Cholesky, row by row within the band (left-looking)
  for (int64_t r = 0; r < n; ++r) {
    const int64_t c0 = r - w > 0 ? r - w : 0;
    for (int64_t c = c0; c <= r; ++c) {
      const int64_t k0 = (c - w > c0 ? c - w : c0);
      fascia_real s = BAND(b, r, c);
      for (int64_t k = k0; k < c; ++k) s -= BAND(b, r, k) * BAND(b, c, k);
      if (c < r) {
        BAND(b, r, c) = s / BAND(b, c, c);
      } else {
        if (!(s > 0) || !isfinite(s)) return 0;
        BAND(b, r, r) = sqrt(s);
      }
    }
  }
  return 1;
}

void fascia_banded_solve(const fascia_banded *b, const fascia_real *rhs, fascia_real *x, fascia_real *y) {
  const int64_t n = b->n, w = b->bandwidth;
  const int32_t N = (int32_t)(n / 6);
  for (int32_t i = 0; i < N; ++i)
    for (int a = 0; a < 6; ++a) y[6 * (int64_t)b->position[i] + a] = rhs[6 * (int64_t)i + a];
  for (int64_t r = 0; r < n; ++r) { // L z = y
    fascia_real s = y[r];
    for (int64_t k = (r - w > 0 ? r - w : 0); k < r; ++k) s -= BAND(b, r, k) * y[k];
    y[r] = s / BAND(b, r, r);
  }
  for (int64_t r = n - 1; r >= 0; --r) { // L^T x = z
    fascia_real s = y[r];
    for (int64_t k = r + 1; k <= (r + w < n - 1 ? r + w : n - 1); ++k) s -= BAND(b, k, r) * y[k];
    y[r] = s / BAND(b, r, r);
  }
  for (int32_t i = 0; i < N; ++i)
    for (int a = 0; a < 6; ++a) x[6 * (int64_t)i + a] = y[6 * (int64_t)b->position[i] + a];
}
