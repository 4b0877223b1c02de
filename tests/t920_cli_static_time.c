// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia run --static` on a model whose organ B is prescribed to move 5 mm
// along x by t = 1 s (A fixed, no gravity): the equilibrium is for the end of
// the motion by default (the tissue near B nearly 5 mm along), for the time
// --static-time gives (half of that at 0.5 s), and the output says which. A model
// file with a piece of tissue held by nothing is refused: exit 1, the message
// names the file and the piece, and no results file is written.
// Usage: t920_cli_static_time PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <hdf5.h>
#include <unistd.h>

#include "check.h"
#include "cli_exec.h"
#include "organ_fixture.h"

static cli_result result;

// Largest sample displacement of `fascia run MODEL ARGS --json`, -1 on failure.
static double max_displacement(const char *fascia, const char *model, const char *args, const char *err,
                               double *time, char *why, size_t why_size) {
  char line[4096];
  snprintf(line, sizeof line, "run '%s' --threads 1 --json %s", model, args);
  if (!cli_exec(fascia, line, err, &result) || result.status != 0) {
    fprintf(stderr, "fascia %s: exit %d: %s\n", line, result.status, result.err);
    return -1;
  }
  cJSON *root = cJSON_Parse(result.out);
  const cJSON *d = cJSON_GetObjectItem(cJSON_GetObjectItem(root, "displacement"), "max");
  const cJSON *t = cJSON_GetObjectItem(root, "static_time"), *w = cJSON_GetObjectItem(root, "static_time_of");
  const double u = cJSON_IsNumber(d) ? d->valuedouble : -1;
  *time = cJSON_IsNumber(t) ? t->valuedouble : -1;
  snprintf(why, why_size, "%s", cJSON_IsString(w) ? w->valuestring : "");
  cJSON_Delete(root);
  return u;
}

int main(int argc, char **argv) {
  CHECK(argc == 3);
  const char *fascia = argv[1];
  char model[1024], loose[1024], err[1024], results[1024], why[128];
  snprintf(model, sizeof model, "%s/t920_model.h5", argv[2]);
  snprintf(loose, sizeof loose, "%s/t920_loose.h5", argv[2]);
  snprintf(err, sizeof err, "%s/t920_err.txt", argv[2]);
  snprintf(results, sizeof results, "%s/t920_results.h5", argv[2]);
  fascia_ctx_def cdef = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  CHECK(fascia_ctx_create(&cdef, &ctx) == FASCIA_OK);
  organ_fixture_def def = organ_fixture_def_default();
  def.kind_b = FASCIA_ORGAN_PRESCRIBED;
  def.pull_b[0] = 0.005;
  fascia_model *m = NULL;
  CHECK_OK(organ_fixture_build(ctx, &def, &m), ctx);
  CHECK_OK(fascia_model_save(ctx, m, model), ctx);

  double t = 0;
  const double u_end = max_displacement(fascia, model, "--static", err, &t, why, sizeof why);
  fprintf(stderr, "default: max displacement %g m at t = %g s (%s)\n", u_end, t, why);
  // samples sit inside the tissue, short of B's face: most of B's 5 mm
  CHECK(u_end > 0.004 && u_end <= 0.005 + 1e-9);
  CHECK(t == 1 && strstr(why, "end of the prescribed motions"));
  const double u_half = max_displacement(fascia, model, "--static-time 0.5", err, &t, why, sizeof why);
  fprintf(stderr, "--static-time 0.5: max displacement %g m at t = %g s (%s)\n", u_half, t, why);
  CHECK_NEAR(u_half / u_end, 0.5, 1e-2, 0); // half the pull, nearly linear at these strains
  CHECK(t == 0.5 && strstr(why, "--static-time"));
  // the text summary says it too
  char line[4096];
  snprintf(line, sizeof line, "run '%s' --threads 1", model);
  CHECK(cli_exec(fascia, line, err, &result) && result.status == 0);
  CHECK(strstr(result.out, "static equilibrium at t = 1 s (the end of the prescribed motions)"));
  snprintf(line, sizeof line, "run '%s' --steps 2 --static-time 1", model);
  CHECK(cli_exec(fascia, line, err, &result) && result.status == 2);

  // a loose lump: the tissue cut off from both organs, written with
  // allow_floating and the attribute then removed, as an older prep would
  // have left it
  fascia_model_destroy(&m);
  def.cut = 1;
  def.kind_b = FASCIA_ORGAN_FIXED;
  CHECK_OK(organ_fixture_build(ctx, &def, &m), ctx);
  // the tissue left (x up to L/3) hangs on A's frames: free them and drop
  // the coupling, so that nothing holds it
  for (int32_t i = 0; i < m->frame_count; ++i) m->frame_kind[i] = FASCIA_FRAME_FREE;
  m->coupling_count = 0;
  m->allow_floating = 1;
  m->gravity[2] = -9.81;
  CHECK_OK(fascia_model_save(ctx, m, loose), ctx);
  hid_t f = H5Fopen(loose, H5F_ACC_RDWR, H5P_DEFAULT);
  CHECK(f >= 0 && H5Adelete_by_name(f, "/", "allow_floating", H5P_DEFAULT) >= 0);
  H5Fclose(f);
  remove(results);
  snprintf(line, sizeof line, "run '%s' --threads 1 --steps 3 -o '%s'", loose, results);
  CHECK(cli_exec(fascia, line, err, &result));
  fprintf(stderr, "loose lump: exit %d: %s", result.status, result.err);
  CHECK(result.status == 1);
  CHECK(strstr(result.err, "t920_loose.h5") && strstr(result.err, "held by nothing") && strstr(result.err, "cm^3"));
  CHECK(access(results, F_OK) != 0);
  snprintf(line, sizeof line, "run '%s' --threads 1 --static", loose);
  CHECK(cli_exec(fascia, line, err, &result) && result.status == 1);

  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  remove(model), remove(loose), remove(err), remove(results);
  return check_failures_ != 0;
}
