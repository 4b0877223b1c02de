// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The direct solver on CHOLMOD (see direct.h). The fill-reducing ordering is
// computed on the frame graph (6 times smaller than the unknowns': AMD, or
// METIS where CHOLMOD finds AMD's fill large), postordered, and expanded to
// each frame's free unknowns, numbered together: the unknowns' elimination
// tree is then the frames' with each frame a chain, still postordered, and
// a frame's unknowns stay together in the supernodes. CHOLMOD factors the
// matrix in that natural order: given the triangle it works on (the lower
// one for a supernodal factor, the upper one for a simplicial one), with
// each column's rows ascending, a factorization copies no matrix. With the
// ordering left to CHOLMOD it transposed the matrix twice per
// factorization, which cost more than the supernodal arithmetic on the
// 20x3x3 cantilever. The matrix is written once, column by column, with a
// map from each stored value to the block values and no other array per
// entry (row, value and map: three numbers each), because on fresh pages a
// set-up is mostly page faults.
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include <cholmod.h>

#include "cpu/direct.h"

// OpenBLAS's thread count (CMake links it by name, cmake/FindCHOLMOD.cmake).
void openblas_set_num_threads(int threads);

struct fascia_direct {
  int64_t unknowns;     // 6N
  int64_t free_count;   // unknowns of the systems
  int64_t *free_index;  // [6N] row of the unknown in the factored matrix (the fill-reducing order), -1 fixed
  unsigned char *mask;  // [6N] the mask the analysis is for
  int64_t entries;      // stored values
  int64_t *value_index; // [entries] where each stored value is in the block values (36 blk + 6 a + c)
  int lower;            // the matrix holds the lower triangle (a supernodal factor), else the upper (simplicial)
  cholmod_common common;
  cholmod_sparse *matrix; // [free_count^2] one triangle, pattern fixed at creation
  cholmod_factor *factor;
  cholmod_dense *rhs, *solution, *work_y, *work_e;
  double *diagonal; // [free_count] the unshifted diagonal of the last fascia_direct_factor (a retry's base)
  int finite;       // its gathered values were all finite (1), or not (0), or no values yet (-1)
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

// Fill-reducing order of the frames that have a free unknown, postordered
// (CHOLMOD's weighted postorder of the frame graph's elimination tree), as
// frame indices in *order (count in *frames).
static fascia_status order_frames(fascia_ctx *ctx, fascia_direct *d, const fascia_bsr *B, int64_t *order,
                                  int64_t *frames) {
  const int32_t N = B->rows;
  int64_t *graph_index = fascia_calloc(N, sizeof(int64_t)), F = 0, entries = 0;
  FASCIA_CHECK(graph_index, ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for %d frames", (int)N);
  for (int32_t i = 0; i < N; ++i) {
    int free_unknowns = 0;
    for (int a = 0; a < 6; ++a) free_unknowns += d->mask[6 * (int64_t)i + a] != 0;
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
  d->common.postorder = 1;                   // so that each subtree's frames are numbered together
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

// A block of the pattern as the frame whose columns hold it sees it: the
// other frame's place in the order, and the block (in the row of the pair's
// lower-indexed frame, j >= i).
typedef struct {
  int64_t place;
  int64_t block;
} frame_pair;

static int pair_compare(const void *x, const void *y) {
  const int64_t a = ((const frame_pair *)x)->place, b = ((const frame_pair *)y)->place;
  return (a > b) - (a < b);
}

static void free_matrix(fascia_direct *d) {
  cholmod_l_free_sparse(&d->matrix, &d->common);
  free(d->value_index);
  d->value_index = NULL;
}

static void release(fascia_direct *d) {
  cholmod_l_free_factor(&d->factor, &d->common);
  cholmod_l_free_dense(&d->rhs, &d->common);
  cholmod_l_free_dense(&d->solution, &d->common);
  cholmod_l_free_dense(&d->work_y, &d->common);
  cholmod_l_free_dense(&d->work_e, &d->common);
  free(d->free_index);
  free(d->mask);
  free(d->diagonal);
  free_matrix(d);
  d->free_index = NULL;
  d->mask = NULL;
  d->diagonal = NULL;
  d->finite = -1;
  d->free_count = d->entries = 0;
}

static fascia_status analysis_failed(fascia_ctx *ctx, const fascia_direct *d) {
  return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY,
                     "direct solver: the analysis of %lld unknowns (%lld entries) failed (CHOLMOD status %d); use the "
                     "CG solver",
                     (long long)d->free_count, (long long)d->entries, d->common.status);
}

// d->matrix (triangle d->lower) and d->value_index, in the unknowns' final
// numbering, where frame order[q]'s free unknowns are numbered together in
// place q. Each frame's blocks are listed by the other frame's place; a
// column is then its frame's blocks in that order, so the rows come out
// ascending, written once, in the order CHOLMOD keeps them.
static fascia_status fill_matrix(fascia_ctx *ctx, fascia_direct *d, const fascia_bsr *B, const int64_t *order,
                                 int64_t frames) {
  const int32_t N = B->rows;
  const int lower = d->lower;
  int64_t *place_of = fascia_calloc(N > 0 ? N : 1, sizeof(int64_t)), *pair_offsets = fascia_calloc(frames + 1,
                                                                                                     sizeof(int64_t));
  fascia_status st = FASCIA_OK;
  frame_pair *pairs = NULL;
  if (!place_of || !pair_offsets) goto out_of_memory;
  for (int32_t i = 0; i < N; ++i) place_of[i] = -1;
  for (int64_t q = 0; q < frames; ++q) place_of[order[q]] = q;
  // a pair's blocks go to the columns of its frame placed first (lower
  // triangle) or last (upper)
#define HOLDER(pi, pj) (lower ? ((pi) < (pj) ? (pi) : (pj)) : ((pi) < (pj) ? (pj) : (pi)))
  int64_t pair_count = 0;
  for (int32_t i = 0; i < N; ++i) {
    if (place_of[i] < 0) continue;
    for (int32_t blk = B->diagonal[i]; blk < B->row_offsets[i + 1]; ++blk) {
      const int64_t pj = place_of[B->cols[blk]];
      if (pj < 0) continue;
      ++pair_offsets[HOLDER(place_of[i], pj) + 1];
      ++pair_count;
    }
  }
  for (int64_t q = 0; q < frames; ++q) pair_offsets[q + 1] += pair_offsets[q];
  pairs = malloc((size_t)(pair_count > 0 ? pair_count : 1) * sizeof *pairs);
  if (!pairs) goto out_of_memory;
  for (int32_t i = 0; i < N; ++i) {
    const int64_t pi = place_of[i];
    if (pi < 0) continue;
    for (int32_t blk = B->diagonal[i]; blk < B->row_offsets[i + 1]; ++blk) {
      const int64_t pj = place_of[B->cols[blk]];
      if (pj < 0) continue;
      const int64_t holder = HOLDER(pi, pj);
      pairs[pair_offsets[holder]++] = (frame_pair){holder == pi ? pj : pi, blk};
    }
  }
#undef HOLDER
  for (int64_t q = frames; q > 0; --q) pair_offsets[q] = pair_offsets[q - 1]; // back to each frame's first pair
  pair_offsets[0] = 0;
  for (int64_t q = 0; q < frames; ++q)
    qsort(pairs + pair_offsets[q], (size_t)(pair_offsets[q + 1] - pair_offsets[q]), sizeof *pairs, pair_compare);
  const int64_t n = d->free_count, entries = d->entries;
  d->matrix = cholmod_l_allocate_sparse((size_t)n, (size_t)n, (size_t)entries, 1, 1, lower ? -1 : 1, CHOLMOD_REAL,
                                        &d->common);
  d->value_index = fascia_calloc(entries > 0 ? entries : 1, sizeof(int64_t));
  if (!d->matrix || !d->value_index) goto out_of_memory;
  SuiteSparse_long *p = d->matrix->p, *rows = d->matrix->i;
  int64_t k = 0;
  for (int64_t q = 0; q < frames; ++q) {
    const int64_t frame = order[q];
    for (int a = 0; a < 6; ++a) {
      const int64_t column = d->free_index[6 * frame + a];
      if (column < 0) continue;
      p[column] = k;
      for (int64_t e = pair_offsets[q]; e < pair_offsets[q + 1]; ++e) {
        const int64_t other = order[pairs[e].place], blk = pairs[e].block;
        for (int c = 0; c < 6; ++c) {
          const int64_t row = d->free_index[6 * other + c];
          if (row < 0 || (other == frame && (lower ? row < column : row > column))) continue;
          // the entry's place in the block, whose row is the pair's lower-indexed
          // frame; of a frame's own block the upper triangle, as the walk reads it
          int r = a, col = c;
          if (other == frame) r = a < c ? a : c, col = a < c ? c : a;
          else if (frame > other) r = c, col = a;
          rows[k] = row;
          d->value_index[k] = 36 * blk + 6 * r + col;
          ++k;
        }
      }
    }
  }
  p[n] = k;
  if (k != entries) st = FASCIA_FAIL(ctx, FASCIA_ERR_INTERNAL, "direct solver: %lld entries filled of %lld",
                                     (long long)k, (long long)entries);
  goto done;
out_of_memory:
  st = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for a matrix of %lld entries",
                   (long long)d->entries);
done:
  free(place_of);
  free(pair_offsets);
  free(pairs);
  return st;
}

static fascia_status create(fascia_ctx *ctx, const fascia_bsr *B, const unsigned char *mask, fascia_direct *d) {
  const int32_t N = B->rows;
  d->unknowns = 6 * (int64_t)N;
  d->free_index = fascia_calloc(d->unknowns, sizeof(int64_t));
  d->mask = fascia_calloc(d->unknowns, 1);
  int64_t *order = fascia_calloc(N > 0 ? N : 1, sizeof(int64_t)), frames = 0;
  fascia_status st = FASCIA_OK;
  if (!d->free_index || !d->mask || !order) {
    st = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for %d frames", (int)N);
    goto done;
  }
  memcpy(d->mask, mask, (size_t)d->unknowns);
  if ((st = order_frames(ctx, d, B, order, &frames)) != FASCIA_OK) goto done;
  // 1. the unknowns numbered in that order, a frame's free ones together:
  // the frames' elimination tree with each frame a chain, still postordered
  for (int64_t u = 0; u < d->unknowns; ++u) d->free_index[u] = -1;
  for (int64_t q = 0; q < frames; ++q)
    for (int a = 0; a < 6; ++a)
      if (mask[6 * order[q] + a]) d->free_index[6 * order[q] + a] = d->free_count++;
  int64_t entries = 0;
  FOR_EACH_ENTRY(d, B, ++entries);
  d->entries = entries;
  const size_t n = (size_t)d->free_count;
  // 2. the symbolic factor in that order: supernodal where the fronts are
  // dense enough (it reads the lower triangle as it is), else simplicial
  // (the upper one)
  d->lower = 1;
  if ((st = fill_matrix(ctx, d, B, order, frames)) != FASCIA_OK) goto done;
  d->common.nmethods = 1;
  d->common.method[0].ordering = CHOLMOD_NATURAL;
  d->common.postorder = 0;
  d->common.supernodal = CHOLMOD_AUTO;
  d->common.final_ll = 1; // LL^T, not LDL^T, so that a system not positive definite fails
  d->factor = cholmod_l_analyze(d->matrix, &d->common);
  if (!d->factor) {
    st = analysis_failed(ctx, d);
    goto done;
  }
  if (!d->factor->is_super) {
    free_matrix(d);
    d->lower = 0;
    if ((st = fill_matrix(ctx, d, B, order, frames)) != FASCIA_OK) goto done;
  }
  d->rhs = cholmod_l_zeros(n, 1, CHOLMOD_REAL, &d->common);
  d->diagonal = fascia_calloc(n > 0 ? n : 1, sizeof(double));
  d->finite = -1;
  if (!d->rhs || !d->diagonal)
    st = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "direct solver: out of memory for %lld unknowns", (long long)n);
done:
  free(order);
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

// 1 when every stored value is finite: OpenBLAS's Cholesky lets a NaN
// through, so the numbers are looked at before they are factored
static int values_finite(const fascia_direct *d) {
  const double *x = d->matrix->x;
  for (int64_t e = 0; e < d->entries; ++e)
    if (!isfinite(x[e])) return 0;
  return 1;
}

// The stored value of a row's diagonal entry: first in its column of the
// lower triangle, last in the upper
static double *diagonal_entry(const fascia_direct *d, int64_t row) {
  const SuiteSparse_long *p = d->matrix->p;
  return (double *)d->matrix->x + (d->lower ? p[row] : p[row + 1] - 1);
}

// Writes the diagonal as the kept unshifted one plus shift * damping; 0
// where a value is not finite.
static int shift_diagonal(fascia_direct *d, const fascia_real *damping, fascia_real shift) {
  int finite = 1;
  for (int64_t u = 0; u < d->unknowns; ++u) {
    const int64_t row = d->free_index[u];
    if (row < 0) continue;
    double *diagonal = diagonal_entry(d, row);
    *diagonal = d->diagonal[row] + shift * damping[u];
    finite &= isfinite(*diagonal) != 0;
  }
  return finite;
}

// Factors the values in d->matrix (finite): 1, or 0 when not positive definite.
static int factor_values(fascia_direct *d) {
  // CHOLMOD's supernodal factorization may ask OpenMP for teams of its own,
  // for loops that only copy (the BLAS runs on one thread). With no active
  // level allowed, every one of its regions runs as a team of one: its teams
  // would compete with the solver's threads for the cores and sleep between
  // factorizations, and one thread is not slower; the bits are the same.
  // Dynamic adjustment would do the same but asks the kernel for the load in
  // every region (docs/mechanics.md, "CHOLMOD's threads").
  int factored;
#ifdef _OPENMP
  const int levels = omp_get_max_active_levels();
  omp_set_max_active_levels(0);
#endif
  factored = cholmod_l_factorize(d->matrix, d->factor, &d->common);
#ifdef _OPENMP
  omp_set_max_active_levels(levels);
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
  d->finite = values_finite(d);
  for (int64_t row = 0; row < d->free_count; ++row) d->diagonal[row] = *diagonal_entry(d, row);
  return shift_diagonal(d, damping, shift) && d->finite && factor_values(d);
}

int fascia_direct_refactor(fascia_direct *d, const fascia_real *damping, fascia_real shift) {
  if (d->finite != 1) return 0; // not finite under any shift (or nothing gathered)
  return shift_diagonal(d, damping, shift) && factor_values(d);
}

int64_t fascia_direct_values_count(const fascia_direct *d) { return d->entries; }

// The place among the stored values of the entry (column, row) of the
// walk's triangle: its column's rows are ascending (fill_matrix).
static int64_t stored_place(const fascia_direct *d, int64_t column, int64_t row) {
  const int64_t target = d->lower == (column < row) ? column : row, other = target == column ? row : column;
  const SuiteSparse_long *p = d->matrix->p, *rows = d->matrix->i;
  int64_t lo = p[target], hi = p[target + 1] - 1;
  while (lo < hi) {
    const int64_t mid = lo + (hi - lo) / 2;
    if (rows[mid] < other) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

void fascia_direct_values_save(const fascia_direct *d, const fascia_bsr *pattern, double *out) {
  const double *x = d->matrix->x;
  int64_t j = 0;
  FOR_EACH_ENTRY(d, pattern, out[j++] = x[stored_place(d, column, row)]);
}

int fascia_direct_values_load(fascia_direct *d, const fascia_bsr *pattern, const double *in) {
  double *x = d->matrix->x;
  int64_t j = 0;
  FOR_EACH_ENTRY(d, pattern, x[stored_place(d, column, row)] = in[j++]);
  d->finite = -1; // shifted values, not a base for fascia_direct_refactor
  return values_finite(d) && factor_values(d);
}

void fascia_direct_solve(fascia_direct *d, const fascia_real *rhs, fascia_real *x) {
  double *b = d->rhs->x;
  for (int64_t u = 0; u < d->unknowns; ++u)
    if (d->free_index[u] >= 0) b[d->free_index[u]] = rhs[u];
  cholmod_l_solve2(CHOLMOD_A, d->factor, d->rhs, NULL, &d->solution, NULL, &d->work_y, &d->work_e, &d->common);
  const double *s = d->solution->x;
  for (int64_t u = 0; u < d->unknowns; ++u) x[u] = d->free_index[u] >= 0 ? s[d->free_index[u]] : 0;
}
