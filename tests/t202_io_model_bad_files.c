// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Every kind of bad model file is refused with FASCIA_ERR_FORMAT or _IO and a
// message naming the file and the dataset, without crashing or leaking; a
// failed save leaves neither a file nor a temporary behind and does not
// clobber an existing good file. The file's checksum: values edited through
// HDF5 that pass every other check, and a file without a checksum, are
// refused; of random byte mutations of a saved model every one is either
// refused or loads bit-identical. A FIFO, a folder or a device given as the
// model is refused at once (an alarm fails the test if the open blocks).
#define _POSIX_C_SOURCE 200809L
#include <hdf5.h>
#include <signal.h>
#include <sys/stat.h>

#include "check.h"
#include "io_fixture.h"

static char dir[] = "t202-XXXXXX";
static char good[256];

// Loads path and expects `want` (or, with want_alt != FASCIA_OK, either)
// with a message containing the file name and each of `parts` (NULL-ended).
static void expect_refused(fascia_ctx *ctx, const char *path, fascia_status want, fascia_status want_alt,
                           const char *part1, const char *part2) {
  fascia_model *m = NULL;
  fascia_ctx_clear(ctx);
  const fascia_status st = fascia_model_load(ctx, path, &m);
  const char *message = fascia_ctx_message(ctx);
  if (!(st == want || (want_alt != FASCIA_OK && st == want_alt)) || m != NULL || !strstr(message, path) ||
      (part1 && !strstr(message, part1)) || (part2 && !strstr(message, part2))) {
    fprintf(stderr, "t202: '%s' gave %s (wanted %s) with message \"%s\" (wanted '%s', '%s')\n", path,
            fascia_status_name(st), fascia_status_name(want), message, part1 ? part1 : "", part2 ? part2 : "");
    ++check_failures_;
  }
  fascia_model_destroy(&m);
}

// A copy of the good file, named after the corruption, opened read-write.
static hid_t corrupt_copy(const char *what, char *path, size_t size) {
  snprintf(path, size, "%s/%s.h5", dir, what);
  if (fixture_copy(good, path, -1)) return H5I_INVALID_HID;
  return H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
}

// Replaces dataset `name` with a new one of the given type and shape (contents zero).
static int replace_dataset(hid_t file, const char *name, hid_t type, int rank, const hsize_t *dims) {
  if (H5Ldelete(file, name, H5P_DEFAULT) < 0) return 1;
  hid_t space = H5Screate_simple(rank, dims, NULL);
  hid_t dset = H5Dcreate2(file, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  H5Sclose(space);
  if (dset < 0) return 1;
  return H5Dclose(dset) < 0;
}

// Overwrites element `index` of a double (is_int == 0) or int32 dataset.
static int poke(hid_t file, const char *name, int is_int, hsize_t index, double value) {
  hid_t dset = H5Dopen2(file, name, H5P_DEFAULT);
  if (dset < 0) return 1;
  hid_t space = H5Dget_space(dset);
  const hsize_t one = 1;
  hid_t memory = H5Screate_simple(1, &one, NULL);
  hsize_t start[2] = {index, 0};
  if (H5Sget_simple_extent_ndims(space) == 2) {
    hsize_t dims[2];
    H5Sget_simple_extent_dims(space, dims, NULL);
    start[0] = index / dims[1];
    start[1] = index % dims[1];
  }
  const hsize_t count[2] = {1, 1};
  const int32_t int_value = (int32_t)value;
  int failed = H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, count, NULL) < 0;
  if (!failed)
    failed = H5Dwrite(dset, is_int ? H5T_NATIVE_INT32 : H5T_NATIVE_DOUBLE, memory, space, H5P_DEFAULT,
                      is_int ? (const void *)&int_value : (const void *)&value) < 0;
  H5Sclose(memory);
  H5Sclose(space);
  H5Dclose(dset);
  return failed;
}

static int set_version(hid_t file, int32_t version) {
  hid_t attr = H5Aopen_by_name(file, "/", "fascia_model_version", H5P_DEFAULT, H5P_DEFAULT);
  if (attr < 0) return 1;
  const int failed = H5Awrite(attr, H5T_NATIVE_INT32, &version) < 0;
  H5Aclose(attr);
  return failed;
}

static void bad_files(fascia_ctx *ctx, const fascia_model *m) {
  char path[512];
  const hsize_t S = (hsize_t)m->sample_count, N = (hsize_t)m->frame_count;

  snprintf(path, sizeof path, "%s/missing.h5", dir);
  expect_refused(ctx, path, FASCIA_ERR_IO, FASCIA_OK, "No such file", NULL);

  snprintf(path, sizeof path, "%s/text.h5", dir);
  FILE *text = fopen(path, "w");
  CHECK(text && fputs("frames: 5\nsamples: 3\n", text) >= 0 && fclose(text) == 0);
  expect_refused(ctx, path, FASCIA_ERR_IO, FASCIA_OK, "not an HDF5 file", NULL);

  FILE *in = fopen(good, "rb");
  CHECK(in && fseek(in, 0, SEEK_END) == 0);
  const long size = in ? ftell(in) : 0;
  if (in) fclose(in);
  snprintf(path, sizeof path, "%s/truncated.h5", dir);
  CHECK(fixture_copy(good, path, size / 2) == 0);
  expect_refused(ctx, path, FASCIA_ERR_IO, FASCIA_ERR_FORMAT, NULL, NULL);

  hid_t file;
  CHECK((file = corrupt_copy("no-volume", path, sizeof path)) >= 0);
  CHECK(H5Ldelete(file, "/samples/volume", H5P_DEFAULT) >= 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/samples/volume", "missing");

  CHECK((file = corrupt_copy("no-organs-group", path, sizeof path)) >= 0);
  CHECK(H5Ldelete(file, "/organs", H5P_DEFAULT) >= 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/organs", "missing");

  const hsize_t volume_2d[2] = {S, 3};
  CHECK((file = corrupt_copy("volume-2d", path, sizeof path)) >= 0);
  CHECK(replace_dataset(file, "/samples/volume", H5T_IEEE_F64LE, 2, volume_2d) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/samples/volume: expected 1-D array of 3 values",
                 "found 2-D 3x3");

  const hsize_t short_rotation[2] = {N, 3};
  CHECK((file = corrupt_copy("rotation-3-columns", path, sizeof path)) >= 0);
  CHECK(replace_dataset(file, "/frames/rotation", H5T_IEEE_F64LE, 2, short_rotation) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/frames/rotation", "found 2-D 5x3");

  hid_t string_type = H5Tcopy(H5T_C_S1);
  H5Tset_size(string_type, 8);
  CHECK((file = corrupt_copy("kind-strings", path, sizeof path)) >= 0);
  CHECK(replace_dataset(file, "/frames/kind", string_type, 1, &N) == 0 && H5Fclose(file) >= 0);
  H5Tclose(string_type);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/frames/kind", "expected integers, found strings");

  CHECK((file = corrupt_copy("weights-integers", path, sizeof path)) >= 0);
  const hsize_t P = (hsize_t)m->pair_count;
  CHECK(replace_dataset(file, "/pairs/weight", H5T_STD_I32LE, 1, &P) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/pairs/weight", "expected floating-point numbers");

  // declared, never written: a huge contiguous dataset costs no disk space
  const hsize_t huge[2] = {(hsize_t)1 << 33, 3};
  CHECK((file = corrupt_copy("huge", path, sizeof path)) >= 0);
  CHECK(replace_dataset(file, "/samples/position", H5T_IEEE_F64LE, 2, huge) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/samples/position", "limit");

  CHECK((file = corrupt_copy("frame-out-of-range", path, sizeof path)) >= 0);
  CHECK(poke(file, "/pairs/frame", 1, 1, 99) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/pairs/frame", "frame 99");

  CHECK((file = corrupt_copy("nan-position", path, sizeof path)) >= 0);
  CHECK(poke(file, "/frames/position", 0, 4, NAN) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/frames/position", "frame 1");

  CHECK((file = corrupt_copy("offsets-decrease", path, sizeof path)) >= 0);
  CHECK(poke(file, "/samples/offsets", 1, 2, 1) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/samples/offsets", "decrease");

  CHECK((file = corrupt_copy("weights-sum", path, sizeof path)) >= 0);
  CHECK(poke(file, "/pairs/weight", 0, 0, 0.8) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/pairs/weight", "sample 0");

  CHECK((file = corrupt_copy("negative-volume", path, sizeof path)) >= 0);
  CHECK(poke(file, "/samples/volume", 0, 2, -1e-5) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/samples/volume", "sample 2");

  CHECK((file = corrupt_copy("version-99", path, sizeof path)) >= 0);
  CHECK(set_version(file, 99) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "version 99", "reads versions 1 to 4");

  CHECK((file = corrupt_copy("no-version", path, sizeof path)) >= 0);
  CHECK(H5Adelete(file, "fascia_model_version") >= 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "fascia_model_version", NULL);

  CHECK((file = corrupt_copy("organ-no-kind", path, sizeof path)) >= 0);
  CHECK(H5Adelete_by_name(file, "/organs/liver", "kind", H5P_DEFAULT) >= 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/organs/liver", "'kind' missing");

  CHECK((file = corrupt_copy("motion-no-keys", path, sizeof path)) >= 0);
  const hsize_t none = 0;
  CHECK(replace_dataset(file, "/motions/breathing/time", H5T_IEEE_F64LE, 1, &none) == 0 && H5Fclose(file) >= 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "/motions/breathing/time", "no keyframe");
}

// Writers other than fascia (h5py writes variable-length strings by default)
// are accepted: variable-length names and an ASCII variable-length provenance.
static int other_writers(fascia_ctx *ctx, fascia_model *m) {
  char path[512], base[512];
  hid_t file;
  // the same model with an ASCII provenance, its strings then rewritten in
  // another storage: the values, and so the checksum, stay the same
  snprintf(base, sizeof base, "%s/ascii-provenance.h5", dir);
  fascia_model *ascii = NULL;
  CHECK_OK(fascia_model_load(ctx, good, &ascii), ctx);
  CHECK_OK(fascia_model_set_provenance(ctx, ascii, "{\"tool\": \"h5py\"}"), ctx);
  CHECK_OK(fascia_model_save(ctx, ascii, base), ctx);
  fascia_model_destroy(&ascii);
  snprintf(path, sizeof path, "%s/variable-strings.h5", dir);
  CHECK(fixture_copy(base, path, -1) == 0);
  CHECK((file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT)) >= 0);
  hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  const hsize_t M = 2;
  const char *names[2] = {"fat", "fascia"}, *provenance = "{\"tool\": \"h5py\"}";
  CHECK(replace_dataset(file, "/materials/name", type, 1, &M) == 0);
  hid_t dset = H5Dopen2(file, "/materials/name", H5P_DEFAULT);
  CHECK(dset >= 0 && H5Dwrite(dset, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, names) >= 0 && H5Dclose(dset) >= 0);
  CHECK(H5Ldelete(file, "/provenance", H5P_DEFAULT) >= 0);
  hid_t space = H5Screate(H5S_SCALAR);
  dset = H5Dcreate2(file, "/provenance", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  CHECK(dset >= 0 && H5Dwrite(dset, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, &provenance) >= 0 && H5Dclose(dset) >= 0);
  H5Sclose(space);
  H5Tclose(type);
  CHECK(H5Fclose(file) >= 0);
  fascia_model *loaded = NULL;
  CHECK_OK(fascia_model_load(ctx, path, &loaded), ctx);
  CHECK(!strcmp(loaded->materials[0].name, "fat") && !strcmp(loaded->materials[1].name, "fascia"));
  CHECK(!strcmp(loaded->provenance, provenance));
  CHECK(loaded->sample_count == m->sample_count);
  fascia_model_destroy(&loaded);
  return 0;
}

static int delete_attribute(const char *path, const char *name) {
  hid_t file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) return 1;
  const int failed = H5Adelete_by_name(file, "/", name, H5P_DEFAULT) < 0;
  return H5Fclose(file) < 0 || failed;
}

// Values that every other check accepts, edited through HDF5 (which keeps
// the file well formed), are refused by the checksum; so is a file without one.
static void checksum_cases(fascia_ctx *ctx, int *cases) {
  static const struct {
    const char *dataset;
    int is_int;
    hsize_t index;
    double value;
  } edits[] = {
      {"/materials/youngs_modulus", 0, 0, 1000},  {"/materials/density", 0, 1, 1234},
      {"/materials/poisson_ratio", 0, 0, 0.3},    {"/gravity", 0, 2, -1.62},
      {"/frames/load", 0, 3, 0.5},                {"/frames/position", 0, 3, 0.0005},
      {"/samples/volume", 0, 1, 2e-5},            {"/motions/breathing/pivot", 0, 1, 0.25},
      {"/motions/breathing/translation", 0, 4, 0.002}, {"/probes/position", 0, 0, 0.01},
      {"/organs/liver/vertices", 0, 1, 0.0123},
  };
  char path[512], what[64];
  hid_t file;
  for (size_t k = 0; k < sizeof edits / sizeof edits[0]; ++k) {
    snprintf(what, sizeof what, "edit-%zu", k);
    CHECK((file = corrupt_copy(what, path, sizeof path)) >= 0);
    CHECK(poke(file, edits[k].dataset, edits[k].is_int, edits[k].index, edits[k].value) == 0 && H5Fclose(file) >= 0);
    expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "checksum mismatch", "re-run fascia prep");
    ++*cases;
  }
  CHECK((file = corrupt_copy("no-checksum", path, sizeof path)) >= 0 && H5Fclose(file) >= 0);
  CHECK(delete_attribute(path, "fascia_model_checksum") == 0);
  expect_refused(ctx, path, FASCIA_ERR_FORMAT, FASCIA_OK, "no checksum", "re-run 'fascia prep'");
  ++*cases;
}

// Random byte mutations (1 to 3 bytes each) of the saved model: each one is
// refused with a message naming the file, or loads to the very same model.
static void mutations(fascia_ctx *ctx, const fascia_model *m, int count, int *refused, int *same) {
  FILE *f = fopen(good, "rb");
  static unsigned char bytes[1 << 20], copy[1 << 20];
  const size_t size = f ? fread(bytes, 1, sizeof bytes, f) : 0;
  if (f) fclose(f);
  CHECK(size > 0 && size < sizeof bytes);
  unsigned long long state = 0x9e3779b97f4a7c15ULL;
  char path[512];
  snprintf(path, sizeof path, "%s/mutated.h5", dir);
  for (int k = 0; k < count && size > 0; ++k) {
    memcpy(copy, bytes, size);
    state ^= state << 13, state ^= state >> 7, state ^= state << 17;
    const int n = 1 + (int)(state % 3);
    for (int j = 0; j < n; ++j) {
      state ^= state << 13, state ^= state >> 7, state ^= state << 17;
      const size_t at = (size_t)(state % size);
      const unsigned char to = (unsigned char)(state >> 40);
      copy[at] = to != copy[at] ? to : (unsigned char)(to ^ 0x01);
    }
    FILE *out = fopen(path, "wb");
    CHECK(out && fwrite(copy, 1, size, out) == size && fclose(out) == 0);
    fascia_model *loaded = NULL;
    fascia_ctx_clear(ctx);
    const fascia_status st = fascia_model_load(ctx, path, &loaded);
    if (st != FASCIA_OK) {
      ++*refused;
      if (loaded || !strstr(fascia_ctx_message(ctx), path)) {
        fprintf(stderr, "t202: mutation %d refused without the file named: \"%s\"\n", k, fascia_ctx_message(ctx));
        ++check_failures_;
      }
    } else {
      const char *differs = fixture_models_differ(m, loaded);
      if (differs) {
        fprintf(stderr, "t202: mutation %d (%d bytes) loaded with a different %s\n", k, n, differs);
        ++check_failures_;
      } else {
        ++*same;
      }
    }
    fascia_model_destroy(&loaded);
  }
}

// Not regular files: refused at once, naming what the path is.
static void not_regular_files(fascia_ctx *ctx, int *cases) {
  char path[512];
  snprintf(path, sizeof path, "%s/fifo.h5", dir);
  CHECK(mkfifo(path, 0600) == 0);
  alarm(20); // a blocking open kills the test instead of hanging it
  expect_refused(ctx, path, FASCIA_ERR_IO, FASCIA_OK, "is a FIFO", "not a regular file");
  expect_refused(ctx, dir, FASCIA_ERR_IO, FASCIA_OK, "is a folder", "not a regular file");
  expect_refused(ctx, "/dev/null", FASCIA_ERR_IO, FASCIA_OK, "character device", "not a regular file");
  alarm(0);
  remove(path);
  *cases += 3;
}

// A failed save leaves nothing behind and keeps an existing file intact.
static void failed_saves(fascia_ctx *ctx, fascia_model *m) {
  char path[512];
  snprintf(path, sizeof path, "%s/no-such-folder/model.h5", dir);
  fascia_ctx_clear(ctx);
  CHECK(fascia_model_save(ctx, m, path) == FASCIA_ERR_IO);
  CHECK(strstr(fascia_ctx_message(ctx), path) != NULL);

  // an invalid model must not replace the good file
  snprintf(path, sizeof path, "%s/keep.h5", dir);
  CHECK(fixture_copy(good, path, -1) == 0);
  const double weight = m->pair_weight[0];
  m->pair_weight[0] = 0.5;
  fascia_ctx_clear(ctx);
  CHECK(fascia_model_save(ctx, m, path) == FASCIA_ERR_FORMAT);
  CHECK(strstr(fascia_ctx_message(ctx), "/pairs/weight") != NULL);
  m->pair_weight[0] = weight;
  CHECK(fixture_same_bytes(good, path));

  // names that cannot be HDF5 group names are refused before writing
  char name[FASCIA_NAME_SIZE];
  memcpy(name, m->organs[0].name, sizeof name);
  snprintf(m->organs[0].name, sizeof m->organs[0].name, "left/right");
  fascia_ctx_clear(ctx);
  CHECK(fascia_model_save(ctx, m, path) == FASCIA_ERR_ARGUMENT);
  CHECK(strstr(fascia_ctx_message(ctx), "left/right") != NULL);
  memcpy(m->organs[0].name, name, sizeof name);
  CHECK(fixture_same_bytes(good, path));

  CHECK(fixture_count_files(dir, ".tmp") == 0);
  CHECK(fixture_count_files(dir, "no-such-folder") == 0);
}

// Open HDF5 files and objects in them: a load or save that forgets to close
// one (on an error path, say) shows up as a difference.
static ssize_t open_ids(void) { return H5Fget_obj_count((hid_t)H5F_OBJ_ALL, H5F_OBJ_ALL); }

int main(int argc, char **argv) {
  // --no-mutations: the cases whose files HDF5 reads safely (the sanitized run)
  const int random_mutations = !(argc > 1 && !strcmp(argv[1], "--no-mutations"));
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&def, &ctx) != FASCIA_OK) return 1;
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL); // the corrupting helpers report by return value
  CHECK(mkdtemp(dir) != NULL);
  snprintf(good, sizeof good, "%s/good.h5", dir);
  fascia_model *m = NULL;
  CHECK_OK(fixture_model(ctx, 0, &m), ctx);
  CHECK_OK(fascia_model_save(ctx, m, good), ctx);
  const ssize_t ids = open_ids();
  bad_files(ctx, m);
  CHECK(other_writers(ctx, m) == 0);
  int cases = 0, refused = 0, same = 0;
  checksum_cases(ctx, &cases);
  not_regular_files(ctx, &cases);
  if (random_mutations) {
    mutations(ctx, m, 300, &refused, &same);
    CHECK(refused >= 50 && refused + same == 300);
  }
  if (getenv("FASCIA_TEST_VERBOSE"))
    fprintf(stderr, "t202: %d checksum and file-kind cases; mutations: %d refused, %d loaded the same\n", cases,
            refused, same);
  failed_saves(ctx, m);
  CHECK(open_ids() == ids);
  fascia_model_destroy(&m);
  if (!check_failures_) fixture_remove_dir(dir);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
