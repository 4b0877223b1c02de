// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The same scene prepared again in one build gives the same model, bit for
// bit, whatever the heap looks like: a hollow organ as a shell (a closed
// sphere, and an open bowl with free edges), prepared three times in one
// process with different blocks held on the heap around each run, every
// numeric array of the model (contract/model_table.h) compared byte for byte
// with the first run's, and the model file's checksum too. Libraries that
// order their results by memory address (CGAL's advancing-front surface
// reconstruction does) show here as a difference in the wall's samples.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "model/model_arrays.h"
#include "prep_fixture.h"

#define RUNS 3

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 3, \"gravity\": [0, 0, -9.81],\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3},\n"
    "               \"wall\": {\"youngs_modulus\": 30000, \"poisson_ratio\": 0.45}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"%s\", \"model\": \"shell\", \"material\": \"wall\",\n"
    "               \"thickness\": 0.001, \"frame_spacing\": %s%s}],\n"
    " \"tissues\": [{\"name\": \"t\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008, \"material\": \"soft\",\n"
    "               \"frame_spacing\": 0.003, \"sample_spacing\": 0.0015}]}\n";

// Blocks of the sizes a triangulation's small records have, some freed
// again: run r leaves the allocator's free lists in a shape of its own.
typedef struct heap_noise {
  void **blocks;
  int count;
} heap_noise;
static heap_noise make_noise(int run) {
  heap_noise h = {NULL, 400 + 1500 * run};
  h.blocks = calloc((size_t)h.count, sizeof *h.blocks);
  uint32_t state = 12345u + 977u * (uint32_t)run;
  for (int k = 0; h.blocks && k < h.count; ++k) {
    state = state * 1664525u + 1013904223u;
    h.blocks[k] = malloc(16 + (state >> 8) % 300);
  }
  for (int k = 0; h.blocks && k < h.count; k += 2 + run) free(h.blocks[k]), h.blocks[k] = NULL;
  return h;
}
static void free_noise(heap_noise *h) {
  for (int k = 0; h->blocks && k < h->count; ++k) free(h->blocks[k]);
  free(h->blocks);
}

// 0 when every REAL and INT array of b equals a's; else names the first
// difference of each array that has one.
static int compare_models(const fascia_model *a, const fascia_model *b, const char *what, int run) {
  fascia_model_view va[FASCIA_MA_COUNT], vb[FASCIA_MA_COUNT];
  fascia_model_views(a, va);
  fascia_model_views(b, vb);
  int differ = 0;
  for (int k = 0; k < FASCIA_MA_COUNT; ++k) {
    const fascia_model_array *row = va[k].array;
    if (row->kind != FASCIA_MA_REAL && row->kind != FASCIA_MA_INT) continue;
    if (va[k].rows != vb[k].rows) {
      fprintf(stderr, "%s run %d %s: %lld rows, the first run %lld\n", what, run, row->path, (long long)vb[k].rows,
              (long long)va[k].rows);
      ++differ;
      continue;
    }
    const size_t value = fascia_model_array_size(row->kind), bytes = fascia_model_view_bytes(va + k);
    if (!bytes || !memcmp(va[k].data, vb[k].data, bytes)) continue;
    size_t e = 0, count = 0;
    for (size_t j = 0; j < bytes / value; ++j)
      if (memcmp((const char *)va[k].data + j * value, (const char *)vb[k].data + j * value, value))
        e = count++ ? e : j;
    const double x = row->kind == FASCIA_MA_REAL ? ((const fascia_real *)va[k].data)[e]
                                                 : ((const int32_t *)va[k].data)[e],
                 y = row->kind == FASCIA_MA_REAL ? ((const fascia_real *)vb[k].data)[e]
                                                 : ((const int32_t *)vb[k].data)[e];
    fprintf(stderr, "%s run %d %s: %zu of %zu values differ from the first run's, first at value %zu: %.17g vs %.17g\n",
            what, run, row->path, count, bytes / value, e, y, x);
    ++differ;
  }
  return differ;
}

static int check_case(const char *dir, const char *mesh, const char *spacing, const char *extra) {
  char text[4096];
  snprintf(text, sizeof text, scene_format, mesh, spacing, extra);
  fixture_run runs[RUNS];
  memset(runs, 0, sizeof runs);
  fascia_ctx *ctx = fixture_ctx();
  int ok = ctx != NULL;
  for (int run = 0; ok && run < RUNS; ++run) {
    heap_noise noise = make_noise(run);
    const fascia_status st = fixture_prep_text(ctx, dir, text, runs + run);
    if (st != FASCIA_OK) fprintf(stderr, "%s run %d: %s\n", mesh, run, fascia_ctx_message(ctx));
    ok = st == FASCIA_OK && runs[run].model;
    free_noise(&noise);
  }
  for (int run = 1; ok && run < RUNS; ++run) {
    CHECK(compare_models(runs[0].model, runs[run].model, mesh, run) == 0);
    CHECK(fascia_model_hash_rows(1, runs[0].model, 1) == fascia_model_hash_rows(1, runs[run].model, 1));
  }
  for (int run = 0; run < RUNS; ++run) fixture_free(runs + run);
  fascia_ctx_destroy(&ctx);
  return ok;
}

int main(void) {
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  const double a_lo[3] = {-0.02, -0.02, -0.02}, a_hi[3] = {0, 0.02, 0.02};
  const double centre[3] = {0.015, 0, 0};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && fixture_icosphere(dir, "b.obj", centre, 0.01, 3, 0) &&
        fixture_icosphere(dir, "bowl.obj", centre, 0.01, 3, 1));
  // a closed wall; an open one, its free edge held (border frames first)
  CHECK(check_case(dir, "b.obj", "0.004", ""));
  CHECK(check_case(dir, "bowl.obj", "0.0025",
                   ", \"hold\": {\"box\": {\"min\": [0, -0.02, -0.0005], \"max\": [0.03, 0.02, 0.0005]}}"));
  static const char *const files[] = {"a.obj", "b.obj", "bowl.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
