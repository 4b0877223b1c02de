// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Running CalculiX leaves the caller's memory as it was: the program is
// spawned, not forked. A fork write-protects every page of the bench's
// process, and the fascia row timed after a CalculiX run would pay a page
// fault for each page it writes again. Here the program run is `true`, which
// writes no results (so the solve reports its output unreadable), also by
// a path relative to the caller's folder; a program that does not exist is
// reported as not run, one killed by a signal as stopped. Needs neither ccx nor
// a particular machine; skipped where getrusage counts no page faults.
#define _DEFAULT_SOURCE // mkstemp
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "beam_calculix.h"
#include "check.h"

#define HEAP_BYTES (64u << 20)

static long minor_faults(void) {
  struct rusage usage;
  memset(&usage, 0, sizeof usage);
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  unsigned char *heap = malloc(HEAP_BYTES);
  if (!heap) return 1;
  const long first = minor_faults();
  memset(heap, 1, HEAP_BYTES); // every page mapped and written
  const long written = minor_faults() - first;
  if (written < 1000) {
    printf("skipped: writing %u MB of new memory counted %ld page faults\n", HEAP_BYTES >> 20, written);
    free(heap);
    fascia_ctx_destroy(&ctx);
    return TEST_SKIP;
  }
  fascia_ccx_beam_def def = fascia_ccx_beam_def_default();
  def.cells[0] = 2, def.cells[1] = 2, def.cells[2] = 2;
  fascia_ccx_result result;
  CHECK(fascia_ccx_beam_solve(ctx, &def, "true", 1, &result) == FASCIA_ERR_FORMAT);
  const long before = minor_faults();
  memset(heap, 2, HEAP_BYTES); // the same pages written again
  const long again = minor_faults() - before;
  printf("%u MB written: %ld page faults the first time, %ld again after running a program\n", HEAP_BYTES >> 20,
         written, again);
  CHECK(again < written / 10);
  // a program ended by a signal stopped, it did not fail to start
  char killed[] = "/tmp/t364-killed-XXXXXX";
  const int fd = mkstemp(killed);
  CHECK(fd >= 0);
  if (fd >= 0) {
    static const char script[] = "#!/bin/sh\nkill -KILL $$\n";
    CHECK(write(fd, script, sizeof script - 1) == (ssize_t)(sizeof script - 1));
    close(fd);
    CHECK(chmod(killed, 0755) == 0);
    CHECK(fascia_ccx_beam_solve(ctx, &def, killed, 1, &result) == FASCIA_ERR_NUMERIC);
    CHECK(strstr(fascia_ctx_message(ctx), "stopped (exit 137)") != NULL);
    unlink(killed);
  }
  // a relative path is taken from the caller's folder, not the run folder
  if (chdir("/") == 0) {
    CHECK(fascia_ccx_beam_solve(ctx, &def, "bin/true", 1, &result) == FASCIA_ERR_FORMAT);
    CHECK(fascia_ccx_beam_solve(ctx, &def, "bin/no-such-ccx", 1, &result) == FASCIA_ERR_IO);
  }
  CHECK(fascia_ccx_beam_solve(ctx, &def, "/nonexistent/ccx", 1, &result) == FASCIA_ERR_IO);
  CHECK(strstr(fascia_ctx_message(ctx), "could not run '/nonexistent/ccx' (No such file or directory)") != NULL);
  free(heap);
  fascia_ctx_destroy(&ctx);
  return check_failures_ != 0;
}
