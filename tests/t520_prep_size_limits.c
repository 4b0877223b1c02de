// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A scene whose voxel grid would be absurdly large (a 1 m gap at a voxel
// size of 10 micrometres: about 1e17 voxels) is refused by voxelize before
// anything is allocated, with a message naming voxel_size, the voxels it
// would need and the voxel size that fits; a sane voxel size passes.
#define _POSIX_C_SOURCE 200809L
#include <time.h>

#include "check.h"
#include "prep_fixture.h"

static fascia_status voxelize(fascia_ctx *ctx, const char *dir, const char *voxel_size, double *seconds) {
  char text[2048], path[512];
  snprintf(text, sizeof text,
           "{\"fascia_scene\": 1, \"voxel_size\": %s,\n"
           " \"materials\": {\"m\": {\"law\": \"stvk\", \"youngs_modulus\": 1000, \"poisson_ratio\": 0.3, "
           "\"density\": 1000}},\n"
           " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\"}, {\"name\": \"B\", \"mesh\": \"b.obj\"}],\n"
           " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 1.5, \"material\": \"m\",\n"
           "               \"frame_spacing\": 0.5, \"sample_spacing\": 0.25}]}\n",
           voxel_size);
  if (!fixture_write(dir, "scene.json", text)) return FASCIA_ERR_IO;
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_prep_scene *scene = NULL;
  fascia_prep_meshes *meshes = NULL;
  fascia_prep_volume *volume = NULL;
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  fascia_status st = fascia_prep_scene_load(ctx, path, &scene);
  if (!st) st = fascia_prep_import(ctx, scene, &meshes);
  if (!st) st = fascia_prep_voxelize(ctx, scene, meshes, &volume);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  *seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
  fascia_prep_volume_destroy(&volume);
  fascia_prep_meshes_destroy(&meshes);
  fascia_prep_scene_destroy(&scene);
  return st;
}

int main(void) {
  char dir[256];
  CHECK(fixture_tmpdir(dir));
  const double a_lo[3] = {0, 0, 0}, a_hi[3] = {1, 1, 1}, b_lo[3] = {2, 0, 0}, b_hi[3] = {3, 1, 1};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi));
  CHECK(fixture_box(dir, "b.obj", b_lo, b_hi));
  fascia_ctx *ctx = fixture_ctx();
  CHECK(ctx != NULL);
  double seconds = 0;
  const fascia_status st = voxelize(ctx, dir, "1e-5", &seconds);
  const char *message = fascia_ctx_message(ctx);
  CHECK(st == FASCIA_ERR_ARGUMENT);
  CHECK(strstr(message, "voxel_size") != NULL);
  CHECK(strstr(message, "voxels") != NULL && strstr(message, "GiB") != NULL);
  CHECK(strstr(message, "set voxel_size to at least") != NULL);
  CHECK(seconds < 5); // refused up front, not after filling memory
  if (CHECK_RESULT()) fprintf(stderr, "status %s, message: %s\n", fascia_status_name(st), message);
  // the same scene at a sane voxel size voxelizes
  fascia_ctx_clear(ctx);
  const fascia_status ok = voxelize(ctx, dir, "0.1", &seconds);
  CHECK(ok == FASCIA_OK);
  if (ok != FASCIA_OK) fprintf(stderr, "voxel size 0.1: %s\n", fascia_ctx_message(ctx));
  fascia_ctx_destroy(&ctx);
  static const char *const names[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, names);
  return CHECK_RESULT();
}
