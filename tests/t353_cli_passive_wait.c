// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The fascia program runs OpenMP with the passive wait policy, so that its
// threads do not spin for cores a busy machine does not give them (README.md,
// "On a busy machine") after a short spin, and keeps a policy or a spin
// count the user set; OpenBLAS starts no spinning workers
// (OPENBLAS_NUM_THREADS=1, the direct solver's one BLAS thread) unless the
// user set a count.
//   t353_cli_passive_wait FASCIA_BINARY
#include <stdio.h>
#include <string.h>
#include <sys/wait.h>

#include "check.h"
#include "cli_exec.h"

static cli_result result;

// `fascia info` with the environment settings in env (e.g. "OMP_WAIT_POLICY=active"),
// OMP_WAIT_POLICY, GOMP_SPINCOUNT and OPENBLAS_NUM_THREADS unset otherwise
static int info(const char *fascia, const char *env) {
  char command[8192];
  snprintf(command, sizeof command, "env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT -u OPENBLAS_NUM_THREADS %s '%s' info", env, fascia);
  FILE *p = popen(command, "r");
  if (!p) return 0;
  cli_read_all_(p, result.out);
  return pclose(p) == 0;
}

int main(int argc, char **argv) {
  if (argc < 2) return 2;
  CHECK(info(argv[1], ""));
  CHECK(strstr(result.out, "openmp wait policy: PASSIVE\n") != NULL);
  CHECK(strstr(result.out, "openmp spin count: 3000\n") != NULL);
  CHECK(strstr(result.out, "openblas threads: 1\n") != NULL);
  CHECK(info(argv[1], "OMP_WAIT_POLICY=active"));
  CHECK(strstr(result.out, "openmp wait policy: active\n") != NULL);
  CHECK(strstr(result.out, "openmp spin count: the runtime's default\n") != NULL);
  CHECK(strstr(result.out, "openblas threads: 1\n") != NULL); // set even where the OpenMP ones are the user's
  CHECK(info(argv[1], "OPENBLAS_NUM_THREADS=2"));
  CHECK(strstr(result.out, "openblas threads: 2\n") != NULL);
  CHECK(strstr(result.out, "openmp wait policy: PASSIVE\n") != NULL);
  CHECK(info(argv[1], "GOMP_SPINCOUNT=0"));
  CHECK(strstr(result.out, "openmp wait policy: the runtime's default\n") != NULL);
  CHECK(strstr(result.out, "openmp spin count: 0\n") != NULL);
  if (check_failures_) fprintf(stderr, "fascia info said:\n%s", result.out);
  return CHECK_RESULT();
}
