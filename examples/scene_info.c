// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The preprocessing library from a program of your own (fascia::prep): reads
// and checks a scene file and prints its organs and tissues.
//
//   scene_info SCENE.json
#include <stdio.h>

#include <fascia/fascia.h>
#include <fascia/prep.h>

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: scene_info SCENE.json\n");
    return 2;
  }
  fascia_ctx *ctx = NULL;
  fascia_ctx_def cd = fascia_ctx_def_default();
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  fascia_prep_scene *scene = NULL;
  if (fascia_prep_scene_load(ctx, argv[1], &scene) != FASCIA_OK) {
    fprintf(stderr, "scene_info: %s\n", fascia_ctx_message(ctx));
    fascia_ctx_destroy(&ctx);
    return 1;
  }
  printf("scene: %s\n", scene->path);
  printf("voxel_size_m: %g\n", scene->voxel_size);
  printf("organs: %d\n", (int)scene->organ_count);
  for (int32_t o = 0; o < scene->organ_count; ++o)
    printf("organ: %s (%s)\n", scene->organs[o].name, scene->organs[o].mesh_path);
  printf("tissues: %d\n", (int)scene->tissue_count);
  fascia_prep_scene_destroy(&scene);
  fascia_ctx_destroy(&ctx);
  return 0;
}
