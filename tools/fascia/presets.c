// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The named solver presets of `fascia run --preset` (see presets.h). Their
// measured error and ms per step on the cantilever come from
// `fascia tradeoff` (group "preset") and are listed in tools/bench/README.md.
#include "presets.h"

#include <string.h>

// The rule: every preset converges every step (an unconverged one is split,
// then refused), so its error is bounded by its Newton tolerance; the presets
// differ in that tolerance only. A looser tolerance takes fewer Newton
// iterations and keeps the factorization over more steps, so `interactive`
// does at most the default's work; `accurate`'s is the tightest.
static const fascia_preset presets[] = {
    {"interactive", "Newton to 1e-2 (up to 20), steps that do not converge are split"},
    {"balanced", "Newton to 1e-4 (up to 20), steps that do not converge are split"},
    {"accurate", "Newton to 1e-8 (up to 20), CG to 1e-6; steps that do not converge are split"},
};

const fascia_preset *cli_presets(int *count) {
  *count = (int)(sizeof presets / sizeof presets[0]);
  return presets;
}

// The settings a converged step needs, then the preset's tolerance.
static void converged_steps(fascia_solver_def *d, double newton_tolerance) {
  d->newton_iterations = 20;
  d->newton_tolerance = newton_tolerance;
  d->linear_solver = FASCIA_LINEAR_AUTO;
  d->cg_iterations = 200;
  d->cg_fixed = 0;
  d->cg_tolerance = 1e-3;
  d->precond = FASCIA_PRECOND_BLOCK_JACOBI;
  d->require_convergence = 1;
  d->step_retries = 4;
}

int cli_preset_apply(const char *name, fascia_solver_def *d) {
  if (!strcmp(name, "interactive")) {
    converged_steps(d, 1e-2);
    return 1;
  }
  if (!strcmp(name, "balanced")) {
    converged_steps(d, 1e-4);
    return 1;
  }
  if (!strcmp(name, "accurate")) {
    converged_steps(d, 1e-8);
    d->cg_iterations = 1000;
    d->cg_tolerance = 1e-6;
    return 1;
  }
  return 0;
}
