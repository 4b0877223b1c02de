// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The direct solver's factorizations start no threads of their own: a
// one-thread static solve of the 20x3x3 cantilever (supernodal factors)
// leaves the process with the threads it had. CHOLMOD may ask OpenMP for
// teams of its own in its supernodal factorization; even fitted to the free
// cores such a team starts a worker beside the solver's thread that
// competes for the cores and is slow to wake after an idle spell
// (docs/mechanics.md, "CHOLMOD's threads"). The thread count is read from
// /proc/self/task, so the test is skipped where there is none. The runtime
// fits a team to the cores its load average leaves free, so on a machine
// with one core, or one loaded over its cores, the check cannot fail.
#include <dirent.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "fascia/solver.h"
#include "scenes.h"

// Threads of this process, or -1 where /proc/self/task cannot be read.
static int thread_count(void) {
  DIR *d = opendir("/proc/self/task");
  if (!d) return -1;
  int count = 0;
  for (struct dirent *e; (e = readdir(d));)
    if (e->d_name[0] != '.') ++count;
  closedir(d);
  return count;
}

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1;
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  fascia_scene_beam_def def = fascia_scene_beam_def_default(); // hex 20x3x3, nu = 0.3
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &def, &m), ctx);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.threads = 1;
  sd.linear_solver = FASCIA_LINEAR_DIRECT;
  sd.newton_iterations = 100;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  const int before = thread_count();
  if (before < 0) {
    printf("skipped: no /proc/self/task to count threads in\n");
    fascia_solver_destroy(&s);
    fascia_model_destroy(&m);
    fascia_ctx_destroy(&ctx);
    return TEST_SKIP;
  }
  fascia_solve_report report = {0};
  CHECK_OK(fascia_solver_solve_static(s, &report), ctx);
  const int after = thread_count();
  printf("static solve on 1 thread: %d factorizations, %d Newton iterations; threads %d before, %d after\n",
         report.factorizations, report.newton_iterations, before, after);
  CHECK(report.converged && report.direct && report.factorizations > 0);
  CHECK(after == before);
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return check_failures_ != 0;
}
