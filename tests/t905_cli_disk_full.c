// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A disk that fills while fascia writes an HDF5 file (results, checkpoint,
// model) ends in exit status 1 with one line on stderr that names the folder
// and the reason: no crash, no temporary file left, nothing at the final
// path. Two ways to fill it: a file size limit of 0 (`ulimit -f 0`, SIGXFSZ
// ignored: writes fail with EFBIG) everywhere, and a full 2 MiB tmpfs (real
// ENOSPC) where this process may mount one (root); otherwise that part is
// skipped with a line saying why. On the nearly full tmpfs, a run whose
// results do not fit fails before its first step and leaves an older
// --history file of the same name as it was.
// Usage: t905_cli_disk_full PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "cli_exec.h"

static cli_result result;

typedef struct full_case {
  const char *name, *args; // args: printf of the model, then the full folder
  const char *final_name;  // the file that must not appear
} full_case;

// `prefix` fills the disk for the command (a ulimit, or nothing on the full
// tmpfs); every case fails cleanly and leaves `dir` as it found it.
static int run_cases(const char *fascia, const char *prefix, const char *model, const char *dir) {
  static const full_case cases[] = {
      {"results", "run '%s' --steps 30 --samples --threads 1 -o '%s/r.h5'", "r.h5"},
      {"checkpoint", "run '%s' --steps 3 --threads 1 --checkpoint '%s/c.h5'", "c.h5"},
      {"model", "beam --frames 6x2x2%.0s -o '%s/m.h5'", "m.h5"},
  };
  const int before = cli_dir_count(dir, "", 0);
  int failures = 0;
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
    const full_case *c = cases + k;
    char args[4096], command[8192], final_path[2048];
    snprintf(args, sizeof args, c->args, model, dir);
    snprintf(command, sizeof command, "%s '%s' %s", prefix, fascia, args);
    snprintf(final_path, sizeof final_path, "%s/%s", dir, c->final_name);
    if (!cli_shell(command, &result)) return 1;
    // exit 1, not a crash (-1: killed by a signal) nor 0
    const int ok = result.status == 1 && cli_lines(result.err) == 1 && strstr(result.err, dir) &&
                   !cli_file_exists(final_path) && cli_dir_count(dir, "", 0) == before;
    if (!ok) {
      fprintf(stderr, "%s (%s): exit %d, %d stderr lines, %d entries in %s (before: %d):\n%.1500s\n", c->name,
              prefix[0] ? prefix : "full tmpfs", result.status, cli_lines(result.err), cli_dir_count(dir, "", 1),
              dir, before, result.err);
      ++failures;
    }
  }
  return failures;
}

// Mounts a 2 MiB tmpfs on dir and fills it: 1 when done, 0 (with why) when
// this process cannot.
static int mount_full_tmpfs(const char *dir) {
  char command[8192];
  snprintf(command, sizeof command, "mount -t tmpfs -o size=2m t905 '%s' 2>/dev/null", dir);
  if (geteuid() != 0 || system(command) != 0) {
    fprintf(stderr, "t905: the full-tmpfs part is skipped: cannot mount a tmpfs here (needs root)\n");
    return 0;
  }
  snprintf(command, sizeof command, "dd if=/dev/zero of='%s/fill' bs=64k 2>/dev/null; true", dir);
  if (system(command) != 0) return 0;
  return 1;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t905_cli_disk_full PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1];
  char model[1024], dir[1024], args[4096], err[1024];
  snprintf(model, sizeof model, "%s/t905_beam.h5", argv[2]);
  snprintf(dir, sizeof dir, "%s/t905_full", argv[2]);
  snprintf(err, sizeof err, "%s/t905_stderr.txt", argv[2]);
  snprintf(args, sizeof args, "beam --frames 6x2x2 -o '%s'", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  char command[8192];
  snprintf(command, sizeof command, "umount '%s' 2>/dev/null; rm -rf '%s'", dir, dir);
  CHECK(system(command) == 0);
  CHECK(mkdir(dir, 0777) == 0);

  // a file size limit of 0: every write fails with EFBIG (SIGXFSZ ignored)
  int failures = run_cases(fascia, "trap '' XFSZ; ulimit -f 0;", model, dir);
  if (mount_full_tmpfs(dir)) {
    failures += run_cases(fascia, "", model, dir);
    // nearly full: room for a text file, not for the results' margin. The run
    // fails before its first step and an older --history stays as it was.
    snprintf(command, sizeof command, "rm -f '%s/fill' && dd if=/dev/zero of='%s/fill' bs=64k count=26 2>/dev/null",
             dir, dir);
    CHECK(system(command) == 0);
    char history[1100], old_text[64], now_text[64];
    snprintf(history, sizeof history, "%s/h.csv", dir);
    FILE *f = fopen(history, "w");
    CHECK(f && fputs("an older history, kept\n", f) >= 0 && fclose(f) == 0);
    snprintf(args, sizeof args, "run '%s' --steps 3 --threads 1 -o '%s/r.h5' --history '%s'", model, dir, history);
    snprintf(command, sizeof command, "'%s' %s", fascia, args);
    CHECK(cli_shell(command, &result));
    const long n = cli_read_file(history, now_text, sizeof now_text);
    snprintf(old_text, sizeof old_text, "an older history, kept\n");
    if (result.status != 1 || n != (long)strlen(old_text) || memcmp(now_text, old_text, (size_t)n)) {
      fprintf(stderr, "nearly full: exit %d, --history %s; stderr: %.600s\n", result.status,
              n == (long)strlen(old_text) && !memcmp(now_text, old_text, (size_t)n) ? "kept" : "REPLACED", result.err);
      ++failures;
    }
    snprintf(command, sizeof command, "umount '%s'", dir);
    CHECK(system(command) == 0);
  }
  CHECK(failures == 0);
  return CHECK_RESULT();
}
