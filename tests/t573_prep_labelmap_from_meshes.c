// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The same geometry through both of prep's paths (docs/labelmaps.md): a
// shipped mesh scene is prepared, its organs written as a label map
// (fascia_prep_labelmap_write), and the scene prepared again with every
// organ made of its label, unsmoothed. The first organ's inside voxels are
// its mesh's, voxel for voxel (the affine places the map on the scene's
// lattice), and each tissue's volume is within one voxel layer of its faces
// against the organs of the mesh scene's. The label table is written
// beside the map.
//
// Usage: t573_prep_labelmap_from_meshes SCENE.json (a scene of mesh organs)
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <cjson/cJSON.h>
#include <math.h>

#include "check.h"
#include "prep_fixture.h"

// The scene text with each organ made of its label in organs.nii.gz; NULL on error.
static char *label_scene(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  char text[1 << 16];
  const size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  text[n] = 0;
  cJSON *root = cJSON_Parse(text);
  if (!root) return NULL;
  cJSON *seg = cJSON_AddObjectToObject(root, "segmentation");
  cJSON_AddStringToObject(seg, "file", "organs.nii.gz");
  cJSON_AddStringToObject(seg, "labels", "organs.tsv");
  cJSON_AddNumberToObject(seg, "smoothing", 0);
  cJSON_DeleteItemFromObject(root, "output");
  cJSON *organ;
  cJSON_ArrayForEach(organ, cJSON_GetObjectItem(root, "organs")) {
    const char *const mesh_keys[] = {"mesh", "parts", "units", "transform"};
    for (int k = 0; k < 4; ++k) cJSON_DeleteItemFromObject(organ, mesh_keys[k]);
    cJSON_AddStringToObject(organ, "labels", cJSON_GetObjectItem(organ, "name")->valuestring);
  }
  char *out = cJSON_Print(root);
  cJSON_Delete(root);
  return out;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s SCENE.json\n", argv[0]);
    return 2;
  }
  char dir[256], map[512], table[512], scene[512];
  CHECK(fixture_tmpdir(dir));
  snprintf(map, sizeof map, "%s/organs.nii.gz", dir);
  snprintf(scene, sizeof scene, "%s/labels.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run mesh, labels;
  CHECK_OK(fixture_prep(ctx, argv[1], &mesh), ctx);
  CHECK_OK(fascia_prep_labelmap_write(ctx, mesh.scene, mesh.meshes, map, table, sizeof table), ctx);
  CHECK(!strcmp(table + strlen(table) - 11, "/organs.tsv"));
  char *text = label_scene(argv[1]);
  CHECK(text && fixture_write(dir, "labels.json", text));
  free(text);
  CHECK_OK(fixture_prep(ctx, scene, &labels), ctx);
  if (!CHECK_RESULT() && labels.volume) {
    const double h = mesh.volume->voxel_size;
    // the first organ keeps all its voxels (an overlap goes to the organ listed first)
    // unsmoothed, a label organ's surface runs along the faces of its voxels, so the voxel centres inside
    // it are those inside its mesh: the first organ's (an overlap goes to the organ listed first) agree
    // wherever the two runs' grids meet, and a map placed off by a voxel would not
    const fascia_prep_volume *va = mesh.volume, *vb = labels.volume;
    int64_t compared = 0, differ = 0;
    for (int32_t k = 0; k < va->dims[2]; ++k)
      for (int32_t j = 0; j < va->dims[1]; ++j)
        for (int32_t i = 0; i < va->dims[0]; ++i) {
          const int32_t c[3] = {i + va->lattice[0] - vb->lattice[0], j + va->lattice[1] - vb->lattice[1],
                                k + va->lattice[2] - vb->lattice[2]};
          if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= vb->dims[0] || c[1] >= vb->dims[1] || c[2] >= vb->dims[2])
            continue;
          const int in_a = va->distance[0][i + (int64_t)va->dims[0] * (j + (int64_t)va->dims[1] * k)] <= 0;
          const int in_b = vb->distance[0][c[0] + (int64_t)vb->dims[0] * (c[1] + (int64_t)vb->dims[1] * c[2])] <= 0;
          ++compared, differ += in_a != in_b;
        }
    printf("organ '%s': %lld voxels compared, %lld inside one organ only\n", mesh.scene->organs[0].name,
           (long long)compared, (long long)differ);
    CHECK(compared > 1000 && differ == 0);
    for (int32_t t = 0; t < mesh.volume->tissue_count; ++t) {
      const fascia_prep_tissue_report *a = mesh.volume->tissues + t, *b = labels.volume->tissues + t;
      const double layer = (double)a->organ_face_voxels * h * h * h;
      printf("tissue '%s': %.4f cm^3 from meshes, %.4f from labels, one voxel layer %.4f\n",
             mesh.scene->tissues[t].name, 1e6 * a->volume, 1e6 * b->volume, 1e6 * layer);
      CHECK(a->organ_face_voxels > 0 && a->organ_face_voxels < a->voxels);
      CHECK_NEAR(b->volume, a->volume, 0, layer);
    }
  }
  fixture_free(&mesh);
  fixture_free(&labels);
  fascia_ctx_destroy(&ctx);
  const char *const names[] = {"organs.nii.gz", "organs.tsv", "labels.json", NULL};
  fixture_cleanup(dir, names);
  return CHECK_RESULT();
}
