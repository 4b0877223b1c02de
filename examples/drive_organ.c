// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// fascia from an outside simulator, with the installed public API only:
// loads a model, finds the tissue's static equilibrium under gravity, then
// drives one organ's coupling frames (lifts it against gravity, a little each
// step, as a surgical simulator moving that organ would) and reads back the
// forces the tissue applies on it.
//
//   drive_organ MODEL.h5 [ORGAN [LIFT_MM [STEPS]]]
//
// ORGAN: its name in the model (default: the first organ); LIFT_MM: how far
// it is lifted in all (default 2); STEPS: time steps of 0.01 s (default 10).
// Prints one "key: values" line per result, then a table of the steps.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <fascia/fascia.h>

// The context's message names the file or the object; `what` (may be NULL)
// says which step failed.
static int fail(fascia_ctx *ctx, const char *what) {
  fprintf(stderr, "drive_organ: %s%s%s\n", what ? what : "", what ? ": " : "", fascia_ctx_message(ctx));
  return 1;
}

static double norm3(const double v[3]) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// Sum of the reaction forces (N) over an organ's coupling frames; nonzero on
// error (the context has the message).
static int organ_force(fascia_ctx *ctx, fascia_solver *s, int32_t organ, double sum[3]) {
  const int32_t n = fascia_solver_organ_frame_count(s, organ);
  double *f = malloc(sizeof(double) * 3 * (size_t)(n > 0 ? n : 1));
  if (!f) {
    fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "out of memory");
    return 1;
  }
  sum[0] = sum[1] = sum[2] = 0;
  const fascia_status st = fascia_solver_organ_reaction(s, organ, f, NULL);
  for (int32_t k = 0; st == FASCIA_OK && k < n; ++k)
    for (int c = 0; c < 3; ++c) sum[c] += f[3 * k + c];
  free(f);
  return st != FASCIA_OK;
}

int main(int argc, char **argv) {
  if (argc < 2 || argc > 5) {
    fprintf(stderr, "usage: drive_organ MODEL.h5 [ORGAN [LIFT_MM [STEPS]]]\n");
    return 2;
  }
  const double lift = (argc > 3 ? atof(argv[3]) : 2.0) * 1e-3; // m
  const int steps = argc > 4 ? atoi(argv[4]) : 10;
  if (!(lift >= 0 && lift < 1) || steps < 1) {
    fprintf(stderr, "drive_organ: LIFT_MM must be in [0, 1000) and STEPS at least 1\n");
    return 2;
  }
  fascia_ctx *ctx = NULL;
  fascia_ctx_def cd = fascia_ctx_def_default();
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  fascia_model *m = NULL;
  fascia_solver *s = NULL;
  double *target = NULL, *rot = NULL;
  int rc = 1;
  if (fascia_model_load(ctx, argv[1], &m) != FASCIA_OK) {
    rc = fail(ctx, NULL);
    goto done;
  }
  if (m->organ_count < 1) {
    fprintf(stderr, "drive_organ: %s: the model has no organs to drive\n", argv[1]);
    goto done;
  }
  const int32_t organ = argc > 2 ? fascia_model_find_organ(m, argv[2]) : 0;
  if (organ < 0) {
    fprintf(stderr, "drive_organ: %s: no organ '%s'\n", argv[1], argv[2]);
    goto done;
  }
  printf("fascia: %s\n", fascia_version());
  printf("model: %s, %d frames, %d samples, %d organs\n", argv[1], (int)m->frame_count, (int)m->sample_count,
         (int)m->organ_count);

  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = "cpu";
  sd.time_step = 0.01;
  if (fascia_solver_create(ctx, m, &sd, &s) != FASCIA_OK) {
    rc = fail(ctx, "solver");
    goto done;
  }
  fascia_solve_report rep;
  if (fascia_solver_solve_static(s, &rep) != FASCIA_OK) {
    rc = fail(ctx, "static equilibrium");
    goto done;
  }
  printf("static: %d Newton iterations, converged %d\n", rep.newton_iterations, rep.converged);

  // At equilibrium the organs carry the tissue: the reactions on all of
  // them add up to its weight.
  double weight[3], total[3] = {0, 0, 0}, f[3];
  for (int c = 0; c < 3; ++c) weight[c] = fascia_model_mass(m) * m->gravity[c];
  for (int32_t o = 0; o < m->organ_count; ++o) {
    if (organ_force(ctx, s, o, f)) {
      rc = fail(ctx, "reaction");
      goto done;
    }
    for (int c = 0; c < 3; ++c) total[c] += f[c];
  }
  const double diff[3] = {total[0] - weight[0], total[1] - weight[1], total[2] - weight[2]};
  const double wn = norm3(weight), en = norm3(diff);
  printf("weight_N: %.9g %.9g %.9g\n", weight[0], weight[1], weight[2]);
  printf("reaction_all_organs_N: %.9g %.9g %.9g\n", total[0], total[1], total[2]);
  printf("balance_error: %.3g\n", wn > 0 ? en / wn : en);

  // Drive the organ: its coupling frames move up (against gravity; +y
  // without gravity) from where they are, lift/steps per step.
  const double gn = norm3(m->gravity);
  const double up[3] = {gn > 0 ? -m->gravity[0] / gn : 0, gn > 0 ? -m->gravity[1] / gn : 1,
                        gn > 0 ? -m->gravity[2] / gn : 0};
  const int32_t n = fascia_solver_organ_frame_count(s, organ);
  int32_t *frames = malloc(sizeof(int32_t) * (size_t)(n > 0 ? n : 1));
  target = malloc(sizeof(double) * 3 * (size_t)(n > 0 ? n : 1));
  rot = malloc(sizeof(double) * 4 * (size_t)(n > 0 ? n : 1));
  if (!frames || !target || !rot || fascia_solver_organ_frames(s, organ, frames) != FASCIA_OK) {
    free(frames);
    rc = fail(ctx, "organ frames");
    goto done;
  }
  const double *x = fascia_solver_frame_positions(s), *q = fascia_solver_frame_rotations(s);
  for (int32_t k = 0; k < n; ++k) {
    memcpy(target + 3 * k, x + 3 * frames[k], 3 * sizeof(double));
    memcpy(rot + 4 * k, q + 4 * frames[k], 4 * sizeof(double));
  }
  free(frames);
  double rest[3];
  if (organ_force(ctx, s, organ, rest)) {
    rc = fail(ctx, "reaction");
    goto done;
  }
  printf("organ: %s, %d coupling frames, lifted %.3g mm over %d steps of %.3g s\n", m->organs[organ].name, (int)n,
         lift * 1e3, steps, sd.time_step);
  printf("reaction_at_rest_N: %.9g %.9g %.9g\n", rest[0], rest[1], rest[2]);
  printf("step time_s lift_mm reaction_x_N reaction_y_N reaction_z_N\n");
  for (int step = 1; step <= steps; ++step) {
    for (int32_t k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c) target[3 * k + c] += up[c] * lift / steps;
    if (fascia_solver_organ_set_frames(s, organ, target, rot) != FASCIA_OK ||
        fascia_solver_step(s, &rep) != FASCIA_OK || organ_force(ctx, s, organ, f)) {
      rc = fail(ctx, "step");
      goto done;
    }
    printf("%4d %.3f %.3f %.9g %.9g %.9g\n", step, fascia_solver_time(s), lift * 1e3 * step / steps, f[0], f[1], f[2]);
  }
  // the tissue holds the lifted organ back: its reaction along "up" drops
  const double held = (f[0] - rest[0]) * up[0] + (f[1] - rest[1]) * up[1] + (f[2] - rest[2]) * up[2];
  printf("reaction_change_along_lift_N: %.9g\n", held);
  rc = 0;
done:
  free(target);
  free(rot);
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return rc;
}
