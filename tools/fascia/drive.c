// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Organs driven from a CSV file (per-frame positions read from a
// file, for an organ driven by another simulator); the format is specified
// in docs/drive-format.md:
//
//   time,f12_x,f12_y,f12_z,f12_qw,f12_qx,f12_qy,f12_qz,f40_x,...   row 1: header
//   0,0.01,0,0,1,0,0,0,0.02,...                                   row 2: t0
//   0.5,0.011,0,0,1,0,0,0,0.021,...                               row 3: t1 > t0
//
// one group of 7 columns per coupling frame, in the order of
// fascia_solver_organ_frames, named after the model's frame index (so a file
// written for another model fails on its header). Before each step the
// rows are interpolated at the step's end time and handed to
// fascia_solver_organ_set_frames. Rows are the file's lines, 1-based, the
// header being row 1; blank lines are skipped but counted.
#define _POSIX_C_SOURCE 200809L
#include "drive.h"
#include "commands.h"
#include "fascia/files.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char run_drive_usage[] =
    "Organs driven by another simulator (docs/drive-format.md):\n"
    "  --drive ORGAN=FILE.csv the organ's coupling frames follow FILE (time, then x y z qw qx qy qz\n"
    "                         per coupling frame), interpolated at each step's end; repeatable\n"
    "  --drive-template ORGAN=FILE.csv\n"
    "                         write FILE's header and the frames' rest row, then exit without solving\n";

static const char *const component_names[7] = {"x", "y", "z", "qw", "qx", "qy", "qz"};

// ---------------------------------------------------------------- options

// Splits "ORGAN=FILE" into d; 0 when it is not of that form.
static int split_value(const char *value, drive_organ *d) {
  const char *eq = strchr(value, '=');
  if (!eq || eq == value || !eq[1] || (size_t)(eq - value) >= sizeof d->organ_name) return 0;
  memset(d, 0, sizeof *d);
  memcpy(d->organ_name, value, (size_t)(eq - value));
  d->organ_name[eq - value] = '\0';
  d->path = eq + 1;
  return 1;
}

int run_drive_take(int *argc, char **argv, run_drive *drive) {
  memset(drive, 0, sizeof *drive);
  drive->organs = calloc((size_t)*argc, sizeof(drive_organ));
  drive->templates = calloc((size_t)*argc, sizeof(drive_organ));
  if (!drive->organs || !drive->templates) {
    fprintf(stderr, "fascia run: out of memory\n");
    return 1;
  }
  static const char *const names[] = {"--drive", "--drive-template", NULL};
  int k = 1, kept = 1, taken;
  const char *o, *v;
  while ((taken = cli_take_option(argc, argv, &k, &kept, names, " ORGAN=FILE.csv", &o, &v)) == 1) {
    const int is_template = !strcmp(o, "--drive-template");
    drive_organ *list = is_template ? drive->templates : drive->organs;
    int *count = is_template ? &drive->template_count : &drive->count;
    if (!split_value(v, list + *count)) {
      fprintf(stderr, "fascia run: bad value '%s' for %s: expected ORGAN=FILE.csv (see fascia run --help)\n", v, o);
      return 2;
    }
    for (int j = 0; j < *count; ++j)
      if (!strcmp(list[j].organ_name, list[*count].organ_name)) {
        fprintf(stderr, "fascia run: organ '%s' given twice to %s\n", list[j].organ_name, o);
        return 2;
      }
    ++*count;
  }
  return taken ? taken : -1;
}

void run_drive_free(run_drive *drive) {
  for (int k = 0; drive->organs && k < drive->count; ++k) {
    drive_organ *d = drive->organs + k;
    free(d->time), free(d->position), free(d->rotation), free(d->x), free(d->q);
  }
  free(drive->organs), free(drive->templates);
  memset(drive, 0, sizeof *drive);
}

// Resolves d's organ in the model and its coupling frames (frames [C],
// allocated, freed by the caller).
static fascia_status find_organ(fascia_ctx *ctx, drive_organ *d, const fascia_model *m, const fascia_solver *solver,
                                int32_t **frames) {
  *frames = NULL;
  d->organ = fascia_model_find_organ(m, d->organ_name);
  if (d->organ < 0) {
    char names[512] = "";
    for (int32_t k = 0; k < m->organ_count && strlen(names) + FASCIA_NAME_SIZE + 3 < sizeof names; ++k)
      strcat(strcat(names, k ? ", " : ""), m->organs[k].name);
    return fascia_ctx_fail(ctx, FASCIA_ERR_ARGUMENT, __FILE__, __LINE__,
                           "drive '%s': the model has no organ '%s' (its organs: %s); give --drive ORGAN=FILE.csv "
                           "with one of them",
                           d->path, d->organ_name, m->organ_count ? names : "none");
  }
  d->frame_count = fascia_solver_organ_frame_count(solver, d->organ);
  if (d->frame_count <= 0)
    return fascia_ctx_fail(ctx, FASCIA_ERR_ARGUMENT, __FILE__, __LINE__,
                           "drive '%s': organ '%s' has no coupling frames, so there is nothing to drive", d->path,
                           d->organ_name);
  *frames = malloc(sizeof(int32_t) * (size_t)d->frame_count);
  if (!*frames)
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "drive '%s': out of memory", d->path);
  return fascia_solver_organ_frames(solver, d->organ, *frames);
}

// Header name of column `column` (0-based; 0 is the time).
static void column_name(const int32_t *frames, int column, char *out, size_t size) {
  if (column == 0) snprintf(out, size, "time");
  else snprintf(out, size, "f%d_%s", (int)frames[(column - 1) / 7], component_names[(column - 1) % 7]);
}

// ---------------------------------------------------------------- template

static fascia_status write_template(fascia_ctx *ctx, drive_organ *d, const fascia_model *m,
                                    const fascia_solver *solver) {
  int32_t *frames = NULL;
  fascia_status st = find_organ(ctx, d, m, solver, &frames);
  fascia_file *file = NULL;
  if (st == FASCIA_OK) st = fascia_file_open(ctx, "--drive-template", d->path, &file);
  if (st != FASCIA_OK) goto cleanup;
  FILE *f = fascia_file_stream(file);
  const int columns = 1 + 7 * d->frame_count;
  for (int c = 0; c < columns; ++c) {
    char name[64];
    column_name(frames, c, name, sizeof name);
    fprintf(f, "%s%s", c ? "," : "", name);
  }
  const fascia_real *x = fascia_solver_frame_positions(solver), *q = fascia_solver_frame_rotations(solver);
  fprintf(f, "\n%.17g", fascia_solver_time(solver));
  for (int32_t k = 0; k < d->frame_count; ++k) {
    const int32_t i = frames[k];
    fprintf(f, ",%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", x[3 * i], x[3 * i + 1], x[3 * i + 2], q[4 * i],
            q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]);
  }
  fputc('\n', f);
  st = fascia_file_commit(&file);
cleanup:
  free(frames);
  return st;
}

fascia_status run_drive_write_templates(run_drive *drive, fascia_ctx *ctx, const fascia_model *model,
                                        const fascia_solver *solver) {
  for (int k = 0; k < drive->template_count; ++k) {
    fascia_status st = write_template(ctx, drive->templates + k, model, solver);
    if (st != FASCIA_OK) return st;
  }
  return FASCIA_OK;
}

// ---------------------------------------------------------------- reading

// The line without its end-of-line and trailing blanks; NULL if blank.
static char *trim_line(char *line) {
  size_t n = strlen(line);
  while (n > 0 && (line[n - 1] == '\n' || line[n - 1] == '\r' || line[n - 1] == ' ' || line[n - 1] == '\t'))
    line[--n] = '\0';
  while (*line == ' ' || *line == '\t') ++line;
  return *line ? line : NULL;
}

// Splits a line at its commas in place; cells[k] trimmed. Returns the
// number of cells (all counted, at most `capacity` stored).
static int split_cells(char *line, char **cells, int capacity) {
  int n = 0;
  for (char *p = line;; ++n) {
    char *comma = strchr(p, ',');
    if (comma) *comma = '\0';
    char *cell = trim_line(p);
    if (n < capacity) cells[n] = cell ? cell : p + strlen(p);
    if (!comma) return n + 1;
    p = comma + 1;
  }
}

// Grows d's rows to hold at least `rows`.
static int reserve_rows(drive_organ *d, int32_t *capacity, int32_t rows) {
  if (rows <= *capacity) return 1;
  const int32_t c = *capacity ? 2 * *capacity : 16, C = d->frame_count;
  fascia_real *t = realloc(d->time, sizeof(fascia_real) * (size_t)c);
  if (t) d->time = t;
  fascia_real *x = realloc(d->position, sizeof(fascia_real) * 3 * (size_t)C * (size_t)c);
  if (x) d->position = x;
  fascia_real *q = realloc(d->rotation, sizeof(fascia_real) * 4 * (size_t)C * (size_t)c);
  if (q) d->rotation = q;
  if (!t || !x || !q) return 0;
  *capacity = c;
  return 1;
}

// Checks the header row against the organ's frames.
static fascia_status check_header(fascia_ctx *ctx, const drive_organ *d, const int32_t *frames, char **cells,
                                  int found) {
  const int columns = 1 + 7 * d->frame_count;
  if (found != columns)
    return fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__,
                           "drive '%s' row 1: %d header columns, expected %d (time, then x y z qw qx qy qz for each "
                           "of the %d coupling frames of organ '%s'); write the header with 'fascia run MODEL.h5 "
                           "--drive-template %s=FILE.csv'",
                           d->path, found, columns, (int)d->frame_count, d->organ_name, d->organ_name);
  for (int c = 0; c < columns; ++c) {
    char name[64];
    column_name(frames, c, name, sizeof name);
    if (strcmp(cells[c], name))
      return fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__,
                             "drive '%s' row 1 column %d: header '%s', expected '%s' (the columns follow the coupling "
                             "frames of organ '%s' in the model); write the header with 'fascia run MODEL.h5 "
                             "--drive-template %s=FILE.csv'",
                             d->path, c + 1, cells[c], name, d->organ_name, d->organ_name);
  }
  return FASCIA_OK;
}

// Parses data row `r` (file row `row`) into d's arrays.
static fascia_status parse_row(fascia_ctx *ctx, drive_organ *d, const int32_t *frames, char **cells, int found,
                               int32_t r, long row) {
  const int columns = 1 + 7 * d->frame_count;
  if (found != columns)
    return fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__,
                           "drive '%s' row %ld: %d columns, expected %d like the header (time, then 7 per coupling "
                           "frame of organ '%s')",
                           d->path, row, found, columns, d->organ_name);
  fascia_real values[8];
  for (int c = 0; c < columns; ++c) {
    char name[64], *end = NULL;
    column_name(frames, c, name, sizeof name);
    errno = 0;
    const double v = strtod(cells[c], &end);
    if (!cells[c][0] || *end || errno == EINVAL)
      return fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__,
                             "drive '%s' row %ld column %d (%s): '%s' is not a number", d->path, row, c + 1, name,
                             cells[c]);
    if (!isfinite(v))
      return fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__,
                             "drive '%s' row %ld column %d (%s): '%s' is not finite; give a finite value", d->path,
                             row, c + 1, name, cells[c]);
    values[c == 0 ? 7 : (c - 1) % 7] = v;
    if (c == 0) {
      if (r > 0 && !(v > d->time[r - 1]))
        return fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__,
                               "drive '%s' row %ld column 1 (time): %.9g s is not after the previous row's %.9g s; "
                               "times must increase from row to row",
                               d->path, row, v, d->time[r - 1]);
      d->time[r] = v;
      continue;
    }
    if ((c - 1) % 7 != 6) continue;
    // a whole frame read: store it, the rotation normalized
    const int32_t k = (c - 1) / 7;
    const double norm = sqrt(values[3] * values[3] + values[4] * values[4] + values[5] * values[5] +
                             values[6] * values[6]);
    if (!(norm > 1e-12) || !isfinite(norm))
      return fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__,
                             "drive '%s' row %ld columns %d-%d (f%d_qw..f%d_qz): the rotation quaternion is zero; "
                             "give a unit quaternion w x y z (1 0 0 0 at rest)",
                             d->path, row, c - 2, c + 1, (int)frames[k], (int)frames[k]);
    fascia_real *x = d->position + (size_t)r * 3 * d->frame_count + 3 * k;
    fascia_real *q = d->rotation + (size_t)r * 4 * d->frame_count + 4 * k;
    for (int j = 0; j < 3; ++j) x[j] = values[j];
    for (int j = 0; j < 4; ++j) q[j] = values[3 + j] / norm;
  }
  return FASCIA_OK;
}

// Reads one drive file (d's organ resolved) into d.
static fascia_status read_file(fascia_ctx *ctx, drive_organ *d, const int32_t *frames) {
  FILE *f = NULL; // a regular file only, opened without blocking (a FIFO put there after the path check)
  const fascia_status opened = fascia_file_open_input(ctx, "drive", d->path, &f);
  if (opened != FASCIA_OK) return opened;
  const int columns = 1 + 7 * d->frame_count;
  char **cells = malloc(sizeof(char *) * (size_t)columns);
  char *buffer = NULL;
  size_t buffer_size = 0;
  int32_t capacity = 0;
  long row = 0;
  int header = 1;
  fascia_status st = cells ? FASCIA_OK
                           : fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "drive '%s': out of memory",
                                             d->path);
  while (st == FASCIA_OK && getline(&buffer, &buffer_size, f) != -1) {
    ++row;
    char *line = trim_line(buffer);
    if (!line) continue;
    const int found = split_cells(line, cells, columns);
    if (header) {
      st = check_header(ctx, d, frames, cells, found);
      header = 0;
    } else if (!reserve_rows(d, &capacity, d->row_count + 1)) {
      st = fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "drive '%s' row %ld: out of memory", d->path,
                           row);
    } else if ((st = parse_row(ctx, d, frames, cells, found, d->row_count, row)) == FASCIA_OK) {
      d->row_count++;
    }
  }
  if (st == FASCIA_OK && ferror(f))
    st = fascia_ctx_fail(ctx, FASCIA_ERR_IO, __FILE__, __LINE__, "drive '%s': read error after row %ld", d->path,
                         row);
  if (st == FASCIA_OK && d->row_count == 0)
    st = fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__,
                         "drive '%s': no data rows%s; give a header row, then one row per time", d->path,
                         header ? " and no header" : " after the header");
  free(buffer), free(cells);
  fclose(f);
  return st;
}

fascia_status run_drive_load(run_drive *drive, fascia_ctx *ctx, const fascia_model *model,
                             const fascia_solver *solver) {
  fascia_status st = FASCIA_OK;
  for (int k = 0; k < drive->count && st == FASCIA_OK; ++k) {
    drive_organ *d = drive->organs + k;
    int32_t *frames = NULL;
    st = find_organ(ctx, d, model, solver, &frames);
    if (st == FASCIA_OK) st = read_file(ctx, d, frames);
    if (st == FASCIA_OK) {
      d->x = malloc(sizeof(fascia_real) * 3 * (size_t)d->frame_count);
      d->q = malloc(sizeof(fascia_real) * 4 * (size_t)d->frame_count);
      if (!d->x || !d->q)
        st = fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "drive '%s': out of memory", d->path);
    }
    free(frames);
  }
  return st;
}

// ---------------------------------------------------------------- stepping

// Spherical linear interpolation from a to b (unit quaternions) by s in
// [0, 1] along the shorter arc; normalized linear where they nearly agree
// (angle below about 2 degrees: slerp's weights lose digits there).
static void slerp(const fascia_real *a, const fascia_real *b, fascia_real s, fascia_real *out) {
  fascia_real d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  const fascia_real sign = d < 0 ? -1 : 1;
  d = fabs(d);
  fascia_real wa = 1 - s, wb = s;
  if (d < 0.9995) {
    const fascia_real angle = acos(d), sin_angle = sin(angle);
    wa = sin((1 - s) * angle) / sin_angle;
    wb = sin(s * angle) / sin_angle;
  }
  fascia_real norm = 0;
  for (int j = 0; j < 4; ++j) out[j] = wa * a[j] + sign * wb * b[j], norm += out[j] * out[j];
  norm = sqrt(norm);
  for (int j = 0; j < 4; ++j) out[j] /= norm;
}

// d's pose at time t into d->x, d->q.
static void interpolate(drive_organ *d, fascia_real t) {
  const size_t X = 3 * (size_t)d->frame_count, Q = 4 * (size_t)d->frame_count;
  int32_t lo = 0, hi = d->row_count - 1; // the last row with time <= t, or 0
  if (t >= d->time[hi]) lo = hi;
  while (hi - lo > 1) {
    const int32_t mid = lo + (hi - lo) / 2;
    if (d->time[mid] <= t) lo = mid;
    else hi = mid;
  }
  const fascia_real *x0 = d->position + lo * X, *q0 = d->rotation + lo * Q;
  if (lo == d->row_count - 1 || t <= d->time[lo]) { // a row's time, before the first or after the last: that row
    memcpy(d->x, x0, sizeof(fascia_real) * X);
    memcpy(d->q, q0, sizeof(fascia_real) * Q);
    return;
  }
  const fascia_real s = (t - d->time[lo]) / (d->time[lo + 1] - d->time[lo]);
  const fascia_real *x1 = x0 + X, *q1 = q0 + Q;
  for (size_t j = 0; j < X; ++j) d->x[j] = (1 - s) * x0[j] + s * x1[j];
  for (int32_t k = 0; k < d->frame_count; ++k) slerp(q0 + 4 * k, q1 + 4 * k, s, d->q + 4 * k);
}

fascia_status run_drive_before_step(run_drive *drive, fascia_solver *solver, fascia_real t_end) {
  for (int k = 0; k < drive->count; ++k) {
    drive_organ *d = drive->organs + k;
    interpolate(d, t_end);
    fascia_status st = fascia_solver_organ_set_frames(solver, d->organ, d->x, d->q);
    if (st != FASCIA_OK) return st;
  }
  return FASCIA_OK;
}

// FNV-1a over bytes, as the checkpoint's own checksum is made.
static uint64_t fnv(uint64_t h, const void *data, size_t bytes) {
  const unsigned char *p = data;
  for (size_t k = 0; k < bytes; ++k) h = (h ^ p[k]) * UINT64_C(0x100000001b3);
  return h;
}

uint64_t run_drive_digest(const run_drive *drive) {
  uint64_t digest = 0;
  for (int k = 0; k < drive->count; ++k) { // summed: the order of the options does not matter
    const drive_organ *d = drive->organs + k;
    const size_t T = (size_t)d->row_count, C = (size_t)d->frame_count;
    uint64_t h = fnv(UINT64_C(0xcbf29ce484222325), d->organ_name, strlen(d->organ_name) + 1);
    h = fnv(h, &d->row_count, sizeof d->row_count);
    h = fnv(h, &d->frame_count, sizeof d->frame_count);
    h = fnv(h, d->time, T * sizeof *d->time);
    h = fnv(h, d->position, 3 * C * T * sizeof *d->position);
    digest += fnv(h, d->rotation, 4 * C * T * sizeof *d->rotation);
  }
  return drive->count && !digest ? 1 : digest; // 0 means "no drive"
}
