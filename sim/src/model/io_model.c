// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The model file: fascia_model_save and fascia_model_load over HDF5. The full
// specification, with units and meanings, is docs/model-format.md; this
// summary must stay in step with it. Bump the version (and the reader's
// range) whenever a reader of the previous version would misread a new file.
//
// Schema, version 4 (version 3: /samples/modes only 0 or 1; version 2: the
// same without /samples/modes; version 1: without /samples/patch either. A
// model is written
// with the lowest version that holds it, which older readers read the same
// way). N frames, S samples, P sample-frame pairs, M materials,
// Q probes, R probe-frame pairs, C coupling entries, K keys of a motion,
// V vertices and T triangles of an organ. Reals are IEEE f64 little endian,
// indices int32 (-1 = none), names fixed strings of 64 bytes (NUL-terminated,
// variable-length strings are accepted on reading). Every dataset is
// present, also when it has 0 rows.
//
//   /                     attributes: fascia_model_version (int32, = 1),
//                         fascia_model_checksum (u64, below),
//                         units ("SI: m, kg, s, Pa"), creator ("fascia X.Y.Z"),
//                         allow_floating (int32 1, optional: pieces held by
//                         nothing are meant; absent = 0, such pieces refused)
//   /frames/position      [N,3]  f64  m     rest position x_i, world
//   /frames/rotation      [N,4]  f64  1     rest rotation, unit quaternion w,x,y,z
//   /frames/kind          [N]    i32        0 free, 1 fixed, 2 prescribed
//   /frames/motion        [N]    i32        motion index (prescribed), else -1
//   /frames/load          [N,6]  f64  N, N m  constant force then torque, world
//   /frames/offsets       [N+1]  i32        reverse table (CSR) into /frames/pairs
//   /frames/pairs         [P]    i32        pair indices of each frame, ascending
//   /samples/position     [S,3]  f64  m     rest position, world
//   /samples/volume       [S]    f64  m^3   > 0
//   /samples/material     [S]    i32        material index
//   /samples/patch        [S]    i32        volumetric patch, -1 none (version 2)
//   /samples/modes        [S]    i32        the patch's enhanced strain modes: 0 none, 1 nine
//                                           (version 3), 2 the three normal ones (version 4)
//   /samples/offsets      [S+1]  i32        CSR into /pairs
//   /pairs/frame          [P]    i32        frame index, ascending per sample
//   /pairs/weight         [P]    f64  1     w_is, sum per sample = 1
//   /pairs/gradient       [P,3]  f64  1/m   rest-space gradient of w_is, sum = 0
//   /materials/name       [M]    str64
//   /materials/law        [M]    i32        0 stvk, 1 neohookean
//   /materials/youngs_modulus [M] f64 Pa;  poisson_ratio [M] f64 1;
//   /materials/density    [M]    f64  kg/m^3;  rotation_coupling, rotation_smoothing [M] f64 1
//   /motions/NAME/        group per motion; attribute index (int32, order)
//       pivot [3] f64 m; time [K] f64 s; translation [K,3] f64 m;
//       rotation [K,4] f64 (unit quaternions w,x,y,z)
//   /probes/name          [Q]    str64
//   /probes/position      [Q,3]  f64  m     rest position
//   /probes/offsets       [Q+1]  i32        CSR into /probes/frame, /probes/weight
//   /probes/frame         [R]    i32;   /probes/weight [R] f64 (sum per probe = 1)
//   /organs/NAME/         group per organ; attributes index, kind (0 fixed,
//                         1 prescribed, 2 rigid, 3 deformable), motion (int32)
//       vertices [V,3] f64 m (rest); triangles [T,3] i32 (vertex indices)
//   /coupling/organ       [C]    i32;  frame [C] i32;  triangle [C] i32
//   /coupling/barycentric [C,3]  f64  1
//   /gravity              [3]    f64  m/s^2, world
//   /tissue_surface/      optional (drawing only): vertices [V,3] f64 m,
//                         triangles [T,3] i32 (any version reads it)
//   /tetrahedra           [M,4] i32, optional (drawing only): the frames at
//                         the corners of a tet tissue's tetrahedra
//   /provenance           scalar string, JSON text (absent when unknown)
//
// The checksum is FNV-1a 64 (fnv.h) of the model as a reader builds it from
// the file (model_checksum below: the version, every count, array, name,
// attribute, the optional parts and the provenance), so that a file damaged
// or edited anywhere a load reads is refused instead of loaded as another
// model. It is checked after every other check (those name what is wrong);
// a file without it (written before it existed) is refused.
//
// Sizes come from the datasets' shapes; before anything is allocated for
// them the reader checks that every dataset declaring values also stores
// them (a small damaged or hostile file can declare a billion rows), and that
// the arrays of the model would fit in this machine's memory.
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fascia/model.h"
#include "util/fnv.h"
#include "io/h5io.h"
#include "model/model_arrays.h"

// A model with volumetric patches is version 2: a version 1 reader would
// drop the patches and compute a locking answer without a word.
#define MODEL_VERSION_PATCHES 2
// A model whose patches carry enhanced strain modes (/samples/modes) is
// version 3: a version 2 reader would drop the modes and compute a stiffer
// answer without a word.
#define MODEL_VERSION_MODES 3
// A model with patches of the three normal modes (/samples/modes 2) is
// version 4: a version 3 reader refuses the value with a message that
// does not say a newer fascia reads it.
#define MODEL_VERSION_MODE_SETS 4
// Versions this reader understands.
#define MODEL_VERSION_MIN 1
#define MODEL_VERSION_MAX 4
#define MODEL_UNITS "SI: m, kg, s, Pa"
#define REMEDY "re-run 'fascia prep' or 'fascia beam' with this version"
#define PATH_SIZE 256
#define CHECKSUM_ATTR "fascia_model_checksum"

_Static_assert(sizeof(fascia_real) == sizeof(double), "model files store fascia_real as f64");

// ---------------------------------------------------------------------------
// The checksum of what a file holds

static uint64_t hash_count(uint64_t h, int64_t n) { return fascia_fnv(h, &n, sizeof n); }

// Everything a load of this model from a file of version `version` gives:
// what the writer stores, as the reader reads it back.
static uint64_t model_checksum(const fascia_model *m, int32_t version) {
  const size_t R = sizeof(fascia_real), I = sizeof(int32_t);
  uint64_t h = fascia_fnv(FASCIA_FNV_START, &version, sizeof version);
  const fascia_model_sizes counts = fascia_model_shape(m);
  _Static_assert(sizeof counts == 9 * sizeof(int32_t), "the checksum hashes the nine counts in their order");
  h = fascia_fnv(h, &counts, sizeof counts);
  h = fascia_model_hash_rows(h, m, 1);
  h = fascia_fnv(h, m->gravity, 3 * R);
  const int32_t floating = m->allow_floating != 0; // stored as 1 or not at all
  h = fascia_fnv(h, &floating, sizeof floating);
  // the optional parts as the writer stores them: a surface without triangles is not written
  const fascia_surface *ts = &m->tissue_surface;
  const int32_t surface[2] = {ts->triangle_count > 0 ? ts->vertex_count : 0, ts->triangle_count > 0 ? ts->triangle_count : 0};
  h = fascia_fnv(h, surface, sizeof surface);
  h = fascia_fnv(h, ts->vertices, 3 * (size_t)surface[0] * R);
  h = fascia_fnv(h, ts->triangles, 3 * (size_t)surface[1] * I);
  const int32_t tetrahedra = m->tetrahedron_count > 0 ? m->tetrahedron_count : 0;
  h = fascia_fnv(h, &tetrahedra, sizeof tetrahedra);
  h = fascia_fnv(h, m->tetrahedra, 4 * (size_t)tetrahedra * I);
  h = hash_count(h, m->provenance ? (int64_t)strlen(m->provenance) : -1);
  if (m->provenance) h = fascia_fnv(h, m->provenance, strlen(m->provenance));
  return h;
}

// ---------------------------------------------------------------------------
// Writing

typedef struct writer {
  fascia_ctx *ctx;
  const char *path; // final path, for messages
  hid_t file;
} writer;

static fascia_status write_failed(writer *w, const char *name) {
  char detail[600];
  fascia_h5_error(detail, sizeof detail);
  return FASCIA_FAIL(w->ctx, FASCIA_ERR_IO, "model '%s' %s: cannot write (HDF5: %s); check the disk space", w->path,
                     name, detail);
}

static hid_t name_type(void) {
  hid_t type = H5Tcopy(H5T_C_S1);
  // names and provenance are UTF-8 text (organ names come from mesh files)
  if (type >= 0 && (H5Tset_size(type, FASCIA_NAME_SIZE) < 0 || H5Tset_strpad(type, H5T_STR_NULLTERM) < 0 ||
                    H5Tset_cset(type, H5T_CSET_UTF8) < 0)) {
    H5Tclose(type);
    return H5I_INVALID_HID;
  }
  return type;
}

// Writes dataset `name` (absolute) of rank 1 [d0] or 2 [d0,d1] from data,
// with an optional `unit` attribute.
static fascia_status write_dataset(writer *w, const char *name, fascia_ma_kind kind, int rank, int64_t d0, int64_t d1,
                                   const void *data, const char *unit) {
  const hsize_t dims[2] = {(hsize_t)d0, (hsize_t)d1};
  hid_t space = H5Screate_simple(rank, dims, NULL), dset = H5I_INVALID_HID, type = H5I_INVALID_HID;
  hid_t file_type = kind == FASCIA_MA_REAL ? H5T_IEEE_F64LE : H5T_STD_I32LE;
  hid_t mem_type = kind == FASCIA_MA_REAL ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT32;
  if (kind == FASCIA_MA_NAME) file_type = mem_type = type = name_type();
  int ok = space >= 0 && file_type >= 0;
  if (ok) dset = H5Dcreate2(w->file, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  ok = ok && dset >= 0;
  if (ok && d0 * (rank == 2 ? d1 : 1) > 0) ok = H5Dwrite(dset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0;
  if (ok && unit) ok = fascia_h5_attr_string(dset, "unit", unit) >= 0;
  fascia_status status = ok ? FASCIA_OK : write_failed(w, name);
  if (dset >= 0) H5Dclose(dset);
  if (type >= 0) H5Tclose(type);
  if (space >= 0) H5Sclose(space);
  return status;
}

#define WRITE1(w, name, kind, n, data, unit) FASCIA_TRY(write_dataset(w, name, kind, 1, n, 0, data, unit))
#define WRITE2(w, name, kind, n, m, data, unit) FASCIA_TRY(write_dataset(w, name, kind, 2, n, m, data, unit))

static fascia_status write_text(writer *w, const char *name, const char *text) {
  hid_t type = H5Tcopy(H5T_C_S1), space = H5Screate(H5S_SCALAR), dset = H5I_INVALID_HID;
  int ok = type >= 0 && space >= 0 && H5Tset_size(type, strlen(text) + 1) >= 0 &&
           H5Tset_strpad(type, H5T_STR_NULLTERM) >= 0 && H5Tset_cset(type, H5T_CSET_UTF8) >= 0;
  if (ok) dset = H5Dcreate2(w->file, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  ok = ok && dset >= 0 && H5Dwrite(dset, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, text) >= 0;
  fascia_status status = ok ? FASCIA_OK : write_failed(w, name);
  if (dset >= 0) H5Dclose(dset);
  if (space >= 0) H5Sclose(space);
  if (type >= 0) H5Tclose(type);
  return status;
}

// Creates group `name`; with index >= 0 also its attributes index, and for
// organs kind and motion (kind >= 0).
static fascia_status write_group(writer *w, const char *name, int32_t index, int32_t kind, int32_t motion) {
  hid_t group = H5Gcreate2(w->file, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  int ok = group >= 0;
  if (ok && index >= 0) ok = fascia_h5_attr_int(group, "index", index) >= 0;
  if (ok && kind >= 0)
    ok = fascia_h5_attr_int(group, "kind", kind) >= 0 && fascia_h5_attr_int(group, "motion", motion) >= 0;
  fascia_status status = ok ? FASCIA_OK : write_failed(w, name);
  if (group >= 0) H5Gclose(group);
  return status;
}

// The version the modes need: 0 without modes.
static int model_modes_version(const fascia_model *m) {
  int version = 0;
  for (int32_t s = 0; s < m->sample_count; ++s)
    if (m->sample_modes[s] > FASCIA_MODES_NINE) return MODEL_VERSION_MODE_SETS;
    else if (m->sample_modes[s]) version = MODEL_VERSION_MODES;
  return version;
}

// Materials as parallel datasets, one per field (simpler to check on reading
// than a compound, and each carries its own unit), in file order.
typedef struct material_field {
  const char *path, *unit;
  fascia_ma_kind kind;
  size_t offset; ///< in fascia_material
} material_field;

static const material_field material_fields[] = {
    {"/materials/name", NULL, FASCIA_MA_NAME, offsetof(fascia_material, name)},
    {"/materials/law", NULL, FASCIA_MA_INT, offsetof(fascia_material, law)},
    {"/materials/youngs_modulus", "Pa", FASCIA_MA_REAL, offsetof(fascia_material, youngs_modulus)},
    {"/materials/poisson_ratio", "1", FASCIA_MA_REAL, offsetof(fascia_material, poisson_ratio)},
    {"/materials/density", "kg/m^3", FASCIA_MA_REAL, offsetof(fascia_material, density)},
    {"/materials/rotation_coupling", "1", FASCIA_MA_REAL, offsetof(fascia_material, rotation_coupling)},
    {"/materials/rotation_smoothing", "1", FASCIA_MA_REAL, offsetof(fascia_material, rotation_smoothing)},
    // the last, optional on reading: files before reduced integration are all FASCIA_PART_FULL (0)
    {"/materials/part", NULL, FASCIA_MA_INT, offsetof(fascia_material, part)},
};
#define MATERIAL_FIELD_COUNT (sizeof material_fields / sizeof material_fields[0])

static fascia_status write_materials(writer *w, const fascia_model *m) {
  const int64_t M = m->material_count;
  char *column = fascia_calloc(M, FASCIA_NAME_SIZE); // the largest field
  FASCIA_CHECK(column, w->ctx, FASCIA_ERR_MEMORY, "model '%s' /materials: out of memory", w->path);
  fascia_status status = write_group(w, "/materials", -1, -1, -1);
  for (size_t f = 0; f < MATERIAL_FIELD_COUNT && status == FASCIA_OK; ++f) {
    const material_field *field = material_fields + f;
    const size_t size = fascia_model_array_size(field->kind);
    for (int64_t k = 0; k < M; ++k) memcpy(column + k * size, (const char *)(m->materials + k) + field->offset, size);
    status = write_dataset(w, field->path, field->kind, 1, M, 0, column, field->unit);
  }
  free(column);
  return status;
}

// Writes dataset `leaf` of a motion's or organ's group (as write_dataset;
// cols 0: a 1-D dataset).
static fascia_status write_member(writer *w, const char *group, const char *leaf, fascia_ma_kind kind, int64_t rows,
                                  int64_t cols, const void *data, const char *unit) {
  char name[PATH_SIZE + 16];
  snprintf(name, sizeof name, "%s/%s", group, leaf);
  return write_dataset(w, name, kind, cols ? 2 : 1, rows, cols, data, unit);
}

static fascia_status write_motions(writer *w, const fascia_model *m) {
  char group[PATH_SIZE];
  FASCIA_TRY(write_group(w, "/motions", -1, -1, -1));
  for (int32_t k = 0; k < m->motion_count; ++k) {
    const fascia_motion *mo = m->motions + k;
    const int64_t K = mo->key_count;
    snprintf(group, sizeof group, "/motions/%s", mo->name);
    FASCIA_TRY(write_group(w, group, k, -1, -1));
    FASCIA_TRY(write_member(w, group, "pivot", FASCIA_MA_REAL, 3, 0, mo->pivot, "m"));
    FASCIA_TRY(write_member(w, group, "time", FASCIA_MA_REAL, K, 0, mo->key_time, "s"));
    FASCIA_TRY(write_member(w, group, "translation", FASCIA_MA_REAL, K, 3, mo->key_translation, "m"));
    FASCIA_TRY(write_member(w, group, "rotation", FASCIA_MA_REAL, K, 4, mo->key_rotation, "1"));
  }
  return FASCIA_OK;
}

static fascia_status write_organs(writer *w, const fascia_model *m) {
  char group[PATH_SIZE];
  FASCIA_TRY(write_group(w, "/organs", -1, -1, -1));
  for (int32_t k = 0; k < m->organ_count; ++k) {
    const fascia_organ *o = m->organs + k;
    snprintf(group, sizeof group, "/organs/%s", o->name);
    FASCIA_TRY(write_group(w, group, k, o->kind, o->motion));
    FASCIA_TRY(write_member(w, group, "vertices", FASCIA_MA_REAL, o->vertex_count, 3, o->vertices, "m"));
    FASCIA_TRY(write_member(w, group, "triangles", FASCIA_MA_INT, o->triangle_count, 3, o->triangles, NULL));
  }
  return FASCIA_OK;
}

// The table's arrays (contract/model_table.h) in its order, but for an EARLY row
// written before the row above; each group before its first dataset.
static fascia_status write_arrays(writer *w, const fascia_model *m, const fascia_model_view *views) {
  char group[PATH_SIZE] = "";
  for (int k = 0; k < FASCIA_MA_COUNT; ++k) {
    const int early = k + 1 < FASCIA_MA_COUNT && (views[k + 1].array->flags & FASCIA_MA_EARLY);
    const fascia_model_view *v = views + (early ? k + 1 : views[k].array->flags & FASCIA_MA_EARLY ? k - 1 : k);
    const fascia_model_array *a = v->array;
    if (a->kind == FASCIA_MA_MATERIAL) FASCIA_TRY(write_materials(w, m));
    else if (a->kind == FASCIA_MA_MOTION) FASCIA_TRY(write_motions(w, m));
    else if (a->kind == FASCIA_MA_ORGAN) FASCIA_TRY(write_organs(w, m));
    else if (fascia_model_view_set(v)) {
      const size_t parent = (size_t)(strrchr(a->path, '/') - a->path);
      if (strlen(group) != parent || strncmp(group, a->path, parent)) {
        snprintf(group, sizeof group, "%.*s", (int)parent, a->path);
        FASCIA_TRY(write_group(w, group, -1, -1, -1));
      }
      FASCIA_TRY(write_dataset(w, a->path, a->kind, a->width > 1 ? 2 : 1, v->rows, a->width, v->data, a->unit));
    }
  }
  return FASCIA_OK;
}

static herr_t attr_u64(hid_t loc, const char *name, uint64_t value) {
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t attr = space >= 0 ? H5Acreate2(loc, name, H5T_STD_U64LE, space, H5P_DEFAULT, H5P_DEFAULT) : H5I_INVALID_HID;
  const herr_t status = attr >= 0 ? H5Awrite(attr, H5T_NATIVE_UINT64, &value) : -1;
  if (attr >= 0) H5Aclose(attr);
  if (space >= 0) H5Sclose(space);
  return status;
}

static fascia_status write_model(writer *w, const fascia_model *m) {
  char creator[64];
  snprintf(creator, sizeof creator, "fascia %s", fascia_version());
  hid_t root = H5Gopen2(w->file, "/", H5P_DEFAULT);
  fascia_model_view views[FASCIA_MA_COUNT];
  fascia_model_views(m, views);
  const int modes = model_modes_version(m);
  const int version = modes                                                      ? modes
                      : fascia_model_view_set(views + FASCIA_MA_ID_sample_patch) ? MODEL_VERSION_PATCHES
                                                                                 : 1;
  const uint64_t checksum = model_checksum(m, version);
  const int ok = root >= 0 && fascia_h5_attr_int(root, "fascia_model_version", version) >= 0 &&
                 attr_u64(root, CHECKSUM_ATTR, checksum) >= 0 &&
                 fascia_h5_attr_string(root, "units", MODEL_UNITS) >= 0 &&
                 fascia_h5_attr_string(root, "creator", creator) >= 0 &&
                 (!m->allow_floating || fascia_h5_attr_int(root, "allow_floating", 1) >= 0);
  if (root >= 0) H5Gclose(root);
  if (!ok) return write_failed(w, "/");
  FASCIA_TRY(write_arrays(w, m, views));
  WRITE1(w, "/gravity", FASCIA_MA_REAL, 3, m->gravity, "m/s^2");
  const fascia_surface *ts = &m->tissue_surface;
  if (ts->triangle_count > 0) { // optional, for drawing: older readers ignore it and simulate the same
    FASCIA_TRY(write_group(w, "/tissue_surface", -1, -1, -1));
    WRITE2(w, "/tissue_surface/vertices", FASCIA_MA_REAL, ts->vertex_count, 3, ts->vertices, "m");
    WRITE2(w, "/tissue_surface/triangles", FASCIA_MA_INT, ts->triangle_count, 3, ts->triangles, NULL);
  }
  if (m->tetrahedron_count > 0) WRITE2(w, "/tetrahedra", FASCIA_MA_INT, m->tetrahedron_count, 4, m->tetrahedra, NULL);
  if (m->provenance) FASCIA_TRY(write_text(w, "/provenance", m->provenance));
  return FASCIA_OK;
}

// Motion and organ names become HDF5 group names: they must be unique within
// their kind, non-empty, without '/', and not ".". Material names only need
// to be terminated. Validation does not cover these, so save checks them.
static fascia_status check_names(fascia_ctx *ctx, const fascia_model *m, const char *path) {
  for (int32_t k = 0; k < m->material_count; ++k)
    FASCIA_CHECK(memchr(m->materials[k].name, 0, FASCIA_NAME_SIZE), ctx, FASCIA_ERR_ARGUMENT,
                 "cannot save model '%s': material %d has an unterminated name", path, (int)k);
  for (int pass = 0; pass < 2; ++pass) {
    const int32_t count = pass ? m->organ_count : m->motion_count;
    const char *kind = pass ? "organ" : "motion";
    for (int32_t k = 0; k < count; ++k) {
      const char *name = pass ? m->organs[k].name : m->motions[k].name;
      FASCIA_CHECK(memchr(name, 0, FASCIA_NAME_SIZE) && name[0] && !strchr(name, '/') && strcmp(name, "."), ctx,
                   FASCIA_ERR_ARGUMENT,
                   "cannot save model '%s': %s %d has name '%.*s'; names must be non-empty, without '/', at most %d "
                   "characters",
                   path, kind, (int)k, FASCIA_NAME_SIZE - 1, name, FASCIA_NAME_SIZE - 1);
      for (int32_t j = 0; j < k; ++j) {
        const char *other = pass ? m->organs[j].name : m->motions[j].name;
        FASCIA_CHECK(strcmp(name, other), ctx, FASCIA_ERR_ARGUMENT,
                     "cannot save model '%s': %ss %d and %d are both named '%s'; names must be unique", path, kind,
                     (int)j, (int)k, name);
      }
    }
  }
  return FASCIA_OK;
}

fascia_status fascia_model_save(fascia_ctx *ctx, const fascia_model *model, const char *path) {
  FASCIA_CHECK(model && path && path[0], ctx, FASCIA_ERR_ARGUMENT, "fascia_model_save: NULL model or empty path");
  fascia_status status = fascia_model_validate(ctx, model, path);
  if (status != FASCIA_OK) {
    char reason[2048];
    snprintf(reason, sizeof reason, "%s", fascia_ctx_message(ctx));
    return FASCIA_FAIL(ctx, status, "cannot save: %s", reason);
  }
  FASCIA_TRY(check_names(ctx, model, path));
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  writer w = {ctx, path, H5I_INVALID_HID};
  // built in memory, then written out: a full disk fails the write, not HDF5
  status = fascia_h5_create_memory(ctx, "model", path, &w.file);
  if (status == FASCIA_OK) {
    status = write_model(&w, model);
    if (status == FASCIA_OK) status = fascia_h5_finish_memory(ctx, "model", &w.file, path);
    else H5Fclose(w.file);
  }
  fascia_h5_quiet_end(&quiet);
  return status;
}

// ---------------------------------------------------------------------------
// Reading

typedef struct reader {
  fascia_ctx *ctx;
  const char *path;
  hid_t file;
  int32_t version;   ///< the file's fascia_model_version
  uint64_t checksum; ///< the file's fascia_model_checksum
} reader;

static const char *class_phrase(H5T_class_t cls) {
  switch (cls) {
  case H5T_INTEGER: return "integers";
  case H5T_FLOAT: return "floating-point numbers";
  case H5T_STRING: return "strings";
  case H5T_COMPOUND: return "a compound type";
  case H5T_ENUM: return "an enumeration";
  case H5T_ARRAY: return "an array type";
  default: return "an unsupported type";
  }
}

// "5x4", "?x3" (unknown count), "" for a scalar.
static void dims_phrase(char *buf, size_t size, int rank, const int64_t *dims) {
  int n = 0;
  buf[0] = 0;
  for (int k = 0; k < rank && n >= 0 && (size_t)n < size; ++k)
    n += dims[k] < 0 ? snprintf(buf + n, size - (size_t)n, "%s?", k ? "x" : "")
                     : snprintf(buf + n, size - (size_t)n, "%s%lld", k ? "x" : "", (long long)dims[k]);
}

static fascia_status read_failed(reader *r, const char *name, const char *action) {
  char detail[600];
  fascia_h5_error(detail, sizeof detail);
  return FASCIA_FAIL(r->ctx, FASCIA_ERR_IO, "model '%s' %s: cannot %s (HDF5: %s); the file may be damaged", r->path,
                     name, action, detail);
}

// Opens dataset `name` and checks it: present, of `kind`, of rank `rank`
// (0..2) with dims[k] rows in axis k, where dims[k] < 0 accepts any count
// and is filled in. Counts over FASCIA_MAX_COUNT are refused before anyone
// allocates for them. On success *out is an open dataset.
static fascia_status open_checked(reader *r, const char *name, fascia_ma_kind kind, int rank, int64_t *dims, hid_t *out) {
  *out = H5I_INVALID_HID;
  FASCIA_CHECK(fascia_h5_link_exists(r->file, name), r->ctx, FASCIA_ERR_FORMAT, "model '%s' %s: dataset missing; %s", r->path,
               name, REMEDY);
  hid_t dset = H5Dopen2(r->file, name, H5P_DEFAULT);
  if (dset < 0) return read_failed(r, name, "open it as a dataset");
  fascia_h5_scope scope = FASCIA_H5_SCOPE_INIT; // all but the dataset, which goes to the caller on success
  const hid_t type = fascia_h5_keep(&scope, H5Dget_type(dset)), space = fascia_h5_keep(&scope, H5Dget_space(dset));
  fascia_status status = FASCIA_OK;
  if (type < 0 || space < 0) {
    status = read_failed(r, name, "read its type and shape");
    goto cleanup;
  }
  const H5T_class_t cls = H5Tget_class(type);
  const H5T_class_t want = kind == FASCIA_MA_REAL ? H5T_FLOAT : kind == FASCIA_MA_INT ? H5T_INTEGER : H5T_STRING;
  if (cls != want) {
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_FORMAT, "model '%s' %s: expected %s, found %s; %s", r->path, name,
                         class_phrase(want), class_phrase(cls), REMEDY);
    goto cleanup;
  }
  if (kind != FASCIA_MA_NAME && !fascia_h5_number_type_ok(type)) {
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_FORMAT, "model '%s' %s: %s of a damaged or unsupported layout; %s",
                         r->path, name, class_phrase(cls), REMEDY);
    goto cleanup;
  }
  hsize_t found[H5S_MAX_RANK];
  const int found_rank = H5Sget_simple_extent_type(space) == H5S_NULL ? -1 : H5Sget_simple_extent_dims(space, found, NULL);
  int64_t found64[H5S_MAX_RANK];
  int match = found_rank == rank;
  int64_t total = 1;
  for (int k = 0; k < found_rank; ++k) {
    found64[k] = found[k] > (hsize_t)INT64_MAX ? INT64_MAX : (int64_t)found[k];
    if (match && dims[k] >= 0 && dims[k] != found64[k]) match = 0;
    total = found64[k] > FASCIA_MAX_COUNT || total > FASCIA_MAX_COUNT ? FASCIA_MAX_COUNT + 1 : total * found64[k];
  }
  if (!match) {
    char want_text[96], found_text[96], dims_text[64];
    dims_phrase(dims_text, sizeof dims_text, rank, dims);
    if (rank == 0)
      snprintf(want_text, sizeof want_text, "a scalar");
    else
      snprintf(want_text, sizeof want_text, "%d-D array of %s values", rank, dims_text);
    dims_phrase(dims_text, sizeof dims_text, found_rank, found64);
    if (found_rank < 0)
      snprintf(found_text, sizeof found_text, "an empty (null) dataspace");
    else if (found_rank == 0)
      snprintf(found_text, sizeof found_text, "a scalar");
    else
      snprintf(found_text, sizeof found_text, "%d-D %s", found_rank, dims_text);
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_FORMAT, "model '%s' %s: expected %s, found %s; %s", r->path, name,
                         want_text, found_text, REMEDY);
    goto cleanup;
  }
  if (total > FASCIA_MAX_COUNT) {
    char dims_text[64];
    dims_phrase(dims_text, sizeof dims_text, found_rank, found64);
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_FORMAT,
                         "model '%s' %s: %s values is more than fascia's limit of %lld per array; the file is damaged "
                         "or not a model",
                         r->path, name, dims_text, (long long)FASCIA_MAX_COUNT);
    goto cleanup;
  }
  for (int k = 0; k < rank; ++k) dims[k] = found64[k];
  *out = dset;
  dset = H5I_INVALID_HID;
cleanup:
  fascia_h5_scope_close(&scope);
  if (dset >= 0) H5Dclose(dset);
  return status;
}

// Row count (axis 0) of dataset `name`, checked as open_checked does, with
// `cols` columns (0 for a 1-D dataset).
static fascia_status count_rows(reader *r, const char *name, fascia_ma_kind kind, int64_t cols, int64_t *rows) {
  int64_t dims[2] = {-1, cols};
  hid_t dset;
  FASCIA_TRY(open_checked(r, name, kind, cols ? 2 : 1, dims, &dset));
  H5Dclose(dset);
  *rows = dims[0];
  return FASCIA_OK;
}

// Reads numeric dataset `name` of exactly [rows] (cols == 0) or [rows,cols]
// into buf, converting to double or int32.
static fascia_status read_numbers(reader *r, const char *name, fascia_ma_kind kind, int64_t rows, int64_t cols, void *buf) {
  int64_t dims[2] = {rows, cols};
  hid_t dset;
  FASCIA_TRY(open_checked(r, name, kind, cols ? 2 : 1, dims, &dset));
  fascia_status status = FASCIA_OK;
  if (rows * (cols ? cols : 1) > 0 &&
      H5Dread(dset, kind == FASCIA_MA_REAL ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0)
    status = read_failed(r, name, "read it");
  H5Dclose(dset);
  return status;
}

#define READ(r, name, kind, rows, cols, buf) FASCIA_TRY(read_numbers(r, name, kind, rows, cols, buf))

// Reads the strings of an open string dataset of `count` elements (rank 0 or
// 1) into one buffer: entry k at out + k * stride, each NUL-terminated,
// max_length characters at most (longer is a format error). Fixed-length and
// variable-length strings are both accepted.
static fascia_status read_strings(reader *r, const char *name, hid_t dset, int64_t count, char *out, size_t stride,
                                  size_t max_length) {
  fascia_status status = FASCIA_OK;
  fascia_h5_scope scope = FASCIA_H5_SCOPE_INIT;
  const hid_t file_type = fascia_h5_keep(&scope, H5Dget_type(dset)), mem_type = fascia_h5_keep(&scope, H5Tcopy(H5T_C_S1)),
              space = fascia_h5_keep(&scope, H5Dget_space(dset));
  char *fixed = NULL, **variable = NULL;
  if (file_type < 0 || mem_type < 0 || space < 0) goto failed;
  const htri_t is_variable = H5Tis_variable_str(file_type);
  const size_t file_size = H5Tget_size(file_type);
  // HDF5 converts no character set into another: read in the file's (ASCII or UTF-8)
  if (is_variable < 0 || file_size == 0 || H5Tset_cset(mem_type, H5Tget_cset(file_type)) < 0) goto failed;
  if (is_variable) {
    variable = fascia_calloc(count, sizeof *variable);
    if (!variable) goto memory;
    if (H5Tset_size(mem_type, H5T_VARIABLE) < 0 ||
        H5Dread(dset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, variable) < 0)
      goto failed;
  } else {
    // one extra byte per string so that the converted value always ends in NUL
    if (file_size > (size_t)FASCIA_MAX_COUNT || count * (int64_t)(file_size + 1) > FASCIA_MAX_COUNT) goto too_long;
    fixed = fascia_calloc(count, file_size + 1);
    if (!fixed) goto memory;
    if (H5Tset_size(mem_type, file_size + 1) < 0 || H5Tset_strpad(mem_type, H5T_STR_NULLTERM) < 0 ||
        H5Dread(dset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, fixed) < 0)
      goto failed;
  }
  for (int64_t k = 0; k < count; ++k) {
    const char *text = variable ? (variable[k] ? variable[k] : "") : fixed + k * (int64_t)(file_size + 1);
    const size_t length = strlen(text);
    if (length > max_length) {
      status = FASCIA_FAIL(r->ctx, FASCIA_ERR_FORMAT, "model '%s' %s: entry %lld has %zu characters, at most %zu allowed",
                           r->path, name, (long long)k, length, max_length);
      goto cleanup;
    }
    memcpy(out + k * (int64_t)stride, text, length + 1);
  }
  goto cleanup;
too_long:
  status = FASCIA_FAIL(r->ctx, FASCIA_ERR_FORMAT, "model '%s' %s: strings of %zu bytes are too long", r->path, name,
                       file_size);
  goto cleanup;
memory:
  status = FASCIA_FAIL(r->ctx, FASCIA_ERR_MEMORY, "model '%s' %s: out of memory", r->path, name);
  goto cleanup;
failed:
  status = read_failed(r, name, "read its strings");
cleanup:
  if (variable) H5Dvlen_reclaim(mem_type, space, H5P_DEFAULT, variable);
  free(variable);
  free(fixed);
  fascia_h5_scope_close(&scope);
  return status;
}

static fascia_status read_names(reader *r, const char *name, int64_t count, char (*out)[FASCIA_NAME_SIZE]) {
  int64_t dims[1] = {count};
  hid_t dset;
  FASCIA_TRY(open_checked(r, name, FASCIA_MA_NAME, 1, dims, &dset));
  fascia_status status = FASCIA_OK;
  if (count > 0) status = read_strings(r, name, dset, count, out[0], FASCIA_NAME_SIZE, FASCIA_NAME_SIZE - 1);
  H5Dclose(dset);
  return status;
}

// Reads the optional scalar string /provenance into *out (NULL if absent).
static fascia_status read_provenance(reader *r, char **out) {
  *out = NULL;
  if (!fascia_h5_link_exists(r->file, "/provenance")) return FASCIA_OK;
  int64_t dims[1];
  hid_t dset;
  FASCIA_TRY(open_checked(r, "/provenance", FASCIA_MA_NAME, 0, dims, &dset));
  fascia_status status = FASCIA_OK;
  fascia_h5_scope scope = FASCIA_H5_SCOPE_INIT;
  fascia_h5_keep(&scope, dset);
  const hid_t type = fascia_h5_keep(&scope, H5Dget_type(dset)), mem_type = fascia_h5_keep(&scope, H5Tcopy(H5T_C_S1)),
              space = fascia_h5_keep(&scope, H5Dget_space(dset));
  char *variable = NULL;
  const htri_t is_variable = type >= 0 ? H5Tis_variable_str(type) : -1;
  if (type < 0 || mem_type < 0 || space < 0 || is_variable < 0 || H5Tset_cset(mem_type, H5Tget_cset(type)) < 0)
    goto failed;
  // a variable-length string is measured after reading, a fixed one by its type
  size_t size = 0;
  if (is_variable) {
    if (H5Tset_size(mem_type, H5T_VARIABLE) < 0 || H5Dread(dset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, &variable) < 0)
      goto failed;
    size = variable ? strlen(variable) : 0;
  } else {
    size = H5Tget_size(type);
  }
  if (size >= (size_t)FASCIA_MAX_COUNT || !(*out = malloc(size + 1))) {
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_MEMORY, "model '%s' /provenance: out of memory for %zu bytes", r->path,
                         size);
    goto cleanup;
  }
  if (is_variable) {
    memcpy(*out, variable ? variable : "", size + 1);
  } else if (H5Tset_size(mem_type, size + 1) < 0 || H5Tset_strpad(mem_type, H5T_STR_NULLTERM) < 0 ||
             H5Dread(dset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, *out) < 0) {
    goto failed;
  }
  goto cleanup;
failed:
  status = read_failed(r, "/provenance", "read it");
cleanup:
  if (variable) H5Dvlen_reclaim(mem_type, space, H5P_DEFAULT, &variable);
  fascia_h5_scope_close(&scope);
  if (status != FASCIA_OK) {
    free(*out);
    *out = NULL;
  }
  return status;
}

// Reads integer attribute `attr` of the object at `name` (scalar or one value).
static fascia_status read_int_attr(reader *r, const char *name, const char *attr_name, int32_t *value) {
  const htri_t exists = H5Aexists_by_name(r->file, name, attr_name, H5P_DEFAULT);
  FASCIA_CHECK(exists > 0, r->ctx, FASCIA_ERR_FORMAT, "model '%s' %s: attribute '%s' missing; %s", r->path, name,
               attr_name, REMEDY);
  fascia_h5_scope scope = FASCIA_H5_SCOPE_INIT;
  fascia_status status = FASCIA_OK;
  const hid_t attr = fascia_h5_keep(&scope, H5Aopen_by_name(r->file, name, attr_name, H5P_DEFAULT, H5P_DEFAULT));
  const hid_t type = attr >= 0 ? fascia_h5_keep(&scope, H5Aget_type(attr)) : H5I_INVALID_HID;
  const hid_t space = attr >= 0 ? fascia_h5_keep(&scope, H5Aget_space(attr)) : H5I_INVALID_HID;
  if (attr < 0 || type < 0 || space < 0)
    status = read_failed(r, name, "open an attribute");
  else if (H5Tget_class(type) != H5T_INTEGER || !fascia_h5_number_type_ok(type) ||
           H5Sget_simple_extent_npoints(space) != 1)
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_FORMAT, "model '%s' %s: attribute '%s' is not one integer (found %s); %s",
                         r->path, name, attr_name, class_phrase(H5Tget_class(type)), REMEDY);
  else if (H5Aread(attr, H5T_NATIVE_INT32, value) < 0)
    status = read_failed(r, name, "read an attribute");
  fascia_h5_scope_close(&scope);
  return status;
}

static fascia_status read_version(reader *r) {
  const htri_t exists = H5Aexists_by_name(r->file, "/", "fascia_model_version", H5P_DEFAULT);
  FASCIA_CHECK(exists > 0, r->ctx, FASCIA_ERR_FORMAT,
               "model '%s' /: not a fascia model file (no root attribute 'fascia_model_version'); %s", r->path, REMEDY);
  int32_t version = 0;
  FASCIA_TRY(read_int_attr(r, "/", "fascia_model_version", &version));
  r->version = version;
  FASCIA_CHECK(version >= MODEL_VERSION_MIN && version <= MODEL_VERSION_MAX, r->ctx, FASCIA_ERR_FORMAT,
               "model '%s' /: format version %d is not supported, this fascia (%s) reads versions %d to %d; %s",
               r->path, (int)version, fascia_version(), MODEL_VERSION_MIN, MODEL_VERSION_MAX,
               version > MODEL_VERSION_MAX ? "use a newer fascia" : REMEDY);
  return FASCIA_OK;
}

// The stored checksum, compared with the model's once everything is read.
static fascia_status read_checksum(reader *r) {
  const htri_t exists = H5Aexists_by_name(r->file, "/", CHECKSUM_ATTR, H5P_DEFAULT);
  FASCIA_CHECK(exists > 0, r->ctx, FASCIA_ERR_FORMAT,
               "model '%s' /: no checksum (root attribute '%s' missing): written by an older fascia, or edited; "
               "re-run 'fascia prep' (or 'fascia beam') to write it again",
               r->path, CHECKSUM_ATTR);
  fascia_h5_scope scope = FASCIA_H5_SCOPE_INIT;
  const hid_t attr = fascia_h5_keep(&scope, H5Aopen_by_name(r->file, "/", CHECKSUM_ATTR, H5P_DEFAULT, H5P_DEFAULT));
  const hid_t type = attr >= 0 ? fascia_h5_keep(&scope, H5Aget_type(attr)) : H5I_INVALID_HID;
  const hid_t space = attr >= 0 ? fascia_h5_keep(&scope, H5Aget_space(attr)) : H5I_INVALID_HID;
  const int ok = type >= 0 && space >= 0 && H5Tget_class(type) == H5T_INTEGER && H5Tget_size(type) == 8 &&
                 H5Tget_sign(type) == H5T_SGN_NONE && fascia_h5_number_type_ok(type) &&
                 H5Sget_simple_extent_npoints(space) == 1 && H5Aread(attr, H5T_NATIVE_UINT64, &r->checksum) >= 0;
  fascia_h5_scope_close(&scope);
  FASCIA_CHECK(ok, r->ctx, FASCIA_ERR_FORMAT,
               "model '%s' /: attribute '%s' is not one unsigned 64-bit integer: the file is damaged or was edited; "
               "re-run 'fascia prep'",
               r->path, CHECKSUM_ATTR);
  return FASCIA_OK;
}

// Number of members of group `name` (each a motion or organ).
static fascia_status count_members(reader *r, const char *name, int64_t *count) {
  FASCIA_CHECK(fascia_h5_link_exists(r->file, name), r->ctx, FASCIA_ERR_FORMAT, "model '%s' %s: group missing; %s", r->path,
               name, REMEDY);
  fascia_h5_scope scope = FASCIA_H5_SCOPE_INIT;
  const hid_t group = fascia_h5_keep(&scope, H5Gopen2(r->file, name, H5P_DEFAULT));
  H5G_info_t info;
  const herr_t ok = group >= 0 ? H5Gget_info(group, &info) : -1;
  if (ok < 0) {
    const fascia_status status = read_failed(r, name, group < 0 ? "open it as a group" : "list it");
    fascia_h5_scope_close(&scope);
    return status;
  }
  fascia_h5_scope_close(&scope);
  FASCIA_CHECK(info.nlinks <= (hsize_t)FASCIA_MAX_COUNT, r->ctx, FASCIA_ERR_FORMAT,
               "model '%s' %s: %llu members is beyond fascia's limit; the file is damaged", r->path, name,
               (unsigned long long)info.nlinks);
  *count = (int64_t)info.nlinks;
  return FASCIA_OK;
}

// Member k of group `group` (in name order): from its attribute `index`, its
// place in the model, checked to be in range and not taken (the name there,
// at names + index * stride, still empty), which then gets its name.
static fascia_status member(reader *r, const char *group, int64_t k, int32_t count, char *names, size_t stride,
                            char *member_path, int32_t *index) {
  char link[FASCIA_NAME_SIZE + 1];
  const ssize_t length =
      H5Lget_name_by_idx(r->file, group, H5_INDEX_NAME, H5_ITER_INC, (hsize_t)k, link, sizeof link, H5P_DEFAULT);
  if (length < 0) return read_failed(r, group, "list it");
  FASCIA_CHECK(length < FASCIA_NAME_SIZE, r->ctx, FASCIA_ERR_FORMAT,
               "model '%s' %s: member %lld has a name longer than %d characters", r->path, group, (long long)k,
               FASCIA_NAME_SIZE - 1);
  snprintf(member_path, PATH_SIZE, "%s/%s", group, link);
  FASCIA_TRY(read_int_attr(r, member_path, "index", index));
  FASCIA_CHECK(*index >= 0 && *index < count, r->ctx, FASCIA_ERR_FORMAT,
               "model '%s' %s: index %d is out of range 0..%d", r->path, member_path, (int)*index, (int)count - 1);
  char *name = names + (size_t)*index * stride;
  FASCIA_CHECK(!name[0], r->ctx, FASCIA_ERR_FORMAT, "model '%s' %s: index %d is also used by '%s'", r->path,
               member_path, (int)*index, name);
  memcpy(name, link, (size_t)length + 1);
  return FASCIA_OK;
}

// A dataset that declares many values must store them: HDF5 reads the fill
// value (zeros) for storage never written, so a file of a few kilobytes can
// declare arrays of gigabytes. Every dataset fascia writes is stored whole.
// Small datasets are left to the shape, type and value checks (a wrong
// shape says more than "not stored"); they cannot exhaust memory.
#define STORED_CHECK_VALUES 65536
static fascia_status check_stored(reader *r, const char *name) {
  if (!fascia_h5_link_exists(r->file, name)) return FASCIA_OK; // reported as missing where it is read
  fascia_h5_scope scope = FASCIA_H5_SCOPE_INIT;
  const hid_t dset = fascia_h5_keep(&scope, H5Dopen2(r->file, name, H5P_DEFAULT));
  if (dset < 0) return FASCIA_OK; // reported where it is read
  const hid_t space = fascia_h5_keep(&scope, H5Dget_space(dset));
  const hssize_t values = space >= 0 ? H5Sget_simple_extent_npoints(space) : 0;
  H5D_space_status_t stored = H5D_SPACE_STATUS_ERROR;
  const herr_t ok = H5Dget_space_status(dset, &stored);
  fascia_h5_scope_close(&scope);
  FASCIA_CHECK(values < STORED_CHECK_VALUES || (ok >= 0 && stored == H5D_SPACE_STATUS_ALLOCATED), r->ctx, FASCIA_ERR_FORMAT,
               "model '%s' %s: declares %lld values but the file stores %s of them; the file is damaged or "
               "truncated, %s",
               r->path, name, (long long)values, stored == H5D_SPACE_STATUS_PART_ALLOCATED ? "only some" : "none",
               REMEDY);
  return FASCIA_OK;
}

// Bytes the model's arrays take for these sizes (fascia_model_alloc), and the
// machine's physical memory (0 when unknown).
static double model_bytes(const fascia_model_sizes *z) {
  double bytes = 0;
#define BYTES(field, kind, count, plus, width, ...)                                                                  \
  bytes += ((double)z->count + (plus)) * (width) * (double)fascia_model_array_size(FASCIA_MA_##kind);
  FASCIA_MODEL_ARRAYS(BYTES)
#undef BYTES
  return bytes;
}

static double physical_memory(void) {
#if defined(_SC_PHYS_PAGES) && defined(_SC_PAGESIZE)
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0) return (double)pages * (double)page;
#endif
  return 0;
}

// Refuses sizes whose arrays would not fit in memory, before allocating.
static fascia_status check_memory(reader *r, const fascia_model_sizes *z) {
  const double need = model_bytes(z), have = physical_memory();
  FASCIA_CHECK(have <= 0 || need <= have, r->ctx, FASCIA_ERR_MEMORY,
               "model '%s': %d frames, %d samples and %d sample-frame pairs need %.1f GiB for the model alone, more "
               "than this machine's %.1f GiB of memory; use a coarser model (larger frame and sample spacing)",
               r->path, (int)z->frames, (int)z->samples, (int)z->pairs, need / 1073741824.0, have / 1073741824.0);
  return FASCIA_OK;
}

// The dataset whose rows count a row's entries: a material's name.
static const char *counted_dataset(const fascia_model_array *a) {
  return a->kind == FASCIA_MA_MATERIAL ? "/materials/name" : a->path;
}

// The number of entries the file holds for a row: its dataset's rows, or the
// members of its group (motions, organs).
static fascia_status count_entries(reader *r, const fascia_model_array *a, int64_t *n) {
  if (a->kind == FASCIA_MA_MOTION || a->kind == FASCIA_MA_ORGAN) return count_members(r, a->path, n);
  if (a->kind == FASCIA_MA_MATERIAL) return count_rows(r, counted_dataset(a), FASCIA_MA_NAME, 0, n);
  return count_rows(r, a->path, a->kind, a->width > 1 ? a->width : 0, n);
}

static fascia_status read_sizes(reader *r, fascia_model_sizes *z) {
  int64_t n;
  // open_checked bounded every count by FASCIA_MAX_COUNT (< INT32_MAX)
#define SIZE(field, kind, count, plus, width, path, unit, fill, flags, ...)                                          \
  if ((flags) & FASCIA_MA_SIZES) {                                                                                   \
    FASCIA_TRY(count_entries(r, fascia_model_arrays + FASCIA_MA_ID_##field, &n));                                   \
    z->count = (int32_t)n;                                                                                           \
  }
  FASCIA_MODEL_ARRAYS(SIZE)
#undef SIZE
  FASCIA_CHECK(z->pairs <= (int64_t)z->samples * 1024, r->ctx, FASCIA_ERR_FORMAT,
               "model '%s' /pairs/frame: %lld pairs for %lld samples is more than 1024 neighbours per sample; %s",
               r->path, (long long)z->pairs, (long long)z->samples, REMEDY);
  for (int k = 0; k < FASCIA_MA_COUNT; ++k)
    if (fascia_model_arrays[k].kind != FASCIA_MA_MOTION && fascia_model_arrays[k].kind != FASCIA_MA_ORGAN)
      FASCIA_TRY(check_stored(r, counted_dataset(fascia_model_arrays + k)));
  return check_memory(r, z);
}

static fascia_status read_materials(reader *r, fascia_model *m) {
  const int64_t M = m->material_count;
  char *column = fascia_calloc(M, FASCIA_NAME_SIZE); // the largest field
  FASCIA_CHECK(column, r->ctx, FASCIA_ERR_MEMORY, "model '%s' /materials: out of memory", r->path);
  fascia_status status = FASCIA_OK;
  for (size_t f = 0; f < MATERIAL_FIELD_COUNT && status == FASCIA_OK; ++f) {
    const material_field *field = material_fields + f;
    const size_t size = fascia_model_array_size(field->kind);
    if (f == MATERIAL_FIELD_COUNT - 1 && !fascia_h5_link_exists(r->file, field->path)) break; // part
    status = field->kind == FASCIA_MA_NAME ? read_names(r, field->path, M, (char(*)[FASCIA_NAME_SIZE])column)
                                           : read_numbers(r, field->path, field->kind, M, 0, column);
    for (int64_t k = 0; k < M && status == FASCIA_OK; ++k)
      memcpy((char *)(m->materials + k) + field->offset, column + k * size, size);
  }
  free(column);
  return status;
}

// Dataset `leaf` of a motion's or organ's group: its rows (as count_rows),
// checked to be stored, and its path in `name`.
static fascia_status count_member_rows(reader *r, const char *group, const char *leaf, fascia_ma_kind kind,
                                       int64_t cols, char *name, size_t size, int64_t *rows) {
  snprintf(name, size, "%s/%s", group, leaf);
  FASCIA_TRY(count_rows(r, name, kind, cols, rows));
  return check_stored(r, name);
}

// Reads dataset `leaf` of a motion's or organ's group (as read_numbers).
static fascia_status read_member(reader *r, const char *group, const char *leaf, fascia_ma_kind kind, int64_t rows,
                                 int64_t cols, void *buf) {
  char name[PATH_SIZE + 16];
  snprintf(name, sizeof name, "%s/%s", group, leaf);
  return read_numbers(r, name, kind, rows, cols, buf);
}

static fascia_status read_motions(reader *r, fascia_model *m) {
  char group[PATH_SIZE], name[PATH_SIZE + 16];
  for (int64_t k = 0; k < m->motion_count; ++k) {
    int32_t index;
    int64_t K;
    FASCIA_TRY(member(r, "/motions", k, m->motion_count, m->motions->name, sizeof *m->motions, group, &index));
    fascia_motion *mo = m->motions + index;
    FASCIA_TRY(count_member_rows(r, group, "time", FASCIA_MA_REAL, 0, name, sizeof name, &K));
    FASCIA_CHECK(K >= 1, r->ctx, FASCIA_ERR_FORMAT, "model '%s' %s: no keyframe, expected at least one; %s", r->path,
                 name, REMEDY);
    FASCIA_TRY(fascia_motion_alloc(r->ctx, mo, (int32_t)K));
    FASCIA_TRY(read_member(r, group, "time", FASCIA_MA_REAL, K, 0, mo->key_time));
    FASCIA_TRY(read_member(r, group, "pivot", FASCIA_MA_REAL, 3, 0, mo->pivot));
    FASCIA_TRY(read_member(r, group, "translation", FASCIA_MA_REAL, K, 3, mo->key_translation));
    FASCIA_TRY(read_member(r, group, "rotation", FASCIA_MA_REAL, K, 4, mo->key_rotation));
  }
  return FASCIA_OK;
}

static fascia_status read_organs(reader *r, fascia_model *m) {
  char group[PATH_SIZE], name[PATH_SIZE + 16];
  for (int64_t k = 0; k < m->organ_count; ++k) {
    int32_t index;
    int64_t V, T;
    FASCIA_TRY(member(r, "/organs", k, m->organ_count, m->organs->name, sizeof *m->organs, group, &index));
    fascia_organ *o = m->organs + index;
    FASCIA_TRY(read_int_attr(r, group, "kind", &o->kind));
    FASCIA_TRY(read_int_attr(r, group, "motion", &o->motion));
    FASCIA_TRY(count_member_rows(r, group, "vertices", FASCIA_MA_REAL, 3, name, sizeof name, &V));
    FASCIA_TRY(count_member_rows(r, group, "triangles", FASCIA_MA_INT, 3, name, sizeof name, &T));
    FASCIA_TRY(fascia_organ_alloc(r->ctx, o, (int32_t)V, (int32_t)T));
    FASCIA_TRY(read_member(r, group, "vertices", FASCIA_MA_REAL, V, 3, o->vertices));
    FASCIA_TRY(read_member(r, group, "triangles", FASCIA_MA_INT, T, 3, o->triangles));
  }
  return FASCIA_OK;
}

// The table's arrays (contract/model_table.h) in its order. A dataset of a later
// version than the file's keeps its fill, as does an optional one the file
// lacks (organ owners came with deformable organs: files without them are
// all tissue).
static fascia_status read_arrays(reader *r, fascia_model *m) {
  fascia_model_view views[FASCIA_MA_COUNT];
  fascia_model_views(m, views);
  for (int k = 0; k < FASCIA_MA_COUNT; ++k) {
    const fascia_model_array *a = views[k].array;
    if (a->since ? r->version < a->since : !fascia_h5_link_exists(r->file, a->path)) continue;
    if (a->kind == FASCIA_MA_MATERIAL) FASCIA_TRY(read_materials(r, m));
    else if (a->kind == FASCIA_MA_MOTION) FASCIA_TRY(read_motions(r, m));
    else if (a->kind == FASCIA_MA_ORGAN) FASCIA_TRY(read_organs(r, m));
    else if (a->kind == FASCIA_MA_NAME) FASCIA_TRY(read_names(r, a->path, views[k].rows, views[k].data));
    else READ(r, a->path, a->kind, views[k].rows, a->width > 1 ? a->width : 0, views[k].data);
  }
  for (int64_t s = 0; s < m->sample_count && r->version < MODEL_VERSION_MODE_SETS; ++s)
    FASCIA_CHECK(m->sample_modes[s] <= FASCIA_MODES_NINE, r->ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /samples/modes: sample %d has %d, which needs format version %d (the file says %d)",
                 r->path, (int)s, (int)m->sample_modes[s], MODEL_VERSION_MODE_SETS, (int)r->version);
  return FASCIA_OK;
}

// What follows the table's arrays: gravity, the optional parts, provenance.
static fascia_status read_rest(reader *r, fascia_model *m) {
  READ(r, "/gravity", FASCIA_MA_REAL, 3, 0, m->gravity);
  // optional: absent in files of models that must be held everywhere
  const htri_t floating = H5Aexists_by_name(r->file, "/", "allow_floating", H5P_DEFAULT);
  if (floating > 0) {
    FASCIA_TRY(read_int_attr(r, "/", "allow_floating", &m->allow_floating));
    FASCIA_CHECK(m->allow_floating == 0 || m->allow_floating == 1, r->ctx, FASCIA_ERR_FORMAT,
                 "model '%s' /: attribute 'allow_floating' is %d, not 0 or 1; %s", r->path, (int)m->allow_floating,
                 REMEDY);
  }
  if (fascia_h5_link_exists(r->file, "/tissue_surface/triangles")) {
    int64_t V, T;
    FASCIA_TRY(count_rows(r, "/tissue_surface/vertices", FASCIA_MA_REAL, 3, &V));
    FASCIA_TRY(count_rows(r, "/tissue_surface/triangles", FASCIA_MA_INT, 3, &T));
    FASCIA_TRY(check_stored(r, "/tissue_surface/vertices"));
    FASCIA_TRY(check_stored(r, "/tissue_surface/triangles"));
    FASCIA_TRY(fascia_surface_alloc(r->ctx, &m->tissue_surface, (int32_t)V, (int32_t)T));
    READ(r, "/tissue_surface/vertices", FASCIA_MA_REAL, V, 3, m->tissue_surface.vertices);
    READ(r, "/tissue_surface/triangles", FASCIA_MA_INT, T, 3, m->tissue_surface.triangles);
  }
  if (fascia_h5_link_exists(r->file, "/tetrahedra")) {
    int64_t M;
    FASCIA_TRY(count_rows(r, "/tetrahedra", FASCIA_MA_INT, 4, &M));
    FASCIA_TRY(check_stored(r, "/tetrahedra"));
    FASCIA_TRY(fascia_model_tetrahedra_alloc(r->ctx, m, (int32_t)M));
    READ(r, "/tetrahedra", FASCIA_MA_INT, M, 4, m->tetrahedra);
  }
  return read_provenance(r, &m->provenance);
}

// Opens path read-only; a missing, unreadable or non-HDF5 file is FASCIA_ERR_IO.
static fascia_status open_file(reader *r) {
  return fascia_h5_open_read(r->ctx, "model", r->path, "expected a model written by 'fascia prep' or 'fascia beam'",
                             &r->file);
}

fascia_status fascia_model_load(fascia_ctx *ctx, const char *path, fascia_model **out) {
  FASCIA_CHECK(out && path, ctx, FASCIA_ERR_ARGUMENT, "fascia_model_load: NULL argument");
  *out = NULL;
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  reader r = {ctx, path, H5I_INVALID_HID, 0, 0};
  fascia_model *m = NULL;
  fascia_model_sizes sizes;
  fascia_status status = FASCIA_OK;
  FASCIA_TRY_GOTO(open_file(&r));
  FASCIA_TRY_GOTO(read_version(&r));
  FASCIA_TRY_GOTO(read_checksum(&r));
  FASCIA_TRY_GOTO(read_sizes(&r, &sizes));
  FASCIA_TRY_GOTO(fascia_model_alloc(ctx, &sizes, &m));
  FASCIA_TRY_GOTO(read_arrays(&r, m));
  FASCIA_TRY_GOTO(read_rest(&r, m));
cleanup:
  if (r.file >= 0) H5Fclose(r.file);
  fascia_h5_quiet_end(&quiet);
  // index and value checks name the file through `path`
  if (status == FASCIA_OK) status = fascia_model_validate(ctx, m, path);
  if (status == FASCIA_OK && model_checksum(m, r.version) != r.checksum)
    status = FASCIA_FAIL(ctx, FASCIA_ERR_FORMAT,
                         "model '%s': checksum mismatch: the file is damaged or was edited; re-run fascia prep", path);
  if (status == FASCIA_OK)
    *out = m;
  else
    fascia_model_destroy(&m);
  return status;
}
