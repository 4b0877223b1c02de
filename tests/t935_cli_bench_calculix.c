// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia bench cantilever` where ccx is installed: beside each row the
// fastest CalculiX mesh (C3D8I and C3D20R) at least as accurate as the row,
// solved in the same run, with its mesh, error and time; the text output
// prints both times side by side. No time is checked (no timed tests).
// Skipped without ccx.
// Usage: t935_cli_bench_calculix PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <string.h>

#include "beam_calculix.h"
#include "check.h"
#include "cli_exec.h"

static cli_result result;

int main(int argc, char **argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: t935_cli_bench_calculix PATH/TO/fascia WORK_DIR\n");
    return 2;
  }
  if (!fascia_ccx_program()) {
    printf("skipped: CalculiX (ccx) is not installed (apt-get install calculix-ccx)\n");
    return TEST_SKIP;
  }
  const char *fascia = argv[1];
  char err[1024];
  snprintf(err, sizeof err, "%s/t935.err", argv[2]);
  CHECK(cli_exec(fascia, "bench cantilever --frames 10x2x2 --json --threads 1", err, &result));
  CHECK(result.status == 0);
  cJSON *rows = cJSON_Parse(result.out);
  CHECK(cJSON_IsArray(rows) && cJSON_GetArraySize(rows) == 1);
  const cJSON *row = cJSON_GetArrayItem(rows, 0);
  const cJSON *peers = cJSON_GetObjectItemCaseSensitive(row, "calculix");
  const double row_error = cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(row, "error_uz_percent"));
  const fascia_scene_beam_def beam = fascia_scene_beam_def_default();
  const double ref = fascia_ccx_reference_find(&beam)->tip_uz;
  for (int e = 0; e < FASCIA_CCX_ELEMENT_COUNT_; ++e) {
    const cJSON *p = cJSON_GetObjectItemCaseSensitive(peers, fascia_ccx_element_name(e));
    CHECK(cJSON_IsObject(p)); // 10x2x2 is 15 % off: the first mesh of each ladder is more accurate
    if (!cJSON_IsObject(p)) continue;
    const double uz = cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(p, "tip_uz"));
    const double error = cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(p, "error_uz_percent"));
    CHECK_NEAR(error, 100 * (uz - ref) / fabs(ref), 1e-9, 1e-9);
    CHECK(fabs(error) <= fabs(row_error));
    CHECK(fabs(error) < 3); // the coarsest graded meshes of the ladders are within 3 %
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(p, "ms")) > 0);
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(p, "dofs")) > 0);
    CHECK(cJSON_IsString(cJSON_GetObjectItemCaseSensitive(p, "mesh")));
  }
  cJSON_Delete(rows);
  // the text: CalculiX's ladder and the side-by-side table
  CHECK(cli_exec(fascia, "bench cantilever --frames 10x2x2 --threads 1", err, &result));
  CHECK(result.status == 0);
  CHECK(strstr(result.out, "CalculiX (") != NULL);
  CHECK(strstr(result.out, "time to the same error") != NULL);
  CHECK(strstr(result.out, "C3D8I") != NULL && strstr(result.out, "C3D20R") != NULL);
  if (check_failures_) fprintf(stderr, "stdout: %.2000s\nstderr: %.400s\n", result.out, result.err);
  return CHECK_RESULT();
}
