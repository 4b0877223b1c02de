// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Volumetric patches in the model file: a model with patches is written as
// version 2 with /samples/patch and reads back the same; one without stays
// version 1 with no such dataset (older readers read it as before); a
// version 2 file without the dataset, a patch index out of range and a patch
// mixing materials are refused with the file, the dataset and the problem.
// Enhanced strain modes: a model whose patches carry them is version 3 with
// /samples/modes and reads back the same; a version 3 file without the
// dataset, modes on a sample in no patch, a patch whose samples disagree and
// a value other than 0, 1 or 2 are refused likewise. The three normal modes
// (value 2, fascia beam's default on hexahedral cells) make it version 4;
// a file that says version 3 and holds a 2 is refused, naming the version.
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

static int has_dataset(const char *path, const char *name) {
  hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  const int has = file >= 0 && H5Lexists(file, "/samples", H5P_DEFAULT) > 0 && H5Lexists(file, name, H5P_DEFAULT) > 0;
  if (file >= 0) H5Fclose(file);
  return has;
}

static int has_patch_dataset(const char *path) { return has_dataset(path, "/samples/patch"); }

// modes: -1 fascia beam's rule (the nine for tet, the normal three for hex, with patches), or a set
static fascia_model *beam_of(fascia_ctx *ctx, int shape, int patch, int modes) {
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 6;
  def.shape = shape;
  def.volumetric_patch = patch;
  def.enhanced_modes = modes;
  fascia_model *m = NULL;
  return fascia_scene_beam_build(ctx, &def, &m) == FASCIA_OK ? m : NULL;
}

// patches without modes
static fascia_model *beam(fascia_ctx *ctx, int patch) { return beam_of(ctx, FASCIA_SCENE_HEX, patch, FASCIA_MODES_NONE); }

// Saves m, expecting the validation to refuse it naming /samples/modes and what.
static void expect_modes_refused(fascia_ctx *ctx, const fascia_model *m, const char *path, const char *what) {
  CHECK(fascia_model_save(ctx, m, path) == FASCIA_ERR_FORMAT);
  CHECK(strstr(fascia_ctx_message(ctx), "/samples/modes") && strstr(fascia_ctx_message(ctx), what));
  printf("t209: %s\n", fascia_ctx_message(ctx));
}

static int modes_in_file(fascia_ctx *ctx, const char *dir) {
  char path[256];
  snprintf(path, sizeof path, "%s/modes.h5", dir);
  fascia_model *m = beam_of(ctx, FASCIA_SCENE_TET, FASCIA_SCENE_PATCH_CELL, -1), *back = NULL;
  CHECK(m != NULL);
  if (!m) return 1;
  int32_t with = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) with += m->sample_modes[s];
  CHECK(with == m->sample_count); // every tet sample is in a cell patch with modes
  CHECK_OK(fascia_model_save(ctx, m, path), ctx);
  CHECK(version_of(path) == 3 && has_dataset(path, "/samples/modes"));
  CHECK_OK(fascia_model_load(ctx, path, &back), ctx);
  CHECK(back && !memcmp(back->sample_modes, m->sample_modes, (size_t)m->sample_count * sizeof(int32_t)));
  CHECK(back && fascia_model_fingerprint(back) == fascia_model_fingerprint(m));
  fascia_model_destroy(&back);
  // the fingerprint tells a model with modes from the same without
  const uint64_t with_modes = fascia_model_fingerprint(m);
  for (int32_t s = 0; s < m->sample_count; ++s) m->sample_modes[s] = 0;
  CHECK(fascia_model_fingerprint(m) != with_modes);
  for (int32_t s = 0; s < m->sample_count; ++s) m->sample_modes[s] = 1;
  // version 3 without its dataset
  hid_t file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
  CHECK(file >= 0 && H5Ldelete(file, "/samples/modes", H5P_DEFAULT) >= 0 && H5Fclose(file) >= 0);
  CHECK(fascia_model_load(ctx, path, &back) == FASCIA_ERR_FORMAT && back == NULL);
  CHECK(strstr(fascia_ctx_message(ctx), path) && strstr(fascia_ctx_message(ctx), "/samples/modes"));
  // bad values
  m->sample_modes[5] = 3;
  expect_modes_refused(ctx, m, path, "sample 5");
  m->sample_modes[5] = 1;
  const int32_t patch = m->sample_patch[7];
  m->sample_patch[7] = -1;
  expect_modes_refused(ctx, m, path, "no volumetric patch");
  m->sample_patch[7] = patch;
  m->sample_modes[7] = 0;
  expect_modes_refused(ctx, m, path, "share its modes");
  fascia_model_destroy(&m);
  // the three normal modes of hexahedral cells: version 4
  m = beam_of(ctx, FASCIA_SCENE_HEX, FASCIA_SCENE_PATCH_CELL, -1);
  CHECK(m != NULL);
  if (!m) return 1;
  int32_t normal = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) normal += m->sample_modes[s] == FASCIA_MODES_NORMAL;
  CHECK(normal == m->sample_count);
  CHECK_OK(fascia_model_save(ctx, m, path), ctx);
  CHECK(version_of(path) == 4);
  CHECK_OK(fascia_model_load(ctx, path, &back), ctx);
  CHECK(back && !memcmp(back->sample_modes, m->sample_modes, (size_t)m->sample_count * sizeof(int32_t)));
  fascia_model_destroy(&back);
  // the same file claiming version 3, whose modes are only 0 or 1
  file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
  hid_t attr = file >= 0 ? H5Aopen_by_name(file, "/", "fascia_model_version", H5P_DEFAULT, H5P_DEFAULT) : -1;
  const int32_t three = 3;
  CHECK(attr >= 0 && H5Awrite(attr, H5T_NATIVE_INT32, &three) >= 0 && H5Aclose(attr) >= 0 && H5Fclose(file) >= 0);
  CHECK(fascia_model_load(ctx, path, &back) == FASCIA_ERR_FORMAT && back == NULL);
  CHECK(strstr(fascia_ctx_message(ctx), path) && strstr(fascia_ctx_message(ctx), "/samples/modes") &&
        strstr(fascia_ctx_message(ctx), "version 4"));
  printf("t209: %s\n", fascia_ctx_message(ctx));
  fascia_model_destroy(&m);
  remove(path);
  return 0;
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
  modes_in_file(ctx, dir);
  remove(path);
  remove(plain);
  rmdir(dir);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
