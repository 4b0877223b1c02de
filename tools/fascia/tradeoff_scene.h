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
/// A point of a plot of error against time.
typedef struct cli_tradeoff_point {
  double ms, error;  ///< as plotted
  const char *label;
  int pareto;        ///< on the Pareto front
} cli_tradeoff_point;
/// The data files of such a plot for gnuplot: dir/points_name holds every
/// point, dir/front_name the Pareto points by time, each headed "# columns".
/// 0, else 1 after the message (nothing left of either file).
int cli_tradeoff_write_points(fascia_ctx *ctx, const char *dir, const char *points_name, const char *front_name,
                              const char *columns, const cli_tradeoff_point *points, int count);
/// Runs gnuplot on each of scripts (NULL-terminated) in dir: 0, also when
/// gnuplot is absent (said on stderr), 1 when it fails.
int cli_tradeoff_gnuplot(const char *dir, const char *const *scripts);

#endif
