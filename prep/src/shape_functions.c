// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Stage 5, shape functions: the weights and rest-space gradients that tie
// each sample to its frames (DESIGN.md "The mechanics"; paper sec. 2.1).
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
// Regions. Tissues and the insides of deformable organs are treated alike,
// each sample by the region of its voxel. A frame is reached from its own
// voxel and, when it is shared with a deformable organ, also from the organ's
// inside voxel it is attached to (frame_organ_voxel): both the tissue's and
// the organ's samples can take it.
//
// TET (mesh-based). The region's frames are tetrahedralised (CGAL Delaunay);
// a tetrahedron is kept when its centroid and the midpoints of its edges lie
// in the region. Each sample takes the barycentric weights of the
// kept tetrahedron holding it, or, if none does, of the nearest kept one
// (extrapolated: still a partition of unity reproducing linear fields).
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

// Per-thread state of the geodesic search.
typedef struct search {
  double *dist;      // [voxels] INFINITY when untouched (double: the same type as the heap keys)
  int64_t *touched;  // voxels whose dist was set, to reset them
  int64_t touched_count, touched_capacity;
  prep_heap heap;
  fascia_ctx *ctx;   // private context: fascia_shape_mls writes its message here
} search;

typedef struct candidate {
  double distance;
  int32_t frame;
} candidate;

// Frames by voxel: attachment a puts frame[a] at a voxel; head[v] is the
// first attachment at voxel v, next[a] the following one (-1 ends).
typedef struct frame_index {
  int32_t *head;  // [voxels]
  int32_t *next;  // [attachments]
  int32_t *frame; // [attachments]
} frame_index;

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

static int by_frame(const void *a, const void *b) {
  const int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
  return (x > y) - (x < y);
}

// MLS weights of sample s into frame[0..count), w, grad (ascending frames).
// Returns 0 ok, 1 no usable frame set (message on se->ctx), -1 out of memory.
static int mls_sample(search *se, const prep_grid *g, const fascia_prep_volume *vol, const fascia_prep_points *pts,
                      const frame_index *fi, int32_t s, int32_t k, int32_t *frame, double *w, double *grad,
                      int32_t *count) {
  candidate cand[MAX_PAIRS];
  const double *p = pts->sample_position + 3 * (int64_t)s;
  const int32_t tries[3] = {k + 4 < MAX_PAIRS ? k + 4 : MAX_PAIRS, 2 * k + 8 < MAX_PAIRS ? 2 * k + 8 : MAX_PAIRS,
                            MAX_PAIRS};
  for (int attempt = 0; attempt < 3; ++attempt) {
    const int32_t found = nearest_frames(se, g, vol, pts, fi, s, tries[attempt], cand);
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

static int in_region(const prep_grid *g, const fascia_prep_volume *vol, uint8_t label, const double *x) {
  const int64_t v = prep_grid_locate(g, x);
  return v >= 0 && vol->region[v] == label;
}

// Barycentric weights of p in tet (a, b, c, d): w[4], grad[12]; 0 if flat.
static int tet_weights(const double *const *x, const double *p, double *w, double *grad) {
  double e[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) e[c][r] = x[c + 1][r] - x[0][r];
  // columns e1 e2 e3; inverse rows give gradients of w1..w3
  const double det = e[0][0] * (e[1][1] * e[2][2] - e[2][1] * e[1][2]) - e[1][0] * (e[0][1] * e[2][2] - e[2][1] * e[0][2]) +
                     e[2][0] * (e[0][1] * e[1][2] - e[1][1] * e[0][2]);
  double scale = 0;
  for (int c = 0; c < 3; ++c) scale = fmax(scale, e[c][0] * e[c][0] + e[c][1] * e[c][1] + e[c][2] * e[c][2]);
  if (!(fabs(det) > 1e-9 * scale * sqrt(scale))) return 0;
  // inverse of the matrix A with A[r][c] = e[c][r]
  double inv[3][3];
  inv[0][0] = (e[1][1] * e[2][2] - e[2][1] * e[1][2]) / det;
  inv[0][1] = -(e[1][0] * e[2][2] - e[2][0] * e[1][2]) / det;
  inv[0][2] = (e[1][0] * e[2][1] - e[2][0] * e[1][1]) / det;
  inv[1][0] = -(e[0][1] * e[2][2] - e[2][1] * e[0][2]) / det;
  inv[1][1] = (e[0][0] * e[2][2] - e[2][0] * e[0][2]) / det;
  inv[1][2] = -(e[0][0] * e[2][1] - e[2][0] * e[0][1]) / det;
  inv[2][0] = (e[0][1] * e[1][2] - e[1][1] * e[0][2]) / det;
  inv[2][1] = -(e[0][0] * e[1][2] - e[1][0] * e[0][2]) / det;
  inv[2][2] = (e[0][0] * e[1][1] - e[1][0] * e[0][1]) / det;
  const double d[3] = {p[0] - x[0][0], p[1] - x[0][1], p[2] - x[0][2]};
  w[0] = 1;
  for (int c = 0; c < 3; ++c) {
    w[c + 1] = inv[c][0] * d[0] + inv[c][1] * d[1] + inv[c][2] * d[2];
    w[0] -= w[c + 1];
    for (int r = 0; r < 3; ++r) grad[3 * (c + 1) + r] = inv[c][r];
  }
  for (int r = 0; r < 3; ++r) grad[r] = -(grad[3 + r] + grad[6 + r] + grad[9 + r]);
  return 1;
}

// Tet weights for the samples of the region with this label (a tissue or a
// deformable organ's inside) into the per-sample buffers. The region's frames
// are those reached from its voxels (shared frames included).
static fascia_status tet_region(fascia_ctx *ctx, const fascia_prep_scene *scene, const prep_grid *g,
                                const fascia_prep_volume *vol, const fascia_prep_points *pts, uint8_t label,
                                int32_t *pair_frame, double *pair_w, double *pair_g, int32_t *pair_count) {
  fascia_status status = FASCIA_OK;
  char name[FASCIA_NAME_SIZE + 32];
  prep_label_name(scene, vol, label, name, sizeof name);
  int32_t *tets = NULL, tet_count = 0, kept = 0, count = 0;
  double *centre = NULL, *position = NULL;
  int32_t *list = prep_calloc(pts->frame_count, sizeof(int32_t)); // region frame -> frame, ascending
  PREP_CHECK(list, ctx, FASCIA_ERR_MEMORY, "shape functions: out of memory");
  for (int32_t i = 0; i < pts->frame_count; ++i) {
    const int64_t shared = pts->frame_organ_voxel[i];
    if (vol->region[pts->frame_voxel[i]] == label || (shared >= 0 && vol->region[shared] == label)) list[count++] = i;
  }
  position = prep_calloc(3 * (int64_t)count, sizeof(double));
  PREP_CHECK_GOTO(position, ctx, FASCIA_ERR_MEMORY, "shape functions: out of memory");
  for (int32_t k = 0; k < count; ++k) memcpy(position + 3 * k, pts->frame_position + 3 * (int64_t)list[k], 3 * sizeof(double));
  PREP_CHECK_GOTO(count >= 4, ctx, FASCIA_ERR_NUMERIC, "%s: fewer than 4 frames, no tetrahedral mesh", name);
  PREP_TRY_GOTO(fascia_cgal_delaunay(ctx, count, position, &tets, &tet_count));
  // keep tets inside the region
  for (int32_t k = 0; k < tet_count; ++k) {
    const double *x[4];
    for (int r = 0; r < 4; ++r) x[r] = position + 3 * (int64_t)tets[4 * k + r];
    double c[3] = {0, 0, 0};
    for (int r = 0; r < 4; ++r)
      for (int a = 0; a < 3; ++a) c[a] += x[r][a] / 4;
    int ok = in_region(g, vol, label, c);
    for (int a = 0; a < 4 && ok; ++a)
      for (int b = a + 1; b < 4 && ok; ++b) {
        const double m[3] = {(x[a][0] + x[b][0]) / 2, (x[a][1] + x[b][1]) / 2, (x[a][2] + x[b][2]) / 2};
        ok = in_region(g, vol, label, m);
      }
    double wtest[4], gtest[12];
    if (ok && tet_weights(x, c, wtest, gtest)) memmove(tets + 4 * kept++, tets + 4 * k, 4 * sizeof(int32_t));
  }
  PREP_CHECK_GOTO(kept > 0, ctx, FASCIA_ERR_NUMERIC,
                  "%s: no tetrahedron of its frames lies inside its region; use shape_functions.kind \"mls\" "
                  "or a smaller frame_spacing",
                  name);
  centre = prep_calloc(3 * (int64_t)kept, sizeof(double));
  PREP_CHECK_GOTO(centre, ctx, FASCIA_ERR_MEMORY, "shape functions: out of memory");
  for (int32_t k = 0; k < kept; ++k)
    for (int r = 0; r < 4; ++r)
      for (int a = 0; a < 3; ++a)
        centre[3 * k + a] += position[3 * (int64_t)tets[4 * k + r] + a] / 4;
  // each sample: the kept tet with the largest smallest barycentric weight
  // (inside when >= 0), ties to the lower tet index
#pragma omp parallel for schedule(dynamic, 64) num_threads(fascia_ctx_threads(ctx))
  for (int32_t s = 0; s < pts->sample_count; ++s) {
    if (vol->region[pts->sample_voxel[s]] != label) continue;
    const double *p = pts->sample_position + 3 * (int64_t)s;
    double best = -INFINITY, bw[4] = {0}, bg[12] = {0};
    int32_t bk = -1;
    for (int32_t k = 0; k < kept; ++k) {
      const double *c = centre + 3 * k;
      const double *x[4];
      for (int r = 0; r < 4; ++r) x[r] = position + 3 * (int64_t)tets[4 * k + r];
      double reach = 0;
      for (int r = 0; r < 4; ++r)
        reach = fmax(reach, (x[r][0] - c[0]) * (x[r][0] - c[0]) + (x[r][1] - c[1]) * (x[r][1] - c[1]) +
                                (x[r][2] - c[2]) * (x[r][2] - c[2]));
      const double d2 = (p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) + (p[2] - c[2]) * (p[2] - c[2]);
      if (best >= 0 && d2 > reach) continue; // cannot contain p
      double w[4], gr[12];
      if (!tet_weights(x, p, w, gr)) continue;
      const double low = fmin(fmin(w[0], w[1]), fmin(w[2], w[3]));
      if (low > best) {
        best = low, bk = k;
        memcpy(bw, w, sizeof bw);
        memcpy(bg, gr, sizeof bg);
      }
    }
    // ascending frame order
    int32_t order[4] = {0, 1, 2, 3};
    for (int a = 1; a < 4; ++a)
      for (int b = a; b > 0 && tets[4 * bk + order[b - 1]] > tets[4 * bk + order[b]]; --b) {
        const int32_t tmp = order[b];
        order[b] = order[b - 1];
        order[b - 1] = tmp;
      }
    for (int r = 0; r < 4; ++r) {
      pair_frame[(int64_t)MAX_PAIRS * s + r] = list[tets[4 * bk + order[r]]];
      pair_w[(int64_t)MAX_PAIRS * s + r] = bw[order[r]];
      memcpy(pair_g + 3 * ((int64_t)MAX_PAIRS * s + r), bg + 3 * order[r], 3 * sizeof(double));
    }
    pair_count[s] = 4;
  }
cleanup:
  free(tets);
  free(centre);
  free(position);
  free(list);
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
  for (int64_t v = 0; v < n; ++v) fi.head[v] = -1;
  for (int32_t i = N - 1, a = N + shared - 1; i >= 0; --i) { // lists ascend by frame index
    const int64_t at[2] = {points->frame_organ_voxel[i], points->frame_voxel[i]};
    for (int k = 0; k < 2; ++k) {
      if (at[k] < 0) continue;
      fi.frame[a] = i;
      fi.next[a] = fi.head[at[k]];
      fi.head[at[k]] = a--;
    }
  }
  // TET regions: the tissues, then the deformable organs' insides
  for (int32_t label = 1; label <= scene->tissue_count + volume->organ_count; ++label) {
    const int32_t o = label > scene->tissue_count ? prep_label_organ(volume, (uint8_t)label) : -1;
    if (label > scene->tissue_count && o < 0) continue;
    int32_t kind;
    prep_label_sampling(scene, volume, (uint8_t)label, NULL, NULL, &kind, NULL);
    fascia_ctx_progress(ctx, "shape functions", 0, o >= 0 ? scene->organs[o].name : scene->tissues[label - 1].name);
    if (kind == FASCIA_PREP_SHAPE_TET)
      PREP_TRY_GOTO(tet_region(ctx, scene, &g, volume, points, (uint8_t)label, pair_frame, pair_w, pair_g, pair_count));
  }
  {
    int32_t failed = INT32_MAX, out_of_memory = 0;
    char message[1024] = "";
#pragma omp parallel num_threads(fascia_ctx_threads(ctx))
    {
      search se = {0};
      fascia_ctx_def def = fascia_ctx_def_default();
      def.threads = 1;
      se.dist = malloc((size_t)n * sizeof(double));
      if (se.dist)
        for (int64_t v = 0; v < n; ++v) se.dist[v] = INFINITY;
      const int ready = se.dist && fascia_ctx_create(&def, &se.ctx) == FASCIA_OK;
#pragma omp for schedule(dynamic, 16)
      for (int32_t s = 0; s < S; ++s) {
        int32_t kind, neighbours;
        prep_label_sampling(scene, volume, volume->region[points->sample_voxel[s]], NULL, NULL, &kind, &neighbours);
        if (kind != FASCIA_PREP_SHAPE_MLS) continue;
        if (!ready) {
#pragma omp atomic write
          out_of_memory = 1;
          continue;
        }
        const int64_t base = (int64_t)MAX_PAIRS * s;
        const int r = mls_sample(&se, &g, volume, points, &fi, s, neighbours, pair_frame + base, pair_w + base,
                                 pair_g + 3 * base, pair_count + s);
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
      free(se.dist);
      free(se.touched);
      prep_heap_free(&se.heap);
    }
    PREP_CHECK_GOTO(!out_of_memory, ctx, FASCIA_ERR_MEMORY, "shape functions: out of memory");
    char name[FASCIA_NAME_SIZE + 32] = "";
    if (failed != INT32_MAX) prep_label_name(scene, volume, volume->region[points->sample_voxel[failed]], name, sizeof name);
    PREP_CHECK_GOTO(failed == INT32_MAX, ctx, FASCIA_ERR_NUMERIC, "%s %s", name, message);
  }
  // compact into CSR and measure linear reproduction
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
    for (int r = 0; r < 3; ++r)
      W->max_linear_error =
          fmax(W->max_linear_error, fabs(reproduced[r] - points->sample_position[3 * (int64_t)s + r]));
  }
  fascia_ctx_progress(ctx, "shape functions", 1, "done");
  *out = W;
  W = NULL;
cleanup:
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
