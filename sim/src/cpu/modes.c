// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Enhanced strain modes over volumetric patches (see modes.h). Every sum runs
// in a fixed order (patch by patch, entries ascending), so the results are
// bit-identical for any thread count.
#include <stdlib.h>
#include <string.h>

#include "cpu/modes.h"
#include "cpu/wide.h"
#include "cpu/dilatation.h"

// A mode column acts where its patch spans that direction: sum v xi_c^2
// at least this share of sum v |xi|^2 (a flat patch has no modes across it).
#define SPAN_SHARE 1e-10

_Static_assert((int)FASCIA_PT_MODES_NINE == (int)FASCIA_MODES_NINE && (int)FASCIA_PT_MODES_NORMAL == (int)FASCIA_MODES_NORMAL,
               "sim/point/modes.h names the model's sets of modes");

void fascia_modes_destroy(fascia_modes **modes) {
  if (!modes || !*modes) return;
  fascia_modes *md = *modes;
#define FREE_ARRAY(name, ...) free(md->name);
  FASCIA_MODES_ARRAYS(FREE_ARRAY)
#undef FREE_ARRAY
  free(md->sample_share);
  free(md->pair_share);
  free(md);
  *modes = NULL;
}

fascia_status fascia_modes_create(fascia_system *sys, fascia_modes **out) {
  *out = NULL;
  const fascia_model *m = sys->model;
  int32_t wanted = 0;
  for (int32_t s = 0; s < m->sample_count && !wanted; ++s) wanted = m->sample_modes[s];
  if (!wanted) return FASCIA_OK;
  const struct fascia_dilatation *d = sys->dilatation;
  FASCIA_CHECK(d, sys->ctx, FASCIA_ERR_FORMAT,
               "the model asks for enhanced strain modes but has no volumetric patches (/samples/patch); they "
               "live on the patches");
  const fascia_patch_table *t = &d->table;
  const int32_t P = t->patch_count, S = m->sample_count;
  fascia_modes *md = calloc(1, sizeof *md);
  FASCIA_CHECK(md, sys->ctx, FASCIA_ERR_MEMORY, "modes: out of memory");
  const int64_t E = t->entry_count;
  int allocated = 1;
#define ALLOC_ARRAY(name, type, count, width) FASCIA_ALLOC_ROW(md, allocated, name, type, count, width);
  FASCIA_MODES_ARRAYS(ALLOC_ARRAY)
#undef ALLOC_ARRAY
  if (!allocated) {
    fascia_modes_destroy(&md);
    return FASCIA_FAIL(sys->ctx, FASCIA_ERR_MEMORY, "modes: out of memory for %d patches", (int)P);
  }
  for (int32_t p = 0; p < P; ++p) {
    fascia_real centre[3] = {0, 0, 0}, spread[3] = {0, 0, 0};
    for (int32_t q = t->patch_offsets[p]; q < t->patch_offsets[p + 1]; ++q) {
      const int32_t s = t->patch_samples[q];
      for (int c = 0; c < 3; ++c) centre[c] += m->sample_volume[s] * m->sample_position[3 * (int64_t)s + c];
    }
    for (int c = 0; c < 3; ++c) centre[c] /= d->patch_volume[p];
    for (int32_t q = t->patch_offsets[p]; q < t->patch_offsets[p + 1]; ++q) {
      const int32_t s = t->patch_samples[q];
      for (int c = 0; c < 3; ++c) {
        const fascia_real xi = m->sample_position[3 * (int64_t)s + c] - centre[c];
        md->sample_xi[3 * (int64_t)s + c] = xi;
        spread[c] += m->sample_volume[s] * xi * xi;
        md->xi_max[3 * p + c] = fmax(md->xi_max[3 * p + c], fabs(xi));
      }
    }
    const fascia_real total = spread[0] + spread[1] + spread[2];
    const int32_t set = m->sample_modes[t->patch_samples[t->patch_offsets[p]]]; // the same for all its samples
    for (int j = 0; j < 9; ++j)
      if (total > 0 && spread[j % 3] > SPAN_SHARE * total && fascia_pt_modes_set_has(set, j)) md->active[p] |= 1 << j;
  }
#define VIEW_ARRAY(name, ...) md->view.name = md->name;
  FASCIA_MODES_ARRAYS(VIEW_ARRAY)
#undef VIEW_ARRAY
  sys->pm.sample_enhanced = md->sample_enhanced;
  *out = md;
  return FASCIA_OK;
}

// One patch's local solve and its tangent's factors, compiled wide (wide.h).
WIDE_CLONES static void patch_evaluate(const fascia_pt_model *m, const fascia_pt_state *st, const fascia_pt_patches *t,
                                       const fascia_pt_modes *md, int32_t p) {
  fascia_pt_modes_evaluate(m, st, t, md, p);
}

WIDE_CLONES static void patch_tangent(const fascia_system *sys, const fascia_pt_state *st, const fascia_pt_patches *t,
                                      const fascia_modes *md, int32_t p) {
  fascia_pt_modes_tangent(&sys->pm, st, t, &md->view, p, sys->cache, sys->pair_buffer,
                          md->shares_current ? md->sample_share : NULL, md->shares_current ? md->pair_share : NULL);
}

int32_t fascia_modes_evaluate(fascia_system *sys, fascia_modes *md) {
  const fascia_pt_state st = {sys->x, sys->A};
  const fascia_pt_model own = fascia_pt_modes_local_model(&sys->pm);
  const fascia_pt_patches *t = &sys->dilatation->view;
#pragma omp parallel for num_threads(sys->threads) schedule(dynamic, 4)
  for (int32_t p = 0; p < t->count; ++p) patch_evaluate(&own, &st, t, &md->view, p);
  md->tangent_current = md->shares_current = 0;
  for (int32_t p = 0; p < t->count; ++p)
    if (md->failed[p]) return p;
  return -1;
}

void fascia_modes_tangent(const fascia_system *sys, fascia_modes *md) {
  if (md->tangent_current) return;
  fascia_dilatation_gradients(sys, sys->dilatation);
  const fascia_pt_state st = {sys->x, sys->A};
  const fascia_pt_patches *t = &sys->dilatation->view;
#pragma omp parallel for num_threads(sys->threads) schedule(dynamic, 4)
  for (int32_t p = 0; p < t->count; ++p) patch_tangent(sys, &st, t, md, p);
  md->tangent_current = 1;
}

int fascia_modes_shares_ready(const fascia_system *sys, fascia_modes *md) {
  const fascia_model *m = sys->model;
  if (!md->sample_share) md->sample_share = fascia_calloc(81 * (int64_t)m->sample_count, sizeof(fascia_real));
  if (!md->pair_share) md->pair_share = fascia_calloc(54 * (int64_t)m->pair_count, sizeof(fascia_real));
  return md->sample_share && md->pair_share;
}

int32_t fascia_modes_sample_patch(const fascia_system *sys, const fascia_modes *md, int32_t s) {
  const fascia_model *m = sys->model;
  if (m->sample_offsets[s] == m->sample_offsets[s + 1] || sys->pm.sample_coupling[s] > 0) return -1;
  const fascia_pt_patches *t = &sys->dilatation->view;
  const int32_t e = t->pair_entry[m->sample_offsets[s]];
  return e >= 0 && md->active[t->entry_patch[e]] ? t->entry_patch[e] : -1;
}

void fascia_modes_apply_add(const fascia_system *sys, fascia_modes *md, const fascia_real *v, fascia_real *out) {
  fascia_modes_tangent(sys, md);
  const fascia_pt_patches *t = &sys->dilatation->view;
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t p = 0; p < t->count; ++p) fascia_pt_modes_reduce(t, &md->view, p, v);
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t i = 0; i < sys->frame_count; ++i) fascia_pt_modes_frame_add(t, &md->view, i, out + 6 * (int64_t)i);
}

void fascia_modes_diagonal_add(const fascia_system *sys, fascia_modes *md, fascia_real *blocks) {
  fascia_modes_tangent(sys, md);
  const fascia_pt_patches *t = &sys->dilatation->view;
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t i = 0; i < sys->frame_count; ++i) fascia_pt_modes_frame_diagonal_add(t, &md->view, i, blocks + 36 * (int64_t)i);
}
