// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Named solver presets: bundles of the settings that trade time
// for accuracy, chosen from the sweep of `fascia tradeoff` and measured there
// on the cantilever (tools/bench/README.md). `fascia run --preset NAME`.
#ifndef FASCIA_TOOLS_PRESETS_H
#define FASCIA_TOOLS_PRESETS_H

#include "fascia/solver.h"

typedef struct fascia_preset {
  const char *name;
  const char *help; ///< one line
} fascia_preset;

/// The presets, fastest first; *count gets their number.
const fascia_preset *cli_presets(int *count);
/// Applies preset `name` to def (the fields it sets; others untouched).
/// Returns 0 for an unknown name.
int cli_preset_apply(const char *name, fascia_solver_def *def);

#endif
