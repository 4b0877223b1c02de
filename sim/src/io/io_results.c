// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The results writer: a time series of frame and sample states in HDF5 with
// an XDMF sidecar for ParaView. Specification: docs/results-format.md.
//
// Schema, version 2 (T steps, N frames, S samples; f64 little endian):
//   /                   attributes fascia_results_version (= 2), units,
//                       creator, every, frame_count, sample_count, step_count
//   /steps/time         [T]      s    extendible, chunked
//   /frames/position, displacement, axis_x, axis_y, axis_z  [T,N,3]
//   /frames/rotation    [T,N,4]  unit quaternions w,x,y,z
//   /frames/kind, organ [N] i32, rest_position [N,3]  (static, from the model)
//   /samples/position, displacement [T,S,3]  only with write_samples
//   /samples/material, organ [S] i32, volume [S], rest_position [S,3] (static)
//   /samples/fields/NAME [T,S]   per-sample scalar, NaN where not given
//   /provenance         scalar string, the model's provenance (if any)
//   /xdmf               what the sidecar reads: vertex lists and, per step,
//                       virtual datasets viewing row t of each series
// Every dataset carries the attributes `unit` and `meaning`. Every series
// grows by one row per fascia_results_append; close trims them all to the
// steps that completed, so a failed append leaves no ragged tail.
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/files.h"
#include "fascia/results.h"
#include "fascia/solver.h"
#include "fascia/vtk_xml.h"
#include "io/h5io.h"

#define RESULTS_VERSION 2
#define RESULTS_UNITS "SI: m, kg, s, Pa"
// Rows of one chunk along N or S: one step of up to 65536 frames is one
// chunk (at most 2 MiB), written whole, so appending never re-reads a chunk.
#define CHUNK_ROWS 65536
// Time values per chunk of /steps/time.
#define CHUNK_TIMES 1024
#define PATH_SIZE 4096
#define TEXT_SIZE 256

typedef struct field {
  char name[FASCIA_NAME_SIZE];
  char unit[TEXT_SIZE]; ///< as described, for the XDMF sidecar
  hid_t dset;
} field;

// The per-step series of 3-vectors, in the order of their ids below: their
// HDF5 path, whether they are per sample, the unit and the meaning.
enum { SERIES_FRAME_POSITION, SERIES_FRAME_DISPLACEMENT, SERIES_AXIS_X, SERIES_AXIS_Y, SERIES_AXIS_Z,
       SERIES_SAMPLE_POSITION, SERIES_SAMPLE_DISPLACEMENT, SERIES_COUNT };
typedef struct series_info {
  const char *path, *name, *unit, *meaning;
  bool samples;
} series_info;
static const series_info series_table[SERIES_COUNT] = {
    {"/frames/position", "position", "m", "frame position x_i, world", false},
    {"/frames/displacement", "displacement", "m", "frame position minus its rest position", false},
    {"/frames/axis_x", "axis_x", "1", "first column of the frame rotation R_i: the frame's x axis, world", false},
    {"/frames/axis_y", "axis_y", "1", "second column of the frame rotation R_i: the frame's y axis, world", false},
    {"/frames/axis_z", "axis_z", "1", "third column of the frame rotation R_i: the frame's z axis, world", false},
    {"/samples/position", "position", "m", "deformed sample position p_s, world", true},
    {"/samples/displacement", "displacement", "m", "sample position minus its rest position", true},
};

struct fascia_results {
  fascia_ctx *ctx;
  char path[PATH_SIZE], tmp[PATH_SIZE];
  hid_t file, time, frame_rotation;
  hid_t series[SERIES_COUNT];
  int32_t frame_count, sample_count, every;
  bool write_samples;
  int64_t step_count, time_capacity;
  fascia_real *times; ///< [step_count] for the XDMF sidecar
  fascia_real *frame_rest, *sample_rest; ///< [3N], [3S]: rest positions, for the displacements
  fascia_real *scratch;                  ///< [3 max(N, S)]: one row being written
  char time_meaning[TEXT_SIZE];          ///< what /steps/time means (fascia_results_set_time_meaning)
  int32_t field_count;
  field fields[FASCIA_RESULTS_MAX_FIELDS];
};

fascia_results_def fascia_results_def_default(void) {
  fascia_results_def def;
  memset(&def, 0, sizeof def);
  def.every = 1;
  def.cookie_ = FASCIA_DEF_COOKIE;
  return def;
}

int32_t fascia_results_step_count(const fascia_results *r) { return r ? (int32_t)r->step_count : 0; }

static fascia_status h5_failed(fascia_results *r, const char *name, const char *action) {
  char detail[600];
  fascia_h5_error(detail, sizeof detail);
  return FASCIA_FAIL(r->ctx, FASCIA_ERR_IO, "results '%s' %s: cannot %s (HDF5: %s); check the disk space", r->path,
                     name, action, detail);
}

// Creates an extendible series `name` of rank 1 [0] or rank 2..3 [0,rows(,cols)],
// growing along axis 0; values not written read as NaN.
static hid_t create_series(hid_t file, const char *name, int rank, hsize_t rows, hsize_t cols) {
  const hsize_t dims[3] = {0, rows, cols}, max[3] = {H5S_UNLIMITED, rows, cols};
  const hsize_t chunk[3] = {rank == 1 ? CHUNK_TIMES : 1, rows < CHUNK_ROWS ? rows : CHUNK_ROWS, cols};
  const double nan_value = NAN;
  hid_t space = H5Screate_simple(rank, dims, max), dcpl = H5Pcreate(H5P_DATASET_CREATE), dset = H5I_INVALID_HID;
  if (space >= 0 && dcpl >= 0 && H5Pset_chunk(dcpl, rank, chunk) >= 0 &&
      H5Pset_fill_value(dcpl, H5T_NATIVE_DOUBLE, &nan_value) >= 0)
    dset = H5Dcreate2(file, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  if (dcpl >= 0) H5Pclose(dcpl);
  if (space >= 0) H5Sclose(space);
  return dset;
}

// Grows series dset to at least step+1 rows and writes row `step` from data
// (row of `rows` x `cols` values; rank as in create_series).
static herr_t write_row(hid_t dset, int rank, int64_t step, hsize_t rows, hsize_t cols, const fascia_real *data) {
  hsize_t dims[3];
  hid_t space = H5Dget_space(dset);
  if (space < 0) return -1;
  H5Sget_simple_extent_dims(space, dims, NULL);
  H5Sclose(space);
  if (dims[0] <= (hsize_t)step) {
    dims[0] = (hsize_t)step + 1;
    if (H5Dset_extent(dset, dims) < 0) return -1;
  }
  const hsize_t start[3] = {(hsize_t)step, 0, 0}, count[3] = {1, rows, cols};
  herr_t status = -1;
  space = H5Dget_space(dset);
  hid_t memory = H5Screate_simple(rank, count, NULL);
  if (space >= 0 && memory >= 0 && H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, count, NULL) >= 0)
    status = H5Dwrite(dset, H5T_NATIVE_DOUBLE, memory, space, H5P_DEFAULT, data);
  if (memory >= 0) H5Sclose(memory);
  if (space >= 0) H5Sclose(space);
  return status;
}

// The attributes every dataset carries: its unit and what it means (given
// again, they replace the earlier ones).
static herr_t describe(hid_t dset, const char *unit, const char *meaning) {
  const char *names[2] = {"unit", "meaning"}, *values[2] = {unit, meaning};
  for (int k = 0; k < 2; ++k) {
    if (H5Aexists(dset, names[k]) > 0 && H5Adelete(dset, names[k]) < 0) return -1;
    if (fascia_h5_attr_string(dset, names[k], values[k]) < 0) return -1;
  }
  return 0;
}

// A dataset written once: count rows of cols values (cols 0: rank 1).
static herr_t write_static(hid_t file, const char *name, hid_t file_type, hid_t mem_type, hsize_t count, hsize_t cols,
                           const void *data, const char *unit, const char *meaning) {
  herr_t status = -1;
  const hsize_t dims[2] = {count, cols};
  hid_t space = H5Screate_simple(cols ? 2 : 1, dims, NULL), dset = H5I_INVALID_HID;
  if (space >= 0) dset = H5Dcreate2(file, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (dset >= 0) status = H5Dwrite(dset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
  if (status >= 0) status = describe(dset, unit, meaning);
  if (dset >= 0) H5Dclose(dset);
  if (space >= 0) H5Sclose(space);
  return status;
}

static herr_t create_group(hid_t file, const char *name) {
  hid_t group = H5Gcreate2(file, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  return group >= 0 ? H5Gclose(group) : -1;
}

static herr_t write_text(hid_t file, const char *name, const char *text) {
  hid_t type = H5Tcopy(H5T_C_S1), space = H5Screate(H5S_SCALAR), dset = H5I_INVALID_HID;
  herr_t status = -1;
  if (type >= 0 && space >= 0 && H5Tset_size(type, strlen(text) + 1) >= 0 && H5Tset_cset(type, H5T_CSET_UTF8) >= 0)
    dset = H5Dcreate2(file, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (dset >= 0) status = H5Dwrite(dset, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, text);
  if (dset >= 0) H5Dclose(dset);
  if (space >= 0) H5Sclose(space);
  if (type >= 0) H5Tclose(type);
  return status;
}

// Root attributes, groups, static datasets and empty series.
static fascia_status create_layout(fascia_results *r, const fascia_model *m) {
  char creator[64], fingerprint[32];
  snprintf(creator, sizeof creator, "fascia %s", fascia_version());
  snprintf(fingerprint, sizeof fingerprint, "%016llx", (unsigned long long)fascia_model_fingerprint(m));
  hid_t root = H5Gopen2(r->file, "/", H5P_DEFAULT);
  const int ok = root >= 0 && fascia_h5_attr_int(root, "fascia_results_version", RESULTS_VERSION) >= 0 &&
                 fascia_h5_attr_string(root, "model_fingerprint", fingerprint) >= 0 &&
                 fascia_h5_attr_string(root, "units", RESULTS_UNITS) >= 0 &&
                 fascia_h5_attr_string(root, "creator", creator) >= 0 &&
                 fascia_h5_attr_int(root, "every", r->every) >= 0 &&
                 fascia_h5_attr_int(root, "frame_count", r->frame_count) >= 0 &&
                 fascia_h5_attr_int(root, "sample_count", r->write_samples ? r->sample_count : 0) >= 0;
  if (root >= 0) H5Gclose(root);
  if (!ok) return h5_failed(r, "/", "write the attributes");
  if (create_group(r->file, "/steps") < 0 || create_group(r->file, "/frames") < 0 || create_group(r->file, "/xdmf") < 0)
    return h5_failed(r, "/", "create the groups");
  const hsize_t N = (hsize_t)r->frame_count, S = (hsize_t)r->sample_count;
  if (write_static(r->file, "/frames/kind", H5T_STD_I32LE, H5T_NATIVE_INT32, N, 0, m->frame_kind, "1",
                   "frame kind from the model: 0 free, 1 fixed, 2 prescribed") < 0 ||
      write_static(r->file, "/frames/organ", H5T_STD_I32LE, H5T_NATIVE_INT32, N, 0, m->frame_organ, "1",
                   "index of the deformable organ the frame belongs to (the model's organ order), -1 tissue") < 0 ||
      write_static(r->file, "/frames/rest_position", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, N, 3, m->frame_position, "m",
                   "frame rest position, world") < 0)
    return h5_failed(r, "/frames", "write the model's frame data");
  if (m->provenance && write_text(r->file, "/provenance", m->provenance) < 0)
    return h5_failed(r, "/provenance", "write");
  r->time = create_series(r->file, "/steps/time", 1, 0, 0);
  r->frame_rotation = create_series(r->file, "/frames/rotation", 3, N, 4);
  if (r->time < 0 || r->frame_rotation < 0 ||
      describe(r->time, "s", "time of the saved step: t0 + k dt, k the solver step (docs/results-format.md)") < 0 ||
      describe(r->frame_rotation, "1", "frame rotation R_i, unit quaternion (w, x, y, z), world") < 0)
    return h5_failed(r, "/frames", "create a series");
  if (r->write_samples) {
    if (create_group(r->file, "/samples") < 0 || create_group(r->file, "/samples/fields") < 0)
      return h5_failed(r, "/samples", "create the group");
    if (write_static(r->file, "/samples/material", H5T_STD_I32LE, H5T_NATIVE_INT32, S, 0, m->sample_material, "1",
                     "material index from the model") < 0 ||
        write_static(r->file, "/samples/organ", H5T_STD_I32LE, H5T_NATIVE_INT32, S, 0, m->sample_organ, "1",
                     "index of the deformable organ the sample belongs to, -1 tissue") < 0 ||
        write_static(r->file, "/samples/volume", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, S, 0, m->sample_volume, "m^3",
                     "rest volume the sample integrates") < 0 ||
        write_static(r->file, "/samples/rest_position", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, S, 3, m->sample_position,
                     "m", "sample rest position, world") < 0)
      return h5_failed(r, "/samples", "write the model's sample data");
  }
  for (int k = 0; k < SERIES_COUNT; ++k) {
    const series_info *info = series_table + k;
    if (info->samples && !r->write_samples) continue;
    r->series[k] = create_series(r->file, info->path, 3, info->samples ? S : N, 3);
    if (r->series[k] < 0 || describe(r->series[k], info->unit, info->meaning) < 0)
      return h5_failed(r, info->path, "create");
  }
  return FASCIA_OK;
}

// Closes every HDF5 object and the file (ids may be invalid).
static herr_t close_all(fascia_results *r) {
  // field names stay: the XDMF sidecar is written after the file is closed
  for (int32_t k = 0; k < r->field_count; ++k) {
    if (r->fields[k].dset >= 0) H5Dclose(r->fields[k].dset);
    r->fields[k].dset = H5I_INVALID_HID;
  }
  for (int k = 0; k < SERIES_COUNT; ++k) {
    if (r->series[k] >= 0) H5Dclose(r->series[k]);
    r->series[k] = H5I_INVALID_HID;
  }
  if (r->time >= 0) H5Dclose(r->time);
  if (r->frame_rotation >= 0) H5Dclose(r->frame_rotation);
  r->time = r->frame_rotation = H5I_INVALID_HID;
  herr_t status = 0;
  if (r->file >= 0) status = H5Fclose(r->file);
  r->file = H5I_INVALID_HID;
  return status;
}

void fascia_results_destroy(fascia_results **results) {
  if (!results || !*results) return;
  fascia_results *r = *results;
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  close_all(r);
  fascia_h5_quiet_end(&quiet);
  if (r->tmp[0]) remove(r->tmp);
  free(r->times), free(r->frame_rest), free(r->sample_rest), free(r->scratch);
  free(r);
  *results = NULL;
}

fascia_status fascia_results_open(fascia_ctx *ctx, const char *path, const fascia_model *model,
                                  const fascia_results_def *def, fascia_results **out) {
  FASCIA_CHECK(out, ctx, FASCIA_ERR_ARGUMENT, "fascia_results_open: NULL out");
  *out = NULL;
  FASCIA_CHECK(path && path[0] && model && def, ctx, FASCIA_ERR_ARGUMENT,
               "fascia_results_open: NULL path, model or def");
  FASCIA_CHECK(def->cookie_ == FASCIA_DEF_COOKIE, ctx, FASCIA_ERR_ARGUMENT,
               "results '%s': the def was not made by fascia_results_def_default()", path);
  FASCIA_CHECK(def->every >= 1, ctx, FASCIA_ERR_ARGUMENT, "results '%s': every is %d, expected >= 1", path,
               (int)def->every);
  FASCIA_CHECK(model->frame_count >= 1 && model->sample_count >= 0, ctx, FASCIA_ERR_ARGUMENT,
               "results '%s': the model has no frame", path);
  FASCIA_CHECK(strlen(path) + 32 < PATH_SIZE, ctx, FASCIA_ERR_ARGUMENT, "results '%s': the path is too long", path);
  fascia_results *r = calloc(1, sizeof *r);
  FASCIA_CHECK(r, ctx, FASCIA_ERR_MEMORY, "results '%s': out of memory", path);
  r->ctx = ctx;
  snprintf(r->path, sizeof r->path, "%s", path);
  r->file = r->time = r->frame_rotation = H5I_INVALID_HID;
  for (int k = 0; k < SERIES_COUNT; ++k) r->series[k] = H5I_INVALID_HID;
  r->frame_count = model->frame_count;
  r->sample_count = model->sample_count;
  r->write_samples = def->write_samples && model->sample_count > 0;
  r->every = def->every;
  snprintf(r->time_meaning, sizeof r->time_meaning, "%s", "simulation time");
  const size_t N = (size_t)r->frame_count, S = (size_t)r->sample_count, most = N > S ? N : S;
  r->frame_rest = malloc(3 * N * sizeof(fascia_real));
  r->sample_rest = malloc(3 * (S + 1) * sizeof(fascia_real));
  r->scratch = malloc(3 * most * sizeof(fascia_real));
  if (!r->frame_rest || !r->sample_rest || !r->scratch) {
    fascia_results_destroy(&r);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "results '%s': out of memory", path);
  }
  memcpy(r->frame_rest, model->frame_position, 3 * N * sizeof(fascia_real));
  if (S) memcpy(r->sample_rest, model->sample_position, 3 * S * sizeof(fascia_real));
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  fascia_status status = fascia_h5_create_temp(ctx, "results", path, r->tmp, sizeof r->tmp, &r->file);
  if (status != FASCIA_OK) r->tmp[0] = 0; // nothing was created
  if (status == FASCIA_OK) // the static datasets, kinds and sample data
    status = fascia_h5_space_check(ctx, "results", path, r->tmp, 4 * (int64_t)r->frame_count + 12 * (int64_t)r->sample_count);
  if (status == FASCIA_OK) status = create_layout(r, model);
  fascia_h5_quiet_end(&quiet);
  if (status != FASCIA_OK) {
    fascia_results_destroy(&r);
    return status;
  }
  *out = r;
  return FASCIA_OK;
}

// Row of series k for one step: the positions given, or the displacements and
// axes computed from them into r->scratch.
static const fascia_real *series_row(fascia_results *r, int k, const fascia_real *frame_position,
                                     const fascia_real *frame_rotation, const fascia_real *sample_position) {
  const int64_t N = r->frame_count, S = r->sample_count;
  fascia_real *out = r->scratch;
  switch (k) {
  case SERIES_FRAME_POSITION: return frame_position;
  case SERIES_SAMPLE_POSITION: return sample_position;
  case SERIES_FRAME_DISPLACEMENT:
    for (int64_t j = 0; j < 3 * N; ++j) out[j] = frame_position[j] - r->frame_rest[j];
    return out;
  case SERIES_SAMPLE_DISPLACEMENT:
    for (int64_t j = 0; j < 3 * S; ++j) out[j] = sample_position[j] - r->sample_rest[j];
    return out;
  default: break;
  }
  const int column = k - SERIES_AXIS_X; // column c of R(q): R e_c
  for (int64_t i = 0; i < N; ++i) {
    fascia_real axes[9];
    fascia_frame_axes(frame_rotation + 4 * i, 1, axes);
    memcpy(out + 3 * i, axes + 3 * column, 3 * sizeof(fascia_real));
  }
  return out;
}

fascia_status fascia_results_append(fascia_results *r, fascia_real time, const fascia_real *frame_position,
                                    const fascia_real *frame_rotation, const fascia_real *sample_position) {
  if (!r) return FASCIA_ERR_ARGUMENT;
  FASCIA_CHECK(r->file >= 0, r->ctx, FASCIA_ERR_ARGUMENT, "results '%s': the file is closed", r->path);
  FASCIA_CHECK(frame_position && frame_rotation && (sample_position || !r->write_samples), r->ctx,
               FASCIA_ERR_ARGUMENT, "results '%s' step %lld: NULL frame%s data", r->path, (long long)r->step_count,
               r->write_samples ? " or sample" : "");
  FASCIA_CHECK(isfinite(time) && (r->step_count == 0 || time > r->times[r->step_count - 1]), r->ctx,
               FASCIA_ERR_ARGUMENT, "results '%s' step %lld: time %.17g s does not follow the previous step's", r->path,
               (long long)r->step_count, time);
  if (r->step_count == r->time_capacity) {
    const int64_t capacity = r->time_capacity ? 2 * r->time_capacity : 256;
    fascia_real *times = realloc(r->times, (size_t)capacity * sizeof *times);
    FASCIA_CHECK(times, r->ctx, FASCIA_ERR_MEMORY, "results '%s': out of memory", r->path);
    r->times = times;
    r->time_capacity = capacity;
  }
  const int64_t t = r->step_count;
  const hsize_t N = (hsize_t)r->frame_count, S = (hsize_t)r->sample_count;
  // a step's rows, the per-sample fields included (strain, stress)
  const int64_t row_bytes = 8 * (1 + 19 * (int64_t)N + (r->write_samples ? 8 * (int64_t)S : 0));
  FASCIA_TRY(fascia_h5_space_check(r->ctx, "results", r->path, r->tmp, row_bytes));
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  // the previous step goes to disk now, while there is room for it
  fascia_status status = H5Fflush(r->file, H5F_SCOPE_LOCAL) < 0 ? h5_failed(r, "/", "flush") : FASCIA_OK;
  if (status != FASCIA_OK) {
  } else if (write_row(r->time, 1, t, 0, 0, &time) < 0)
    status = h5_failed(r, "/steps/time", "append");
  else if (write_row(r->frame_rotation, 3, t, N, 4, frame_rotation) < 0)
    status = h5_failed(r, "/frames/rotation", "append");
  for (int k = 0; k < SERIES_COUNT && status == FASCIA_OK; ++k) {
    const series_info *info = series_table + k;
    if (info->samples && !r->write_samples) continue;
    const fascia_real *row = series_row(r, k, frame_position, frame_rotation, sample_position);
    if (write_row(r->series[k], 3, t, info->samples ? S : N, 3, row) < 0) status = h5_failed(r, info->path, "append");
  }
  fascia_h5_quiet_end(&quiet);
  if (status != FASCIA_OK) return status;
  r->times[t] = time;
  r->step_count = t + 1;
  return FASCIA_OK;
}

// The field `name`, created on first use; NULL with the status set when it
// cannot be (too many fields, HDF5).
static field *find_field(fascia_results *r, const char *name, fascia_status *status) {
  for (int32_t k = 0; k < r->field_count; ++k)
    if (!strcmp(r->fields[k].name, name)) return r->fields + k;
  char full[FASCIA_NAME_SIZE + 32];
  snprintf(full, sizeof full, "/samples/fields/%s", name);
  if (r->field_count == FASCIA_RESULTS_MAX_FIELDS) {
    *status = FASCIA_FAIL(r->ctx, FASCIA_ERR_ARGUMENT, "results '%s' field '%s': more than %d fields", r->path, name,
                          FASCIA_RESULTS_MAX_FIELDS);
    return NULL;
  }
  const hid_t dset = create_series(r->file, full, 2, (hsize_t)r->sample_count, 0);
  if (dset >= 0 && describe(dset, "unknown", "a per-sample field its writer did not describe") < 0) {
    H5Dclose(dset);
    *status = h5_failed(r, full, "describe");
    return NULL;
  }
  if (dset < 0) {
    *status = h5_failed(r, full, "create");
    return NULL;
  }
  field *f = r->fields + r->field_count++;
  snprintf(f->name, sizeof f->name, "%s", name);
  snprintf(f->unit, sizeof f->unit, "unknown");
  f->dset = dset;
  return f;
}

static fascia_status check_field(fascia_results *r, const char *name) {
  FASCIA_CHECK(r->file >= 0, r->ctx, FASCIA_ERR_ARGUMENT, "results '%s': the file is closed", r->path);
  FASCIA_CHECK(name, r->ctx, FASCIA_ERR_ARGUMENT, "results '%s': NULL field name", r->path);
  FASCIA_CHECK(r->write_samples, r->ctx, FASCIA_ERR_ARGUMENT,
               "results '%s' field '%s': per-sample fields need write_samples in the results def", r->path, name);
  FASCIA_CHECK(name[0] && strlen(name) < FASCIA_NAME_SIZE && !strchr(name, '/') && strcmp(name, "."), r->ctx,
               FASCIA_ERR_ARGUMENT, "results '%s': field name '%s' must be 1 to %d characters without '/'", r->path,
               name, FASCIA_NAME_SIZE - 1);
  return FASCIA_OK;
}

fascia_status fascia_results_append_field(fascia_results *r, const char *name, const fascia_real *values) {
  if (!r) return FASCIA_ERR_ARGUMENT;
  FASCIA_TRY(check_field(r, name));
  FASCIA_CHECK(values, r->ctx, FASCIA_ERR_ARGUMENT, "results '%s': NULL values of field '%s'", r->path, name);
  FASCIA_CHECK(r->step_count >= 1, r->ctx, FASCIA_ERR_ARGUMENT,
               "results '%s' field '%s': append a step before its fields", r->path, name);
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  fascia_status status = FASCIA_OK;
  field *f = find_field(r, name, &status);
  if (f && write_row(f->dset, 2, r->step_count - 1, (hsize_t)r->sample_count, 0, values) < 0)
    status = h5_failed(r, "/samples/fields", "append");
  fascia_h5_quiet_end(&quiet);
  return status;
}

fascia_status fascia_results_describe_field(fascia_results *r, const char *name, const char *unit,
                                            const char *meaning) {
  if (!r) return FASCIA_ERR_ARGUMENT;
  FASCIA_TRY(check_field(r, name));
  FASCIA_CHECK(unit && meaning, r->ctx, FASCIA_ERR_ARGUMENT, "results '%s' field '%s': NULL unit or meaning",
               r->path, name);
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  fascia_status status = FASCIA_OK;
  field *f = find_field(r, name, &status);
  if (f && describe(f->dset, unit, meaning) < 0) status = h5_failed(r, "/samples/fields", "describe");
  if (f) snprintf(f->unit, sizeof f->unit, "%s", unit);
  fascia_h5_quiet_end(&quiet);
  return status;
}

fascia_status fascia_results_set_run(fascia_results *r, const char *model_file, const char *settings) {
  if (!r) return FASCIA_ERR_ARGUMENT;
  FASCIA_CHECK(model_file && settings, r->ctx, FASCIA_ERR_ARGUMENT, "results '%s': no model file or settings",
               r->path);
  hid_t root = H5Gopen2(r->file, "/", H5P_DEFAULT);
  const int ok = root >= 0 && fascia_h5_attr_string(root, "model_file", model_file) >= 0 &&
                 fascia_h5_attr_string(root, "run_settings", settings) >= 0;
  if (root >= 0) H5Gclose(root);
  return ok ? FASCIA_OK : h5_failed(r, "/", "write the run's attributes");
}

fascia_status fascia_results_set_time_meaning(fascia_results *r, const char *meaning) {
  if (!r) return FASCIA_ERR_ARGUMENT;
  FASCIA_CHECK(meaning && strlen(meaning) < TEXT_SIZE, r->ctx, FASCIA_ERR_ARGUMENT,
               "results '%s': the time's meaning must be at most %d characters", r->path, TEXT_SIZE - 1);
  snprintf(r->time_meaning, sizeof r->time_meaning, "%s", meaning);
  return FASCIA_OK;
}

// Sets every series to exactly step_count rows: pads fields given only in
// early steps (NaN), drops a row a failed append left behind.
static herr_t trim_series(fascia_results *r) {
  hid_t series[2 + SERIES_COUNT + FASCIA_RESULTS_MAX_FIELDS];
  int count = 0;
  series[count++] = r->time;
  series[count++] = r->frame_rotation;
  for (int k = 0; k < SERIES_COUNT; ++k)
    if (r->series[k] >= 0) series[count++] = r->series[k];
  for (int32_t k = 0; k < r->field_count; ++k) series[count++] = r->fields[k].dset;
  for (int k = 0; k < count; ++k) {
    hsize_t dims[3];
    hid_t space = H5Dget_space(series[k]);
    if (space < 0) return -1;
    H5Sget_simple_extent_dims(space, dims, NULL);
    H5Sclose(space);
    dims[0] = (hsize_t)r->step_count;
    if (H5Dset_extent(series[k], dims) < 0) return -1;
  }
  hid_t root = H5Gopen2(r->file, "/", H5P_DEFAULT);
  if (root < 0) return -1;
  herr_t status = fascia_h5_attr_int(root, "step_count", (int32_t)r->step_count);
  H5Gclose(root);
  if (status >= 0) status = fascia_h5_attr_string(r->time, "time_meaning", r->time_meaning);
  return status;
}

// --- what the XDMF sidecar reads --------------------------------------------
// ParaView's Xdmf3 readers cannot read an XDMF hyperslab ("Skipping
// unrecognized array type"), and without an explicit connectivity their
// Polyvertex grids have points but no cells to draw. So every step gets plain
// datasets to name: HDF5 virtual datasets, each viewing row t of a series
// (no data copied), and each block a vertex list 0..n-1.

// /xdmf/step_t/NAME, a virtual dataset of row t of `source` ([T,rows(,cols)]).
static herr_t create_view(hid_t file, const char *name, const char *source, int64_t t, hsize_t rows, hsize_t cols) {
  const hsize_t T = (hsize_t)t + 1, source_dims[3] = {T, rows, cols}, view_dims[2] = {rows, cols};
  const int rank = cols ? 3 : 2;
  const hsize_t start[3] = {(hsize_t)t, 0, 0}, count[3] = {1, rows, cols};
  const double nan_value = NAN;
  hid_t view_space = H5Screate_simple(rank - 1, view_dims, NULL), source_space = H5Screate_simple(rank, source_dims, NULL);
  hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE), dset = H5I_INVALID_HID;
  if (view_space >= 0 && source_space >= 0 && dcpl >= 0 && H5Pset_fill_value(dcpl, H5T_NATIVE_DOUBLE, &nan_value) >= 0 &&
      H5Sselect_hyperslab(source_space, H5S_SELECT_SET, start, NULL, count, NULL) >= 0 &&
      H5Pset_virtual(dcpl, view_space, ".", source, source_space) >= 0) // ".": this very file
    dset = H5Dcreate2(file, name, H5T_IEEE_F64LE, view_space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  if (dset >= 0) H5Dclose(dset);
  if (dcpl >= 0) H5Pclose(dcpl);
  if (source_space >= 0) H5Sclose(source_space);
  if (view_space >= 0) H5Sclose(view_space);
  return dset >= 0 ? 0 : -1;
}

static herr_t write_vertices(hid_t file, const char *name, int32_t count) {
  int32_t *index = malloc(((size_t)count + 1) * sizeof *index);
  if (!index) return -1;
  for (int32_t k = 0; k < count; ++k) index[k] = k;
  const herr_t status = write_static(file, name, H5T_STD_I32LE, H5T_NATIVE_INT32, (hsize_t)count, 0, index, "1",
                                     "point indices 0..n-1: the Polyvertex cells of the XDMF sidecar");
  free(index);
  return status;
}

static herr_t create_views(fascia_results *r) {
  const hsize_t N = (hsize_t)r->frame_count, S = (hsize_t)r->sample_count;
  if (write_vertices(r->file, "/xdmf/frames_vertex", r->frame_count) < 0) return -1;
  if (r->write_samples && write_vertices(r->file, "/xdmf/samples_vertex", r->sample_count) < 0) return -1;
  for (int64_t t = 0; t < r->step_count; ++t) {
    char group[64], name[FASCIA_NAME_SIZE + 96];
    snprintf(group, sizeof group, "/xdmf/step_%lld", (long long)t);
    if (create_group(r->file, group) < 0) return -1;
    for (int k = 0; k < SERIES_COUNT; ++k) {
      const series_info *info = series_table + k;
      if (info->samples && !r->write_samples) continue;
      snprintf(name, sizeof name, "%s/%s_%s", group, info->samples ? "samples" : "frames", info->name);
      if (create_view(r->file, name, info->path, t, info->samples ? S : N, 3) < 0) return -1;
    }
    for (int32_t k = 0; k < r->field_count; ++k) {
      char source[FASCIA_NAME_SIZE + 32];
      snprintf(source, sizeof source, "/samples/fields/%s", r->fields[k].name);
      snprintf(name, sizeof name, "%s/field_%s", group, r->fields[k].name);
      if (create_view(r->file, name, source, t, S, 0) < 0) return -1;
    }
  }
  return 0;
}

void fascia_results_sidecar_path(const char *path, char *out, size_t size) {
  size_t length = strlen(path);
  if (length > 3 && !strcmp(path + length - 3, ".h5"))
    length -= 3;
  else if (length > 5 && !strcmp(path + length - 5, ".hdf5"))
    length -= 5;
  snprintf(out, size, "%.*s.xdmf", (int)length, path);
}

// An HDF DataItem of dataset h5:/path, `rows` by `cols` (0: a scalar per row).
static void xdmf_item(FILE *out, const char *h5, const char *path, int64_t rows, int cols, bool integer) {
  fprintf(out, "            <DataItem Dimensions=\"%lld", (long long)rows);
  if (cols) fprintf(out, " %d", cols);
  fprintf(out, "\" NumberType=\"%s\" Precision=\"%d\" Format=\"HDF\">", integer ? "Int" : "Float", integer ? 4 : 8);
  fascia_xml_text(out, h5);
  fputc(':', out);
  fascia_xml_text(out, path); // field names are free text
  fputs("</DataItem>\n", out);
}

// An attribute with its unit as an XDMF Information element (readers that
// do not know it skip it).
static void xdmf_attribute(FILE *out, const char *name, const char *unit, const char *h5, const char *path,
                           int64_t rows, int cols, bool integer) {
  fputs("          <Attribute Name=\"", out);
  fascia_xml_text(out, name);
  fprintf(out, "\" AttributeType=\"%s\" Center=\"Node\">\n", cols ? "Vector" : "Scalar");
  fputs("            <Information Name=\"unit\" Value=\"", out);
  fascia_xml_text(out, unit);
  fputs("\"/>\n", out);
  xdmf_item(out, h5, path, rows, cols, integer);
  fputs("          </Attribute>\n", out);
}

// Step t of block "frames" or "samples": one Uniform grid of Polyvertex cells.
static void xdmf_grid(FILE *out, const fascia_results *r, const char *h5, int64_t t, bool samples) {
  const char *block = samples ? "samples" : "frames";
  const int64_t rows = samples ? r->sample_count : r->frame_count;
  char path[FASCIA_NAME_SIZE + 96];
  fprintf(out, "        <Grid Name=\"%s\" GridType=\"Uniform\">\n          <Time Value=\"%.17g\"/>\n", block,
          r->times[t]);
  fprintf(out, "          <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%lld\" NodesPerElement=\"1\">\n",
          (long long)rows);
  snprintf(path, sizeof path, "/xdmf/%s_vertex", block);
  xdmf_item(out, h5, path, rows, 0, true);
  fputs("          </Topology>\n          <Geometry GeometryType=\"XYZ\">\n", out);
  snprintf(path, sizeof path, "/xdmf/step_%lld/%s_position", (long long)t, block);
  xdmf_item(out, h5, path, rows, 3, false);
  fputs("          </Geometry>\n", out);
  for (int k = 0; k < SERIES_COUNT; ++k) {
    const series_info *info = series_table + k;
    if (info->samples != samples || k == SERIES_FRAME_POSITION || k == SERIES_SAMPLE_POSITION) continue;
    snprintf(path, sizeof path, "/xdmf/step_%lld/%s_%s", (long long)t, block, info->name);
    xdmf_attribute(out, info->name, info->unit, h5, path, rows, 3, false);
  }
  snprintf(path, sizeof path, "/%s/rest_position", block);
  xdmf_attribute(out, "rest_position", "m", h5, path, rows, 3, false);
  snprintf(path, sizeof path, "/%s/organ", block);
  xdmf_attribute(out, "organ", "1", h5, path, rows, 0, true);
  if (samples) {
    xdmf_attribute(out, "material", "1", h5, "/samples/material", rows, 0, true);
    xdmf_attribute(out, "volume", "m^3", h5, "/samples/volume", rows, 0, false);
  } else {
    xdmf_attribute(out, "kind", "1", h5, "/frames/kind", rows, 0, true);
  }
  for (int32_t k = 0; samples && k < r->field_count; ++k) {
    snprintf(path, sizeof path, "/xdmf/step_%lld/field_%s", (long long)t, r->fields[k].name);
    xdmf_attribute(out, r->fields[k].name, r->fields[k].unit, h5, path, rows, 0, false);
  }
  fputs("        </Grid>\n", out);
}

// Writes the sidecar: a spatial collection of one temporal collection per
// block (frames, samples), so that a block keeps its name at every step.
static fascia_status write_xdmf(fascia_results *r) {
  char xdmf[PATH_SIZE];
  fascia_results_sidecar_path(r->path, xdmf, sizeof xdmf);
  fascia_file *file = NULL;
  FASCIA_TRY(fascia_file_open(r->ctx, "results sidecar", xdmf, &file));
  FILE *out = fascia_file_stream(file);
  // the sidecar sits next to the .h5 file and names it relative to itself
  const char *slash = strrchr(r->path, '/');
  const char *h5 = slash ? slash + 1 : r->path;
  fprintf(out, "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"3.0\">\n");
  fprintf(out, "  <Domain>\n    <Information Name=\"units\" Value=\"%s; Time in s\"/>\n", RESULTS_UNITS);
  fprintf(out, "    <Grid Name=\"fascia\" GridType=\"Collection\" CollectionType=\"Spatial\">\n");
  for (int b = 0; b < (r->write_samples ? 2 : 1); ++b) {
    fprintf(out, "      <Grid Name=\"%s\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
            b ? "samples" : "frames");
    for (int64_t t = 0; t < r->step_count; ++t) xdmf_grid(out, r, h5, t, b == 1);
    fprintf(out, "      </Grid>\n");
  }
  fprintf(out, "    </Grid>\n  </Domain>\n</Xdmf>\n");
  return fascia_file_commit(&file);
}

fascia_status fascia_results_close(fascia_results **results) {
  if (!results || !*results) return FASCIA_OK;
  fascia_results *r = *results;
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  fascia_status status = FASCIA_OK;
  if (r->file < 0)
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_ARGUMENT, "results '%s': the file is closed", r->path);
  else if (trim_series(r) < 0)
    status = h5_failed(r, "/", "finish the series");
  else if (fascia_h5_space_check(r->ctx, "results", r->path, r->tmp, 2048 * (r->step_count + 1)) != FASCIA_OK)
    status = FASCIA_ERR_IO;
  else if (create_views(r) < 0)
    status = h5_failed(r, "/xdmf", "write the views of the XDMF sidecar");
  // closing flushes: a failure here (disk full) fails the whole file
  if (close_all(r) < 0 && status == FASCIA_OK) status = h5_failed(r, "/", "close");
  fascia_h5_quiet_end(&quiet);
  if (status == FASCIA_OK) status = fascia_commit_temp(r->ctx, "results", r->tmp, r->path);
  if (status == FASCIA_OK) {
    r->tmp[0] = 0; // moved into place: destroy must not remove anything
    status = write_xdmf(r);
  }
  fascia_results_destroy(results);
  return status;
}
