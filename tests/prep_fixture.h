// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Helpers of the prep tests (t5xx): a private temporary folder, box meshes
// written as OBJ files, scene text, and the whole pipeline in one call.
#ifndef FASCIA_TESTS_PREP_FIXTURE_H
#define FASCIA_TESTS_PREP_FIXTURE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fascia/fascia.h"
#include "fascia/prep.h"

/// A fresh folder under $TMPDIR (or /tmp) into dir[256]; 0 on failure.
static inline int fixture_tmpdir(char *dir) {
  const char *base = getenv("TMPDIR");
  snprintf(dir, 256, "%s/fascia-prep-XXXXXX", base && base[0] ? base : "/tmp");
  return mkdtemp(dir) != NULL;
}

/// Removes the files a test wrote (names relative to dir) and the folder.
static inline void fixture_cleanup(const char *dir, const char *const *names) {
  char path[512];
  for (int k = 0; names[k]; ++k) {
    snprintf(path, sizeof path, "%s/%s", dir, names[k]);
    remove(path);
  }
  rmdir(dir);
}

static inline int fixture_write(const char *dir, const char *name, const char *text) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "w");
  if (!f) return 0;
  fputs(text, f);
  return fclose(f) == 0;
}

/// An axis-aligned box [lo, hi] (m) as a closed, outward-oriented OBJ.
static inline int fixture_box(const char *dir, const char *name, const double *lo, const double *hi) {
  char text[2048];
  int n = 0;
  for (int c = 0; c < 8; ++c)
    n += snprintf(text + n, sizeof text - (size_t)n, "v %.9g %.9g %.9g\n", (c & 1) ? hi[0] : lo[0],
                  (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]);
  // two outward triangles per face (OBJ indices from 1)
  static const int quads[6][4] = {{1, 3, 7, 5}, {2, 6, 8, 4}, {1, 5, 6, 2}, {3, 4, 8, 7}, {1, 2, 4, 3}, {5, 7, 8, 6}};
  for (int f = 0; f < 6; ++f)
    n += snprintf(text + n, sizeof text - (size_t)n, "f %d %d %d\nf %d %d %d\n", quads[f][0], quads[f][1],
                  quads[f][2], quads[f][0], quads[f][2], quads[f][3]);
  return fixture_write(dir, name, text);
}

/// The two-organ layout of several prep tests: box A ends at x = -face, box
/// B starts at x = +face (20 x 20.4 x 20.4 mm each), written as a.obj and
/// b.obj; with scene text also scene.json, whose path goes into
/// path[512]. 0 on failure.
static inline int fixture_two_boxes(const char *dir, double face, const char *scene, char *path) {
  const double a_lo[3] = {-0.02, -0.0102, -0.0102}, a_hi[3] = {-face, 0.0102, 0.0102};
  const double b_lo[3] = {face, -0.0102, -0.0102}, b_hi[3] = {0.02, 0.0102, 0.0102};
  if (!fixture_box(dir, "a.obj", a_lo, a_hi) || !fixture_box(dir, "b.obj", b_lo, b_hi)) return 0;
  if (!scene) return 1;
  snprintf(path, 512, "%s/scene.json", dir);
  return fixture_write(dir, "scene.json", scene);
}

/// How far a model's weights are from what the mechanics needs, over all
/// samples: worst[0] |sum w - 1|, worst[1] |sum w x_i - p| (m), worst[2]
/// |sum grad w| (at mm scale: gradients go as 1/spacing) and
/// |sum x_i (x) grad w - I|.
static inline void fixture_weight_errors(const fascia_model *m, double worst[3]) {
  worst[0] = worst[1] = worst[2] = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    double w = 0, g[3] = {0, 0, 0}, p[3] = {0, 0, 0}, G[9] = {0};
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k) {
      const double *x = m->frame_position + 3 * m->pair_frame[k], *dw = m->pair_gradient + 3 * k;
      w += m->pair_weight[k];
      for (int a = 0; a < 3; ++a) {
        g[a] += dw[a];
        p[a] += m->pair_weight[k] * x[a];
        for (int b = 0; b < 3; ++b) G[3 * a + b] += x[a] * dw[b];
      }
    }
    worst[0] = fmax(worst[0], fabs(w - 1));
    for (int a = 0; a < 3; ++a) {
      worst[1] = fmax(worst[1], fabs(p[a] - m->sample_position[3 * s + a]));
      worst[2] = fmax(worst[2], fabs(g[a]) * 1e-3);
      for (int b = 0; b < 3; ++b) worst[2] = fmax(worst[2], fabs(G[3 * a + b] - (a == b)));
    }
  }
}

/// Everything the pipeline builds.
/// Every stage's output (fascia_prep_stages).
typedef fascia_prep_stages fixture_run;

/// 1 when every 26-connected piece of the region with this label has voxels
/// next to (26 neighbours) the insides of at least `need` different organs
/// (of at most 64); *pieces counts them. A tissue piece that bridges two
/// organs touches both; a sheet floating between them touches neither.
static inline int fixture_pieces_touch(const fascia_prep_volume *v, int label, int need, int *pieces) {
  const int32_t nx = v->dims[0], ny = v->dims[1], nz = v->dims[2];
  const int64_t n = (int64_t)nx * ny * nz;
  int64_t *queue = (int64_t *)malloc((size_t)n * sizeof *queue);
  uint8_t *seen = (uint8_t *)calloc((size_t)n, 1);
  int ok = queue && seen && v->organ_count <= 64;
  *pieces = 0;
  for (int64_t s = 0; ok && s < n; ++s) {
    if (v->region[s] != label || seen[s]) continue;
    int64_t head = 0, tail = 0;
    uint64_t touched = 0;
    queue[tail++] = s, seen[s] = 1;
    ++*pieces;
    while (head < tail) {
      const int64_t w = queue[head++];
      const int32_t x = (int32_t)(w % nx), y = (int32_t)(w / nx % ny), z = (int32_t)(w / ((int64_t)nx * ny));
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int32_t X = x + dx, Y = y + dy, Z = z + dz;
            if (X < 0 || Y < 0 || Z < 0 || X >= nx || Y >= ny || Z >= nz) continue;
            const int64_t m = X + (int64_t)nx * (Y + (int64_t)ny * Z);
            for (int32_t o = 0; o < v->organ_count; ++o)
              if (v->distance[o] && v->distance[o][m] <= 0) touched |= (uint64_t)1 << o;
            if (v->region[m] == label && !seen[m]) seen[m] = 1, queue[tail++] = m;
          }
    }
    int count = 0;
    for (int32_t o = 0; o < v->organ_count; ++o) count += (int)((touched >> o) & 1);
    if (count < need) {
      fprintf(stderr, "a piece of %lld voxels touches %d organ(s), fewer than %d\n", (long long)tail, count, need);
      ok = 0;
    }
  }
  free(queue);
  free(seen);
  return ok;
}

/// Runs every stage on the scene file at path; stops at the first error.
static inline fascia_status fixture_prep(fascia_ctx *ctx, const char *path, fixture_run *r) {
  return fascia_prep_stages_run(ctx, path, NULL, r);
}

static inline void fixture_free(fixture_run *r) { fascia_prep_stages_free(r); }

static inline fascia_ctx *fixture_ctx(void) {
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  fascia_ctx_create(&def, &ctx);
  return ctx;
}

#endif
