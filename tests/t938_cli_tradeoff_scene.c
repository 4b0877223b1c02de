// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia tradeoff SCENE.json` on tiny ladders of two shipped scenes:
// every planned row is there, the finest row's error is 0, each row's
// largest organ-force error is what its own forces and the reference's give,
// a rung that cannot be prepared is reported in its rows while the others
// run, the recommendation respects --budget (none fits: exit 1, no model
// written), a finest rung that moved beyond the target since the rung
// before it is said to be unsettled, a finest rung whose frames are farther
// apart than half the layers is said to be so with the factor that reaches
// them, -o writes a model `fascia inspect` reads, a scene whose tissue is
// held exactly still gets its tetrahedral rows, bad arguments are refused
// with one line and exit 2.
// Usage: t938_cli_tradeoff_scene PATH/TO/fascia WORK_DIR SCENE.json SHELL-SCENE.json
#define _POSIX_C_SOURCE 200809L
#include <math.h>

#include "check.h"
#include "scene_copy.h"

static cli_result result;

static double number(const cJSON *o, const char *key) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
  return cJSON_IsNumber(v) ? v->valuedouble : NAN;
}

static int flag(const cJSON *o, const char *key) { return cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(o, key)); }

static double norm3(const double *v) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// Organ g's force of a row into f; 0 when absent.
static int organ_force(const cJSON *row, int g, double f[3]) {
  const cJSON *organ = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(row, "organs"), g);
  const cJSON *a = cJSON_GetObjectItemCaseSensitive(organ, "force");
  if (cJSON_GetArraySize(a) != 3) return 0;
  for (int c = 0; c < 3; ++c) f[c] = cJSON_GetArrayItem(a, c)->valuedouble;
  return 1;
}

// The row's largest organ-force error recomputed from the forces: each
// organ's difference in % of the reference's force, or of 1 % of the
// largest reference force where an organ's is smaller (docs/cli.md).
static double recomputed_error(const cJSON *row, const cJSON *ref) {
  const int organs = cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(ref, "organs"));
  double largest = 0, top = 0, f[3], r[3];
  for (int g = 0; g < organs; ++g)
    if (organ_force(ref, g, r)) largest = fmax(largest, norm3(r));
  for (int g = 0; g < organs; ++g) {
    if (!organ_force(row, g, f) || !organ_force(ref, g, r)) return NAN;
    const double d[3] = {f[0] - r[0], f[1] - r[1], f[2] - r[2]};
    top = fmax(top, 100 * norm3(d) / fmax(norm3(r), 0.01 * largest));
  }
  return top;
}

// Every tissue held by the organs' whole surfaces ("attachment": "exact").
static void hold_exactly(cJSON *scene, void *arg) {
  (void)arg;
  cJSON *item;
  cJSON_ArrayForEach(item, cJSON_GetObjectItemCaseSensitive(scene, "tissues"))
    cJSON_AddStringToObject(item, "attachment", "exact");
}

int main(int argc, char **argv) {
  if (argc < 5) {
    fprintf(stderr, "usage: t938_cli_tradeoff_scene PATH/TO/fascia WORK_DIR SCENE.json SHELL-SCENE.json\n");
    return 1;
  }
#ifndef FASCIA_HAVE_PREP
  printf("skipped: the prep stage was not built\n");
  return 77;
#endif
  const char *fascia = argv[1], *scene = argv[3], *shells = argv[4];
  char dir[1024], err[1200], model[1200], args[4096];
  snprintf(dir, sizeof dir, "%s/t938", argv[2]);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  snprintf(model, sizeof model, "%s/recommended.h5", dir);
  snprintf(args, sizeof args, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
  CHECK(system(args) == 0);

  snprintf(args, sizeof args,
           "tradeoff '%s' --ladder 1.4,1 --kinds scene --presets default,interactive --steps 10 --repeats 1 "
           "--threads 1 --budget 1000 --out '%s' -o '%s' --json --no-plot",
           scene, dir, model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  if (result.status != 0) fprintf(stderr, "%s\n", result.err);
  cJSON *rows = cJSON_Parse(result.out);
  CHECK(cJSON_IsArray(rows));
  // 2 rungs x 2 presets, the one tissue one rung coarser, the base drawn with another seed
  CHECK(cJSON_GetArraySize(rows) == 6);
  const cJSON *ref = NULL, *best = NULL, *row;
  int failed = 0, ladder = 0, tissue = 0, seed = 0;
  cJSON_ArrayForEach(row, rows) {
    const cJSON *error = cJSON_GetObjectItemCaseSensitive(row, "error");
    const char *group = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(row, "group"));
    ladder += group && !strcmp(group, "ladder"), tissue += group && !strcmp(group, "tissue");
    seed += group && !strcmp(group, "seed");
    if (cJSON_IsString(error)) {
      ++failed;
      continue;
    }
    if (flag(row, "reference")) ref = row;
    if (flag(row, "recommended")) best = row;
  }
  CHECK(failed == 0 && ladder == 4 && tissue == 1 && seed == 1);
  CHECK(ref != NULL && best != NULL);
  if (ref && best) {
    CHECK(number(ref, "factor") == 1 && number(ref, "force_error_percent") == 0);
    const double budget_ms = 1000;
    CHECK(number(best, "ms_per_step") <= budget_ms);
    // the recommendation: no row within the budget is more accurate
    cJSON_ArrayForEach(row, rows) {
      if (cJSON_IsString(cJSON_GetObjectItemCaseSensitive(row, "error"))) continue;
      if (number(row, "ms_per_step") <= budget_ms)
        CHECK(number(row, "force_error_percent") >= number(best, "force_error_percent"));
    }
    // every error is computed against the reference's forces
    cJSON_ArrayForEach(row, rows) {
      if (cJSON_IsString(cJSON_GetObjectItemCaseSensitive(row, "error"))) continue;
      const double e = number(row, "force_error_percent");
      CHECK_NEAR(recomputed_error(row, ref), e, 1e-6, 1e-9);
    }
  }
  // the finest rung's own movement: the rung before it, of its preset, is
  // said to leave it unsettled exactly when it is beyond the 5 % target
  const cJSON *before = NULL;
  const char *ref_preset = ref ? cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(ref, "preset")) : NULL;
  cJSON_ArrayForEach(row, rows) {
    const char *group = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(row, "group"));
    const char *preset = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(row, "preset"));
    if (group && !strcmp(group, "ladder") && number(row, "factor") == 1.4 && preset && ref_preset &&
        !strcmp(preset, ref_preset))
      before = row;
  }
  CHECK(before != NULL);
  if (before)
    CHECK((strstr(result.err, "has not settled") != NULL) == (number(before, "force_error_percent") > 5));
  cJSON_Delete(rows);
  CHECK(cli_file_exists(model));
  snprintf(args, sizeof args, "%s/tradeoff-scene.csv", dir);
  CHECK(cli_file_exists(args));
  snprintf(args, sizeof args, "inspect '%s' --json", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);

  // a rung that cannot be prepared (the shell's wall as thick as its frames are
  // apart at x0.5) is reported in its row, and the other rung still runs
  snprintf(args, sizeof args,
           "tradeoff '%s' --ladder 1,0.5 --kinds scene --presets interactive --no-tissues --steps 5 --repeats 1 "
           "--threads 1 --out '%s' --json --no-plot",
           shells, dir);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  rows = cJSON_Parse(result.out);
  CHECK(cJSON_GetArraySize(rows) == 2);
  const cJSON *coarse = cJSON_GetArrayItem(rows, 0), *fine = cJSON_GetArrayItem(rows, 1);
  CHECK(number(coarse, "factor") == 1 && cJSON_IsNull(cJSON_GetObjectItemCaseSensitive(coarse, "error")));
  const char *why = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(fine, "error"));
  CHECK(number(fine, "factor") == 0.5 && why && strstr(why, "prep: ") && strstr(why, "thickness"));
  cJSON_Delete(rows);

  // the tissue held exactly: its tetrahedral rung drops the attachment, which
  // only MLS weights have, rather than failing to prepare
  char exact[1200];
  snprintf(exact, sizeof exact, "%s/exact.json", dir);
  CHECK(scene_copy(scene, exact, hold_exactly, NULL));
  snprintf(args, sizeof args,
           "tradeoff '%s' --ladder 1 --kinds scene,tet --presets interactive --no-tissues --steps 3 --repeats 1 "
           "--threads 1 --out '%s' --json --no-plot",
           exact, dir);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  rows = cJSON_Parse(result.out);
  CHECK(cJSON_GetArraySize(rows) == 2);
  cJSON_ArrayForEach(row, rows) {
    const cJSON *error = cJSON_GetObjectItemCaseSensitive(row, "error");
    CHECK(cJSON_IsNull(error));
    if (!cJSON_IsNull(error)) fprintf(stderr, "%s\n", cJSON_GetStringValue(error));
  }
  cJSON_Delete(rows);

  // under a target no two rungs meet (0.001 %) the finest rung is said to be
  // unsettled, with the rung before it and a finer factor to add
  snprintf(args, sizeof args,
           "tradeoff '%s' --ladder 1.4,1 --kinds scene --presets interactive --no-tissues --steps 3 --repeats 1 "
           "--threads 1 --error 0.001 --out '%s' --no-plot",
           scene, dir);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(strstr(result.out, "has not settled") && strstr(result.out, "x1.4 scene, interactive") &&
        strstr(result.out, "--ladder ...,0.7"));
  // its finest rung's frames (3.5 mm) are within half the demo's layers: no word on them
  CHECK(strstr(result.out, "half the layers") == NULL);

  // frames twice the demo's (7 mm) are farther apart than half its layers:
  // the report names the tissue and the largest factor (to 0.01) that
  // brings the frames within half a layer
  snprintf(args, sizeof args,
           "tradeoff '%s' --ladder 2 --kinds scene --presets interactive --no-tissues --steps 3 --repeats 1 "
           "--threads 1 --out '%s' --no-plot",
           scene, dir);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  const char *layers = strstr(result.out, "half the layers of its tissue vesicouterine (frames 7 mm apart");
  double half_mm = 0, factor = 0;
  const char *at = layers ? strstr(layers, "half a layer ") : NULL;
  const char *rung_at = layers ? strstr(layers, "a rung at x") : NULL;
  CHECK(at && sscanf(at, "half a layer %lf mm", &half_mm) == 1);
  CHECK(rung_at && sscanf(rung_at, "a rung at x%lf", &factor) == 1);
  CHECK(half_mm > 3.5 && half_mm < 7 && factor * 3.5 <= half_mm * (1 + 1e-3) && (factor + 0.01) * 3.5 > half_mm);
  if (!layers || !(factor * 3.5 <= half_mm * (1 + 1e-3))) fprintf(stderr, "%s\n", result.out);

  // a budget no row meets: exit 1 saying so, no model written
  char none[1200];
  snprintf(none, sizeof none, "%s/none.h5", dir);
  snprintf(args, sizeof args,
           "tradeoff '%s' --ladder 1 --kinds scene --presets interactive --no-tissues --steps 5 --repeats 1 "
           "--threads 1 --budget 0.000001 --out '%s' -o '%s' --no-plot",
           scene, dir, none);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 1);
  CHECK(strstr(result.err, "no row") && strstr(result.err, "--budget"));
  CHECK(!cli_file_exists(none));

  // bad arguments: one line, exit 2, nothing prepared
  static const char *const bad[] = {"--budget -1", "--budget 5 --error 5", "--ladder 1,1.4", "--presets fast",
                                    "--kinds hex", "--steps 0", "extra.json", "--frobnicate"};
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    snprintf(args, sizeof args, "tradeoff '%s' %s --out '%s'", scene, bad[k], dir);
    CHECK(cli_exec(fascia, args, err, &result) && result.status == 2);
    CHECK(cli_lines(result.err) == 1 && strstr(result.err, "fascia tradeoff: "));
    if (result.status != 2 || cli_lines(result.err) != 1) fprintf(stderr, "'%s': %s\n", bad[k], result.err);
  }
  snprintf(args, sizeof args, "tradeoff '%s/missing.json' --out '%s'", dir, dir);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 1 && cli_lines(result.err) == 1);
  return CHECK_RESULT();
}
