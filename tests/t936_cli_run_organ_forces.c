// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia run` reports the tissue's force on each organ (organ_force in
// --json, start and end; a line of changes in the text). At a static
// equilibrium the organs hold the whole tissue: the forces on all organs add
// up to the tissue's weight M g (the elastic forces cancel, free frames are
// balanced), with B pulled 1 cm away from A and with gravity along two axes.
// The pull shows: B's force changes, and A's opposes it.
// Usage: t936_cli_run_organ_forces PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <math.h>

#include "check.h"
#include "cli_exec.h"
#include "organ_fixture.h"

static cli_result result;

// The tissue's force on organ o at "start" or "end" from the JSON; 0 when absent.
static int read_force(const cJSON *root, const char *organ, const char *when, double *f) {
  const cJSON *a = cJSON_GetObjectItemCaseSensitive(
      cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(root, "organ_force"), organ), when);
  if (cJSON_GetArraySize(a) != 3) return 0;
  for (int r = 0; r < 3; ++r) f[r] = cJSON_GetArrayItem(a, r)->valuedouble;
  return 1;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t936_cli_run_organ_forces PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1];
  char dir[1024], model[1200], err[1200], args[4096];
  snprintf(dir, sizeof dir, "%s/t936", argv[2]);
  snprintf(model, sizeof model, "%s/organs.h5", dir);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  snprintf(args, sizeof args, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
  CHECK(system(args) == 0);
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1;
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  organ_fixture_def fd = organ_fixture_def_default();
  fd.kind_b = FASCIA_ORGAN_PRESCRIBED;
  fd.pull_b[0] = 0.01;
  fd.gravity[0] = 0, fd.gravity[1] = -9.81, fd.gravity[2] = 3;
  fascia_model *m = NULL;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  double weight[3] = {0, 0, 0}, mass = 0;
  for (int32_t s = 0; m && s < m->sample_count; ++s) mass += m->materials[m->sample_material[s]].density * m->sample_volume[s];
  for (int r = 0; m && r < 3; ++r) weight[r] = mass * m->gravity[r];
  char names[2][FASCIA_NAME_SIZE];
  for (int o = 0; m && o < 2; ++o) snprintf(names[o], sizeof names[o], "%s", m->organs[o].name);
  CHECK_OK(fascia_model_save(ctx, m, model), ctx);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);

  snprintf(args, sizeof args, "run '%s' --static --json --threads 1", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  cJSON *root = cJSON_Parse(result.out);
  double start[2][3], end[2][3];
  for (int o = 0; o < 2; ++o) CHECK(read_force(root, names[o], "start", start[o]) && read_force(root, names[o], "end", end[o]));
  cJSON_Delete(root);
  const double scale = sqrt(weight[0] * weight[0] + weight[1] * weight[1] + weight[2] * weight[2]);
  for (int r = 0; r < 3; ++r) CHECK_NEAR(end[0][r] + end[1][r], weight[r], 0, 1e-6 * scale);
  // B pulled along +x: the tissue pulls it back (-x) and A forward (+x), by more than the weight
  CHECK(end[1][0] - start[1][0] < -scale && end[0][0] - start[0][0] > scale);
  printf("weight (%.4g, %.4g, %.4g) N; forces on A (%.4g, %.4g, %.4g), on B (%.4g, %.4g, %.4g) N\n", weight[0],
         weight[1], weight[2], end[0][0], end[0][1], end[0][2], end[1][0], end[1][1], end[1][2]);

  // the text summary says it too
  snprintf(args, sizeof args, "run '%s' --static --threads 1", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  CHECK(strstr(result.out, "organs      the tissue's force on each organ") && strstr(result.out, names[1]));
  return CHECK_RESULT();
}
