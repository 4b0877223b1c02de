// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Implicit Euler stays stable from dt = 1e-4 s to 1 s: a clamped
// beam under its own weight, StVK and stable Neo-Hookean, takes every step
// with finite values and without energy growth, and with dt = 1 s (20 steps,
// far beyond the beam's period of about 1 s) it settles on the static
// equilibrium instead of returning garbage.
#include "stability.h"

int main(int argc, char **argv) {
  stab_backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(stab_backend);
  fascia_ctx *ctx = stab_ctx();
  if (!ctx) return 1;
  const double dts[] = {1e-4, 1e-3, 1e-2, 0.1, 1.0};
  for (int law = 0; law < FASCIA_LAW_COUNT_; ++law) {
    fascia_scene_beam_def bd = stab_beam_def(6, law);
    fascia_model *m = NULL;
    CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
    fascia_status st;
    const double tip_static = stab_static_tip(ctx, m, 100, &st);
    CHECK_OK(st, ctx);
    for (size_t k = 0; k < sizeof dts / sizeof dts[0]; ++k) {
      fascia_solver_def sd = stab_solver_def();
      sd.time_step = dts[k];
      char name[64];
      snprintf(name, sizeof name, "%s dt %g", fascia_law_name(law), dts[k]);
      const stab_result r = stab_run(ctx, name, m, &sd, 20, 0, 1);
      CHECK(!r.bad);
      CHECK(r.steps == 20); // nothing here needs a refusal
      CHECK(r.energy_end < r.energy_start); // it fell and dissipated
      if (dts[k] == 1.0) {
        // 20 s of strongly damped steps: at the static equilibrium
        fascia_solver *s = NULL;
        CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
        for (int n = 0; n < 20; ++n) CHECK_OK(fascia_solver_step(s, NULL), ctx);
        const int32_t tip = fascia_model_find_probe(m, "tip");
        fascia_real p[3];
        fascia_solver_probe_position(s, tip, p);
        // 1e-3 relative: the residual motion after 20 steps of 1 s
        CHECK_NEAR(p[2] - m->probe_position[3 * tip + 2], tip_static, 1e-3, 0);
        fascia_solver_destroy(&s);
      }
    }
    fascia_model_destroy(&m);
  }
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
