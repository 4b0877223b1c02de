// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A checkpoint is only resumed when it is intact and belongs to the solver:
// a flipped bit in the state, positions moved through the HDF5 API, a step
// count or time that cannot be, another model, or a solver with other
// settings are each refused with the file and the dataset named (the kept
// factorization, /state/linear, is under the checksum too), and the
// solver is left unchanged. After every refusal no HDF5 object is left open.
// The settings read back from a checkpoint are those it was written with.
// The records a resume trusts besides the state (/settings, /run, /model) are
// under a checksum of their own: a flipped bit in any setting attribute, a
// step, time, time step, input digest, size or fingerprint rewritten is
// refused by fascia_checkpoint_read_settings, _read_inputs and _load alike,
// and a version 2 file (whose checksum left them out) is refused.
// Of random byte mutations of a checkpoint, every one is either refused
// (by fascia_checkpoint_read_settings or _load) or resumes the very same
// state with the very same settings. A FIFO given as the checkpoint is
// refused at once (an alarm fails the
// test if the open blocks).
#define _POSIX_C_SOURCE 200809L
#include <hdf5.h>
#include <signal.h>
#include <sys/stat.h>

#include "check.h"
#include "io_fixture.h"
#include "scenes.h"

static char dir[] = "t207-XXXXXX";
static char good[256];

static ssize_t open_ids(void) { return H5Fget_obj_count((hid_t)H5F_OBJ_ALL, H5F_OBJ_ALL); }

// Loads path into solver and expects `want` with a message naming the file
// and containing part1 and part2; the solver's time must not change.
static void expect_refused(fascia_ctx *ctx, fascia_solver *solver, const char *path, fascia_status want,
                           const char *part1, const char *part2) {
  const double time = fascia_solver_time(solver);
  int64_t step = -1;
  fascia_ctx_clear(ctx);
  const fascia_status st = fascia_checkpoint_load(ctx, solver, path, &step);
  const char *message = fascia_ctx_message(ctx);
  if (st != want || !strstr(message, path) || (part1 && !strstr(message, part1)) ||
      (part2 && !strstr(message, part2)) || step != -1 || fascia_solver_time(solver) != time) {
    fprintf(stderr, "t207: '%s' gave %s (wanted %s), step %lld, message \"%s\" (wanted '%s', '%s')\n", path,
            fascia_status_name(st), fascia_status_name(want), (long long)step, message, part1 ? part1 : "",
            part2 ? part2 : "");
    ++check_failures_;
  }
  if (open_ids() != 0) {
    fprintf(stderr, "t207: '%s': %ld HDF5 objects left open after the refusal\n", path, (long)open_ids());
    ++check_failures_;
  }
}

static hid_t corrupt_copy(const char *what, char *path, size_t size) {
  snprintf(path, size, "%s/%s.ck.h5", dir, what);
  if (fixture_copy(good, path, -1)) return H5I_INVALID_HID;
  return H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
}

// Rewrites element `index` of dataset `name` (read and written as doubles, or
// as int64 when is_int) through the HDF5 API, adding `delta` or setting `value`.
static int edit(hid_t file, const char *name, int is_int, size_t index, int add, double value) {
  hid_t dset = H5Dopen2(file, name, H5P_DEFAULT);
  if (dset < 0) return 1;
  hid_t space = H5Dget_space(dset);
  const hssize_t count = H5Sget_simple_extent_npoints(space);
  H5Sclose(space);
  int failed = count <= (hssize_t)index;
  if (!failed && is_int) {
    int64_t *v = calloc((size_t)count, sizeof *v);
    failed = !v || H5Dread(dset, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0;
    // wrapping, as the stored bits of a u64 digest read as int64 may be the largest int64
    if (!failed) v[index] = add ? (int64_t)((uint64_t)v[index] + (uint64_t)(int64_t)value) : (int64_t)value;
    failed = failed || H5Dwrite(dset, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0;
    free(v);
  } else if (!failed) {
    double *v = calloc((size_t)count, sizeof *v);
    failed = !v || H5Dread(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0;
    if (!failed) v[index] = add ? v[index] + value : value;
    failed = failed || H5Dwrite(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0;
    free(v);
  }
  H5Dclose(dset);
  return failed;
}

// Flips one bit of the stored bytes of dataset `name` (contiguous), under
// HDF5: the file is patched with stdio at the dataset's offset.
static int flip_bit(const char *path, const char *name, long byte) {
  hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return 1;
  hid_t dset = H5Dopen2(file, name, H5P_DEFAULT);
  const haddr_t offset = dset >= 0 ? H5Dget_offset(dset) : HADDR_UNDEF;
  if (dset >= 0) H5Dclose(dset);
  H5Fclose(file);
  if (offset == HADDR_UNDEF) return 1;
  FILE *f = fopen(path, "r+b");
  if (!f) return 1;
  int failed = fseek(f, (long)offset + byte, SEEK_SET) != 0;
  const int c = failed ? EOF : fgetc(f);
  failed = failed || c == EOF || fseek(f, (long)offset + byte, SEEK_SET) != 0 || fputc(c ^ 0x10, f) == EOF;
  return fclose(f) != 0 || failed;
}

// Flips bit `bit` of the f64 attribute `attr` of /settings, in place in
// the file's bytes (found by the value's bit pattern: the test's settings are
// distinct enough that each pattern occurs once).
static int flip_setting_bit(const char *path, const char *attr, int bit) {
  hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return 1;
  double value = 0;
  hid_t a = H5Aopen_by_name(file, "/settings", attr, H5P_DEFAULT, H5P_DEFAULT);
  const int failed = a < 0 || H5Aread(a, H5T_NATIVE_DOUBLE, &value) < 0;
  if (a >= 0) H5Aclose(a);
  H5Fclose(file);
  if (failed) return 1;
  unsigned char pattern[8];
  memcpy(pattern, &value, 8); // little-endian host, as the file
  FILE *f = fopen(path, "r+b");
  if (!f) return 1;
  static unsigned char bytes[1 << 20];
  const size_t n = fread(bytes, 1, sizeof bytes, f);
  long at = -1;
  int found = 0;
  for (size_t k = 0; k + 8 <= n; ++k)
    if (!memcmp(bytes + k, pattern, 8)) at = (long)k, ++found;
  int bad = found != 1 || fseek(f, at + bit / 8, SEEK_SET) != 0 || fputc(bytes[at + bit / 8] ^ (1 << bit % 8), f) == EOF;
  return fclose(f) != 0 || bad;
}

// Rewrites the scalar f64 attribute `attr` of /settings through the HDF5 API.
static int set_setting(const char *path, const char *attr, double value) {
  hid_t file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) return 1;
  hid_t group = H5Gopen2(file, "/settings", H5P_DEFAULT);
  hid_t a = group >= 0 ? H5Aopen(group, attr, H5P_DEFAULT) : H5I_INVALID_HID;
  const int failed = a < 0 || H5Awrite(a, H5T_NATIVE_DOUBLE, &value) < 0;
  if (a >= 0) H5Aclose(a);
  if (group >= 0) H5Gclose(group);
  return H5Fclose(file) < 0 || failed;
}

// The three readers all refuse path with FORMAT naming /run/checksum.
static void expect_header_refused(fascia_ctx *ctx, fascia_solver *solver, const fascia_model *m, const char *path) {
  expect_refused(ctx, solver, path, FASCIA_ERR_FORMAT, "/run/checksum", "do not match");
  fascia_solver_def def = fascia_solver_def_default();
  int64_t step = -1;
  uint64_t inputs = 7;
  fascia_ctx_clear(ctx);
  const fascia_status a = fascia_checkpoint_read_settings(ctx, path, m, &def, &step);
  const int named_a = strstr(fascia_ctx_message(ctx), "/run/checksum") != NULL;
  fascia_ctx_clear(ctx);
  const fascia_status b = fascia_checkpoint_read_inputs(ctx, path, NULL, &inputs);
  const int named_b = strstr(fascia_ctx_message(ctx), "/run/checksum") != NULL;
  if (a != FASCIA_ERR_FORMAT || b != FASCIA_ERR_FORMAT || !named_a || !named_b || step != -1 || inputs != 7) {
    fprintf(stderr, "t207: '%s': read_settings gave %s, read_inputs %s (wanted FORMAT naming /run/checksum)\n", path,
            fascia_status_name(a), fascia_status_name(b));
    ++check_failures_;
  }
}

static int set_version(hid_t file, int32_t version) {
  hid_t attr = H5Aopen_by_name(file, "/", "fascia_checkpoint_version", H5P_DEFAULT, H5P_DEFAULT);
  if (attr < 0) return 1;
  const int failed = H5Awrite(attr, H5T_NATIVE_INT32, &version) < 0;
  H5Aclose(attr);
  return failed;
}

static fascia_model *beam(fascia_ctx *ctx, double youngs_modulus) {
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 5, def.frames[1] = 2, def.frames[2] = 2, def.length = 4;
  def.youngs_modulus = youngs_modulus;
  fascia_model *m = NULL;
  if (fascia_scene_beam_build(ctx, &def, &m) != FASCIA_OK) {
    fprintf(stderr, "t207: beam: %s\n", fascia_ctx_message(ctx));
    exit(1);
  }
  return m;
}

// Every recorded setting changed in turn: a solver with it is refused, and
// the message names the setting.
static void other_settings(fascia_ctx *ctx, const fascia_model *m, const fascia_solver_def *sd) {
  const int count = fascia_checkpoint_setting_count();
  CHECK(count >= 15);
  for (int k = 0; k < count; ++k) {
    const char *name = fascia_checkpoint_setting_name(k);
    fascia_solver_def other = *sd;
    const double value = fascia_checkpoint_setting_get(sd, k);
    // another valid value: flags and enumerations flip between 0 and 1 (or 2),
    // counts and reals double
    double changed = value == 0 ? 1 : value == 1 ? 0 : 2 * value;
    if (!strcmp(name, "cg_tolerance") || !strcmp(name, "newton_tolerance")) changed = value / 2;
    if (!strcmp(name, "precond") || !strcmp(name, "linear_solver")) changed = value == 1 ? 2 : 1;
    if (!strcmp(name, "assembled") || !strcmp(name, "single_precision_matrix"))
      changed = value == 1 ? 0 : 1; // -1 (auto), 0 or 1
    fascia_checkpoint_setting_set(&other, k, changed);
    fascia_solver *solver = NULL;
    if (fascia_solver_create(ctx, m, &other, &solver) != FASCIA_OK) {
      fprintf(stderr, "t207: setting %s = %g: %s\n", name, changed, fascia_ctx_message(ctx));
      ++check_failures_;
      continue;
    }
    expect_refused(ctx, solver, good, FASCIA_ERR_ARGUMENT, "/settings", name);
    fascia_solver_destroy(&solver);
  }
}

// The state a checkpoint restores, bytes: x, q, u, time.
static size_t state_bytes(const fascia_solver *s, int32_t N, unsigned char *out) {
  size_t n = 0;
  memcpy(out + n, fascia_solver_frame_positions(s), 3 * (size_t)N * sizeof(fascia_real)), n += 3 * (size_t)N * sizeof(fascia_real);
  memcpy(out + n, fascia_solver_frame_rotations(s), 4 * (size_t)N * sizeof(fascia_real)), n += 4 * (size_t)N * sizeof(fascia_real);
  memcpy(out + n, fascia_solver_frame_velocities(s), 6 * (size_t)N * sizeof(fascia_real)), n += 6 * (size_t)N * sizeof(fascia_real);
  const fascia_real t = fascia_solver_time(s);
  memcpy(out + n, &t, sizeof t), n += sizeof t;
  return n;
}

static int mutations(fascia_ctx *ctx, const fascia_model *m, const fascia_solver_def *sd, int count, int *refused,
                     int *same) {
  static unsigned char bytes[1 << 20], copy[1 << 20], want[1 << 16], got[1 << 16];
  FILE *f = fopen(good, "rb");
  const size_t size = f ? fread(bytes, 1, sizeof bytes, f) : 0;
  if (f) fclose(f);
  CHECK(size > 0 && size < sizeof bytes && 14 * (size_t)m->frame_count * sizeof(fascia_real) < sizeof want);
  fascia_solver *ref = NULL;
  int64_t step = 0;
  CHECK_OK(fascia_solver_create(ctx, m, sd, &ref), ctx);
  CHECK_OK(fascia_checkpoint_load(ctx, ref, good, &step), ctx);
  const size_t n = state_bytes(ref, m->frame_count, want);
  fascia_solver_destroy(&ref);
  char path[512];
  snprintf(path, sizeof path, "%s/mutated.ck.h5", dir);
  unsigned long long state = 0x2545f4914f6cdd1dULL;
  for (int k = 0; k < count && size > 0; ++k) {
    memcpy(copy, bytes, size);
    state ^= state << 13, state ^= state >> 7, state ^= state << 17;
    const int flips = 1 + (int)(state % 3);
    for (int j = 0; j < flips; ++j) {
      state ^= state << 13, state ^= state >> 7, state ^= state << 17;
      const size_t at = (size_t)(state % size);
      const unsigned char to = (unsigned char)(state >> 40);
      copy[at] = to != copy[at] ? to : (unsigned char)(to ^ 0x01);
    }
    f = fopen(path, "wb");
    CHECK(f && fwrite(copy, 1, size, f) == size && fclose(f) == 0);
    fascia_solver_def def = fascia_solver_def_default();
    def.backend = sd->backend;
    int64_t at_step = -1;
    fascia_solver *s = NULL;
    fascia_ctx_clear(ctx);
    fascia_status st = fascia_checkpoint_read_settings(ctx, path, m, &def, &at_step);
    if (st == FASCIA_OK) st = fascia_solver_create(ctx, m, &def, &s);
    if (st == FASCIA_OK) st = fascia_checkpoint_load(ctx, s, path, &at_step);
    if (st != FASCIA_OK) {
      ++*refused;
      if (!fascia_ctx_message(ctx)[0]) {
        fprintf(stderr, "t207: mutation %d refused without a message\n", k);
        ++check_failures_;
      }
    } else {
      int differs = at_step != step || state_bytes(s, m->frame_count, got) != n || memcmp(want, got, n) != 0;
      for (int j = 0; j < fascia_checkpoint_setting_count(); ++j)
        differs |= fascia_checkpoint_setting_get(&def, j) != fascia_checkpoint_setting_get(sd, j);
      if (differs) {
        fprintf(stderr, "t207: mutation %d (%d bytes) resumed a different state or settings\n", k, flips);
        ++check_failures_;
      } else {
        ++*same;
      }
    }
    fascia_solver_destroy(&s);
    CHECK(open_ids() == 0);
  }
  return 0;
}

int main(int argc, char **argv) {
  // --no-mutations: the cases whose files HDF5 reads safely (the sanitized run)
  const int random_mutations = !(argc > 1 && !strcmp(argv[1], "--no-mutations"));
  fascia_ctx_def cdef = fascia_ctx_def_default();
  cdef.threads = 1;
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cdef, &ctx) != FASCIA_OK) return 1;
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL); // the corrupting helpers report by return value
  CHECK(mkdtemp(dir) != NULL);
  snprintf(good, sizeof good, "%s/good.ck.h5", dir);

  fascia_model *m = beam(ctx, 40000), *other_model = beam(ctx, 50000);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.time_step = 0.01;
  sd.backend = "cpu";
  fascia_solver *solver = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &solver), ctx);
  for (int n = 0; n < 3; ++n) CHECK_OK(fascia_solver_step(solver, NULL), ctx);
  CHECK_OK(fascia_checkpoint_save(ctx, solver, 3, good), ctx);
  fascia_solver_destroy(&solver);

  // a fresh solver (at t = 0) takes the good checkpoint
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &solver), ctx);
  int64_t step = 0;
  CHECK_OK(fascia_checkpoint_load(ctx, solver, good, &step), ctx);
  CHECK(step == 3 && fascia_solver_time(solver) == 0.01 + 0.01 + 0.01);
  CHECK(open_ids() == 0);
  fascia_solver_destroy(&solver);
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &solver), ctx);

  char path[512];
  hid_t file;
  int header_cases = 0;
  CHECK((file = corrupt_copy("bit-flip", path, sizeof path)) >= 0 && H5Fclose(file) >= 0);
  CHECK(flip_bit(path, "/state/position", 21) == 0);
  expect_refused(ctx, solver, path, FASCIA_ERR_FORMAT, "/state/checksum", "does not match");

  CHECK((file = corrupt_copy("moved-1m", path, sizeof path)) >= 0);
  CHECK(edit(file, "/state/position", 0, 4, 1, 1.0) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, solver, path, FASCIA_ERR_FORMAT, "/state/checksum", "does not match");

  CHECK((file = corrupt_copy("velocity", path, sizeof path)) >= 0);
  CHECK(edit(file, "/state/velocity", 0, 0, 1, 1e-12) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, solver, path, FASCIA_ERR_FORMAT, "/state/checksum", NULL);

  // the direct solver's kept factorization travels with the state, under the same checksum
  CHECK((file = corrupt_copy("linear", path, sizeof path)) >= 0);
  CHECK(edit(file, "/state/linear", 0, 5, 1, 1e-9) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, solver, path, FASCIA_ERR_FORMAT, "/state/checksum", "does not match");

  CHECK((file = corrupt_copy("step-1e15", path, sizeof path)) >= 0);
  CHECK(edit(file, "/run/step", 1, 0, 0, 1e15) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, solver, path, FASCIA_ERR_FORMAT, "/run/checksum", "do not match");

  CHECK((file = corrupt_copy("time-negative", path, sizeof path)) >= 0);
  CHECK(edit(file, "/run/time", 0, 0, 0, -5) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, solver, path, FASCIA_ERR_FORMAT, "/run/checksum", "do not match");

  CHECK((file = corrupt_copy("step-and-time", path, sizeof path)) >= 0);
  CHECK(edit(file, "/run/step", 1, 0, 1, 1) == 0 && H5Fclose(file) >= 0); // 4 steps, the time of 3
  expect_refused(ctx, solver, path, FASCIA_ERR_FORMAT, "/run/checksum", "do not match");

  CHECK((file = corrupt_copy("no-checksum", path, sizeof path)) >= 0);
  CHECK(H5Ldelete(file, "/state/checksum", H5P_DEFAULT) >= 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, solver, path, FASCIA_ERR_FORMAT, "/state/checksum", "missing");

  CHECK((file = corrupt_copy("no-settings", path, sizeof path)) >= 0);
  CHECK(H5Ldelete(file, "/settings", H5P_DEFAULT) >= 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, solver, path, FASCIA_ERR_FORMAT, "/settings", "missing");

  // the records a resume trusts besides the state: every setting, bit by bit
  // in the file's bytes (sign, exponent and mantissa bits) and rewritten
  // through HDF5; each record of /run and /model rewritten
  for (int k = 0; k < fascia_checkpoint_setting_count(); ++k) {
    const char *name = fascia_checkpoint_setting_name(k);
    for (int b = 0; b < 3; ++b) {
      const int bit = (int[]){63, 60, 20}[b];
      char what[64];
      snprintf(what, sizeof what, "flip-%s-%d", name, bit);
      CHECK((file = corrupt_copy(what, path, sizeof path)) >= 0 && H5Fclose(file) >= 0);
      if (flip_setting_bit(path, name, bit) == 0) {
        expect_header_refused(ctx, solver, m, path);
        ++header_cases;
      }
    }
    snprintf(path, sizeof path, "%s/set-%s.ck.h5", dir, name);
    CHECK(fixture_copy(good, path, -1) == 0);
    CHECK(set_setting(path, name, fascia_checkpoint_setting_get(&sd, k) + 1) == 0);
    expect_header_refused(ctx, solver, m, path);
    ++header_cases;
  }
  CHECK(header_cases >= 30); // most settings' bit patterns are unique in the file
  CHECK((file = corrupt_copy("time-step", path, sizeof path)) >= 0);
  CHECK(edit(file, "/run/time_step", 0, 0, 0, 0.02) == 0 && set_setting(path, "time_step", 0.02) == 0 &&
        H5Fclose(file) >= 0); // time step and setting together, consistent
  expect_header_refused(ctx, solver, m, path);
  CHECK((file = corrupt_copy("inputs", path, sizeof path)) >= 0);
  CHECK(edit(file, "/run/inputs", 1, 0, 0, 12345) == 0 && H5Fclose(file) >= 0);
  expect_header_refused(ctx, solver, m, path);
  CHECK((file = corrupt_copy("sizes", path, sizeof path)) >= 0);
  CHECK(edit(file, "/model/sizes", 1, 8, 1, 1) == 0 && H5Fclose(file) >= 0);
  expect_header_refused(ctx, solver, m, path);
  CHECK((file = corrupt_copy("run-checksum", path, sizeof path)) >= 0);
  CHECK(edit(file, "/run/checksum", 1, 0, 1, 1) == 0 && H5Fclose(file) >= 0);
  expect_header_refused(ctx, solver, m, path);

  // the caller's input digest comes back as saved, 0 from fascia_checkpoint_save
  {
    uint64_t inputs = 99;
    CHECK_OK(fascia_checkpoint_read_inputs(ctx, good, m, &inputs), ctx);
    CHECK(inputs == 0);
    snprintf(path, sizeof path, "%s/inputs.ck.h5", dir);
    fascia_solver *s2 = NULL;
    CHECK_OK(fascia_solver_create(ctx, m, &sd, &s2), ctx);
    const uint64_t digest = UINT64_C(0xfedcba9876543210);
    CHECK_OK(fascia_checkpoint_save_inputs(ctx, s2, 0, digest, path), ctx);
    CHECK_OK(fascia_checkpoint_read_inputs(ctx, path, m, &inputs), ctx);
    CHECK(inputs == digest);
    CHECK(fascia_checkpoint_read_inputs(ctx, path, other_model, &inputs) == FASCIA_ERR_ARGUMENT);
    CHECK_OK(fascia_checkpoint_load(ctx, s2, path, &step), ctx);
    CHECK(step == 0);
    fascia_solver_destroy(&s2);
    CHECK(open_ids() == 0);
  }

  CHECK((file = corrupt_copy("version-2", path, sizeof path)) >= 0);
  CHECK(set_version(file, 2) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, solver, path, FASCIA_ERR_FORMAT, "version 2", "older fascia");

  CHECK((file = corrupt_copy("version-1", path, sizeof path)) >= 0);
  CHECK(set_version(file, 1) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, solver, path, FASCIA_ERR_FORMAT, "version 1", "older fascia");

  // not a regular file: refused at once by load, read_settings and read_inputs
  snprintf(path, sizeof path, "%s/fifo.ck.h5", dir);
  CHECK(mkfifo(path, 0600) == 0);
  alarm(20); // a blocking open kills the test instead of hanging it
  expect_refused(ctx, solver, path, FASCIA_ERR_IO, "is a FIFO", "not a regular file");
  {
    fascia_solver_def def = sd;
    uint64_t inputs = 0;
    fascia_ctx_clear(ctx);
    CHECK(fascia_checkpoint_read_settings(ctx, path, m, &def, &step) == FASCIA_ERR_IO &&
          strstr(fascia_ctx_message(ctx), "FIFO"));
    CHECK(fascia_checkpoint_read_inputs(ctx, path, NULL, &inputs) == FASCIA_ERR_IO);
  }
  expect_refused(ctx, solver, dir, FASCIA_ERR_IO, "is a folder", NULL);
  alarm(0);
  remove(path);

  snprintf(path, sizeof path, "%s/truncated.ck.h5", dir);
  CHECK(fixture_copy(good, path, 1000) == 0);
  fascia_ctx_clear(ctx);
  CHECK(fascia_checkpoint_load(ctx, solver, path, &step) != FASCIA_OK && open_ids() == 0);

  // another model (same sizes, stiffer), another solver setting
  fascia_solver *other = NULL;
  CHECK_OK(fascia_solver_create(ctx, other_model, &sd, &other), ctx);
  expect_refused(ctx, other, good, FASCIA_ERR_ARGUMENT, "/model/fingerprint", "another model");
  fascia_solver_destroy(&other);
  other_settings(ctx, m, &sd);

  // the settings read back are those of the run; others stay as they are
  fascia_solver_def read = fascia_solver_def_default();
  read.time_step = 0.5, read.mass_damping = 3, read.cg_iterations = 7, read.threads = 5, read.load_steps = 9;
  step = 0;
  CHECK_OK(fascia_checkpoint_read_settings(ctx, good, m, &read, &step), ctx);
  CHECK(step == 3 && read.threads == 5 && read.load_steps == 9);
  for (int k = 0; k < fascia_checkpoint_setting_count(); ++k)
    CHECK(fascia_checkpoint_setting_get(&read, k) == fascia_checkpoint_setting_get(&sd, k));
  fascia_ctx_clear(ctx);
  CHECK(fascia_checkpoint_read_settings(ctx, good, other_model, &read, &step) == FASCIA_ERR_ARGUMENT);
  CHECK(open_ids() == 0);

  int refused = 0, same = 0;
  if (random_mutations) {
    CHECK(mutations(ctx, m, &sd, 300, &refused, &same) == 0);
    CHECK(refused >= 50 && refused + same == 300);
  }
  if (getenv("FASCIA_TEST_VERBOSE"))
    fprintf(stderr, "t207: %d header cases; mutations: %d refused, %d resumed the same\n", header_cases, refused, same);

  fascia_solver_destroy(&solver);
  fascia_model_destroy(&m);
  fascia_model_destroy(&other_model);
  if (!check_failures_) fixture_remove_dir(dir);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
