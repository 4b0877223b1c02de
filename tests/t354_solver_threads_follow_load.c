// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The solver's thread count follows the free cores (fascia_threads_free,
// docs/measured.md "On a busy machine"): never more than asked, at least one, and
// one while other processes keep every core busy, unless its passes are long
// (FASCIA_THREADS_LONG_PASS_PAIRS pairs or more: all it asked for, busy or
// not); a run that changes its thread count on the way gives the same bits
// as one that does not.
#define _POSIX_C_SOURCE 200809L
#include <signal.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "scenes.h"
#include "solve/solver_internal.h"

#define MAX_BUSY 64

int main(void) {
  const long cores = sysconf(_SC_NPROCESSORS_ONLN);
  const int64_t short_passes = FASCIA_THREADS_LONG_PASS_PAIRS - 1, long_passes = FASCIA_THREADS_LONG_PASS_PAIRS;
  CHECK(fascia_threads_free(1, short_passes) == 1);
  CHECK(fascia_threads_free(0, short_passes) == 1);
  CHECK(fascia_threads_free(1, long_passes) == 1);
  const int quiet = fascia_threads_free((int)cores, short_passes);
  CHECK(quiet >= 1 && quiet <= cores);
  // every core busy with another process: one thread
  pid_t busy[MAX_BUSY];
  int started = 0;
  for (long k = 0; k < cores && k < MAX_BUSY; ++k) {
    const pid_t p = fork();
    if (p == 0)
      for (volatile unsigned long spin = 0;; ++spin) {
      }
    if (p > 0) busy[started++] = p;
  }
  const struct timespec settle = {0, 200 * 1000 * 1000};
  nanosleep(&settle, NULL);
  int loaded = (int)cores, loaded_long = (int)cores;
  for (int k = 0; k < 5; ++k) { // the lowest of a few looks: the count is a sample
    const int t = fascia_threads_free((int)cores, short_passes);
    loaded = t < loaded ? t : loaded;
    const int l = fascia_threads_free((int)cores, long_passes);
    loaded_long = l < loaded_long ? l : loaded_long;
  }
  for (int k = 0; k < started; ++k) kill(busy[k], SIGKILL);
  for (int k = 0; k < started; ++k) waitpid(busy[k], NULL, 0);
  printf("%ld cores: %d threads free when quiet, %d beside %d busy processes (long passes: %d)\n", cores, quiet,
         loaded, started, loaded_long);
  CHECK(started == cores || started == MAX_BUSY);
  CHECK(loaded == 1 || cores > MAX_BUSY);
  CHECK(loaded_long == cores);

  // the same steps on a fixed thread count and on one that changes each step
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  fascia_scene_beam_def bd = fascia_scene_beam_def_default();
  bd.frames[0] = 8, bd.frames[1] = 2, bd.frames[2] = 2;
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = "cpu";
  sd.threads = 2;
  sd.linear_solver = FASCIA_LINEAR_CG;
  fascia_solver *fixed = NULL, *changing = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &fixed), ctx);
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &changing), ctx);
  for (int n = 0; n < 6; ++n) {
    fixed->sys->threads_max = 2;
    changing->sys->threads_max = 1 + n % 2; // the rule's result, alternating
    CHECK_OK(fascia_solver_step(fixed, NULL), ctx);
    CHECK_OK(fascia_solver_step(changing, NULL), ctx);
  }
  const int64_t N = m->frame_count;
  CHECK(!memcmp(fascia_solver_frame_positions(fixed), fascia_solver_frame_positions(changing), 3 * N * sizeof(double)));
  CHECK(!memcmp(fascia_solver_frame_rotations(fixed), fascia_solver_frame_rotations(changing), 4 * N * sizeof(double)));
  fascia_solver_destroy(&fixed);
  fascia_solver_destroy(&changing);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
