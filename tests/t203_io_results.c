// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The results writer stores every appended step exactly (read back with the
// HDF5 API), pads fields missing in a step with NaN, writes an XDMF sidecar
// naming every step, shows nothing at the final path before close, and leaves
// nothing behind when abandoned; it records what made the results: the
// model's fingerprint (always), the model file and the run's settings.
#define _POSIX_C_SOURCE 200809L
#include <hdf5.h>

#include "check.h"
#include "io_fixture.h"

#define STEPS 4

// Reads a whole double dataset; its element count must be `count`.
static int read_all(hid_t file, const char *name, double *out, hsize_t count) {
  hid_t dset = H5Dopen2(file, name, H5P_DEFAULT);
  if (dset < 0) return 1;
  hid_t space = H5Dget_space(dset);
  const int ok = H5Sget_simple_extent_npoints(space) == (hssize_t)count &&
                 H5Dread(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) >= 0;
  H5Sclose(space);
  H5Dclose(dset);
  return !ok;
}

// State of step t: frame and sample positions, rotations, a strain field.
static void state(int t, const fascia_model *m, double *x, double *q, double *p, double *strain) {
  for (int32_t i = 0; i < m->frame_count; ++i) {
    for (int r = 0; r < 3; ++r) x[3 * i + r] = m->frame_position[3 * i + r] + 0.001 * t * (r + 1) + 1e-19 * i;
    const double angle = 0.01 * t + 0.1 * i;
    q[4 * i] = cos(angle), q[4 * i + 1] = 0, q[4 * i + 2] = sin(angle), q[4 * i + 3] = 0;
  }
  for (int32_t s = 0; s < m->sample_count; ++s) {
    for (int r = 0; r < 3; ++r) p[3 * s + r] = m->sample_position[3 * s + r] - 0.002 * t / 3.0;
    strain[s] = 1e-3 * t / 7.0 + s;
  }
}

static char *read_text(const char *path) {
  FILE *in = fopen(path, "rb");
  if (!in) return NULL;
  fseek(in, 0, SEEK_END);
  const long size = ftell(in);
  fseek(in, 0, SEEK_SET);
  char *text = calloc((size_t)size + 1, 1);
  if (text && fread(text, 1, (size_t)size, in) != (size_t)size) text[0] = 0;
  fclose(in);
  return text;
}

static int check_file(const char *path, const char *xdmf, const fascia_model *m, const double *times) {
  const int32_t N = m->frame_count, S = m->sample_count;
  double x[15], q[20], p[9], strain[3], got[STEPS * 20], got_time[STEPS];
  hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  CHECK(file >= 0);
  if (file < 0) return 1;
  CHECK(read_all(file, "/steps/time", got_time, STEPS) == 0);
  CHECK(memcmp(got_time, times, sizeof got_time) == 0);
  for (int t = 0; t < STEPS; ++t) {
    state(t, m, x, q, p, strain);
    CHECK(read_all(file, "/frames/position", got, (hsize_t)STEPS * N * 3) == 0);
    CHECK(memcmp(got + t * N * 3, x, sizeof x) == 0);
    CHECK(read_all(file, "/frames/rotation", got, (hsize_t)STEPS * N * 4) == 0);
    CHECK(memcmp(got + t * N * 4, q, sizeof q) == 0);
    CHECK(read_all(file, "/samples/position", got, (hsize_t)STEPS * S * 3) == 0);
    CHECK(memcmp(got + t * S * 3, p, sizeof p) == 0);
    CHECK(read_all(file, "/samples/fields/strain", got, (hsize_t)STEPS * S) == 0);
    CHECK(memcmp(got + t * S, strain, sizeof strain) == 0);
    // "damage" is given in step 2 only: NaN elsewhere
    CHECK(read_all(file, "/samples/fields/damage", got, (hsize_t)STEPS * S) == 0);
    for (int32_t s = 0; s < S; ++s) CHECK(t == 2 ? got[t * S + s] == 0.5 * s : isnan(got[t * S + s]));
  }
  int32_t kind[5] = {0};
  hid_t dset = H5Dopen2(file, "/frames/kind", H5P_DEFAULT);
  CHECK(dset >= 0 && H5Dread(dset, H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, kind) >= 0);
  if (dset >= 0) H5Dclose(dset);
  CHECK(memcmp(kind, m->frame_kind, sizeof kind) == 0);
  H5Fclose(file);

  char *text = read_text(xdmf);
  CHECK(text != NULL);
  if (!text) return 1;
  CHECK(strstr(text, "CollectionType=\"Temporal\"") && strstr(text, "Polyvertex"));
  // per step, views of the series' rows (what ParaView reads: tests/t230)
  for (int t = 0; t < STEPS; ++t) {
    char step[64], value[64];
    snprintf(step, sizeof step, "results.h5:/xdmf/step_%d/field_strain", t);
    snprintf(value, sizeof value, "<Time Value=\"%.17g\"/>", times[t]);
    CHECK(strstr(text, step) && strstr(text, value));
  }
  free(text);
  return 0;
}

// The string attribute `name` of the file's root equals `want`.
static int root_text_is(const char *path, const char *name, const char *want) {
  char text[512] = "";
  hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t attr = file >= 0 ? H5Aopen_by_name(file, "/", name, H5P_DEFAULT, H5P_DEFAULT) : -1;
  hid_t type = attr >= 0 ? H5Aget_type(attr) : -1;
  const int ok = type >= 0 && H5Tget_size(type) < sizeof text && H5Aread(attr, type, text) >= 0;
  if (type >= 0) H5Tclose(type);
  if (attr >= 0) H5Aclose(attr);
  if (file >= 0) H5Fclose(file);
  if (!ok || strcmp(text, want)) fprintf(stderr, "root attribute %s: '%s', expected '%s'\n", name, text, want);
  return ok && !strcmp(text, want);
}

int main(void) {
  fascia_ctx_def cdef = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cdef, &ctx) != FASCIA_OK) return 1;
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  char dir[] = "t203-XXXXXX";
  CHECK(mkdtemp(dir) != NULL);
  char path[256], xdmf[256];
  snprintf(path, sizeof path, "%s/results.h5", dir);
  snprintf(xdmf, sizeof xdmf, "%s/results.xdmf", dir);
  fascia_model *m = NULL;
  CHECK_OK(fixture_model(ctx, 0, &m), ctx);

  fascia_results_def def = fascia_results_def_default();
  def.write_samples = true;
  fascia_results *r = NULL;
  double x[15], q[20], p[9], strain[3], damage[3] = {0, 0.5, 1.0}, times[STEPS];
  CHECK_OK(fascia_results_open(ctx, path, m, &def, &r), ctx);
  CHECK_OK(fascia_results_set_run(r, "models/pelvis.h5", "{\"mode\": \"dynamic\", \"dt\": 0.01}"), ctx);
  for (int t = 0; t < STEPS; ++t) {
    state(t, m, x, q, p, strain);
    times[t] = 0.01 * t + 1.0 / 3.0;
    CHECK_OK(fascia_results_append(r, times[t], x, q, p), ctx);
    CHECK_OK(fascia_results_append_field(r, "strain", strain), ctx);
    if (t == 2) CHECK_OK(fascia_results_append_field(r, "damage", damage), ctx);
    // a step that goes back in time is refused and not counted
    CHECK(fascia_results_append(r, times[t], x, q, p) == FASCIA_ERR_ARGUMENT);
    // nothing at the final path until close
    CHECK(access(path, F_OK) != 0 && access(xdmf, F_OK) != 0);
  }
  CHECK(fascia_results_step_count(r) == STEPS);
  CHECK(fascia_results_append_field(r, "a/b", strain) == FASCIA_ERR_ARGUMENT);
  CHECK(fixture_count_files(dir, ".tmp-") == 1);
  CHECK_OK(fascia_results_close(&r), ctx);
  CHECK(r == NULL);
  CHECK(fixture_count_files(dir, ".tmp") == 0);
  if (check_file(path, xdmf, m, times)) ++check_failures_;
  char fingerprint[32];
  snprintf(fingerprint, sizeof fingerprint, "%016llx", (unsigned long long)fascia_model_fingerprint(m));
  CHECK(root_text_is(path, "model_fingerprint", fingerprint));
  CHECK(root_text_is(path, "model_file", "models/pelvis.h5"));
  CHECK(root_text_is(path, "run_settings", "{\"mode\": \"dynamic\", \"dt\": 0.01}"));
  // another model, another fingerprint
  m->frame_position[0] += 1e-9;
  char moved[32];
  snprintf(moved, sizeof moved, "%016llx", (unsigned long long)fascia_model_fingerprint(m));
  CHECK(strcmp(moved, fingerprint) != 0);
  m->frame_position[0] -= 1e-9;

  // abandoned results leave nothing behind
  char other[256];
  snprintf(other, sizeof other, "%s/abandoned.h5", dir);
  CHECK_OK(fascia_results_open(ctx, other, m, &def, &r), ctx);
  CHECK_OK(fascia_results_append(r, 0, x, q, p), ctx);
  fascia_results_destroy(&r);
  CHECK(r == NULL && access(other, F_OK) != 0 && fixture_count_files(dir, "abandoned") == 0);

  // a results file in a folder that does not exist fails at open
  snprintf(other, sizeof other, "%s/no-such-folder/r.h5", dir);
  CHECK(fascia_results_open(ctx, other, m, &def, &r) == FASCIA_ERR_IO && r == NULL);

  fascia_model_destroy(&m);
  if (!check_failures_) fixture_remove_dir(dir);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
