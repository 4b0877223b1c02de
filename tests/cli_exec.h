// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Helpers of the CLI end-to-end tests (t9xx): run the built `fascia` binary
// through the shell, capture its stdout and stderr and its exit status.
// Needs _POSIX_C_SOURCE (popen, WEXITSTATUS) defined before any include.
#ifndef FASCIA_TESTS_CLI_EXEC_H
#define FASCIA_TESTS_CLI_EXEC_H

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#define CLI_TEXT_SIZE (1 << 20)

/// What one command did: exit status (-1 if it did not exit normally),
/// stdout and stderr (NUL-terminated, truncated at CLI_TEXT_SIZE - 1).
typedef struct cli_result {
  int status;
  char out[CLI_TEXT_SIZE];
  char err[CLI_TEXT_SIZE];
} cli_result;

static inline size_t cli_read_all_(FILE *f, char *buffer) {
  size_t n = 0, got;
  while (n + 1 < CLI_TEXT_SIZE && (got = fread(buffer + n, 1, CLI_TEXT_SIZE - 1 - n, f)) > 0) n += got;
  buffer[n] = '\0';
  return n;
}

/// A python3 that imports `modules` ("h5py, numpy"): Debian's, which holds
/// Debian's packages (a python3 earlier on PATH may not), else PATH's; NULL
/// for none.
static inline const char *cli_python_with(const char *modules) {
  static char command[512];
  snprintf(command, sizeof command, "/usr/bin/python3 -c 'import %s' >/dev/null 2>&1", modules);
  if (system(command) == 0) return "/usr/bin/python3";
  snprintf(command, sizeof command, "python3 -c 'import %s' >/dev/null 2>&1", modules);
  if (system(command) == 0) return "python3";
  return NULL;
}

/// Runs "'fascia' ARGS" with stderr sent to err_path and fills r. Returns 0
/// when the command could not be started.
static inline int cli_exec(const char *fascia, const char *args, const char *err_path, cli_result *r) {
  static char command[8192];
  snprintf(command, sizeof command, "FASCIA_PROGRESS=0 '%s' %s 2>'%s'", fascia, args, err_path);
  r->out[0] = r->err[0] = '\0';
  FILE *p = popen(command, "r");
  if (!p) return 0;
  cli_read_all_(p, r->out);
  const int ws = pclose(p);
  r->status = ws != -1 && WIFEXITED(ws) ? WEXITSTATUS(ws) : -1;
  FILE *e = fopen(err_path, "r");
  if (e) {
    cli_read_all_(e, r->err);
    fclose(e);
  }
  return 1;
}

/// Runs the shell text `command` (it names the fascia binary itself) with
/// stdout thrown away and stderr captured through a pipe into r->err: for
/// commands that must not write any file of the test's, such as under
/// `ulimit -f 0`. Returns 0 when the shell could not be started.
static inline int cli_shell(const char *command, cli_result *r) {
  static char full[16384];
  snprintf(full, sizeof full, "(FASCIA_PROGRESS=0; export FASCIA_PROGRESS; %s) 2>&1 >/dev/null", command);
  r->out[0] = r->err[0] = '\0';
  FILE *p = popen(full, "r");
  if (!p) return 0;
  cli_read_all_(p, r->err);
  const int ws = pclose(p);
  r->status = ws != -1 && WIFEXITED(ws) ? WEXITSTATUS(ws) : -1;
  return 1;
}

/// Lines in text (newline characters).
static inline int cli_lines(const char *text) {
  int n = 0;
  for (; *text; ++text) n += *text == '\n';
  return n;
}

/// Reads up to size - 1 bytes of path into buffer (NUL-terminated); the
/// byte count, or -1 when it cannot be opened.
static inline long cli_read_file(const char *path, char *buffer, size_t size) {
  FILE *f = fopen(path, "rb");
  if (!f) return -1;
  const size_t n = fread(buffer, 1, size - 1, f);
  buffer[n] = '\0';
  fclose(f);
  return (long)n;
}

/// Entries of folder dir whose name contains `part` ("" for all, "." and
/// ".." left out); -1 when it cannot be read. Prints them when verbose.
static inline int cli_dir_count(const char *dir, const char *part, int verbose) {
  DIR *d = opendir(dir);
  if (!d) return -1;
  int n = 0;
  for (struct dirent *e = readdir(d); e; e = readdir(d)) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..") || !strstr(e->d_name, part)) continue;
    if (verbose) fprintf(stderr, "  %s/%s\n", dir, e->d_name);
    ++n;
  }
  closedir(d);
  return n;
}

static inline int cli_file_exists(const char *path) {
  FILE *f = fopen(path, "rb");
  if (f) fclose(f);
  return f != NULL;
}

/// Writes the smallest prep scene into dir: a tetrahedron mesh a.obj used
/// by two organs A and B, one tissue between them (scene and mesh get the
/// paths, each of 1024 bytes). 1 on success.
static inline int cli_write_tiny_scene(const char *dir, char *scene, char *mesh) {
  snprintf(mesh, 1024, "%s/a.obj", dir);
  snprintf(scene, 1024, "%s/s.json", dir);
  FILE *f = fopen(mesh, "w");
  if (!f) return 0;
  fputs("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n", f);
  fclose(f);
  f = fopen(scene, "w");
  if (!f) return 0;
  fputs("{\"fascia_scene\": 1, \"voxel_size\": 0.02,\n"
        " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
        " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\"}, {\"name\": \"B\", \"mesh\": \"a.obj\"}],\n"
        " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.1,\n"
        "  \"material\": \"soft\", \"frame_spacing\": 0.1, \"sample_spacing\": 0.05}]}\n",
        f);
  fclose(f);
  return 1;
}

#endif
