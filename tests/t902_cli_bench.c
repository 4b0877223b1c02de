// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia bench` keeps its command-line contract: `bench ROW ... --json`
// prints one JSON array of row objects with the documented keys (Table 3
// rows with the paper's GPU time), 60 CG iterations per step as in the
// paper; `bench cantilever --json` rows carry the tip error against the
// reference; --csv writes a header row and one line per row; an unknown row
// is a usage error.
// Usage: t902_cli_bench PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <math.h>

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

static void check_cantilever(const char *fascia, const char *err) {
  CHECK(cli_exec(fascia, "bench cantilever --frames 6x2x2 --json --threads 1", err, &result));
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
    // the error is (uz - (-6.511)) / 6.511 in per cent
    if (cJSON_IsNumber(uz) && cJSON_IsNumber(e))
      CHECK_NEAR(e->valuedouble, 100 * (uz->valuedouble + 6.511) / 6.511, 1e-9, 1e-9);
    CHECK(cJSON_GetObjectItemCaseSensitive(row, "frames")->valueint == 24);
  } else {
    fprintf(stderr, "stdout: %.400s\nstderr: %.400s\n", result.out, result.err);
  }
  cJSON_Delete(rows);
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
  CHECK(cli_exec(fascia, "bench --list", err, &result) && result.status == 0);
  CHECK(strstr(result.out, "t3-s34610") != NULL);
  CHECK(cli_exec(fascia, "bench no-such-row", err, &result) && result.status == 2);
  CHECK(strstr(result.err, "no-such-row") != NULL);
  CHECK(cli_exec(fascia, "bench paper --table 4", err, &result) && result.status == 2);
  return CHECK_RESULT();
}
