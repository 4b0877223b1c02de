// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Meshless neighbours found locally. Two boxes with the tissue wrapped
// around their edges (so some frames hide behind a corner): every sample's
// frames are its nearest through the region, checked against a plain
// Dijkstra search written here; the stage reports its progress sample by
// sample; and at finer voxels its cost stays with the samples and their
// neighbourhoods (CPU time well below the voxelization's) instead of
// growing with the voxels of every neighbourhood.
#define _POSIX_C_SOURCE 200809L // mkdtemp, clock_gettime
#include <time.h>

#include "check.h"
#include "prep_fixture.h"

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": %g, \"seed\": 7,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"fixed\"}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008, \"material\": \"soft\",\n"
    "  \"frame_spacing\": 0.003, \"sample_spacing\": 0.0015,\n"
    "  \"shape_functions\": {\"kind\": \"mls\", \"neighbours\": 8}}]}\n";

typedef struct progress_log {
  int calls, between; // calls for the stage; with 0 < fraction < 1
} progress_log;

static void on_progress(void *user, const char *stage, double fraction, const char *detail) {
  (void)detail;
  progress_log *log = user;
  if (strcmp(stage, "shape functions") != 0) return;
  log->calls++;
  log->between += fraction > 0 && fraction < 1;
}

static double cpu_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double distance3(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// Dijkstra over the 26-neighbourhood of sample s's region voxels (as the
// stage defines the distance): the chosen frames must be reached no later
// than any frame left out. Returns the number of samples that break it.
static int check_neighbours(const fascia_prep_volume *v, const fascia_prep_points *p, const fascia_prep_weights *w) {
  const int64_t nx = v->dims[0], ny = v->dims[1], nz = v->dims[2], n = nx * ny * nz;
  const double h = v->voxel_size;
  double *dist = malloc((size_t)n * sizeof(double)), *frame_dist = malloc((size_t)p->frame_count * sizeof(double));
  int64_t *heap_v = malloc((size_t)(27 * n + 1) * sizeof(int64_t));
  double *heap_k = malloc((size_t)(27 * n + 1) * sizeof(double));
  int32_t *head = malloc((size_t)n * sizeof(int32_t)), *next = malloc((size_t)(2 * p->frame_count) * sizeof(int32_t));
  int bad = 0;
  if (!dist || !frame_dist || !heap_v || !heap_k || !head || !next) return -1;
  for (int64_t k = 0; k < n; ++k) head[k] = -1;
  for (int32_t i = 0; i < p->frame_count; ++i) { // attachment 2i: frame voxel, 2i + 1: organ voxel
    const int64_t at[2] = {p->frame_voxel[i], p->frame_organ_voxel[i]};
    for (int k = 0; k < 2; ++k)
      if (at[k] >= 0) next[2 * i + k] = head[at[k]], head[at[k]] = 2 * i + k;
  }
  for (int32_t s = 0; s < p->sample_count; ++s) {
    for (int64_t k = 0; k < n; ++k) dist[k] = INFINITY;
    for (int32_t i = 0; i < p->frame_count; ++i) frame_dist[i] = INFINITY;
    const int64_t start = p->sample_voxel[s];
    const uint8_t label = v->region[start];
    double chosen_far = 0, c[3];
    int32_t reached = 0;
    const int32_t m = w->sample_offsets[s + 1] - w->sample_offsets[s];
    int64_t size = 0;
    const double *ps = p->sample_position + 3 * (int64_t)s;
    for (int r = 0; r < 3; ++r) c[r] = v->origin[r] + h * (double)(r == 0 ? start % nx : r == 1 ? start / nx % ny : start / (nx * ny));
    dist[start] = distance3(ps, c);
    heap_v[size] = start, heap_k[size++] = dist[start];
    while (size > 0) {
      // pop the smallest (binary heap)
      const int64_t u = heap_v[0];
      const double key = heap_k[0];
      --size;
      int64_t at = 0;
      while (1) {
        int64_t child = 2 * at + 1;
        if (child >= size) break;
        if (child + 1 < size && heap_k[child + 1] < heap_k[child]) ++child;
        if (heap_k[size] <= heap_k[child]) break;
        heap_k[at] = heap_k[child], heap_v[at] = heap_v[child], at = child;
      }
      heap_k[at] = heap_k[size], heap_v[at] = heap_v[size];
      if (key > dist[u]) continue;
      if (reached == m && key > chosen_far * (1 + 1e-9)) break;
      const int32_t ui = (int32_t)(u % nx), uj = (int32_t)(u / nx % ny), uk = (int32_t)(u / (nx * ny));
      const double cu[3] = {v->origin[0] + h * ui, v->origin[1] + h * uj, v->origin[2] + h * uk};
      for (int32_t a = head[u]; a >= 0; a = next[a]) {
        const int32_t i = a / 2;
        const double d = key + distance3(p->frame_position + 3 * (int64_t)i, cu);
        if (d < frame_dist[i]) frame_dist[i] = d;
      }
      // the chosen frames reached so far and the farthest of them
      reached = 0;
      chosen_far = 0;
      for (int32_t k = w->sample_offsets[s]; k < w->sample_offsets[s + 1]; ++k)
        if (frame_dist[w->pair_frame[k]] < INFINITY) ++reached, chosen_far = fmax(chosen_far, frame_dist[w->pair_frame[k]]);
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int32_t x = ui + dx, y = uj + dy, z = uk + dz;
            if (x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz) continue;
            const int64_t nb = x + nx * (y + ny * (int64_t)z);
            if (v->region[nb] != label) continue;
            const double d = key + h * sqrt((double)(dx * dx + dy * dy + dz * dz));
            if (d < dist[nb]) {
              dist[nb] = d;
              int64_t up = size++;
              while (up > 0 && heap_k[(up - 1) / 2] > d)
                heap_k[up] = heap_k[(up - 1) / 2], heap_v[up] = heap_v[(up - 1) / 2], up = (up - 1) / 2;
              heap_k[up] = d, heap_v[up] = nb;
            }
          }
    }
    // no frame left out may be nearer than the farthest chosen one
    int wrong = reached != m;
    for (int32_t i = 0; i < p->frame_count && !wrong; ++i) {
      int chosen = 0;
      for (int32_t k = w->sample_offsets[s]; k < w->sample_offsets[s + 1]; ++k) chosen |= w->pair_frame[k] == i;
      wrong = !chosen && frame_dist[i] < chosen_far * (1 - 1e-9);
    }
    if (wrong && bad < 5) fprintf(stderr, "sample %d: its %d frames are not its nearest through the region\n", (int)s, (int)m);
    bad += wrong;
  }
  free(dist), free(frame_dist), free(heap_v), free(heap_k), free(head), free(next);
  return bad;
}

static int run(const char *dir, double h, int check, double *sf_cpu, double *vox_cpu) {
  char text[4096], path[512];
  snprintf(text, sizeof text, scene_format, h);
  CHECK(fixture_write(dir, "scene.json", text));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  progress_log log = {0, 0};
  fascia_ctx_def def = fascia_ctx_def_default();
  def.threads = 1; // CPU times of one thread
  def.progress = on_progress;
  def.progress_user = &log;
  fascia_ctx *ctx = NULL;
  CHECK(fascia_ctx_create(&def, &ctx) == FASCIA_OK);
  fixture_run r;
  memset(&r, 0, sizeof r);
  CHECK_OK(fascia_prep_scene_load(ctx, path, &r.scene), ctx);
  CHECK_OK(fascia_prep_import(ctx, r.scene, &r.meshes), ctx);
  CHECK_OK(fascia_prep_repair(ctx, r.scene, r.meshes), ctx);
  double t0 = cpu_seconds();
  CHECK_OK(fascia_prep_voxelize(ctx, r.scene, r.meshes, &r.volume), ctx);
  double t1 = cpu_seconds();
  CHECK_OK(fascia_prep_sample(ctx, r.scene, r.meshes, r.volume, &r.points), ctx);
  double t2 = cpu_seconds();
  CHECK_OK(fascia_prep_shape_functions(ctx, r.scene, r.volume, r.points, &r.weights), ctx);
  double t3 = cpu_seconds();
  *vox_cpu = t1 - t0;
  *sf_cpu = t3 - t2;
  // progress while the samples are worked through, not only at the ends
  CHECK(log.between >= 10);
  if (check) CHECK(check_neighbours(r.volume, r.points, r.weights) == 0);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return 0;
}

int main(void) {
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  // the fixture's boxes with the whole space within max_gap of both as the
  // tissue: a slab between the faces that wraps around the boxes' edges
  CHECK(fixture_two_boxes(dir, 0.0031, NULL, NULL));
  double sf, vox;
  int failed = run(dir, 0.0006, 1, &sf, &vox);
  failed |= run(dir, 0.0003, 0, &sf, &vox);
  if (!(sf < 0.5 * vox + 0.05))
    fprintf(stderr, "shape functions at 0.3 mm voxels: %.2f s CPU, voxelize %.2f s\n", sf, vox);
  CHECK(sf < 0.5 * vox + 0.05);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return failed || CHECK_RESULT();
}
