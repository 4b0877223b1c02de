// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Extra outputs of `fascia run` for people and plotting scripts:
// a per-step history CSV, the samples, frames and organ surfaces as
// ParaView files per saved step, and CSV snapshots of the scene at rest and
// at the end for tools/plots/.
#ifndef FASCIA_TOOLS_RUN_OUTPUTS_H
#define FASCIA_TOOLS_RUN_OUTPUTS_H

#include <stdio.h>

#include "fascia/fascia.h"
#include "fascia/files.h"

typedef struct run_outputs {
  const char *history_path;  ///< --history FILE.csv
  const char *paraview_dir;  ///< --paraview DIR (--organs DIR): run.pvd, organs.pvd, tissue/samples/frames-<k>.vtu, <organ>-<k>.vtu
  const char *snapshots_dir; ///< --snapshots DIR: tissue-{rest,final}.csv, organs-{rest,final}.csv
  // state
  fascia_ctx *ctx;
  const fascia_model *model;
  fascia_file *history; ///< written under a temporary name, renamed at the end
  fascia_file *pvd;     ///< organs.pvd
  fascia_file *run_pvd; ///< run.pvd
  int organ_steps;
  fascia_real *strain, *stress, *positions; ///< [S], [S], [3S]
  fascia_real *scratch, *axes;              ///< [3 max(S, N)], [9N]
  int32_t *coupled_organ;                   ///< [N] the organ a frame is shared with (its first coupling), -1 none
} run_outputs;

/// Takes --history, --paraview (--organs) and --snapshots (with their values) out of
/// argv. Returns -1 to go on, else the exit status (2: usage error).
int run_outputs_take(int *argc, char **argv, run_outputs *out);
/// Usage lines of the options.
extern const char run_outputs_usage[];

/// Before the first step: opens the files, writes the rest snapshot and the
/// organs at the current state, labelled `time` (s). On error the ctx holds the message.
fascia_status run_outputs_begin(run_outputs *out, fascia_ctx *ctx, const fascia_model *model, fascia_solver *solver,
                                fascia_real time);
/// After step `step` (1-based) that took `ms`: a history row; the organs
/// too when `saved`; both at `time` (s), the results' time of the step.
fascia_status run_outputs_step(run_outputs *out, fascia_solver *solver, int step, const fascia_solve_report *report,
                               double ms, int saved, fascia_real time);
/// After the last step: the final snapshot; closes everything (also after
/// an error, then with status ignored).
fascia_status run_outputs_end(run_outputs *out, fascia_solver *solver, int ok);
/// Removes what run_outputs_begin started (the history, the .pvd
/// collections) without writing it, so that a run that failed before its
/// first step leaves older files of those names as they were; frees the
/// buffers. A no-op after run_outputs_end.
void run_outputs_discard(run_outputs *out);

#endif
