// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// An organ's surface where the simulation has put it (fascia/organs.h,
// fascia_solver_organ_surface): what the results' organ files draw.
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/organs.h"
#include "fascia/shape.h"
#include "organs/organs.h"
#include "point/frame.h"
#include "solve/solver_internal.h"

#define SKIN_NEIGHBOURS 8 // frames carrying each vertex of a deformable organ

// p = R p_rest + t for every vertex
static void place_rigidly(const fascia_organ *o, const fascia_real *R, const fascia_real *t, fascia_real *out) {
  for (int32_t v = 0; v < o->vertex_count; ++v) {
    fascia_pt_mat_vec(R, o->vertices + 3 * (int64_t)v, out + 3 * (int64_t)v);
    for (int c = 0; c < 3; ++c) out[3 * (int64_t)v + c] += t[c];
  }
}

// The frames that carry a deformable organ: its own and its coupling frames.
// frames: [N] work space, the list on return (ascending).
static int32_t organ_frames(const fascia_model *m, int32_t organ, int32_t *frames) {
  for (int32_t i = 0; i < m->frame_count; ++i) frames[i] = m->frame_organ[i] == organ;
  for (int32_t c = 0; c < m->coupling_count; ++c)
    if (m->coupling_organ[c] == organ) frames[m->coupling_frame[c]] = 1;
  int32_t n = 0;
  for (int32_t i = 0; i < m->frame_count; ++i)
    if (frames[i]) frames[n++] = i;
  return n;
}

// Each vertex as a sample would move: sum_i w_i (x_i + A_i (p_rest - x_rest_i)),
// w the normalized kernel weights of its nearest frames at rest, among the n
// frames listed in frames (what names the surface in messages).
static fascia_status skin(const fascia_solver *S, const char *what, const int32_t *frames, int32_t n,
                          const fascia_real *vertices, int32_t vertex_count, fascia_real *out) {
  const fascia_model *m = S->model;
  fascia_real *rest = malloc(3 * ((size_t)n + 1) * sizeof *rest);
  fascia_frame_grid *grid = NULL;
  fascia_status st = rest ? FASCIA_OK : FASCIA_FAIL(S->ctx, FASCIA_ERR_MEMORY, "%s: out of memory", what);
  if (st == FASCIA_OK && n == 0) st = FASCIA_FAIL(S->ctx, FASCIA_ERR_FORMAT, "%s: no frame carries it", what);
  for (int32_t j = 0; st == FASCIA_OK && j < n; ++j)
    memcpy(rest + 3 * j, m->frame_position + 3 * (int64_t)frames[j], 3 * sizeof *rest);
  if (st == FASCIA_OK) st = fascia_frame_grid_create(S->ctx, n, rest, &grid);
  const int32_t k = n < SKIN_NEIGHBOURS ? n : SKIN_NEIGHBOURS;
  for (int32_t v = 0; st == FASCIA_OK && v < vertex_count; ++v) {
    const fascia_real *p = vertices + 3 * (int64_t)v;
    int32_t near[SKIN_NEIGHBOURS];
    fascia_real radius = 0, w[SKIN_NEIGHBOURS], sum = 0;
    st = fascia_frame_grid_nearest(S->ctx, grid, p, k, near, &radius);
    for (int32_t j = 0; st == FASCIA_OK && j < k; ++j) {
      const fascia_real *x = rest + 3 * near[j];
      const fascia_real d[3] = {p[0] - x[0], p[1] - x[1], p[2] - x[2]};
      w[j] = fascia_shape_kernel(sqrt(fascia_pt_dot3(d, d)) / radius);
      sum += w[j];
    }
    fascia_real *q = out + 3 * (int64_t)v;
    q[0] = q[1] = q[2] = 0;
    for (int32_t j = 0; st == FASCIA_OK && j < k; ++j) {
      const int32_t f = frames[near[j]];
      fascia_real A[9], d[3], a[3];
      fascia_pt_frame_A(S->q + 4 * (int64_t)f, m->frame_rotation + 4 * (int64_t)f, A);
      for (int c = 0; c < 3; ++c) d[c] = p[c] - m->frame_position[3 * (int64_t)f + c];
      fascia_pt_mat_vec(A, d, a);
      for (int c = 0; c < 3; ++c) q[c] += w[j] / sum * (S->x[3 * (int64_t)f + c] + a[c]);
    }
  }
  fascia_frame_grid_destroy(&grid);
  free(rest);
  return st;
}

// A deformable organ carried by its own and its coupling frames.
static fascia_status skin_organ(const fascia_solver *S, int32_t organ, fascia_real *out) {
  const fascia_model *m = S->model;
  const fascia_organ *o = m->organs + organ;
  int32_t *frames = malloc(((size_t)m->frame_count + 1) * sizeof *frames);
  FASCIA_CHECK(frames, S->ctx, FASCIA_ERR_MEMORY, "organ surface: out of memory");
  char what[FASCIA_NAME_SIZE + 32];
  snprintf(what, sizeof what, "deformable organ '%s'", o->name);
  const fascia_status st = skin(S, what, frames, organ_frames(m, organ, frames), o->vertices, o->vertex_count, out);
  free(frames);
  return st;
}

// A driven organ follows its first coupling frame: R = R_f R_f,rest^T
// (exact when the caller moves the organ rigidly).
static fascia_status follow_first_frame(const fascia_solver *S, int32_t organ, fascia_real *out) {
  const fascia_model *m = S->model;
  int32_t f = -1;
  for (int32_t c = 0; c < m->coupling_count && f < 0; ++c)
    if (m->coupling_organ[c] == organ) f = m->coupling_frame[c];
  FASCIA_CHECK(f >= 0, S->ctx, FASCIA_ERR_FORMAT, "organ '%s' is driven but has no coupling frame",
               m->organs[organ].name);
  fascia_real R[9], p[3], t[3];
  fascia_pt_frame_A(S->q + 4 * (int64_t)f, m->frame_rotation + 4 * (int64_t)f, R);
  fascia_pt_mat_vec(R, m->frame_position + 3 * (int64_t)f, p);
  for (int c = 0; c < 3; ++c) t[c] = S->x[3 * (int64_t)f + c] - p[c];
  place_rigidly(m->organs + organ, R, t, out);
  return FASCIA_OK;
}

fascia_status fascia_solver_organ_surface(const fascia_solver *S, int32_t organ, fascia_real *positions) {
  FASCIA_CHECK(S && positions, S ? S->ctx : NULL, FASCIA_ERR_ARGUMENT, "organ surface: NULL argument");
  FASCIA_CHECK(organ >= 0 && organ < S->model->organ_count, S->ctx, FASCIA_ERR_ARGUMENT,
               "organ surface: organ %d does not exist (the model has %d organs)", (int)organ,
               (int)S->model->organ_count);
  const fascia_organ *o = S->model->organs + organ;
  if (o->kind == FASCIA_ORGAN_DEFORMABLE) return skin_organ(S, organ, positions);
  if (fascia_organs_driven(S->organs, organ)) return follow_first_frame(S, organ, positions);
  fascia_real t[3], q[4], R[9];
  FASCIA_TRY(fascia_solver_organ_pose(S, organ, t, q));
  fascia_pt_quat_to_mat(q, R);
  place_rigidly(o, R, t, positions);
  return FASCIA_OK;
}

fascia_status fascia_solver_tissue_surface(const fascia_solver *S, fascia_real *positions, fascia_real *strain) {
  FASCIA_CHECK(S && positions, S ? S->ctx : NULL, FASCIA_ERR_ARGUMENT, "tissue surface: NULL argument");
  const fascia_model *m = S->model;
  const fascia_surface *ts = &m->tissue_surface;
  if (ts->vertex_count == 0) return FASCIA_OK;
  const size_t most = (size_t)(m->frame_count > m->sample_count ? m->frame_count : m->sample_count) + 1;
  int32_t *list = malloc(most * sizeof *list);
  fascia_real *rest = malloc(3 * most * sizeof *rest), *sample_strain = malloc(most * sizeof *sample_strain);
  fascia_frame_grid *grid = NULL;
  fascia_status st = list && rest && sample_strain
                         ? FASCIA_OK
                         : FASCIA_FAIL(S->ctx, FASCIA_ERR_MEMORY, "tissue surface: out of memory");
  int32_t n = 0;
  for (int32_t i = 0; st == FASCIA_OK && i < m->frame_count; ++i)
    if (m->frame_organ[i] < 0) list[n++] = i;
  if (st == FASCIA_OK) st = skin(S, "the tissue surface", list, n, ts->vertices, ts->vertex_count, positions);
  if (st == FASCIA_OK && strain) { // each vertex shows the strain of the tissue sample nearest it at rest
    n = 0;
    for (int32_t s = 0; s < m->sample_count; ++s)
      if (m->sample_organ[s] < 0) list[n] = s, memcpy(rest + 3 * n++, m->sample_position + 3 * (int64_t)s, 3 * sizeof *rest);
    fascia_solver_sample_strain(S, sample_strain, NULL);
    st = n > 0 ? fascia_frame_grid_create(S->ctx, n, rest, &grid)
               : FASCIA_FAIL(S->ctx, FASCIA_ERR_FORMAT, "tissue surface: the model has no tissue sample");
    for (int32_t v = 0; st == FASCIA_OK && v < ts->vertex_count; ++v) {
      int32_t nearest;
      fascia_real radius;
      st = fascia_frame_grid_nearest(S->ctx, grid, ts->vertices + 3 * (int64_t)v, 1, &nearest, &radius);
      if (st == FASCIA_OK) strain[v] = sample_strain[list[nearest]];
    }
  }
  fascia_frame_grid_destroy(&grid);
  free(list), free(rest), free(sample_strain);
  return st;
}
