// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A killed fascia leaves its temporary files (`NAME.tmp-PID-K`, next to the
// output); the next command writing that output removes those whose process
// is gone, says so in one line, and leaves alone those of a running process
// and files of other names.
// Usage: t911_cli_stale_temporaries PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include "check.h"
#include "cli_exec.h"

static cli_result result;

static int touch(const char *dir, const char *name) {
  char path[2048];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "w");
  if (!f) return 0;
  fputs("left by a killed writer\n", f);
  return fclose(f) == 0;
}

static int exists(const char *dir, const char *name) {
  char path[2048];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  return cli_file_exists(path);
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t911_cli_stale_temporaries PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1];
  char dir[512], snap[1024], model[1024], err[1024], args[4096];
  snprintf(dir, sizeof dir, "%s/t911", argv[2]);
  snprintf(snap, sizeof snap, "%s/snap", dir);
  snprintf(model, sizeof model, "%s/beam.h5", dir);
  snprintf(err, sizeof err, "%s/t911_stderr.txt", argv[2]);
  snprintf(args, sizeof args, "rm -rf '%s' && mkdir -p '%s'", dir, snap);
  CHECK(system(args) == 0);
  snprintf(args, sizeof args, "beam --frames 6x2x2 -o '%s'", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);

  // a process that is gone: a child that has exited and been reaped
  const pid_t child = fork();
  if (child == 0) _exit(0);
  CHECK(child > 0 && waitpid(child, NULL, 0) == child);
  char dead[3][64], alive[64], other[64], dead_snapshot[64];
  snprintf(dead[0], sizeof dead[0], "r.h5.tmp-%ld-0", (long)child);
  snprintf(dead[1], sizeof dead[1], "r.h5.tmp-%ld-7", (long)child);
  snprintf(dead[2], sizeof dead[2], "r.xdmf.tmp-%ld-0", (long)child);
  snprintf(alive, sizeof alive, "r.h5.tmp-%ld-0", (long)getpid()); // this test is running
  snprintf(other, sizeof other, "notes.txt.tmp-%ld-0", (long)child);  // no output of this run
  snprintf(dead_snapshot, sizeof dead_snapshot, "tissue-rest.csv.tmp-%ld-0", (long)child);
  for (int k = 0; k < 3; ++k) CHECK(touch(dir, dead[k]));
  CHECK(touch(dir, alive) && touch(dir, other) && touch(snap, dead_snapshot));

  snprintf(args, sizeof args, "run '%s' --steps 2 --threads 1 -o '%s/r.h5' --snapshots '%s'", model, dir, snap);
  CHECK(cli_exec(fascia, args, err, &result));
  CHECK(result.status == 0);
  for (int k = 0; k < 3; ++k) CHECK(!exists(dir, dead[k]));
  CHECK(!exists(snap, dead_snapshot));
  CHECK(exists(dir, alive) && exists(dir, other));
  CHECK(strstr(result.err, "removed 4 temporary files") != NULL);
  if (CHECK_RESULT()) {
    fprintf(stderr, "exit %d, stderr:\n%.800s\n", result.status, result.err);
    cli_dir_count(dir, "", 1);
    cli_dir_count(snap, "", 1);
  }
  return CHECK_RESULT();
}
