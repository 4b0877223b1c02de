// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The retraction loop of examples/retract.py in C, for the Python
// package's benchmark (tools/bench/python_step.py) and its test: each step
// poses ORGAN LIFT_MM * n / STEPS up (+y) from rest, steps, reads the
// organ's wrench. Prints the loop's wall time per step; --dump FILE writes
// the final frame positions and the last wrench as raw doubles.
//
//   fascia_retract_loop MODEL ORGAN LIFT_MM STEPS [--dump FILE]
#define _POSIX_C_SOURCE 200809L // clock_gettime
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fascia/fascia.h"

static double now_ms(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

int main(int argc, char **argv) {
  if (argc != 5 && argc != 7) {
    fprintf(stderr, "usage: fascia_retract_loop MODEL ORGAN LIFT_MM STEPS [--dump FILE]\n");
    return 2;
  }
  const double lift = atof(argv[3]) * 1e-3;
  const int steps = atoi(argv[4]);
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  fascia_model *m = NULL;
  fascia_solver *s = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  int rc = 1;
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = "cpu";
  sd.time_step = 0.01;
  if (fascia_model_load(ctx, argv[1], &m) != FASCIA_OK || fascia_solver_create(ctx, m, &sd, &s) != FASCIA_OK)
    goto done;
  const int32_t organ = fascia_model_find_organ(m, argv[2]);
  double force[3], torque[3];
  const double rotation[4] = {1, 0, 0, 0};
  const double t0 = now_ms();
  for (int n = 1; n <= steps; ++n) {
    const double translation[3] = {0, lift * n / steps, 0};
    if (fascia_solver_organ_set_pose(s, organ, translation, rotation) != FASCIA_OK ||
        fascia_solver_step(s, NULL) != FASCIA_OK || fascia_solver_organ_wrench(s, organ, force, torque, NULL) != FASCIA_OK)
      goto done;
  }
  printf("ms_per_step: %.6f\n", (now_ms() - t0) / steps);
  if (argc == 7) { // under a temporary name, renamed when complete
    fascia_file *file = NULL;
    if (fascia_file_open(ctx, "dump", argv[6], &file) != FASCIA_OK) goto done;
    FILE *f = fascia_file_stream(file);
    fwrite(fascia_solver_frame_positions(s), sizeof(double), 3 * (size_t)m->frame_count, f);
    fwrite(force, sizeof(double), 3, f);
    fwrite(torque, sizeof(double), 3, f);
    if (fascia_file_commit(&file) != FASCIA_OK) goto done;
  }
  rc = 0;
done:
  if (rc) fprintf(stderr, "fascia_retract_loop: %s\n", fascia_ctx_message(ctx));
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return rc;
}
