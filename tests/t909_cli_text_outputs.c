// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The text outputs (--history, --organs, --snapshots of `fascia run`, --csv
// of `fascia bench`) are written under a temporary name and renamed when
// complete: when writing fails (here a file size limit of 0, `ulimit -f 0`
// with SIGXFSZ ignored, so every write fails with EFBIG) the command exits 1
// with one line naming the folder and the reason, an older file of the same
// name is left exactly as it was, and no temporary file remains. They used
// to be opened in place, so a failure left them truncated.
// Usage: t909_cli_text_outputs PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <sys/stat.h>

#include "check.h"
#include "cli_exec.h"

#define OLDER "an older file, to be kept\n"

static cli_result result;

static int write_older(const char *path) {
  FILE *f = fopen(path, "w");
  if (!f) return 0;
  fputs(OLDER, f);
  return fclose(f) == 0;
}

// `args` under ulimit -f 0 fails as documented and `kept` still holds OLDER.
static int fails_cleanly(const char *fascia, const char *args, const char *folder, const char *kept) {
  char command[8192], now[256];
  snprintf(command, sizeof command, "trap '' XFSZ; ulimit -f 0; '%s' %s", fascia, args);
  CHECK(cli_shell(command, &result));
  const long n = cli_read_file(kept, now, sizeof now);
  const int same = n == (long)strlen(OLDER) && !strcmp(now, OLDER);
  const int temporaries = cli_dir_count(folder, ".tmp-", 0);
  char where[1100];
  snprintf(where, sizeof where, "folder '%s'", folder);
  if (result.status != 1 || cli_lines(result.err) != 1 || !strstr(result.err, where) ||
      !strstr(result.err, "File too large") || !same || temporaries != 0) {
    fprintf(stderr, "%s\n  exit %d, %s %s, %d temporary files; stderr:\n%.800s\n", args, result.status, kept,
            same ? "kept" : "CHANGED", temporaries, result.err);
    return 1;
  }
  return 0;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t909_cli_text_outputs PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1];
  char dir[512], model[1024], err[1024], args[4096], path[1200], folder[1024];
  snprintf(dir, sizeof dir, "%s/t909", argv[2]);
  snprintf(model, sizeof model, "%s/t909_beam.h5", argv[2]);
  snprintf(err, sizeof err, "%s/t909_stderr.txt", argv[2]);
  snprintf(args, sizeof args, "rm -rf '%s' && mkdir -p '%s/snap' '%s/organs'", dir, dir, dir);
  CHECK(system(args) == 0);
  snprintf(args, sizeof args, "beam --frames 6x2x2 -o '%s'", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);

  int failures = 0;
  snprintf(path, sizeof path, "%s/h.csv", dir);
  CHECK(write_older(path));
  snprintf(args, sizeof args, "run '%s' --steps 3 --threads 1 --history '%s'", model, path);
  failures += fails_cleanly(fascia, args, dir, path);

  snprintf(folder, sizeof folder, "%s/snap", dir);
  snprintf(path, sizeof path, "%s/tissue-rest.csv", folder);
  CHECK(write_older(path));
  snprintf(args, sizeof args, "run '%s' --steps 3 --threads 1 --snapshots '%s'", model, folder);
  failures += fails_cleanly(fascia, args, folder, path);

  snprintf(folder, sizeof folder, "%s/organs", dir);
  snprintf(path, sizeof path, "%s/organs.pvd", folder);
  CHECK(write_older(path));
  snprintf(args, sizeof args, "run '%s' --steps 3 --threads 1 --organs '%s'", model, folder);
  failures += fails_cleanly(fascia, args, folder, path);

  snprintf(path, sizeof path, "%s/bench.csv", dir);
  CHECK(write_older(path));
  snprintf(args, sizeof args,
           "bench cantilever --frames 6x2x2 --steps 1 --repeats 1 --threads 1 --no-calculix --csv '%s'", path);
  failures += fails_cleanly(fascia, args, dir, path);
  CHECK(failures == 0);

  // and without a limit they are written and complete
  snprintf(path, sizeof path, "%s/h.csv", dir);
  snprintf(args, sizeof args, "run '%s' --steps 3 --threads 1 --history '%s'", model, path);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  static char text[CLI_TEXT_SIZE];
  CHECK(cli_read_file(path, text, sizeof text) > 0 && cli_lines(text) == 4 && !strstr(text, "older"));
  return CHECK_RESULT();
}
