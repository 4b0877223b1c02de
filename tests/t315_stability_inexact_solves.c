// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Inexact solves stay stable: CG stopped after 2 iterations, one
// Newton iteration per step, the paper's fixed-cost mode (one Newton
// iteration, exactly 60 CG iterations, no line search), and the crudest mix
// (one Newton iteration of 2 CG iterations, with and without line search).
// Each step is taken and finite, and the energy ends below its start. Where
// each step still solves its minimization well enough (all but the last two
// cases) the energy never grows in a step. The crudest mix is not a
// minimizer of the step: its energy is measured to rise in single steps (by
// 0.48 J over 25 steps, t = 0.25..0.5 s, out of the 1.07 J the beam loses
// settling) while staying below its start and settling on the equilibrium,
// so only that bound is checked for it (docs in tools/bench/README.md).
#include "stability.h"

int main(int argc, char **argv) {
  stab_backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(stab_backend);
  fascia_ctx *ctx = stab_ctx();
  if (!ctx) return 1;
  for (int law = 0; law < FASCIA_LAW_COUNT_; ++law) {
    fascia_scene_beam_def bd = stab_beam_def(6, law);
    fascia_model *m = NULL;
    CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
    for (int c = 0; c < 5; ++c) {
      fascia_solver_def sd = stab_solver_def();
      static const char *const names[5] = {"cg 2", "newton 1", "paper mode", "newton 1 cg 2",
                                           "newton 1 cg 2 no line search"};
      // "newton 1" keeps an accurate linear solve: the CPU's direct one (auto),
      // a device's CG to its tolerance (2 iterations would make it "newton 1 cg 2")
      if (c != 1) sd.linear_solver = FASCIA_LINEAR_CG, sd.cg_fixed = 1, sd.cg_iterations = c == 2 ? 60 : 2;
      if (c >= 1) sd.newton_iterations = 1, sd.require_convergence = 0;
      if (c == 2 || c == 4) sd.line_search = 0;
      char name[64];
      snprintf(name, sizeof name, "%s %s", fascia_law_name(law), names[c]);
      const stab_result r = stab_run(ctx, name, m, &sd, 60, 0, c < 3);
      CHECK(!r.bad);
      CHECK(r.steps == 60);
      CHECK(r.energy_end < r.energy_start);
    }
    fascia_model_destroy(&m);
  }
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
