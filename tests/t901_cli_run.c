// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia run` keeps its command-line contract: on a small beam the static
// --json output is one JSON object whose tip probe sags (finite, negative z)
// with the documented keys; a missing model exits 1 naming the file; unknown
// or conflicting options exit 2 naming the option; a dynamic run with -o
// writes the results file and its XDMF sidecar; --backend emulated runs the
// device solver in host loops and says so; an unknown backend is a usage error.
// With --json, stdout holds one JSON object, valid UTF-8, that says how the
// run ended whatever happened: a run whose second step fails says "failed"
// and not converged, one that fails at its first step still prints its
// object, a usage error or a model that cannot be read prints
// {"command", "exit_status", "error"}; a model path that is not UTF-8 is
// printed with U+FFFD in its place; the text summary of a failed static
// solve says FAILED. Options given twice, or options that contradict each
// other, are refused naming both.
// Usage: t901_cli_run PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <math.h>

#include "check.h"
#include "cli_exec.h"

static cli_result result;

static int check_static_json(const char *fascia, const char *model, const char *err) {
  char args[4096];
  snprintf(args, sizeof args, "run '%s' --static --json --threads 1", model);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 0);
  cJSON *root = cJSON_Parse(result.out);
  CHECK(cJSON_IsObject(root));
  if (!cJSON_IsObject(root)) {
    fprintf(stderr, "stdout: %.400s\nstderr: %.400s\n", result.out, result.err);
    cJSON_Delete(root);
    return 1;
  }
  static const char *const keys[] = {"probes", "ms_per_step", "newton_iterations", "cg_iterations",
                                     "factorizations", "newton_iterations_per_step", "cg_iterations_per_step", "converged",
                                     "backend", "device", "steps", "time", "energy"};
  for (size_t k = 0; k < sizeof keys / sizeof keys[0]; ++k)
    if (!cJSON_GetObjectItemCaseSensitive(root, keys[k])) {
      fprintf(stderr, "missing key '%s'\n", keys[k]);
      CHECK(0);
    }
  CHECK(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(root, "converged")));
  const cJSON *backend = cJSON_GetObjectItemCaseSensitive(root, "backend");
  CHECK(cJSON_IsString(backend) && !strcmp(backend->valuestring, "cpu"));
  const cJSON *ms = cJSON_GetObjectItemCaseSensitive(root, "ms_per_step");
  CHECK(cJSON_IsNumber(ms) && ms->valuedouble > 0);
  const cJSON *newton = cJSON_GetObjectItemCaseSensitive(root, "newton_iterations");
  CHECK(cJSON_IsNumber(newton) && newton->valueint >= 1);
  // the direct solver factors at most once per Newton iteration (chord steps: fewer)
  const cJSON *factorizations = cJSON_GetObjectItemCaseSensitive(root, "factorizations");
  CHECK(cJSON_IsNumber(factorizations) && factorizations->valueint <= newton->valueint);
  const cJSON *tip = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(root, "probes"), "tip");
  const cJSON *u = cJSON_GetObjectItemCaseSensitive(tip, "displacement");
  const cJSON *x = cJSON_GetObjectItemCaseSensitive(tip, "position");
  CHECK(cJSON_IsArray(u) && cJSON_GetArraySize(u) == 3);
  CHECK(cJSON_IsArray(x) && cJSON_GetArraySize(x) == 3);
  if (cJSON_GetArraySize(u) == 3 && cJSON_GetArraySize(x) == 3) {
    const double uz = cJSON_GetArrayItem(u, 2)->valuedouble;
    // gravity pulls the free end down; the coarse beam is stiff, but a 16 m
    // beam of E = 40 kPa under its weight sags by metres (reference -6.5 m)
    CHECK(isfinite(uz) && uz < -1 && uz > -8);
    // position = rest (16, 0, 0) + displacement
    CHECK_NEAR(cJSON_GetArrayItem(x, 0)->valuedouble, 16 + cJSON_GetArrayItem(u, 0)->valuedouble, 0, 1e-9);
    CHECK_NEAR(cJSON_GetArrayItem(x, 2)->valuedouble, uz, 0, 1e-9);
  }
  cJSON_Delete(root);
  return 0;
}

// Every byte sequence of text is UTF-8 (no overlong forms or surrogates).
static int is_utf8(const char *text) {
  const unsigned char *s = (const unsigned char *)text;
  while (*s) {
    int n = *s < 0x80 ? 1 : *s >= 0xC2 && *s <= 0xDF ? 2 : *s >= 0xE0 && *s <= 0xEF ? 3 : *s >= 0xF0 && *s <= 0xF4 ? 4 : 0;
    if (!n) return 0;
    for (int k = 1; k < n; ++k)
      if ((s[k] & 0xC0) != 0x80) return 0;
    if ((s[0] == 0xE0 && s[1] < 0xA0) || (s[0] == 0xED && s[1] >= 0xA0) || (s[0] == 0xF0 && s[1] < 0x90) ||
        (s[0] == 0xF4 && s[1] >= 0x90))
      return 0;
    s += n;
  }
  return 1;
}

// `fascia ARGS --json`: exit status `status`, stdout one line holding one
// JSON object, valid UTF-8, whose "exit_status" is the status, with "ended"
// as given (NULL: the object need not have one) and "converged" false
// unless the run completed; the error, when the status is not 0, in it.
static int json_ending(const char *fascia, const char *args, const char *err, int status, const char *ended,
                       const char *error_part) {
  CHECK(cli_exec(fascia, args, err, &result));
  cJSON *root = cJSON_Parse(result.out);
  const cJSON *exit_status = cJSON_GetObjectItemCaseSensitive(root, "exit_status");
  const cJSON *error = cJSON_GetObjectItemCaseSensitive(root, "error");
  const cJSON *how = cJSON_GetObjectItemCaseSensitive(root, "ended");
  const cJSON *converged = cJSON_GetObjectItemCaseSensitive(root, "converged");
  const char *newline = strchr(result.out, '\n');
  const int ok = result.status == status && cJSON_IsObject(root) && is_utf8(result.out) && newline &&
                 !newline[1] && cJSON_IsNumber(exit_status) && exit_status->valueint == status &&
                 (status == 0 ? cJSON_IsNull(error)
                              : cJSON_IsString(error) && strstr(error->valuestring, error_part) != NULL) &&
                 (!ended || (cJSON_IsString(how) && !strcmp(how->valuestring, ended))) &&
                 (!ended || (cJSON_IsBool(converged) && (cJSON_IsTrue(converged) == !strcmp(ended, "completed"))));
  if (!ok) fprintf(stderr, "fascia %s: exit %d\nstdout: %.600s\nstderr: %.600s\n", args, result.status, result.out,
                   result.err);
  cJSON_Delete(root);
  return ok ? 0 : 1;
}

static int check_json_endings(const char *fascia, const char *model, const char *dir, const char *err) {
  char args[4096], odd[1024];
  int failures = 0;
  snprintf(args, sizeof args, "run '%s' --steps 3 --threads 1 --json", model);
  failures += json_ending(fascia, args, err, 0, "completed", "");
  // the second step blows up (the beam sags past a strain of 1e-4): failed, whatever the first did
  snprintf(args, sizeof args, "run '%s' --steps 6 --blow-up-strain 1e-4 --step-retries 0 --threads 1 --json", model);
  failures += json_ending(fascia, args, err, 1, "failed", "blew up");
  snprintf(args, sizeof args, "run '%s' --steps 6 --blow-up-strain 1e-6 --step-retries 0 --threads 1 --json", model);
  failures += json_ending(fascia, args, err, 1, "failed", "blew up");
  snprintf(args, sizeof args, "run '%s' --steps 2 --json --bogus", model);
  failures += json_ending(fascia, args, err, 2, NULL, "--bogus");
  snprintf(args, sizeof args, "run '%s/none.h5' --json", dir);
  failures += json_ending(fascia, args, err, 1, NULL, "none.h5");
  snprintf(args, sizeof args, "inspect '%s/none.h5' --json", dir);
  failures += json_ending(fascia, args, err, 1, NULL, "none.h5");
  // a path that is not UTF-8 (a Latin-1 file name): the JSON carries U+FFFD for its byte
  snprintf(odd, sizeof odd, "%s/caf\xe9.h5", dir);
  char copy[4096];
  snprintf(copy, sizeof copy, "cp '%s' '%s'", model, odd);
  CHECK(system(copy) == 0);
  snprintf(args, sizeof args, "run '%s' --static --threads 1 --json", odd);
  failures += json_ending(fascia, args, err, 0, "completed", "");
  CHECK(strstr(result.out, "caf\xef\xbf\xbd.h5") != NULL);
  snprintf(args, sizeof args, "inspect '%s' --json", odd);
  failures += json_ending(fascia, args, err, 0, NULL, "");
  // the text summary of a failed static solve says so, and not "converged"
  snprintf(args, sizeof args, "run '%s' --static --blow-up-strain 1e-9 --threads 1", model);
  CHECK(cli_exec(fascia, args, err, &result));
  if (result.status != 1 || !strstr(result.out, "FAILED") || strstr(result.out, "converged")) {
    fprintf(stderr, "fascia %s: exit %d, stdout: %.600s\n", args, result.status, result.out);
    ++failures;
  }
  // contradictions and repeats: exit 2, one line naming the options
  static const char *const twice[][2] = {{"--single --double", "--double"},  {"--assembled --matrix-free", "--matrix-free"},
                                         {"--steps 2 --steps 3", "--steps"}, {"--steps 2 -o a.h5 -o b.h5", "-o"},
                                         {"--steps 2 -o a.h5 --output b.h5", "--output"},
                                         {"--steps 2 --require-convergence --accept-unconverged", "--accept-unconverged"}};
  for (size_t k = 0; k < sizeof twice / sizeof twice[0]; ++k) {
    snprintf(args, sizeof args, "run '%s' %s", model, twice[k][0]);
    CHECK(cli_exec(fascia, args, err, &result));
    if (result.status != 2 || cli_lines(result.err) != 1 || !strstr(result.err, twice[k][1])) {
      fprintf(stderr, "fascia %s: exit %d, stderr: %.400s\n", args, result.status, result.err);
      ++failures;
    }
  }
  return failures;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t901_cli_run PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1], *dir = argv[2];
  char model[2048], err[2048], results[2048], xdmf[2048], missing[2048], args[8192];
  snprintf(model, sizeof model, "%s/t901_beam.h5", dir);
  snprintf(err, sizeof err, "%s/t901_stderr.txt", dir);
  snprintf(results, sizeof results, "%s/t901_r.h5", dir);
  snprintf(xdmf, sizeof xdmf, "%s/t901_r.xdmf", dir);
  snprintf(missing, sizeof missing, "%s/t901_no_such_model.h5", dir);

  // a small beam: 6 x 2 x 2 frames solve in well under a second
  snprintf(args, sizeof args, "beam --frames 6x2x2 -o '%s'", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  if (result.status != 0) {
    fprintf(stderr, "fascia beam failed: %s\n", result.err);
    return 1;
  }
  if (check_static_json(fascia, model, err)) return 1;

  // a missing model: failure (1), its name in the one-line reason
  remove(missing);
  snprintf(args, sizeof args, "run '%s' --json", missing);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 1);
  CHECK(strstr(result.err, "t901_no_such_model.h5") != NULL);
  CHECK(strstr(result.out, "\"exit_status\":1") != NULL); // --json: the object that says so (check_json_endings)

  // usage errors (2) name the option
  snprintf(args, sizeof args, "run '%s' --no-such-option", model);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 2);
  CHECK(strstr(result.err, "--no-such-option") != NULL);
  snprintf(args, sizeof args, "run '%s' --static --steps 3", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 2);
  snprintf(args, sizeof args, "run '%s' --steps 3 --dt -1", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 2);
  CHECK(strstr(result.err, "--dt") != NULL);
  // a run whose end time overflows (it had run, and reported t = inf as done)
  snprintf(args, sizeof args, "run '%s' --steps 3 --dt 1e308", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 2);
  CHECK(strstr(result.err, "--dt 1e+308") != NULL && strstr(result.err, "largest time") != NULL);
  CHECK(cli_exec(fascia, "run", err, &result) && result.status == 2);

  // a dynamic run writes the results and the XDMF sidecar
  remove(results);
  remove(xdmf);
  snprintf(args, sizeof args, "run '%s' --steps 3 --dt 0.01 -o '%s' --samples --threads 1 --json", model, results);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 0);
  CHECK(cli_file_exists(results));
  CHECK(cli_file_exists(xdmf));
  cJSON *root = cJSON_Parse(result.out);
  const cJSON *steps = cJSON_GetObjectItemCaseSensitive(root, "steps");
  const cJSON *saved = cJSON_GetObjectItemCaseSensitive(root, "saved_steps");
  const cJSON *t = cJSON_GetObjectItemCaseSensitive(root, "time");
  CHECK(cJSON_IsNumber(steps) && steps->valueint == 3);
  CHECK(cJSON_IsNumber(saved) && saved->valueint == 4); // the rest state and three steps
  CHECK(cJSON_IsNumber(t) && fabs(t->valuedouble - 0.03) < 1e-12);
  cJSON_Delete(root);

  // the device solver in host loops: a dynamic run (the device solver is CG
  // only, which the static cantilever does not converge with in few steps)
  snprintf(args, sizeof args, "run '%s' --steps 2 --backend emulated --threads 1 --json", model);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 0);
  root = cJSON_Parse(result.out);
  const cJSON *backend = cJSON_GetObjectItemCaseSensitive(root, "backend");
  const cJSON *device = cJSON_GetObjectItemCaseSensitive(root, "device");
  const cJSON *linear = cJSON_GetObjectItemCaseSensitive(root, "linear_solver");
  steps = cJSON_GetObjectItemCaseSensitive(root, "steps");
  CHECK(cJSON_IsString(backend) && !strcmp(backend->valuestring, "emulated"));
  CHECK(cJSON_IsString(device) && device->valuestring[0] != '\0');
  CHECK(cJSON_IsString(linear) && !strcmp(linear->valuestring, "cg"));
  CHECK(cJSON_IsNumber(steps) && steps->valueint == 2);
  const cJSON *product = cJSON_GetObjectItemCaseSensitive(root, "cg_product");
  CHECK(cJSON_IsString(product) && !strcmp(product->valuestring, "matrix-free")); // the device has no matrix
  if (!cJSON_IsObject(root)) fprintf(stderr, "stdout: %.400s\nstderr: %.400s\n", result.out, result.err);
  cJSON_Delete(root);
  // CG on the CPU: the assembled matrix's float copy by default, the double one when asked for
  const char *const products[][2] = {{"", "assembled float"}, {"--double", "assembled double"},
                                     {"--cg-tolerance 1e-8", "assembled double"}, {"--matrix-free", "matrix-free"}};
  for (int k = 0; k < 4; ++k) {
    snprintf(args, sizeof args, "run '%s' --steps 1 --linear-solver cg %s --threads 1 --json", model, products[k][0]);
    CHECK(cli_exec(fascia, args, err, &result));
    CHECK(result.status == 0);
    root = cJSON_Parse(result.out);
    product = cJSON_GetObjectItemCaseSensitive(root, "cg_product");
    CHECK(cJSON_IsString(product) && !strcmp(product->valuestring, products[k][1]));
    cJSON_Delete(root);
  }
  CHECK(check_json_endings(fascia, model, argv[2], err) == 0);
  snprintf(args, sizeof args, "run '%s' --steps 1 --backend bogus", model);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 2);
  CHECK(strstr(result.err, "--backend") != NULL && strstr(result.err, "bogus") != NULL);
  CHECK(result.out[0] == '\0');
  if (check_failures_) fprintf(stderr, "last stderr: %.600s\n", result.err);
  return CHECK_RESULT();
}
