// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A step the solver cannot take is rejected and redone as shorter steps
// (fascia_solver_def.step_retries, require_convergence: detect it,
// say so, and recover): on a Neo-Hookean beam whose end is pushed 3 m into
// it, steps of 0.05 s do not converge while it buckles. Without retries the
// first such step is refused with FASCIA_ERR_NUMERIC, a message, and the
// state and time exactly as before; with the default retries every step is
// taken, some split, and the energy still does not grow once the push stops.
// A push of 10 m buckles so violently that even 1/16 of the step fails: the
// step is refused, the message names the shortest step tried (5 m was enough
// before the direct solver's chord steps, which take it). The device
// backends (CG only) check the refusal without retries alone.
#include "stability.h"

#define MOTION_END 1.0 // s
#define DT 0.05

int main(int argc, char **argv) {
  stab_backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(stab_backend);
  fascia_ctx *ctx = stab_ctx();
  if (!ctx) return 1;
  const fascia_solver_def defaults = fascia_solver_def_default();
  CHECK(defaults.step_retries == 4);
  CHECK(defaults.require_convergence == 1);
  const int steps = (int)(1.2 * MOTION_END / DT + 0.5);
  fascia_model *m = stab_pushed_beam(ctx, FASCIA_LAW_NEOHOOKEAN, 4.0, 3.0, MOTION_END);
  CHECK(m != NULL);
  if (!m) return 1;
  fascia_solver_def sd = stab_solver_def();
  sd.time_step = DT;
  sd.require_convergence = 1;
  // no retries: refused at the first hard step, state kept (stab_run checks)
  sd.step_retries = 0;
  stab_result r = stab_run(ctx, "no retries", m, &sd, steps, MOTION_END, 1);
  CHECK(!r.bad);
  CHECK(r.numeric_errors == 1);
  CHECK(r.steps < steps);
  if (!backend_runs_cpu_case(stab_backend, "retries, beyond recovery",
                             "recovering from the buckling needs the direct solver (auto's choice on the CPU): "
                             "with CG, on the CPU too, the 3 m push fails even at dt / 16")) {
    fascia_model_destroy(&m);
    fascia_ctx_destroy(&ctx);
    return CHECK_RESULT();
  }
  // default retries: all taken, some split
  sd.step_retries = defaults.step_retries;
  r = stab_run(ctx, "retries", m, &sd, steps, MOTION_END, 1);
  CHECK(!r.bad);
  CHECK(r.steps == steps);
  CHECK(r.substeps > steps);
  CHECK(r.converged == steps);
  fascia_model_destroy(&m);
  // beyond recovery: refused after splitting, the message says how far
  m = stab_pushed_beam(ctx, FASCIA_LAW_NEOHOOKEAN, 4.0, 10.0, MOTION_END);
  CHECK(m != NULL);
  if (!m) return 1;
  r = stab_run(ctx, "beyond recovery", m, &sd, steps, MOTION_END, 1);
  CHECK(!r.bad);
  CHECK(r.numeric_errors == 1);
  CHECK(strstr(fascia_ctx_message(ctx), "shortest step tried") != NULL);
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  fascia_solve_report rep;
  fascia_status st = FASCIA_OK;
  for (int n = 0; n < steps && st == FASCIA_OK; ++n) st = fascia_solver_step(s, &rep);
  CHECK(st == FASCIA_ERR_NUMERIC);
  CHECK(rep.rejected >= sd.step_retries); // split down to DT / 16 along one path at least
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
