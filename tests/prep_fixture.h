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

/// Writes text as dir/scene.json and runs every stage on it.
static inline fascia_status fixture_prep_text(fascia_ctx *ctx, const char *dir, const char *text, fixture_run *r) {
  char path[512];
  snprintf(path, sizeof path, "%s/scene.json", dir);
  if (!fixture_write(dir, "scene.json", text)) return FASCIA_ERR_IO;
  return fixture_prep(ctx, path, r);
}

static inline fascia_ctx *fixture_ctx(void) {
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  fascia_ctx_create(&def, &ctx);
  return ctx;
}

/// Writes an icosphere of the given radius about centre as OBJ file dir/name:
/// the icosahedron refined `levels` times (20 4^levels triangles), each new
/// vertex put on the sphere; lower_half keeps only the triangles wholly at
/// or below the centre's z (an open bowl). 1 on success.
static inline int fixture_icosphere(const char *dir, const char *name, const double *centre, double radius, int levels,
                                    int lower_half) {
  int nt = 20, nv = 12, mt = 20, mv = 12;
  for (int l = 0; l < levels; ++l) mt *= 4, mv = 4 * mv - 6;
  double *v = (double *)malloc(3 * sizeof(double) * (size_t)mv);
  int *t = (int *)malloc(3 * sizeof(int) * (size_t)mt), *t2 = (int *)malloc(3 * sizeof(int) * (size_t)mt);
  int *number = (int *)calloc((size_t)mv, sizeof(int));
  char *text = (char *)malloc(96 * ((size_t)mv + (size_t)mt) + 1);
  int ok = v && t && t2 && number && text;
  const double g = (1 + sqrt(5.0)) / 2;
  const double v0[12][3] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                            {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  const int t0[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                         {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                         {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int i = 0; ok && i < 12; ++i) {
    const double len = sqrt(v0[i][0] * v0[i][0] + v0[i][1] * v0[i][1] + v0[i][2] * v0[i][2]);
    for (int r = 0; r < 3; ++r) v[3 * i + r] = v0[i][r] / len;
  }
  for (int k = 0; ok && k < 20; ++k)
    for (int r = 0; r < 3; ++r) t[3 * k + r] = t0[k][r];
  for (int level = 0; ok && level < levels; ++level) {
    int n2 = 0;
    for (int k = 0; k < nt; ++k) {
      int mid[3];
      for (int e = 0; e < 3; ++e) {
        const int a = t[3 * k + e], b = t[3 * k + (e + 1) % 3];
        double p[3];
        for (int r = 0; r < 3; ++r) p[r] = 0.5 * (v[3 * a + r] + v[3 * b + r]);
        const double len = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        for (int r = 0; r < 3; ++r) p[r] /= len;
        int found = -1; // midpoints are shared by two triangles: look them up
        for (int i = 0; i < nv && found < 0; ++i)
          if (fabs(v[3 * i] - p[0]) + fabs(v[3 * i + 1] - p[1]) + fabs(v[3 * i + 2] - p[2]) < 1e-12) found = i;
        if (found < 0) {
          memcpy(v + 3 * nv, p, sizeof p);
          found = nv++;
        }
        mid[e] = found;
      }
      const int c[4][3] = {{t[3 * k], mid[0], mid[2]}, {mid[0], t[3 * k + 1], mid[1]},
                           {mid[2], mid[1], t[3 * k + 2]}, {mid[0], mid[1], mid[2]}};
      for (int j = 0; j < 4; ++j, ++n2)
        for (int r = 0; r < 3; ++r) t2[3 * n2 + r] = c[j][r];
    }
    nt = n2;
    memcpy(t, t2, 3 * sizeof(int) * (size_t)nt);
  }
  int kept = 0, count = 0;
  size_t n = 0;
  for (int k = 0; ok && k < nt; ++k) {
    if (lower_half && (v[3 * t[3 * k] + 2] > 1e-9 || v[3 * t[3 * k + 1] + 2] > 1e-9 || v[3 * t[3 * k + 2] + 2] > 1e-9))
      continue;
    for (int r = 0; r < 3; ++r) number[t[3 * k + r]] = 1, t[3 * kept + r] = t[3 * k + r];
    ++kept;
  }
  for (int i = 0; ok && i < nv; ++i) {
    if (!number[i]) continue;
    number[i] = ++count;
    n += (size_t)sprintf(text + n, "v %.9f %.9f %.9f\n", centre[0] + radius * v[3 * i], centre[1] + radius * v[3 * i + 1],
                         centre[2] + radius * v[3 * i + 2]);
  }
  for (int k = 0; ok && k < kept; ++k)
    n += (size_t)sprintf(text + n, "f %d %d %d\n", number[t[3 * k]], number[t[3 * k + 1]], number[t[3 * k + 2]]);
  ok = ok && fixture_write(dir, name, text);
  free(v), free(t), free(t2), free(number), free(text);
  return ok;
}

/// Prepares the scene at path into *r and solves its static equilibrium at
/// time 1 on one CPU thread; force: the tissue's force on organ `organ`
/// (model order), N. 1 on success, else 0 with the message on stderr.
static inline int fixture_prep_static(const char *path, int32_t organ, fixture_run *r, double force[3]) {
  fascia_ctx *ctx = fixture_ctx();
  int ok = ctx && fixture_prep(ctx, path, r) == FASCIA_OK;
  fascia_solver *solver = NULL;
  fascia_solver_def def = fascia_solver_def_default();
  def.backend = "cpu";
  def.threads = 1;
  def.newton_iterations = 100;
  fascia_solve_report report;
  ok = ok && fascia_solver_create(ctx, r->model, &def, &solver) == FASCIA_OK &&
       fascia_solver_set_time(solver, 1) == FASCIA_OK && fascia_solver_solve_static(solver, &report) == FASCIA_OK;
  fascia_real f[3] = {0, 0, 0}, torque[3], point[3];
  ok = ok && fascia_solver_organ_wrench(solver, organ, f, torque, point) == FASCIA_OK;
  for (int c = 0; c < 3; ++c) force[c] = f[c];
  if (!ok) fprintf(stderr, "%s: %s\n", path, ctx ? fascia_ctx_message(ctx) : "no context");
  fascia_solver_destroy(&solver);
  fascia_ctx_destroy(&ctx);
  return ok;
}

#endif
