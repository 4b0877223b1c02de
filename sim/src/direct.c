// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The direct solver on CHOLMOD (see direct.h). The fill-reducing ordering is
// computed on the frame graph (6 times smaller than the unknowns': AMD, or
// METIS where CHOLMOD finds AMD's fill large) and expanded to each frame's
// free unknowns, which keeps a frame's 6 unknowns together in the
// supernodes. The matrix is CHOLMOD's lower triangle in compressed columns:
// column 6i+a holds row a of frame i's blocks with frames j >= i, so the
// values are copied from the block rows in storage order, the order the
// pattern was built in.
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include <cholmod.h>

#include "direct.h"

// OpenBLAS's thread count (CMake links it by name, cmake/FindCHOLMOD.cmake).
void openblas_set_num_threads(int threads);

struct fascia_direct {
  int64_t unknowns;     // 6N
  int64_t free_count;   // unknowns of the systems
  int64_t *free_index;  // [6N] index among the free unknowns, -1 for a fixed one
  unsigned char *mask;  // [6N] the mask the analysis is for
  cholmod_common common;
  cholmod_sparse *matrix; // [free_count^2] lower triangle, pattern fixed at creation
  cholmod_factor *factor;
  cholmod_dense *rhs, *solution, *work_y, *work_e;
};

// Runs BODY for every stored entry (column, row, value_index into B's
// values) in storage order: the pattern and the values take the same walk.
#define FOR_EACH_ENTRY(d, B, BODY)                                                                                   \
  for (int32_t i = 0; i < (B)->rows; ++i)                                                                            \
    for (int a = 0; a < 6; ++a) {                                                                                    \
      const int64_t column = (d)->free_index[6 * (int64_t)i + a];                                                    \
      if (column < 0) continue;                                                                                      \
      for (int32_t blk = (B)->diagonal[i]; blk < (B)->row_offsets[i + 1]; ++blk)                                     \
        for (int c = (B)->cols[blk] == i ? a : 0; c < 6; ++c) {                                                      \
          const int64_t row = (d)->free_index[6 * (int64_t)(B)->cols[blk] + c];                                      \
          if (row < 0) continue;                                                                                     \
          const int64_t value_index = 36 * (int64_t)blk + 6 * a + c;                                                 \
          (void)value_index;                                                                                         \
          BODY;                                                                                                      \
        }                                                                                                            \
    }

// Fill-reducing order of the frames that have a free unknown, as frame
// indices in *order (count in *frames).
static fascia_status order_frames(fascia_ctx *ctx, fascia_direct *d, const fascia_bsr *B, int64_t *order,
                                  int64_t *frames) {
  const int32_t N = B->rows;
  int64_t *graph_index = fascia_calloc(N, sizeof(int64_t)), F = 0, entries = 0;
  FASCIA_CHECK(graph_index, ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for %d frames", (int)N);
  for (int32_t i = 0; i < N; ++i) {
    int free_unknowns = 0;
    for (int a = 0; a < 6; ++a) free_unknowns += d->free_index[6 * (int64_t)i + a] >= 0;
    graph_index[i] = free_unknowns ? F++ : -1;
  }
  for (int32_t i = 0; i < N; ++i)
    if (graph_index[i] >= 0)
      for (int32_t blk = B->diagonal[i]; blk < B->row_offsets[i + 1]; ++blk) entries += graph_index[B->cols[blk]] >= 0;
  cholmod_sparse *G = cholmod_l_allocate_sparse((size_t)F, (size_t)F, (size_t)entries, 1, 1, -1, CHOLMOD_PATTERN,
                                                &d->common);
  if (!G) {
    free(graph_index);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for the frame graph (%lld entries)",
                       (long long)entries);
  }
  SuiteSparse_long *p = G->p, *rows = G->i, k = 0;
  for (int32_t i = 0; i < N; ++i) {
    if (graph_index[i] < 0) continue;
    p[graph_index[i]] = k;
    for (int32_t blk = B->diagonal[i]; blk < B->row_offsets[i + 1]; ++blk)
      if (graph_index[B->cols[blk]] >= 0) rows[k++] = graph_index[B->cols[blk]];
  }
  p[F] = k;
  d->common.nmethods = 0;                    // CHOLMOD's choice: AMD, or METIS where AMD fills much
  d->common.supernodal = CHOLMOD_SIMPLICIAL; // only the ordering is wanted here
  cholmod_factor *L = cholmod_l_analyze(G, &d->common);
  cholmod_l_free_sparse(&G, &d->common);
  if (!L) {
    free(graph_index);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "direct solver: the ordering of %lld frames failed (CHOLMOD status %d)",
                       (long long)F, d->common.status);
  }
  int64_t *frame_of = fascia_calloc(F > 0 ? F : 1, sizeof(int64_t));
  if (!frame_of) {
    cholmod_l_free_factor(&L, &d->common);
    free(graph_index);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for %d frames", (int)N);
  }
  for (int32_t i = 0; i < N; ++i)
    if (graph_index[i] >= 0) frame_of[graph_index[i]] = i;
  const SuiteSparse_long *perm = L->Perm;
  for (int64_t q = 0; q < F; ++q) order[q] = frame_of[perm[q]];
  *frames = F;
  cholmod_l_free_factor(&L, &d->common);
  free(frame_of);
  free(graph_index);
  return FASCIA_OK;
}

static void release(fascia_direct *d) {
  cholmod_l_free_sparse(&d->matrix, &d->common);
  cholmod_l_free_factor(&d->factor, &d->common);
  cholmod_l_free_dense(&d->rhs, &d->common);
  cholmod_l_free_dense(&d->solution, &d->common);
  cholmod_l_free_dense(&d->work_y, &d->common);
  cholmod_l_free_dense(&d->work_e, &d->common);
  free(d->free_index);
  free(d->mask);
  d->free_index = NULL;
  d->mask = NULL;
  d->free_count = 0;
}

static fascia_status create(fascia_ctx *ctx, const fascia_bsr *B, const unsigned char *mask, fascia_direct *d) {
  const int32_t N = B->rows;
  d->unknowns = 6 * (int64_t)N;
  d->free_index = fascia_calloc(d->unknowns, sizeof(int64_t));
  d->mask = fascia_calloc(d->unknowns, 1);
  int64_t *order = fascia_calloc(N, sizeof(int64_t)), frames = 0;
  SuiteSparse_long *perm = fascia_calloc(d->unknowns, sizeof(SuiteSparse_long));
  fascia_status st = FASCIA_OK;
  if (!d->free_index || !d->mask || !order || !perm) {
    st = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for %d frames", (int)N);
    goto done;
  }
  memcpy(d->mask, mask, (size_t)d->unknowns);
  for (int64_t k = 0; k < d->unknowns; ++k) d->free_index[k] = mask[k] ? d->free_count++ : -1;
  if ((st = order_frames(ctx, d, B, order, &frames)) != FASCIA_OK) goto done;
  int64_t count = 0;
  for (int64_t q = 0; q < frames; ++q)
    for (int a = 0; a < 6; ++a)
      if (d->free_index[6 * order[q] + a] >= 0) perm[count++] = d->free_index[6 * order[q] + a];

  int64_t entries = 0;
  FOR_EACH_ENTRY(d, B, ++entries);
  const size_t n = (size_t)d->free_count;
  d->matrix = cholmod_l_allocate_sparse(n, n, (size_t)entries, 1, 1, -1, CHOLMOD_REAL, &d->common);
  d->rhs = cholmod_l_zeros(n, 1, CHOLMOD_REAL, &d->common);
  if (!d->matrix || !d->rhs) {
    st = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for a matrix of %lld entries",
                     (long long)entries);
    goto done;
  }
  SuiteSparse_long *p = d->matrix->p, *rows = d->matrix->i, k = 0, previous = -1;
  FOR_EACH_ENTRY(d, B, {
    if (column != previous) {
      p[column] = k;
      previous = column;
    }
    rows[k++] = row;
  });
  p[n] = k;
  // the given frame order, postordered, and the supernodal symbolic factor
  d->common.nmethods = 1;
  d->common.method[0].ordering = CHOLMOD_GIVEN;
  d->common.postorder = 1;
  d->common.supernodal = CHOLMOD_AUTO; // supernodal where the fronts are dense enough, else simplicial
  d->common.final_ll = 1;              // LL^T, not LDL^T, so that a system not positive definite fails
  d->factor = cholmod_l_analyze_p(d->matrix, perm, NULL, 0, &d->common);
  if (!d->factor)
    st = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY,
                     "direct solver: the analysis of %lld unknowns (%lld entries) failed (CHOLMOD status %d); use the "
                     "CG solver",
                     (long long)n, (long long)entries, d->common.status);
done:
  free(order);
  free(perm);
  return st;
}

fascia_status fascia_direct_create(fascia_ctx *ctx, const fascia_bsr *pattern, const unsigned char *mask,
                                   fascia_direct **out) {
  *out = NULL;
  fascia_direct *d = calloc(1, sizeof *d);
  FASCIA_CHECK(d, ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory");
  cholmod_l_start(&d->common);
  d->common.print = 0;          // failures are reported by the caller, in its words
  d->common.error_handler = NULL;
  // one BLAS thread: the factorization then gives the same bits whatever the
  // solver's thread count, and no BLAS thread spins beside the solver's
  openblas_set_num_threads(1);
  const fascia_status st = create(ctx, pattern, mask, d);
  if (st != FASCIA_OK) {
    fascia_direct_destroy(&d);
    return st;
  }
  *out = d;
  return FASCIA_OK;
}

void fascia_direct_destroy(fascia_direct **dp) {
  fascia_direct *d = *dp;
  if (!d) return;
  release(d);
  cholmod_l_finish(&d->common);
  free(d);
  *dp = NULL;
}

double fascia_direct_flops(const fascia_direct *d) { return d->common.fl; }

double fascia_direct_factor_nonzeros(const fascia_direct *d) { return d->common.lnz; }

int fascia_direct_mask_is(const fascia_direct *d, const unsigned char *mask) {
  return !memcmp(mask, d->mask, (size_t)d->unknowns);
}

int fascia_direct_factor(fascia_direct *d, fascia_ctx *ctx, const fascia_bsr *K, const unsigned char *mask,
                         const fascia_real *damping, fascia_real shift) {
  if (!fascia_direct_mask_is(d, mask)) { // other unknowns fixed: analyse again
    release(d);
    if (create(ctx, K, mask, d) != FASCIA_OK) return -1;
  }
  double *x = d->matrix->x;
  const SuiteSparse_long *p = d->matrix->p;
  int64_t k = 0;
  FOR_EACH_ENTRY(d, K, x[k++] = K->values[value_index]);
  for (int64_t u = 0; u < d->unknowns; ++u) {
    const int64_t column = d->free_index[u];
    if (column >= 0) x[p[column]] += shift * damping[u]; // the diagonal leads its column
  }
  return fascia_direct_factor_values(d);
}

double *fascia_direct_values(fascia_direct *d, int64_t *count) {
  *count = (int64_t)((const SuiteSparse_long *)d->matrix->p)[d->matrix->ncol];
  return d->matrix->x;
}

int fascia_direct_factor_values(fascia_direct *d) {
  int64_t k;
  const double *x = fascia_direct_values(d, &k);
  // OpenBLAS's Cholesky lets a NaN through: look at the numbers first
  for (int64_t e = 0; e < k; ++e)
    if (!isfinite(x[e])) return 0;
  // Debian's CHOLMOD asks OpenMP for teams of a fixed 4 threads in its
  // supernodal factorization: on 2 cores each factorization started two
  // extra threads that competed with the solver's (t3-row-sized scenes: 83
  // against 30 ms of linear solves per step). With OpenMP's dynamic
  // adjustment on, the runtime gives its teams no more threads than the
  // cores are free for; its loops only copy, so the bits do not change.
  int factored;
#ifdef _OPENMP
  const int dynamic = omp_get_dynamic();
  omp_set_dynamic(1);
#endif
  factored = cholmod_l_factorize(d->matrix, d->factor, &d->common);
#ifdef _OPENMP
  omp_set_dynamic(dynamic);
#endif
  return factored && d->common.status == CHOLMOD_OK && d->factor->minor == d->factor->n;
}

void fascia_direct_solve(fascia_direct *d, const fascia_real *rhs, fascia_real *x) {
  double *b = d->rhs->x;
  for (int64_t u = 0; u < d->unknowns; ++u)
    if (d->free_index[u] >= 0) b[d->free_index[u]] = rhs[u];
  cholmod_l_solve2(CHOLMOD_A, d->factor, d->rhs, NULL, &d->solution, NULL, &d->work_y, &d->work_e, &d->common);
  const double *s = d->solution->x;
  for (int64_t u = 0; u < d->unknowns; ++u) x[u] = d->free_index[u] >= 0 ? s[d->free_index[u]] : 0;
}
