// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The results writer: a time series of frame and sample states in HDF5 with
// an XDMF sidecar for ParaView. Specification: docs/results-format.md.
//
// Schema, version 1 (T steps, N frames, S samples; f64 little endian):
//   /                   attributes fascia_results_version (= 1), units,
//                       creator, every, frame_count, sample_count, step_count
//   /steps/time         [T]      s    extendible, chunked
//   /frames/position    [T,N,3]  m    world
//   /frames/rotation    [T,N,4]  1    unit quaternions w,x,y,z
//   /frames/kind        [N]      i32  from the model (static)
//   /samples/position   [T,S,3]  m    only with write_samples
//   /samples/material   [S] i32, /samples/volume [S] m^3 (static, with samples)
//   /samples/fields/NAME [T,S]   per-sample scalar, NaN where not given
//   /provenance         scalar string, the model's provenance (if any)
// Every series grows by one row per fascia_results_append; close trims them
// all to the steps that completed, so a failed append leaves no ragged tail.
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/files.h"
#include "fascia/results.h"
#include "h5io.h"

#define RESULTS_VERSION 1
#define RESULTS_UNITS "SI: m, kg, s, Pa"
// Rows of one chunk along N or S: one step of up to 65536 frames is one
// chunk (at most 2 MiB), written whole, so appending never re-reads a chunk.
#define CHUNK_ROWS 65536
// Time values per chunk of /steps/time.
#define CHUNK_TIMES 1024
#define PATH_SIZE 4096

typedef struct field {
  char name[FASCIA_NAME_SIZE];
  hid_t dset;
} field;

struct fascia_results {
  fascia_ctx *ctx;
  char path[PATH_SIZE], tmp[PATH_SIZE];
  hid_t file, time, frame_position, frame_rotation, sample_position;
  int32_t frame_count, sample_count, every;
  bool write_samples;
  int64_t step_count, time_capacity;
  fascia_real *times; ///< [step_count] for the XDMF sidecar
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

static herr_t write_static(hid_t file, const char *name, hid_t file_type, hid_t mem_type, hsize_t count,
                           const void *data, const char *unit) {
  herr_t status = -1;
  hid_t space = H5Screate_simple(1, &count, NULL), dset = H5I_INVALID_HID;
  if (space >= 0) dset = H5Dcreate2(file, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (dset >= 0) status = H5Dwrite(dset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
  if (status >= 0 && unit) status = fascia_h5_attr_string(dset, "unit", unit);
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
  char creator[64];
  snprintf(creator, sizeof creator, "fascia %s", fascia_version());
  hid_t root = H5Gopen2(r->file, "/", H5P_DEFAULT);
  const int ok = root >= 0 && fascia_h5_attr_int(root, "fascia_results_version", RESULTS_VERSION) >= 0 &&
                 fascia_h5_attr_string(root, "units", RESULTS_UNITS) >= 0 &&
                 fascia_h5_attr_string(root, "creator", creator) >= 0 &&
                 fascia_h5_attr_int(root, "every", r->every) >= 0 &&
                 fascia_h5_attr_int(root, "frame_count", r->frame_count) >= 0 &&
                 fascia_h5_attr_int(root, "sample_count", r->write_samples ? r->sample_count : 0) >= 0;
  if (root >= 0) H5Gclose(root);
  if (!ok) return h5_failed(r, "/", "write the attributes");
  if (create_group(r->file, "/steps") < 0 || create_group(r->file, "/frames") < 0)
    return h5_failed(r, "/", "create the groups");
  if (write_static(r->file, "/frames/kind", H5T_STD_I32LE, H5T_NATIVE_INT32, (hsize_t)r->frame_count, m->frame_kind,
                   NULL) < 0)
    return h5_failed(r, "/frames/kind", "write");
  if (m->provenance && write_text(r->file, "/provenance", m->provenance) < 0)
    return h5_failed(r, "/provenance", "write");
  const hsize_t N = (hsize_t)r->frame_count, S = (hsize_t)r->sample_count;
  r->time = create_series(r->file, "/steps/time", 1, 0, 0);
  r->frame_position = create_series(r->file, "/frames/position", 3, N, 3);
  r->frame_rotation = create_series(r->file, "/frames/rotation", 3, N, 4);
  if (r->time < 0 || r->frame_position < 0 || r->frame_rotation < 0) return h5_failed(r, "/frames", "create a series");
  if (!r->write_samples) return FASCIA_OK;
  if (create_group(r->file, "/samples") < 0 || create_group(r->file, "/samples/fields") < 0)
    return h5_failed(r, "/samples", "create the group");
  if (write_static(r->file, "/samples/material", H5T_STD_I32LE, H5T_NATIVE_INT32, S, m->sample_material, NULL) < 0 ||
      write_static(r->file, "/samples/volume", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, S, m->sample_volume, "m^3") < 0)
    return h5_failed(r, "/samples", "write the model's sample data");
  r->sample_position = create_series(r->file, "/samples/position", 3, S, 3);
  if (r->sample_position < 0) return h5_failed(r, "/samples/position", "create");
  return FASCIA_OK;
}

// Closes every HDF5 object and the file (ids may be invalid).
static herr_t close_all(fascia_results *r) {
  // field names stay: the XDMF sidecar is written after the file is closed
  for (int32_t k = 0; k < r->field_count; ++k) {
    if (r->fields[k].dset >= 0) H5Dclose(r->fields[k].dset);
    r->fields[k].dset = H5I_INVALID_HID;
  }
  const hid_t series[] = {r->time, r->frame_position, r->frame_rotation, r->sample_position};
  for (size_t k = 0; k < sizeof series / sizeof series[0]; ++k)
    if (series[k] >= 0) H5Dclose(series[k]);
  r->time = r->frame_position = r->frame_rotation = r->sample_position = H5I_INVALID_HID;
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
  free(r->times);
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
  r->file = r->time = r->frame_position = r->frame_rotation = r->sample_position = H5I_INVALID_HID;
  r->frame_count = model->frame_count;
  r->sample_count = model->sample_count;
  r->write_samples = def->write_samples && model->sample_count > 0;
  r->every = def->every;
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
  const int64_t row_bytes = 8 * (1 + 7 * (int64_t)N + (r->write_samples ? 5 * (int64_t)S : 0));
  FASCIA_TRY(fascia_h5_space_check(r->ctx, "results", r->path, r->tmp, row_bytes));
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  // the previous step goes to disk now, while there is room for it
  fascia_status status = H5Fflush(r->file, H5F_SCOPE_LOCAL) < 0 ? h5_failed(r, "/", "flush") : FASCIA_OK;
  if (status != FASCIA_OK) {
  } else if (write_row(r->time, 1, t, 0, 0, &time) < 0)
    status = h5_failed(r, "/steps/time", "append");
  else if (write_row(r->frame_position, 3, t, N, 3, frame_position) < 0)
    status = h5_failed(r, "/frames/position", "append");
  else if (write_row(r->frame_rotation, 3, t, N, 4, frame_rotation) < 0)
    status = h5_failed(r, "/frames/rotation", "append");
  else if (r->write_samples && write_row(r->sample_position, 3, t, S, 3, sample_position) < 0)
    status = h5_failed(r, "/samples/position", "append");
  fascia_h5_quiet_end(&quiet);
  if (status != FASCIA_OK) return status;
  r->times[t] = time;
  r->step_count = t + 1;
  return FASCIA_OK;
}

fascia_status fascia_results_append_field(fascia_results *r, const char *name, const fascia_real *values) {
  if (!r) return FASCIA_ERR_ARGUMENT;
  FASCIA_CHECK(r->file >= 0, r->ctx, FASCIA_ERR_ARGUMENT, "results '%s': the file is closed", r->path);
  FASCIA_CHECK(name && values, r->ctx, FASCIA_ERR_ARGUMENT, "results '%s': NULL field name or values", r->path);
  FASCIA_CHECK(r->write_samples, r->ctx, FASCIA_ERR_ARGUMENT,
               "results '%s' field '%s': per-sample fields need write_samples in the results def", r->path, name);
  FASCIA_CHECK(r->step_count >= 1, r->ctx, FASCIA_ERR_ARGUMENT,
               "results '%s' field '%s': append a step before its fields", r->path, name);
  FASCIA_CHECK(name[0] && strlen(name) < FASCIA_NAME_SIZE && !strchr(name, '/') && strcmp(name, "."), r->ctx,
               FASCIA_ERR_ARGUMENT, "results '%s': field name '%s' must be 1 to %d characters without '/'", r->path,
               name, FASCIA_NAME_SIZE - 1);
  char full[FASCIA_NAME_SIZE + 32];
  snprintf(full, sizeof full, "/samples/fields/%s", name);
  field *f = NULL;
  for (int32_t k = 0; k < r->field_count && !f; ++k)
    if (!strcmp(r->fields[k].name, name)) f = r->fields + k;
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  fascia_status status = FASCIA_OK;
  if (!f && r->field_count == FASCIA_RESULTS_MAX_FIELDS) {
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_ARGUMENT, "results '%s' field '%s': more than %d fields", r->path, name,
                         FASCIA_RESULTS_MAX_FIELDS);
  } else if (!f) {
    const hid_t dset = create_series(r->file, full, 2, (hsize_t)r->sample_count, 0);
    if (dset < 0) {
      status = h5_failed(r, full, "create");
    } else {
      f = r->fields + r->field_count++;
      snprintf(f->name, sizeof f->name, "%s", name);
      f->dset = dset;
    }
  }
  if (f && write_row(f->dset, 2, r->step_count - 1, (hsize_t)r->sample_count, 0, values) < 0)
    status = h5_failed(r, full, "append");
  fascia_h5_quiet_end(&quiet);
  return status;
}

// Sets every series to exactly step_count rows: pads fields given only in
// early steps (NaN), drops a row a failed append left behind.
static herr_t trim_series(fascia_results *r) {
  hid_t series[4 + FASCIA_RESULTS_MAX_FIELDS];
  int count = 0;
  series[count++] = r->time;
  series[count++] = r->frame_position;
  series[count++] = r->frame_rotation;
  if (r->sample_position >= 0) series[count++] = r->sample_position;
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
  const herr_t status = fascia_h5_attr_int(root, "step_count", (int32_t)r->step_count);
  H5Gclose(root);
  return status;
}

void fascia_results_sidecar_path(const char *path, char *out, size_t size) {
  size_t length = strlen(path);
  if (length > 3 && !strcmp(path + length - 3, ".h5"))
    length -= 3;
  else if (length > 5 && !strcmp(path + length - 5, ".hdf5"))
    length -= 5;
  snprintf(out, size, "%.*s.xdmf", (int)length, path);
}

static void xml_escaped(FILE *out, const char *text) {
  for (; *text; ++text) switch (*text) {
    case '&': fputs("&amp;", out); break;
    case '<': fputs("&lt;", out); break;
    case '>': fputs("&gt;", out); break;
    case '"': fputs("&quot;", out); break;
    default: fputc(*text, out);
    }
}

// One XDMF DataItem selecting row t of series `dataset` [T,rows(,cols)].
static void xdmf_row(FILE *out, const char *h5, const char *dataset, int64_t t, int64_t T, int64_t rows, int cols,
                     const char *indent) {
  if (cols) {
    fprintf(out, "%s<DataItem ItemType=\"HyperSlab\" Type=\"HyperSlab\" Dimensions=\"%lld %d\" NumberType=\"Float\" "
                 "Precision=\"8\">\n", indent, (long long)rows, cols);
    fprintf(out, "%s  <DataItem Dimensions=\"3 3\" Format=\"XML\">%lld 0 0 1 1 1 1 %lld %d</DataItem>\n", indent,
            (long long)t, (long long)rows, cols);
    fprintf(out, "%s  <DataItem Dimensions=\"%lld %lld %d\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">",
            indent, (long long)T, (long long)rows, cols);
  } else {
    fprintf(out, "%s<DataItem ItemType=\"HyperSlab\" Type=\"HyperSlab\" Dimensions=\"%lld\" NumberType=\"Float\" "
                 "Precision=\"8\">\n", indent, (long long)rows);
    fprintf(out, "%s  <DataItem Dimensions=\"3 2\" Format=\"XML\">%lld 0 1 1 1 %lld</DataItem>\n", indent,
            (long long)t, (long long)rows);
    fprintf(out, "%s  <DataItem Dimensions=\"%lld %lld\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">",
            indent, (long long)T, (long long)rows);
  }
  xml_escaped(out, h5);
  fputc(':', out);
  xml_escaped(out, dataset); // field names are free text
  fprintf(out, "</DataItem>\n%s</DataItem>\n", indent);
}

static void xdmf_grid(FILE *out, const fascia_results *r, const char *h5, int64_t t, bool samples) {
  const int64_t T = r->step_count, rows = samples ? r->sample_count : r->frame_count;
  const char *in = "          ";
  fprintf(out, "        <Grid Name=\"%s\" GridType=\"Uniform\">\n", samples ? "samples" : "frames");
  fprintf(out, "%s<Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%lld\" NodesPerElement=\"1\"/>\n", in,
          (long long)rows);
  fprintf(out, "%s<Geometry GeometryType=\"XYZ\">\n", in);
  xdmf_row(out, h5, samples ? "/samples/position" : "/frames/position", t, T, rows, 3, "            ");
  fprintf(out, "%s</Geometry>\n", in);
  if (!samples) {
    // a quaternion has 4 components: "Matrix" is XDMF's generic n-component type
    fprintf(out, "%s<Attribute Name=\"rotation\" AttributeType=\"Matrix\" Center=\"Node\">\n", in);
    xdmf_row(out, h5, "/frames/rotation", t, T, rows, 4, "            ");
    fprintf(out, "%s</Attribute>\n", in);
  }
  fprintf(out, "%s<Attribute Name=\"%s\" AttributeType=\"Scalar\" Center=\"Node\">\n", in,
          samples ? "material" : "kind");
  fprintf(out, "%s  <DataItem Dimensions=\"%lld\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">", in,
          (long long)rows);
  xml_escaped(out, h5);
  fprintf(out, ":%s</DataItem>\n%s</Attribute>\n", samples ? "/samples/material" : "/frames/kind", in);
  for (int32_t k = 0; samples && k < r->field_count; ++k) {
    char dataset[FASCIA_NAME_SIZE + 32];
    snprintf(dataset, sizeof dataset, "/samples/fields/%s", r->fields[k].name);
    fprintf(out, "%s<Attribute Name=\"", in);
    xml_escaped(out, r->fields[k].name);
    fprintf(out, "\" AttributeType=\"Scalar\" Center=\"Node\">\n");
    xdmf_row(out, h5, dataset, t, T, rows, 0, "            ");
    fprintf(out, "%s</Attribute>\n", in);
  }
  fprintf(out, "        </Grid>\n");
}

// Writes the sidecar: a temporal collection with, per step, a spatial
// collection of the frame grid and (with samples) the sample grid.
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
  fprintf(out, "  <Domain>\n    <Grid Name=\"fascia\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
  for (int64_t t = 0; t < r->step_count; ++t) {
    fprintf(out, "      <Grid Name=\"step %lld\" GridType=\"Collection\" CollectionType=\"Spatial\">\n", (long long)t);
    fprintf(out, "        <Time Value=\"%.17g\"/>\n", r->times[t]);
    xdmf_grid(out, r, h5, t, false);
    if (r->write_samples) xdmf_grid(out, r, h5, t, true);
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
