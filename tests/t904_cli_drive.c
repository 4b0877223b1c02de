// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia run --drive ORGAN=FILE.csv` moves an organ's coupling frames to the
// file's rows: on the organ fixture (A fixed, B rigid), --drive-template
// writes B's frames in fascia_solver_organ_frames order at rest; a CSV that
// translates B by 2 mm and turns its frames by 3 degrees over 0.04 s puts
// the frames in the results exactly on the slerp/linear interpolation half
// way and on the last row after it; bad files (missing, wrong column count,
// not a number, NaN, zero quaternion, unknown organ, times going back, wrong
// header) exit 1 naming the file (and row and column) and leave no results
// file. A checkpoint of a driven run records its drive: resuming it without
// --drive, or with a file whose rows differ, is refused (exit 2); with the
// same drive it continues.
// Usage: t904_cli_drive PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <hdf5.h>
#include <math.h>

#include "check.h"
#include "cli_exec.h"
#include "fascia/organs.h"
#include "organ_fixture.h"

#define C 9          // coupling frames per organ in the fixture
#define COLUMNS (1 + 7 * C)
#define PUSH 0.002   // m, B's translation along x at the last row
#define ANGLE 0.0523598775598298873 // rad, 3 degrees about x: the frames' rotation at the last row

static cli_result result;

// Reads /frames/position or /frames/rotation [T, N, width] of a results file.
static double *read_series(const char *path, const char *name, int width, hsize_t *steps) {
  hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) return NULL;
  hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
  hid_t space = H5Dget_space(d);
  hsize_t dims[3] = {0, 0, 0};
  H5Sget_simple_extent_dims(space, dims, NULL);
  double *v = dims[2] == (hsize_t)width ? malloc(sizeof(double) * dims[0] * dims[1] * dims[2]) : NULL;
  if (v && H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0) free(v), v = NULL;
  *steps = dims[0];
  H5Sclose(space), H5Dclose(d), H5Fclose(f);
  return v;
}

static int write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  if (!f) return 0;
  fputs(text, f);
  return fclose(f) == 0;
}

// The header line of B's drive file, as --drive-template must write it.
static void expected_header(const int32_t *fb, char *out, size_t size) {
  static const char *const names[7] = {"x", "y", "z", "qw", "qx", "qy", "qz"};
  size_t n = (size_t)snprintf(out, size, "time");
  for (int k = 0; k < C; ++k)
    for (int j = 0; j < 7; ++j) n += (size_t)snprintf(out + n, size - n, ",f%d_%s", (int)fb[k], names[j]);
}

// One row of B's drive file at time t: rest + (dx, 0, 0), rotation q, every frame.
static size_t drive_row(const fascia_model *m, const int32_t *fb, double t, double dx, const double *q, char *out,
                        size_t size) {
  size_t n = (size_t)snprintf(out, size, "%.17g", t);
  for (int k = 0; k < C; ++k) {
    const double *x = m->frame_position + 3 * fb[k];
    n += (size_t)snprintf(out + n, size - n, ",%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", x[0] + dx, x[1], x[2], q[0],
                          q[1], q[2], q[3]);
  }
  n += (size_t)snprintf(out + n, size - n, "\n");
  return n;
}

// Runs `fascia run MODEL --steps 6 --dt 0.01 --drive ORGAN=CSV -o RESULTS`
// expecting a failure (1) whose stderr holds each of the `needles`, and no
// results file.
static int expect_failure(const char *fascia, const char *model, const char *organ, const char *csv,
                          const char *results, const char *err, const char *const *needles, int needle_count) {
  char args[8192];
  remove(results);
  snprintf(args, sizeof args, "run '%s' --steps 6 --dt 0.01 --threads 1 --drive '%s=%s' -o '%s'", model, organ, csv,
           results);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 1);
  for (int k = 0; k < needle_count; ++k)
    if (!strstr(result.err, needles[k])) {
      fprintf(stderr, "stderr lacks '%s': %s\n", needles[k], result.err);
      CHECK(0);
    }
  CHECK(!cli_file_exists(results));
  return 0;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t904_cli_drive PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1], *dir = argv[2];
  char model_path[2048], err[2048], tmpl[2048], csv[2048], bad[2048], results[2048], args[8192];
  snprintf(model_path, sizeof model_path, "%s/t904_organs.h5", dir);
  snprintf(err, sizeof err, "%s/t904_stderr.txt", dir);
  snprintf(tmpl, sizeof tmpl, "%s/t904_template.csv", dir);
  snprintf(csv, sizeof csv, "%s/t904_drive.csv", dir);
  snprintf(bad, sizeof bad, "%s/t904_bad.csv", dir);
  snprintf(results, sizeof results, "%s/t904_r.h5", dir);

  // the model: A fixed, B rigid, no gravity; B's frame order from the C API
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1;
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  organ_fixture_def fd = organ_fixture_def_default();
  fascia_model *m = NULL;
  fascia_solver *s = NULL;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  CHECK_OK(fascia_model_save(ctx, m, model_path), ctx);
  fascia_solver_def sd = fascia_solver_def_default();
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  int32_t fb[C], fa[C];
  CHECK(fascia_solver_organ_frame_count(s, 1) == C);
  CHECK_OK(fascia_solver_organ_frames(s, 1, fb), ctx);
  CHECK_OK(fascia_solver_organ_frames(s, 0, fa), ctx);
  fascia_solver_destroy(&s);

  // --drive-template: the header in B's frame order and the rest row
  static char line[1 << 16], header[1 << 16], text[1 << 18];
  remove(tmpl);
  snprintf(args, sizeof args, "run '%s' --drive-template 'b=%s'", model_path, tmpl);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  expected_header(fb, header, sizeof header);
  const double rest_q[4] = {1, 0, 0, 0};
  FILE *f = fopen(tmpl, "r");
  CHECK(f != NULL);
  if (!f) return 1;
  CHECK(fgets(line, sizeof line, f) != NULL);
  line[strcspn(line, "\n")] = '\0';
  CHECK(!strcmp(line, header));
  CHECK(fgets(line, sizeof line, f) != NULL);
  fclose(f);
  drive_row(m, fb, 0, 0, rest_q, text, sizeof text);
  CHECK(!strcmp(line, text)); // %.17g both sides: the rest positions exactly

  // the drive: rest at t = 0, pushed and turned at t = 0.04, held after
  const double q_end[4] = {cos(ANGLE / 2), sin(ANGLE / 2), 0, 0};
  size_t n = (size_t)snprintf(text, sizeof text, "%s\n", header);
  n += drive_row(m, fb, 0, 0, rest_q, text + n, sizeof text - n);
  drive_row(m, fb, 0.04, PUSH, q_end, text + n, sizeof text - n);
  CHECK(write_text(csv, text));
  remove(results);
  snprintf(args, sizeof args, "run '%s' --steps 6 --dt 0.01 --threads 1 --drive 'b=%s' -o '%s' --json", model_path,
           csv, results);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 0);
  if (result.status != 0) fprintf(stderr, "fascia run failed: %s\n", result.err);
  CHECK(strstr(result.out, "\"drive\":{\"b\":") != NULL);
  hsize_t steps = 0, steps_q = 0;
  double *x = read_series(results, "/frames/position", 3, &steps);
  double *q = read_series(results, "/frames/rotation", 4, &steps_q);
  CHECK(x && q && steps == 7 && steps_q == 7); // rest + 6 steps
  if (x && q && steps == 7) {
    const size_t N = (size_t)m->frame_count;
    const double q_half[4] = {cos(ANGLE / 4), sin(ANGLE / 4), 0, 0}; // slerp half way: half the angle
    for (int k = 0; k < C; ++k) {
      const double *rest = m->frame_position + 3 * fb[k];
      for (int c = 0; c < 3; ++c) {
        // t = 0.02, half way: the solver lands driven frames on the target to
        // rounding (t323); 1e-15 m covers the interpolation's rounding
        CHECK_NEAR(x[(2 * N + fb[k]) * 3 + c], rest[c] + (c == 0 ? PUSH / 2 : 0), 0, 1e-15);
        for (size_t t = 4; t <= 6; ++t) // from t = 0.04 on: the last row, held
          CHECK_NEAR(x[(t * N + fb[k]) * 3 + c], rest[c] + (c == 0 ? PUSH : 0), 0, 1e-15);
        CHECK(x[(6 * N + fa[k]) * 3 + c] == m->frame_position[3 * fa[k] + c]); // fixed A holds exactly
      }
      for (int c = 0; c < 4; ++c) {
        CHECK_NEAR(q[(2 * N + fb[k]) * 4 + c], q_half[c], 0, 1e-14); // slerp and normalization rounding
        CHECK_NEAR(q[(6 * N + fb[k]) * 4 + c], q_end[c], 0, 1e-15);
      }
    }
    // the tissue between the organs followed the push
    int moved = 0;
    for (size_t i = 0; i < N; ++i)
      moved += m->frame_position[3 * i] > 0.005 && m->frame_position[3 * i] < FIX_L - 0.005 &&
               x[(6 * N + i) * 3] > m->frame_position[3 * i] + 1e-5;
    CHECK(moved > 0);
  }
  free(x), free(q);

  // bad files: exit 1, the file (row, column) named, no results file
  {
    char missing[2048];
    snprintf(missing, sizeof missing, "%s/t904_no_such_drive.csv", dir);
    remove(missing);
    const char *const needles[] = {"t904_no_such_drive.csv"};
    CHECK(!expect_failure(fascia, model_path, "b", missing, results, err, needles, 1));
  }
  { // wrong column count in row 3: the last value dropped
    n = (size_t)snprintf(text, sizeof text, "%s\n", header);
    n += drive_row(m, fb, 0, 0, rest_q, text + n, sizeof text - n);
    drive_row(m, fb, 0.04, PUSH, q_end, text + n, sizeof text - n);
    *strrchr(text, ',') = '\0';
    strcat(text, "\n");
    CHECK(write_text(bad, text));
    const char *const needles[] = {"t904_bad.csv", "row 3", "columns, expected 64"};
    CHECK(!expect_failure(fascia, model_path, "b", bad, results, err, needles, 3));
  }
  { // not a number in row 2, column 3 (f<fb[0]>_y)
    n = (size_t)snprintf(text, sizeof text, "%s\n", header);
    n += drive_row(m, fb, 0, 0, rest_q, text + n, sizeof text - n);
    char *second = strchr(strchr(strchr(text, '\n') + 1, ',') + 1, ',') + 1; // row 2, column 3
    memcpy(second, "abc", 3);
    CHECK(write_text(bad, text));
    char where[128];
    snprintf(where, sizeof where, "row 2 column 3 (f%d_y)", (int)fb[0]);
    const char *const needles[] = {"t904_bad.csv", where, "is not a number"};
    CHECK(!expect_failure(fascia, model_path, "b", bad, results, err, needles, 3));
  }
  { // NaN in row 3, column 2
    n = (size_t)snprintf(text, sizeof text, "%s\n", header);
    n += drive_row(m, fb, 0, 0, rest_q, text + n, sizeof text - n);
    char *row3 = text + n;
    n += drive_row(m, fb, 0.04, PUSH, q_end, text + n, sizeof text - n);
    char *end = strchr(strchr(row3, ',') + 1, ',');
    memmove(strchr(row3, ',') + 4, end, strlen(end) + 1);
    memcpy(strchr(row3, ',') + 1, "nan", 3);
    CHECK(write_text(bad, text));
    const char *const needles[] = {"t904_bad.csv", "row 3 column 2", "not finite"};
    CHECK(!expect_failure(fascia, model_path, "b", bad, results, err, needles, 3));
  }
  { // zero quaternions in row 2: the first frame's is reported
    const double zero_q[4] = {0, 0, 0, 0};
    n = (size_t)snprintf(text, sizeof text, "%s\n", header);
    n += drive_row(m, fb, 0, 0, zero_q, text + n, sizeof text - n);
    CHECK(write_text(bad, text));
    char where[128];
    snprintf(where, sizeof where, "row 2 columns 5-8 (f%d_qw..f%d_qz)", (int)fb[0], (int)fb[0]);
    const char *const needles[] = {"t904_bad.csv", where, "quaternion is zero"};
    CHECK(!expect_failure(fascia, model_path, "b", bad, results, err, needles, 3));
  }
  { // times not increasing: row 3 at the time of row 2
    n = (size_t)snprintf(text, sizeof text, "%s\n", header);
    n += drive_row(m, fb, 0.01, 0, rest_q, text + n, sizeof text - n);
    drive_row(m, fb, 0.01, PUSH, q_end, text + n, sizeof text - n);
    CHECK(write_text(bad, text));
    const char *const needles[] = {"t904_bad.csv", "row 3 column 1 (time)", "times must increase"};
    CHECK(!expect_failure(fascia, model_path, "b", bad, results, err, needles, 3));
  }
  { // a header of another organ's frames (A's)
    expected_header(fa, text, sizeof text);
    strcat(text, "\n");
    drive_row(m, fa, 0, 0, rest_q, text + strlen(text), sizeof text - strlen(text));
    CHECK(write_text(bad, text));
    const char *const needles[] = {"t904_bad.csv", "row 1 column 2", "--drive-template b="};
    CHECK(!expect_failure(fascia, model_path, "b", bad, results, err, needles, 3));
  }
  { // an organ the model lacks
    const char *const needles[] = {"t904_drive.csv", "no organ 'liver'", "a, b"};
    CHECK(!expect_failure(fascia, model_path, "liver", csv, results, err, needles, 3));
  }
  { // a resume drives the organs as the run that saved the checkpoint did
    char checkpoint[2048], other[2048], body[8192];
    snprintf(checkpoint, sizeof checkpoint, "%s/t904_checkpoint.h5", argv[2]);
    snprintf(other, sizeof other, "%s/t904_other.csv", argv[2]);
    size_t k = (size_t)snprintf(body, sizeof body, "%s\n", header);
    k += drive_row(m, fb, 0, 0, rest_q, body + k, sizeof body - k);
    drive_row(m, fb, 0.04, 2 * PUSH, q_end, body + k, sizeof body - k); // pushed twice as far
    CHECK(write_text(other, body));
    remove(checkpoint);
    snprintf(args, sizeof args, "run '%s' --steps 3 --dt 0.01 --threads 1 --drive 'b=%s' --checkpoint '%s'",
             model_path, csv, checkpoint);
    CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
    static const char *const resumes[][2] = {{"", "drove organs from --drive files"},
                                             {"--drive 'b=%s'", "other --drive files"}};
    for (int r = 0; r < 2; ++r) {
      char extra[2048];
      snprintf(extra, sizeof extra, resumes[r][0], other);
      snprintf(args, sizeof args, "run '%s' --steps 6 --threads 1 --resume '%s' %s", model_path, checkpoint, extra);
      CHECK(cli_exec(fascia, args, err, &result) && result.status == 2 && strstr(result.err, resumes[r][1]));
      if (result.status != 2) fprintf(stderr, "%s: exit %d: %s\n", args, result.status, result.err);
    }
    snprintf(args, sizeof args, "run '%s' --steps 6 --threads 1 --resume '%s' --drive 'b=%s'", model_path, checkpoint,
             csv);
    CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  }
  // usage errors (2): no '=', or no dynamic run
  snprintf(args, sizeof args, "run '%s' --steps 2 --drive b", model_path);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 2 && strstr(result.err, "--drive"));
  snprintf(args, sizeof args, "run '%s' --static --drive 'b=%s'", model_path, csv);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 2 && strstr(result.err, "--drive"));

  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  if (check_failures_) fprintf(stderr, "last stderr: %.600s\n", result.err);
  return CHECK_RESULT();
}
