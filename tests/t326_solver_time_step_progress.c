// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A host simulator's frame time: (1) fascia_solver_set_time_step changes the
// step from the next one on, and the run continues as a solver made with
// that step from the same state would; an impossible step is refused with
// nothing changed; (2) the context's progress hook is called once per
// accepted step, with stage "step" and the time reached.
#include "backend_arg.h"
#include "check.h"
#include "fascia/organs.h"
#include "organ_fixture.h"

typedef struct hook_log {
  int calls;
  char stage[32], detail[128];
  double fraction;
} hook_log;

static void hook(void *user, const char *stage, double fraction, const char *detail) {
  hook_log *log = user;
  ++log->calls;
  snprintf(log->stage, sizeof log->stage, "%s", stage);
  snprintf(log->detail, sizeof log->detail, "%s", detail ? detail : "");
  log->fraction = fraction;
}

int main(int argc, char **argv) {
  const char *backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(backend);
  hook_log log;
  memset(&log, 0, sizeof log);
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1;
  cd.progress = hook, cd.progress_user = &log;
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  organ_fixture_def fd = organ_fixture_def_default();
  fd.kind_a = FASCIA_ORGAN_FIXED, fd.kind_b = FASCIA_ORGAN_PRESCRIBED;
  fd.pull_b[0] = 0.004, fd.pull_b[2] = 0.002; // B pulled along x and up over 1 s
  fd.gravity[2] = -9.81;
  fascia_model *m = NULL;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = backend;
  sd.time_step = 0.01;
  fascia_solver *a = NULL, *b = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &a), ctx);

  // (2) one call per step
  for (int n = 1; n <= 3; ++n) {
    CHECK_OK(fascia_solver_step(a, NULL), ctx);
    CHECK(log.calls == n);
  }
  CHECK(!strcmp(log.stage, "step") && log.fraction < 0);
  CHECK(strstr(log.detail, "t = 0.03 s") != NULL);

  // (1) a shorter step from here on; b is made with it and given a's state
  CHECK(fascia_solver_time_step(a) == 0.01);
  CHECK_OK(fascia_solver_set_time_step(a, 0.004), ctx);
  CHECK(fascia_solver_time_step(a) == 0.004);
  sd.time_step = 0.004;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &b), ctx);
  const int32_t N = fascia_solver_frame_count(a);
  CHECK(N == m->frame_count && fascia_solver_sample_count(a) == m->sample_count);
  CHECK_OK(fascia_solver_set_state(b, fascia_solver_frame_positions(a), fascia_solver_frame_rotations(a),
                                   fascia_solver_frame_velocities(a)), ctx);
  CHECK_OK(fascia_solver_set_time(b, fascia_solver_time(a)), ctx);
  for (int n = 0; n < 5; ++n) {
    CHECK_OK(fascia_solver_step(a, NULL), ctx);
    CHECK_OK(fascia_solver_step(b, NULL), ctx);
  }
  CHECK_NEAR(fascia_solver_time(a), 0.05, 0, 1e-15);
  const double *xa = fascia_solver_frame_positions(a), *xb = fascia_solver_frame_positions(b);
  const double *ua = fascia_solver_frame_velocities(a), *ub = fascia_solver_frame_velocities(b);
  for (int64_t k = 0; k < 3 * (int64_t)N; ++k) CHECK_NEAR(xa[k], xb[k], 0, 1e-12); // Newton tolerance 1e-6 of mm moves
  for (int64_t k = 0; k < 6 * (int64_t)N; ++k) CHECK_NEAR(ua[k], ub[k], 0, 1e-9);
  CHECK(log.calls == 13);

  // impossible steps: refused, nothing changed
  const double bad[] = {0, -0.01, NAN, INFINITY, 1e-9};
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    CHECK(fascia_solver_set_time_step(a, bad[k]) == FASCIA_ERR_ARGUMENT);
    CHECK(fascia_solver_time_step(a) == 0.004);
  }
  CHECK(strstr(fascia_ctx_message(ctx), "time step") != NULL);

  fascia_solver_destroy(&a);
  fascia_solver_destroy(&b);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
