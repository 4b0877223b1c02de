// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Volumetric patches for models without cells (fascia_model_make_patches in
// model.h): patch centres are a Poisson-disk subset of the samples, chosen
// greedily in sample order, and every sample joins its nearest centre. A
// uniform grid of cells at least the largest radius wide finds the centres
// near a point: every centre within the radius lies in the 27 cells around it.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/model.h"
#include "util/status.h"

// Largest grid the search may use; past it the cells grow (fewer, larger).
#define MAX_GRID_CELLS (1 << 22)

typedef struct patch_grid {
  fascia_real origin[3], cell;
  int64_t dims[3];
  int32_t *head; ///< [cells] first centre of each cell, -1 for none
  int32_t *next; ///< [S] next centre in the same cell
} patch_grid;

static int64_t cell_of(const patch_grid *g, const fascia_real *p, int64_t c[3]) {
  for (int r = 0; r < 3; ++r) {
    int64_t k = (int64_t)floor((p[r] - g->origin[r]) / g->cell);
    c[r] = k < 0 ? 0 : k >= g->dims[r] ? g->dims[r] - 1 : k;
  }
  return (c[2] * g->dims[1] + c[1]) * g->dims[0] + c[0];
}

// The nearest centre to sample s of the same material and organ within
// `radius`, -1 if none (ties: the lower sample index).
static int32_t nearest_centre(const patch_grid *g, const fascia_model *m, int32_t s, fascia_real radius) {
  // the grid's cells are at least this radius wide: 27 cells hold every centre within it
  const fascia_real *p = m->sample_position + 3 * (int64_t)s;
  int64_t c[3];
  cell_of(g, p, c);
  int32_t best = -1;
  fascia_real best_d2 = radius * radius;
  for (int64_t z = c[2] - 1; z <= c[2] + 1; ++z)
    for (int64_t y = c[1] - 1; y <= c[1] + 1; ++y)
      for (int64_t x = c[0] - 1; x <= c[0] + 1; ++x) {
        if (x < 0 || y < 0 || z < 0 || x >= g->dims[0] || y >= g->dims[1] || z >= g->dims[2]) continue;
        for (int32_t t = g->head[(z * g->dims[1] + y) * g->dims[0] + x]; t >= 0; t = g->next[t]) {
          if (m->sample_material[t] != m->sample_material[s] || m->sample_organ[t] != m->sample_organ[s]) continue;
          const fascia_real *q = m->sample_position + 3 * (int64_t)t;
          const fascia_real d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
          if (d2 < best_d2 || (d2 == best_d2 && t < best)) {
            best_d2 = d2;
            best = t;
          }
        }
      }
  return best;
}

fascia_status fascia_model_make_patches(fascia_ctx *ctx, fascia_model *m, const fascia_real *radius_of) {
  FASCIA_CHECK(m && radius_of, ctx, FASCIA_ERR_ARGUMENT, "fascia_model_make_patches: NULL argument");
  fascia_real radius = 0; // the grid's cell: the largest radius
  for (int32_t k = 0; k < m->material_count; ++k) {
    const fascia_real r = radius_of[k];
    FASCIA_CHECK(!isnan(r) && isfinite(r), ctx, FASCIA_ERR_ARGUMENT,
                 "volumetric patches: material '%s' has radius %g m, expected a length (<= 0: no patches)",
                 m->materials[k].name, r);
    FASCIA_CHECK(r <= 0 || m->materials[k].part == FASCIA_PART_FULL, ctx, FASCIA_ERR_ARGUMENT,
                 "volumetric patches: material '%s' integrates only part of its energy; patches need whole materials",
                 m->materials[k].name);
    radius = r > radius ? r : radius;
  }
  const int32_t S = m->sample_count;
  if (radius <= 0) {
    for (int32_t s = 0; s < S; ++s) m->sample_patch[s] = -1;
    return FASCIA_OK;
  }
  patch_grid g;
  memset(&g, 0, sizeof g);
  fascia_real lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int32_t s = 0; s < S; ++s)
    for (int r = 0; r < 3; ++r) {
      const fascia_real x = m->sample_position[3 * (int64_t)s + r];
      lo[r] = x < lo[r] ? x : lo[r];
      hi[r] = x > hi[r] ? x : hi[r];
    }
  g.cell = radius;
  for (;;) {
    int64_t total = 1;
    for (int r = 0; r < 3; ++r) {
      g.dims[r] = (int64_t)floor((hi[r] - lo[r]) / g.cell) + 1;
      total *= g.dims[r];
    }
    if (total <= MAX_GRID_CELLS) break;
    g.cell *= 2; // a coarser grid still finds every centre within the radius
  }
  memcpy(g.origin, lo, sizeof lo);
  const int64_t cells = g.dims[0] * g.dims[1] * g.dims[2];
  g.head = malloc((size_t)cells * sizeof *g.head);
  g.next = malloc((size_t)S * sizeof *g.next);
  if (!g.head || !g.next) {
    free(g.head);
    free(g.next);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "volumetric patches: out of memory for %lld samples", (long long)S);
  }
  for (int64_t c = 0; c < cells; ++c) g.head[c] = -1;
  // centres: a sample with no centre of its kind within its radius becomes one
  for (int32_t s = 0; s < S; ++s) {
    m->sample_patch[s] = -1;
    const fascia_real r = radius_of[m->sample_material[s]];
    if (r <= 0 || nearest_centre(&g, m, s, r) >= 0) continue;
    int64_t c[3];
    const int64_t k = cell_of(&g, m->sample_position + 3 * (int64_t)s, c);
    g.next[s] = g.head[k];
    g.head[k] = s;
    m->sample_patch[s] = s;
  }
  // every sample has a centre of its kind within the radius: it joins the nearest
  for (int32_t s = 0; s < S; ++s)
    if (m->sample_patch[s] != s && radius_of[m->sample_material[s]] > 0)
      m->sample_patch[s] = nearest_centre(&g, m, s, radius_of[m->sample_material[s]]);
  free(g.head);
  free(g.next);
  return FASCIA_OK;
}

int32_t fascia_model_patch_count(const fascia_model *m, int32_t *patched) {
  int32_t count = 0, in = 0;
  unsigned char *seen = calloc((size_t)m->sample_count + 1, 1);
  for (int32_t s = 0; s < m->sample_count; ++s) {
    const int32_t p = m->sample_patch[s];
    if (p < 0 || p >= m->sample_count) continue;
    ++in;
    if (seen && !seen[p]) {
      seen[p] = 1;
      ++count;
    }
  }
  free(seen);
  if (patched) *patched = in;
  return seen ? count : -1;
}
