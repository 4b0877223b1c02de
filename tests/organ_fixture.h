// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Two organs joined by a block of tissue, for the organ tests (t32x): organ A
// is the box x in [-a, 0], organ B the box x in [L, L + a] (y, z in
// [-w/2, w/2]); the tissue is the hexahedral beam [0, L] x [-w/2, w/2]^2
// between them, whose frames at x = 0 are A's coupling frames and those at
// x = L B's. Each organ is fixed, prescribed (motion 0 for A, 1 for B) or
// rigid. With `cut` the samples between x = L/3 and L are removed, so
// nothing joins B to A (frames left without samples become fixed).
#ifndef FASCIA_TESTS_ORGAN_FIXTURE_H
#define FASCIA_TESTS_ORGAN_FIXTURE_H

#include <stdlib.h>
#include <string.h>

#include "fascia/fascia.h"
#include "scenes.h"

#define FIX_L 0.06  // m, tissue length
#define FIX_W 0.03  // m, tissue and organ width
#define FIX_A 0.03  // m, organ length along x
#define FIX_NX 7    // frames along x (1 cm apart)

typedef struct organ_fixture_def {
  int kind_a, kind_b;   ///< fascia_organ_kind
  int cut;              ///< remove the tissue between x = L/3 and L
  double gravity[3];
  double pull_a[3];     ///< A's prescribed translation at t = 1 s (motion 0)
  double pull_b[3];     ///< B's prescribed translation at t = 1 s (motion 1)
} organ_fixture_def;

// A closed box [lo, hi], triangles outward.
static fascia_status fixture_box(fascia_ctx *ctx, fascia_organ *o, const double *lo, const double *hi) {
  static const int tris[36] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                               2, 3, 7, 2, 7, 6, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5};
  fascia_status st = fascia_organ_alloc(ctx, o, 8, 12);
  if (st != FASCIA_OK) return st;
  for (int v = 0; v < 8; ++v) {
    o->vertices[3 * v + 0] = (v & 1) ^ ((v >> 1) & 1) ? hi[0] : lo[0];
    o->vertices[3 * v + 1] = (v & 2) ? hi[1] : lo[1];
    o->vertices[3 * v + 2] = (v & 4) ? hi[2] : lo[2];
  }
  memcpy(o->triangles, tris, sizeof tris);
  return FASCIA_OK;
}

static fascia_status fixture_motion(fascia_ctx *ctx, fascia_motion *mo, const char *name, const double *pull) {
  strcpy(mo->name, name);
  fascia_status st = fascia_motion_alloc(ctx, mo, 2);
  if (st != FASCIA_OK) return st;
  mo->key_time[0] = 0, mo->key_time[1] = 1;
  for (int c = 0; c < 3; ++c) mo->key_translation[3 + c] = pull[c];
  mo->key_rotation[0] = mo->key_rotation[4] = 1;
  return FASCIA_OK;
}

static int fixture_frame_kind(int organ_kind) {
  return organ_kind == FASCIA_ORGAN_FIXED ? FASCIA_FRAME_FIXED
         : organ_kind == FASCIA_ORGAN_PRESCRIBED ? FASCIA_FRAME_PRESCRIBED
                                                 : FASCIA_FRAME_FREE;
}

static fascia_status organ_fixture_build(fascia_ctx *ctx, const organ_fixture_def *def, fascia_model **out) {
  *out = NULL;
  fascia_scene_beam_def bd = fascia_scene_beam_def_default();
  bd.length = FIX_L, bd.width = FIX_W, bd.height = FIX_W;
  bd.frames[0] = FIX_NX, bd.frames[1] = 3, bd.frames[2] = 3;
  bd.youngs_modulus = 5000, bd.poisson_ratio = 0.3, bd.density = 1050;
  fascia_model *src = NULL, *m = NULL;
  fascia_status st = fascia_scene_beam_build(ctx, &bd, &src);
  if (st != FASCIA_OK) return st;
  // samples kept: all, or those whose frames all lie left of L/3
  int32_t S = 0, P = 0, C = 0;
  unsigned char *keep = calloc((size_t)src->sample_count, 1);
  for (int32_t s = 0; s < src->sample_count; ++s) {
    keep[s] = 1;
    for (int32_t k = src->sample_offsets[s]; def->cut && k < src->sample_offsets[s + 1]; ++k)
      if (src->frame_position[3 * src->pair_frame[k]] > FIX_L / 3 + 1e-9) keep[s] = 0;
    if (keep[s]) ++S, P += src->sample_offsets[s + 1] - src->sample_offsets[s];
  }
  for (int32_t i = 0; i < src->frame_count; ++i) {
    const double x = src->frame_position[3 * i];
    C += fabs(x) < 1e-9 || fabs(x - FIX_L) < 1e-9;
  }
  fascia_model_sizes z = {src->frame_count, S, P, 1, 2, 0, 0, 2, C};
  st = fascia_model_alloc(ctx, &z, &m);
  if (st != FASCIA_OK) goto done;
  memcpy(m->frame_position, src->frame_position, 3 * sizeof(double) * src->frame_count);
  memcpy(m->materials, src->materials, sizeof(fascia_material));
  for (int32_t s = 0, t = 0, p = 0; s < src->sample_count; ++s) {
    if (!keep[s]) continue;
    memcpy(m->sample_position + 3 * t, src->sample_position + 3 * s, 3 * sizeof(double));
    m->sample_volume[t] = src->sample_volume[s];
    m->sample_material[t] = 0;
    m->sample_offsets[t] = p;
    for (int32_t k = src->sample_offsets[s]; k < src->sample_offsets[s + 1]; ++k, ++p) {
      m->pair_frame[p] = src->pair_frame[k];
      m->pair_weight[p] = src->pair_weight[k];
      memcpy(m->pair_gradient + 3 * p, src->pair_gradient + 3 * k, 3 * sizeof(double));
    }
    m->sample_offsets[++t] = p;
  }
  for (int c = 0; c < 3; ++c) m->gravity[c] = def->gravity[c];
  if ((st = fixture_motion(ctx, m->motions + 0, "pull-a", def->pull_a)) != FASCIA_OK) goto done;
  if ((st = fixture_motion(ctx, m->motions + 1, "pull-b", def->pull_b)) != FASCIA_OK) goto done;
  const double lo_a[3] = {-FIX_A, -FIX_W / 2, -FIX_W / 2}, hi_a[3] = {0, FIX_W / 2, FIX_W / 2};
  const double lo_b[3] = {FIX_L, -FIX_W / 2, -FIX_W / 2}, hi_b[3] = {FIX_L + FIX_A, FIX_W / 2, FIX_W / 2};
  strcpy(m->organs[0].name, "a");
  strcpy(m->organs[1].name, "b");
  m->organs[0].kind = def->kind_a, m->organs[1].kind = def->kind_b;
  m->organs[0].motion = def->kind_a == FASCIA_ORGAN_PRESCRIBED ? 0 : -1;
  m->organs[1].motion = def->kind_b == FASCIA_ORGAN_PRESCRIBED ? 1 : -1;
  if ((st = fixture_box(ctx, m->organs + 0, lo_a, hi_a)) != FASCIA_OK) goto done;
  if ((st = fixture_box(ctx, m->organs + 1, lo_b, hi_b)) != FASCIA_OK) goto done;
  C = 0;
  for (int32_t i = 0; i < m->frame_count; ++i) {
    const double x = m->frame_position[3 * i];
    const int organ = fabs(x) < 1e-9 ? 0 : fabs(x - FIX_L) < 1e-9 ? 1 : -1;
    m->frame_kind[i] = FASCIA_FRAME_FREE;
    m->frame_motion[i] = -1;
    if (organ < 0) continue;
    const int kind = organ == 0 ? def->kind_a : def->kind_b;
    m->frame_kind[i] = fixture_frame_kind(kind);
    if (kind == FASCIA_ORGAN_PRESCRIBED) m->frame_motion[i] = organ;
    m->coupling_organ[C] = organ, m->coupling_frame[C] = i, m->coupling_triangle[C] = organ == 0 ? 2 : 4;
    m->coupling_barycentric[3 * C] = 1;
    ++C;
  }
  st = fascia_model_build_reverse(ctx, m);
  if (st != FASCIA_OK) goto done;
  for (int32_t i = 0; i < m->frame_count; ++i) // frames left without tissue (cut) and not on an organ
    if (m->frame_offsets[i + 1] == m->frame_offsets[i] && m->frame_kind[i] == FASCIA_FRAME_FREE &&
        fabs(m->frame_position[3 * i] - FIX_L) > 1e-9)
      m->frame_kind[i] = FASCIA_FRAME_FIXED;
  st = fascia_model_validate(ctx, m, "organ fixture");
done:
  free(keep);
  fascia_model_destroy(&src);
  if (st != FASCIA_OK) fascia_model_destroy(&m);
  *out = m;
  return st;
}

/// Gives the model a tissue surface: the box of its samples' positions,
/// outward, 2 triangles a face.
static inline fascia_status organ_fixture_add_surface(fascia_ctx *ctx, fascia_model *m) {
  double lo[3] = {1e30, 1e30, 1e30}, hi[3] = {-1e30, -1e30, -1e30};
  for (int32_t s = 0; s < m->sample_count; ++s)
    for (int r = 0; r < 3; ++r)
      lo[r] = fmin(lo[r], m->sample_position[3 * s + r]), hi[r] = fmax(hi[r], m->sample_position[3 * s + r]);
  fascia_organ box;
  memset(&box, 0, sizeof box);
  fascia_status st = fixture_box(ctx, &box, lo, hi);
  if (st == FASCIA_OK) st = fascia_surface_alloc(ctx, &m->tissue_surface, box.vertex_count, box.triangle_count);
  if (st == FASCIA_OK) {
    memcpy(m->tissue_surface.vertices, box.vertices, 3 * sizeof(double) * (size_t)box.vertex_count);
    memcpy(m->tissue_surface.triangles, box.triangles, 3 * sizeof(int32_t) * (size_t)box.triangle_count);
  }
  free(box.vertices), free(box.triangles);
  return st;
}

static organ_fixture_def organ_fixture_def_default(void) {
  organ_fixture_def d;
  memset(&d, 0, sizeof d);
  d.kind_a = FASCIA_ORGAN_FIXED, d.kind_b = FASCIA_ORGAN_RIGID;
  return d;
}

#endif
