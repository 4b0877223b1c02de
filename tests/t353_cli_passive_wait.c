// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The fascia program runs OpenMP with the passive wait policy, so that its
// threads do not spin for cores a busy machine does not give them (README.md,
// "On a busy machine"), and keeps a policy the user set.
//   t353_cli_passive_wait FASCIA_BINARY
#include <stdio.h>
#include <string.h>
#include <sys/wait.h>

#include "check.h"
#include "cli_exec.h"

static cli_result result;

// `fascia info` with OMP_WAIT_POLICY unset (NULL) or set to policy
static int info(const char *fascia, const char *policy) {
  char command[8192];
  if (policy) snprintf(command, sizeof command, "OMP_WAIT_POLICY=%s '%s' info", policy, fascia);
  else snprintf(command, sizeof command, "env -u OMP_WAIT_POLICY '%s' info", fascia);
  FILE *p = popen(command, "r");
  if (!p) return 0;
  cli_read_all_(p, result.out);
  return pclose(p) == 0;
}

int main(int argc, char **argv) {
  if (argc < 2) return 2;
  CHECK(info(argv[1], NULL));
  CHECK(strstr(result.out, "openmp wait policy: PASSIVE\n") != NULL);
  CHECK(info(argv[1], "active"));
  CHECK(strstr(result.out, "openmp wait policy: active\n") != NULL);
  if (check_failures_) fprintf(stderr, "fascia info said:\n%s", result.out);
  return CHECK_RESULT();
}
