// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Assembly of the block-sparse tangent and mass (see assemble.h). Row i of a
// symmetric operator equals the transpose of its column i, and column i of
// one sample's contribution is that sample's product with a unit vector on
// frame i: so every row is built from the frame's own reverse table.
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "cpu/assemble.h"
#include "cpu/dilatation.h"
#include "cpu/modes.h"
#include "util/index_set.h"

static int32_t find_block(const fascia_bsr *B, int32_t i, int32_t j);

// position[b]: where BSR block b is among chunk k's blocks (for b in them).
static void number_chunk_blocks(const fascia_bsr *B, int32_t k, int32_t *position) {
  for (int64_t t = B->chunk_block_offsets[k]; t < B->chunk_block_offsets[k + 1]; ++t)
    position[B->chunk_blocks[t]] = (int32_t)(t - B->chunk_block_offsets[k]);
}

// The chunks of whole samples whose local blocks fit the scratch, the BSR
// blocks each chunk adds to (ascending), and each one's entries: the chunk's
// local blocks it adds, in ascending e (transposed[e]: added transposed).
static fascia_status plan_chunks(fascia_ctx *ctx, const fascia_model *m, const unsigned char *transposed,
                                 fascia_bsr *B) {
  const int32_t S = m->sample_count;
  B->chunk_samples = fascia_calloc((int64_t)S + 1, sizeof(int32_t)); // at most one chunk per sample
  FASCIA_CHECK(B->chunk_samples, ctx, FASCIA_ERR_MEMORY, "assembly: out of memory for the plan");
  int32_t chunks = 0;
  for (int32_t s0 = 0; s0 < S; ++chunks) {
    int32_t s1 = s0 + 1;
    while (s1 < S && B->local_offsets[s1 + 1] - B->local_offsets[s0] <= B->chunk_capacity) ++s1;
    B->chunk_samples[chunks + 1] = s0 = s1;
  }
  B->chunk_count = chunks;
  B->chunk_block_offsets = fascia_calloc((int64_t)chunks + 1, sizeof(int64_t));
  int32_t *seen = fascia_calloc(B->blocks, sizeof(int32_t)); // the mark of the last chunk that touched each block
  if (!B->chunk_block_offsets || !seen) {
    free(seen);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "assembly: out of memory for the plan of %d chunks", (int)chunks);
  }
  // two walks, each chunk with its own mark: count each chunk's blocks, then list them
  for (int walk = 0; walk < 2; ++walk) {
    int64_t count = 0;
    for (int32_t k = 0; k < chunks; ++k) {
      const int32_t mark = walk * chunks + k + 1;
      const int64_t first = count;
      for (int64_t e = B->local_offsets[B->chunk_samples[k]]; e < B->local_offsets[B->chunk_samples[k + 1]]; ++e)
        if (seen[B->local_block[e]] != mark) {
          seen[B->local_block[e]] = mark;
          if (walk) B->chunk_blocks[count] = B->local_block[e];
          ++count;
        }
      if (walk) fascia_index_set_make(B->chunk_blocks + first, (int32_t)(count - first)); // unique already: sorts
      B->chunk_block_offsets[k + 1] = count;
    }
    if (!walk && !(B->chunk_blocks = fascia_calloc(count, sizeof(int32_t)))) {
      free(seen);
      return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "assembly: out of memory for the plan of %d chunks", (int)chunks);
    }
  }
  const int64_t T = B->chunk_block_offsets[chunks], E = B->local_offsets[m->sample_count];
  B->chunk_entry_offsets = fascia_calloc(T + 1, sizeof(int64_t));
  B->chunk_entries = fascia_calloc(E, sizeof(int32_t));
  B->chunk_entry_transposed = fascia_calloc(E, 1);
  int64_t *fill = fascia_calloc(T + 1, sizeof(int64_t));
  if (!B->chunk_entry_offsets || !B->chunk_entries || !B->chunk_entry_transposed || !fill) {
    free(seen), free(fill);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "assembly: out of memory for the plan of %lld local blocks",
                       (long long)E);
  }
  // seen, no longer needed as marks, holds the blocks' positions in the chunk being planned
  for (int32_t k = 0; k < chunks; ++k) {
    const int64_t e0 = B->local_offsets[B->chunk_samples[k]], e1 = B->local_offsets[B->chunk_samples[k + 1]];
    number_chunk_blocks(B, k, seen);
    for (int64_t e = e0; e < e1; ++e) ++B->chunk_entry_offsets[B->chunk_block_offsets[k] + seen[B->local_block[e]] + 1];
  }
  for (int64_t t = 0; t < T; ++t) B->chunk_entry_offsets[t + 1] += B->chunk_entry_offsets[t];
  memcpy(fill, B->chunk_entry_offsets, (size_t)T * sizeof(int64_t));
  for (int32_t k = 0; k < chunks; ++k) { // ascending e, so each block's entries ascend
    const int64_t e0 = B->local_offsets[B->chunk_samples[k]], e1 = B->local_offsets[B->chunk_samples[k + 1]];
    number_chunk_blocks(B, k, seen);
    for (int64_t e = e0; e < e1; ++e) {
      const int64_t c = fill[B->chunk_block_offsets[k] + seen[B->local_block[e]]]++;
      B->chunk_entries[c] = (int32_t)(e - e0);
      B->chunk_entry_transposed[c] = transposed[e];
    }
  }
  free(seen), free(fill);
  return FASCIA_OK;
}

// The assembly plan (see fascia_bsr in assemble.h).
static fascia_status plan(fascia_ctx *ctx, const fascia_model *m, fascia_bsr *B) {
  const int32_t S = m->sample_count;
  B->local_offsets = fascia_calloc((int64_t)S + 1, sizeof(int64_t));
  FASCIA_CHECK(B->local_offsets, ctx, FASCIA_ERR_MEMORY, "assembly: out of memory");
  for (int32_t s = 0; s < S; ++s) {
    const int64_t n = m->sample_offsets[s + 1] - m->sample_offsets[s];
    B->local_offsets[s + 1] = B->local_offsets[s] + n * (n + 1) / 2;
  }
  const int64_t E = B->local_offsets[S];
  B->local_block = fascia_calloc(E, sizeof(int32_t));
  B->mirror = fascia_calloc(B->blocks, sizeof(int32_t));
  B->chunk_capacity = FASCIA_ASSEMBLY_CHUNK;
  for (int32_t s = 0; s < S; ++s)
    if (B->local_offsets[s + 1] - B->local_offsets[s] > B->chunk_capacity)
      B->chunk_capacity = B->local_offsets[s + 1] - B->local_offsets[s];
  B->chunk = fascia_calloc(36 * B->chunk_capacity, sizeof(fascia_real));
  FASCIA_CHECK(B->local_block && B->mirror && B->chunk,
               ctx, FASCIA_ERR_MEMORY, "assembly: out of memory for %lld local blocks", (long long)E);
  // local block (a, b), a <= b, is K_ab: it adds to BSR block (i, j) of its
  // frames as it is where i <= j, else transposed (to block (j, i))
  unsigned char *transposed = fascia_calloc(E, 1);
  FASCIA_CHECK(transposed, ctx, FASCIA_ERR_MEMORY, "assembly: out of memory for %lld local blocks", (long long)E);
  for (int32_t s = 0; s < S; ++s) {
    const int32_t begin = m->sample_offsets[s], n = m->sample_offsets[s + 1] - begin;
    for (int32_t a = 0; a < n; ++a)
      for (int32_t b = a; b < n; ++b) {
        const int32_t fa = m->pair_frame[begin + a], fb = m->pair_frame[begin + b];
        const int64_t e = B->local_offsets[s] + fascia_pt_upper_block(n, a, b);
        const int32_t blk = fa <= fb ? find_block(B, fa, fb) : find_block(B, fb, fa);
        B->local_block[e] = blk;
        transposed[e] = fa > fb;
      }
  }
  B->block_row = fascia_calloc(B->blocks, sizeof(int32_t));
  if (!B->block_row) {
    free(transposed);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "assembly: out of memory for %lld blocks", (long long)B->blocks);
  }
  for (int32_t i = 0; i < B->rows; ++i)
    for (int32_t b = B->row_offsets[i]; b < B->row_offsets[i + 1]; ++b) {
      B->mirror[b] = B->cols[b] < i ? find_block(B, B->cols[b], i) : -1;
      B->block_row[b] = i;
    }
  const fascia_status status = plan_chunks(ctx, m, transposed, B);
  free(transposed);
  return status;
}

// Appends frame to row i's list unless the row has it (row_of: the row
// that last listed each frame), so that a row is sorted without its repeats:
// a frame of the hex beam meets its 27 neighbours about 20 times each
// through its samples and patches, and sorting the repeats dominated the set-up.
static inline void list_once(int32_t *row_of, int32_t i, int32_t frame, int32_t *row, int32_t *len) {
  if (row_of[frame] != i) row_of[frame] = i, row[(*len)++] = frame;
}

fascia_status fascia_bsr_create(fascia_ctx *ctx, const fascia_model *m, fascia_bsr *out) {
  memset(out, 0, sizeof *out);
  const int32_t N = m->frame_count;
  // a volumetric patch couples every two frames of its support
  fascia_patch_table patches;
  FASCIA_TRY(fascia_patch_table_build(ctx, m, &patches));
  // count with duplicates, then sort and unique each row
  int64_t total = 0;
  for (int32_t i = 0; i < N; ++i) {
    for (int32_t r = m->frame_offsets[i]; r < m->frame_offsets[i + 1]; ++r) {
      const int32_t s = fascia_model_pair_owner(m, m->frame_pairs[r]);
      total += m->sample_offsets[s + 1] - m->sample_offsets[s];
    }
    for (int32_t r = patches.patch_count ? patches.frame_entry_offsets[i] : 0;
         patches.patch_count && r < patches.frame_entry_offsets[i + 1]; ++r) {
      const int32_t p = patches.entry_patch[patches.frame_entries[r]];
      total += patches.support_offsets[p + 1] - patches.support_offsets[p];
    }
  }
  int32_t *scratch = fascia_calloc(total + N, sizeof(int32_t));
  int32_t *row_of = fascia_calloc(N, sizeof(int32_t)); // the row that last listed each frame
  out->row_offsets = fascia_calloc((int64_t)N + 1, sizeof(int32_t));
  out->diagonal = fascia_calloc(N, sizeof(int32_t));
  if (!scratch || !row_of || !out->row_offsets || !out->diagonal) {
    free(scratch), free(row_of);
    fascia_patch_table_free(&patches);
    fascia_bsr_destroy(out);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "assembly: out of memory for the block pattern (%lld entries)",
                       (long long)total);
  }
  int64_t count = 0;
  for (int32_t j = 0; j < N; ++j) row_of[j] = -1;
  for (int32_t i = 0; i < N; ++i) {
    int32_t *row = scratch + count, len = 0;
    list_once(row_of, i, i, row, &len);
    for (int32_t r = m->frame_offsets[i]; r < m->frame_offsets[i + 1]; ++r) {
      const int32_t s = fascia_model_pair_owner(m, m->frame_pairs[r]);
      for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k)
        list_once(row_of, i, m->pair_frame[k], row, &len);
    }
    for (int32_t r = patches.patch_count ? patches.frame_entry_offsets[i] : 0;
         patches.patch_count && r < patches.frame_entry_offsets[i + 1]; ++r) {
      const int32_t p = patches.entry_patch[patches.frame_entries[r]];
      for (int32_t e = patches.support_offsets[p]; e < patches.support_offsets[p + 1]; ++e)
        list_once(row_of, i, patches.entry_frame[e], row, &len);
    }
    count += fascia_index_set_make(row, len);
    out->row_offsets[i + 1] = (int32_t)count;
  }
  free(row_of);
  fascia_patch_table_free(&patches);
  out->rows = N;
  out->blocks = count;
  out->cols = fascia_index_set_trim(scratch, count);
  out->values = fascia_calloc(36 * count, sizeof(fascia_real));
  if (!out->values) {
    fascia_bsr_destroy(out);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "assembly: out of memory for %lld 6x6 blocks", (long long)count);
  }
  for (int32_t i = 0; i < N; ++i)
    for (int32_t b = out->row_offsets[i]; b < out->row_offsets[i + 1]; ++b)
      if (out->cols[b] == i) out->diagonal[i] = b;
  return plan(ctx, m, out);
}

void fascia_bsr_destroy(fascia_bsr *bsr) {
  fascia_bsr_single_release(bsr);
  free(bsr->local_offsets);
  free(bsr->local_block);
  free(bsr->chunk_entry_offsets);
  free(bsr->chunk_entries);
  free(bsr->chunk_entry_transposed);
  free(bsr->mirror);
  free(bsr->block_row);
  free(bsr->chunk_samples);
  free(bsr->chunk_block_offsets);
  free(bsr->chunk_blocks);
  free(bsr->add_offsets);
  free(bsr->add_blocks);
  free(bsr->chunk);
  free(bsr->row_offsets);
  free(bsr->cols);
  free(bsr->diagonal);
  free(bsr->values);
  memset(bsr, 0, sizeof *bsr);
}

static int32_t find_block(const fascia_bsr *B, int32_t i, int32_t j) {
  return fascia_index_set_find(B->cols, B->row_offsets[i], B->row_offsets[i + 1], j);
}

// Rows of the consistent mass: for each sample of frame i, the product with
// unit vectors on frame i's slot gives column i, which is row i transposed
// (the mass is symmetric).
static void mass_rows(fascia_system *sys, const unsigned char *moves, fascia_bsr *B, fascia_real coefficient) {
  const fascia_model *m = sys->model;
  const fascia_pt_state st = {sys->x, sys->A_mass};
  const int32_t maxn = sys->max_neighbours;
#pragma omp parallel num_threads(sys->threads)
  {
    fascia_real *dq = calloc(6 * (size_t)maxn, sizeof(fascia_real));
    fascia_real *col = calloc(6 * (size_t)maxn, sizeof(fascia_real));
#pragma omp for schedule(static)
    for (int32_t i = 0; i < sys->frame_count; ++i) {
      if (!dq || !col) continue; // out of memory in a worker: rows stay as they were
      if (!fascia_frame_moving(moves, i)) continue;
      for (int32_t r = m->frame_offsets[i]; r < m->frame_offsets[i + 1]; ++r) {
        const int32_t k = m->frame_pairs[r], s = sys->pair_sample[k], begin = m->sample_offsets[s];
        const int32_t n = m->sample_offsets[s + 1] - begin, j = k - begin;
        for (int c = 0; c < 6; ++c) {
          dq[6 * j + c] = 1;
          fascia_pt_sample_mass(&sys->pm, &st, s, sys->sample_mass[s], dq, sys->local_slot, col);
          dq[6 * j + c] = 0;
          for (int32_t l = 0; l < n; ++l) {
            if (!fascia_frame_moving(moves, m->pair_frame[begin + l])) continue;
            fascia_real *blk = B->values + 36 * (int64_t)find_block(B, i, m->pair_frame[begin + l]);
            for (int a = 0; a < 6; ++a) blk[6 * c + a] += coefficient * col[6 * l + a];
          }
        }
      }
    }
    free(dq);
    free(col);
  }
}

// Local stiffness of sample s into out (its blocks (a, b), a <= b, at
// fascia_pt_upper_block): the paper's terms in closed form (the rotation
// smoothing is added per frame pair: smoothing_rows), the rotation
// coupling, when on, as products with the 6n unit
// vectors of the sample (its upper blocks: the assembled matrix is
// symmetric). Blocks with a frame not in moves are left unwritten. A
// sample in patch p >= 0 with enhanced strain modes also leaves its shares
// of the modes' terms (sim/src/cpu/modes.h) from its D and B^T D.
// dq, col: 6 max_neighbours reals; scratch: 66 max_neighbours. Its loops
// over the sample's pairs are compiled wide (wide.h), where AVX2 pays.
WIDE_CLONES static void local_stiffness(const fascia_system *sys, const fascia_pt_state *st, const unsigned char *moves,
                            int32_t s, int32_t p, fascia_real *out, fascia_real *dq, fascia_real *col,
                            fascia_real *scratch) {
  const fascia_model *m = sys->model;
  const fascia_real *cache = sys->cache + (int64_t)s * FASCIA_PT_CACHE_SIZE;
  const int32_t begin = m->sample_offsets[s], n = m->sample_offsets[s + 1] - begin;
  const fascia_modes *md = sys->modes;
  fascia_real Dv[81], *BtDv = scratch + 12 * sys->max_neighbours;
  fascia_pt_sample_local_stiffness(&sys->pm, st, s, cache, moves, scratch, out, p >= 0 ? Dv : NULL,
                                   p >= 0 ? BtDv : NULL);
  if (p >= 0) {
    const fascia_real *xi = md->sample_xi + 3 * (int64_t)s;
    fascia_pt_modes_sample_share(&md->view, p, xi, Dv, md->sample_share + 81 * (int64_t)s);
    for (int32_t a = 0; a < n; ++a)
      fascia_pt_modes_pair_share(&md->view, p, xi, BtDv + 54 * a, md->pair_share + 54 * (int64_t)(begin + a));
  }
  if (sys->sample_coupling[s] == 0) return;
  for (int32_t b = 0; b < n; ++b) {
    if (!fascia_frame_moving(moves, m->pair_frame[begin + b])) continue;
    for (int c = 0; c < 6; ++c) {
      dq[6 * b + c] = 1;
      fascia_pt_sample_stiffness_parts(&sys->pm, st, s, cache, dq, sys->local_slot, col, FASCIA_PT_PART_COUPLING);
      dq[6 * b + c] = 0;
      for (int32_t a = 0; a <= b; ++a)
        for (int r = 0; r < 6; ++r) out[36 * fascia_pt_upper_block(n, a, b) + 6 * r + c] += col[6 * a + r];
    }
  }
}

// The volumetric patches' rank-one terms lambda_p / V_p G_p G_p^T, row by
// row, on the upper blocks.
// Frame i's row of the patches' rank-one terms. A patch's support frames
// ascend, and so do row i's blocks: one merged walk finds each block (a
// search per block was a quarter of this row's time), and the products are
// made on local copies, which the compiler can make wide.
WIDE_CLONES static void dilatation_row(const fascia_dilatation *d, const unsigned char *moves, fascia_bsr *B,
                                       int32_t i) {
  const fascia_patch_table *t = &d->table;
  const int32_t row_end = B->row_offsets[i + 1];
  for (int32_t r = t->frame_entry_offsets[i]; r < t->frame_entry_offsets[i + 1]; ++r) {
    const int32_t e = t->frame_entries[r], p = t->entry_patch[e];
    const fascia_real c = d->patch_lambda[p] / d->patch_volume[p];
    fascia_real cGi[6];
    for (int a = 0; a < 6; ++a) cGi[a] = c * d->entry_gradient[6 * (int64_t)e + a];
    int32_t place = B->row_offsets[i];
    // entries f > e of the support are the frames j > i; e itself is (i, i)
    for (int32_t f = e; f < t->support_offsets[p + 1]; ++f) {
      const int32_t j = t->entry_frame[f];
      if (!fascia_frame_moving(moves, j)) continue;
      while (place < row_end && B->cols[place] < j) ++place;
      fascia_real Gj[6], *FASCIA_RESTRICT blk = B->values + 36 * (int64_t)place;
      for (int b = 0; b < 6; ++b) Gj[b] = d->entry_gradient[6 * (int64_t)f + b];
      for (int a = 0; a < 6; ++a)
        for (int b = 0; b < 6; ++b) blk[6 * a + b] += cGi[a] * Gj[b];
    }
  }
}

static void dilatation_rows(const fascia_system *sys, const unsigned char *moves, fascia_bsr *B) {
  fascia_dilatation *d = sys->dilatation;
  fascia_dilatation_gradients(sys, d);
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t i = 0; i < sys->frame_count; ++i)
    if (fascia_frame_moving(moves, i)) dilatation_row(d, moves, B, i);
}

// The rotation smoothing's frame graph (fascia_system: smoothing_offsets),
// made by the first assembly (a solver that never assembles has no use for
// it): counted, then filled, each row through the frame's reverse table in
// a fixed order. Without smoothing only the offsets, all 0. Returns 0 when
// out of memory.
static int smoothing_graph(fascia_system *sys) {
  const fascia_model *m = sys->model;
  const int32_t N = m->frame_count;
  int any = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) any |= sys->sample_curvature[s] > 0;
  if (!any) return (sys->smoothing_offsets = fascia_calloc((int64_t)N + 1, sizeof(int32_t))) != NULL;
  int32_t *row_of = fascia_calloc(N, sizeof(int32_t)), *place = fascia_calloc(N, sizeof(int32_t));
  sys->smoothing_offsets = fascia_calloc((int64_t)N + 1, sizeof(int32_t));
  if (!row_of || !place || !sys->smoothing_offsets) {
    free(row_of), free(place);
    return 0;
  }
  for (int32_t j = 0; j < N; ++j) row_of[j] = -1;
  for (int pass = 0; pass < 2; ++pass) {
    for (int32_t i = 0; i < N; ++i) {
      int32_t count = 0;
      const int32_t base = sys->smoothing_offsets[i];
      for (int32_t r = m->frame_offsets[i]; r < m->frame_offsets[i + 1]; ++r) {
        const int32_t k = m->frame_pairs[r], s = sys->pair_sample[k];
        const fascia_real vk = m->sample_volume[s] * sys->sample_curvature[s];
        if (!(vk > 0)) continue;
        for (int32_t l = m->sample_offsets[s]; l < m->sample_offsets[s + 1]; ++l) {
          const int32_t j = m->pair_frame[l];
          if (row_of[j] != pass * N + i) { // first met in this row
            row_of[j] = pass * N + i;
            place[j] = count++;
            if (pass) sys->smoothing_frames[base + place[j]] = j;
          }
          if (pass)
            sys->smoothing_weight[base + place[j]] +=
                vk * fascia_pt_dot3(m->pair_gradient + 3 * k, m->pair_gradient + 3 * l);
        }
      }
      if (!pass) sys->smoothing_offsets[i + 1] = sys->smoothing_offsets[i] + count;
    }
    if (!pass) {
      const int32_t E = sys->smoothing_offsets[N];
      sys->smoothing_frames = fascia_calloc(E, sizeof(int32_t));
      sys->smoothing_weight = fascia_calloc(E, sizeof(fascia_real));
      if (!sys->smoothing_frames || !sys->smoothing_weight) break;
    }
  }
  free(row_of), free(place);
  return sys->smoothing_frames && sys->smoothing_weight;
}

// The rotation smoothing's theta-theta blocks from its frame graph
// (system.h: 1/2 sum_ij W_ij <A_i, A_j>), row by row, on the upper blocks:
// block (i, j) gets W_ij (tr(Q) I - Q), Q = A_j A_i^T, and the diagonal
// block also A_i N_i^T - tr(A_i N_i^T) I with N_i = sum_j W_ij A_j (its
// geometric part). Per sample, as it was, the same terms cost 8 % of the
// static 20x3x3 hex cantilever; per frame pair a tenth of that.
static void smoothing_rows(const fascia_system *sys, const unsigned char *moves, fascia_bsr *B) {
  const int32_t *offsets = sys->smoothing_offsets, *frames = sys->smoothing_frames;
  const fascia_real *W = sys->smoothing_weight, *A = sys->A;
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t i = 0; i < sys->frame_count; ++i) {
    if (!fascia_frame_moving(moves, i)) continue;
    const fascia_real *Ai = A + 9 * (int64_t)i;
    fascia_real N[9] = {0}, X[9];
    for (int32_t e = offsets[i]; e < offsets[i + 1]; ++e) {
      const int32_t j = frames[e];
      for (int q = 0; q < 9; ++q) N[q] += W[e] * A[9 * (int64_t)j + q];
      if (j < i || !fascia_frame_moving(moves, j)) continue;
      fascia_real Q[9];
      fascia_pt_mat_mult(A + 9 * (int64_t)j, Ai, Q);
      const fascia_real trQ = fascia_pt_trace(Q);
      fascia_real *K = B->values + 36 * (int64_t)find_block(B, i, j);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) K[6 * (3 + r) + 3 + c] += W[e] * ((r == c ? trQ : 0) - Q[3 * r + c]);
    }
    fascia_pt_mat_mult(Ai, N, X);
    const fascia_real trX = fascia_pt_trace(X);
    fascia_real *K = B->values + 36 * (int64_t)B->diagonal[i];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) K[6 * (3 + r) + 3 + c] += X[3 * r + c] - (r == c ? trX : 0);
  }
}

// The enhanced strain modes' condensed terms -K_ue K_aa^-1 K_uf^T, row by
// row, on the upper blocks.
static void modes_rows(const fascia_system *sys, const unsigned char *moves, fascia_bsr *B) {
  fascia_modes *md = sys->modes;
  fascia_modes_tangent(sys, md);
  const fascia_pt_patches *t = &sys->dilatation->view;
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t i = 0; i < sys->frame_count; ++i) {
    if (!fascia_frame_moving(moves, i)) continue;
    for (int32_t r = t->frame_entry_offsets[i]; r < t->frame_entry_offsets[i + 1]; ++r) {
      const int32_t e = t->frame_entries[r], p = t->entry_patch[e];
      for (int32_t f = t->support_offsets[p]; f < t->support_offsets[p + 1]; ++f) {
        if (t->entry_frame[f] < i || !fascia_frame_moving(moves, t->entry_frame[f])) continue;
        fascia_pt_modes_block_add(t, &md->view, e, f, B->values + 36 * (int64_t)find_block(B, i, t->entry_frame[f]));
      }
    }
  }
}

// Whether sample s has a frame that moves.
static int sample_moves(const fascia_model *m, const unsigned char *moves, int32_t s) {
  for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k)
    if (fascia_frame_moving(moves, m->pair_frame[k])) return 1;
  return 0;
}

// The u-th of T near-equal runs [*first, *end) of the count items from begin.
static void team_share(int64_t begin, int64_t count, int u, int T, int64_t *first, int64_t *end) {
  const int64_t q = count / T, r = count % T;
  *first = begin + u * q + (u < r ? u : r);
  *end = *first + q + (u < r);
}

// Which of the T runs of chunk k's samples gave each of block t's entries
// (votes[u]: how many from run u; run_end: where each run's local blocks end).
static void count_votes(const fascia_bsr *B, int64_t t, int T, const int64_t *run_end, int64_t *votes) {
  for (int u = 0; u < T; ++u) votes[u] = 0;
  for (int64_t c = B->chunk_entry_offsets[t]; c < B->chunk_entry_offsets[t + 1]; ++c) {
    int u = 0;
    while (B->chunk_entries[c] >= run_end[u]) ++u;
    ++votes[u];
  }
}

// B->add_offsets and add_blocks for a team of T > 1 (fascia_bsr in
// assemble.h; one thread adds every block, in order, from no lists, so a
// team that changes between one and more threads keeps its lists): each
// block goes to the thread whose samples gave most of its entries, while
// that thread adds no more than its share of the chunk's entries (a 32nd
// over an even share); the others, in a second pass, to the thread with
// most of their entries that has room, or the one with the least.
// 0: out of memory.
static int plan_adds(fascia_bsr *B, int T) {
  free(B->add_offsets), free(B->add_blocks);
  B->adds_team = 0;
  const int64_t total = B->chunk_block_offsets[B->chunk_count];
  B->add_offsets = fascia_calloc((int64_t)B->chunk_count * T + 1, sizeof(int64_t));
  B->add_blocks = fascia_calloc(total, sizeof(int32_t));
  int32_t *owner = fascia_calloc(total, sizeof(int32_t));
  int64_t *votes = fascia_calloc(3 * (int64_t)T, sizeof(int64_t)), *run_end = votes + T, *load = votes + 2 * T;
  if (!B->add_offsets || !B->add_blocks || !owner || !votes) {
    free(owner), free(votes);
    return 0;
  }
  int64_t count = 0;
  B->add_offsets[0] = 0;
  for (int32_t k = 0; k < B->chunk_count; ++k) {
    const int32_t s0 = B->chunk_samples[k], s1 = B->chunk_samples[k + 1];
    const int64_t e0 = B->local_offsets[s0], t0 = B->chunk_block_offsets[k], t1 = B->chunk_block_offsets[k + 1];
    const int64_t entries = B->chunk_entry_offsets[t1] - B->chunk_entry_offsets[t0];
    const int64_t cap = (entries + T - 1) / T + entries / 32;
    for (int u = 0; u < T; ++u) { // where each thread's samples' local blocks end
      int64_t first, end;
      team_share(s0, s1 - s0, u, T, &first, &end);
      run_end[u] = B->local_offsets[end] - e0;
      load[u] = 0;
    }
    for (int pass = 0; pass < 2; ++pass)
      for (int64_t t = t0; t < t1; ++t) {
        if (pass == 1 && owner[t] >= 0) continue;
        const int64_t size = B->chunk_entry_offsets[t + 1] - B->chunk_entry_offsets[t];
        count_votes(B, t, T, run_end, votes);
        int best = -1;
        if (pass == 0) { // the majority's thread, if it has room
          int major = 0;
          for (int u = 1; u < T; ++u)
            if (votes[u] > votes[major]) major = u;
          if (load[major] + size <= cap) best = major;
        } else { // the thread with room that gave the most, else the least loaded
          for (int u = 0; u < T; ++u)
            if (load[u] + size <= cap && (best < 0 || votes[u] > votes[best])) best = u;
          if (best < 0) {
            best = 0;
            for (int u = 1; u < T; ++u)
              if (load[u] < load[best]) best = u;
          }
        }
        owner[t] = best;
        if (best >= 0) load[best] += size;
      }
    for (int u = 0; u < T; ++u) {
      for (int64_t t = t0; t < t1; ++t)
        if (owner[t] == u) B->add_blocks[count++] = (int32_t)(t - t0);
      B->add_offsets[(int64_t)k * T + u + 1] = count;
    }
  }
  free(owner), free(votes);
  B->adds_team = T;
  return 1;
}

// Adds to BSR block chunk_blocks[t] its entries, local blocks of the
// chunk in B->chunk, in ascending order. Its sums are compiled wide
// (wide.h) and give the same bits as the baseline build's.
WIDE_CLONES static void add_contributions(fascia_bsr *B, int64_t t) {
  fascia_real *FASCIA_RESTRICT dst = B->values + 36 * (int64_t)B->chunk_blocks[t];
  for (int64_t c = B->chunk_entry_offsets[t]; c < B->chunk_entry_offsets[t + 1]; ++c) {
    const fascia_real *FASCIA_RESTRICT src = B->chunk + 36 * (int64_t)B->chunk_entries[c];
    if (B->chunk_entry_transposed[c])
      for (int r = 0; r < 6; ++r)
        for (int q = 0; q < 6; ++q) dst[6 * r + q] += src[6 * q + r];
    else
      for (int q = 0; q < 36; ++q) dst[q] += src[q];
  }
}

int fascia_system_hessian_assemble(fascia_system *sys, const unsigned char *moves, fascia_bsr *B) {
  const fascia_pt_state st = {sys->x, sys->A};
  int out_of_memory = 0;
  fascia_modes *md = sys->modes;
  const int shares = md && fascia_modes_shares_ready(sys, md);
  if (!sys->smoothing_offsets && !smoothing_graph(sys)) return 0;
  memset(B->values, 0, 36 * (size_t)B->blocks * sizeof(fascia_real));
#pragma omp parallel num_threads(sys->threads) reduction(| : out_of_memory)
  {
#ifdef _OPENMP
    const int T = omp_get_num_threads(), u = omp_get_thread_num(); // the team may be smaller than asked
#else
    const int T = 1, u = 0;
#endif
    fascia_real *dq = calloc(78 * (size_t)sys->max_neighbours, sizeof(fascia_real));
    out_of_memory = !dq;
#pragma omp single
    if (T > 1 && B->adds_team != T && !plan_adds(B, T)) out_of_memory = 1;
    const int planned = T == 1 || B->adds_team == T; // read by all after the single's barrier
    for (int32_t k = 0; planned && k < B->chunk_count; ++k) {
      const int32_t s0 = B->chunk_samples[k], s1 = B->chunk_samples[k + 1];
      const int64_t e0 = B->local_offsets[s0], t0 = B->chunk_block_offsets[k];
      int64_t first, end;
      team_share(s0, s1 - s0, u, T, &first, &end);
      // a sample with modes leaves its shares even where no frame of it moves
      for (int32_t s = (int32_t)first; s < end; ++s) {
        const int32_t p = shares ? fascia_modes_sample_patch(sys, md, s) : -1;
        if (dq && (p >= 0 || sample_moves(sys->model, moves, s)))
          local_stiffness(sys, &st, moves, s, p, B->chunk + 36 * (B->local_offsets[s] - e0), dq,
                          dq + 6 * sys->max_neighbours, dq + 12 * sys->max_neighbours);
      }
#pragma omp barrier
      // the chunk's upper blocks this thread adds (the lower ones are
      // mirrored at the end); a block of two moving frames has
      // contributions from moving samples only
      const int64_t i0 = T == 1 ? 0 : B->add_offsets[(int64_t)k * T + u];
      const int64_t i1 = T == 1 ? B->chunk_block_offsets[k + 1] - t0 : B->add_offsets[(int64_t)k * T + u + 1];
      for (int64_t i = i0; i < i1; ++i) {
        const int64_t t = t0 + (T == 1 ? i : B->add_blocks[i]);
        const int32_t b = B->chunk_blocks[t];
        if (!fascia_frame_moving(moves, B->block_row[b]) || !fascia_frame_moving(moves, B->cols[b])) continue;
        add_contributions(B, t);
      }
#pragma omp barrier
    }
    free(dq);
  }
  if (out_of_memory) return 0;
  if (shares) md->shares_current = 1;
  if (sys->smoothing_weight) smoothing_rows(sys, moves, B);
  if (sys->dilatation) dilatation_rows(sys, moves, B);
  if (sys->modes) modes_rows(sys, moves, B);
  // frame-local terms: gravity (theta-theta) and the symmetrizing 1/2 [g_theta]x
  const fascia_real gs = sys->gravity_scale, *g = sys->gravity;
  for (int32_t i = 0; i < sys->frame_count; ++i) {
    if (!fascia_frame_moving(moves, i)) continue;
    fascia_real *D = B->values + 36 * (int64_t)B->diagonal[i], b[3];
    fascia_pt_mat_vec(sys->A + 9 * i, sys->frame_moment + 3 * i, b);
    const fascia_real bg = fascia_pt_dot3(b, g), *t = sys->conservative_torque + 3 * i;
    const fascia_real skew[9] = {0, -t[2], t[1], t[2], 0, -t[0], -t[1], t[0], 0};
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c)
        D[6 * (3 + a) + 3 + c] += -gs * (b[a] * g[c] - (a == c ? bg : 0)) + FASCIA_R(0.5) * skew[3 * a + c];
    for (int a = 0; a < 6; ++a) // symmetric up to rounding: make it exactly so
      for (int c = a + 1; c < 6; ++c) D[6 * a + c] = D[6 * c + a] = FASCIA_R(0.5) * (D[6 * a + c] + D[6 * c + a]);
  }
  // the lower blocks: the upper ones transposed
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int64_t b = 0; b < B->blocks; ++b) {
    if (B->mirror[b] < 0) continue;
    const fascia_real *src = B->values + 36 * (int64_t)B->mirror[b];
    fascia_real *dst = B->values + 36 * b;
    for (int r = 0; r < 6; ++r)
      for (int q = 0; q < 6; ++q) dst[6 * r + q] = src[6 * q + r];
  }
  return 1;
}

void fascia_system_mass_assemble_add(fascia_system *sys, const unsigned char *moves, fascia_real coefficient,
                                     fascia_bsr *B) {
  mass_rows(sys, moves, B, coefficient);
}
