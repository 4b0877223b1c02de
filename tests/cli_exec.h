// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Helpers of the CLI end-to-end tests (t9xx): run the built `fascia` binary
// through the shell, capture its stdout and stderr and its exit status.
// Needs _POSIX_C_SOURCE (popen, WEXITSTATUS) defined before any include.
#ifndef FASCIA_TESTS_CLI_EXEC_H
#define FASCIA_TESTS_CLI_EXEC_H

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

static inline int cli_file_exists(const char *path) {
  FILE *f = fopen(path, "rb");
  if (f) fclose(f);
  return f != NULL;
}

#endif
