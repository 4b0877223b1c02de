// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Helpers of the prep tests (t5xx): a private temporary folder, box meshes
// written as OBJ files, scene text, and the whole pipeline in one call.
#ifndef FASCIA_TESTS_PREP_FIXTURE_H
#define FASCIA_TESTS_PREP_FIXTURE_H

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

/// Everything the pipeline builds.
typedef struct fixture_run {
  fascia_prep_scene *scene;
  fascia_prep_meshes *meshes;
  fascia_prep_volume *volume;
  fascia_prep_points *points;
  fascia_prep_weights *weights;
  fascia_prep_coupling *coupling;
  fascia_model *model;
} fixture_run;

/// Runs every stage on the scene file at path; stops at the first error.
static inline fascia_status fixture_prep(fascia_ctx *ctx, const char *path, fixture_run *r) {
  memset(r, 0, sizeof *r);
  fascia_status st = fascia_prep_scene_load(ctx, path, &r->scene);
  if (!st) st = fascia_prep_import(ctx, r->scene, &r->meshes);
  if (!st) st = fascia_prep_repair(ctx, r->scene, r->meshes);
  if (!st) st = fascia_prep_voxelize(ctx, r->scene, r->meshes, &r->volume);
  if (!st) st = fascia_prep_sample(ctx, r->scene, r->meshes, r->volume, &r->points);
  if (!st) st = fascia_prep_shape_functions(ctx, r->scene, r->volume, r->points, &r->weights);
  if (!st) st = fascia_prep_couple(ctx, r->scene, r->meshes, r->points, &r->coupling);
  if (!st)
    st = fascia_prep_package(ctx, r->scene, r->meshes, r->volume, r->points, r->weights, r->coupling, NULL,
                             &r->model);
  return st;
}

static inline void fixture_free(fixture_run *r) {
  fascia_model_destroy(&r->model);
  fascia_prep_coupling_destroy(&r->coupling);
  fascia_prep_weights_destroy(&r->weights);
  fascia_prep_points_destroy(&r->points);
  fascia_prep_volume_destroy(&r->volume);
  fascia_prep_meshes_destroy(&r->meshes);
  fascia_prep_scene_destroy(&r->scene);
}

static inline fascia_ctx *fixture_ctx(void) {
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  fascia_ctx_create(&def, &ctx);
  return ctx;
}

#endif
