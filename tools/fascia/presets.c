// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The named solver presets of `fascia run --preset` (see presets.h). Their
// measured error and ms per step on the cantilever come from
// `fascia tradeoff` (group "preset") and are listed in tools/bench/README.md.
#include "presets.h"

#include <string.h>

static const fascia_preset presets[] = {
    {"interactive", "1 Newton iteration per step; CG (where not direct) to 1e-2, at most 30 iterations"},
    {"balanced", "up to 3 Newton iterations to 1e-4, linear solver chosen automatically"},
    {"accurate", "Newton to 1e-8 (up to 20), steps that do not converge are split"},
};

const fascia_preset *cli_presets(int *count) {
  *count = (int)(sizeof presets / sizeof presets[0]);
  return presets;
}

int cli_preset_apply(const char *name, fascia_solver_def *d) {
  if (!strcmp(name, "interactive")) {
    d->newton_iterations = 1;
    d->linear_solver = FASCIA_LINEAR_AUTO;
    d->cg_iterations = 30;
    d->cg_fixed = 0;
    d->cg_tolerance = 1e-2;
    d->precond = FASCIA_PRECOND_BLOCK_JACOBI;
    d->require_convergence = 0;
    return 1;
  }
  if (!strcmp(name, "balanced")) {
    d->newton_iterations = 3;
    d->newton_tolerance = 1e-4;
    d->linear_solver = FASCIA_LINEAR_AUTO;
    d->cg_iterations = 200;
    d->cg_fixed = 0;
    d->cg_tolerance = 1e-3;
    d->require_convergence = 0;
    return 1;
  }
  if (!strcmp(name, "accurate")) {
    d->newton_iterations = 20;
    d->newton_tolerance = 1e-8;
    d->linear_solver = FASCIA_LINEAR_AUTO;
    d->cg_iterations = 1000;
    d->cg_fixed = 0;
    d->cg_tolerance = 1e-6;
    d->require_convergence = 1;
    d->step_retries = 4;
    return 1;
  }
  return 0;
}
