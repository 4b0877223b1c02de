// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Volumetric patches in the model file: a model with patches is written as
// version 2 with /samples/patch and reads back the same; one without stays
// version 1 with no such dataset (older readers read it as before); a
// version 2 file without the dataset, a patch index out of range and a patch
// mixing materials are refused with the file, the dataset and the problem.
#define _POSIX_C_SOURCE 200809L
#include <hdf5.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "fascia/fascia.h"
#include "scenes.h"

static int version_of(const char *path) {
  int32_t version = -1;
  hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t attr = file >= 0 ? H5Aopen_by_name(file, "/", "fascia_model_version", H5P_DEFAULT, H5P_DEFAULT) : -1;
  if (attr >= 0) H5Aread(attr, H5T_NATIVE_INT32, &version), H5Aclose(attr);
  if (file >= 0) H5Fclose(file);
  return version;
}

static int has_patch_dataset(const char *path) {
  hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  const int has = file >= 0 && H5Lexists(file, "/samples/patch", H5P_DEFAULT) > 0;
  if (file >= 0) H5Fclose(file);
  return has;
}

static fascia_model *beam(fascia_ctx *ctx, int patch) {
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 6;
  def.volumetric_patch = patch;
  fascia_model *m = NULL;
  return fascia_scene_beam_build(ctx, &def, &m) == FASCIA_OK ? m : NULL;
}

int main(void) {
  fascia_hdf5_quiet();
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  char dir[] = "t209-XXXXXX", path[256], plain[256];
  CHECK(mkdtemp(dir) != NULL);
  snprintf(path, sizeof path, "%s/patched.h5", dir);
  snprintf(plain, sizeof plain, "%s/plain.h5", dir);
  fascia_model *m = beam(ctx, FASCIA_SCENE_PATCH_CELL), *p = beam(ctx, FASCIA_SCENE_PATCH_NONE), *back = NULL;
  CHECK(m && p);
  if (!m || !p) return 1;
  CHECK(fascia_model_patch_count(m, NULL) == 5 * 2 * 2);
  CHECK_OK(fascia_model_save(ctx, m, path), ctx);
  CHECK_OK(fascia_model_save(ctx, p, plain), ctx);
  CHECK(version_of(path) == 2 && has_patch_dataset(path));
  CHECK(version_of(plain) == 1 && !has_patch_dataset(plain));
  CHECK_OK(fascia_model_load(ctx, path, &back), ctx);
  CHECK(back && !memcmp(back->sample_patch, m->sample_patch, (size_t)m->sample_count * sizeof(int32_t)));
  fascia_model_destroy(&back);
  CHECK_OK(fascia_model_load(ctx, plain, &back), ctx);
  int none = 1;
  for (int32_t s = 0; back && s < back->sample_count; ++s) none &= back->sample_patch[s] == -1;
  CHECK(back && none);
  fascia_model_destroy(&back);
  // version 2 without its dataset
  hid_t file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
  CHECK(file >= 0 && H5Ldelete(file, "/samples/patch", H5P_DEFAULT) >= 0 && H5Fclose(file) >= 0);
  CHECK(fascia_model_load(ctx, path, &back) == FASCIA_ERR_FORMAT && back == NULL);
  CHECK(strstr(fascia_ctx_message(ctx), path) && strstr(fascia_ctx_message(ctx), "/samples/patch"));
  // bad values, refused by the validation every model passes
  m->sample_patch[3] = m->sample_count;
  CHECK(fascia_model_save(ctx, m, path) == FASCIA_ERR_FORMAT);
  CHECK(strstr(fascia_ctx_message(ctx), "/samples/patch") && strstr(fascia_ctx_message(ctx), "sample 3"));
  m->sample_patch[3] = m->sample_patch[4];
  fascia_material *grown = realloc(m->materials, 2 * sizeof *m->materials);
  CHECK(grown != NULL);
  if (!grown) return 1;
  m->materials = grown;
  m->materials[1] = m->materials[0];
  m->material_count = 2;
  m->sample_material[4] = 1;
  CHECK(fascia_model_validate(ctx, m, "t209") == FASCIA_ERR_FORMAT);
  CHECK(strstr(fascia_ctx_message(ctx), "different materials") != NULL);
  printf("t209: %s\n", fascia_ctx_message(ctx));
  fascia_model_destroy(&m);
  fascia_model_destroy(&p);
  remove(path);
  remove(plain);
  rmdir(dir);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
