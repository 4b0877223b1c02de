// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Checkpoints of a dynamic run (issue 7, "nothing lost"): the solver state
// that the next implicit Euler step reads (solver.c: x, q, u and the time)
// written whole through a temporary name, and read back bit for bit.
//
// Schema, version 1 (N frames; reals f64 little endian):
//   /                     attributes fascia_checkpoint_version (int32, = 1),
//                         units ("SI: m, kg, s, Pa"), creator ("fascia X.Y.Z")
//   /run/step             [1]   i64  completed steps
//   /run/time             [1]   f64  s, the solver's time after them
//   /run/time_step        [1]   f64  s, the run's time step (must match on resume)
//   /model/sizes          [9]   i64  frames, samples, pairs, materials, motions,
//                                    probes, probe pairs, organs, couplings
//   /model/fingerprint    [1]   u64  FNV-1a of the model's arrays (see fingerprint)
//   /state/position       [N,3] f64  m, world
//   /state/rotation       [N,4] f64  unit quaternions w,x,y,z
//   /state/velocity       [N,6] f64  m/s then rad/s, world
//   /state/organs         [B]   f64  state of the rigid organ bodies (organs.c:
//                                    fascia_organs_save), B = 0 without them
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/checkpoint.h"
#include "h5io.h"
#include "organs.h"
#include "solver_internal.h"

#define CHECKPOINT_VERSION 1
#define CHECKPOINT_UNITS "SI: m, kg, s, Pa"
#define SIZE_COUNT 9

_Static_assert(sizeof(fascia_real) == sizeof(double), "checkpoints store fascia_real as f64");

// ---------------------------------------------------------------------------
// What identifies the model

static void model_sizes(const fascia_model *m, int64_t *z) {
  const int32_t n[SIZE_COUNT] = {m->frame_count,  m->sample_count, m->pair_count,
                                 m->material_count, m->motion_count, m->probe_count,
                                 m->probe_pair_count, m->organ_count, m->coupling_count};
  for (int k = 0; k < SIZE_COUNT; ++k) z[k] = n[k];
}

static uint64_t fnv(uint64_t h, const void *data, size_t bytes) {
  const unsigned char *p = data;
  for (size_t k = 0; k < bytes; ++k) h = (h ^ p[k]) * UINT64_C(0x100000001b3);
  return h;
}

// FNV-1a over every array the solver reads (rest state, kinds, motions,
// loads, samples, weights, materials, gravity): two models with the same
// fingerprint simulate alike. Names, organs and provenance do not count.
static uint64_t fingerprint(const fascia_model *m) {
  const size_t R = sizeof(fascia_real), I = sizeof(int32_t);
  const size_t N = (size_t)m->frame_count, S = (size_t)m->sample_count, P = (size_t)m->pair_count;
  uint64_t h = UINT64_C(0xcbf29ce484222325);
  h = fnv(h, m->frame_position, 3 * N * R);
  h = fnv(h, m->frame_rotation, 4 * N * R);
  h = fnv(h, m->frame_kind, N * I);
  h = fnv(h, m->frame_motion, N * I);
  h = fnv(h, m->frame_load, 6 * N * R);
  h = fnv(h, m->sample_position, 3 * S * R);
  h = fnv(h, m->sample_volume, S * R);
  h = fnv(h, m->sample_material, S * I);
  h = fnv(h, m->sample_offsets, (S + 1) * I);
  h = fnv(h, m->pair_frame, P * I);
  h = fnv(h, m->pair_weight, P * R);
  h = fnv(h, m->pair_gradient, 3 * P * R);
  for (int32_t k = 0; k < m->material_count; ++k) {
    const fascia_material *mat = m->materials + k;
    const fascia_real values[5] = {mat->youngs_modulus, mat->poisson_ratio, mat->density, mat->rotation_coupling,
                                   mat->rotation_smoothing};
    h = fnv(h, &mat->law, I);
    h = fnv(h, values, sizeof values);
  }
  for (int32_t k = 0; k < m->motion_count; ++k) {
    const fascia_motion *mo = m->motions + k;
    const size_t K = (size_t)mo->key_count;
    h = fnv(h, mo->pivot, 3 * R);
    h = fnv(h, mo->key_time, K * R);
    h = fnv(h, mo->key_translation, 3 * K * R);
    h = fnv(h, mo->key_rotation, 4 * K * R);
  }
  return fnv(h, m->gravity, 3 * R);
}

// ---------------------------------------------------------------------------
// Writing

static fascia_status write_failed(fascia_ctx *ctx, const char *path, const char *name) {
  char detail[600];
  fascia_h5_error(detail, sizeof detail);
  return FASCIA_FAIL(ctx, FASCIA_ERR_IO, "checkpoint '%s' %s: cannot write (HDF5: %s); check the disk space", path,
                     name, detail);
}

// Writes dataset `name` of rank 1 [d0] or 2 [d0,d1] with the given file and
// memory types.
static int write_dataset(hid_t file, const char *name, int rank, hsize_t d0, hsize_t d1, hid_t file_type,
                         hid_t mem_type, const void *data) {
  const hsize_t dims[2] = {d0, d1};
  hid_t space = H5Screate_simple(rank, dims, NULL), dset = H5I_INVALID_HID;
  int ok = space >= 0;
  if (ok) dset = H5Dcreate2(file, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  ok = ok && dset >= 0;
  if (ok && d0 * (rank == 2 ? d1 : 1) > 0) ok = H5Dwrite(dset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0;
  if (dset >= 0) H5Dclose(dset);
  if (space >= 0) H5Sclose(space);
  return ok;
}

static int write_group(hid_t file, const char *name) {
  hid_t group = H5Gcreate2(file, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (group < 0) return 0;
  H5Gclose(group);
  return 1;
}

static fascia_status write_checkpoint(fascia_ctx *ctx, hid_t file, const fascia_solver *S, int64_t step,
                                      const char *path) {
  char creator[64];
  snprintf(creator, sizeof creator, "fascia %s", fascia_version());
  hid_t root = H5Gopen2(file, "/", H5P_DEFAULT);
  const int ok = root >= 0 && fascia_h5_attr_int(root, "fascia_checkpoint_version", CHECKPOINT_VERSION) >= 0 &&
                 fascia_h5_attr_string(root, "units", CHECKPOINT_UNITS) >= 0 &&
                 fascia_h5_attr_string(root, "creator", creator) >= 0;
  if (root >= 0) H5Gclose(root);
  if (!ok) return write_failed(ctx, path, "/");
  const hsize_t N = (hsize_t)S->frame_count;
  int64_t sizes[SIZE_COUNT];
  model_sizes(S->model, sizes);
  const uint64_t print = fingerprint(S->model);
  const double time_step = S->def.time_step;
  const size_t B = S->organs ? fascia_organs_state_size(S->organs) : 0;
  fascia_real *bodies = fascia_calloc((int64_t)B + 1, sizeof(fascia_real));
  FASCIA_CHECK(bodies, ctx, FASCIA_ERR_MEMORY, "checkpoint '%s': out of memory", path);
  if (B) fascia_organs_save(S->organs, bodies);
  fascia_status status = FASCIA_OK;
  if (!write_group(file, "/run") || !write_group(file, "/model") || !write_group(file, "/state"))
    status = write_failed(ctx, path, "groups");
#define PUT(name, rank, d0, d1, ftype, mtype, data)                                                                  \
  if (status == FASCIA_OK && !write_dataset(file, name, rank, d0, d1, ftype, mtype, data))                          \
  status = write_failed(ctx, path, name)
  PUT("/run/step", 1, 1, 0, H5T_STD_I64LE, H5T_NATIVE_INT64, &step);
  PUT("/run/time", 1, 1, 0, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &S->time);
  PUT("/run/time_step", 1, 1, 0, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &time_step);
  PUT("/model/sizes", 1, SIZE_COUNT, 0, H5T_STD_I64LE, H5T_NATIVE_INT64, sizes);
  PUT("/model/fingerprint", 1, 1, 0, H5T_STD_U64LE, H5T_NATIVE_UINT64, &print);
  PUT("/state/position", 2, N, 3, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, S->x);
  PUT("/state/rotation", 2, N, 4, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, S->q);
  PUT("/state/velocity", 2, N, 6, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, S->u);
  PUT("/state/organs", 1, B, 0, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, bodies);
#undef PUT
  free(bodies);
  return status;
}

fascia_status fascia_checkpoint_save(fascia_ctx *ctx, const fascia_solver *solver, int64_t step, const char *path) {
  FASCIA_CHECK(solver && path && path[0], ctx, FASCIA_ERR_ARGUMENT,
               "fascia_checkpoint_save: NULL solver or empty path");
  FASCIA_CHECK(step >= 0, ctx, FASCIA_ERR_ARGUMENT, "checkpoint '%s': step %lld is negative", path, (long long)step);
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  hid_t file;
  // built in memory, then written out: a full disk fails the write, not HDF5
  fascia_status status = fascia_h5_create_memory(ctx, "checkpoint", path, &file);
  if (status == FASCIA_OK) {
    status = write_checkpoint(ctx, file, solver, step, path);
    if (status == FASCIA_OK) status = fascia_h5_finish_memory(ctx, "checkpoint", &file, path);
    else H5Fclose(file);
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
} reader;

// Reads dataset `name`, which must hold exactly `count` values of class
// `cls` (any rank), converted to mem_type.
static fascia_status read_exact(reader *r, const char *name, H5T_class_t cls, hid_t mem_type, hsize_t count,
                                void *out) {
  FASCIA_CHECK(fascia_h5_link_exists(r->file, name), r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' %s: dataset missing; not a checkpoint written by 'fascia run --checkpoint'", r->path,
               name);
  hid_t dset = H5Dopen2(r->file, name, H5P_DEFAULT);
  hid_t type = dset >= 0 ? H5Dget_type(dset) : H5I_INVALID_HID, space = dset >= 0 ? H5Dget_space(dset) : H5I_INVALID_HID;
  fascia_status status = FASCIA_OK;
  char detail[600];
  if (dset < 0 || type < 0 || space < 0) {
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_IO, "checkpoint '%s' %s: cannot open (HDF5: %s); the file is damaged",
                         r->path, name, fascia_h5_error(detail, sizeof detail));
  } else if (H5Tget_class(type) != cls || H5Sget_simple_extent_npoints(space) != (hssize_t)count) {
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_FORMAT,
                         "checkpoint '%s' %s: expected %llu %s, found %lld values of another kind; the file is damaged",
                         r->path, name, (unsigned long long)count, cls == H5T_FLOAT ? "reals" : "integers",
                         (long long)H5Sget_simple_extent_npoints(space));
  } else if (count > 0 && H5Dread(dset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) < 0) {
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_IO, "checkpoint '%s' %s: cannot read (HDF5: %s); the file is damaged",
                         r->path, name, fascia_h5_error(detail, sizeof detail));
  }
  if (space >= 0) H5Sclose(space);
  if (type >= 0) H5Tclose(type);
  if (dset >= 0) H5Dclose(dset);
  return status;
}

static fascia_status open_checkpoint(reader *r) {
  char detail[600];
  FILE *probe = fopen(r->path, "rb");
  FASCIA_CHECK(probe, r->ctx, FASCIA_ERR_IO, "checkpoint '%s': cannot open: no such file or not readable", r->path);
  fclose(probe);
  const htri_t is_hdf5 = H5Fis_hdf5(r->path);
  FASCIA_CHECK(is_hdf5 > 0, r->ctx, FASCIA_ERR_IO, "checkpoint '%s': not an HDF5 file (%s)", r->path,
               is_hdf5 < 0 ? fascia_h5_error(detail, sizeof detail) : "no HDF5 signature");
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl >= 0) H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG);
  r->file = H5Fopen(r->path, H5F_ACC_RDONLY, fapl >= 0 ? fapl : H5P_DEFAULT);
  if (r->file < 0) fascia_h5_error(detail, sizeof detail);
  if (fapl >= 0) H5Pclose(fapl);
  FASCIA_CHECK(r->file >= 0, r->ctx, FASCIA_ERR_IO, "checkpoint '%s': cannot open as HDF5 (%s); the file is damaged",
               r->path, detail);
  const htri_t has_version = H5Aexists_by_name(r->file, "/", "fascia_checkpoint_version", H5P_DEFAULT);
  FASCIA_CHECK(has_version > 0, r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' /: not a fascia checkpoint (no root attribute 'fascia_checkpoint_version')", r->path);
  int32_t version = 0;
  hid_t attr = H5Aopen_by_name(r->file, "/", "fascia_checkpoint_version", H5P_DEFAULT, H5P_DEFAULT);
  const herr_t read = attr >= 0 ? H5Aread(attr, H5T_NATIVE_INT32, &version) : -1;
  if (attr >= 0) H5Aclose(attr);
  FASCIA_CHECK(read >= 0 && version == CHECKPOINT_VERSION, r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' /: format version %d, this fascia (%s) reads version %d; resume with the fascia that "
               "wrote it",
               r->path, (int)version, fascia_version(), CHECKPOINT_VERSION);
  return FASCIA_OK;
}

// Checks that the checkpoint belongs to this solver's model and time step.
static fascia_status check_identity(reader *r, const fascia_solver *S) {
  static const char *const size_names[SIZE_COUNT] = {"frames", "samples", "pairs", "materials", "motions",
                                                     "probes", "probe pairs", "organs", "couplings"};
  int64_t sizes[SIZE_COUNT], expected[SIZE_COUNT];
  uint64_t print = 0;
  double time_step = 0;
  FASCIA_TRY(read_exact(r, "/model/sizes", H5T_INTEGER, H5T_NATIVE_INT64, SIZE_COUNT, sizes));
  FASCIA_TRY(read_exact(r, "/model/fingerprint", H5T_INTEGER, H5T_NATIVE_UINT64, 1, &print));
  FASCIA_TRY(read_exact(r, "/run/time_step", H5T_FLOAT, H5T_NATIVE_DOUBLE, 1, &time_step));
  model_sizes(S->model, expected);
  for (int k = 0; k < SIZE_COUNT; ++k)
    FASCIA_CHECK(sizes[k] == expected[k], r->ctx, FASCIA_ERR_ARGUMENT,
                 "checkpoint '%s' belongs to another model: it has %lld %s, this model %lld (%lld frames and %lld "
                 "samples there, %lld and %lld here); resume with the model the run started from",
                 r->path, (long long)sizes[k], size_names[k], (long long)expected[k], (long long)sizes[0],
                 (long long)sizes[1], (long long)expected[0], (long long)expected[1]);
  const uint64_t here = fingerprint(S->model);
  FASCIA_CHECK(print == here, r->ctx, FASCIA_ERR_ARGUMENT,
               "checkpoint '%s' belongs to another model: same sizes, different contents (fingerprint %016llx, this "
               "model %016llx); resume with the model the run started from",
               r->path, (unsigned long long)print, (unsigned long long)here);
  FASCIA_CHECK(time_step == S->def.time_step, r->ctx, FASCIA_ERR_ARGUMENT,
               "checkpoint '%s' was written with a time step of %.17g s, this run uses %.17g s; resume with --dt %.17g",
               r->path, time_step, S->def.time_step, time_step);
  return FASCIA_OK;
}

// Reads and checks the state into x, q, u ([3N], [4N], [6N]).
static fascia_status read_state(reader *r, int64_t N, fascia_real *x, fascia_real *q, fascia_real *u,
                                size_t B, fascia_real *bodies, fascia_real *time, int64_t *step) {
  FASCIA_TRY(read_exact(r, "/run/step", H5T_INTEGER, H5T_NATIVE_INT64, 1, step));
  FASCIA_TRY(read_exact(r, "/run/time", H5T_FLOAT, H5T_NATIVE_DOUBLE, 1, time));
  FASCIA_CHECK(*step >= 0 && isfinite(*time), r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' /run: step %lld at time %g s is impossible; the file is damaged", r->path,
               (long long)*step, *time);
  FASCIA_TRY(read_exact(r, "/state/position", H5T_FLOAT, H5T_NATIVE_DOUBLE, (hsize_t)(3 * N), x));
  FASCIA_TRY(read_exact(r, "/state/rotation", H5T_FLOAT, H5T_NATIVE_DOUBLE, (hsize_t)(4 * N), q));
  FASCIA_TRY(read_exact(r, "/state/velocity", H5T_FLOAT, H5T_NATIVE_DOUBLE, (hsize_t)(6 * N), u));
  FASCIA_TRY(read_exact(r, "/state/organs", H5T_FLOAT, H5T_NATIVE_DOUBLE, (hsize_t)B, bodies));
  for (size_t k = 0; k < B; ++k)
    FASCIA_CHECK(isfinite(bodies[k]), r->ctx, FASCIA_ERR_FORMAT,
                 "checkpoint '%s' /state/organs: value %zu is not finite; the file is damaged", r->path, k);
  for (int64_t i = 0; i < N; ++i) {
    int finite = 1;
    for (int c = 0; c < 3; ++c) finite &= isfinite(x[3 * i + c]) != 0;
    for (int c = 0; c < 6; ++c) finite &= isfinite(u[6 * i + c]) != 0;
    const fascia_real *qi = q + 4 * i;
    const fascia_real norm2 = qi[0] * qi[0] + qi[1] * qi[1] + qi[2] * qi[2] + qi[3] * qi[3];
    // a unit quaternion to rounding (the solver normalizes after every update)
    FASCIA_CHECK(finite && fabs(norm2 - 1) < 1e-9, r->ctx, FASCIA_ERR_FORMAT,
                 "checkpoint '%s' /state: frame %lld has a non-finite value or a rotation that is not a unit "
                 "quaternion (|q|^2 = %g); the file is damaged",
                 r->path, (long long)i, norm2);
  }
  return FASCIA_OK;
}

fascia_status fascia_checkpoint_load(fascia_ctx *ctx, fascia_solver *solver, const char *path, int64_t *step) {
  FASCIA_CHECK(solver && path && step, ctx, FASCIA_ERR_ARGUMENT, "fascia_checkpoint_load: NULL argument");
  const int64_t N = solver->frame_count;
  const size_t B = solver->organs ? fascia_organs_state_size(solver->organs) : 0;
  fascia_real *buffer = fascia_calloc(13 * N + (int64_t)B + 1, sizeof(fascia_real));
  FASCIA_CHECK(buffer, ctx, FASCIA_ERR_MEMORY, "checkpoint '%s': out of memory for %lld frames", path, (long long)N);
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  reader r = {ctx, path, H5I_INVALID_HID};
  fascia_real time = 0;
  int64_t steps = 0;
  fascia_status status = open_checkpoint(&r);
  if (status == FASCIA_OK) status = check_identity(&r, solver);
  if (status == FASCIA_OK) status = read_state(&r, N, buffer, buffer + 3 * N, buffer + 7 * N, B, buffer + 13 * N, &time, &steps);
  if (r.file >= 0) H5Fclose(r.file);
  fascia_h5_quiet_end(&quiet);
  if (status == FASCIA_OK) {
    // copied as stored: no renormalization, so the next step starts from the very same bits
    memcpy(solver->x, buffer, 3 * (size_t)N * sizeof(fascia_real));
    memcpy(solver->q, buffer + 3 * N, 4 * (size_t)N * sizeof(fascia_real));
    memcpy(solver->u, buffer + 7 * N, 6 * (size_t)N * sizeof(fascia_real));
    solver->time = time;
    if (B) fascia_organs_restore(solver->organs, buffer + 13 * N);
    fascia_system_set_state(solver->sys, solver->x, solver->q);
    *step = steps;
  }
  free(buffer);
  return status;
}
