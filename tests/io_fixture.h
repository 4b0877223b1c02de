// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A small hand-built model that uses every part of fascia_model (for the I/O
// tests t2xx_io_*), and file helpers for tests that write into a scratch folder.
#ifndef FASCIA_TESTS_IO_FIXTURE_H
#define FASCIA_TESTS_IO_FIXTURE_H

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fascia/fascia.h"

// One sample's neighbours: frames ascending, weights summing to 1 and
// gradients summing to 0 (linear barycentric functions of the unit
// tetrahedron 0..3 restricted to an edge, a face or the whole tetrahedron).
typedef struct fixture_sample {
  int n;
  int32_t frame[4];
  double weight[4], gradient[4][3];
} fixture_sample;

/// Builds the fixture: 5 frames (tetrahedron corners plus one prescribed
/// frame, rotated rest frames, loads), 3 samples with 2, 3 and 4
/// neighbours, 2 materials, 1 motion with 2 keys, 1 probe, 1 organ with 2
/// triangles, 2 coupling entries, gravity and provenance, and samples 0 and 2
/// (of the whole material) in one volumetric patch (a version 2 file). With
/// minimal != 0 instead: no motion, probe, organ, coupling, provenance or
/// patch (empty arrays, a version 1 file).
static inline fascia_status fixture_model(fascia_ctx *ctx, int minimal, fascia_model **out) {
  const fixture_sample samples[3] = {
      {2, {0, 1, 0, 0}, {0.75, 0.25, 0, 0}, {{-1, 0, 0}, {1, 0, 0}}},
      {3, {0, 1, 2, 0}, {0.5, 0.25, 0.25, 0}, {{-1, -1, 0}, {1, 0, 0}, {0, 1, 0}}},
      {4, {0, 1, 2, 3}, {0.25, 0.25, 0.25, 0.25}, {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}},
  };
  fascia_model_sizes z = {5, 3, 9, 2, 1, 1, 2, 1, 2};
  if (minimal) z.motions = z.probes = z.probe_pairs = z.organs = z.couplings = 0;
  fascia_model *m = NULL;
  fascia_status st = fascia_model_alloc(ctx, &z, &m);
  if (st != FASCIA_OK) return st;
  const double corner[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1.5, 1.5, 1.5}};
  for (int i = 0; i < 5; ++i) {
    for (int r = 0; r < 3; ++r) m->frame_position[3 * i + r] = 0.1 * corner[i][r] + 1e-17 * i;
    const double angle = 0.1 * i; // rotated rest frames exercise all 4 quaternion components
    m->frame_rotation[4 * i + 0] = cos(angle);
    m->frame_rotation[4 * i + 1 + i % 3] = sin(angle);
    for (int r = 0; r < 6; ++r) m->frame_load[6 * i + r] = (i == 3) ? 0.01 * (r + 1) : 0;
  }
  m->frame_kind[0] = FASCIA_FRAME_FIXED;
  if (!minimal) {
    m->frame_kind[4] = FASCIA_FRAME_PRESCRIBED;
    m->frame_motion[4] = 0;
  }
  int32_t k = 0;
  for (int s = 0; s < 3; ++s) {
    m->sample_offsets[s] = k;
    double p[3] = {0, 0, 0};
    for (int j = 0; j < samples[s].n; ++j, ++k) {
      m->pair_frame[k] = samples[s].frame[j];
      m->pair_weight[k] = samples[s].weight[j];
      for (int r = 0; r < 3; ++r) {
        m->pair_gradient[3 * k + r] = samples[s].gradient[j][r] / 0.1; // 1/m at 0.1 m edge
        p[r] += samples[s].weight[j] * m->frame_position[3 * samples[s].frame[j] + r];
      }
    }
    for (int r = 0; r < 3; ++r) m->sample_position[3 * s + r] = p[r];
    m->sample_volume[s] = 1e-4 * (s + 1) / 3.0;
    m->sample_material[s] = s % 2;
  }
  m->sample_offsets[3] = k;
  if (!minimal) m->sample_patch[0] = m->sample_patch[2] = 2;
  const char *names[2] = {"fat", "fascia"};
  for (int j = 0; j < 2; ++j) {
    snprintf(m->materials[j].name, FASCIA_NAME_SIZE, "%s", names[j]);
    m->materials[j].law = j;
    m->materials[j].youngs_modulus = j ? 2e5 : 3000.0 / 7.0;
    m->materials[j].poisson_ratio = j ? 0.3 : 0.45;
    m->materials[j].density = j ? 1100 : 950.5;
    m->materials[j].rotation_coupling = j ? 0.1 : 0;
    m->materials[j].rotation_smoothing = j ? 0 : 0.25;
    m->materials[j].part = j ? FASCIA_PART_DEVIATORIC : FASCIA_PART_FULL;
  }
  m->gravity[2] = -9.81;
  if (!minimal) {
    fascia_motion *mo = m->motions;
    snprintf(mo->name, FASCIA_NAME_SIZE, "breathing");
    mo->pivot[0] = 0.1, mo->pivot[1] = 0.2, mo->pivot[2] = 0.3;
    if ((st = fascia_motion_alloc(ctx, mo, 2)) != FASCIA_OK) goto fail;
    mo->key_time[1] = 1.25;
    mo->key_translation[3 + 2] = 0.02;
    mo->key_rotation[4] = cos(0.05), mo->key_rotation[5] = sin(0.05);
    snprintf(m->probe_name[0], FASCIA_NAME_SIZE, "tip");
    for (int r = 0; r < 3; ++r) m->probe_position[r] = 0.25 * corner[3][r] + 0.75 * corner[4][r];
    m->probe_offsets[1] = 2;
    m->probe_frame[0] = 3, m->probe_frame[1] = 4;
    m->probe_weight[0] = 0.25, m->probe_weight[1] = 0.75;
    fascia_organ *o = m->organs;
    snprintf(o->name, FASCIA_NAME_SIZE, "liver");
    o->kind = FASCIA_ORGAN_PRESCRIBED;
    o->motion = 0;
    if ((st = fascia_organ_alloc(ctx, o, 4, 2)) != FASCIA_OK) goto fail;
    for (int v = 0; v < 4; ++v)
      for (int r = 0; r < 3; ++r) o->vertices[3 * v + r] = 0.1 * corner[v][r] + 0.001;
    const int32_t tri[6] = {0, 1, 2, 1, 2, 3};
    memcpy(o->triangles, tri, sizeof tri);
    m->coupling_organ[0] = m->coupling_organ[1] = 0;
    m->coupling_frame[0] = 1, m->coupling_frame[1] = 2;
    m->coupling_triangle[0] = 0, m->coupling_triangle[1] = 1;
    const double bary[6] = {0.2, 0.3, 0.5, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0};
    memcpy(m->coupling_barycentric, bary, sizeof bary);
    if ((st = fascia_model_set_provenance(ctx, m, "{\"tool\": \"fixture\", \"seed\": 7, \"note\": \"caf\xc3\xa9\"}")) !=
        FASCIA_OK)
      goto fail;
  }
  if ((st = fascia_model_build_reverse(ctx, m)) != FASCIA_OK) goto fail;
  *out = m;
  return FASCIA_OK;
fail:
  fascia_model_destroy(&m);
  return st;
}

/// Copies file from -> to (first `limit` bytes when limit >= 0). 0 on success.
static inline int fixture_copy(const char *from, const char *to, long limit) {
  FILE *in = fopen(from, "rb"), *out = fopen(to, "wb");
  int ok = in && out;
  char buf[4096];
  long done = 0;
  while (ok) {
    size_t want = sizeof buf;
    if (limit >= 0 && (long)want > limit - done) want = (size_t)(limit - done);
    const size_t n = want ? fread(buf, 1, want, in) : 0;
    if (!n) break;
    ok = fwrite(buf, 1, n, out) == n;
    done += (long)n;
  }
  if (in) fclose(in);
  if (out && fclose(out) != 0) ok = 0;
  return ok ? 0 : 1;
}

/// 1 if two files have identical bytes.
static inline int fixture_same_bytes(const char *a, const char *b) {
  FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
  int same = fa && fb;
  while (same) {
    const int ca = fgetc(fa), cb = fgetc(fb);
    if (ca != cb) same = 0;
    if (ca == EOF || cb == EOF) break;
  }
  if (fa) fclose(fa);
  if (fb) fclose(fb);
  return same;
}

/// Number of entries in folder dir whose name contains `part`.
static inline int fixture_count_files(const char *dir, const char *part) {
  DIR *d = opendir(dir);
  int count = 0;
  for (struct dirent *e; d && (e = readdir(d));)
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..") && strstr(e->d_name, part)) ++count;
  if (d) closedir(d);
  return count;
}

#define FIXTURE_DIFFERS_(a, b, count) ((count) > 0 && memcmp((a), (b), (size_t)(count) * sizeof *(a)) != 0)

/// The first field in which two models differ ("frame_position"), bit for
/// bit (doubles compared as bytes), or NULL when they hold the same: every
/// field a model file stores.
static inline const char *fixture_models_differ(const fascia_model *a, const fascia_model *b) {
  if (a->frame_count != b->frame_count || a->sample_count != b->sample_count || a->pair_count != b->pair_count ||
      a->material_count != b->material_count || a->motion_count != b->motion_count ||
      a->probe_count != b->probe_count || a->probe_pair_count != b->probe_pair_count ||
      a->organ_count != b->organ_count || a->coupling_count != b->coupling_count)
    return "sizes";
  const int64_t N = a->frame_count, S = a->sample_count, P = a->pair_count, Q = a->probe_count,
                R = a->probe_pair_count, C = a->coupling_count;
#define FIXTURE_FIELD_(f, count)                                                                                      \
  if (FIXTURE_DIFFERS_(a->f, b->f, count)) return #f
  FIXTURE_FIELD_(frame_position, 3 * N);
  FIXTURE_FIELD_(frame_rotation, 4 * N);
  FIXTURE_FIELD_(frame_kind, N);
  FIXTURE_FIELD_(frame_motion, N);
  FIXTURE_FIELD_(frame_load, 6 * N);
  FIXTURE_FIELD_(frame_organ, N);
  FIXTURE_FIELD_(frame_offsets, N + 1);
  FIXTURE_FIELD_(frame_pairs, P);
  FIXTURE_FIELD_(sample_position, 3 * S);
  FIXTURE_FIELD_(sample_volume, S);
  FIXTURE_FIELD_(sample_material, S);
  FIXTURE_FIELD_(sample_organ, S);
  FIXTURE_FIELD_(sample_patch, S);
  FIXTURE_FIELD_(sample_modes, S);
  FIXTURE_FIELD_(sample_offsets, S + 1);
  FIXTURE_FIELD_(pair_frame, P);
  FIXTURE_FIELD_(pair_weight, P);
  FIXTURE_FIELD_(pair_gradient, 3 * P);
  FIXTURE_FIELD_(probe_position, 3 * Q);
  FIXTURE_FIELD_(probe_offsets, Q + 1);
  FIXTURE_FIELD_(probe_frame, R);
  FIXTURE_FIELD_(probe_weight, R);
  FIXTURE_FIELD_(coupling_organ, C);
  FIXTURE_FIELD_(coupling_frame, C);
  FIXTURE_FIELD_(coupling_triangle, C);
  FIXTURE_FIELD_(coupling_barycentric, 3 * C);
  FIXTURE_FIELD_(gravity, 3);
#undef FIXTURE_FIELD_
  for (int64_t q = 0; q < Q; ++q)
    if (strcmp(a->probe_name[q], b->probe_name[q])) return "probe_name";
  for (int32_t k = 0; k < a->material_count; ++k) {
    const fascia_material *x = a->materials + k, *y = b->materials + k;
    const double vx[5] = {x->youngs_modulus, x->poisson_ratio, x->density, x->rotation_coupling, x->rotation_smoothing};
    const double vy[5] = {y->youngs_modulus, y->poisson_ratio, y->density, y->rotation_coupling, y->rotation_smoothing};
    if (strcmp(x->name, y->name) || x->law != y->law || x->part != y->part || memcmp(vx, vy, sizeof vx))
      return "materials";
  }
  for (int32_t k = 0; k < a->motion_count; ++k) {
    const fascia_motion *x = a->motions + k, *y = b->motions + k;
    if (strcmp(x->name, y->name) || x->key_count != y->key_count || FIXTURE_DIFFERS_(x->pivot, y->pivot, 3) ||
        FIXTURE_DIFFERS_(x->key_time, y->key_time, x->key_count) ||
        FIXTURE_DIFFERS_(x->key_translation, y->key_translation, 3 * x->key_count) ||
        FIXTURE_DIFFERS_(x->key_rotation, y->key_rotation, 4 * x->key_count))
      return "motions";
  }
  for (int32_t k = 0; k < a->organ_count; ++k) {
    const fascia_organ *x = a->organs + k, *y = b->organs + k;
    if (strcmp(x->name, y->name) || x->kind != y->kind || x->motion != y->motion ||
        x->vertex_count != y->vertex_count || x->triangle_count != y->triangle_count ||
        FIXTURE_DIFFERS_(x->vertices, y->vertices, 3 * x->vertex_count) ||
        FIXTURE_DIFFERS_(x->triangles, y->triangles, 3 * x->triangle_count))
      return "organs";
  }
  if ((a->allow_floating != 0) != (b->allow_floating != 0)) return "allow_floating";
  const fascia_surface *sa = &a->tissue_surface, *sb = &b->tissue_surface;
  if (sa->triangle_count != sb->triangle_count ||
      (sa->triangle_count > 0 && (sa->vertex_count != sb->vertex_count ||
                                  FIXTURE_DIFFERS_(sa->vertices, sb->vertices, 3 * sa->vertex_count) ||
                                  FIXTURE_DIFFERS_(sa->triangles, sb->triangles, 3 * sa->triangle_count))))
    return "tissue_surface";
  if (a->tetrahedron_count != b->tetrahedron_count ||
      FIXTURE_DIFFERS_(a->tetrahedra, b->tetrahedra, 4 * a->tetrahedron_count))
    return "tetrahedra";
  if ((a->provenance == NULL) != (b->provenance == NULL) ||
      (a->provenance && strcmp(a->provenance, b->provenance)))
    return "provenance";
  return NULL;
}

/// Removes every file in dir, then dir.
static inline void fixture_remove_dir(const char *dir) {
  DIR *d = opendir(dir);
  char path[1024];
  for (struct dirent *e; d && (e = readdir(d));)
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
      snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
      remove(path);
    }
  if (d) closedir(d);
  rmdir(dir);
}

#endif
