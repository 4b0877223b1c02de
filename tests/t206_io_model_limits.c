// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A model file that declares absurd sizes is refused up front, before the
// loader allocates for them: a dataset declaring 2^28 rows (within the
// per-array count limit, 6 GiB of values) that the file does not store is
// refused at once with a message naming the file and the dataset.
#define _POSIX_C_SOURCE 200809L
#include <hdf5.h>
#include <time.h>

#include "check.h"
#include "io_fixture.h"

// Replaces dataset `name` ([rows, cols] f64) by a chunked one of `rows` rows
// that is never written (a few kilobytes on disk whatever rows is).
static int declare_unwritten(const char *path, const char *name, hsize_t rows, hsize_t cols) {
  hid_t file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) return 0;
  H5Ldelete(file, name, H5P_DEFAULT);
  const hsize_t dims[2] = {rows, cols}, chunk[2] = {1024, cols};
  hid_t space = H5Screate_simple(2, dims, NULL), dcpl = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(dcpl, 2, chunk);
  hid_t dset = H5Dcreate2(file, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  const int ok = dset >= 0;
  if (ok) H5Dclose(dset);
  H5Pclose(dcpl);
  H5Sclose(space);
  H5Fclose(file);
  return ok;
}

int main(void) {
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  CHECK_OK(fascia_ctx_create(&def, &ctx), ctx);
  fascia_model *model = NULL;
  CHECK_OK(fixture_model(ctx, 0, &model), ctx);
  char path[64];
  snprintf(path, sizeof path, "t206-%ld.h5", (long)getpid());
  CHECK_OK(fascia_model_save(ctx, model, path), ctx);
  fascia_model_destroy(&model);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);

  // 2^28 x 3 values: under FASCIA_MAX_COUNT (2^30) values per array, but 6 GiB
  CHECK(declare_unwritten(path, "/samples/position", (hsize_t)1 << 28, 3));
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  const fascia_status st = fascia_model_load(ctx, path, &model);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  const double seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
  const char *message = fascia_ctx_message(ctx);
  CHECK(st == FASCIA_ERR_FORMAT);
  CHECK(model == NULL);
  CHECK(strstr(message, path) != NULL && strstr(message, "/samples/position") != NULL);
  CHECK(strstr(message, "declares 805306368 values") != NULL && strstr(message, "stores none") != NULL);
  CHECK(seconds < 2); // nothing of 6 GiB was allocated or read
  if (CHECK_RESULT()) fprintf(stderr, "status %s after %.3f s: %s\n", fascia_status_name(st), seconds, message);
  fascia_model_destroy(&model);
  remove(path);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
