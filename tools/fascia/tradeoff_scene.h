// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia tradeoff SCENE.json` (cmd_tradeoff_scene.c): the speed/accuracy
// trade measured on the user's own scene; `fascia tradeoff` hands over to it
// when its command line names a scene file.
#ifndef FASCIA_TOOLS_TRADEOFF_SCENE_H
#define FASCIA_TOOLS_TRADEOFF_SCENE_H

#include "fascia/files.h"

/// 1 when argv (after "tradeoff") holds a positional argument, a scene file.
int cli_tradeoff_scene_wanted(int argc, char **argv);
/// The command on a scene; the exit status (0, 1 failure, 2 usage error).
int cmd_tradeoff_scene(int argc, char **argv);

/// Marks in pareto[k] the points no other beats in both ms and error (skip[k]
/// nonzero: left out and unmarked).
void cli_pareto_mark(int count, const double *ms, const double *error, const int *skip, int *pareto);

/// The output files of `fascia tradeoff` (cmd_tradeoff.c): dir/name opened
/// under a temporary name (NULL after the message), and committed (0, else 1
/// after the message, nothing left under its name).
fascia_file *cli_tradeoff_open(fascia_ctx *ctx, const char *dir, const char *name);
int cli_tradeoff_commit(fascia_ctx *ctx, fascia_file *file);
/// Runs gnuplot on each of scripts (NULL-terminated) in dir: 0, also when
/// gnuplot is absent (said on stderr), 1 when it fails.
int cli_tradeoff_gnuplot(const char *dir, const char *const *scripts);

#endif
