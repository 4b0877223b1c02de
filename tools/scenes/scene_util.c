// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Private helpers of the code-built scenes (see scene_util.h): frame grid,
// Kuhn split, shape functions in grid terms, pair storage, finishing steps.
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "scene_util.h"

scene_grid scene_grid_of_beam(const fascia_scene_beam_def *def, const int32_t frames[3]) {
  scene_grid g;
  const fascia_real size[3] = {def->length, def->width, def->height};
  const fascia_real lo[3] = {0, -def->width / 2, -def->height / 2};
  for (int d = 0; d < 3; ++d) {
    g.n[d] = frames[d];
    g.lo[d] = lo[d];
    g.hi[d] = lo[d] + size[d];
    g.step[d] = size[d] / (frames[d] - 1);
  }
  return g;
}

int32_t scene_grid_frame_count(const scene_grid *g) { return g->n[0] * g->n[1] * g->n[2]; }
int32_t scene_grid_cell_count(const scene_grid *g) { return (g->n[0] - 1) * (g->n[1] - 1) * (g->n[2] - 1); }

void scene_grid_positions(const scene_grid *g, fascia_real *position) {
  for (int32_t ix = 0; ix < g->n[0]; ++ix)
    for (int32_t iy = 0; iy < g->n[1]; ++iy)
      for (int32_t iz = 0; iz < g->n[2]; ++iz) {
        fascia_real *x = position + 3 * (((int64_t)ix * g->n[1] + iy) * g->n[2] + iz);
        const int32_t idx[3] = {ix, iy, iz};
        for (int d = 0; d < 3; ++d) x[d] = scene_grid_coord(g, d, idx[d]);
      }
}

fascia_real scene_grid_coord(const scene_grid *g, int d, int32_t idx) {
  // the last frame sits exactly on the far face, not at lo + (n-1) step
  return idx >= g->n[d] - 1 ? g->hi[d] : g->lo[d] + g->step[d] * idx;
}

void scene_grid_cell_of(const scene_grid *g, const fascia_real p[3], int32_t cell[3]) {
  for (int d = 0; d < 3; ++d) {
    const fascia_real t = floor((p[d] - g->lo[d]) / g->step[d]);
    cell[d] = !(t > 0) ? 0 : t >= g->n[d] - 2 ? g->n[d] - 2 : (int32_t)t;
  }
}

void scene_grid_cell_unflatten(const scene_grid *g, int32_t c, int32_t cell[3]) {
  const int32_t cy = g->n[1] - 1, cz = g->n[2] - 1;
  cell[2] = c % cz;
  cell[1] = (c / cz) % cy;
  cell[0] = c / (cz * cy);
}

void scene_grid_cell_corners(const scene_grid *g, const int32_t cell[3], int32_t frame[8], fascia_real lo[3],
                             fascia_real hi[3]) {
  for (int c = 0; c < 8; ++c) {
    const int32_t ix = cell[0] + (c & 1), iy = cell[1] + ((c >> 1) & 1), iz = cell[2] + ((c >> 2) & 1);
    frame[c] = (ix * g->n[1] + iy) * g->n[2] + iz;
  }
  for (int d = 0; d < 3; ++d) {
    lo[d] = scene_grid_coord(g, d, cell[d]);
    hi[d] = scene_grid_coord(g, d, cell[d] + 1);
  }
}

void scene_kuhn_tet(int t, int corner[4]) {
  static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  const int a = 1 << perm[t][0], b = 1 << perm[t][1];
  corner[0] = 0;
  corner[1] = a;
  corner[2] = a | b;
  corner[3] = 7;
}

void scene_cell_tet(const scene_grid *g, const int32_t cell[3], int t, int32_t frame[4], fascia_real vertex[12]) {
  int32_t corner_frame[8];
  fascia_real lo[3], hi[3];
  scene_grid_cell_corners(g, cell, corner_frame, lo, hi);
  int corner[4];
  scene_kuhn_tet(t, corner);
  for (int j = 0; j < 4; ++j) {
    frame[j] = corner_frame[corner[j]];
    for (int d = 0; d < 3; ++d) vertex[3 * j + d] = (corner[j] >> d) & 1 ? hi[d] : lo[d];
  }
}

fascia_status scene_hex_at(fascia_ctx *ctx, const scene_grid *g, const fascia_real p[3], int32_t frame[8],
                           fascia_real w[8], fascia_real grad[24]) {
  int32_t cell[3];
  fascia_real lo[3], hi[3];
  scene_grid_cell_of(g, p, cell);
  scene_grid_cell_corners(g, cell, frame, lo, hi);
  return fascia_shape_hex(ctx, lo, hi, p, w, grad);
}

fascia_status scene_tet_at(fascia_ctx *ctx, const scene_grid *g, const fascia_real p[3], int32_t frame[4],
                           fascia_real w[4], fascia_real grad[12]) {
  int32_t cell[3];
  scene_grid_cell_of(g, p, cell);
  fascia_real best = -INFINITY;
  for (int t = 0; t < 6; ++t) {
    int32_t f[4];
    fascia_real vertex[12], wt[4], gt[12];
    scene_cell_tet(g, cell, t, f, vertex);
    SCENE_TRY(fascia_shape_tet(ctx, vertex, p, wt, gt));
    const fascia_real smallest = fmin(fmin(wt[0], wt[1]), fmin(wt[2], wt[3]));
    if (smallest > best) {
      best = smallest;
      memcpy(frame, f, sizeof f);
      memcpy(w, wt, sizeof wt);
      memcpy(grad, gt, sizeof gt);
    }
  }
  return FASCIA_OK;
}

fascia_status scene_mls_at(fascia_ctx *ctx, const fascia_frame_grid *grid, const fascia_real p[3], int32_t k,
                           int32_t *frame, fascia_real *w, fascia_real *grad) {
  fascia_real radius, x[3 * FASCIA_SHAPE_MAX_NEIGHBOURS];
  SCENE_TRY(fascia_frame_grid_nearest(ctx, grid, p, k, frame, &radius));
  const fascia_real *position = fascia_frame_grid_positions(grid);
  for (int32_t j = 0; j < k; ++j)
    for (int d = 0; d < 3; ++d) x[3 * j + d] = position[3 * (int64_t)frame[j] + d];
  return fascia_shape_mls(ctx, k, x, p, radius, w, grad);
}

void scene_set_pairs(fascia_model *m, int32_t s, int32_t n, const int32_t *frame, const fascia_real *w,
                     const fascia_real *grad) {
  const int32_t base = m->sample_offsets[s];
  // insertion sort of the n pairs into place by frame index (n is small)
  for (int32_t j = 0; j < n; ++j) {
    int32_t k = base + j;
    while (k > base && m->pair_frame[k - 1] > frame[j]) {
      m->pair_frame[k] = m->pair_frame[k - 1];
      m->pair_weight[k] = m->pair_weight[k - 1];
      for (int d = 0; d < 3; ++d) m->pair_gradient[3 * (int64_t)k + d] = m->pair_gradient[3 * (int64_t)k - 3 + d];
      --k;
    }
    m->pair_frame[k] = frame[j];
    m->pair_weight[k] = w[j];
    for (int d = 0; d < 3; ++d) m->pair_gradient[3 * (int64_t)k + d] = grad[3 * j + d];
  }
  m->sample_offsets[s + 1] = base + n;
}

void scene_probe_set(scene_probe *probe, const fascia_real position[3], int32_t n, const int32_t *frame,
                     const fascia_real *w) {
  probe->count = 0;
  for (int d = 0; d < 3; ++d) probe->position[d] = position[d];
  for (int32_t j = 0; j < n && probe->count < SCENE_PROBE_MAX; ++j) {
    if (w[j] == 0) continue;
    int32_t k = probe->count++;
    while (k > 0 && probe->frame[k - 1] > frame[j]) {
      probe->frame[k] = probe->frame[k - 1];
      probe->weight[k] = probe->weight[k - 1];
      --k;
    }
    probe->frame[k] = frame[j];
    probe->weight[k] = w[j];
  }
}

fascia_status scene_check_body(fascia_ctx *ctx, const fascia_scene_beam_def *def, const char *who) {
  SCENE_CHECK(def, ctx, FASCIA_ERR_ARGUMENT, "%s: NULL def", who);
  SCENE_CHECK(def->cookie_ == FASCIA_SCENE_BEAM_COOKIE_, ctx, FASCIA_ERR_ARGUMENT,
              "%s: the def was not made by fascia_scene_beam_def_default()", who);
  const fascia_real size[3] = {def->length, def->width, def->height};
  static const char *const size_name[3] = {"length", "width", "height"};
  for (int d = 0; d < 3; ++d)
    SCENE_CHECK(isfinite(size[d]) && size[d] > 0, ctx, FASCIA_ERR_ARGUMENT, "%s: %s is %g m, expected > 0", who,
                size_name[d], size[d]);
  SCENE_CHECK(def->law >= 0 && def->law < FASCIA_LAW_COUNT_, ctx, FASCIA_ERR_ARGUMENT,
              "%s: law %d is not a fascia_law (0 stvk, 1 neohookean)", who, (int)def->law);
  SCENE_CHECK(isfinite(def->youngs_modulus) && def->youngs_modulus > 0, ctx, FASCIA_ERR_ARGUMENT,
              "%s: Young's modulus is %g Pa, expected > 0", who, def->youngs_modulus);
  SCENE_CHECK(isfinite(def->poisson_ratio) && def->poisson_ratio >= 0 && def->poisson_ratio < 0.5, ctx,
              FASCIA_ERR_ARGUMENT, "%s: Poisson ratio is %g, expected in [0, 0.5)", who, def->poisson_ratio);
  SCENE_CHECK(isfinite(def->density) && (def->density > 0 || (isfinite(def->mass) && def->mass > 0)), ctx,
              FASCIA_ERR_ARGUMENT, "%s: mass %g kg and density %g kg/m^3; expected a positive mass or density", who,
              def->mass, def->density);
  SCENE_CHECK(isfinite(def->rotation_coupling) && def->rotation_coupling >= 0, ctx, FASCIA_ERR_ARGUMENT,
              "%s: rotation coupling is %g, expected >= 0", who, def->rotation_coupling);
  SCENE_CHECK(isfinite(def->rotation_smoothing) &&
                  (def->rotation_smoothing >= 0 || def->rotation_smoothing == FASCIA_SCENE_SMOOTHING_AUTO),
              ctx, FASCIA_ERR_ARGUMENT, "%s: rotation smoothing is %g, expected >= 0 (or -1: by shape kind)", who,
              def->rotation_smoothing);
  SCENE_CHECK(isfinite(def->gravity[0]) && isfinite(def->gravity[1]) && isfinite(def->gravity[2]), ctx,
              FASCIA_ERR_ARGUMENT, "%s: gravity is not finite", who);
  return FASCIA_OK;
}

fascia_real scene_smoothing(const fascia_scene_beam_def *def) {
  if (def->rotation_smoothing >= 0) return def->rotation_smoothing;
  if (def->shape == FASCIA_SCENE_STRAND || def->shape == FASCIA_SCENE_SHEET) return 0;
  return def->shape == FASCIA_SCENE_TET ? 0.05 : 0.1;
}

void scene_section_moduli(const fascia_scene_beam_def *def, fascia_real *youngs_modulus, fascia_real *poisson_ratio) {
  fascia_shape_section_moduli(fascia_scene_shape_dimension(def->shape), def->youngs_modulus, def->poisson_ratio,
                              youngs_modulus, poisson_ratio);
}

fascia_real scene_density(const fascia_scene_beam_def *def) {
  return def->density > 0 ? def->density : def->mass / (def->length * def->width * def->height);
}

fascia_status scene_model_alloc(fascia_ctx *ctx, int32_t frames, const fascia_real *position, int32_t samples,
                                int32_t pairs, int32_t materials, const scene_probe *probe, fascia_model **out) {
  fascia_model_sizes sizes;
  memset(&sizes, 0, sizeof sizes);
  sizes.frames = frames;
  sizes.samples = samples;
  sizes.pairs = pairs;
  sizes.materials = materials;
  sizes.probes = 1;
  sizes.probe_pairs = probe->count;
  SCENE_TRY(fascia_model_alloc(ctx, &sizes, out));
  memcpy((*out)->frame_position, position, 3 * (size_t)frames * sizeof *position);
  return FASCIA_OK;
}

fascia_status scene_build_begin(fascia_ctx *ctx, int32_t frames, const char *who, scene_build *b) {
  b->position = malloc(3 * (size_t)frames * sizeof *b->position);
  b->provenance = malloc(SCENE_PROVENANCE_SIZE);
  b->grid = NULL;
  b->m = NULL;
  if (b->position && b->provenance) return FASCIA_OK;
  return scene_build_end(b, SCENE_FAIL(ctx, FASCIA_ERR_MEMORY, "%s: out of memory for %d frames", who, (int)frames),
                         NULL);
}

fascia_status scene_build_end(scene_build *b, fascia_status status, fascia_model **out) {
  if (status == FASCIA_OK) {
    *out = b->m;
    b->m = NULL;
  }
  fascia_model_destroy(&b->m);
  fascia_frame_grid_destroy(&b->grid);
  free(b->position);
  free(b->provenance);
  return status;
}

fascia_status scene_finish(fascia_ctx *ctx, fascia_model *m, const fascia_scene_beam_def *def,
                           const scene_probe *probe, const char *provenance, const char *origin) {
  fascia_material *mat = &m->materials[0];
  snprintf(mat->name, sizeof mat->name, "beam");
  mat->law = def->law;
  scene_section_moduli(def, &mat->youngs_modulus, &mat->poisson_ratio);
  mat->density = scene_density(def);
  mat->rotation_coupling = def->rotation_coupling;
  mat->rotation_smoothing = scene_smoothing(def);
  if (m->material_count == 2) { // selective reduced integration: the same material split in two parts
    m->materials[1] = *mat;
    mat->part = FASCIA_PART_DEVIATORIC;
    m->materials[1].part = FASCIA_PART_VOLUMETRIC;
    snprintf(mat->name, sizeof mat->name, "beam-deviatoric");
    snprintf(m->materials[1].name, sizeof m->materials[1].name, "beam-volumetric");
  }
  for (int d = 0; d < 3; ++d) m->gravity[d] = def->gravity[d];
  // the clamped end: frames placed at exactly x = 0 by scene_grid_positions
  for (int32_t i = 0; i < m->frame_count; ++i)
    m->frame_kind[i] = m->frame_position[3 * (int64_t)i] == 0 ? FASCIA_FRAME_FIXED : FASCIA_FRAME_FREE;
  snprintf(m->probe_name[0], FASCIA_NAME_SIZE, "tip");
  for (int d = 0; d < 3; ++d) m->probe_position[d] = probe->position[d];
  m->probe_offsets[0] = 0;
  m->probe_offsets[1] = probe->count;
  for (int32_t k = 0; k < probe->count; ++k) {
    m->probe_frame[k] = probe->frame[k];
    m->probe_weight[k] = probe->weight[k];
  }
  SCENE_TRY(fascia_model_set_provenance(ctx, m, provenance));
  SCENE_TRY(fascia_model_build_reverse(ctx, m));
  return fascia_model_validate(ctx, m, origin);
}

void scene_append(char *buf, size_t size, const char *format, ...) {
  const size_t used = strlen(buf);
  if (used + 1 >= size) return;
  va_list args;
  va_start(args, format);
  vsnprintf(buf + used, size - used, format, args);
  va_end(args);
}

// Shortest of %.15g / %.17g that reads back to the same double (JSON number).
static void append_real(char *buf, size_t size, const char *key, fascia_real x, const char *sep) {
  char text[40];
  snprintf(text, sizeof text, "%.15g", x);
  if (strtod(text, NULL) != x) snprintf(text, sizeof text, "%.17g", x);
  scene_append(buf, size, "\"%s\": %s%s", key, text, sep);
}

void scene_append_body_json(char *buf, size_t size, const fascia_scene_beam_def *def) {
  append_real(buf, size, "length", def->length, ", ");
  append_real(buf, size, "width", def->width, ", ");
  append_real(buf, size, "height", def->height, ", ");
  scene_append(buf, size, "\"law\": \"%s\", ", fascia_law_name(def->law));
  append_real(buf, size, "youngs_modulus", def->youngs_modulus, ", ");
  append_real(buf, size, "poisson_ratio", def->poisson_ratio, ", ");
  append_real(buf, size, "mass", def->density > 0 ? scene_density(def) * def->length * def->width * def->height
                                                   : def->mass,
              ", ");
  append_real(buf, size, "density", scene_density(def), ", ");
  append_real(buf, size, "rotation_coupling", def->rotation_coupling, ", ");
  append_real(buf, size, "rotation_smoothing", scene_smoothing(def), ", ");
  scene_append(buf, size, "\"reduced_volumetric\": %d, ", (int)def->reduced_volumetric);
  if (def->volumetric_patch != FASCIA_SCENE_PATCH_NONE)
    scene_append(buf, size, "\"volumetric_patch\": \"%s\", ", fascia_scene_patch_name(def->volumetric_patch));
  if (def->enhanced_modes > 0) scene_append(buf, size, "\"enhanced_modes\": %d, ", (int)def->enhanced_modes);
  scene_append(buf, size, "\"gravity\": [%.15g, %.15g, %.15g], ", def->gravity[0], def->gravity[1], def->gravity[2]);
  scene_append(buf, size, "\"fixed\": \"frames at x = 0\", \"probe\": \"tip at (%.15g, 0, 0)\"", def->length);
}

double scene_now_ms(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}
