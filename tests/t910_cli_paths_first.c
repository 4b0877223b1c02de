// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Output paths are checked before any work: a missing output folder, an
// empty -o and a folder that is a file fail at once with one line naming the
// option and the path (no solve, no summary, no prep stages), and a --steps
// whose results the disk cannot hold is refused up front with the size of
// those results, instead of "out of memory" or hours of steps.
// Usage: t910_cli_paths_first PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <sys/stat.h>

#include "check.h"
#include "cli_exec.h"

static cli_result result;

// `args` exits `status` with one line on stderr holding `expect` (and
// `expect2` when not NULL) and prints nothing on stdout (no work done).
static int refused_early(const char *fascia, const char *args, int status, const char *expect, const char *expect2,
                         const char *err) {
  CHECK(cli_exec(fascia, args, err, &result));
  if (result.status != status || cli_lines(result.err) != 1 || result.out[0] || !strstr(result.err, expect) ||
      (expect2 && !strstr(result.err, expect2))) {
    fprintf(stderr, "%s\n  exit %d (expected %d), stdout %zu bytes, stderr:\n%.800s\n", args, result.status, status,
            strlen(result.out), result.err);
    return 1;
  }
  return 0;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t910_cli_paths_first PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1];
  char dir[512], model[1024], err[1024], args[4096], missing[1024], file[1024];
  snprintf(dir, sizeof dir, "%s/t910", argv[2]);
  snprintf(model, sizeof model, "%s/beam.h5", dir);
  snprintf(err, sizeof err, "%s/t910_stderr.txt", argv[2]);
  snprintf(missing, sizeof missing, "%s/no-such-folder", dir);
  snprintf(file, sizeof file, "%s/a-file", dir);
  snprintf(args, sizeof args, "rm -rf '%s' && mkdir -p '%s' && echo x > '%s'", dir, dir, file);
  CHECK(system(args) == 0);
  snprintf(args, sizeof args, "beam --frames 6x2x2 -o '%s'", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);

  int failures = 0;
  // a static solve writes its results after solving: the folder is checked first
  snprintf(args, sizeof args, "run '%s' --static --threads 1 -o '%s/r.h5'", model, missing);
  failures += refused_early(fascia, args, 1, missing, "does not exist", err);
  snprintf(args, sizeof args, "run '%s' --static --threads 1 -o ''", model);
  failures += refused_early(fascia, args, 2, "-o needs a path", NULL, err);
  snprintf(args, sizeof args, "run '%s' --static --threads 1 --history ''", model);
  failures += refused_early(fascia, args, 2, "--history needs a path", NULL, err);
  snprintf(args, sizeof args, "run '%s' --static --threads 1 --snapshots '%s'", model, file);
  failures += refused_early(fascia, args, 2, "--snapshots", "is a file, not a folder", err);
  snprintf(args, sizeof args, "run '%s' --static --threads 1 -o '%s/r.h5'", model, file);
  failures += refused_early(fascia, args, 1, file, "is not a folder", err);
  snprintf(args, sizeof args, "beam --frames 6x2x2 -o '%s/m.h5'", missing);
  failures += refused_early(fascia, args, 1, missing, "does not exist", err);
  snprintf(args, sizeof args, "beam --frames 6x2x2 -o ''");
  failures += refused_early(fascia, args, 2, "-o needs a path", NULL, err);
  snprintf(args, sizeof args, "bench cantilever --steps 1 --repeats 1 --threads 1 --csv '%s/b.csv'", missing);
  failures += refused_early(fascia, args, 1, missing, "does not exist", err);
  snprintf(args, sizeof args, "tradeoff --quick --out '%s'", file);
  failures += refused_early(fascia, args, 2, "--out", "is a file, not a folder", err); // it said "is not a regular file"
  // 2e9 saved steps of this beam are about 1.4 TB: refused with that figure
  // (under a timeout: a run that went ahead would take years)
  snprintf(args, sizeof args, "timeout 60 '%s' run '%s' --steps 2000000000 --threads 1 -o '%s/r.h5'", fascia, model,
           dir);
  CHECK(cli_shell(args, &result));
  if (result.status != 1 || cli_lines(result.err) != 1 || !strstr(result.err, "2000000002 saved steps") ||
      !strstr(result.err, "TB") || strstr(result.err, "out of memory")) {
    fprintf(stderr, "--steps 2000000000: exit %d, stderr:\n%.800s\n", result.status, result.err);
    ++failures;
  }
#ifdef FASCIA_HAVE_PREP
  // prep: the folder is checked before the pipeline runs
  char scene[1024], mesh[1024];
  CHECK(cli_write_tiny_scene(dir, scene, mesh));
  snprintf(args, sizeof args, "prep '%s' -o '%s/m.h5'", scene, missing);
  failures += refused_early(fascia, args, 1, missing, "does not exist", err);
  snprintf(args, sizeof args, "prep '%s' -o ''", scene);
  failures += refused_early(fascia, args, 2, "-o needs a path", NULL, err);
  snprintf(args, sizeof args, "prep '%s' -o '%s/m.h5' --preview '%s/p'", scene, dir, missing);
  failures += refused_early(fascia, args, 1, missing, "does not exist", err);
#endif
  CHECK(failures == 0);
  return CHECK_RESULT();
}
