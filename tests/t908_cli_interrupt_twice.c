// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Two SIGINTs in quick succession (Ctrl-C twice) stop a dynamic `fascia run`
// the way one does: exit status 1 with "interrupted after step N" on stderr,
// the results file (with its XDMF sidecar), the checkpoint and the history
// written under their names, and no temporary file left. SIGTERM twice the
// same. (A handler reset by its first delivery would let the second signal
// kill the run with nothing saved.)
// Usage: t908_cli_interrupt_twice PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "cli_exec.h"

static cli_result result;

static void sleep_ms(long ms) {
  struct timespec t = {ms / 1000, (ms % 1000) * 1000000L};
  while (nanosleep(&t, &t) != 0 && errno == EINTR) {
  }
}

// One interrupted run in folder dir, stopped by two `sig`; 0 when it ended
// as documented.
// late: the second comes once the stop message is on stderr, while the run
// closes its outputs and exits (restoring the default action there would
// let a late second signal kill it).
static int interrupt_twice(const char *fascia, const char *model, const char *dir, int sig, int late) {
  char command[4096], results[1024], xdmf[1024], checkpoint[1024], history[1024], err[1024];
  snprintf(command, sizeof command, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
  CHECK(system(command) == 0);
  snprintf(results, sizeof results, "%s/r.h5", dir);
  snprintf(xdmf, sizeof xdmf, "%s/r.xdmf", dir);
  snprintf(checkpoint, sizeof checkpoint, "%s/c.h5", dir);
  snprintf(history, sizeof history, "%s/h.csv", dir);
  snprintf(err, sizeof err, "%s.stderr", dir);
  const pid_t pid = fork();
  if (pid == 0) {
    if (!freopen("/dev/null", "w", stdout) || !freopen(err, "w", stderr)) _exit(127);
    setenv("FASCIA_PROGRESS", "0", 1);
    execl(fascia, fascia, "run", model, "--steps", "1000000", "--threads", "1", "-o", results, "--checkpoint",
          checkpoint, "--checkpoint-every", "1", "--history", history, (char *)NULL);
    _exit(127);
  }
  CHECK(pid > 0);
  // running steps: the first checkpoint is in place
  for (int k = 0; k < 600 && !cli_file_exists(checkpoint); ++k) sleep_ms(50);
  CHECK(cli_file_exists(checkpoint));
  kill(pid, sig);
  if (late) {
    for (int k = 0; k < 20000; ++k) {
      cli_read_file(err, result.err, sizeof result.err);
      if (strstr(result.err, "interrupted after step")) break;
      struct timespec t = {0, 20000L};
      nanosleep(&t, NULL);
    }
  } else {
    sleep_ms(10); // delivered before the second: two pending signals would merge into one
  }
  kill(pid, sig);
  int ws = 0;
  CHECK(waitpid(pid, &ws, 0) == pid);
  cli_read_file(err, result.err, sizeof result.err);
  const int status = WIFEXITED(ws) ? WEXITSTATUS(ws) : -1;
  const int temporaries = cli_dir_count(dir, ".tmp-", 0);
  const int ok = status == 1 && strstr(result.err, "interrupted after step") && cli_file_exists(results) &&
                 cli_file_exists(xdmf) && cli_file_exists(checkpoint) && cli_file_exists(history) &&
                 temporaries == 0;
  if (!ok) {
    fprintf(stderr, "signal %d twice: %s %d; results %d, sidecar %d, checkpoint %d, history %d, %d temporary files\n",
            sig, WIFEXITED(ws) ? "exit" : "killed by signal", WIFEXITED(ws) ? status : WTERMSIG(ws),
            cli_file_exists(results), cli_file_exists(xdmf), cli_file_exists(checkpoint), cli_file_exists(history),
            temporaries);
    cli_dir_count(dir, "", 1);
    fprintf(stderr, "stderr:\n%.800s\n", result.err);
  }
  return !ok;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t908_cli_interrupt_twice PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1];
  char model[512], dir[512], err[512], args[2048];
  snprintf(model, sizeof model, "%s/t908_beam.h5", argv[2]);
  snprintf(err, sizeof err, "%s/t908_stderr.txt", argv[2]);
  // steps of about a tenth of a second: the second signal comes while one runs
  snprintf(args, sizeof args, "beam --frames 16x4x4 -o '%s'", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  snprintf(dir, sizeof dir, "%s/t908_int", argv[2]);
  int failures = interrupt_twice(fascia, model, dir, SIGINT, 0);
  snprintf(dir, sizeof dir, "%s/t908_term", argv[2]);
  failures += interrupt_twice(fascia, model, dir, SIGTERM, 0);
  snprintf(dir, sizeof dir, "%s/t908_late", argv[2]);
  failures += interrupt_twice(fascia, model, dir, SIGTERM, 1);
  CHECK(failures == 0);
  return CHECK_RESULT();
}
