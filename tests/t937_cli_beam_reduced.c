// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia beam --shape strand --frames 20` and `--shape sheet --frames 20x3`
// write the 1-D and 2-D cantilevers (20 frames, 2 neighbours a sample; 60
// frames, 4), volume 16 m^3 and mass 5 kg; a grid of the wrong dimension for
// the shape, patches or enhanced modes on a strand are usage errors naming
// the option; `fascia bench cantilever --shapes strand,sheet --frames
// 20x3x3` runs a strand 20 and a sheet 20x3 (the grid's leading counts) and
// reports them within 1 % of the reference.
// Usage: t937_cli_beam_reduced PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>

#include "check.h"
#include "cli_exec.h"

static cli_result result;

static void check_beam(const char *fascia, const char *err, const char *dir, const char *options, int frames,
                       int neighbours) {
  char args[4096];
  snprintf(args, sizeof args, "beam %s -o '%s/t937_beam.h5' --json", options, dir);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 0);
  cJSON *o = cJSON_Parse(result.out);
  CHECK(o != NULL);
  if (!o) {
    fprintf(stderr, "%s: stdout %.300s stderr %.300s\n", options, result.out, result.err);
    return;
  }
  CHECK(cJSON_GetObjectItem(o, "frames") && cJSON_GetObjectItem(o, "frames")->valuedouble == frames);
  CHECK(cJSON_GetObjectItem(o, "neighbours") && cJSON_GetObjectItem(o, "neighbours")->valuedouble == neighbours);
  CHECK_NEAR(cJSON_GetObjectItem(o, "volume")->valuedouble, 16, 1e-12, 0);
  CHECK_NEAR(cJSON_GetObjectItem(o, "mass")->valuedouble, 5, 1e-12, 0);
  cJSON_Delete(o);
}

static void check_refused(const char *fascia, const char *err, const char *dir, const char *options,
                          const char *says) {
  char args[4096];
  snprintf(args, sizeof args, "beam %s -o '%s/t937_bad.h5'", options, dir);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 2);
  CHECK(strstr(result.err, says) != NULL);
  CHECK(cli_lines(result.err) == 1);
  if (result.status != 2 || !strstr(result.err, says)) fprintf(stderr, "%s: stderr %.300s\n", options, result.err);
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t937_cli_beam_reduced PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1], *dir = argv[2];
  char err[2048];
  snprintf(err, sizeof err, "%s/t937_stderr.txt", dir);
  check_beam(fascia, err, dir, "--shape strand --frames 20", 20, 2);
  check_beam(fascia, err, dir, "--shape strand", 20, 2);
  check_beam(fascia, err, dir, "--shape sheet --frames 20x3", 60, 4);
  check_beam(fascia, err, dir, "--frames 20x3 --shape sheet --section-points 3", 60, 4);
  check_refused(fascia, err, dir, "--shape strand --frames 20x3x3", "--frames");
  check_refused(fascia, err, dir, "--shape sheet --frames 20", "--frames");
  check_refused(fascia, err, dir, "--frames 20", "--frames");
  check_refused(fascia, err, dir, "--shape strand --volumetric cell", "volumetric");
  check_refused(fascia, err, dir, "--shape sheet --modes on", "modes");
  check_refused(fascia, err, dir, "--shape strand --section-points 5", "section points");

  CHECK(cli_exec(fascia, "bench cantilever --shapes strand,sheet --frames 20x3x3 --no-calculix --json --threads 1",
                 err, &result));
  CHECK(result.status == 0);
  cJSON *rows = cJSON_Parse(result.out);
  CHECK(cJSON_IsArray(rows) && cJSON_GetArraySize(rows) == 2);
  if (cJSON_IsArray(rows) && cJSON_GetArraySize(rows) == 2) {
    static const char *const shapes[2] = {"strand", "sheet"}, *const grids[2] = {"20", "20x3"};
    for (int k = 0; k < 2; ++k) {
      const cJSON *row = cJSON_GetArrayItem(rows, k);
      const cJSON *shape = cJSON_GetObjectItem(row, "shape"), *grid = cJSON_GetObjectItem(row, "grid");
      const cJSON *error = cJSON_GetObjectItem(row, "error_uz_percent");
      CHECK(cJSON_IsString(shape) && !strcmp(shape->valuestring, shapes[k]));
      CHECK(cJSON_IsString(grid) && !strcmp(grid->valuestring, grids[k]));
      CHECK(cJSON_IsNumber(error) && fabs(error->valuedouble) < 1);
    }
  } else {
    fprintf(stderr, "bench: stdout %.400s stderr %.400s\n", result.out, result.err);
  }
  cJSON_Delete(rows);
  return CHECK_RESULT();
}
