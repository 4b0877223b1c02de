// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Stage 5, shape functions: the weights and rest-space gradients that tie
// each sample to its frames (docs/mechanics.md; paper sec. 2.1).
//
// MLS (meshless). The neighbours of a sample are the frames nearest to it
// *through the region*: a Dijkstra search over the tissue's voxels
// (26-neighbourhood, steps h, h sqrt 2, h sqrt 3) from the sample's voxel,
// a frame counting at the distance of its voxel plus the straight step from
// the voxel centre. A frame on the far side of an organ or of a void is
// never reached, so no weight reaches across. The weights themselves are the
// simulator's fascia_shape_mls (linear basis, Wendland kernel; a partition of
// unity that reproduces linear fields), with a support radius
// FASCIA_SHAPE_SUPPORT_MARGIN times the farthest chosen frame. When the
// chosen frames are too flat for a linear basis, more are taken.
//
// The same neighbours, found locally. The search expands every voxel closer
// than the farthest neighbour, (distance / h)^3 voxels per sample: most of
// the region at fine voxels. But its distance between two voxels is at
// least the length of the shortest path of the whole 26-neighbour lattice,
// h ((a - b) + (b - c) sqrt 2 + c sqrt 3) for the sorted index differences
// a >= b >= c, and equal to it when one such path runs inside the region.
// So each sample first gathers the frames attached within a cube of voxels
// around it (from a table of frames by cell) and ranks them by that form; it
// keeps the ranking when a shortest lattice path to each chosen frame stays
// in the region (O(distance / h) to check), every other frame's bound lies
// beyond the last chosen one, and no two frames tie within round-off where
// the choice is made. Otherwise the search decides. Either way the frames
// are those the search picks, and cost goes with the samples and their
// neighbourhoods, not with the voxels between.
//
// Regions. Tissues and the insides of deformable organs are treated alike,
// each sample by the region of its voxel. A frame is reached from its own
// voxel and, when it is shared with a deformable organ, also from the organ's
// inside voxel it is attached to (frame_organ_voxel): both the tissue's and
// the organ's samples can take it.
//
// TET (mesh-based). The sampling stage tetrahedralised the region's frames
// and put the samples at the quadrature points of the tetrahedra that lie in
// the region (sample.c); each sample records its tet's frames
// (sample_tet_frame). Its weights are the barycentric coordinates in that
// tet (fascia_shape_tet), all in [0, 1]: nothing is extrapolated.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "fascia/shape.h"
#include "prep_util.h"

#define MAX_PAIRS 64

void fascia_prep_weights_destroy(fascia_prep_weights **weights) {
  if (!weights || !*weights) return;
  fascia_prep_weights *w = *weights;
  free(w->sample_offsets);
  free(w->pair_frame);
  free(w->pair_weight);
  free(w->pair_gradient);
  free(w);
  *weights = NULL;
}

typedef struct candidate {
  double distance;
  int32_t frame;
} candidate;

// A frame gathered by the local search: the lattice form of its distance
// and the voxel it is attached at.
typedef struct gathered {
  double distance;
  int32_t frame;
  int32_t exact; // 1: distance is the search's (within round-off), 0: a lower bound
  int64_t voxel;
} gathered;

// Per-thread state of the geodesic search.
typedef struct search {
  double *dist;      // [voxels] INFINITY when untouched (double: the same type as the heap keys)
  int64_t *touched;  // voxels whose dist was set, to reset them
  int64_t touched_count, touched_capacity;
  prep_heap heap;
  fascia_ctx *ctx;   // private context: fascia_shape_mls writes its message here
  struct gathered *pool; // frames gathered by the local search
  int32_t pool_capacity;
} search;

// Frames by voxel: attachment a puts frame[a] at a voxel; head[v] is the
// first attachment at voxel v, next[a] the following one (-1 ends).
typedef struct frame_index {
  int32_t *head;  // [voxels]
  int32_t *next;  // [attachments]
  int32_t *frame; // [attachments]
} frame_index;

// The distance array of a thread's searches, made on its first search
// (samples settled locally need none). 0 when out of memory.
static int search_ready(search *se, const prep_grid *g) {
  if (se->dist) return 1;
  const int64_t n = prep_grid_count(g);
  se->dist = malloc((size_t)n * sizeof(double));
  if (!se->dist) return 0;
  for (int64_t k = 0; k < n; ++k) se->dist[k] = INFINITY;
  return 1;
}

static int touch(search *se, int64_t v, double d) {
  if (se->dist[v] == INFINITY) {
    if (se->touched_count == se->touched_capacity) {
      const int64_t cap = se->touched_capacity ? 2 * se->touched_capacity : 4096;
      int64_t *t = realloc(se->touched, (size_t)cap * sizeof(int64_t));
      if (!t) return 0;
      se->touched = t;
      se->touched_capacity = cap;
    }
    se->touched[se->touched_count++] = v;
  }
  se->dist[v] = d;
  return 1;
}

// The `want` frames nearest to sample s through its region, ascending
// distance (ties by frame index). Returns the count found (< want when the
// piece holds fewer frames), -1 when out of memory.
static int32_t nearest_frames(search *se, const prep_grid *g, const fascia_prep_volume *vol,
                              const fascia_prep_points *pts, const frame_index *fi, int32_t s, int32_t want,
                              candidate *out) {
  const uint8_t label = vol->region[pts->sample_voxel[s]];
  const double *ps = pts->sample_position + 3 * (int64_t)s;
  int32_t found = 0;
  se->heap.count = 0;
  double c[3];
  const int64_t start = pts->sample_voxel[s];
  prep_grid_center(g, start, c);
  const double d0 = sqrt((ps[0] - c[0]) * (ps[0] - c[0]) + (ps[1] - c[1]) * (ps[1] - c[1]) +
                         (ps[2] - c[2]) * (ps[2] - c[2]));
  if (!search_ready(se, g)) return -1;
  int ok = touch(se, start, d0) && prep_heap_push(&se->heap, d0, start);
  double key;
  int64_t v;
  while (ok && prep_heap_pop(&se->heap, &key, &v)) {
    if (key > se->dist[v]) continue;
    if (found == want && key > out[want - 1].distance) break;
    prep_grid_center(g, v, c);
    for (int32_t a = fi->head[v]; a >= 0; a = fi->next[a]) {
      const int32_t i = fi->frame[a];
      const double *x = pts->frame_position + 3 * (int64_t)i;
      const double d = key + sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) +
                                  (x[2] - c[2]) * (x[2] - c[2]));
      // insertion into the sorted list of the best `want`
      if (found == want && (d > out[want - 1].distance || (d == out[want - 1].distance && i > out[want - 1].frame)))
        continue;
      int32_t k = found < want ? found++ : want - 1;
      while (k > 0 && (out[k - 1].distance > d || (out[k - 1].distance == d && out[k - 1].frame > i))) {
        out[k] = out[k - 1];
        --k;
      }
      out[k].distance = d;
      out[k].frame = i;
    }
    int32_t ijk[3];
    prep_grid_ijk(g, v, ijk);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int32_t x = ijk[0] + dx, y = ijk[1] + dy, z = ijk[2] + dz;
          if (x < 0 || y < 0 || z < 0 || x >= g->dims[0] || y >= g->dims[1] || z >= g->dims[2]) continue;
          const int64_t nb = prep_grid_index(g, x, y, z);
          if (vol->region[nb] != label) continue;
          const double d = key + g->h * sqrt((double)(dx * dx + dy * dy + dz * dz));
          if (d < se->dist[nb]) ok = ok && touch(se, nb, d) && prep_heap_push(&se->heap, d, nb);
        }
  }
  for (int64_t k = 0; k < se->touched_count; ++k) se->dist[se->touched[k]] = INFINITY;
  se->touched_count = 0;
  return ok ? found : -1;
}

// ------------------------------------------------------------ local search

// Frame attachments by cell of cell x cell x cell voxels (CSR).
typedef struct cell_index {
  int32_t cell, dims[3];
  int64_t *start;  // [cells + 1]
  int32_t *frame;  // [attachments], by cell
  int64_t *voxel;  // [attachments]
} cell_index;

// The shared tables of the local search, read-only once built.
typedef struct local_tables {
  cell_index cells;
} local_tables;

// 1 when one shortest 26-neighbour lattice path from voxel a to voxel b,
// the one that follows the straight segment (its double steps spread evenly
// among the steps, its triple steps evenly among the double ones), runs
// through the region's voxels only: then the search's distance between them
// is the lattice distance.
static int path_clear(const prep_grid *g, const uint8_t *region, uint8_t label, const int32_t *a, const int32_t *b) {
  int32_t d[3], sign[3], ax[3] = {0, 1, 2};
  for (int r = 0; r < 3; ++r) d[r] = b[r] > a[r] ? b[r] - a[r] : a[r] - b[r], sign[r] = b[r] > a[r] ? 1 : -1;
  for (int i = 0; i < 2; ++i) // axes by descending difference
    for (int j = 0; j < 2 - i; ++j)
      if (d[ax[j]] < d[ax[j + 1]]) {
        const int t = ax[j];
        ax[j] = ax[j + 1];
        ax[j + 1] = t;
      }
  const int64_t A = d[ax[0]], B = d[ax[1]], C = d[ax[2]];
  int32_t p[3] = {a[0], a[1], a[2]};
  for (int64_t t = 1, k = 0; t <= A; ++t) {
    p[ax[0]] += sign[ax[0]];
    if ((2 * t * B + A) / (2 * A) != (2 * (t - 1) * B + A) / (2 * A)) {
      ++k;
      p[ax[1]] += sign[ax[1]];
      if ((2 * k * C + B) / (2 * B) != (2 * (k - 1) * C + B) / (2 * B)) p[ax[2]] += sign[ax[2]];
    }
    if (region[prep_grid_index(g, p[0], p[1], p[2])] != label) return 0;
  }
  return 1;
}

// Length of the shortest 26-neighbour lattice path between voxels a and b.
static double lattice_distance(double h, const int32_t *a, const int32_t *b) {
  int32_t d[3];
  for (int r = 0; r < 3; ++r) d[r] = a[r] > b[r] ? a[r] - b[r] : b[r] - a[r];
  for (int i = 0; i < 2; ++i) // sort descending
    for (int j = 0; j < 2 - i; ++j)
      if (d[j] < d[j + 1]) {
        const int32_t t = d[j];
        d[j] = d[j + 1];
        d[j + 1] = t;
      }
  return h * ((double)(d[0] - d[1]) + (double)(d[1] - d[2]) * sqrt(2.0) + (double)d[2] * sqrt(3.0));
}

// Distance through the region from voxel start (at d0) to voxel target,
// by a search aimed at it (A*, the lattice distance to the target as its
// heuristic, which never overestimates and grows by at most a step per
// step, so the first time the target leaves the heap its distance is
// final). A heuristic weighted by 1 + 1e-10 breaks the lattice's many ties
// towards the target at a cost of at most 1e-10 of the distance. Returns -1
// when the search would expand more voxels than a plain search around the
// sample to that distance, or out of memory.
static double aimed_distance(search *se, const prep_grid *g, const uint8_t *region, uint8_t label, int64_t start,
                             double d0, int64_t target) {
  if (!search_ready(se, g)) return -1;
  const double w = 1 + 1e-10, h = g->h;
  int32_t t_ijk[3], v_ijk[3];
  prep_grid_ijk(g, target, t_ijk);
  prep_grid_ijk(g, start, v_ijk);
  const double reach = lattice_distance(h, v_ijk, t_ijk) / h + 1;
  const int64_t budget = (int64_t)(reach * reach * reach) + 64;
  se->heap.count = 0;
  double result = -1, key;
  int64_t v, expanded = 0;
  int ok = touch(se, start, d0) && prep_heap_push(&se->heap, d0 + w * lattice_distance(h, v_ijk, t_ijk), start);
  while (ok && prep_heap_pop(&se->heap, &key, &v)) {
    prep_grid_ijk(g, v, v_ijk);
    if (key > se->dist[v] + w * lattice_distance(h, v_ijk, t_ijk)) continue; // a stale entry
    if (v == target) {
      result = se->dist[v];
      break;
    }
    if (++expanded > budget) break;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int32_t nb_ijk[3] = {v_ijk[0] + dx, v_ijk[1] + dy, v_ijk[2] + dz};
          if (nb_ijk[0] < 0 || nb_ijk[1] < 0 || nb_ijk[2] < 0 || nb_ijk[0] >= g->dims[0] ||
              nb_ijk[1] >= g->dims[1] || nb_ijk[2] >= g->dims[2])
            continue;
          const int64_t nb = prep_grid_index(g, nb_ijk[0], nb_ijk[1], nb_ijk[2]);
          if (region[nb] != label) continue;
          const double d = se->dist[v] + h * sqrt((double)(dx * dx + dy * dy + dz * dz));
          if (d < se->dist[nb])
            ok = ok && touch(se, nb, d) && prep_heap_push(&se->heap, d + w * lattice_distance(h, nb_ijk, t_ijk), nb);
        }
  }
  for (int64_t k = 0; k < se->touched_count; ++k) se->dist[se->touched[k]] = INFINITY;
  se->touched_count = 0;
  return ok ? result : -1;
}

static fascia_status cell_index_build(fascia_ctx *ctx, const prep_grid *g, const frame_index *fi, int32_t frames,
                                      int32_t attachments, const int64_t *attach_voxel, cell_index *ci) {
  // about one frame per cell over the grid
  const double per_frame = (double)prep_grid_count(g) / (frames > 0 ? frames : 1);
  ci->cell = (int32_t)fmax(1, floor(cbrt(per_frame)));
  int64_t cells = 1;
  for (int r = 0; r < 3; ++r) ci->dims[r] = (g->dims[r] + ci->cell - 1) / ci->cell, cells *= ci->dims[r];
  ci->start = prep_calloc(cells + 1, sizeof(int64_t));
  ci->frame = prep_calloc(attachments, sizeof(int32_t));
  ci->voxel = prep_calloc(attachments, sizeof(int64_t));
  PREP_CHECK(ci->start && ci->frame && ci->voxel, ctx, FASCIA_ERR_MEMORY, "shape functions: out of memory");
  int64_t *cell_of = prep_calloc(attachments, sizeof(int64_t));
  PREP_CHECK(cell_of, ctx, FASCIA_ERR_MEMORY, "shape functions: out of memory");
  for (int32_t a = 0; a < attachments; ++a) {
    int32_t c[3];
    prep_grid_ijk(g, attach_voxel[a], c);
    cell_of[a] = (c[0] / ci->cell) + (int64_t)ci->dims[0] * ((c[1] / ci->cell) + (int64_t)ci->dims[1] * (c[2] / ci->cell));
    ci->start[cell_of[a] + 1]++;
  }
  for (int64_t k = 0; k < cells; ++k) ci->start[k + 1] += ci->start[k];
  for (int32_t a = 0; a < attachments; ++a) { // stable: ascending attachment order within a cell
    const int64_t at = ci->start[cell_of[a]]++;
    ci->frame[at] = fi->frame[a];
    ci->voxel[at] = attach_voxel[a];
  }
  for (int64_t k = cells; k > 0; --k) ci->start[k] = ci->start[k - 1];
  ci->start[0] = 0;
  free(cell_of);
  return FASCIA_OK;
}

static int by_distance_then_frame(const void *a, const void *b) {
  const gathered *x = a, *y = b;
  if (x->distance != y->distance) return x->distance < y->distance ? -1 : 1;
  return (x->frame > y->frame) - (x->frame < y->frame);
}

// The `want` frames nearest to sample s through its region without the
// search, when the closed form settles them (see the note): returns `want`
// with out filled, or 0 when the search must decide. The choice is made at
// every count from `first` to `want` (mls_sample tries each), so ties
// matter only there. se->pool holds the candidates.
static int32_t local_frames(search *se, const prep_grid *g, const fascia_prep_volume *vol,
                            const fascia_prep_points *pts, const local_tables *lt, int32_t s, int32_t want,
                            int32_t first, candidate *out) {
  const int64_t start = pts->sample_voxel[s];
  const uint8_t label = vol->region[start];
  const cell_index *ci = &lt->cells;
  const double h = g->h, *ps = pts->sample_position + 3 * (int64_t)s;
  int32_t s_ijk[3];
  prep_grid_ijk(g, start, s_ijk);
  double c[3];
  prep_grid_center(g, start, c);
  const double d0 = sqrt((ps[0] - c[0]) * (ps[0] - c[0]) + (ps[1] - c[1]) * (ps[1] - c[1]) +
                         (ps[2] - c[2]) * (ps[2] - c[2]));
  const int32_t largest = g->dims[0] > g->dims[1] ? (g->dims[0] > g->dims[2] ? g->dims[0] : g->dims[2])
                                                  : (g->dims[1] > g->dims[2] ? g->dims[1] : g->dims[2]);
  for (int32_t reach = 2 * ci->cell;; reach *= 2) {
    // frames attached within `reach` voxels (Chebyshev) of the sample's voxel;
    // any other lies at least reach h away through the region
    const int whole = reach >= largest;
    int32_t lo[3], hi[3];
    for (int r = 0; r < 3; ++r) {
      lo[r] = (s_ijk[r] - reach < 0 ? 0 : s_ijk[r] - reach) / ci->cell;
      hi[r] = (s_ijk[r] + reach >= g->dims[r] ? g->dims[r] - 1 : s_ijk[r] + reach) / ci->cell;
    }
    int32_t count = 0;
    for (int32_t z = lo[2]; z <= hi[2]; ++z)
      for (int32_t y = lo[1]; y <= hi[1]; ++y)
        for (int32_t x = lo[0]; x <= hi[0]; ++x) {
          const int64_t cell = x + (int64_t)ci->dims[0] * (y + (int64_t)ci->dims[1] * z);
          for (int64_t a = ci->start[cell]; a < ci->start[cell + 1]; ++a) {
            const int64_t v = ci->voxel[a];
            if (vol->region[v] != label) continue;
            int32_t f_ijk[3];
            prep_grid_ijk(g, v, f_ijk);
            int outside = 0;
            for (int r = 0; r < 3; ++r)
              outside |= f_ijk[r] < s_ijk[r] - reach || f_ijk[r] > s_ijk[r] + reach;
            if (outside) continue;
            if (count == se->pool_capacity) {
              const int32_t cap = se->pool_capacity ? 2 * se->pool_capacity : 256;
              gathered *grown = realloc(se->pool, (size_t)cap * sizeof *grown);
              if (!grown) return 0;
              se->pool = grown;
              se->pool_capacity = cap;
            }
            const int32_t i = ci->frame[a];
            const double *xf = pts->frame_position + 3 * (int64_t)i;
            double cv[3];
            prep_grid_center(g, v, cv);
            const double e = sqrt((xf[0] - cv[0]) * (xf[0] - cv[0]) + (xf[1] - cv[1]) * (xf[1] - cv[1]) +
                                  (xf[2] - cv[2]) * (xf[2] - cv[2]));
            se->pool[count].distance = d0 + lattice_distance(h, s_ijk, f_ijk) + e;
            se->pool[count].frame = i;
            se->pool[count].voxel = v;
            se->pool[count].exact = 0;
            ++count;
          }
        }
    const double beyond = whole ? INFINITY : reach * h; // bound of the frames not gathered
    if (count >= want) {
      qsort(se->pool, (size_t)count, sizeof *se->pool, by_distance_then_frame);
      for (int32_t j = 0; j < want; ++j) // a frame gathered twice (two attachments): the search decides
        for (int32_t k = j + 1; k < count; ++k)
          if (se->pool[k].frame == se->pool[j].frame) return 0;
      // the chosen frames' forms must be their distances (the others' are
      // bounds): a frame whose lattice path leaves the region gets its
      // distance from a search aimed at it, and the ranking is redone
      int32_t j = 0;
      while (j < want) {
        gathered *f = se->pool + j;
        if (f->exact) {
          ++j;
          continue;
        }
        int32_t f_ijk[3];
        prep_grid_ijk(g, f->voxel, f_ijk);
        f->exact = 1;
        if (path_clear(g, vol->region, label, s_ijk, f_ijk)) {
          ++j;
          continue;
        }
        const double e = f->distance - d0 - lattice_distance(h, s_ijk, f_ijk);
        const double d = aimed_distance(se, g, vol->region, label, start, d0, f->voxel);
        if (!(d >= 0)) return 0; // too far around, or out of memory: the search decides
        f->distance = d + e;
        qsort(se->pool + j, (size_t)(count - j), sizeof *se->pool, by_distance_then_frame);
      }
      const double last = se->pool[want - 1].distance, tol = 1e-9 * (h + last);
      if (last + tol < beyond || whole) {
        int settled = count == want || se->pool[want].distance > last + tol;
        for (int32_t m = first > 1 ? first : 1; m < want && settled; ++m)
          settled = se->pool[m].distance - se->pool[m - 1].distance > tol;
        if (!settled) return 0;
        for (int32_t k = 0; k < want; ++k) out[k].distance = se->pool[k].distance, out[k].frame = se->pool[k].frame;
        return want;
      }
    }
    if (whole) return 0; // fewer frames than wanted in reach: the search says how many
  }
}

static int by_frame(const void *a, const void *b) {
  const int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
  return (x > y) - (x < y);
}

// MLS weights of sample s into frame[0..count), w, grad (ascending frames).
// Returns 0 ok, 1 no usable frame set (message on se->ctx), -1 out of memory.
static int mls_sample(search *se, const prep_grid *g, const fascia_prep_volume *vol, const fascia_prep_points *pts,
                      const frame_index *fi, const local_tables *lt, int32_t s, int32_t k, int32_t *frame, double *w,
                      double *grad, int32_t *count) {
  candidate cand[MAX_PAIRS];
  const double *p = pts->sample_position + 3 * (int64_t)s;
  const int32_t tries[3] = {k + 4 < MAX_PAIRS ? k + 4 : MAX_PAIRS, 2 * k + 8 < MAX_PAIRS ? 2 * k + 8 : MAX_PAIRS,
                            MAX_PAIRS};
  for (int attempt = 0; attempt < 3; ++attempt) {
    int32_t found = local_frames(se, g, vol, pts, lt, s, tries[attempt], k, cand);
    if (found == 0) found = nearest_frames(se, g, vol, pts, fi, s, tries[attempt], cand);
    if (found < 0) return -1;
    for (int32_t m = k < found ? k : found; m <= found; ++m) {
      if (m < 4) continue;
      int32_t idx[MAX_PAIRS];
      double x[3 * MAX_PAIRS], far = 0;
      for (int32_t j = 0; j < m; ++j) idx[j] = cand[j].frame;
      qsort(idx, (size_t)m, sizeof idx[0], by_frame);
      for (int32_t j = 0; j < m; ++j) {
        const double *y = pts->frame_position + 3 * (int64_t)idx[j];
        memcpy(x + 3 * j, y, 3 * sizeof(double));
        far = fmax(far, sqrt((y[0] - p[0]) * (y[0] - p[0]) + (y[1] - p[1]) * (y[1] - p[1]) +
                             (y[2] - p[2]) * (y[2] - p[2])));
      }
      if (!(far > 0)) continue;
      if (fascia_shape_mls(se->ctx, m, x, p, FASCIA_SHAPE_SUPPORT_MARGIN * far, w, grad) == FASCIA_OK) {
        memcpy(frame, idx, (size_t)m * sizeof(int32_t));
        *count = m;
        return 0;
      }
    }
    if (found < tries[attempt]) break; // the piece has no more frames
  }
  fascia_ctx_fail(se->ctx, FASCIA_ERR_NUMERIC, __FILE__, __LINE__,
                  "sample %d at (%.4g %.4g %.4g) m: no set of up to %d frames reachable through the region supports "
                  "a linear basis (too few frames in its piece of region, or all coplanar); lower frame_spacing or "
                  "raise min_component",
                  (int)s, p[0], p[1], p[2], MAX_PAIRS);
  return 1;
}

// ------------------------------------------------------------ TET

// Barycentric weights of every sample of a TET region in its own tet (frames
// ascending, so the pairs are too). A sample of a TET region without a tet,
// or a flat tet, is a bug of the sampling stage: FASCIA_ERR_INTERNAL naming
// the lowest such sample.
static fascia_status tet_weights(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_volume *vol,
                                 const fascia_prep_points *pts, int32_t *pair_frame, double *pair_w, double *pair_g,
                                 int32_t *pair_count) {
  for (int32_t s = 0; s < pts->sample_count; ++s) {
    if (pts->sample_voxel[s] < 0) continue; // a strand's or a sheet's
    const uint8_t label = vol->region[pts->sample_voxel[s]];
    int32_t kind;
    prep_label_sampling(scene, vol, label, NULL, NULL, &kind, NULL);
    if (kind != FASCIA_PREP_SHAPE_TET) continue;
    char name[FASCIA_NAME_SIZE + 32];
    const int32_t *v = pts->sample_tet_frame + 4 * (int64_t)s;
    PREP_CHECK(v[0] >= 0, ctx, FASCIA_ERR_INTERNAL, "%s sample %d: no tetrahedron recorded by the sampling stage",
               prep_label_name(scene, vol, label, name, sizeof name), (int)s);
    double x[12];
    for (int r = 0; r < 4; ++r) memcpy(x + 3 * r, pts->frame_position + 3 * (int64_t)v[r], 3 * sizeof(double));
    const int64_t base = (int64_t)MAX_PAIRS * s;
    if (fascia_shape_tet(ctx, x, pts->sample_position + 3 * (int64_t)s, pair_w + base, pair_g + 3 * base) != FASCIA_OK) {
      char why[512];
      snprintf(why, sizeof why, "%s", fascia_ctx_message(ctx));
      return PREP_FAIL(ctx, FASCIA_ERR_INTERNAL, "%s sample %d: %s", prep_label_name(scene, vol, label, name, sizeof name),
                       (int)s, why);
    }
    memcpy(pair_frame + base, v, 4 * sizeof(int32_t));
    pair_count[s] = 4;
  }
  return FASCIA_OK;
}

// ------------------------------------------------------------ strands and sheets

// Kernel support over a sample's own interval or triangle, times the
// distance to its farthest frame (as the beam's strand and sheet): every
// frame well inside it.
#define CELL_SUPPORT_FACTOR 2.0

// A strand's or a sheet's samples (no voxel): fascia_shape_mls_adaptive
// over the frames of the sample's interval or triangle
// (points->sample_cell_frame), linear in the span of those frames; the
// frames must span a line or a plane.
static fascia_status cell_weights(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_points *pts,
                                  int32_t *pair_frame, double *pair_w, double *pair_g, int32_t *pair_count) {
  for (int32_t s = 0; s < pts->sample_count; ++s) {
    if (pts->sample_voxel[s] >= 0) continue;
    const int32_t *c = pts->sample_cell_frame + 3 * (int64_t)s;
    const int32_t t = pts->sample_tissue[s], o = pts->sample_inside_organ[s]; // a shell organ's wall: o >= 0
    PREP_CHECK(c[0] >= 0 && c[1] >= 0 && (t >= 0 || o >= 0), ctx, FASCIA_ERR_INTERNAL,
               "sample %d: neither a voxel nor a strand's, sheet's or shell's cell recorded by the sampling stage",
               (int)s);
    int32_t frame[3];
    const int32_t k = c[2] >= 0 ? 3 : 2;
    memcpy(frame, c, (size_t)k * sizeof(int32_t));
    for (int32_t i = 1; i < k; ++i) // ascending, as the model's pairs
      for (int32_t j = i; j > 0 && frame[j - 1] > frame[j]; --j) {
        const int32_t tmp = frame[j];
        frame[j] = frame[j - 1];
        frame[j - 1] = tmp;
      }
    const double *p = pts->sample_position + 3 * (int64_t)s;
    double x[9], reach = 0;
    for (int32_t j = 0; j < k; ++j) {
      memcpy(x + 3 * j, pts->frame_position + 3 * (int64_t)frame[j], 3 * sizeof(double));
      double d2 = 0;
      for (int r = 0; r < 3; ++r) d2 += (x[3 * j + r] - p[r]) * (x[3 * j + r] - p[r]);
      reach = fmax(reach, sqrt(d2));
    }
    const int64_t base = (int64_t)MAX_PAIRS * s;
    int32_t dim = 0;
    const fascia_status st =
        fascia_shape_mls_adaptive(ctx, k, x, p, CELL_SUPPORT_FACTOR * reach, 0, pair_w + base, pair_g + 3 * base, &dim);
    PREP_CHECK(st == FASCIA_OK && dim == k - 1, ctx, FASCIA_ERR_NUMERIC,
               "%s '%s' (%s) sample %d at (%.4g %.4g %.4g) m: the frames of its %s span %d dimension(s), expected "
               "%d (frames at one point or in a line); repair the geometry there",
               t >= 0 ? "tissue" : "organ", t >= 0 ? scene->tissues[t].name : scene->organs[o].name,
               t >= 0 ? fascia_prep_form_name(scene->tissues[t].form) : "shell", (int)s, p[0], p[1], p[2],
               k == 2 ? "interval" : "triangle", (int)dim, (int)(k - 1));
    memcpy(pair_frame + base, frame, (size_t)k * sizeof(int32_t));
    pair_count[s] = k;
  }
  return FASCIA_OK;
}

// ------------------------------------------------------------ shell walls

// A shell's wall (shell.c) is a sheet of triangles, one point each. With
// the triangle's linear gradients, a bent wall shears: at the point the
// gradient of the interpolated deflection and the interpolated rotation
// differ by about the curvature times the triangle's size (the linear
// triangle's shear locking; a strand's midpoint is free of it, a
// triangle's centroid is not), and the wall is several times too stiff
// where its frames are not much closer than its thickness. The cure: the
// wall point's gradients are those of a quadratic fit (moving least
// squares in the wall's plane over its nearest frames), which differentiate
// every quadratic field exactly there; the shear of a uniformly bent wall
// is then zero. The weights stay the triangle's (the stencil's other
// frames weigh 0): positions and rotations are interpolated as before.
//
// A least-squares fit alone is blind to what no quadratic explains: frame
// patterns that alternate from one frame to the next fit to a flat
// quadratic, so they cost almost nothing (hourglass modes of the deflection
// and the rotations), and frame rotations about the wall's normal (drilling)
// that vary smoothly strain no point at all. The wall then sags too far,
// and farther under refinement (docs/measured.md, "Shell organs against
// CalculiX"). So the fit is made to pass through the triangle's own
// corners: what it leaves there is interpolated linearly and added (exact
// quadratics unchanged, an alternating pattern answered as the linear
// triangle answers it), and SHELL_LINEAR_SHARE of the linear triangle's own
// gradients is mixed in, which gives drilling a stiffness (and a Newton
// solve a tangent without a mechanism) at a small cost in bending.
//
// A sheet tissue's triangles take the same fit with none of the linear
// gradients: the drilling that a fit exact on quadratics leaves free (a
// linear twist about the normal strains no point, just as a uniform bend
// shears none) is held by the sheet's own stabiliser (reduced.h), whose
// gauges see the whole in-plane strain of linear minus fit and no shear
// across the sheet (docs/mechanics.md, "Against CalculiX").
#define SHELL_STENCIL 9
// Frames tied in distance with the stencil's last are taken too (a mesh
// symmetric about the point keeps a symmetric fit), up to this many.
#define SHELL_QUERY (SHELL_STENCIL + 7)
#define SHELL_LINEAR_SHARE 0.1
#define SHELL_BASIS 6

// Solves the SHELL_BASIS x SHELL_BASIS system a x = b (b: SHELL_BASIS x
// columns, row-major, overwritten) by Gaussian elimination with partial
// pivoting; 0 when a pivot falls under 1e-12 of the largest diagonal.
static int solve_small(double *a, double *b, int columns) {
  enum { n = SHELL_BASIS };
  double scale = 0;
  for (int i = 0; i < n; ++i) scale = fmax(scale, fabs(a[i * n + i]));
  for (int c = 0; c < n; ++c) {
    int piv = c;
    for (int r = c + 1; r < n; ++r)
      if (fabs(a[r * n + c]) > fabs(a[piv * n + c])) piv = r;
    if (!(fabs(a[piv * n + c]) > 1e-12 * scale)) return 0;
    for (int k = 0; k < n; ++k) {
      const double t = a[c * n + k];
      a[c * n + k] = a[piv * n + k], a[piv * n + k] = t;
    }
    for (int k = 0; k < columns; ++k) {
      const double t = b[c * columns + k];
      b[c * columns + k] = b[piv * columns + k], b[piv * columns + k] = t;
    }
    for (int r = c + 1; r < n; ++r) {
      const double f = a[r * n + c] / a[c * n + c];
      for (int k = c; k < n; ++k) a[r * n + k] -= f * a[c * n + k];
      for (int k = 0; k < columns; ++k) b[r * columns + k] -= f * b[c * columns + k];
    }
  }
  for (int c = n - 1; c >= 0; --c)
    for (int k = 0; k < columns; ++k) {
      double v = b[c * columns + k];
      for (int j = c + 1; j < n; ++j) v -= a[c * n + j] * b[j * columns + k];
      b[c * columns + k] = v / a[c * n + c];
    }
  return 1;
}

// One wall sample: its triangle's frames (pairs already there, linear
// weights) and the wall's nearest frames; the gradients of the quadratic
// fit at the point. Leaves the sample as it is (the linear
// gradients) where the frames do not determine a quadratic.
static void shell_sample(const fascia_prep_points *pts, const fascia_frame_grid *grid, const int32_t *wall_frame,
                         int32_t s, int32_t *pair_frame, double *pair_w, double *pair_g, int32_t *pair_count) {
  const int64_t base = (int64_t)MAX_PAIRS * s;
  const int32_t *c = pts->sample_cell_frame + 3 * (int64_t)s;
  const double *x0 = pts->frame_position + 3 * (int64_t)c[0], *x1 = pts->frame_position + 3 * (int64_t)c[1],
               *x2 = pts->frame_position + 3 * (int64_t)c[2];
  double here[3], e1[3], e2[3], n[3];
  for (int r = 0; r < 3; ++r) here[r] = (x0[r] + x1[r] + x2[r]) / 3, e1[r] = x1[r] - x0[r], e2[r] = x2[r] - x0[r];
  n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  const double nn = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  const double l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
  if (!(nn > 0) || !(l1 > 0)) return;
  double u[3], v[3]; // the wall's plane
  for (int r = 0; r < 3; ++r) n[r] /= nn, u[r] = e1[r] / l1;
  v[0] = n[1] * u[2] - n[2] * u[1], v[1] = n[2] * u[0] - n[0] * u[2], v[2] = n[0] * u[1] - n[1] * u[0];
  // the point's place on the triangle: its centroid, or a part's where the
  // triangle is split (shell.c); off the plane only by its section offset
  const double *p = pts->sample_position + 3 * (int64_t)s;
  double along_u = 0, along_v = 0;
  for (int r = 0; r < 3; ++r) along_u += (p[r] - here[r]) * u[r], along_v += (p[r] - here[r]) * v[r];
  for (int r = 0; r < 3; ++r) here[r] += along_u * u[r] + along_v * v[r];
  // the stencil: the triangle's frames, then the wall's nearest others
  int32_t near[SHELL_QUERY], by_distance[SHELL_QUERY], frame[SHELL_QUERY + 3];
  double dist[SHELL_QUERY];
  fascia_real radius = 0, at[3] = {here[0], here[1], here[2]};
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *quiet = NULL;
  if (fascia_ctx_create(&cd, &quiet) != FASCIA_OK) return;
  const int32_t count = fascia_frame_grid_count(grid), want = count < SHELL_QUERY ? count : SHELL_QUERY;
  const fascia_status st = fascia_frame_grid_nearest(quiet, grid, at, want, near, &radius);
  fascia_ctx_destroy(&quiet);
  if (st != FASCIA_OK) return;
  const fascia_real *gx = fascia_frame_grid_positions(grid);
  for (int32_t j = 0; j < want; ++j) {
    double d2 = 0;
    for (int r = 0; r < 3; ++r) d2 += (gx[3 * (int64_t)near[j] + r] - at[r]) * (gx[3 * (int64_t)near[j] + r] - at[r]);
    dist[j] = sqrt(d2);
    by_distance[j] = j;
    for (int32_t i = j; i > 0 && dist[by_distance[i - 1]] > dist[by_distance[i]]; --i) {
      const int32_t t = by_distance[i];
      by_distance[i] = by_distance[i - 1], by_distance[i - 1] = t;
    }
  }
  int32_t keep = want < SHELL_STENCIL ? want : SHELL_STENCIL;
  while (keep < want && dist[by_distance[keep]] <= dist[by_distance[keep - 1]] * (1 + 1e-9)) ++keep;
  if (keep < want) radius = FASCIA_SHAPE_SUPPORT_MARGIN * dist[by_distance[keep]];
  int32_t m = 0;
  for (int j = 0; j < 3; ++j) frame[m++] = c[j];
  for (int32_t j = 0; j < keep; ++j) {
    const int32_t f = wall_frame[near[by_distance[j]]];
    if (f != c[0] && f != c[1] && f != c[2]) frame[m++] = f;
  }
  double reach = radius;
  for (int j = 0; j < 3; ++j) {
    double d2 = 0;
    for (int r = 0; r < 3; ++r) d2 += (pts->frame_position[3 * (int64_t)c[j] + r] - here[r]) *
                                      (pts->frame_position[3 * (int64_t)c[j] + r] - here[r]);
    reach = fmax(reach, FASCIA_SHAPE_SUPPORT_MARGIN * sqrt(d2));
  }
  // weighted least squares of the basis (1, a, b, a^2, ab, b^2) in units of reach
  double A[SHELL_BASIS * SHELL_BASIS] = {0}, B[SHELL_BASIS * (SHELL_QUERY + 3)] = {0};
  for (int32_t j = 0; j < m; ++j) {
    const double *x = pts->frame_position + 3 * (int64_t)frame[j];
    double d[3];
    for (int r = 0; r < 3; ++r) d[r] = x[r] - here[r];
    const double a = (d[0] * u[0] + d[1] * u[1] + d[2] * u[2]) / reach;
    const double b = (d[0] * v[0] + d[1] * v[1] + d[2] * v[2]) / reach;
    const double w = fascia_shape_kernel(sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / reach);
    const double basis[SHELL_BASIS] = {1, a, b, a * a, a * b, b * b};
    for (int r = 0; r < SHELL_BASIS; ++r) {
      for (int k = 0; k < SHELL_BASIS; ++k) A[r * SHELL_BASIS + k] += w * basis[r] * basis[k];
      B[r * m + j] = w * basis[r];
    }
  }
  if (m < SHELL_BASIS || !solve_small(A, B, m)) return;
  // the fit's slopes at the point: rows 1 and 2 of A^-1 B; weights as the triangle's
  double weight[SHELL_QUERY + 3] = {0};
  for (int32_t j = 0; j < pair_count[s]; ++j)
    for (int k = 0; k < 3; ++k)
      if (pair_frame[base + j] == c[k]) weight[k] = pair_w[base + j];
  // a drilling gauge's F carries one corner's rotation, not the corners'
  // mean, which is no rotation where they differ (a bent sheet): the gauge
  // would take that shrinkage for a change of area
  if (pts->sample_drilling && pts->sample_drilling[s]) weight[0] = 1, weight[1] = weight[2] = 0;
  int32_t order[SHELL_QUERY + 3];
  for (int32_t j = 0; j < m; ++j) order[j] = j;
  for (int32_t i = 1; i < m; ++i) // frames ascending, as the model's pairs
    for (int32_t j = i; j > 0 && frame[order[j - 1]] > frame[order[j]]; --j) {
      const int32_t t = order[j];
      order[j] = order[j - 1], order[j - 1] = t;
    }
  // the triangle's own linear gradients in (a, b), 1/m
  double pa[3], pb[3], lin_a[3], lin_b[3];
  for (int k = 0; k < 3; ++k) {
    const double *x = pts->frame_position + 3 * (int64_t)c[k];
    pa[k] = pb[k] = 0;
    for (int r = 0; r < 3; ++r) pa[k] += (x[r] - here[r]) * u[r], pb[k] += (x[r] - here[r]) * v[r];
  }
  const double det = (pa[1] - pa[0]) * (pb[2] - pb[0]) - (pa[2] - pa[0]) * (pb[1] - pb[0]);
  if (!(fabs(det) > 0)) return;
  for (int k = 0; k < 3; ++k)
    lin_a[k] = (pb[(k + 1) % 3] - pb[(k + 2) % 3]) / det, lin_b[k] = (pa[(k + 2) % 3] - pa[(k + 1) % 3]) / det;
  // the fit's slopes, plus the linear slopes of what it leaves at the corners
  double slope_a[SHELL_QUERY + 3], slope_b[SHELL_QUERY + 3];
  for (int32_t j = 0; j < m; ++j) slope_a[j] = B[1 * m + j] / reach, slope_b[j] = B[2 * m + j] / reach;
  for (int k = 0; k < 3; ++k) {
    const double a = pa[k] / reach, b = pb[k] / reach, basis[SHELL_BASIS] = {1, a, b, a * a, a * b, b * b};
    for (int32_t j = 0; j < m; ++j) {
      double fitted = 0; // at corner k, for unit data at frame j
      for (int r = 0; r < SHELL_BASIS; ++r) fitted += basis[r] * B[r * m + j];
      slope_a[j] += lin_a[k] * ((j == k) - fitted), slope_b[j] += lin_b[k] * ((j == k) - fitted);
    }
  }
  // a sheet's drilling stabiliser (reduced.h) takes what the fit leaves out
  // of the linear gradients; a sheet's other points the fit alone
  const int drilling = pts->sample_drilling && pts->sample_drilling[s];
  const double share = pts->sample_tissue[s] >= 0 ? 0 : SHELL_LINEAR_SHARE;
  const double fit = drilling ? -1 : 1 - share, linear = drilling ? 1 : share;
  for (int32_t j = 0; j < m; ++j) slope_a[j] *= fit, slope_b[j] *= fit;
  for (int k = 0; k < 3; ++k) slope_a[k] += linear * lin_a[k], slope_b[k] += linear * lin_b[k];
  if (drilling && pts->sample_drilling[s] == 2) // the deviatoric gauges (reduced.h)
    for (int32_t j = 0; j < m; ++j) slope_b[j] = -slope_b[j];
  if (drilling && pts->sample_drilling[s] == 3)
    for (int32_t j = 0; j < m; ++j) {
      const double t = slope_a[j];
      slope_a[j] = slope_b[j], slope_b[j] = t;
    }
  for (int32_t j = 0; j < m; ++j) {
    const int32_t q = order[j];
    pair_frame[base + j] = frame[q];
    pair_w[base + j] = weight[q];
    for (int r = 0; r < 3; ++r) pair_g[3 * (base + j) + r] = slope_a[q] * u[r] + slope_b[q] * v[r];
  }
  pair_count[s] = m;
}

// Whether sample s is a triangle's of wall w: shell organ w, or sheet tissue
// w - organ_count (a sheet bends as a flat wall: the same cure).
static int on_wall(const fascia_prep_scene *scene, const fascia_prep_points *pts, int32_t s, int32_t w) {
  if (pts->sample_voxel[s] >= 0 || pts->sample_cell_frame[3 * (int64_t)s + 2] < 0) return 0;
  return w < scene->organ_count ? pts->sample_tissue[s] < 0 && pts->sample_inside_organ[s] == w
                                : pts->sample_tissue[s] == w - scene->organ_count;
}

// The wall samples of every shell organ and sheet (shell_sample); after cell_weights.
static fascia_status shell_weights(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_points *pts,
                                   int32_t *pair_frame, double *pair_w, double *pair_g, int32_t *pair_count) {
  const int32_t S = pts->sample_count, N = pts->frame_count;
  int32_t *wall_frame = prep_calloc(N > 0 ? N : 1, sizeof(int32_t));
  uint8_t *on = prep_calloc(N > 0 ? N : 1, 1);
  double *x = prep_calloc(3 * (int64_t)(N > 0 ? N : 1), sizeof(double));
  fascia_status status = FASCIA_OK;
  fascia_frame_grid *grid = NULL;
  PREP_CHECK_GOTO(wall_frame && on && x, ctx, FASCIA_ERR_MEMORY, "shape functions: out of memory");
  for (int32_t s = 0; s < S; ++s) // a drilling stabiliser no fit reaches stays without stiffness
    if (pts->sample_drilling && pts->sample_drilling[s])
      memset(pair_g + 3 * (int64_t)MAX_PAIRS * s, 0, 3 * (size_t)pair_count[s] * sizeof(double));
  for (int32_t o = 0; o < scene->organ_count + scene->tissue_count; ++o) {
    if (o < scene->organ_count ? !scene->organs[o].shell
                               : scene->tissues[o - scene->organ_count].form != FASCIA_PREP_FORM_SHEET)
      continue;
    memset(on, 0, (size_t)N);
    for (int32_t s = 0; s < S; ++s)
      if (on_wall(scene, pts, s, o))
        for (int j = 0; j < 3; ++j) on[pts->sample_cell_frame[3 * (int64_t)s + j]] = 1;
    int32_t n = 0;
    for (int32_t i = 0; i < N; ++i)
      if (on[i]) {
        memcpy(x + 3 * (int64_t)n, pts->frame_position + 3 * (int64_t)i, 3 * sizeof(double));
        wall_frame[n++] = i;
      }
    if (n < SHELL_BASIS) continue;
    PREP_TRY_GOTO(fascia_frame_grid_create(ctx, n, x, &grid));
    for (int32_t s = 0; s < S; ++s)
      if (on_wall(scene, pts, s, o))
        shell_sample(pts, grid, wall_frame, s, pair_frame, pair_w, pair_g, pair_count);
    fascia_frame_grid_destroy(&grid);
  }
cleanup:
  fascia_frame_grid_destroy(&grid);
  free(wall_frame);
  free(on);
  free(x);
  return status;
}

// e without its part across the span of sample s's interval or triangle.
static void in_span(const fascia_prep_points *pts, int32_t s, double *e) {
  const int32_t *c = pts->sample_cell_frame + 3 * (int64_t)s;
  const double *x0 = pts->frame_position + 3 * (int64_t)c[0], *x1 = pts->frame_position + 3 * (int64_t)c[1];
  double a[3], n[3];
  for (int r = 0; r < 3; ++r) a[r] = x1[r] - x0[r];
  if (c[2] >= 0) { // a triangle: drop the normal part
    const double *x2 = pts->frame_position + 3 * (int64_t)c[2];
    const double b[3] = {x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2]};
    n[0] = a[1] * b[2] - a[2] * b[1], n[1] = a[2] * b[0] - a[0] * b[2], n[2] = a[0] * b[1] - a[1] * b[0];
    const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2], en = (e[0] * n[0] + e[1] * n[1] + e[2] * n[2]) / nn;
    for (int r = 0; r < 3; ++r) e[r] -= en * n[r];
  } else { // an interval: keep the part along it
    const double aa = a[0] * a[0] + a[1] * a[1] + a[2] * a[2], ea = (e[0] * a[0] + e[1] * a[1] + e[2] * a[2]) / aa;
    for (int r = 0; r < 3; ++r) e[r] = ea * a[r];
  }
}

// ------------------------------------------------------------ exact attachment

// A tissue with attachment "exact" is held the way the organ holds it: on
// the whole of the surface, not only at its shared frames. Each organ that
// moves rigidly (fixed, prescribed or rigid) within a sample's support adds
// one node to the sample's MLS: the organ's surface point nearest the sample,
// q = p - r grad r / |grad r| (r the organ's signed distance, quadratic
// B-splines on the voxel centres), whose value is the organ's motion. The weight it takes goes to
// the organ's shared frame nearest the sample: every shared frame of the
// organ carries the organ's motion of p (x_j + A_j (p - x_j)), whichever it
// is. Within a layer of thickness L the kernels of the frames that do not
// move with the organ are scaled by psi(r) = t^2 (3 - 2 t), t = r / L (at
// least PSI_FLOOR), so at the surface the fit passes through the organ's
// node and the tissue moves with the organ there; the weights stay an MLS,
// a partition of unity that reproduces linear fields of its nodes (a field
// that vanishes on a flat surface and grows linearly away from it is
// exact). The weights depend on p through q and psi as well, so their
// gradients are central differences of the whole construction.
#define PSI_FLOOR 1e-3
#define GRADIENT_STEP 1e-5 // of the support radius
#define ATTACH_ORGANS 4    // organs held exactly near one sample, at most

// The signed distance of organ o at p and its gradient, by quadratic
// B-splines on the voxel centres: its gradient is continuous (the foot point
// q with it; samples often sit on voxel centres, where a trilinear gradient
// jumps), and it is exact where the distance is linear (a flat surface).
// 0 when the stencil leaves the grid.
static int distance_at(const fascia_prep_volume *vol, const prep_grid *g, int32_t o, const double *p, double *r,
                       double *grad) {
  const float *d = vol->distance[o];
  double b[3][3], db[3][3];
  int32_t c[3];
  for (int k = 0; k < 3; ++k) {
    const double x = p[k] / g->h - g->lo[k];
    c[k] = (int32_t)floor(x + 0.5);
    const double u = x - c[k];
    if (c[k] < 1 || c[k] + 1 >= g->dims[k]) return 0;
    b[k][0] = 0.5 * (0.5 - u) * (0.5 - u), b[k][1] = 0.75 - u * u, b[k][2] = 0.5 * (0.5 + u) * (0.5 + u);
    db[k][0] = -(0.5 - u) / g->h, db[k][1] = -2 * u / g->h, db[k][2] = (0.5 + u) / g->h;
  }
  *r = 0;
  grad[0] = grad[1] = grad[2] = 0;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        const double v = d[prep_grid_index(g, c[0] + i - 1, c[1] + j - 1, c[2] + k - 1)];
        *r += v * b[0][i] * b[1][j] * b[2][k];
        grad[0] += v * db[0][i] * b[1][j] * b[2][k];
        grad[1] += v * b[0][i] * db[1][j] * b[2][k];
        grad[2] += v * b[0][i] * b[1][j] * db[2][k];
      }
  return 1;
}

// 1 when tissue td's frames on organ o are all shared with it and follow it
// rigidly: the organ's node stands for its whole surface.
static int attaches_exactly(const fascia_prep_scene *scene, const fascia_prep_volume *vol,
                            const fascia_prep_tissue_def *td, int32_t o) {
  if (scene->organs[o].kind == FASCIA_ORGAN_DEFORMABLE || scene->organs[o].shell || !vol->distance[o]) return 0;
  for (int32_t k = 0; k < td->coupling_count; ++k)
    if (td->coupling[k].organ == o)
      return td->coupling[k].enabled && td->coupling[k].region.kind == FASCIA_PREP_REGION_NONE &&
             td->coupling[k].parts.count == 0;
  return td->couple_others || fascia_prep_tissue_connects(td, o);
}

// The frame of grid nearest to p (the lowest index among ties).
static int32_t nearest_frame(fascia_ctx *quiet, const fascia_frame_grid *grid, const double *p) {
  int32_t nearest = 0;
  fascia_real radius;
  if (fascia_frame_grid_nearest(quiet, grid, p, 1, &nearest, &radius) == FASCIA_OK) return nearest;
  // p on a frame: no support radius, but that frame is the nearest
  const fascia_real *x = fascia_frame_grid_positions(grid);
  double best = INFINITY;
  for (int32_t i = 0; i < fascia_frame_grid_count(grid); ++i) {
    const double d = (x[3 * i] - p[0]) * (x[3 * i] - p[0]) + (x[3 * i + 1] - p[1]) * (x[3 * i + 1] - p[1]) +
                     (x[3 * i + 2] - p[2]) * (x[3 * i + 2] - p[2]);
    if (d < best) best = d, nearest = i;
  }
  return nearest;
}

// MLS weights at p of the n nodes x with kernel multipliers k (0: none) and
// support radius; w[n]. Returns 0 when the moment matrix is singular.
static int layer_mls(int32_t n, const double *x, const double *k, const double *p, double radius, double *w) {
  double M[16] = {0}, b[4];
  for (int32_t i = 0; i < n; ++i) {
    b[0] = 1;
    double q2 = 0;
    for (int r = 0; r < 3; ++r) b[r + 1] = (x[3 * i + r] - p[r]) / radius, q2 += b[r + 1] * b[r + 1];
    w[i] = k[i] * fascia_shape_kernel(sqrt(q2));
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 4; ++c) M[4 * a + c] += w[i] * b[a] * b[c];
  }
  // M a = e0 by elimination with partial pivoting
  double A[4][5], scale = 0;
  for (int a = 0; a < 4; ++a) {
    for (int c = 0; c < 4; ++c) A[a][c] = M[4 * a + c], scale = fmax(scale, fabs(M[4 * a + c]));
    A[a][4] = a == 0;
  }
  for (int c = 0; c < 4; ++c) {
    int best = c;
    for (int a = c + 1; a < 4; ++a)
      if (fabs(A[a][c]) > fabs(A[best][c])) best = a;
    if (!(fabs(A[best][c]) > 1e-12 * scale)) return 0;
    for (int e = 0; e < 5; ++e) {
      const double t = A[c][e];
      A[c][e] = A[best][e], A[best][e] = t;
    }
    for (int a = c + 1; a < 4; ++a) {
      const double f = A[a][c] / A[c][c];
      for (int e = c; e < 5; ++e) A[a][e] -= f * A[c][e];
    }
  }
  double sol[4];
  for (int a = 3; a >= 0; --a) {
    sol[a] = A[a][4];
    for (int c = a + 1; c < 4; ++c) sol[a] -= A[a][c] * sol[c];
    sol[a] /= A[a][a];
  }
  for (int32_t i = 0; i < n; ++i) {
    double v = sol[0];
    for (int r = 0; r < 3; ++r) v += sol[r + 1] * (x[3 * i + r] - p[r]) / radius;
    w[i] *= v;
  }
  return 1;
}

// 1 when the straight segment from p to organ o's surface point q nearest
// it stays in the sample's region until it reaches the organ: the organ's
// node, like a frame, must not be reached across another organ or a void.
static int surface_in_sight(const fascia_prep_volume *vol, const prep_grid *g, int32_t o, const double *p,
                            uint8_t label) {
  double r, grad[3];
  if (!distance_at(vol, g, o, p, &r, grad)) return 0;
  const double norm = sqrt(grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]);
  if (!(norm > 0) || !(r < vol->band[o] - 2 * g->h)) return 0; // beyond the band the distances are not exact
  const int32_t steps = (int32_t)ceil(2 * fabs(r) / g->h);
  for (int32_t k = 1; k <= steps; ++k) {
    double x[3];
    for (int c = 0; c < 3; ++c) x[c] = p[c] - (double)k / steps * r * grad[c] / norm;
    const int64_t v = prep_grid_locate(g, x);
    if (v < 0) return 0;
    if (vol->region[v] != label && vol->distance[o][v] > g->h) return 0;
  }
  return 1;
}

// What the weights of one sample in the layer are made of.
typedef struct layer_sample {
  int32_t frames;             // the sample's own frames (nodes 0 .. frames - 1)
  const int32_t *frame;       // [frames]
  const uint8_t *held;        // [frames] 1: a frame that moves with an organ (its kernel unscaled)
  int32_t organs;             // the organs' nodes follow
  const int32_t *organ;       // [organs]
  double radius, layer;
} layer_sample;

// Weights of the nodes at p: the frames', then one per organ; 0 when singular.
static int layer_weights(const layer_sample *ls, const fascia_prep_volume *vol, const prep_grid *g,
                         const fascia_prep_points *pts, const double *p, double *w) {
  double x[3 * (MAX_PAIRS + ATTACH_ORGANS)], k[MAX_PAIRS + ATTACH_ORGANS], psi = 1;
  const int32_t n = ls->frames + ls->organs;
  for (int32_t j = 0; j < ls->organs; ++j) {
    double r, grad[3];
    if (!distance_at(vol, g, ls->organ[j], p, &r, grad)) return 0;
    const double norm = sqrt(grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]);
    if (!(norm > 0)) return 0;
    for (int c = 0; c < 3; ++c) x[3 * (ls->frames + j) + c] = p[c] - r * grad[c] / norm;
    k[ls->frames + j] = 1;
    const double t = fmin(fmax(r / ls->layer, 0), 1);
    psi *= t * t * (3 - 2 * t);
  }
  psi = fmax(psi, PSI_FLOOR);
  for (int32_t j = 0; j < ls->frames; ++j) {
    memcpy(x + 3 * j, pts->frame_position + 3 * (int64_t)ls->frame[j], 3 * sizeof(double));
    k[j] = ls->held[j] ? 1 : psi;
  }
  return layer_mls(n, x, k, p, ls->radius, w);
}

// The weights of every MLS sample of the tissues with attachment "exact"
// that lies within its support of an organ they hold to; blended[s] set for
// the samples it changed.
static fascia_status exact_attachment(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_volume *vol,
                                      const fascia_prep_points *pts, int32_t *pair_frame, double *pair_w,
                                      double *pair_g, int32_t *pair_count, uint8_t *blended) {
  const prep_grid g = prep_volume_grid(vol);
  const int32_t N = pts->frame_count, S = pts->sample_count, O = scene->organ_count;
  fascia_status status = FASCIA_OK;
  fascia_frame_grid **grids = prep_calloc(O, sizeof *grids);
  int32_t **ids = prep_calloc(O, sizeof *ids);
  double *x = prep_calloc(3 * (int64_t)(N > 0 ? N : 1), sizeof(double));
  fascia_ctx *quiet = NULL;
  fascia_ctx_def cd = fascia_ctx_def_default();
  PREP_CHECK_GOTO(grids && ids && x && fascia_ctx_create(&cd, &quiet) == FASCIA_OK, ctx, FASCIA_ERR_MEMORY,
                  "shape functions: out of memory");
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    const fascia_prep_tissue_def *td = scene->tissues + t;
    if (td->form != FASCIA_PREP_FORM_VOLUME || td->attachment != FASCIA_PREP_ATTACH_EXACT ||
        td->shape_kind != FASCIA_PREP_SHAPE_MLS)
      continue;
    const double L = td->attachment_layer > 0 ? td->attachment_layer : td->sample_spacing;
    // the tissue's shared frames on each organ it holds to exactly
    for (int32_t o = 0; o < O; ++o) {
      fascia_frame_grid_destroy(grids + o);
      free(ids[o]);
      ids[o] = NULL;
      if (!attaches_exactly(scene, vol, td, o)) continue;
      int32_t n = 0;
      for (int32_t i = 0; i < N; ++i) n += pts->frame_tissue[i] == t && pts->frame_organ[i] == o;
      if (n == 0) continue;
      ids[o] = prep_calloc(n, sizeof(int32_t));
      PREP_CHECK_GOTO(ids[o], ctx, FASCIA_ERR_MEMORY, "shape functions: out of memory");
      n = 0;
      for (int32_t i = 0; i < N; ++i)
        if (pts->frame_tissue[i] == t && pts->frame_organ[i] == o) {
          memcpy(x + 3 * (int64_t)n, pts->frame_position + 3 * (int64_t)i, 3 * sizeof(double));
          ids[o][n++] = i;
        }
      PREP_TRY_GOTO(fascia_frame_grid_create(ctx, n, x, grids + o));
    }
    for (int32_t s = 0; s < S; ++s) {
      if (pts->sample_tissue[s] != t || pts->sample_voxel[s] < 0) continue;
      const double *p = pts->sample_position + 3 * (int64_t)s;
      const int64_t base = (int64_t)MAX_PAIRS * s;
      int32_t *frame = pair_frame + base;
      double far = 0;
      for (int32_t j = 0; j < pair_count[s]; ++j) {
        const double *y = pts->frame_position + 3 * (int64_t)frame[j];
        far = fmax(far, sqrt((y[0] - p[0]) * (y[0] - p[0]) + (y[1] - p[1]) * (y[1] - p[1]) +
                             (y[2] - p[2]) * (y[2] - p[2])));
      }
      int32_t organ[ATTACH_ORGANS], m = 0;
      for (int32_t o = 0; o < O && m < ATTACH_ORGANS; ++o) {
        double r, grad[3];
        if (grids[o] && distance_at(vol, &g, o, p, &r, grad) && r < FASCIA_SHAPE_SUPPORT_MARGIN * far &&
            surface_in_sight(vol, &g, o, p, vol->region[pts->sample_voxel[s]]))
          organ[m++] = o;
      }
      if (m == 0) continue;
      uint8_t held[MAX_PAIRS];
      for (int32_t j = 0; j < pair_count[s]; ++j) {
        held[j] = 0;
        for (int32_t k = 0; k < m; ++k) held[j] |= pts->frame_organ[frame[j]] == organ[k];
      }
      const layer_sample ls = {pair_count[s], frame, held, m, organ, FASCIA_SHAPE_SUPPORT_MARGIN * far, L};
      const int32_t n = pair_count[s] + m;
      double w[MAX_PAIRS + ATTACH_ORGANS], grad[3 * (MAX_PAIRS + ATTACH_ORGANS)];
      double wp[MAX_PAIRS + ATTACH_ORGANS], wm[MAX_PAIRS + ATTACH_ORGANS];
      int ok = layer_weights(&ls, vol, &g, pts, p, w);
      const double step = GRADIENT_STEP * ls.radius;
      for (int c = 0; c < 3 && ok; ++c) {
        double q[3] = {p[0], p[1], p[2]};
        q[c] = p[c] + step;
        ok = layer_weights(&ls, vol, &g, pts, q, wp);
        q[c] = p[c] - step;
        ok = ok && layer_weights(&ls, vol, &g, pts, q, wm);
        for (int32_t j = 0; j < n && ok; ++j) grad[3 * j + c] = (wp[j] - wm[j]) / (2 * step);
      }
      PREP_CHECK_GOTO(ok, ctx, FASCIA_ERR_NUMERIC,
                      "tissue '%s' sample %d at (%.4g %.4g %.4g) m: attachment exact: the weights of its %d frames "
                      "and the organ surface are singular; use attachment \"frames\" or more neighbours",
                      td->name, (int)s, p[0], p[1], p[2], (int)pair_count[s]);
      // the frames' weights, then each organ's onto its shared frame nearest the sample
      memcpy(pair_w + base, w, (size_t)pair_count[s] * sizeof(double));
      memcpy(pair_g + 3 * base, grad, (size_t)pair_count[s] * 3 * sizeof(double));
      for (int32_t k = 0; k < m; ++k) {
        const int32_t target = ids[organ[k]][nearest_frame(quiet, grids[organ[k]], p)];
        int32_t at = 0;
        while (at < pair_count[s] && frame[at] < target) ++at;
        if (at == pair_count[s] || frame[at] != target) {
          PREP_CHECK_GOTO(pair_count[s] < MAX_PAIRS, ctx, FASCIA_ERR_INTERNAL,
                          "tissue '%s' sample %d: %d frames already, no room for organ '%s''s (attachment exact)",
                          td->name, (int)s, MAX_PAIRS, scene->organs[organ[k]].name);
          const int32_t tail = pair_count[s] - at;
          memmove(frame + at + 1, frame + at, (size_t)tail * sizeof *frame);
          memmove(pair_w + base + at + 1, pair_w + base + at, (size_t)tail * sizeof *pair_w);
          memmove(pair_g + 3 * (base + at + 1), pair_g + 3 * (base + at), (size_t)tail * 3 * sizeof *pair_g);
          frame[at] = target, pair_w[base + at] = 0;
          for (int r = 0; r < 3; ++r) pair_g[3 * (base + at) + r] = 0;
          ++pair_count[s];
        }
        pair_w[base + at] += w[ls.frames + k];
        for (int r = 0; r < 3; ++r) pair_g[3 * (base + at) + r] += grad[3 * (ls.frames + k) + r];
      }
      blended[s] = 1;
    }
  }
cleanup:
  fascia_ctx_destroy(&quiet);
  for (int32_t o = 0; grids && o < O; ++o) fascia_frame_grid_destroy(grids + o);
  for (int32_t o = 0; ids && o < O; ++o) free(ids[o]);
  free(grids);
  free(ids);
  free(x);
  return status;
}

// ------------------------------------------------------------ the stage

fascia_status fascia_prep_shape_functions(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                          const fascia_prep_volume *volume, const fascia_prep_points *points,
                                          fascia_prep_weights **out) {
  PREP_CHECK(ctx && scene && volume && points && out, ctx, FASCIA_ERR_ARGUMENT,
             "fascia_prep_shape_functions: NULL argument");
  *out = NULL;
  const prep_grid g = prep_volume_grid(volume);
  const int64_t n = prep_grid_count(&g);
  const int32_t S = points->sample_count, N = points->frame_count;
  fascia_status status = FASCIA_OK;
  local_tables *lt = NULL;
  int64_t *attach_voxel = NULL;
  uint8_t *blended = NULL;
  fascia_prep_weights *W = calloc(1, sizeof *W);
  int32_t shared = 0;
  for (int32_t i = 0; i < N; ++i) shared += points->frame_organ_voxel[i] >= 0;
  frame_index fi = {malloc((size_t)n * sizeof(int32_t)), prep_calloc(N + shared, sizeof(int32_t)),
                    prep_calloc(N + shared, sizeof(int32_t))};
  int32_t *pair_frame = prep_calloc((int64_t)MAX_PAIRS * S, sizeof(int32_t));
  double *pair_w = prep_calloc((int64_t)MAX_PAIRS * S, sizeof(double));
  double *pair_g = prep_calloc((int64_t)MAX_PAIRS * 3 * S, sizeof(double));
  int32_t *pair_count = prep_calloc(S, sizeof(int32_t));
  PREP_CHECK_GOTO(W && fi.head && fi.next && fi.frame && pair_frame && pair_w && pair_g && pair_count, ctx, FASCIA_ERR_MEMORY,
                  "shape functions: out of memory for %d samples", (int)S);
  attach_voxel = prep_calloc(N + shared, sizeof(int64_t));
  PREP_CHECK_GOTO(attach_voxel, ctx, FASCIA_ERR_MEMORY, "shape functions: out of memory");
  for (int64_t v = 0; v < n; ++v) fi.head[v] = -1;
  for (int32_t i = N - 1, a = N + shared - 1; i >= 0; --i) { // lists ascend by frame index
    const int64_t at[2] = {points->frame_organ_voxel[i], points->frame_voxel[i]};
    for (int k = 0; k < 2; ++k) {
      if (at[k] < 0) continue;
      fi.frame[a] = i;
      attach_voxel[a] = at[k];
      fi.next[a] = fi.head[at[k]];
      fi.head[at[k]] = a--;
    }
  }
  // the local search's table of frames by cell
  lt = calloc(1, sizeof *lt);
  PREP_CHECK_GOTO(lt, ctx, FASCIA_ERR_MEMORY, "shape functions: out of memory");
  PREP_TRY_GOTO(cell_index_build(ctx, &g, &fi, N, N + shared, attach_voxel, &lt->cells));
  // TET samples: barycentric in their own tets; then MLS samples
  fascia_ctx_progress(ctx, "shape functions", 0, "tet");
  PREP_TRY_GOTO(tet_weights(ctx, scene, volume, points, pair_frame, pair_w, pair_g, pair_count));
  PREP_TRY_GOTO(cell_weights(ctx, scene, points, pair_frame, pair_w, pair_g, pair_count));
  PREP_TRY_GOTO(shell_weights(ctx, scene, points, pair_frame, pair_w, pair_g, pair_count));
  {
    int64_t mls_count = 0, done = 0, next_report = 1;
    for (int32_t s = 0; s < S; ++s) {
      int32_t kind;
      if (points->sample_voxel[s] < 0) continue;
      prep_label_sampling(scene, volume, volume->region[points->sample_voxel[s]], NULL, NULL, &kind, NULL);
      mls_count += kind == FASCIA_PREP_SHAPE_MLS;
    }
    fascia_ctx_progress(ctx, "shape functions", 0, "mls");
    int32_t failed = INT32_MAX, out_of_memory = 0;
    char message[1024] = "";
#pragma omp parallel num_threads(fascia_ctx_threads(ctx))
    {
      search se = {0}; // its distance array comes with the first search
      fascia_ctx_def def = fascia_ctx_def_default();
      def.threads = 1;
      const int ready = fascia_ctx_create(&def, &se.ctx) == FASCIA_OK;
#ifdef _OPENMP
      const int reporter = omp_get_thread_num() == 0;
#else
      const int reporter = 1;
#endif
#pragma omp for schedule(dynamic, 16)
      for (int32_t s = 0; s < S; ++s) {
        int32_t kind, neighbours;
        if (points->sample_voxel[s] < 0) continue;
        prep_label_sampling(scene, volume, volume->region[points->sample_voxel[s]], NULL, NULL, &kind, &neighbours);
        if (kind != FASCIA_PREP_SHAPE_MLS) continue;
        if (!ready) {
#pragma omp atomic write
          out_of_memory = 1;
          continue;
        }
        const int64_t base = (int64_t)MAX_PAIRS * s;
        const int r = mls_sample(&se, &g, volume, points, &fi, lt, s, neighbours, pair_frame + base, pair_w + base,
                                 pair_g + 3 * base, pair_count + s);
        int64_t now;
#pragma omp atomic capture
        now = ++done;
        // one thread reports (the hook need not be thread-safe), about every percent
        if (reporter && now >= next_report) {
          char detail[64];
          snprintf(detail, sizeof detail, "mls: %lld of %lld samples", (long long)now, (long long)mls_count);
          fascia_ctx_progress(ctx, "shape functions", (double)now / (double)mls_count, detail);
          next_report = now + (mls_count + 99) / 100;
        }
        if (r < 0) {
#pragma omp atomic write
          out_of_memory = 1;
        } else if (r > 0) {
#pragma omp critical(prep_shape_failure)
          if (s < failed) { // the lowest failing sample is reported: deterministic
            failed = s;
            snprintf(message, sizeof message, "%s", fascia_ctx_message(se.ctx));
          }
        }
      }
      fascia_ctx_destroy(&se.ctx);
      free(se.pool);
      free(se.dist);
      free(se.touched);
      prep_heap_free(&se.heap);
    }
    PREP_CHECK_GOTO(!out_of_memory, ctx, FASCIA_ERR_MEMORY, "shape functions: out of memory");
    char name[FASCIA_NAME_SIZE + 32] = "";
    if (failed != INT32_MAX) prep_label_name(scene, volume, volume->region[points->sample_voxel[failed]], name, sizeof name);
    PREP_CHECK_GOTO(failed == INT32_MAX, ctx, FASCIA_ERR_NUMERIC, "%s %s", name, message);
  }
  blended = prep_calloc(S, 1);
  PREP_CHECK_GOTO(blended, ctx, FASCIA_ERR_MEMORY, "shape functions: out of memory");
  PREP_TRY_GOTO(exact_attachment(ctx, scene, volume, points, pair_frame, pair_w, pair_g, pair_count, blended));
  // compact into CSR and measure linear reproduction (a blended sample
  // reproduces its organ's motion instead)
  int64_t P = 0;
  for (int32_t s = 0; s < S; ++s) P += pair_count[s];
  PREP_CHECK_GOTO(P < INT32_MAX, ctx, FASCIA_ERR_MEMORY, "shape functions: %lld pairs is too many", (long long)P);
  W->sample_count = S;
  W->pair_count = (int32_t)P;
  W->sample_offsets = prep_calloc(S + 1, sizeof(int32_t));
  W->pair_frame = prep_calloc(P, sizeof(int32_t));
  W->pair_weight = prep_calloc(P, sizeof(double));
  W->pair_gradient = prep_calloc(3 * P, sizeof(double));
  PREP_CHECK_GOTO(W->sample_offsets && W->pair_frame && W->pair_weight && W->pair_gradient, ctx, FASCIA_ERR_MEMORY,
                  "shape functions: out of memory for %lld pairs", (long long)P);
  int64_t k = 0;
  for (int32_t s = 0; s < S; ++s) {
    double reproduced[3] = {0, 0, 0};
    for (int32_t j = 0; j < pair_count[s]; ++j, ++k) {
      const int64_t src = (int64_t)MAX_PAIRS * s + j;
      W->pair_frame[k] = pair_frame[src];
      W->pair_weight[k] = pair_w[src];
      memcpy(W->pair_gradient + 3 * k, pair_g + 3 * src, 3 * sizeof(double));
      for (int r = 0; r < 3; ++r) reproduced[r] += pair_w[src] * points->frame_position[3 * (int64_t)pair_frame[src] + r];
    }
    W->sample_offsets[s + 1] = (int32_t)k;
    double e[3];
    for (int r = 0; r < 3; ++r) e[r] = reproduced[r] - points->sample_position[3 * (int64_t)s + r];
    if (points->sample_voxel[s] < 0) in_span(points, s, e); // a strand's section, a sheet's thickness: the rotations'
    // a sheet's drilling gauge weighs one corner alone: its position is that corner's offset, not a weighted mean
    const int gauge = points->sample_drilling && points->sample_drilling[s];
    for (int r = 0; r < 3 && !blended[s] && !gauge; ++r) W->max_linear_error = fmax(W->max_linear_error, fabs(e[r]));
  }
  fascia_ctx_progress(ctx, "shape functions", 1, "done");
  *out = W;
  W = NULL;
cleanup:
  if (lt) {
    free(lt->cells.start);
    free(lt->cells.frame);
    free(lt->cells.voxel);
    free(lt);
  }
  free(attach_voxel);
  free(blended);
  fascia_prep_weights_destroy(&W);
  free(fi.head);
  free(fi.next);
  free(fi.frame);
  free(pair_frame);
  free(pair_w);
  free(pair_g);
  free(pair_count);
  return status;
}
