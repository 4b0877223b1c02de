// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Mean dilatation over volumetric patches (see dilatation.h). Every sum runs
// in a fixed order (patch by patch, entries ascending), so the results are
// bit-identical for any thread count.
#include <stdlib.h>
#include <string.h>

#include "cpu/dilatation.h"
#include "cpu/wide.h"
#include "util/index_set.h"

void fascia_patch_table_free(fascia_patch_table *t) {
#define FREE_ARRAY(name) free(t->name);
  FASCIA_PATCH_TABLE_ARRAYS(FREE_ARRAY)
#undef FREE_ARRAY
  memset(t, 0, sizeof *t);
}

// Entry of frame i in patch p's support.
static int32_t find_entry(const fascia_patch_table *t, int32_t p, int32_t i) {
  return fascia_index_set_find(t->entry_frame, t->support_offsets[p], t->support_offsets[p + 1], i);
}

fascia_status fascia_patch_table_build(fascia_ctx *ctx, const fascia_model *m, fascia_patch_table *t) {
  memset(t, 0, sizeof *t);
  const int32_t S = m->sample_count, N = m->frame_count;
  int32_t *compact = fascia_calloc(S, sizeof(int32_t)), patched = 0;
  FASCIA_CHECK(compact, ctx, FASCIA_ERR_MEMORY, "patches: out of memory");
  // compact numbers, ascending in the model's patch numbers
  for (int32_t s = 0; s < S; ++s)
    if (m->sample_patch[s] >= 0) {
      compact[m->sample_patch[s]] = 1;
      ++patched;
    }
  int32_t P = 0;
  for (int32_t p = 0; p < S; ++p) compact[p] = compact[p] ? P++ : -1;
  if (P == 0) {
    free(compact);
    return FASCIA_OK;
  }
  t->patch_count = P;
  t->patch_offsets = fascia_calloc((int64_t)P + 1, sizeof(int32_t));
  t->patch_samples = fascia_calloc(patched, sizeof(int32_t));
  t->support_offsets = fascia_calloc((int64_t)P + 1, sizeof(int32_t));
  t->pair_entry = fascia_calloc(m->pair_count, sizeof(int32_t));
  t->frame_entry_offsets = fascia_calloc((int64_t)N + 1, sizeof(int32_t));
  int64_t pair_total = 0;
  for (int32_t s = 0; s < S; ++s)
    if (m->sample_patch[s] >= 0) pair_total += m->sample_offsets[s + 1] - m->sample_offsets[s];
  int32_t *frames = fascia_calloc(pair_total, sizeof(int32_t));
  if (!t->patch_offsets || !t->patch_samples || !t->support_offsets || !t->pair_entry || !t->frame_entry_offsets ||
      !frames) {
    free(compact);
    free(frames);
    fascia_patch_table_free(t);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "patches: out of memory for %d patches", (int)P);
  }
  for (int32_t s = 0; s < S; ++s)
    if (m->sample_patch[s] >= 0) t->patch_offsets[compact[m->sample_patch[s]] + 1]++;
  for (int32_t p = 0; p < P; ++p) t->patch_offsets[p + 1] += t->patch_offsets[p];
  {
    int32_t *cursor = t->support_offsets; // borrowed as scratch until the supports are counted
    memcpy(cursor, t->patch_offsets, (size_t)P * sizeof(int32_t));
    for (int32_t s = 0; s < S; ++s)
      if (m->sample_patch[s] >= 0) t->patch_samples[cursor[compact[m->sample_patch[s]]]++] = s;
  }
  // each patch's distinct frames, sorted, packed in place
  int64_t count = 0;
  t->support_offsets[0] = 0;
  for (int32_t p = 0; p < P; ++p) {
    int32_t *row = frames + count, len = 0;
    for (int32_t q = t->patch_offsets[p]; q < t->patch_offsets[p + 1]; ++q) {
      const int32_t s = t->patch_samples[q];
      for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k) row[len++] = m->pair_frame[k];
    }
    count += fascia_index_set_make(row, len);
    t->support_offsets[p + 1] = (int32_t)count;
  }
  t->entry_count = (int32_t)count;
  t->entry_frame = fascia_index_set_trim(frames, count);
  t->entry_patch = fascia_calloc(count, sizeof(int32_t));
  t->frame_entries = fascia_calloc(count, sizeof(int32_t));
  if (!t->entry_patch || !t->frame_entries) {
    free(compact);
    fascia_patch_table_free(t);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "patches: out of memory for %lld support entries", (long long)count);
  }
  for (int32_t p = 0; p < P; ++p)
    for (int32_t e = t->support_offsets[p]; e < t->support_offsets[p + 1]; ++e) t->entry_patch[e] = p;
  for (int32_t k = 0; k < m->pair_count; ++k) t->pair_entry[k] = -1;
  for (int32_t s = 0; s < S; ++s)
    if (m->sample_patch[s] >= 0)
      for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k)
        t->pair_entry[k] = find_entry(t, compact[m->sample_patch[s]], m->pair_frame[k]);
  free(compact);
  // frame -> entries, ascending
  for (int32_t e = 0; e < t->entry_count; ++e) t->frame_entry_offsets[t->entry_frame[e] + 1]++;
  for (int32_t i = 0; i < N; ++i) t->frame_entry_offsets[i + 1] += t->frame_entry_offsets[i];
  int32_t *cursor = fascia_calloc(N, sizeof(int32_t));
  if (!cursor) {
    fascia_patch_table_free(t);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "patches: out of memory");
  }
  memcpy(cursor, t->frame_entry_offsets, (size_t)N * sizeof(int32_t));
  for (int32_t e = 0; e < t->entry_count; ++e) t->frame_entries[cursor[t->entry_frame[e]]++] = e;
  free(cursor);
  return FASCIA_OK;
}

// lambda_s of dilatation.h: with it lambda_s + 2 mu is Young's modulus, the
// stiffness of a dilatation the frames cannot pair with a lateral contraction.
static fascia_real sample_lambda_in_patch(fascia_real lambda, fascia_real mu) {
  return lambda > 0 && mu > 0 ? lambda * mu / (lambda + mu) : 0;
}

fascia_status fascia_dilatation_create(fascia_system *sys, fascia_dilatation **out) {
  *out = NULL;
  const fascia_model *m = sys->model;
  fascia_patch_table table;
  FASCIA_TRY(fascia_patch_table_build(sys->ctx, m, &table));
  if (table.patch_count == 0) return FASCIA_OK;
  fascia_dilatation *d = calloc(1, sizeof *d);
  if (!d) {
    fascia_patch_table_free(&table);
    return FASCIA_FAIL(sys->ctx, FASCIA_ERR_MEMORY, "patches: out of memory");
  }
  d->table = table;
  const int32_t P = table.patch_count;
  const int64_t E = table.entry_count, S = m->sample_count;
  int allocated = 1;
#define ALLOC_ARRAY(name, type, count, width, view_name) FASCIA_ALLOC_ROW(d, allocated, name, type, count, width);
  FASCIA_DILATATION_ARRAYS(ALLOC_ARRAY)
#undef ALLOC_ARRAY
  if (!allocated) {
    fascia_dilatation_destroy(&d);
    return FASCIA_FAIL(sys->ctx, FASCIA_ERR_MEMORY, "patches: out of memory for %d patches", (int)P);
  }
  for (int32_t p = 0; p < P; ++p) {
    // validation guarantees one material per patch
    const int32_t first = table.patch_samples[table.patch_offsets[p]];
    const fascia_real own = sample_lambda_in_patch(sys->sample_lambda[first], sys->sample_mu[first]);
    d->patch_lambda[p] = sys->sample_lambda[first] - own;
    d->patch_law[p] = sys->sample_law[first];
    for (int32_t q = table.patch_offsets[p]; q < table.patch_offsets[p + 1]; ++q) {
      const int32_t s = table.patch_samples[q];
      d->patch_volume[p] += m->sample_volume[s];
      sys->sample_lambda[s] = own; // the patch carries the rest
    }
  }
  sys->pm.sample_pressure = d->sample_pressure;
  fascia_pt_patches *v = &d->view;
  v->count = P;
#define VIEW_TABLE(name) v->name = table.name;
  FASCIA_PATCH_TABLE_ARRAYS(VIEW_TABLE)
#undef VIEW_TABLE
#define VIEW_ARRAY(name, type, count, width, view_name) v->view_name = d->name;
  FASCIA_DILATATION_ARRAYS(VIEW_ARRAY)
#undef VIEW_ARRAY
  *out = d;
  return FASCIA_OK;
}

void fascia_dilatation_destroy(fascia_dilatation **dilatation) {
  if (!dilatation || !*dilatation) return;
  fascia_dilatation *d = *dilatation;
  fascia_patch_table_free(&d->table);
#define FREE_ARRAY(name, ...) free(d->name);
  FASCIA_DILATATION_ARRAYS(FREE_ARRAY)
#undef FREE_ARRAY
  free(d);
  *dilatation = NULL;
}

// One patch's mean dilatation and its gradient, compiled wide (wide.h).
WIDE_CLONES static void patch_evaluate(const fascia_system *sys, const fascia_pt_state *st, fascia_dilatation *d,
                                       int32_t p) {
  fascia_pt_patch_evaluate(&sys->pm, st, &d->view, p);
}

WIDE_CLONES static void patch_gradient(const fascia_system *sys, const fascia_pt_state *st, fascia_dilatation *d,
                                       int32_t p) {
  fascia_pt_patch_gradient(&sys->pm, st, &d->view, p);
}

// F of the samples [begin, end) that are in patches, compiled wide. In sample
// order the pairs' data stream from memory; patch by patch they were read
// out of order, and computing F there took over a quarter of a prepared
// scene's evaluation (abdomen-female, one thread).
WIDE_CLONES static void samples_F(const fascia_system *sys, const fascia_pt_state *st, fascia_dilatation *d,
                                  int32_t begin, int32_t end) {
  const int32_t *patch = sys->model->sample_patch;
  for (int32_t s = begin; s < end; ++s)
    if (patch[s] >= 0) fascia_pt_sample_F(&sys->pm, st, s, d->sample_F + 9 * (int64_t)s);
}

fascia_real fascia_dilatation_evaluate(fascia_system *sys, fascia_dilatation *d) {
  const fascia_pt_state st = {sys->x, sys->A};
  const int32_t S = sys->sample_count, block = 256;
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t b = 0; b < (S + block - 1) / block; ++b)
    samples_F(sys, &st, d, b * block, (b + 1) * block < S ? (b + 1) * block : S);
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t p = 0; p < d->view.count; ++p) patch_evaluate(sys, &st, d, p);
  d->gradients_current = 0;
  fascia_real energy = 0;
  for (int32_t p = 0; p < d->view.count; ++p) energy += d->patch_energy[p];
  return energy;
}

void fascia_dilatation_gradients(const fascia_system *sys, fascia_dilatation *d) {
  if (d->gradients_current) return;
  const fascia_pt_state st = {sys->x, sys->A};
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t p = 0; p < d->view.count; ++p) patch_gradient(sys, &st, d, p);
  d->gradients_current = 1;
}

void fascia_dilatation_apply_add(const fascia_system *sys, fascia_dilatation *d, const fascia_real *v,
                                 fascia_real *out) {
  fascia_dilatation_gradients(sys, d);
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t p = 0; p < d->view.count; ++p) fascia_pt_patch_rate(&d->view, p, v);
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t i = 0; i < sys->frame_count; ++i) fascia_pt_patch_frame_add(&d->view, i, out + 6 * (int64_t)i);
}

void fascia_dilatation_diagonal_add(const fascia_system *sys, fascia_dilatation *d, fascia_real *blocks) {
  fascia_dilatation_gradients(sys, d);
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t i = 0; i < sys->frame_count; ++i)
    fascia_pt_patch_frame_diagonal_add(&d->view, i, blocks + 36 * (int64_t)i);
}
