// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Fuzz harness: the model file loader on the *contents* of a valid model.
// The input is a list of edits applied through the HDF5 API to a copy of the
// I/O fixture (tests/io_fixture.h, which uses every part of the schema):
// overwrite values (indices, offsets, NaN, huge numbers), resize, delete or
// retype a dataset, declare a huge unwritten one, change an attribute. The
// edited file is loaded; a model that loads is then run for two short
// implicit steps, which drives its prescribed motions (their motion
// input) through motion.c and the solver. Any refusal must carry a message.
#define _POSIX_C_SOURCE 200809L
#include <hdf5.h>
#include <math.h>

#include "fuzz_common.h"
#include "io_fixture.h"
#include "solve/solver_internal.h"

static uint8_t *template_bytes;
static size_t template_size;
static fascia_ctx *fuzz_ctx;

// Every numeric dataset of the fixture (motion "breathing", organ "liver").
static const char *const datasets[] = {
    "/frames/position",  "/frames/rotation",      "/frames/kind",           "/frames/motion",
    "/frames/load",      "/frames/offsets",       "/frames/pairs",          "/samples/position",
    "/samples/volume",   "/samples/material",     "/samples/offsets",       "/pairs/frame",
    "/pairs/weight",     "/pairs/gradient",       "/materials/law",         "/materials/youngs_modulus",
    "/materials/poisson_ratio", "/materials/density", "/materials/rotation_coupling",
    "/materials/rotation_smoothing", "/motions/breathing/pivot", "/motions/breathing/time",
    "/motions/breathing/translation", "/motions/breathing/rotation", "/probes/position", "/probes/offsets",
    "/probes/frame",     "/probes/weight",        "/organs/liver/vertices", "/organs/liver/triangles",
    "/coupling/organ",   "/coupling/frame",       "/coupling/triangle",     "/coupling/barycentric",
    "/gravity",          "/materials/name",       "/probes/name",           "/provenance",
    "/samples/patch"};
#define DATASET_COUNT ((uint32_t)(sizeof datasets / sizeof datasets[0]))

// Integer attributes: object, attribute name.
static const char *const attributes[][2] = {{"/", "fascia_model_version"},
                                            {"/motions/breathing", "index"},
                                            {"/organs/liver", "index"},
                                            {"/organs/liver", "kind"},
                                            {"/organs/liver", "motion"}};
#define ATTRIBUTE_COUNT ((uint32_t)(sizeof attributes / sizeof attributes[0]))

static double pick_real(fuzz_bytes *b) {
  static const double table[] = {0,     -0.0,   1,     -1,      0.5,     2,     3,      0.25, 1e308,
                                 -1e308, 1e-308, 5e-324, 1e20,   -1e20,   1e-20, 0.9999, 1.25};
  const uint32_t k = fuzz_u8(b) % 21;
  if (k == 17) return NAN;
  if (k == 18) return INFINITY;
  if (k == 19) return -INFINITY;
  if (k == 20) return fuzz_raw_double(b);
  return table[k];
}

static int32_t pick_int(fuzz_bytes *b) {
  static const int32_t table[] = {-1, 0, 1, 2, 3, 4, 5, 8, 9, 10, -2, INT32_MAX, INT32_MIN, 0x40000000, 1 << 20};
  const uint32_t k = fuzz_u8(b) % 16;
  return k == 15 ? (int32_t)fuzz_u32(b) : table[k];
}

// Opens dataset k; fills its class, rank, dims and element count.
static hid_t open_dataset(hid_t file, uint32_t k, H5T_class_t *cls, int *rank, hsize_t dims[2], hsize_t *total) {
  if (H5Lexists(file, datasets[k], H5P_DEFAULT) <= 0) return -1;
  hid_t dset = H5Dopen2(file, datasets[k], H5P_DEFAULT);
  if (dset < 0) return -1;
  hid_t type = H5Dget_type(dset), space = H5Dget_space(dset);
  *cls = H5Tget_class(type);
  *rank = H5Sget_simple_extent_ndims(space);
  dims[0] = dims[1] = 1;
  *total = 0;
  if (*rank >= 0 && *rank <= 2) {
    H5Sget_simple_extent_dims(space, dims, NULL);
    *total = (hsize_t)H5Sget_simple_extent_npoints(space);
  }
  H5Tclose(type);
  H5Sclose(space);
  if (*rank < 0 || *rank > 2 || *total > (1u << 20)) {
    H5Dclose(dset);
    return -1;
  }
  return dset;
}

// Overwrites 1..4 elements of a numeric dataset with chosen values.
static void edit_values(hid_t file, fuzz_bytes *b) {
  const uint32_t k = fuzz_u8(b) % DATASET_COUNT;
  H5T_class_t cls;
  int rank;
  hsize_t dims[2], total;
  hid_t dset = open_dataset(file, k, &cls, &rank, dims, &total);
  if (dset < 0) return;
  if (total > 0 && (cls == H5T_FLOAT || cls == H5T_INTEGER)) {
    const int real = cls == H5T_FLOAT;
    void *buf = calloc(total, 8);
    if (buf && H5Dread(dset, real ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0) {
      const uint32_t edits = 1 + fuzz_u8(b) % 4;
      for (uint32_t e = 0; e < edits; ++e) {
        const hsize_t at = fuzz_u16(b) % total;
        if (real)
          ((double *)buf)[at] = pick_real(b);
        else
          ((int32_t *)buf)[at] = pick_int(b);
      }
      H5Dwrite(dset, real ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
    }
    free(buf);
  }
  H5Dclose(dset);
}

// Replaces dataset k by one of class `cls` (float, integer or string) and
// shape rows x cols (cols 0: 1-D), filled with chosen values; with
// unwritten != 0 it is chunked and nothing is written (huge declared sizes).
static void replace_dataset(hid_t file, uint32_t k, H5T_class_t cls, hsize_t rows, hsize_t cols, int unwritten,
                            fuzz_bytes *b) {
  H5Ldelete(file, datasets[k], H5P_DEFAULT);
  const hsize_t dims[2] = {rows, cols ? cols : 1}, maxdims[2] = {H5S_UNLIMITED, H5S_UNLIMITED};
  const int rank = cols ? 2 : 1;
  hid_t space = H5Screate_simple(rank, dims, unwritten ? maxdims : NULL);
  hid_t type = cls == H5T_FLOAT ? H5Tcopy(H5T_IEEE_F64LE) : cls == H5T_INTEGER ? H5Tcopy(H5T_STD_I32LE) : H5Tcopy(H5T_C_S1);
  if (cls == H5T_STRING) H5Tset_size(type, 1 + fuzz_u8(b) % 80);
  hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  if (unwritten) {
    const hsize_t chunk[2] = {64, cols ? cols : 1};
    H5Pset_chunk(dcpl, rank, chunk);
  }
  hid_t dset = H5Dcreate2(file, datasets[k], type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  const hsize_t total = rows * (cols ? cols : 1);
  if (dset >= 0 && !unwritten && total > 0 && total <= 4096) {
    const size_t esize = H5Tget_size(type);
    uint8_t *buf = calloc(total, esize);
    for (hsize_t e = 0; buf && e < total; ++e) {
      if (cls == H5T_FLOAT) {
        const double x = pick_real(b);
        memcpy(buf + 8 * e, &x, 8);
      } else if (cls == H5T_INTEGER) {
        const int32_t x = pick_int(b);
        memcpy(buf + 4 * e, &x, 4);
      } else {
        for (size_t c = 0; c + 1 < esize; ++c) buf[esize * e + c] = (uint8_t)('a' + fuzz_u8(b) % 27);
      }
      if (!fuzz_left(b)) break; // the rest stays zero
    }
    hid_t mem = cls == H5T_FLOAT ? H5T_NATIVE_DOUBLE : cls == H5T_INTEGER ? H5T_NATIVE_INT32 : type;
    if (buf) H5Dwrite(dset, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
    free(buf);
  }
  if (dset >= 0) H5Dclose(dset);
  H5Pclose(dcpl);
  H5Tclose(type);
  H5Sclose(space);
}

static void edit_shape(hid_t file, fuzz_bytes *b, int how) {
  const uint32_t k = fuzz_u8(b) % DATASET_COUNT;
  H5T_class_t cls;
  int rank;
  hsize_t dims[2], total;
  hid_t dset = open_dataset(file, k, &cls, &rank, dims, &total);
  if (dset < 0) return;
  H5Dclose(dset);
  const hsize_t rows = rank >= 1 ? dims[0] : 1, cols = rank == 2 ? dims[1] : 0;
  if (how == 0) { // another row count, same class
    const hsize_t choices[] = {0, 1, rows ? rows - 1 : 0, rows + 1, 2 * rows + 1, fuzz_u8(b)};
    replace_dataset(file, k, cls, choices[fuzz_u8(b) % 6], cols, 0, b);
  } else if (how == 1) { // a huge declared size with no data
    const hsize_t per = cols ? cols : 1;
    const hsize_t choices[] = {(hsize_t)1 << 20, (hsize_t)1 << 28, ((hsize_t)1 << 30) / per, ((hsize_t)1 << 31) - 1,
                               (hsize_t)1 << 40};
    replace_dataset(file, k, cls, choices[fuzz_u8(b) % 5], cols, 1, b);
  } else if (how == 2) { // another class or rank
    const H5T_class_t classes[] = {H5T_FLOAT, H5T_INTEGER, H5T_STRING};
    const hsize_t col_choices[] = {0, cols, cols + 1, 3};
    replace_dataset(file, k, classes[fuzz_u8(b) % 3], rows, col_choices[fuzz_u8(b) % 4], 0, b);
  } else { // gone
    H5Ldelete(file, datasets[k], H5P_DEFAULT);
  }
}

static void edit_attribute(hid_t file, fuzz_bytes *b) {
  const uint32_t k = fuzz_u8(b) % ATTRIBUTE_COUNT;
  if (H5Aexists_by_name(file, attributes[k][0], attributes[k][1], H5P_DEFAULT) <= 0) return;
  hid_t attr = H5Aopen_by_name(file, attributes[k][0], attributes[k][1], H5P_DEFAULT, H5P_DEFAULT);
  if (attr < 0) return;
  const int32_t value = pick_int(b);
  H5Awrite(attr, H5T_NATIVE_INT32, &value);
  H5Aclose(attr);
}

// A second motion or organ group that copies the first (same index).
static void duplicate_member(hid_t file, fuzz_bytes *b) {
  const int organ = fuzz_u8(b) & 1;
  const char *from = organ ? "/organs/liver" : "/motions/breathing";
  const char *to = organ ? "/organs/liver2" : "/motions/breathing2";
  if (H5Lexists(file, from, H5P_DEFAULT) > 0) H5Ocopy(file, from, file, to, H5P_DEFAULT, H5P_DEFAULT);
}

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc, (void)argv;
  fascia_ctx_def def = fascia_ctx_def_default();
  def.threads = 1;
  fascia_model *model = NULL;
  const char *path = fuzz_scratch_path("template.h5");
  if (fascia_ctx_create(&def, &fuzz_ctx) != FASCIA_OK || fixture_model(fuzz_ctx, 0, &model) != FASCIA_OK ||
      fascia_model_save(fuzz_ctx, model, path) != FASCIA_OK) {
    fprintf(stderr, "fuzz: cannot write the template model: %s\n", fascia_ctx_message(fuzz_ctx));
    abort();
  }
  fascia_model_destroy(&model);
  FILE *f = fopen(path, "rb");
  if (!f || fseek(f, 0, SEEK_END) != 0) abort();
  template_size = (size_t)ftell(f);
  rewind(f);
  template_bytes = malloc(template_size);
  if (!template_bytes || fread(template_bytes, 1, template_size, f) != template_size) abort();
  fclose(f);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL); // the edits fail often, on purpose
  return 0;
}

// Runs a model that loaded: motion poses at chosen times, then two short
// implicit steps (which place prescribed frames through motion.c).
static void exercise(fascia_model *model, fuzz_bytes *b) {
  for (int32_t k = 0; k < model->motion_count; ++k) {
    fascia_real translation[3], rotation[4];
    fascia_motion_pose(model->motions + k, pick_real(b), translation, rotation);
  }
  fascia_solver_def def = fascia_solver_def_default();
  def.threads = 1;
  def.newton_iterations = 2;
  def.require_convergence = 0;
  def.cg_iterations = 20;
  def.step_retries = 1;
  const double steps[] = {0.01, 1e-9, 0.7, 1e3};
  def.time_step = steps[fuzz_u8(b) % 4];
  fascia_solver *solver = NULL;
  fascia_status status = fascia_solver_create(fuzz_ctx, model, &def, &solver);
  fuzz_check_refusal(fuzz_ctx, status, "fascia_solver_create");
  for (int n = 0; n < 2 && status == FASCIA_OK; ++n) {
    status = fascia_solver_step(solver, NULL);
    fuzz_check_refusal(fuzz_ctx, status, "fascia_solver_step");
  }
  fascia_solver_destroy(&solver);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fuzz_bytes b = {data, size, 0};
  const char *path = fuzz_scratch_path("struct.h5");
  fuzz_write_file(path, template_bytes, template_size);
  hid_t file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) abort();
  const uint32_t edits = 1 + fuzz_u8(&b) % 6;
  for (uint32_t e = 0; e < edits && fuzz_left(&b); ++e) {
    const uint32_t op = fuzz_u8(&b) % 10;
    if (op < 4) edit_values(file, &b);
    else if (op < 8) edit_shape(file, &b, (int)op - 4);
    else if (op == 8) edit_attribute(file, &b);
    else duplicate_member(file, &b);
  }
  H5Fclose(file);
  fascia_ctx_clear(fuzz_ctx);
  fascia_model *model = NULL;
  const fascia_status status = fascia_model_load(fuzz_ctx, path, &model);
  fuzz_check_refusal(fuzz_ctx, status, "fascia_model_load");
  if ((status == FASCIA_OK) != (model != NULL)) abort();
  if (model) exercise(model, &b);
  fascia_model_destroy(&model);
  return 0;
}
