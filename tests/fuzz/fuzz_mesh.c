// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Fuzz harness: mesh import through the assimp adapter (fascia_prep_import).
// The first input byte picks the format (OBJ, OFF, STL); the rest is
// written as the mesh file of a one-organ scene and imported. assimp itself
// is not instrumented: what this checks is what fascia does with whatever
// assimp returns (part tables, indices, coordinates). PLY is left out:
// assimp 5.2.4's PLY loader hangs on damaged headers (third-party/README.md).
#define _POSIX_C_SOURCE 200809L
#include "fascia/prep.h"
#include "fuzz_common.h"

#define FORMAT_COUNT 3
static const char *const extensions[FORMAT_COUNT] = {"obj", "off", "stl"};
static fascia_ctx *fuzz_ctx;
static fascia_prep_scene *scenes[FORMAT_COUNT];
static const char *mesh_paths[FORMAT_COUNT];

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc, (void)argv;
  fascia_ctx_def def = fascia_ctx_def_default();
  def.threads = 1;
  if (fascia_ctx_create(&def, &fuzz_ctx) != FASCIA_OK) abort();
  for (int k = 0; k < FORMAT_COUNT; ++k) {
    char name[32], text[1024];
    snprintf(name, sizeof name, "mesh.%s", extensions[k]);
    mesh_paths[k] = fuzz_scratch_path(name);
    snprintf(text, sizeof text,
             "{\"fascia_scene\": 1, \"voxel_size\": 0.002,"
             " \"materials\": {\"m\": {\"law\": \"stvk\", \"youngs_modulus\": 1000, \"poisson_ratio\": 0.3,"
             " \"density\": 1000}},"
             " \"organs\": [{\"name\": \"A\", \"mesh\": \"%s\"}, {\"name\": \"B\", \"mesh\": \"%s\"}],"
             " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.01,"
             " \"material\": \"m\", \"frame_spacing\": 0.01, \"sample_spacing\": 0.005}]}",
             mesh_paths[k], mesh_paths[k]);
    if (fascia_prep_scene_parse(fuzz_ctx, text, "fuzz.json", NULL, &scenes[k]) != FASCIA_OK) {
      fprintf(stderr, "fuzz: the harness's scene is refused: %s\n", fascia_ctx_message(fuzz_ctx));
      abort();
    }
  }
  return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1) return 0;
  const int format = data[0] % FORMAT_COUNT;
  fuzz_write_file(mesh_paths[format], data + 1, size - 1);
  fascia_ctx_clear(fuzz_ctx);
  fascia_prep_meshes *meshes = NULL;
  const fascia_status status = fascia_prep_import(fuzz_ctx, scenes[format], &meshes);
  fuzz_check_refusal(fuzz_ctx, status, "fascia_prep_import");
  if ((status == FASCIA_OK) != (meshes != NULL)) abort();
  // what import passes on must be a mesh: finite vertices, indices in range
  for (int32_t k = 0; meshes && k < meshes->count; ++k) {
    const fascia_prep_mesh *o = meshes->organs + k;
    for (int64_t v = 0; v < 3 * (int64_t)o->vertex_count; ++v)
      if (!(o->vertices[v] == o->vertices[v]) || o->vertices[v] - o->vertices[v] != 0) {
        fprintf(stderr, "fuzz: import passed on a non-finite vertex coordinate\n");
        abort();
      }
    for (int64_t t = 0; t < 3 * (int64_t)o->triangle_count; ++t)
      if (o->triangles[t] < 0 || o->triangles[t] >= o->vertex_count) {
        fprintf(stderr, "fuzz: import passed on triangle %lld with vertex %d of %d\n", (long long)(t / 3),
                (int)o->triangles[t], (int)o->vertex_count);
        abort();
      }
  }
  fascia_prep_meshes_destroy(&meshes);
  return 0;
}
