// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// One solver per thread (fascia/solver.h, "Threads"): two solvers on one
// shared model, each with a context of its own, run a retraction loop (pose
// an organ, step, read its wrench) in two threads at once and end with the
// same bits, state and every wrench, as the same two runs one after the
// other.
#include <pthread.h>

#include "backend_arg.h"
#include "check.h"
#include "fascia/organs.h"
#include "organ_fixture.h"

#define STEPS 30

typedef struct run {
  const fascia_model *model;
  const char *backend;
  double pull;                 ///< m per step along x, different per run
  double wrench[6 * STEPS];    ///< force, torque per step
  double *x, *q;               ///< final state
  fascia_status status;
  char message[512];
} run;

static void *retract(void *arg) {
  run *r = arg;
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 2; // each solver starts an OpenMP team of its own
  fascia_ctx *ctx = NULL;
  fascia_solver *s = NULL;
  r->status = fascia_ctx_create(&cd, &ctx);
  if (r->status != FASCIA_OK) return NULL;
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = r->backend;
  r->status = fascia_solver_create(ctx, r->model, &sd, &s);
  const int32_t organ = fascia_model_find_organ(r->model, "b");
  for (int n = 1; n <= STEPS && r->status == FASCIA_OK; ++n) {
    const double t[3] = {r->pull * n, 0, 0.5 * r->pull * n}, rot[4] = {1, 0, 0, 0};
    r->status = fascia_solver_organ_set_pose(s, organ, t, rot);
    if (r->status == FASCIA_OK) r->status = fascia_solver_step(s, NULL);
    if (r->status == FASCIA_OK)
      r->status = fascia_solver_organ_wrench(s, organ, r->wrench + 6 * (n - 1), r->wrench + 6 * (n - 1) + 3, NULL);
  }
  if (r->status == FASCIA_OK) {
    const size_t N = (size_t)r->model->frame_count;
    memcpy(r->x, fascia_solver_frame_positions(s), 3 * N * sizeof(double));
    memcpy(r->q, fascia_solver_frame_rotations(s), 4 * N * sizeof(double));
  } else {
    snprintf(r->message, sizeof r->message, "%s", fascia_ctx_message(ctx));
  }
  fascia_solver_destroy(&s);
  fascia_ctx_destroy(&ctx);
  return NULL;
}

int main(int argc, char **argv) {
  const char *backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(backend);
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  organ_fixture_def fd = organ_fixture_def_default();
  fd.kind_a = FASCIA_ORGAN_FIXED, fd.kind_b = FASCIA_ORGAN_RIGID; // B driven from outside
  fd.gravity[2] = -9.81;
  fascia_model *m = NULL;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  const size_t N = (size_t)m->frame_count;
  run runs[4];
  memset(runs, 0, sizeof runs);
  for (int k = 0; k < 4; ++k) {
    runs[k].model = m, runs[k].backend = backend, runs[k].pull = (k % 2 ? 4e-5 : 5e-5);
    runs[k].x = malloc(3 * N * sizeof(double)), runs[k].q = malloc(4 * N * sizeof(double));
  }
  // runs 0 and 1 one after the other, 2 and 3 (the same two) at once
  retract(&runs[0]);
  retract(&runs[1]);
  pthread_t threads[2];
  CHECK(pthread_create(&threads[0], NULL, retract, &runs[2]) == 0);
  CHECK(pthread_create(&threads[1], NULL, retract, &runs[3]) == 0);
  pthread_join(threads[0], NULL);
  pthread_join(threads[1], NULL);
  for (int k = 0; k < 4; ++k)
    if (runs[k].status != FASCIA_OK) {
      fprintf(stderr, "run %d: %s: %s\n", k, fascia_status_name(runs[k].status), runs[k].message);
      return 1;
    }
  for (int k = 0; k < 2; ++k) {
    const run *alone = &runs[k], *beside = &runs[k + 2];
    CHECK(!memcmp(alone->x, beside->x, 3 * N * sizeof(double)));
    CHECK(!memcmp(alone->q, beside->q, 4 * N * sizeof(double)));
    CHECK(!memcmp(alone->wrench, beside->wrench, sizeof alone->wrench));
    CHECK(alone->wrench[6 * (STEPS - 1)] < 0); // the tissue holds B back
  }
  CHECK(memcmp(runs[0].x, runs[1].x, 3 * N * sizeof(double))); // the two runs differ
  for (int k = 0; k < 4; ++k) free(runs[k].x), free(runs[k].q);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
