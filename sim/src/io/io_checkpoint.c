// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Checkpoints of a dynamic run ("nothing lost"): the solver state that the
// next implicit Euler step reads (solver.c: x, q, u and the time), written
// whole through a temporary name and read back bit for bit, with what it
// belongs to (the model, the solver settings) and a checksum, so that a
// damaged or edited file, another model or other settings are refused
// instead of resumed into a different trajectory.
//
// Schema, version 3 (N frames; reals f64 little endian):
//   /                     attributes fascia_checkpoint_version (int32, = 3),
//                         units ("SI: m, kg, s, Pa"), creator ("fascia X.Y.Z")
//   /run/step             [1]   i64  completed steps, 0 <= step <= 2^31 - 1
//   /run/time             [1]   f64  s, the solver's time after them; a run
//                                    starts at t = 0, so time = step * time_step
//                                    to rounding
//   /run/time_step        [1]   f64  s, the run's time step (also a setting)
//   /model/sizes          [9]   i64  frames, samples, pairs, materials, motions,
//                                    probes, probe pairs, organs, couplings
//   /run/inputs           [1]   u64  the caller's digest of what else the run
//                                    depends on (drive files; 0: nothing),
//                                    fascia_checkpoint_save_inputs
//   /run/checksum         [1]   u64  FNV-1a of the version, step, time,
//                                    time_step, inputs, the model's sizes and
//                                    fingerprint and the settings (in the
//                                    order of the table `settings`), as the
//                                    native values: everything a resume trusts
//                                    besides the state
//   /model/fingerprint    [1]   u64  FNV-1a of the model's arrays (fascia_model_fingerprint)
//   /settings             group, one f64 attribute per solver setting that
//                         changes the trajectory (the table `settings`:
//                         time_step, newton_iterations, ..., require_convergence)
//   /state/position       [N,3] f64  m, world
//   /state/rotation       [N,4] f64  unit quaternions w,x,y,z
//   /state/velocity       [N,6] f64  m/s then rad/s, world
//   /state/organs         [B]   f64  state of the rigid organ bodies (organs.c:
//                                    fascia_organs_save), B = 0 without them
//   /state/linear         [L]   f64  the linear solver's kept factorization
//                                    (backend.h, linear_state_save; L = 0:
//                                    none; absent in older files: none), so
//                                    that the resumed run takes the saving
//                                    run's path bit for bit
//   /state/checksum       [1]   u64  FNV-1a, continuing from /run/checksum's
//                                    value, of step, time, position, rotation,
//                                    velocity, organs and linear, in that
//                                    order, as the native values (so a state
//                                    cannot be moved under another header)
//
// Versions 1 (no settings, no checksum) and 2 (a checksum of the state only:
// settings and run records unprotected) are refused with a message saying so.
//
// Why a checksum of our own and not HDF5's Fletcher32 filter: the filter
// only sees damage below HDF5 (a flipped bit on disk) and needs chunked
// datasets; a state rewritten through the HDF5 API (a tool, a script, a
// partial copy) gets a fresh, valid Fletcher32 sum. A checksum over the
// values themselves, stored beside them, catches both. FNV-1a is the hash
// this file already uses for the model's fingerprint: every single-byte
// change changes it (each step is a bijection of the running value).
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "solve/backend.h"
#include "fascia/checkpoint.h"
#include "util/fnv.h"
#include "io/h5io.h"
#include "organs/organs.h"
#include "solve/solver_internal.h"

#define CHECKPOINT_VERSION 3
#define CHECKPOINT_UNITS "SI: m, kg, s, Pa"
#define SIZE_COUNT 9
#define MAX_STEP INT64_C(2147483647) // fascia_solver_step counts in int; the CLI's --steps too

_Static_assert(sizeof(fascia_real) == sizeof(double), "checkpoints store fascia_real as f64");

// ---------------------------------------------------------------------------
// What identifies the model

static void model_sizes(const fascia_model *m, int64_t *z) {
  const int32_t n[SIZE_COUNT] = {m->frame_count,  m->sample_count, m->pair_count,
                                 m->material_count, m->motion_count, m->probe_count,
                                 m->probe_pair_count, m->organ_count, m->coupling_count};
  for (int k = 0; k < SIZE_COUNT; ++k) z[k] = n[k];
}


// The checksum of a state, continuing from the header's: step, time, x [3N],
// q [4N], u [6N], bodies [B], linear [L].
static uint64_t state_checksum(uint64_t header, int64_t step, double time, int64_t N, const fascia_real *x,
                               const fascia_real *q, const fascia_real *u, size_t B, const fascia_real *bodies,
                               int64_t L, const fascia_real *linear) {
  const size_t R = sizeof(fascia_real);
  uint64_t h = fascia_fnv(header, &step, sizeof step);
  h = fascia_fnv(h, &time, sizeof time);
  h = fascia_fnv(h, x, 3 * (size_t)N * R);
  h = fascia_fnv(h, q, 4 * (size_t)N * R);
  h = fascia_fnv(h, u, 6 * (size_t)N * R);
  h = fascia_fnv(h, bodies, B * R);
  return fascia_fnv(h, linear, (size_t)L * R);
}

// The backend's kept linear state (backend.h): its size, 0 for none.
static int64_t linear_size(const fascia_solver *S) {
  const fascia_backend *be = S->backend;
  return be->ops->linear_state_size && be->ops->linear_state_save ? be->ops->linear_state_size(S->backend) : 0;
}

// ---------------------------------------------------------------------------
// The settings that change the trajectory

typedef enum setting_kind { SETTING_INT, SETTING_REAL } setting_kind;

typedef struct setting {
  const char *name;
  setting_kind kind;
} setting;

// Every fascia_solver_def field that changes the state a step reaches. Not
// here: backend and threads (the CPU result does not depend on the thread
// count; the device's differs by rounding, a choice the user makes), and
// load_steps (static solves only).
static const setting settings[] = {
    {"time_step", SETTING_REAL},      {"newton_iterations", SETTING_INT},
    {"newton_tolerance", SETTING_REAL}, {"cg_iterations", SETTING_INT},
    {"cg_fixed", SETTING_INT},        {"cg_tolerance", SETTING_REAL},
    {"precond", SETTING_INT},         {"linear_solver", SETTING_INT},
    {"assembled", SETTING_INT},       {"single_precision_matrix", SETTING_INT},
    {"mass", SETTING_INT},            {"mass_damping", SETTING_REAL},
    {"line_search", SETTING_INT},     {"step_retries", SETTING_INT},
    {"require_convergence", SETTING_INT}, {"blow_up_strain", SETTING_REAL},
};
#define SETTING_COUNT ((int)(sizeof settings / sizeof settings[0]))

int fascia_checkpoint_setting_count(void) { return SETTING_COUNT; }

const char *fascia_checkpoint_setting_name(int k) { return k >= 0 && k < SETTING_COUNT ? settings[k].name : NULL; }

double fascia_checkpoint_setting_get(const fascia_solver_def *d, int k) {
  switch (k) {
  case 0: return d->time_step;
  case 1: return d->newton_iterations;
  case 2: return d->newton_tolerance;
  case 3: return d->cg_iterations;
  case 4: return d->cg_fixed;
  case 5: return d->cg_tolerance;
  case 6: return (double)d->precond;
  case 7: return (double)d->linear_solver;
  case 8: return d->assembled;
  case 9: return d->single_precision_matrix;
  case 10: return (double)d->mass;
  case 11: return d->mass_damping;
  case 12: return d->line_search;
  case 13: return d->step_retries;
  case 14: return d->require_convergence;
  case 15: return d->blow_up_strain;
  default: return NAN;
  }
}

void fascia_checkpoint_setting_set(fascia_solver_def *d, int k, double v) {
  const int i = (int)v;
  switch (k) {
  case 0: d->time_step = v; break;
  case 1: d->newton_iterations = i; break;
  case 2: d->newton_tolerance = v; break;
  case 3: d->cg_iterations = i; break;
  case 4: d->cg_fixed = i; break;
  case 5: d->cg_tolerance = v; break;
  case 6: d->precond = (fascia_precond)i; break;
  case 7: d->linear_solver = (fascia_linear_solver)i; break;
  case 8: d->assembled = i; break;
  case 9: d->single_precision_matrix = i; break;
  case 10: d->mass = (fascia_mass_kind)i; break;
  case 11: d->mass_damping = v; break;
  case 12: d->line_search = i; break;
  case 13: d->step_retries = i; break;
  case 14: d->require_convergence = i; break;
  case 15: d->blow_up_strain = v; break;
  default: break;
  }
}

// ---------------------------------------------------------------------------
// What a resume trusts besides the state

typedef struct header {
  int64_t step;
  double time, time_step;
  uint64_t inputs, fingerprint;
  int64_t sizes[SIZE_COUNT];
  double settings[SETTING_COUNT];
} header;

static uint64_t header_checksum(const header *h) {
  const int32_t version = CHECKPOINT_VERSION;
  uint64_t c = fascia_fnv(FASCIA_FNV_START, &version, sizeof version);
  c = fascia_fnv(c, &h->step, sizeof h->step);
  c = fascia_fnv(c, &h->time, sizeof h->time);
  c = fascia_fnv(c, &h->time_step, sizeof h->time_step);
  c = fascia_fnv(c, &h->inputs, sizeof h->inputs);
  c = fascia_fnv(c, h->sizes, sizeof h->sizes);
  c = fascia_fnv(c, &h->fingerprint, sizeof h->fingerprint);
  return fascia_fnv(c, h->settings, sizeof h->settings);
}

static void header_of(const fascia_solver *S, int64_t step, uint64_t inputs, header *h) {
  memset(h, 0, sizeof *h);
  h->step = step;
  h->time = S->time;
  h->time_step = S->def.time_step;
  h->inputs = inputs;
  h->fingerprint = fascia_model_fingerprint(S->model);
  model_sizes(S->model, h->sizes);
  for (int k = 0; k < SETTING_COUNT; ++k) h->settings[k] = fascia_checkpoint_setting_get(&S->def, k);
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

// /settings: one scalar f64 attribute per entry of `settings`.
static int write_settings(hid_t file, const header *h) {
  hid_t group = H5Gcreate2(file, "/settings", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  hid_t space = H5Screate(H5S_SCALAR);
  int ok = group >= 0 && space >= 0;
  for (int k = 0; ok && k < SETTING_COUNT; ++k) {
    const double value = h->settings[k];
    hid_t attr = H5Acreate2(group, settings[k].name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT);
    ok = attr >= 0 && H5Awrite(attr, H5T_NATIVE_DOUBLE, &value) >= 0;
    if (attr >= 0) H5Aclose(attr);
  }
  if (space >= 0) H5Sclose(space);
  if (group >= 0) H5Gclose(group);
  return ok;
}

static fascia_status write_checkpoint(fascia_ctx *ctx, hid_t file, const fascia_solver *S, int64_t step,
                                      uint64_t inputs, const char *path) {
  char creator[64];
  snprintf(creator, sizeof creator, "fascia %s", fascia_version());
  hid_t root = H5Gopen2(file, "/", H5P_DEFAULT);
  const int ok = root >= 0 && fascia_h5_attr_int(root, "fascia_checkpoint_version", CHECKPOINT_VERSION) >= 0 &&
                 fascia_h5_attr_string(root, "units", CHECKPOINT_UNITS) >= 0 &&
                 fascia_h5_attr_string(root, "creator", creator) >= 0;
  if (root >= 0) H5Gclose(root);
  if (!ok) return write_failed(ctx, path, "/");
  const hsize_t N = (hsize_t)S->frame_count;
  header h;
  header_of(S, step, inputs, &h);
  const uint64_t head = header_checksum(&h);
  const size_t B = S->organs ? fascia_organs_state_size(S->organs) : 0;
  fascia_real *bodies = fascia_calloc((int64_t)B + 1, sizeof(fascia_real));
  FASCIA_CHECK(bodies, ctx, FASCIA_ERR_MEMORY, "checkpoint '%s': out of memory", path);
  if (B) fascia_organs_save(S->organs, bodies);
  const int64_t L = linear_size(S);
  fascia_real *linear = fascia_calloc(L + 1, sizeof(fascia_real));
  if (!linear) free(bodies);
  FASCIA_CHECK(linear, ctx, FASCIA_ERR_MEMORY, "checkpoint '%s': out of memory", path);
  if (L) S->backend->ops->linear_state_save(S->backend, linear);
  const uint64_t checksum =
      state_checksum(head, step, h.time, S->frame_count, S->x, S->q, S->u, B, bodies, L, linear);
  fascia_status status = FASCIA_OK;
  if (!write_group(file, "/run") || !write_group(file, "/model") || !write_group(file, "/state"))
    status = write_failed(ctx, path, "groups");
  if (status == FASCIA_OK && !write_settings(file, &h)) status = write_failed(ctx, path, "/settings");
#define PUT(name, rank, d0, d1, ftype, mtype, data)                                                                  \
  if (status == FASCIA_OK && !write_dataset(file, name, rank, d0, d1, ftype, mtype, data))                          \
  status = write_failed(ctx, path, name)
  PUT("/run/step", 1, 1, 0, H5T_STD_I64LE, H5T_NATIVE_INT64, &h.step);
  PUT("/run/time", 1, 1, 0, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &h.time);
  PUT("/run/time_step", 1, 1, 0, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &h.time_step);
  PUT("/run/inputs", 1, 1, 0, H5T_STD_U64LE, H5T_NATIVE_UINT64, &h.inputs);
  PUT("/run/checksum", 1, 1, 0, H5T_STD_U64LE, H5T_NATIVE_UINT64, &head);
  PUT("/model/sizes", 1, SIZE_COUNT, 0, H5T_STD_I64LE, H5T_NATIVE_INT64, h.sizes);
  PUT("/model/fingerprint", 1, 1, 0, H5T_STD_U64LE, H5T_NATIVE_UINT64, &h.fingerprint);
  PUT("/state/position", 2, N, 3, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, S->x);
  PUT("/state/rotation", 2, N, 4, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, S->q);
  PUT("/state/velocity", 2, N, 6, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, S->u);
  PUT("/state/organs", 1, B, 0, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, bodies);
  PUT("/state/linear", 1, (hsize_t)L, 0, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, linear);
  PUT("/state/checksum", 1, 1, 0, H5T_STD_U64LE, H5T_NATIVE_UINT64, &checksum);
#undef PUT
  free(bodies);
  free(linear);
  return status;
}

fascia_status fascia_checkpoint_save_inputs(fascia_ctx *ctx, const fascia_solver *solver, int64_t step,
                                            uint64_t inputs, const char *path) {
  FASCIA_CHECK(solver && path && path[0], ctx, FASCIA_ERR_ARGUMENT,
               "fascia_checkpoint_save: NULL solver or empty path");
  FASCIA_CHECK(step >= 0 && step <= MAX_STEP, ctx, FASCIA_ERR_ARGUMENT,
               "checkpoint '%s': step %lld is outside 0..%lld", path, (long long)step, (long long)MAX_STEP);
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  hid_t file;
  // built in memory, then written out: a full disk fails the write, not HDF5
  fascia_status status = fascia_h5_create_memory(ctx, "checkpoint", path, &file);
  if (status == FASCIA_OK) {
    status = write_checkpoint(ctx, file, solver, step, inputs, path);
    if (status == FASCIA_OK) status = fascia_h5_finish_memory(ctx, "checkpoint", &file, path);
    else H5Fclose(file);
  }
  fascia_h5_quiet_end(&quiet);
  return status;
}

fascia_status fascia_checkpoint_save(fascia_ctx *ctx, const fascia_solver *solver, int64_t step, const char *path) {
  return fascia_checkpoint_save_inputs(ctx, solver, step, 0, path);
}

// ---------------------------------------------------------------------------
// Reading

typedef struct reader {
  fascia_ctx *ctx;
  const char *path;
  hid_t file;
} reader;

#define DAMAGED "the file is damaged or was edited; resume from another checkpoint or start the run again"

// Reads dataset `name`, which must hold exactly `count` values of class
// `cls` (any rank), converted to mem_type.
static fascia_status read_exact(reader *r, const char *name, H5T_class_t cls, hid_t mem_type, hsize_t count,
                                void *out) {
  FASCIA_CHECK(fascia_h5_link_exists(r->file, name), r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' %s: dataset missing; not a checkpoint written by 'fascia run --checkpoint'", r->path,
               name);
  fascia_h5_scope scope = FASCIA_H5_SCOPE_INIT;
  const hid_t dset = fascia_h5_keep(&scope, H5Dopen2(r->file, name, H5P_DEFAULT));
  const hid_t type = dset >= 0 ? fascia_h5_keep(&scope, H5Dget_type(dset)) : H5I_INVALID_HID;
  const hid_t space = dset >= 0 ? fascia_h5_keep(&scope, H5Dget_space(dset)) : H5I_INVALID_HID;
  fascia_status status = FASCIA_OK;
  char detail[600];
  if (dset < 0 || type < 0 || space < 0) {
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_IO, "checkpoint '%s' %s: cannot open (HDF5: %s); %s", r->path, name,
                         fascia_h5_error(detail, sizeof detail), DAMAGED);
  } else if (H5Tget_class(type) != cls || !fascia_h5_number_type_ok(type) ||
             H5Sget_simple_extent_npoints(space) != (hssize_t)count) {
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_FORMAT, "checkpoint '%s' %s: expected %llu %s, found %lld values; %s",
                         r->path, name, (unsigned long long)count, cls == H5T_FLOAT ? "reals" : "integers",
                         (long long)H5Sget_simple_extent_npoints(space), DAMAGED);
  } else if (count > 0 && H5Dread(dset, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) < 0) {
    status = FASCIA_FAIL(r->ctx, FASCIA_ERR_IO, "checkpoint '%s' %s: cannot read (HDF5: %s); %s", r->path, name,
                         fascia_h5_error(detail, sizeof detail), DAMAGED);
  }
  fascia_h5_scope_close(&scope);
  return status;
}

// Reads the scalar numeric attribute `attr_name` of object `name` as a double.
static fascia_status read_attr(reader *r, const char *name, const char *attr_name, double *value) {
  const htri_t exists = H5Aexists_by_name(r->file, name, attr_name, H5P_DEFAULT);
  FASCIA_CHECK(exists > 0, r->ctx, FASCIA_ERR_FORMAT, "checkpoint '%s' %s: attribute '%s' missing; %s", r->path,
               name, attr_name, DAMAGED);
  fascia_h5_scope scope = FASCIA_H5_SCOPE_INIT;
  const hid_t attr = fascia_h5_keep(&scope, H5Aopen_by_name(r->file, name, attr_name, H5P_DEFAULT, H5P_DEFAULT));
  const hid_t type = attr >= 0 ? fascia_h5_keep(&scope, H5Aget_type(attr)) : H5I_INVALID_HID;
  const hid_t space = attr >= 0 ? fascia_h5_keep(&scope, H5Aget_space(attr)) : H5I_INVALID_HID;
  const H5T_class_t cls = type >= 0 ? H5Tget_class(type) : H5T_NO_CLASS;
  const int ok = space >= 0 && (cls == H5T_INTEGER || cls == H5T_FLOAT) && fascia_h5_number_type_ok(type) &&
                 H5Sget_simple_extent_npoints(space) == 1 &&
                 H5Aread(attr, H5T_NATIVE_DOUBLE, value) >= 0;
  fascia_h5_scope_close(&scope);
  FASCIA_CHECK(ok, r->ctx, FASCIA_ERR_FORMAT, "checkpoint '%s' %s: attribute '%s' is not one number; %s", r->path,
               name, attr_name, DAMAGED);
  return FASCIA_OK;
}

static fascia_status open_checkpoint(reader *r) {
  FASCIA_TRY(fascia_h5_open_read(r->ctx, "checkpoint", r->path, "expected a checkpoint written by 'fascia run --checkpoint'",
                                 &r->file));
  const htri_t has_version = H5Aexists_by_name(r->file, "/", "fascia_checkpoint_version", H5P_DEFAULT);
  FASCIA_CHECK(has_version > 0, r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' /: not a fascia checkpoint (no root attribute 'fascia_checkpoint_version')", r->path);
  double version = 0;
  FASCIA_TRY(read_attr(r, "/", "fascia_checkpoint_version", &version));
  FASCIA_CHECK(version != 1 && version != 2, r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' /: format version %g, written by an older fascia whose checksum does not cover %s; "
               "this fascia (%s) reads version %d only: finish the run with the fascia that wrote it, or start it "
               "again",
               r->path, version, version == 1 ? "the state or the solver settings" : "the solver settings and run records",
               fascia_version(), CHECKPOINT_VERSION);
  FASCIA_CHECK(version == CHECKPOINT_VERSION, r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' /: format version %g, this fascia (%s) reads version %d; resume with the fascia that "
               "wrote it",
               r->path, version, fascia_version(), CHECKPOINT_VERSION);
  return FASCIA_OK;
}

// Reads everything but the state into *h and checks it against
// /run/checksum: nothing of it is trusted before that.
static fascia_status read_header(reader *r, header *h) {
  memset(h, 0, sizeof *h);
  FASCIA_TRY(read_exact(r, "/run/step", H5T_INTEGER, H5T_NATIVE_INT64, 1, &h->step));
  FASCIA_TRY(read_exact(r, "/run/time", H5T_FLOAT, H5T_NATIVE_DOUBLE, 1, &h->time));
  FASCIA_TRY(read_exact(r, "/run/time_step", H5T_FLOAT, H5T_NATIVE_DOUBLE, 1, &h->time_step));
  FASCIA_TRY(read_exact(r, "/run/inputs", H5T_INTEGER, H5T_NATIVE_UINT64, 1, &h->inputs));
  FASCIA_TRY(read_exact(r, "/model/sizes", H5T_INTEGER, H5T_NATIVE_INT64, SIZE_COUNT, h->sizes));
  FASCIA_TRY(read_exact(r, "/model/fingerprint", H5T_INTEGER, H5T_NATIVE_UINT64, 1, &h->fingerprint));
  FASCIA_CHECK(fascia_h5_link_exists(r->file, "/settings"), r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' /settings: group missing; %s", r->path, DAMAGED);
  for (int k = 0; k < SETTING_COUNT; ++k) FASCIA_TRY(read_attr(r, "/settings", settings[k].name, &h->settings[k]));
  uint64_t stored = 0;
  FASCIA_TRY(read_exact(r, "/run/checksum", H5T_INTEGER, H5T_NATIVE_UINT64, 1, &stored));
  const uint64_t computed = header_checksum(h);
  FASCIA_CHECK(stored == computed, r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' /run/checksum: the run, model and settings records (/run, /model, /settings) do not "
               "match their checksum (stored %016llx, computed %016llx); %s",
               r->path, (unsigned long long)stored, (unsigned long long)computed, DAMAGED);
  return FASCIA_OK;
}

// The step count and time, checked against each other and the time step.
static fascia_status check_run(reader *r, const header *h) {
  FASCIA_CHECK(h->step >= 0 && h->step <= MAX_STEP, r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' /run/step: step %lld is outside 0..%lld; %s", r->path, (long long)h->step,
               (long long)MAX_STEP, DAMAGED);
  // a run starts at t = 0 and adds time_step per step, rounding once per
  // step: the sum drifts from step * time_step by at most ~step^2 * eps / 4 steps
  const double time_step = h->time_step, expected = (double)h->step * time_step, n = (double)h->step;
  const double tolerance = time_step * (1e-6 + n * n * DBL_EPSILON);
  FASCIA_CHECK(isfinite(h->time) && fabs(h->time - expected) <= tolerance, r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' /run/time: t = %.17g s after %lld steps of %.17g s, expected %.17g s; %s", r->path,
               h->time, (long long)h->step, time_step, expected, DAMAGED);
  return FASCIA_OK;
}

// The settings recorded in /settings, into def (others left as they are).
static fascia_status read_settings(reader *r, const header *h, fascia_solver_def *def) {
  for (int k = 0; k < SETTING_COUNT; ++k) {
    const double value = h->settings[k];
    FASCIA_CHECK(isfinite(value) && (settings[k].kind == SETTING_REAL || (value == floor(value) && fabs(value) < 1e9)),
                 r->ctx, FASCIA_ERR_FORMAT, "checkpoint '%s' /settings: %s = %g is not a valid value; %s", r->path,
                 settings[k].name, value, DAMAGED);
    fascia_checkpoint_setting_set(def, k, value);
  }
  FASCIA_CHECK(h->time_step == def->time_step && h->time_step > 0, r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' /run/time_step: %.17g s, but /settings says %.17g s; %s", r->path, h->time_step,
               def->time_step, DAMAGED);
  return FASCIA_OK;
}

// Checks that the checkpoint belongs to this model.
static fascia_status check_model(reader *r, const header *h, const fascia_model *m) {
  static const char *const size_names[SIZE_COUNT] = {"frames", "samples", "pairs", "materials", "motions",
                                                     "probes", "probe pairs", "organs", "couplings"};
  int64_t expected[SIZE_COUNT];
  const int64_t *sizes = h->sizes;
  model_sizes(m, expected);
  for (int k = 0; k < SIZE_COUNT; ++k)
    FASCIA_CHECK(sizes[k] == expected[k], r->ctx, FASCIA_ERR_ARGUMENT,
                 "checkpoint '%s' /model/sizes: belongs to another model: it has %lld %s, this model %lld (%lld frames "
                 "and %lld samples there, %lld and %lld here); resume with the model the run started from",
                 r->path, (long long)sizes[k], size_names[k], (long long)expected[k], (long long)sizes[0],
                 (long long)sizes[1], (long long)expected[0], (long long)expected[1]);
  const uint64_t here = fascia_model_fingerprint(m);
  FASCIA_CHECK(h->fingerprint == here, r->ctx, FASCIA_ERR_ARGUMENT,
               "checkpoint '%s' /model/fingerprint: belongs to another model: same sizes, different contents "
               "(fingerprint %016llx, this model %016llx); resume with the model the run started from",
               r->path, (unsigned long long)h->fingerprint, (unsigned long long)here);
  return FASCIA_OK;
}

// Checks that the checkpoint was written with this solver's settings.
static fascia_status check_settings(reader *r, const header *h, const fascia_solver_def *def) {
  fascia_solver_def recorded = *def;
  FASCIA_TRY(read_settings(r, h, &recorded));
  for (int k = 0; k < SETTING_COUNT; ++k) {
    const double there = fascia_checkpoint_setting_get(&recorded, k), mine = fascia_checkpoint_setting_get(def, k);
    FASCIA_CHECK(there == mine, r->ctx, FASCIA_ERR_ARGUMENT,
                 "checkpoint '%s' /settings: %s is %.17g there, %.17g in this solver; resume with the settings the run "
                 "started with (fascia_checkpoint_read_settings; 'fascia run --resume' takes them by default)",
                 r->path, settings[k].name, there, mine);
  }
  return FASCIA_OK;
}

// Opens the checkpoint and checks everything but the state: version,
// checksum of the records, step against time, the settings' values and,
// when model is not NULL, that it belongs to it.
static fascia_status read_checked_header(reader *r, const fascia_model *model, header *h, fascia_solver_def *def) {
  FASCIA_TRY(open_checkpoint(r));
  FASCIA_TRY(read_header(r, h));
  FASCIA_TRY(read_settings(r, h, def));
  FASCIA_TRY(check_run(r, h));
  if (model) FASCIA_TRY(check_model(r, h, model));
  return FASCIA_OK;
}

// How many values the dataset holds; 0 where it is absent.
static int64_t dataset_length(reader *r, const char *name) {
  if (!fascia_h5_link_exists(r->file, name)) return 0;
  fascia_h5_scope scope = FASCIA_H5_SCOPE_INIT;
  const hid_t dset = fascia_h5_keep(&scope, H5Dopen2(r->file, name, H5P_DEFAULT));
  const hid_t space = dset >= 0 ? fascia_h5_keep(&scope, H5Dget_space(dset)) : H5I_INVALID_HID;
  const hssize_t n = space >= 0 ? H5Sget_simple_extent_npoints(space) : 0;
  fascia_h5_scope_close(&scope);
  return n > 0 ? (int64_t)n : 0;
}

// Reads and checks the state into x, q, u ([3N], [4N], [6N]), bodies [B]
// and the linear solver's kept state [L].
static fascia_status read_state(reader *r, const header *h, int64_t N, fascia_real *x, fascia_real *q,
                                fascia_real *u, size_t B, fascia_real *bodies, int64_t L, fascia_real *linear) {
  FASCIA_TRY(read_exact(r, "/state/position", H5T_FLOAT, H5T_NATIVE_DOUBLE, (hsize_t)(3 * N), x));
  FASCIA_TRY(read_exact(r, "/state/rotation", H5T_FLOAT, H5T_NATIVE_DOUBLE, (hsize_t)(4 * N), q));
  FASCIA_TRY(read_exact(r, "/state/velocity", H5T_FLOAT, H5T_NATIVE_DOUBLE, (hsize_t)(6 * N), u));
  FASCIA_TRY(read_exact(r, "/state/organs", H5T_FLOAT, H5T_NATIVE_DOUBLE, (hsize_t)B, bodies));
  if (L) FASCIA_TRY(read_exact(r, "/state/linear", H5T_FLOAT, H5T_NATIVE_DOUBLE, (hsize_t)L, linear));
  uint64_t stored = 0;
  FASCIA_TRY(read_exact(r, "/state/checksum", H5T_INTEGER, H5T_NATIVE_UINT64, 1, &stored));
  const uint64_t computed = state_checksum(header_checksum(h), h->step, h->time, N, x, q, u, B, bodies, L, linear);
  FASCIA_CHECK(stored == computed, r->ctx, FASCIA_ERR_FORMAT,
               "checkpoint '%s' /state/checksum: the state does not match its checksum (stored %016llx, computed "
               "%016llx); %s",
               r->path, (unsigned long long)stored, (unsigned long long)computed, DAMAGED);
  // the checksum vouches for the bits; these catch a state that was wrong when written
  for (size_t k = 0; k < B; ++k)
    FASCIA_CHECK(isfinite(bodies[k]), r->ctx, FASCIA_ERR_FORMAT,
                 "checkpoint '%s' /state/organs: value %zu is not finite; %s", r->path, k, DAMAGED);
  for (int64_t i = 0; i < N; ++i) {
    int finite = 1;
    for (int c = 0; c < 3; ++c) finite &= isfinite(x[3 * i + c]) != 0;
    for (int c = 0; c < 6; ++c) finite &= isfinite(u[6 * i + c]) != 0;
    const fascia_real *qi = q + 4 * i;
    const fascia_real norm2 = qi[0] * qi[0] + qi[1] * qi[1] + qi[2] * qi[2] + qi[3] * qi[3];
    // a unit quaternion to rounding (the solver normalizes after every update)
    FASCIA_CHECK(finite && fabs(norm2 - 1) < 1e-9, r->ctx, FASCIA_ERR_FORMAT,
                 "checkpoint '%s' /state: frame %lld has a non-finite value or a rotation that is not a unit "
                 "quaternion (|q|^2 = %g); %s",
                 r->path, (long long)i, norm2, DAMAGED);
  }
  return FASCIA_OK;
}

fascia_status fascia_checkpoint_read_settings(fascia_ctx *ctx, const char *path, const fascia_model *model,
                                              fascia_solver_def *def, int64_t *step) {
  FASCIA_CHECK(path && def && step, ctx, FASCIA_ERR_ARGUMENT, "fascia_checkpoint_read_settings: NULL argument");
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  reader r = {ctx, path, H5I_INVALID_HID};
  fascia_solver_def read = *def;
  header h;
  const fascia_status status = read_checked_header(&r, model, &h, &read);
  if (r.file >= 0) H5Fclose(r.file);
  fascia_h5_quiet_end(&quiet);
  if (status == FASCIA_OK) {
    *def = read;
    *step = h.step;
  }
  return status;
}

fascia_status fascia_checkpoint_read_inputs(fascia_ctx *ctx, const char *path, const fascia_model *model,
                                            uint64_t *inputs) {
  FASCIA_CHECK(path && inputs, ctx, FASCIA_ERR_ARGUMENT, "fascia_checkpoint_read_inputs: NULL argument");
  fascia_h5_quiet quiet;
  fascia_h5_quiet_begin(&quiet);
  reader r = {ctx, path, H5I_INVALID_HID};
  fascia_solver_def read = fascia_solver_def_default();
  header h;
  const fascia_status status = read_checked_header(&r, model, &h, &read);
  if (r.file >= 0) H5Fclose(r.file);
  fascia_h5_quiet_end(&quiet);
  if (status == FASCIA_OK) *inputs = h.inputs;
  return status;
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
  header h;
  fascia_solver_def recorded = solver->def;
  int64_t L = 0;
  fascia_real *linear = NULL;
  fascia_status status = read_checked_header(&r, solver->model, &h, &recorded);
  if (status == FASCIA_OK) status = check_settings(&r, &h, &solver->def);
  if (status == FASCIA_OK) {
    L = dataset_length(&r, "/state/linear");
    linear = fascia_calloc(L + 1, sizeof(fascia_real));
    if (!linear) status = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "checkpoint '%s': out of memory for /state/linear", path);
  }
  if (status == FASCIA_OK)
    status = read_state(&r, &h, N, buffer, buffer + 3 * N, buffer + 7 * N, B, buffer + 13 * N, L, linear);
  if (r.file >= 0) H5Fclose(r.file);
  fascia_h5_quiet_end(&quiet);
  if (status == FASCIA_OK) {
    fascia_solver_resume(solver, buffer, buffer + 3 * N, buffer + 7 * N, h.time, B ? buffer + 13 * N : NULL);
    // the factorization the saving run kept (where it fits: else the next step factors afresh)
    const fascia_backend_ops *ops = solver->backend->ops;
    if (L && ops->linear_state_load) ops->linear_state_load(solver->backend, linear, L);
    *step = h.step;
  }
  free(linear);
  free(buffer);
  return status;
}
