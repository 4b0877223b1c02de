// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Stable over Young's moduli from 1e2 to 1e8 Pa, both laws: a
// clamped beam under its own weight takes every step, finite, without energy
// growth, and its Newton solves converge (on a stiff Neo-Hookean beam the
// energy's rounding can hide the decrease near the minimum). A
// heterogeneous beam, two materials with a 1e4 stiffness contrast alternating
// cell by cell along it, is just as stable, and its static deflection lies
// between those of the all-soft and all-stiff beams. The device backends
// leave out the mixed beam's static solve, for time.
#include "stability.h"

#define SOFT 4e2
#define STIFF 4e6 // contrast 1e4

// The 9 x 2 x 2 beam with E = youngs, or (youngs = 0) alternating SOFT and
// STIFF cells along x, the cell at x = 0 soft.
static fascia_model *beam(fascia_ctx *ctx, int law, double youngs) {
  fascia_scene_beam_def bd = stab_beam_def(9, law);
  bd.youngs_modulus = youngs > 0 ? youngs : STIFF;
  fascia_model *src = NULL;
  if (fascia_scene_beam_build(ctx, &bd, &src) != FASCIA_OK || youngs > 0) return src;
  fascia_model *m = stab_copy_model(ctx, src, 0, 0, 0, 2, 0);
  fascia_model_destroy(&src);
  if (!m) return NULL;
  m->materials[1] = m->materials[0];
  m->materials[0].youngs_modulus = SOFT;
  strcpy(m->materials[0].name, "soft");
  strcpy(m->materials[1].name, "stiff");
  const double cell = bd.length / (bd.frames[0] - 1);
  for (int32_t s = 0; s < m->sample_count; ++s) m->sample_material[s] = (int)(m->sample_position[3 * s] / cell) % 2;
  if (fascia_model_build_reverse(ctx, m) != FASCIA_OK || fascia_model_validate(ctx, m, "heterogeneous beam"))
    fascia_model_destroy(&m);
  return m;
}

int main(int argc, char **argv) {
  stab_backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(stab_backend);
  fascia_ctx *ctx = stab_ctx();
  if (!ctx) return 1;
  const double moduli[] = {1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 0, SOFT, STIFF};
  const int dynamic_count = 8; // the last two only bound the mixed beam's deflection
  const int mixed_static = backend_runs_cpu_case(stab_backend, "the mixed beam's static solve and bounds",
                                                 "by CG it takes 6 s in the emulation, 80 s sanitized");
  const int count = mixed_static ? 10 : dynamic_count;
  for (int law = 0; law < FASCIA_LAW_COUNT_; ++law) {
    double tip[10];
    for (int k = 0; k < count; ++k) {
      fascia_model *m = beam(ctx, law, moduli[k]);
      CHECK(m != NULL);
      if (!m) return 1;
      char name[64];
      if (moduli[k] > 0) snprintf(name, sizeof name, "%s E %g", fascia_law_name(law), moduli[k]);
      else snprintf(name, sizeof name, "%s E %g/%g alternating", fascia_law_name(law), SOFT, STIFF);
      if (k < dynamic_count) {
        fascia_solver_def sd = stab_solver_def();
        const stab_result r = stab_run(ctx, name, m, &sd, 20, 0, 1);
        CHECK(!r.bad);
        CHECK(r.steps == 20);
        if (r.converged != r.steps) fprintf(stderr, "%s: %d of %d steps converged\n", name, r.converged, r.steps);
        CHECK(r.converged == r.steps); // 20 Newton iterations are plenty at dt = 0.01 s
      }
      if (moduli[k] == 0 && !mixed_static) {
        fascia_model_destroy(&m);
        continue;
      }
      // the mixed beam is a hard static problem: its soft cells act as hinges
      // that turn and (StVK) invert under the stiff cells' weight; measured
      // 149 (StVK) and 116 (Neo-Hookean) Newton iterations from rest
      fascia_status st;
      tip[k] = stab_static_tip(ctx, m, moduli[k] == 0 ? 400 : 100, &st);
      if (st != FASCIA_OK) fprintf(stderr, "%s: static solve: %s\n", name, fascia_ctx_message(ctx));
      CHECK(st == FASCIA_OK);
      fascia_model_destroy(&m);
    }
    // deflection falls as E grows; the mixed beam lies between its parts
    for (int k = 1; k < 7; ++k) CHECK(tip[k] > tip[k - 1]);
    if (mixed_static) CHECK(tip[7] > tip[8] && tip[7] < tip[9]);
  }
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
