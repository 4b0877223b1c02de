// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The fascia program runs OpenMP with the passive wait policy, so that its
// threads do not spin for cores a busy machine does not give them (docs/measured.md,
// "On a busy machine") after a short spin, and keeps a policy or a spin
// count the user set; OpenBLAS starts no spinning workers
// (OPENBLAS_NUM_THREADS=1, the direct solver's one BLAS thread) unless the
// user set a count. The libraries read these as they load, so the checks
// look at what they took: libgomp's own display of its settings
// (OMP_DISPLAY_ENV, the last one printed: the program's second start) and
// OpenBLAS's thread count.
//   t353_cli_passive_wait FASCIA_BINARY
#include <stdio.h>
#include <string.h>
#include <sys/wait.h>

#include "check.h"
#include "cli_exec.h"

static cli_result result;

// `fascia info` with the environment settings in env (e.g. "OMP_WAIT_POLICY=active"),
// OMP_WAIT_POLICY, GOMP_SPINCOUNT and OPENBLAS_NUM_THREADS unset otherwise;
// stdout, then libgomp's display of what it read (stderr)
static int info(const char *fascia, const char *env) {
  char command[8192];
  snprintf(command, sizeof command,
           "env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT -u OPENBLAS_NUM_THREADS OMP_DISPLAY_ENV=verbose %s '%s' info 2>&1",
           env, fascia);
  FILE *p = popen(command, "r");
  if (!p) return 0;
  cli_read_all_(p, result.out);
  return pclose(p) == 0;
}

// Whether the last "  NAME = 'VALUE'" libgomp displayed has this value.
static int runtime_took(const char *name, const char *value) {
  char key[128], expected[256];
  snprintf(key, sizeof key, "  %s = '", name);
  snprintf(expected, sizeof expected, "%s%s'", key, value);
  const char *last = NULL;
  for (const char *at = strstr(result.out, key); at; at = strstr(at + 1, key)) last = at;
  return last && !strncmp(last, expected, strlen(expected));
}

int main(int argc, char **argv) {
  if (argc < 2) return 2;
  CHECK(info(argv[1], ""));
  CHECK(strstr(result.out, "openmp wait policy: PASSIVE\n") != NULL);
  CHECK(strstr(result.out, "openmp spin count: 3000\n") != NULL);
  CHECK(strstr(result.out, "openblas threads: 1\n") != NULL);
  CHECK(runtime_took("OMP_WAIT_POLICY", "PASSIVE") && runtime_took("GOMP_SPINCOUNT", "3000"));
  CHECK(strstr(result.out, "openblas threads in use: 1\n") != NULL);
  CHECK(info(argv[1], "OMP_WAIT_POLICY=active"));
  CHECK(strstr(result.out, "openmp wait policy: active\n") != NULL);
  CHECK(strstr(result.out, "openmp spin count: the runtime's default\n") != NULL);
  CHECK(strstr(result.out, "openblas threads: 1\n") != NULL); // set even where the OpenMP ones are the user's
  CHECK(runtime_took("OMP_WAIT_POLICY", "ACTIVE") && strstr(result.out, "openblas threads in use: 1\n") != NULL);
  CHECK(info(argv[1], "OPENBLAS_NUM_THREADS=2"));
  CHECK(strstr(result.out, "openblas threads: 2\n") != NULL);
  CHECK(strstr(result.out, "openmp wait policy: PASSIVE\n") != NULL);
  CHECK(strstr(result.out, "openblas threads in use: 2\n") != NULL && runtime_took("GOMP_SPINCOUNT", "3000"));
  CHECK(info(argv[1], "GOMP_SPINCOUNT=0"));
  CHECK(strstr(result.out, "openmp wait policy: the runtime's default\n") != NULL);
  CHECK(strstr(result.out, "openmp spin count: 0\n") != NULL);
  CHECK(runtime_took("GOMP_SPINCOUNT", "0"));
  if (check_failures_) fprintf(stderr, "fascia info said:\n%s", result.out);
  return CHECK_RESULT();
}
