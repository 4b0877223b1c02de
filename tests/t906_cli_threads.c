// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A thread count beyond fascia's bound (1024) is refused before any work
// with exit status 2 and one line that states the bound, whether it comes
// from --threads (run, bench, prep, tradeoff) or from OMP_NUM_THREADS, which
// the OpenMP runtime may crash on. Counts inside the bound run.
// Usage: t906_cli_threads PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L

#include "check.h"
#include "cli_exec.h"

static cli_result result;

// `command` must exit 2 with one line on stderr holding "1024".
static int refused(const char *command) {
  CHECK(cli_shell(command, &result));
  if (result.status != 2 || cli_lines(result.err) != 1 || !strstr(result.err, "1024")) {
    fprintf(stderr, "%s: exit %d, stderr:\n%.800s\n", command, result.status, result.err);
    return 1;
  }
  return 0;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t906_cli_threads PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1];
  char model[1024], err[1024], command[4096];
  snprintf(model, sizeof model, "%s/t906_beam.h5", argv[2]);
  snprintf(err, sizeof err, "%s/t906_stderr.txt", argv[2]);
  snprintf(command, sizeof command, "beam --frames 6x2x2 -o '%s'", model);
  CHECK(cli_exec(fascia, command, err, &result) && result.status == 0);

  int failures = 0;
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --threads 100000", fascia, model);
  failures += refused(command);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --threads 60000", fascia, model);
  failures += refused(command);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --threads 1025", fascia, model);
  failures += refused(command);
  snprintf(command, sizeof command, "'%s' bench cantilever --steps 1 --repeats 1 --threads 100000", fascia);
  failures += refused(command);
  snprintf(command, sizeof command, "'%s' tradeoff --quick --threads 100000 --out '%s/t906_tradeoff'", fascia,
           argv[2]);
  failures += refused(command);
  snprintf(command, sizeof command, "OMP_NUM_THREADS=100000 '%s' run '%s' --steps 2", fascia, model);
  failures += refused(command);
  snprintf(command, sizeof command, "OMP_NUM_THREADS=60000 '%s' run '%s' --static", fascia, model);
  failures += refused(command);
  CHECK(failures == 0);

  // inside the bound: runs
  snprintf(command, sizeof command, "OMP_NUM_THREADS=2 '%s' run '%s' --steps 2 --threads 3", fascia, model);
  CHECK(cli_shell(command, &result) && result.status == 0);
  return CHECK_RESULT();
}
