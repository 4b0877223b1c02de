// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Implicit Euler stays stable from dt = 1e-4 s to 1 s: a clamped
// beam under its own weight, StVK and stable Neo-Hookean, takes every step
// with finite values and without energy growth, and with dt = 1 s (20 steps,
// far beyond the beam's period of about 1 s) it settles on the static
// equilibrium instead of returning garbage. The same for the beam at
// nu = 0.49 in cell patches with the enhanced strain modes fascia beam puts
// on them: hexahedral with its three normal modes, tetrahedral with its nine.
#include "stability.h"

// 0: the plain hexahedral beam; 1, 2: hex and tet at nu = 0.49 in cell
// patches with fascia beam's modes
static const char *const variant_names[] = {"", " hex nu 0.49 patches+modes", " tet nu 0.49 patches+modes"};

int main(int argc, char **argv) {
  stab_backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(stab_backend);
  fascia_ctx *ctx = stab_ctx();
  if (!ctx) return 1;
  const double dts[] = {1e-4, 1e-3, 1e-2, 0.1, 1.0};
  for (int case_ = 0; case_ < 3 * FASCIA_LAW_COUNT_; ++case_) {
    const int law = case_ % FASCIA_LAW_COUNT_, variant = case_ / FASCIA_LAW_COUNT_;
    fascia_scene_beam_def bd = stab_beam_def(6, law);
    if (variant > 0) {
      bd.shape = variant == 1 ? FASCIA_SCENE_HEX : FASCIA_SCENE_TET;
      bd.poisson_ratio = 0.49;
      bd.volumetric_patch = FASCIA_SCENE_PATCH_CELL;
      bd.enhanced_modes = -1; // fascia beam's rule
    }
    fascia_model *m = NULL;
    CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
    if (!m) continue;
    if (variant > 0) CHECK(m->sample_modes[0] == (variant == 1 ? FASCIA_MODES_NORMAL : FASCIA_MODES_NINE));
    fascia_status st;
    const double tip_static = stab_static_tip(ctx, m, 100, &st);
    CHECK_OK(st, ctx);
    for (size_t k = 0; k < sizeof dts / sizeof dts[0]; ++k) {
      fascia_solver_def sd = stab_solver_def();
      sd.time_step = dts[k];
      char name[64];
      snprintf(name, sizeof name, "%s%s dt %g", fascia_law_name(law), variant_names[variant], dts[k]);
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
