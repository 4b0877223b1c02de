// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The fascia program starts without the prep stage's libraries (OpenVDB,
// assimp, ...): `fascia prep` loads them with its module fascia-prep.so
// (tools/fascia/prep_module.c), found next to the program, and `fascia info`
// says where it is; a program whose module is missing says so in one line
// (and in `fascia info`) and still runs every other command.
//   t355_cli_prep_module FASCIA_BINARY prep|no-prep
#define _POSIX_C_SOURCE 200809L // popen, mkdtemp
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "cli_exec.h"

static cli_result result;

// Runs the shell text with stdout and stderr into result.out; the exit status into result.status.
static int shell(const char *text) {
  char command[8192];
  snprintf(command, sizeof command, "(FASCIA_PROGRESS=0; export FASCIA_PROGRESS; %s) 2>&1", text);
  FILE *p = popen(command, "r");
  if (!p) return 0;
  cli_read_all_(p, result.out);
  const int ws = pclose(p);
  result.status = ws != -1 && WIFEXITED(ws) ? WEXITSTATUS(ws) : -1;
  return 1;
}

int main(int argc, char **argv) {
  if (argc < 3) return 2;
  const char *fascia = argv[1];
  const int prep = !strcmp(argv[2], "prep");
  char command[4096];
  // the loader's list of what it loads: HDF5 (the model files) yes, the prep libraries no
  snprintf(command, sizeof command, "LD_DEBUG=libs '%s' --version", fascia);
  CHECK(shell(command) && result.status == 0);
  CHECK(strstr(result.out, "libhdf5") != NULL); // the list is there to read
  CHECK(strstr(result.out, "libopenvdb") == NULL && strstr(result.out, "libassimp") == NULL);
  CHECK(strstr(result.out, "fascia-prep.so") == NULL);
  if (check_failures_) fprintf(stderr, "fascia --version loaded:\n%s", result.out);
  if (prep) { // the command loads them
    snprintf(command, sizeof command, "LD_DEBUG=libs '%s' prep --help", fascia);
    CHECK(shell(command) && result.status == 0);
    CHECK(strstr(result.out, "fascia-prep.so") != NULL && strstr(result.out, "libopenvdb") != NULL);
    CHECK(strstr(result.out, "usage: fascia prep SCENE.json") != NULL);
  }
  snprintf(command, sizeof command, "'%s' info", fascia);
  CHECK(shell(command) && result.status == 0);
  CHECK(strstr(result.out, prep ? "\nprep: module /" : "\nprep: not built (") != NULL);
  CHECK(!prep || strstr(result.out, "/fascia-prep.so\n") != NULL);
  // the program alone in a folder: prep says what is missing, the rest runs
  char folder[] = "/tmp/fascia-t355-XXXXXX";
  CHECK(mkdtemp(folder) != NULL);
  snprintf(command, sizeof command, "cp '%s' '%s/fascia'", fascia, folder);
  CHECK(shell(command) && result.status == 0);
  snprintf(command, sizeof command, "'%s/fascia' prep scene.json", folder);
  CHECK(shell(command) && result.status == 1);
  const char *line = result.out;
  CHECK(strncmp(line, "fascia prep: ", 13) == 0 && strchr(line, '\n') == line + strlen(line) - 1); // one line
  CHECK(prep ? strstr(line, "fascia-prep.so") && strstr(line, folder) : strstr(line, "not built") != NULL);
  if (check_failures_) fprintf(stderr, "fascia prep without its module said: %s", line);
  snprintf(command, sizeof command, "'%s/fascia' --version", folder);
  CHECK(shell(command) && result.status == 0 && strncmp(result.out, "fascia ", 7) == 0);
  snprintf(command, sizeof command, "'%s/fascia' info", folder);
  CHECK(shell(command) && result.status == 0);
  CHECK(strstr(result.out, prep ? "\nprep: module fascia-prep.so missing: neither in " : "\nprep: not built (") != NULL);
  snprintf(command, sizeof command, "rm -rf '%s'", folder);
  CHECK(shell(command) && result.status == 0);
  return CHECK_RESULT();
}
