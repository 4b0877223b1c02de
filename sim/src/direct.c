// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The direct solver on CHOLMOD (see direct.h). The fill-reducing ordering is
// computed on the frame graph (6 times smaller than the unknowns': AMD, or
// METIS where CHOLMOD finds AMD's fill large) and expanded to each frame's
// free unknowns, which keeps a frame's 6 unknowns together in the
// supernodes. The unknowns are then numbered in that order (postordered),
// and CHOLMOD factors the matrix in its natural order: given the triangle
// it works on (the lower one for a supernodal factor, the upper one for a
// simplicial one), a factorization copies no matrix. With the ordering left
// to CHOLMOD it transposed the matrix twice per factorization, which cost
// more than the supernodal arithmetic on the 20x3x3 cantilever. The values
// are gathered from the block rows through a map made once per analysis.
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
  int64_t *free_index;  // [6N] row of the unknown in the factored matrix (the fill-reducing order), -1 fixed
  unsigned char *mask;  // [6N] the mask the analysis is for
  int64_t entries;      // stored values
  int64_t *value_index; // [entries] where each stored value is in the block values (36 blk + 6 a + c)
  int64_t *walk_place;  // [entries] the place of the pattern walk's j-th entry among the stored values
  int64_t *diagonal;    // [free_count] the place of each diagonal entry
  cholmod_common common;
  cholmod_sparse *matrix; // [free_count^2] one triangle, pattern fixed at creation
  cholmod_factor *factor;
  cholmod_dense *rhs, *solution, *work_y, *work_e;
};

// Runs BODY for every entry of one triangle (column, row: the unknowns'
// numbers; value_index into B's values) in the pattern's walk: frame i's
// row a, then its blocks with frames j >= i.
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

// The matrix and its maps (fill_pattern).
static void free_pattern(fascia_direct *d) {
  cholmod_l_free_sparse(&d->matrix, &d->common);
  free(d->value_index);
  free(d->walk_place);
  free(d->diagonal);
  d->value_index = d->walk_place = d->diagonal = NULL;
}

static void release(fascia_direct *d) {
  cholmod_l_free_factor(&d->factor, &d->common);
  cholmod_l_free_dense(&d->rhs, &d->common);
  cholmod_l_free_dense(&d->solution, &d->common);
  cholmod_l_free_dense(&d->work_y, &d->common);
  cholmod_l_free_dense(&d->work_e, &d->common);
  free(d->free_index);
  free(d->mask);
  free_pattern(d);
  d->free_index = NULL;
  d->mask = NULL;
  d->free_count = d->entries = 0;
}

static fascia_status analysis_failed(fascia_ctx *ctx, const fascia_direct *d) {
  return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY,
                     "direct solver: the analysis of %lld unknowns (%lld entries) failed (CHOLMOD status %d); use the "
                     "CG solver",
                     (long long)d->free_count, (long long)d->entries, d->common.status);
}

// d->matrix in the unknowns' numbering: triangle stype (-1 lower, 1 upper),
// rows ascending in each column; d->value_index, d->walk_place, d->diagonal.
static fascia_status fill_pattern(fascia_ctx *ctx, fascia_direct *d, const fascia_bsr *B, int stype) {
  const int64_t n = d->free_count, entries = d->entries, e1 = entries > 0 ? entries : 1;
  d->matrix = cholmod_l_allocate_sparse((size_t)n, (size_t)n, (size_t)entries, 1, 1, stype, CHOLMOD_REAL, &d->common);
  d->value_index = fascia_calloc(e1, sizeof(int64_t));
  d->walk_place = fascia_calloc(e1, sizeof(int64_t));
  d->diagonal = fascia_calloc(n > 0 ? n : 1, sizeof(int64_t));
  // the entries bucketed by row first (column, value and walk index of each),
  // then dealt to their columns row by row: each column's rows come out
  // ascending, in time linear in the entries
  int64_t *next = fascia_calloc(n + 1, sizeof(int64_t)), *by_row = fascia_calloc(n + 1, sizeof(int64_t));
  int64_t *row_column = fascia_calloc(e1, sizeof(int64_t)), *row_value = fascia_calloc(e1, sizeof(int64_t));
  int64_t *row_walk = fascia_calloc(e1, sizeof(int64_t));
  fascia_status st = FASCIA_OK;
  if (!d->matrix || !d->value_index || !d->walk_place || !d->diagonal || !next || !by_row || !row_column ||
      !row_value || !row_walk) {
    st = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for a matrix of %lld entries",
                     (long long)entries);
    goto done;
  }
  SuiteSparse_long *p = d->matrix->p, *rows = d->matrix->i;
  // an entry (column, row) of the walk's triangle goes to column min or max
#define TARGET(column, row) (stype < 0 ? ((column) < (row) ? (column) : (row)) : ((column) < (row) ? (row) : (column)))
#define OTHER(column, row) (stype < 0 ? ((column) < (row) ? (row) : (column)) : ((column) < (row) ? (column) : (row)))
  FOR_EACH_ENTRY(d, B, {
    ++next[TARGET(column, row) + 1];
    ++by_row[OTHER(column, row) + 1];
  });
  for (int64_t c = 0; c < n; ++c) next[c + 1] += next[c], by_row[c + 1] += by_row[c];
  for (int64_t c = 0; c <= n; ++c) p[c] = next[c];
  int64_t j = 0;
  FOR_EACH_ENTRY(d, B, {
    const int64_t slot = by_row[OTHER(column, row)]++;
    row_column[slot] = TARGET(column, row);
    row_value[slot] = value_index;
    row_walk[slot] = j++;
  });
#undef TARGET
#undef OTHER
  for (int64_t r = 0, slot = 0; r < n; ++r) // by_row[r] is now where row r + 1 starts
    for (; slot < by_row[r]; ++slot) {
      const int64_t c = row_column[slot], place = next[c]++;
      rows[place] = r;
      d->value_index[place] = row_value[slot];
      d->walk_place[row_walk[slot]] = place;
      if (r == c) d->diagonal[c] = place;
    }
done:
  free(next);
  free(by_row);
  free(row_column);
  free(row_value);
  free(row_walk);
  return st;
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
  d->entries = entries;
  const size_t n = (size_t)d->free_count;
  // 1. the given frame order, postordered, on the pattern in mask order
  if ((st = fill_pattern(ctx, d, B, -1)) != FASCIA_OK) goto done;
  d->common.nmethods = 1;
  d->common.method[0].ordering = CHOLMOD_GIVEN;
  d->common.postorder = 1;
  d->common.supernodal = CHOLMOD_AUTO; // supernodal where the fronts are dense enough, else simplicial
  d->common.final_ll = 1;              // LL^T, not LDL^T, so that a system not positive definite fails
  cholmod_factor *ordered = cholmod_l_analyze_p(d->matrix, perm, NULL, 0, &d->common);
  free_pattern(d);
  if (!ordered) {
    st = analysis_failed(ctx, d);
    goto done;
  }
  // 2. number the unknowns in that order (perm is free now: its inverse)
  const SuiteSparse_long *final_order = ordered->Perm;
  for (size_t q = 0; q < n; ++q) perm[final_order[q]] = (SuiteSparse_long)q;
  for (int64_t u = 0; u < d->unknowns; ++u)
    if (d->free_index[u] >= 0) d->free_index[u] = perm[d->free_index[u]];
  const int supernodal = ordered->is_super;
  cholmod_l_free_factor(&ordered, &d->common);
  // 3. the triangle CHOLMOD's natural order reads as it is, rows sorted per
  // column, with the maps to the block values and from the walk
  if ((st = fill_pattern(ctx, d, B, supernodal ? -1 : 1)) != FASCIA_OK) goto done;
  d->rhs = cholmod_l_zeros(n, 1, CHOLMOD_REAL, &d->common);
  if (!d->rhs) {
    st = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for %lld unknowns", (long long)n);
    goto done;
  }
  // 4. the symbolic factor in that order: the same fill, no permutation
  d->common.method[0].ordering = CHOLMOD_NATURAL;
  d->common.postorder = 0;
  d->common.supernodal = supernodal ? CHOLMOD_SUPERNODAL : CHOLMOD_SIMPLICIAL;
  d->factor = cholmod_l_analyze(d->matrix, &d->common);
  if (!d->factor) st = analysis_failed(ctx, d);
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

int fascia_direct_supernodal(const fascia_direct *d) { return d->factor && d->factor->is_super; }

double fascia_direct_factor_nonzeros(const fascia_direct *d) { return d->common.lnz; }

int fascia_direct_mask_is(const fascia_direct *d, const unsigned char *mask) {
  return !memcmp(mask, d->mask, (size_t)d->unknowns);
}

// Factors the values in d->matrix: 1, or 0 when not positive definite (or
// not finite).
static int factor_values(fascia_direct *d) {
  const double *x = d->matrix->x;
  // OpenBLAS's Cholesky lets a NaN through: look at the numbers first
  for (int64_t e = 0; e < d->entries; ++e)
    if (!isfinite(x[e])) return 0;
  // Debian's CHOLMOD asks OpenMP for teams of a fixed 4 threads in its
  // supernodal factorization, for loops that only copy (the BLAS runs on
  // one thread). With dynamic adjustment on, the runtime gives a team no
  // more threads than nthreads-var: one here. Teams of 4 had doubled the
  // 950-frame abdomen's linear solves on 2 cores; teams fitted to the free
  // cores (2) still cost the deformable pelvis 9.9 against 3.2 ms of linear
  // solves per step, and waking their sleeping worker made a factorization
  // after an idle second 3x slower (docs/mechanics.md, "CHOLMOD's threads").
  // One thread was as fast or faster on every scene measured; the bits are
  // the same.
  int factored;
#ifdef _OPENMP
  const int dynamic = omp_get_dynamic(), threads = omp_get_max_threads();
  omp_set_dynamic(1);
  omp_set_num_threads(1);
#endif
  factored = cholmod_l_factorize(d->matrix, d->factor, &d->common);
#ifdef _OPENMP
  omp_set_num_threads(threads);
  omp_set_dynamic(dynamic);
#endif
  return factored && d->common.status == CHOLMOD_OK && d->factor->minor == d->factor->n;
}

int fascia_direct_factor(fascia_direct *d, fascia_ctx *ctx, const fascia_bsr *K, const unsigned char *mask,
                         const fascia_real *damping, fascia_real shift) {
  if (!fascia_direct_mask_is(d, mask)) { // other unknowns fixed: analyse again
    release(d);
    if (create(ctx, K, mask, d) != FASCIA_OK) return -1;
  }
  double *x = d->matrix->x;
  for (int64_t k = 0; k < d->entries; ++k) x[k] = K->values[d->value_index[k]];
  for (int64_t u = 0; u < d->unknowns; ++u) {
    const int64_t row = d->free_index[u];
    if (row >= 0) x[d->diagonal[row]] += shift * damping[u];
  }
  return factor_values(d);
}

int64_t fascia_direct_values_count(const fascia_direct *d) { return d->entries; }

void fascia_direct_values_save(const fascia_direct *d, double *out) {
  const double *x = d->matrix->x;
  for (int64_t j = 0; j < d->entries; ++j) out[j] = x[d->walk_place[j]];
}

int fascia_direct_values_load(fascia_direct *d, const double *in) {
  double *x = d->matrix->x;
  for (int64_t j = 0; j < d->entries; ++j) x[d->walk_place[j]] = in[j];
  return factor_values(d);
}

void fascia_direct_solve(fascia_direct *d, const fascia_real *rhs, fascia_real *x) {
  double *b = d->rhs->x;
  for (int64_t u = 0; u < d->unknowns; ++u)
    if (d->free_index[u] >= 0) b[d->free_index[u]] = rhs[u];
  cholmod_l_solve2(CHOLMOD_A, d->factor, d->rhs, NULL, &d->solution, NULL, &d->work_y, &d->work_e, &d->common);
  const double *s = d->solution->x;
  for (int64_t u = 0; u < d->unknowns; ++u) x[u] = d->free_index[u] >= 0 ? s[d->free_index[u]] : 0;
}
