// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// An output path that names an input (or another output) is refused before
// any work, with exit status 2 and one line naming both options, and the
// input is left byte for byte as it was: `run M -o M`, `--checkpoint M`,
// `--history M`, a hard link or another spelling of M, `-o X --checkpoint
// X`, `--snapshots` holding M under one of its names; `prep S -o S` and `-o`
// naming one of the scene's meshes. A symbolic link, FIFO or device given as
// an output is refused too instead of being replaced by a regular file.
// Continuing a checkpoint into the same file (--resume C --checkpoint C)
// stays allowed.
// Usage: t907_cli_output_is_input PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "cli_exec.h"

static cli_result result;
static char original[CLI_TEXT_SIZE], now[CLI_TEXT_SIZE];

// Runs `command`: exit 2, one line containing `expect`, and `keep` unchanged
// (its bytes as `original` holds them, `length` of them).
static int refused(const char *command, const char *expect, const char *keep, long length) {
  CHECK(cli_shell(command, &result));
  const long n = cli_read_file(keep, now, sizeof now);
  const int same = n == length && !memcmp(now, original, (size_t)length);
  if (result.status != 2 || cli_lines(result.err) != 1 || !strstr(result.err, expect) || !same) {
    fprintf(stderr, "%s\n  exit %d, %s %s, stderr:\n%.800s\n", command, result.status, keep,
            same ? "unchanged" : "CHANGED", result.err);
    return 1;
  }
  return 0;
}

// Runs `command`: exit 2 and `path` is still what it was: a symbolic link
// ('l'), FIFO ('p') or character device ('c').
static int kept(const char *command, const char *path, char kind) {
  CHECK(cli_shell(command, &result));
  struct stat st;
  const int found = lstat(path, &st) == 0;
  const int same = found && (kind == 'l'   ? S_ISLNK(st.st_mode)
                             : kind == 'p' ? S_ISFIFO(st.st_mode)
                                           : S_ISCHR(st.st_mode));
  if (result.status != 2 || cli_lines(result.err) != 1 || !same) {
    fprintf(stderr, "%s\n  exit %d, %s %s, stderr:\n%.800s\n", command, result.status, path,
            same ? "kept" : "REPLACED", result.err);
    return 1;
  }
  return 0;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t907_cli_output_is_input PATH/TO/fascia WORK_DIR\n");
    return 1;
  }
  const char *fascia = argv[1];
  char dir[512], model[1024], err[1024], command[8192], path[1024], other[1024], args[2048];
  snprintf(dir, sizeof dir, "%s/t907", argv[2]);
  snprintf(model, sizeof model, "%s/v.h5", dir);
  snprintf(err, sizeof err, "%s/t907_stderr.txt", argv[2]);
  snprintf(command, sizeof command, "rm -rf '%s' && mkdir -p '%s/snap'", dir, dir);
  CHECK(system(command) == 0);
  snprintf(args, sizeof args, "beam --frames 6x2x2 -o '%s'", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  const long length = cli_read_file(model, original, sizeof original);
  CHECK(length > 0);

  int failures = 0;
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 -o '%s'", fascia, model, model);
  failures += refused(command, "-o", model, length);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --checkpoint '%s'", fascia, model, model);
  failures += refused(command, "--checkpoint", model, length);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --history '%s'", fascia, model, model);
  failures += refused(command, "--history", model, length);
  snprintf(command, sizeof command, "'%s' run '%s' --static -o '%s'", fascia, model, model);
  failures += refused(command, "-o", model, length);
  // the same file spelled another way, and under another name (a hard link)
  snprintf(command, sizeof command, "cd '%s' && '%s' run ./v.h5 --steps 2 -o ../t907/snap/../v.h5", dir, fascia);
  failures += refused(command, "-o", model, length);
  snprintf(path, sizeof path, "%s/hard.h5", dir);
  CHECK(link(model, path) == 0);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 -o '%s'", fascia, model, path);
  failures += refused(command, "-o", model, length);
  // an output folder holding the model under one of the names it writes
  snprintf(path, sizeof path, "%s/snap/tissue-final.csv", dir);
  CHECK(link(model, path) == 0);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --snapshots '%s/snap'", fascia, path, dir);
  failures += refused(command, "--snapshots", model, length);
  // two outputs on one file: the checkpoint would be lost
  snprintf(path, sizeof path, "%s/r.h5", dir);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 -o '%s' --checkpoint '%s'", fascia, model, path, path);
  failures += refused(command, "the same file", model, length);
  CHECK(!cli_file_exists(path));

  // links, FIFOs and devices are not replaced by a regular file
  snprintf(path, sizeof path, "%s/link.h5", dir);
  snprintf(other, sizeof other, "%s/target.h5", dir);
  CHECK(symlink(other, path) == 0);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 -o '%s'", fascia, model, path);
  failures += kept(command, path, 'l');
  snprintf(command, sizeof command, "'%s' beam --frames 6x2x2 -o '%s'", fascia, path);
  failures += kept(command, path, 'l');
  snprintf(path, sizeof path, "%s/fifo", dir);
  CHECK(mkfifo(path, 0666) == 0);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --checkpoint '%s'", fascia, model, path);
  failures += kept(command, path, 'p');
  snprintf(path, sizeof path, "%s/null", dir);
  snprintf(command, sizeof command, "mknod '%s' c 1 3 2>/dev/null", path);
  if (system(command) == 0) {
    snprintf(command, sizeof command, "'%s' run '%s' --static -o '%s'", fascia, model, path);
    failures += kept(command, path, 'c');
  } else {
    fprintf(stderr, "t907: the device case is skipped: mknod needs root\n");
  }

#ifdef FASCIA_HAVE_PREP
  // prep: the scene or one of its meshes as the model file
  char scene[1024], mesh[1024];
  CHECK(cli_write_tiny_scene(dir, scene, mesh));
  const long scene_length = cli_read_file(scene, original, sizeof original);
  snprintf(command, sizeof command, "'%s' prep '%s' -o '%s'", fascia, scene, scene);
  failures += refused(command, "scene", scene, scene_length);
  const long mesh_length = cli_read_file(mesh, original, sizeof original);
  snprintf(command, sizeof command, "'%s' prep '%s' -o '%s'", fascia, scene, mesh);
  failures += refused(command, "mesh", mesh, mesh_length);
#endif
  CHECK(failures == 0);

  // continuing a checkpoint into the file it was read from is the normal use
  snprintf(path, sizeof path, "%s/c.h5", dir);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 2 --checkpoint '%s'", fascia, model, path);
  CHECK(cli_shell(command, &result) && result.status == 0);
  snprintf(command, sizeof command, "'%s' run '%s' --steps 4 --resume '%s' --checkpoint '%s'", fascia, model, path,
           path);
  CHECK(cli_shell(command, &result) && result.status == 0);
  if (result.status != 0) fprintf(stderr, "%.800s\n", result.err);
  return CHECK_RESULT();
}
