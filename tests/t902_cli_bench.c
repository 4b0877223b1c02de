// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia bench` keeps its command-line contract: `bench ROW ... --json`
// prints one JSON array of row objects with the documented keys (Table 3
// rows with the paper's GPU time), 60 CG iterations per step as in the
// paper; `bench cantilever --json` rows carry the tip error against the
// reference; --csv writes a header row and one line per row; an unknown row
// is a usage error. --backend emulated (the device solver in host loops)
// times the row there and on the CPU, beside the paper's GPU figure;
// --backend cuda runs, or fails naming CUDA without crashing; settings the
// device refuses (--assembled) are a usage error; --list shows the large rows.
// --modes on,off gives a 20x3x3 tet row with the enhanced strain modes and
// one without (enhanced_modes true and false; within 1 % with them, more
// than 5 % too stiff without);
// --modes on with --volumetric full is refused before any row runs. A
// sweep whose lists make a row with no beam (a tetrahedral one with 2
// samples per tetrahedron) reports that row with the builder's reason, in
// the JSON and as a CSV line of the header's width, runs the others and
// exits 1 saying how many rows failed (it had stopped at the first).
// Usage: t902_cli_bench PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <ctype.h>
#include <math.h>

#include "beam_calculix.h"
#include "check.h"
#include "cli_exec.h"

static cli_result result;

static void check_keys(const cJSON *row, const char *const *keys, size_t count) {
  for (size_t k = 0; k < count; ++k)
    if (!cJSON_GetObjectItemCaseSensitive(row, keys[k])) {
      fprintf(stderr, "row lacks key '%s'\n", keys[k]);
      CHECK(0);
    }
}

static void check_paper(const char *fascia, const char *err, const char *csv) {
  char args[4096];
  snprintf(args, sizeof args, "bench t2-f72-s400-k4 t3-s800 --json --steps 1 --repeats 1 --threads 1 --csv '%s'",
           csv);
  remove(csv);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 0);
  cJSON *rows = cJSON_Parse(result.out);
  CHECK(cJSON_IsArray(rows) && cJSON_GetArraySize(rows) == 2);
  if (!cJSON_IsArray(rows) || cJSON_GetArraySize(rows) != 2) {
    fprintf(stderr, "stdout: %.400s\nstderr: %.400s\n", result.out, result.err);
    cJSON_Delete(rows);
    return;
  }
  static const char *const keys[] = {"table", "samples", "frames", "neighbours", "ms_per_step", "paper_ms",
                                     "speedup", "peak_memory_mb", "evaluate_ms", "precond_ms", "cg_ms"};
  for (int k = 0; k < 2; ++k) {
    const cJSON *row = cJSON_GetArrayItem(rows, k);
    check_keys(row, keys, sizeof keys / sizeof keys[0]);
    const cJSON *ms = cJSON_GetObjectItemCaseSensitive(row, "ms_per_step");
    CHECK(cJSON_IsNumber(ms) && isfinite(ms->valuedouble) && ms->valuedouble > 0);
    const cJSON *cg = cJSON_GetObjectItemCaseSensitive(row, "cg_iterations_per_step");
    CHECK(cJSON_IsNumber(cg) && cg->valuedouble == 60); // the paper's fixed count
    const cJSON *k4 = cJSON_GetObjectItemCaseSensitive(row, "neighbours");
    CHECK(cJSON_IsNumber(k4) && k4->valueint == 4);
  }
  const cJSON *t2 = cJSON_GetArrayItem(rows, 0), *t3 = cJSON_GetArrayItem(rows, 1);
  CHECK(cJSON_GetObjectItemCaseSensitive(t2, "table")->valueint == 2);
  CHECK(cJSON_GetObjectItemCaseSensitive(t2, "samples")->valueint == 400);
  CHECK(cJSON_GetObjectItemCaseSensitive(t3, "table")->valueint == 3);
  CHECK(cJSON_GetObjectItemCaseSensitive(t3, "samples")->valueint == 800);
  CHECK_NEAR(cJSON_GetObjectItemCaseSensitive(t3, "paper_ms")->valuedouble, 78.42, 0, 1e-9);
  const cJSON *gpu = cJSON_GetObjectItemCaseSensitive(t3, "paper_gpu_ms");
  CHECK(cJSON_IsNumber(gpu) && fabs(gpu->valuedouble - 15.25) < 1e-9);
  cJSON_Delete(rows);
  // CSV: a header row and two rows
  FILE *f = fopen(csv, "r");
  CHECK(f != NULL);
  if (f) {
    char line[4096];
    int lines = 0;
    CHECK(fgets(line, sizeof line, f) && !strncmp(line, "table,name,frames,", 18));
    for (lines = 1; fgets(line, sizeof line, f); ++lines) {}
    CHECK(lines == 3);
    fclose(f);
  }
}

// Counts the fields of a CSV line (quoted fields may hold commas).
static int csv_fields(const char *line) {
  int fields = 1, quoted = 0;
  for (; *line && *line != '\n'; ++line) {
    if (*line == '"') quoted = !quoted;
    else if (*line == ',' && !quoted) ++fields;
  }
  return fields;
}

static void check_failed_row(const char *fascia, const char *err, const char *csv) {
  char args[4096];
  snprintf(args, sizeof args,
           "bench cantilever --shapes hex,tet --frames 6x2x2 --samples-per-cell 2 --json --threads 1 --no-calculix "
           "--csv '%s'",
           csv);
  remove(csv);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 1 && strstr(result.err, "1 of 2 cantilever rows could not be built"));
  cJSON *rows = cJSON_Parse(result.out);
  CHECK(cJSON_IsArray(rows) && cJSON_GetArraySize(rows) == 2);
  const cJSON *hex = cJSON_GetArrayItem(rows, 0), *tet = cJSON_GetArrayItem(rows, 1);
  if (hex && tet) {
    CHECK(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(hex, "converged")));
    CHECK(!cJSON_GetObjectItemCaseSensitive(hex, "error"));
    const cJSON *why = cJSON_GetObjectItemCaseSensitive(tet, "error");
    CHECK(cJSON_IsString(why) && strstr(why->valuestring, "2 samples per tetrahedron"));
    CHECK(!cJSON_GetObjectItemCaseSensitive(tet, "tip_uz"));
  } else {
    fprintf(stderr, "stdout: %.400s\nstderr: %.400s\n", result.out, result.err);
  }
  cJSON_Delete(rows);
  FILE *f = fopen(csv, "r");
  CHECK(f != NULL);
  if (f) {
    char header[4096], line[4096];
    CHECK(fgets(header, sizeof header, f) && strstr(header, ",error\n"));
    const int width = csv_fields(header);
    int lines = 0, failed = 0;
    for (; fgets(line, sizeof line, f); ++lines) {
      CHECK(csv_fields(line) == width);
      failed += strstr(line, "samples per tetrahedron") != NULL && !strncmp(line, "tet,6x2x2,", 10);
    }
    CHECK(lines == 2 && failed == 1);
    fclose(f);
  }
}

static void check_cantilever(const char *fascia, const char *err) {
  CHECK(cli_exec(fascia, "bench cantilever --frames 6x2x2 --json --threads 1 --no-calculix", err, &result));
  CHECK(result.status == 0);
  cJSON *rows = cJSON_Parse(result.out);
  CHECK(cJSON_IsArray(rows) && cJSON_GetArraySize(rows) == 1);
  const cJSON *row = cJSON_GetArrayItem(rows, 0);
  static const char *const keys[] = {"frames", "samples", "neighbours", "tip_ux", "tip_uz", "error_uz_percent",
                                     "twist_rad", "newton_iterations", "cg_iterations", "ms", "converged"};
  if (row) {
    check_keys(row, keys, sizeof keys / sizeof keys[0]);
    const cJSON *uz = cJSON_GetObjectItemCaseSensitive(row, "tip_uz");
    const cJSON *e = cJSON_GetObjectItemCaseSensitive(row, "error_uz_percent");
    CHECK(cJSON_IsNumber(uz) && uz->valuedouble < -1);
    // the error is (uz - ref) / |ref| in per cent, ref the stored CalculiX reference
    const fascia_scene_beam_def beam = fascia_scene_beam_def_default();
    const double ref = fascia_ccx_reference_find(&beam)->tip_uz;
    if (cJSON_IsNumber(uz) && cJSON_IsNumber(e))
      CHECK_NEAR(e->valuedouble, 100 * (uz->valuedouble - ref) / fabs(ref), 1e-9, 1e-9);
    CHECK(cJSON_IsNull(cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(row, "calculix"), "C3D8I")));
    CHECK(cJSON_GetObjectItemCaseSensitive(row, "frames")->valueint == 24);
  } else {
    fprintf(stderr, "stdout: %.400s\nstderr: %.400s\n", result.out, result.err);
  }
  cJSON_Delete(rows);
  CHECK(cli_exec(fascia, "bench cantilever --shapes tet --frames 20x3x3 --modes on,off --json --threads 1 --no-calculix",
                 err, &result));
  CHECK(result.status == 0);
  rows = cJSON_Parse(result.out);
  CHECK(cJSON_IsArray(rows) && cJSON_GetArraySize(rows) == 2);
  const cJSON *with = cJSON_GetArrayItem(rows, 0), *without = cJSON_GetArrayItem(rows, 1);
  if (with && without) {
    CHECK(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(with, "enhanced_modes")));
    CHECK(cJSON_IsFalse(cJSON_GetObjectItemCaseSensitive(without, "enhanced_modes")));
    const cJSON *a = cJSON_GetObjectItemCaseSensitive(with, "error_uz_percent");
    const cJSON *b = cJSON_GetObjectItemCaseSensitive(without, "error_uz_percent");
    CHECK(cJSON_IsNumber(a) && cJSON_IsNumber(b) && fabs(a->valuedouble) < 1 && b->valuedouble > 5);
  }
  cJSON_Delete(rows);
  CHECK(cli_exec(fascia, "bench cantilever --shapes tet --modes on --volumetric full,cell --no-calculix", err, &result));
  CHECK(result.status == 2 && strstr(result.err, "--modes on") && result.out[0] == '\0');
}

static double number(const cJSON *row, const char *key) {
  const cJSON *x = cJSON_GetObjectItemCaseSensitive(row, key);
  return cJSON_IsNumber(x) ? x->valuedouble : NAN;
}

// 1 when text contains word, letters compared without case.
static int contains_nocase(const char *text, const char *word) {
  const size_t n = strlen(word);
  for (; *text; ++text) {
    size_t k = 0;
    while (k < n && text[k] && tolower((unsigned char)text[k]) == tolower((unsigned char)word[k])) ++k;
    if (k == n) return 1;
  }
  return 0;
}

// The smallest row of Table 3, from the scene list rather than by name.
static const char *smallest_table3_row(const char *fascia, const char *err, char *name, size_t size) {
  name[0] = '\0';
  if (!cli_exec(fascia, "bench --list", err, &result) || result.status != 0) return name;
  long fewest = -1;
  for (char *line = strtok(result.out, "\n"); line; line = strtok(NULL, "\n")) {
    char row[128];
    int table = 0, frames = 0, samples = 0;
    if (sscanf(line, " %127s %d %d %d", row, &table, &frames, &samples) == 4 && table == 3 &&
        (fewest < 0 || samples < fewest)) {
      fewest = samples;
      snprintf(name, size, "%s", row);
    }
  }
  return name;
}

static void check_device_backends(const char *fascia, const char *err) {
  char row[128], args[1024];
  smallest_table3_row(fascia, err, row, sizeof row);
  CHECK(row[0] != '\0');
  if (!row[0]) return;
  snprintf(args, sizeof args, "bench %s --backend emulated --steps 1 --repeats 1 --threads 1 --json", row);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 0);
  cJSON *rows = cJSON_Parse(result.out);
  const cJSON *r = cJSON_GetArrayItem(rows, 0);
  CHECK(cJSON_IsArray(rows) && cJSON_GetArraySize(rows) == 1);
  const cJSON *backend = cJSON_GetObjectItemCaseSensitive(r, "backend");
  const cJSON *device = cJSON_GetObjectItemCaseSensitive(r, "device");
  CHECK(cJSON_IsString(backend) && !strcmp(backend->valuestring, "emulated"));
  CHECK(cJSON_IsString(device) && device->valuestring[0] != '\0');
  const double ms = number(r, "ms_per_step"), cpu = number(r, "cpu_ms_per_step"), gpu = number(r, "paper_gpu_ms");
  CHECK(isfinite(ms) && ms > 0);
  CHECK(isfinite(cpu) && cpu > 0);
  CHECK(isfinite(gpu) && gpu > 0); // Table 3 gives a GTX 570 figure for every row
  // the ratios are of the figures beside them
  CHECK_NEAR(number(r, "paper_gpu_ratio"), gpu / ms, 1e-12, 0);
  CHECK_NEAR(number(r, "cpu_gpu_ratio"), cpu / ms, 1e-12, 0);
  CHECK(number(r, "cg_iterations_per_step") == 60); // the paper's mode on the device too
  if (!r) fprintf(stderr, "stdout: %.400s\nstderr: %.400s\n", result.out, result.err);
  cJSON_Delete(rows);

  // cuda: runs where there is a GPU, else fails naming it (no crash, no rows)
  snprintf(args, sizeof args, "bench %s --backend cuda --steps 1 --repeats 1 --threads 1 --json", row);
  CHECK(cli_exec(fascia, args, err, &result));
  if (result.status == 0) {
    rows = cJSON_Parse(result.out);
    backend = cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(rows, 0), "backend");
    CHECK(cJSON_IsString(backend) && !strcmp(backend->valuestring, "cuda"));
    cJSON_Delete(rows);
  } else {
    CHECK(result.status == 1 || result.status == 2);
    CHECK(contains_nocase(result.err, "cuda"));
    // --json: no rows, the object that says how the command ended
    cJSON *ended = cJSON_Parse(result.out);
    const cJSON *status = cJSON_GetObjectItemCaseSensitive(ended, "exit_status");
    CHECK(cJSON_IsNumber(status) && status->valueint == result.status);
    cJSON_Delete(ended);
  }
  // the device solver is matrix-free: the assembled matrix is refused as a usage error
  snprintf(args, sizeof args, "bench %s --backend emulated --assembled --steps 1 --repeats 1", row);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 2);
  CHECK(strstr(result.err, "assembled") != NULL);
  CHECK(cli_exec(fascia, "bench --backend bogus", err, &result) && result.status == 2);
  CHECK(strstr(result.err, "bogus") != NULL);
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t902_cli_bench PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1], *dir = argv[2];
  char err[2048], csv[2048];
  snprintf(err, sizeof err, "%s/t902_stderr.txt", dir);
  snprintf(csv, sizeof csv, "%s/t902_paper.csv", dir);
  check_paper(fascia, err, csv);
  check_cantilever(fascia, err);
  snprintf(csv, sizeof csv, "%s/t902_sweep.csv", dir);
  check_failed_row(fascia, err, csv);
  CHECK(cli_exec(fascia, "bench --list", err, &result) && result.status == 0);
  CHECK(strstr(result.out, "t3-s34610") != NULL);
  CHECK(strstr(result.out, "s1000000-k4") != NULL); // a large row of a million samples
  check_device_backends(fascia, err);
  CHECK(cli_exec(fascia, "bench no-such-row", err, &result) && result.status == 2);
  CHECK(strstr(result.err, "no-such-row") != NULL);
  CHECK(cli_exec(fascia, "bench paper --table 4", err, &result) && result.status == 2);
  return CHECK_RESULT();
}
