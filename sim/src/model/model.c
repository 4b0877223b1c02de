// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The model structure: allocation, the reverse (frame -> samples) table, and
// validation, the one gate every model passes before a solver sees it.
#define _POSIX_C_SOURCE 200809L // strnlen (strict C11 hides it)
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/model.h"
#include "util/fnv.h"
#include "model/model_arrays.h"
#include "util/status.h"

// Tolerances of the validation: weights are computed in double from rest
// geometry, so a partition of unity holds to ~1e-12; 1e-9 leaves room for
// files written by other tools in double.
#define WEIGHT_SUM_TOLERANCE 1e-9
#define QUAT_NORM_TOLERANCE 1e-9

// What a row of each count is, in messages.
#define ROW_frames "frame"
#define ROW_samples "sample"
#define ROW_pairs "pair"
#define ROW_materials "material"
#define ROW_motions "motion"
#define ROW_probes "probe"
#define ROW_probe_pairs "probe-frame pair"
#define ROW_organs "organ"
#define ROW_couplings "coupling entry"

const fascia_model_array fascia_model_arrays[FASCIA_MA_COUNT] = {
#define ROW(field, kind, count, plus, width, path, unit, fill, flags, since, device)                                  \
  {#field, FASCIA_MA_##kind, ROW_##count, plus, width, path, unit, fill, flags, since},
    FASCIA_MODEL_ARRAYS(ROW)
#undef ROW
};

fascia_model_sizes fascia_model_shape(const fascia_model *m) {
  return (fascia_model_sizes){m->frame_count,      m->sample_count,     m->pair_count,
                              m->material_count,   m->motion_count,     m->probe_count,
                              m->probe_pair_count, m->organ_count,      m->coupling_count};
}

void fascia_model_views(const fascia_model *m, fascia_model_view views[FASCIA_MA_COUNT]) {
  const fascia_model_sizes z = fascia_model_shape(m);
#define VIEW(field, kind, count, plus, ...)                                                                           \
  views[FASCIA_MA_ID_##field] =                                                                                      \
      (fascia_model_view){fascia_model_arrays + FASCIA_MA_ID_##field, (void *)m->field, (int64_t)z.count + (plus)};
  FASCIA_MODEL_ARRAYS(VIEW)
#undef VIEW
}

size_t fascia_model_array_size(fascia_ma_kind kind) {
  switch (kind) {
  case FASCIA_MA_REAL: return sizeof(fascia_real);
  case FASCIA_MA_INT: return sizeof(int32_t);
  case FASCIA_MA_NAME: return FASCIA_NAME_SIZE;
  case FASCIA_MA_MATERIAL: return sizeof(fascia_material);
  case FASCIA_MA_MOTION: return sizeof(fascia_motion);
  case FASCIA_MA_ORGAN: return sizeof(fascia_organ);
  }
  return 0;
}

size_t fascia_model_view_bytes(const fascia_model_view *v) {
  return (size_t)v->rows * (size_t)v->array->width * fascia_model_array_size(v->array->kind);
}

// The fill of value e of a row's array: `fill` first in each row, 0 after.
static int32_t fill_value(const fascia_model_array *a, int64_t e) { return e % a->width ? 0 : a->fill; }

static void fill(const fascia_model_view *v) {
  const fascia_model_array *a = v->array;
  const int64_t n = v->rows * a->width;
  for (int64_t e = 0; a->fill && e < n; ++e)
    if (a->kind == FASCIA_MA_INT) ((int32_t *)v->data)[e] = fill_value(a, e);
    else if (a->kind == FASCIA_MA_REAL) ((fascia_real *)v->data)[e] = fill_value(a, e);
}

int fascia_model_view_set(const fascia_model_view *v) {
  const fascia_model_array *a = v->array;
  if (!(a->flags & FASCIA_MA_SPARSE)) return 1;
  const int64_t n = v->rows * a->width;
  for (int64_t e = 0; e < n; ++e)
    if (a->kind == FASCIA_MA_INT ? ((const int32_t *)v->data)[e] != fill_value(a, e)
                                 : ((const fascia_real *)v->data)[e] != fill_value(a, e))
      return 1;
  return 0;
}

fascia_status fascia_model_alloc(fascia_ctx *ctx, const fascia_model_sizes *z, fascia_model **out) {
  FASCIA_CHECK(out && z, ctx, FASCIA_ERR_ARGUMENT, "fascia_model_alloc: NULL argument");
  *out = NULL;
  const int32_t counts[] = {z->frames, z->samples, z->pairs, z->materials, z->motions,
                            z->probes, z->probe_pairs, z->organs, z->couplings};
  for (size_t k = 0; k < sizeof counts / sizeof counts[0]; ++k)
    FASCIA_CHECK(counts[k] >= 0 && counts[k] <= FASCIA_MAX_COUNT, ctx, FASCIA_ERR_MEMORY,
                 "model: size %d is out of range (0 .. %lld)", (int)counts[k], (long long)FASCIA_MAX_COUNT);
  FASCIA_CHECK(z->pairs <= (int64_t)z->samples * 1024, ctx, FASCIA_ERR_ARGUMENT,
               "model: %d pairs for %d samples is more than 1024 neighbours per sample", (int)z->pairs,
               (int)z->samples);
  fascia_model *m = calloc(1, sizeof *m);
  FASCIA_CHECK(m, ctx, FASCIA_ERR_MEMORY, "model: out of memory");
  m->frame_count = z->frames;
  m->sample_count = z->samples;
  m->pair_count = z->pairs;
  m->material_count = z->materials;
  m->motion_count = z->motions;
  m->probe_count = z->probes;
  m->probe_pair_count = z->probe_pairs;
  m->organ_count = z->organs;
  m->coupling_count = z->couplings;
  fascia_model_view views[FASCIA_MA_COUNT];
#define ALLOC(field, kind, count, plus, width, ...)                                                                  \
  m->field = fascia_calloc(((int64_t)z->count + (plus)) * (width), fascia_model_array_size(FASCIA_MA_##kind));
  FASCIA_MODEL_ARRAYS(ALLOC)
#undef ALLOC
  fascia_model_views(m, views);
  for (int k = 0; k < FASCIA_MA_COUNT; ++k)
    if (!views[k].data) {
      fascia_model_destroy(&m);
      return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "model: out of memory for %lld frames, %lld samples, %lld pairs",
                         (long long)z->frames, (long long)z->samples, (long long)z->pairs);
    }
  for (int k = 0; k < FASCIA_MA_COUNT; ++k) fill(views + k);
  for (int32_t k = 0; k < z->organs; ++k) m->organs[k].motion = -1;
  *out = m;
  return FASCIA_OK;
}

void fascia_model_destroy(fascia_model **model) {
  if (!model || !*model) return;
  fascia_model *m = *model;
  for (int32_t k = 0; m->motions && k < m->motion_count; ++k) {
    free(m->motions[k].key_time);
    free(m->motions[k].key_translation);
    free(m->motions[k].key_rotation);
  }
  for (int32_t k = 0; m->organs && k < m->organ_count; ++k) {
    free(m->organs[k].vertices);
    free(m->organs[k].triangles);
  }
#define FREE(field, ...) free(m->field);
  FASCIA_MODEL_ARRAYS(FREE)
#undef FREE
  free(m->tissue_surface.vertices);
  free(m->tissue_surface.triangles);
  free(m->tetrahedra);
  free(m->provenance);
  free(m);
  *model = NULL;
}

fascia_status fascia_motion_alloc(fascia_ctx *ctx, fascia_motion *motion, int32_t key_count) {
  FASCIA_CHECK(motion && key_count >= 1 && key_count <= FASCIA_MAX_COUNT, ctx, FASCIA_ERR_ARGUMENT,
               "motion: key count %d must be at least 1", (int)key_count);
  free(motion->key_time);
  free(motion->key_translation);
  free(motion->key_rotation);
  motion->key_count = key_count;
  motion->key_time = fascia_calloc(key_count, sizeof(fascia_real));
  motion->key_translation = fascia_calloc(3 * (int64_t)key_count, sizeof(fascia_real));
  motion->key_rotation = fascia_calloc(4 * (int64_t)key_count, sizeof(fascia_real));
  FASCIA_CHECK(motion->key_time && motion->key_translation && motion->key_rotation, ctx, FASCIA_ERR_MEMORY,
               "motion '%s': out of memory for %d keys", motion->name, (int)key_count);
  for (int32_t k = 0; k < key_count; ++k) motion->key_rotation[4 * k] = 1;
  return FASCIA_OK;
}

// (Re)allocates a triangle mesh of V vertices and T triangles, zeroed; `what`
// names it in messages.
static fascia_status alloc_mesh(fascia_ctx *ctx, const char *what, fascia_surface *mesh, int32_t V, int32_t T) {
  FASCIA_CHECK(V >= 0 && T >= 0 && V <= FASCIA_MAX_COUNT && T <= FASCIA_MAX_COUNT, ctx, FASCIA_ERR_ARGUMENT,
               "%s: bad size (%d vertices, %d triangles)", what, (int)V, (int)T);
  free(mesh->vertices);
  free(mesh->triangles);
  mesh->vertex_count = V;
  mesh->triangle_count = T;
  mesh->vertices = fascia_calloc(3 * (int64_t)V, sizeof(fascia_real));
  mesh->triangles = fascia_calloc(3 * (int64_t)T, sizeof(int32_t));
  FASCIA_CHECK(mesh->vertices && mesh->triangles, ctx, FASCIA_ERR_MEMORY, "%s: out of memory", what);
  return FASCIA_OK;
}

fascia_status fascia_surface_alloc(fascia_ctx *ctx, fascia_surface *surface, int32_t vertex_count,
                                   int32_t triangle_count) {
  FASCIA_CHECK(surface, ctx, FASCIA_ERR_ARGUMENT, "fascia_surface_alloc: NULL surface");
  return alloc_mesh(ctx, "tissue surface", surface, vertex_count, triangle_count);
}

fascia_status fascia_model_tetrahedra_alloc(fascia_ctx *ctx, fascia_model *m, int32_t count) {
  FASCIA_CHECK(m && count >= 0 && count <= FASCIA_MAX_COUNT, ctx, FASCIA_ERR_ARGUMENT,
               "model: bad tetrahedron count %d", (int)count);
  free(m->tetrahedra);
  m->tetrahedron_count = count;
  m->tetrahedra = fascia_calloc(4 * (int64_t)count, sizeof(int32_t));
  FASCIA_CHECK(m->tetrahedra, ctx, FASCIA_ERR_MEMORY, "model: out of memory for %d tetrahedra", (int)count);
  return FASCIA_OK;
}

fascia_status fascia_organ_alloc(fascia_ctx *ctx, fascia_organ *organ, int32_t vertex_count, int32_t triangle_count) {
  FASCIA_CHECK(organ, ctx, FASCIA_ERR_ARGUMENT, "fascia_organ_alloc: NULL organ");
  char what[FASCIA_NAME_SIZE + 32];
  snprintf(what, sizeof what, "organ '%.*s' surface", FASCIA_NAME_SIZE - 1, organ->name);
  fascia_surface mesh = {organ->vertex_count, organ->triangle_count, organ->vertices, organ->triangles};
  const fascia_status status = alloc_mesh(ctx, what, &mesh, vertex_count, triangle_count);
  organ->vertex_count = mesh.vertex_count;
  organ->triangle_count = mesh.triangle_count;
  organ->vertices = mesh.vertices;
  organ->triangles = mesh.triangles;
  return status;
}

fascia_status fascia_model_set_provenance(fascia_ctx *ctx, fascia_model *model, const char *text) {
  FASCIA_CHECK(model, ctx, FASCIA_ERR_ARGUMENT, "fascia_model_set_provenance: NULL model");
  char *copy = NULL;
  if (text) {
    copy = malloc(strlen(text) + 1);
    FASCIA_CHECK(copy, ctx, FASCIA_ERR_MEMORY, "model: out of memory for provenance");
    strcpy(copy, text);
  }
  free(model->provenance);
  model->provenance = copy;
  return FASCIA_OK;
}

fascia_status fascia_model_build_reverse(fascia_ctx *ctx, fascia_model *m) {
  FASCIA_CHECK(m, ctx, FASCIA_ERR_ARGUMENT, "fascia_model_build_reverse: NULL model");
  const int32_t N = m->frame_count, P = m->pair_count;
  FASCIA_CHECK(m->sample_offsets[m->sample_count] == P, ctx, FASCIA_ERR_ARGUMENT,
               "model: sample_offsets ends at %d, expected the pair count %d", (int)m->sample_offsets[m->sample_count],
               (int)P);
  for (int32_t i = 0; i <= N; ++i) m->frame_offsets[i] = 0;
  for (int32_t k = 0; k < P; ++k) {
    const int32_t i = m->pair_frame[k];
    FASCIA_CHECK(i >= 0 && i < N, ctx, FASCIA_ERR_ARGUMENT, "model: pair %d names frame %d of %d", (int)k, (int)i,
                 (int)N);
    m->frame_offsets[i + 1]++;
  }
  for (int32_t i = 0; i < N; ++i) m->frame_offsets[i + 1] += m->frame_offsets[i];
  int32_t *fill = fascia_calloc(N, sizeof(int32_t));
  FASCIA_CHECK(fill, ctx, FASCIA_ERR_MEMORY, "model: out of memory for the reverse table");
  // pairs are visited in ascending order, so each frame's list is ascending
  for (int32_t k = 0; k < P; ++k) {
    const int32_t i = m->pair_frame[k];
    m->frame_pairs[m->frame_offsets[i] + fill[i]++] = k;
  }
  free(fill);
  return FASCIA_OK;
}

static int finite_all(const fascia_real *x, int64_t n, int64_t *bad) {
  for (int64_t k = 0; k < n; ++k)
    if (!isfinite(x[k])) {
      *bad = k;
      return 0;
    }
  return 1;
}

// CSR check: offsets[0] == 0, monotone, offsets[rows] == total.
static fascia_status check_csr(fascia_ctx *ctx, const char *origin, const char *name, const int32_t *offsets,
                               int32_t rows, int32_t total) {
  FASCIA_CHECK(offsets[0] == 0, ctx, FASCIA_ERR_FORMAT, "model '%s' %s: first offset is %d, expected 0", origin, name,
               (int)offsets[0]);
  for (int32_t r = 0; r < rows; ++r)
    FASCIA_CHECK(offsets[r + 1] >= offsets[r], ctx, FASCIA_ERR_FORMAT,
                 "model '%s' %s: offsets decrease at row %d (%d then %d)", origin, name, (int)r, (int)offsets[r],
                 (int)offsets[r + 1]);
  FASCIA_CHECK(offsets[rows] == total, ctx, FASCIA_ERR_FORMAT, "model '%s' %s: last offset is %d, expected %d", origin,
               name, (int)offsets[rows], (int)total);
  return FASCIA_OK;
}

// Every real array of the table: finite numbers only.
static fascia_status validate_finite(fascia_ctx *ctx, const fascia_model *m, const char *origin) {
  fascia_model_view views[FASCIA_MA_COUNT];
  fascia_model_views(m, views);
  for (int k = 0; k < FASCIA_MA_COUNT; ++k) {
    const fascia_model_array *a = views[k].array;
    const fascia_real *x = views[k].data;
    int64_t bad;
    if (a->kind == FASCIA_MA_REAL && !finite_all(x, views[k].rows * a->width, &bad))
      return FASCIA_FAIL(ctx, FASCIA_ERR_FORMAT, "model '%s' %s: %s %lld has a value that is not finite (%g)", origin,
                         a->path, a->row, (long long)(bad / a->width), x[bad]);
  }
  return FASCIA_OK;
}

static fascia_status validate_frames(fascia_ctx *ctx, const fascia_model *m, const char *origin) {
  const int32_t N = m->frame_count;
  for (int32_t i = 0; i < N; ++i) {
    const fascia_real *q = m->frame_rotation + 4 * i;
    const double norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    FASCIA_CHECK(fabs(norm - 1) < QUAT_NORM_TOLERANCE, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /frames/rotation: frame %d quaternion has norm %.12g, expected 1", origin, (int)i, norm);
    const int32_t kind = m->frame_kind[i];
    FASCIA_CHECK(kind >= 0 && kind < FASCIA_FRAME_KIND_COUNT_, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /frames/kind: frame %d has kind %d, expected 0 (free), 1 (fixed) or 2 (prescribed)",
                 origin, (int)i, (int)kind);
    FASCIA_CHECK(m->frame_organ[i] >= -1 && m->frame_organ[i] < m->organ_count, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /frames/organ: frame %d names organ %d, but the model has %d (-1: tissue)", origin,
                 (int)i, (int)m->frame_organ[i], (int)m->organ_count);
    const int32_t motion = m->frame_motion[i];
    if (kind == FASCIA_FRAME_PRESCRIBED)
      FASCIA_CHECK(motion >= 0 && motion < m->motion_count, ctx, FASCIA_ERR_FORMAT,
                   "model '%s' /frames/motion: prescribed frame %d names motion %d, but the model has %d", origin,
                   (int)i, (int)motion, (int)m->motion_count);
    else
      FASCIA_CHECK(motion == -1, ctx, FASCIA_ERR_FORMAT,
                   "model '%s' /frames/motion: frame %d is not prescribed but names motion %d (expected -1)", origin,
                   (int)i, (int)motion);
  }
  return FASCIA_OK;
}

static fascia_status validate_samples(fascia_ctx *ctx, const fascia_model *m, const char *origin) {
  const int32_t S = m->sample_count, N = m->frame_count;
  for (int32_t s = 0; s < S; ++s) {
    FASCIA_CHECK(isfinite(m->sample_volume[s]) && m->sample_volume[s] > 0, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /samples/volume: sample %d has volume %g, expected a positive number", origin, (int)s,
                 m->sample_volume[s]);
    FASCIA_CHECK(m->sample_organ[s] >= -1 && m->sample_organ[s] < m->organ_count, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /samples/organ: sample %d names organ %d, but the model has %d (-1: tissue)", origin,
                 (int)s, (int)m->sample_organ[s], (int)m->organ_count);
    FASCIA_CHECK(m->sample_material[s] >= 0 && m->sample_material[s] < m->material_count, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /samples/material: sample %d names material %d, but the model has %d", origin, (int)s,
                 (int)m->sample_material[s], (int)m->material_count);
  }
  FASCIA_TRY(check_csr(ctx, origin, "/samples/offsets", m->sample_offsets, S, m->pair_count));
  for (int32_t s = 0; s < S; ++s) {
    const int32_t begin = m->sample_offsets[s], end = m->sample_offsets[s + 1];
    FASCIA_CHECK(end > begin, ctx, FASCIA_ERR_FORMAT, "model '%s' /samples/offsets: sample %d has no neighbour frame",
                 origin, (int)s);
    double sum = 0, grad[3] = {0, 0, 0}, scale = 0;
    for (int32_t k = begin; k < end; ++k) {
      const int32_t i = m->pair_frame[k];
      FASCIA_CHECK(i >= 0 && i < N, ctx, FASCIA_ERR_FORMAT,
                   "model '%s' /pairs/frame: pair %d of sample %d names frame %d, but the model has %d frames", origin,
                   (int)k, (int)s, (int)i, (int)N);
      FASCIA_CHECK(k == begin || m->pair_frame[k - 1] < i, ctx, FASCIA_ERR_FORMAT,
                   "model '%s' /pairs/frame: frames of sample %d are not strictly ascending at pair %d", origin, (int)s,
                   (int)k);
      sum += m->pair_weight[k];
      for (int r = 0; r < 3; ++r) {
        grad[r] += m->pair_gradient[3 * k + r];
        scale += fabs(m->pair_gradient[3 * k + r]);
      }
    }
    FASCIA_CHECK(fabs(sum - 1) < WEIGHT_SUM_TOLERANCE, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /pairs/weight: weights of sample %d sum to %.12g, expected 1 (partition of unity)",
                 origin, (int)s, sum);
    for (int r = 0; r < 3; ++r)
      FASCIA_CHECK(fabs(grad[r]) <= WEIGHT_SUM_TOLERANCE * (1 + scale), ctx, FASCIA_ERR_FORMAT,
                   "model '%s' /pairs/gradient: gradients of sample %d sum to %.3g in component %d, expected 0",
                   origin, (int)s, grad[r], r);
  }
  return FASCIA_OK;
}

static fascia_status validate_reverse(fascia_ctx *ctx, const fascia_model *m, const char *origin) {
  FASCIA_TRY(check_csr(ctx, origin, "/frames/offsets", m->frame_offsets, m->frame_count, m->pair_count));
  for (int32_t i = 0; i < m->frame_count; ++i)
    for (int32_t r = m->frame_offsets[i]; r < m->frame_offsets[i + 1]; ++r) {
      const int32_t k = m->frame_pairs[r];
      FASCIA_CHECK(k >= 0 && k < m->pair_count && m->pair_frame[k] == i, ctx, FASCIA_ERR_FORMAT,
                   "model '%s' /frames/pairs: entry %d of frame %d is pair %d, which does not belong to that frame",
                   origin, (int)r, (int)i, (int)k);
      FASCIA_CHECK(r == m->frame_offsets[i] || m->frame_pairs[r - 1] < k, ctx, FASCIA_ERR_FORMAT,
                   "model '%s' /frames/pairs: pairs of frame %d are not strictly ascending", origin, (int)i);
    }
  return FASCIA_OK;
}

static fascia_status validate_materials(fascia_ctx *ctx, const fascia_model *m, const char *origin) {
  FASCIA_CHECK(m->material_count >= 1 || m->sample_count == 0, ctx, FASCIA_ERR_FORMAT,
               "model '%s' /materials: no material, but %d samples", origin, (int)m->sample_count);
  for (int32_t k = 0; k < m->material_count; ++k) {
    const fascia_material *mat = m->materials + k;
    FASCIA_CHECK(mat->law >= 0 && mat->law < FASCIA_LAW_COUNT_, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /materials: material %d ('%s') has law %d, expected 0 (stvk) or 1 (neohookean)", origin,
                 (int)k, mat->name, (int)mat->law);
    FASCIA_CHECK(isfinite(mat->youngs_modulus) && mat->youngs_modulus > 0 && mat->youngs_modulus <= FASCIA_MAX_MODULUS,
                 ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /materials: material %d ('%s') has Young's modulus %g Pa, expected (0, %g] (stiffer than "
                 "any solid; check the units: Pa)", origin, (int)k, mat->name, mat->youngs_modulus, FASCIA_MAX_MODULUS);
    FASCIA_CHECK(isfinite(mat->poisson_ratio) && mat->poisson_ratio >= 0 && mat->poisson_ratio < 0.5, ctx,
                 FASCIA_ERR_FORMAT, "model '%s' /materials: material %d ('%s') has Poisson ratio %g, expected [0, 0.5)",
                 origin, (int)k, mat->name, mat->poisson_ratio);
    FASCIA_CHECK(isfinite(mat->density) && mat->density > 0 && mat->density <= FASCIA_MAX_DENSITY, ctx,
                 FASCIA_ERR_FORMAT,
                 "model '%s' /materials: material %d ('%s') has density %g kg/m^3, expected (0, %g] (denser than any "
                 "matter; check the units: kg/m^3)", origin, (int)k, mat->name, mat->density, FASCIA_MAX_DENSITY);
    FASCIA_CHECK(mat->part >= 0 && mat->part < FASCIA_PART_COUNT_, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /materials/part: material %d ('%s') has part %d, expected 0 (full), 1 (deviatoric) or "
                 "2 (volumetric)",
                 origin, (int)k, mat->name, (int)mat->part);
    FASCIA_CHECK(isfinite(mat->rotation_smoothing) && mat->rotation_smoothing >= 0, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /materials: material %d ('%s') has rotation smoothing %g, expected >= 0",
                 origin, (int)k, mat->name, mat->rotation_smoothing);
    FASCIA_CHECK(isfinite(mat->rotation_coupling) && mat->rotation_coupling >= 0, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /materials: material %d ('%s') has rotation coupling %g, expected >= 0", origin, (int)k,
                 mat->name, mat->rotation_coupling);
  }
  return FASCIA_OK;
}

static fascia_status validate_motions(fascia_ctx *ctx, const fascia_model *m, const char *origin) {
  for (int32_t k = 0; k < m->motion_count; ++k) {
    const fascia_motion *mo = m->motions + k;
    int64_t bad;
    FASCIA_CHECK(mo->key_count >= 1 && mo->key_time, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /motions/%s: no keyframe", origin, mo->name);
    FASCIA_CHECK(finite_all(mo->pivot, 3, &bad) && finite_all(mo->key_time, mo->key_count, &bad) &&
                     finite_all(mo->key_translation, 3 * (int64_t)mo->key_count, &bad) &&
                     finite_all(mo->key_rotation, 4 * (int64_t)mo->key_count, &bad),
                 ctx, FASCIA_ERR_FORMAT, "model '%s' /motions/%s: a non-finite value", origin, mo->name);
    for (int32_t j = 0; j < mo->key_count; ++j) {
      const fascia_real *q = mo->key_rotation + 4 * j;
      const double norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
      FASCIA_CHECK(fabs(norm - 1) < QUAT_NORM_TOLERANCE, ctx, FASCIA_ERR_FORMAT,
                   "model '%s' /motions/%s/rotation: key %d has norm %.12g, expected 1", origin, mo->name, (int)j,
                   norm);
      FASCIA_CHECK(j == 0 || mo->key_time[j] > mo->key_time[j - 1], ctx, FASCIA_ERR_FORMAT,
                   "model '%s' /motions/%s/time: key times are not strictly increasing at key %d", origin, mo->name,
                   (int)j);
    }
  }
  return FASCIA_OK;
}

static fascia_status validate_probes(fascia_ctx *ctx, const fascia_model *m, const char *origin) {
  FASCIA_TRY(check_csr(ctx, origin, "/probes/offsets", m->probe_offsets, m->probe_count, m->probe_pair_count));
  for (int32_t p = 0; p < m->probe_count; ++p) {
    FASCIA_CHECK(memchr(m->probe_name[p], 0, FASCIA_NAME_SIZE) && m->probe_name[p][0], ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /probes/name: probe %d has an empty or unterminated name", origin, (int)p);
    double sum = 0;
    for (int32_t k = m->probe_offsets[p]; k < m->probe_offsets[p + 1]; ++k) {
      FASCIA_CHECK(m->probe_frame[k] >= 0 && m->probe_frame[k] < m->frame_count, ctx, FASCIA_ERR_FORMAT,
                   "model '%s' /probes/frame: probe '%s' names frame %d of %d", origin, m->probe_name[p],
                   (int)m->probe_frame[k], (int)m->frame_count);
      sum += m->probe_weight[k];
    }
    FASCIA_CHECK(fabs(sum - 1) < WEIGHT_SUM_TOLERANCE, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /probes/weight: weights of probe '%s' sum to %.12g, expected 1", origin, m->probe_name[p],
                 sum);
  }
  return FASCIA_OK;
}

static fascia_status validate_organs(fascia_ctx *ctx, const fascia_model *m, const char *origin) {
  for (int32_t k = 0; k < m->organ_count; ++k) {
    const fascia_organ *o = m->organs + k;
    int64_t bad;
    FASCIA_CHECK(o->kind >= 0 && o->kind < FASCIA_ORGAN_KIND_COUNT_, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /organs/%s: kind %d is not 0..3", origin, o->name, (int)o->kind);
    FASCIA_CHECK(o->kind != FASCIA_ORGAN_PRESCRIBED || (o->motion >= 0 && o->motion < m->motion_count), ctx,
                 FASCIA_ERR_FORMAT, "model '%s' /organs/%s: prescribed organ names motion %d of %d", origin, o->name,
                 (int)o->motion, (int)m->motion_count);
    FASCIA_CHECK(finite_all(o->vertices, 3 * (int64_t)o->vertex_count, &bad), ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /organs/%s/vertices: vertex %lld is not finite", origin, o->name, (long long)(bad / 3));
    for (int64_t t = 0; t < 3 * (int64_t)o->triangle_count; ++t)
      FASCIA_CHECK(o->triangles[t] >= 0 && o->triangles[t] < o->vertex_count, ctx, FASCIA_ERR_FORMAT,
                   "model '%s' /organs/%s/triangles: triangle %lld names vertex %d of %d", origin, o->name,
                   (long long)(t / 3), (int)o->triangles[t], (int)o->vertex_count);
  }
  const fascia_surface *ts = &m->tissue_surface;
  int64_t bad;
  FASCIA_CHECK(finite_all(ts->vertices, 3 * (int64_t)ts->vertex_count, &bad), ctx, FASCIA_ERR_FORMAT,
               "model '%s' /tissue_surface/vertices: vertex %lld is not finite", origin, (long long)(bad / 3));
  for (int64_t t = 0; t < 3 * (int64_t)ts->triangle_count; ++t)
    FASCIA_CHECK(ts->triangles[t] >= 0 && ts->triangles[t] < ts->vertex_count, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /tissue_surface/triangles: triangle %lld names vertex %d of %d", origin,
                 (long long)(t / 3), (int)ts->triangles[t], (int)ts->vertex_count);
  for (int64_t k = 0; k < 4 * (int64_t)m->tetrahedron_count; ++k)
    FASCIA_CHECK(m->tetrahedra[k] >= 0 && m->tetrahedra[k] < m->frame_count, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /tetrahedra: tetrahedron %lld names frame %d of %d", origin, (long long)(k / 4),
                 (int)m->tetrahedra[k], (int)m->frame_count);
  for (int32_t c = 0; c < m->coupling_count; ++c) {
    const int32_t o = m->coupling_organ[c];
    FASCIA_CHECK(o >= 0 && o < m->organ_count, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /coupling/organ: entry %d names organ %d of %d", origin, (int)c, (int)o,
                 (int)m->organ_count);
    FASCIA_CHECK(m->coupling_frame[c] >= 0 && m->coupling_frame[c] < m->frame_count, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /coupling/frame: entry %d names frame %d of %d", origin, (int)c,
                 (int)m->coupling_frame[c], (int)m->frame_count);
    FASCIA_CHECK(m->coupling_triangle[c] >= 0 && m->coupling_triangle[c] < m->organs[o].triangle_count, ctx,
                 FASCIA_ERR_FORMAT, "model '%s' /coupling/triangle: entry %d names triangle %d of organ '%s' (%d)",
                 origin, (int)c, (int)m->coupling_triangle[c], m->organs[o].name, (int)m->organs[o].triangle_count);
    const int32_t i = m->coupling_frame[c];
    // a rigid organ moves its coupling frames itself: a fixed or prescribed
    // one would have two masters (a model problem, not a solver setting)
    FASCIA_CHECK(m->organs[o].kind != FASCIA_ORGAN_RIGID || m->frame_kind[i] == FASCIA_FRAME_FREE, ctx,
                 FASCIA_ERR_FORMAT,
                 "model '%s' /coupling/frame: organ '%s' is rigid, but its coupling frame %d is %s in /frames/kind; "
                 "the frames on a rigid organ must be free: make the frame free, make the organ fixed or "
                 "prescribed, or re-run 'fascia prep'",
                 origin, m->organs[o].name, (int)i, m->frame_kind[i] == FASCIA_FRAME_FIXED ? "fixed" : "prescribed");
    const fascia_real *b = m->coupling_barycentric + 3 * c;
    FASCIA_CHECK(isfinite(b[0]) && isfinite(b[1]) && isfinite(b[2]) && fabs(b[0] + b[1] + b[2] - 1) < 1e-6, ctx,
                 FASCIA_ERR_FORMAT, "model '%s' /coupling/barycentric: entry %d does not sum to 1", origin, (int)c);
  }
  return FASCIA_OK;
}

// A piece that nothing holds falls for ever: the static solve has no
// equilibrium and a dynamic run only tracks the fall. Refused unless the model
// says it is meant to float; the message names the largest such piece.
static fascia_status validate_held(fascia_ctx *ctx, const fascia_model *m, const char *origin) {
  if (m->allow_floating) return FASCIA_OK;
  fascia_model_piece *pieces = fascia_calloc(m->frame_count, sizeof *pieces);
  FASCIA_CHECK(pieces, ctx, FASCIA_ERR_MEMORY, "model '%s': out of memory for its connectivity", origin);
  int32_t count = 0;
  const fascia_status status = fascia_model_floating_components(ctx, m, NULL, pieces, m->frame_count, &count);
  if (status != FASCIA_OK || count == 0) {
    free(pieces);
    return status;
  }
  int32_t big = 0;
  fascia_real volume = 0;
  for (int32_t k = 0; k < count; ++k) {
    volume += pieces[k].volume;
    if (pieces[k].volume > pieces[big].volume) big = k;
  }
  const fascia_model_piece q = pieces[big];
  free(pieces);
  return FASCIA_FAIL(ctx, FASCIA_ERR_FORMAT,
                     "model '%s': %d piece(s) (%.3g cm^3 in all) are held by nothing (no fixed or prescribed frame, "
                     "no organ that is): the largest, %d frames and %d samples (%.3g cm^3) around frame %d at "
                     "(%.4g, %.4g, %.4g) m, would fall for ever; re-run 'fascia prep' (it drops such pieces), attach "
                     "it, or mark the model as meant to float (allow_floating)",
                     origin, (int)count, volume * 1e6, (int)q.frames, (int)q.samples, q.volume * 1e6,
                     (int)q.first_frame, q.position[0], q.position[1], q.position[2]);
}

// Volumetric patches: indices in range, and one material per patch whose
// energy is whole (a deviatoric or volumetric part is the other cure).
static fascia_status validate_patches(fascia_ctx *ctx, const fascia_model *m, const char *origin) {
  const int32_t S = m->sample_count;
  int any = 0;
  for (int32_t s = 0; s < S; ++s) {
    const int32_t p = m->sample_patch[s];
    if (p == -1) continue;
    FASCIA_CHECK(p >= 0 && p < S, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /samples/patch: sample %d names patch %d, expected -1 (none) or 0 .. %d", origin, (int)s,
                 (int)p, (int)S - 1);
    const fascia_material *mat = m->materials + m->sample_material[s];
    FASCIA_CHECK(mat->part == FASCIA_PART_FULL, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /samples/patch: sample %d is in patch %d but its material '%s' integrates only part of "
                 "its energy (part %d); patches need whole materials (part 0)",
                 origin, (int)s, (int)p, mat->name, (int)mat->part);
    any = 1;
  }
  for (int32_t s = 0; s < S; ++s) {
    FASCIA_CHECK(m->sample_modes[s] >= 0 && m->sample_modes[s] < FASCIA_MODES_COUNT_, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /samples/modes: sample %d has %d, expected 0 (none), 1 (nine) or 2 (normal)", origin,
                 (int)s, (int)m->sample_modes[s]);
    FASCIA_CHECK(!m->sample_modes[s] || m->sample_patch[s] >= 0, ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /samples/modes: sample %d has enhanced strain modes but no volumetric patch; the modes "
                 "live on the patches",
                 origin, (int)s);
  }
  if (!any) return FASCIA_OK;
  // one material per patch: the first sample of each patch names it
  int32_t *first = malloc((size_t)S * sizeof *first);
  FASCIA_CHECK(first, ctx, FASCIA_ERR_MEMORY, "model '%s': out of memory checking patches", origin);
  for (int32_t k = 0; k < S; ++k) first[k] = -1;
  for (int32_t s = 0; s < S; ++s) {
    const int32_t p = m->sample_patch[s];
    if (p == -1) continue;
    if (first[p] < 0) first[p] = s;
    else if (m->sample_modes[first[p]] != m->sample_modes[s]) {
      const int32_t a = first[p];
      free(first);
      return FASCIA_FAIL(ctx, FASCIA_ERR_FORMAT,
                         "model '%s' /samples/modes: patch %d holds samples %d (modes %d) and %d (modes %d); a "
                         "patch's samples share its modes",
                         origin, (int)p, (int)a, (int)m->sample_modes[a], (int)s, (int)m->sample_modes[s]);
    } else if (m->sample_material[first[p]] != m->sample_material[s]) {
      const int32_t a = first[p];
      free(first);
      return FASCIA_FAIL(ctx, FASCIA_ERR_FORMAT,
                         "model '%s' /samples/patch: patch %d holds samples %d and %d of different materials (%d, %d); "
                         "a patch averages one material's dilatation",
                         origin, (int)p, (int)a, (int)s, (int)m->sample_material[a], (int)m->sample_material[s]);
    }
  }
  free(first);
  return FASCIA_OK;
}

fascia_status fascia_model_validate(fascia_ctx *ctx, const fascia_model *m, const char *origin) {
  FASCIA_CHECK(m, ctx, FASCIA_ERR_ARGUMENT, "fascia_model_validate: NULL model");
  if (!origin) origin = "(memory)";
  FASCIA_CHECK(m->frame_count >= 1, ctx, FASCIA_ERR_FORMAT, "model '%s' /frames: no frame", origin);
  FASCIA_CHECK(m->sample_count >= 1, ctx, FASCIA_ERR_FORMAT, "model '%s' /samples: no sample", origin);
  int64_t bad;
  FASCIA_CHECK(finite_all(m->gravity, 3, &bad), ctx, FASCIA_ERR_FORMAT, "model '%s' /gravity: not finite", origin);
  FASCIA_TRY(validate_finite(ctx, m, origin));
  FASCIA_TRY(validate_materials(ctx, m, origin));
  FASCIA_TRY(validate_motions(ctx, m, origin));
  FASCIA_TRY(validate_frames(ctx, m, origin));
  FASCIA_TRY(validate_samples(ctx, m, origin));
  FASCIA_TRY(validate_patches(ctx, m, origin));
  FASCIA_TRY(validate_reverse(ctx, m, origin));
  FASCIA_TRY(validate_probes(ctx, m, origin));
  FASCIA_TRY(validate_organs(ctx, m, origin));
  FASCIA_TRY(validate_held(ctx, m, origin));
  return FASCIA_OK;
}

fascia_real fascia_model_volume(const fascia_model *m) {
  fascia_real v = 0;
  for (int32_t s = 0; s < m->sample_count; ++s)
    if (m->materials[m->sample_material[s]].part != FASCIA_PART_VOLUMETRIC) v += m->sample_volume[s];
  return v;
}

fascia_real fascia_model_tissue_volume(const fascia_model *m) {
  fascia_real v = 0;
  for (int32_t s = 0; s < m->sample_count; ++s)
    if (m->sample_organ[s] < 0 && m->materials[m->sample_material[s]].part != FASCIA_PART_VOLUMETRIC)
      v += m->sample_volume[s];
  return v;
}

fascia_real fascia_model_mass(const fascia_model *m) {
  fascia_real mass = 0;
  for (int32_t s = 0; s < m->sample_count; ++s)
    if (m->materials[m->sample_material[s]].part != FASCIA_PART_VOLUMETRIC)
      mass += m->sample_volume[s] * m->materials[m->sample_material[s]].density;
  return mass;
}

void fascia_material_lame(const fascia_material *mat, fascia_real *lambda, fascia_real *mu) {
  const fascia_real E = mat->youngs_modulus, nu = mat->poisson_ratio;
  *lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  *mu = E / (2 * (1 + nu));
}

void fascia_lame_to_young(fascia_real lambda, fascia_real mu, fascia_real *E, fascia_real *nu) {
  *E = mu * (3 * lambda + 2 * mu) / (lambda + mu);
  *nu = lambda / (2 * (lambda + mu));
}

int fascia_law_from_name(const char *name) {
  if (!name) return -1;
  if (!strcmp(name, "stvk")) return FASCIA_LAW_STVK;
  if (!strcmp(name, "neohookean")) return FASCIA_LAW_NEOHOOKEAN;
  return -1;
}

const char *fascia_law_name(int law) {
  switch (law) {
  case FASCIA_LAW_STVK: return "stvk";
  case FASCIA_LAW_NEOHOOKEAN: return "neohookean";
  default: return "unknown";
  }
}

int32_t fascia_model_find_probe(const fascia_model *m, const char *name) {
  for (int32_t p = 0; m && name && p < m->probe_count; ++p)
    if (!strncmp(m->probe_name[p], name, FASCIA_NAME_SIZE)) return p;
  return -1;
}

static uint64_t hash_name(uint64_t h, const char *name) {
  const size_t n = strnlen(name, FASCIA_NAME_SIZE);
  h = fascia_fnv(h, name, n);
  return fascia_fnv(h, "", 1); // the end of the name: "ab"+"c" differs from "a"+"bc"
}

static uint64_t hash_materials(uint64_t h, const fascia_model *m, int file) {
  for (int32_t k = 0; k < m->material_count; ++k) {
    const fascia_material *mat = m->materials + k;
    const fascia_real values[5] = {mat->youngs_modulus, mat->poisson_ratio, mat->density, mat->rotation_coupling,
                                   mat->rotation_smoothing};
    const int32_t kinds[2] = {mat->law, mat->part};
    if (file) h = hash_name(h, mat->name);
    h = fascia_fnv(h, kinds, sizeof kinds);
    h = fascia_fnv(h, values, sizeof values);
  }
  return h;
}

static uint64_t hash_motions(uint64_t h, const fascia_model *m, int file) {
  const size_t R = sizeof(fascia_real);
  for (int32_t k = 0; k < m->motion_count; ++k) {
    const fascia_motion *mo = m->motions + k;
    const size_t K = (size_t)mo->key_count;
    const int64_t keys = mo->key_count;
    if (file) h = fascia_fnv(hash_name(h, mo->name), &keys, sizeof keys);
    h = fascia_fnv(h, mo->pivot, 3 * R);
    h = fascia_fnv(h, mo->key_time, K * R);
    h = fascia_fnv(h, mo->key_translation, 3 * K * R);
    h = fascia_fnv(h, mo->key_rotation, 4 * K * R);
  }
  return h;
}

static uint64_t hash_organs(uint64_t h, const fascia_model *m, int file) {
  for (int32_t k = 0; k < m->organ_count; ++k) {
    const fascia_organ *o = m->organs + k;
    const int32_t head[4] = {o->kind, o->motion, o->vertex_count, o->triangle_count};
    if (file) h = hash_name(h, o->name);
    h = fascia_fnv(h, head, sizeof head);
    h = fascia_fnv(h, o->vertices, 3 * (size_t)o->vertex_count * sizeof(fascia_real));
    h = fascia_fnv(h, o->triangles, 3 * (size_t)o->triangle_count * sizeof(int32_t));
  }
  return h;
}

uint64_t fascia_model_hash_rows(uint64_t h, const fascia_model *m, int file) {
  fascia_model_view views[FASCIA_MA_COUNT];
  fascia_model_views(m, views);
  for (int k = 0; k < FASCIA_MA_COUNT; ++k) {
    const fascia_model_view *v = views + k;
    const int unset = !fascia_model_view_set(v);
    if (file ? unset && v->array->since > FASCIA_MA_CHECKSUM_VERSION : unset || !(v->array->flags & FASCIA_MA_FP))
      continue;
    switch (v->array->kind) {
    case FASCIA_MA_NAME:
      for (int64_t r = 0; r < v->rows; ++r) h = hash_name(h, (const char *)v->data + r * FASCIA_NAME_SIZE);
      break;
    case FASCIA_MA_MATERIAL: h = hash_materials(h, m, file); break;
    case FASCIA_MA_MOTION: h = hash_motions(h, m, file); break;
    case FASCIA_MA_ORGAN: h = hash_organs(h, m, file); break;
    default: h = fascia_fnv(h, v->data, fascia_model_view_bytes(v));
    }
  }
  return h;
}

// FNV-1a over every array the solver reads (model.h says what counts).
uint64_t fascia_model_fingerprint(const fascia_model *m) {
  const uint64_t h = fascia_model_hash_rows(FASCIA_FNV_START, m, 0);
  return fascia_fnv(h, m->gravity, 3 * sizeof(fascia_real));
}
