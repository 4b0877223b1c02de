// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia run --drive ORGAN=FILE.csv` (per-frame positions read
// from a file, for an organ driven by another simulator): reads one CSV per
// driven organ, and before each step sets the organ's coupling frames to the
// rows interpolated at the step's end time (fascia_solver_organ_set_frames).
// `--drive-template ORGAN=FILE.csv` writes the header and the rest row, so a
// user learns the column order. Format: docs/drive-format.md.
#ifndef FASCIA_TOOLS_DRIVE_H
#define FASCIA_TOOLS_DRIVE_H

#include "fascia/fascia.h"

/// One --drive or --drive-template: the organ and its file, and (after
/// run_drive_load) the rows.
typedef struct drive_organ {
  char organ_name[FASCIA_NAME_SIZE];
  const char *path;      ///< points into argv
  int32_t organ;         ///< index in the model
  int32_t frame_count;   ///< C, its coupling frames
  int32_t row_count;     ///< T, data rows
  fascia_real *time;     ///< [T] s, strictly increasing
  fascia_real *position; ///< [T][3C] m, world, frames in fascia_solver_organ_frames order
  fascia_real *rotation; ///< [T][4C] unit quaternions w, x, y, z (normalized on reading)
  fascia_real *x, *q;    ///< [3C], [4C] the pose handed to the solver
} drive_organ;

typedef struct run_drive {
  int count, template_count;
  drive_organ *organs;    ///< [count] --drive
  drive_organ *templates; ///< [template_count] --drive-template
} run_drive;

/// Usage lines of the options.
extern const char run_drive_usage[];

/// Takes --drive and --drive-template (with their values) out of argv.
/// Returns -1 to go on, else the exit status (2: usage error, reported).
/// run_drive_free releases what it took, also after an error.
int run_drive_take(int *argc, char **argv, run_drive *drive);

/// Writes each --drive-template file: the header and one row with the
/// organ's coupling frames at the solver's current state. On error the ctx
/// holds the message (a file may be left half written).
fascia_status run_drive_write_templates(run_drive *drive, fascia_ctx *ctx, const fascia_model *model,
                                        const fascia_solver *solver);

/// Reads and checks every --drive file against the model: organ name,
/// header, column count, finite numbers, nonzero quaternions, increasing
/// times. On error the ctx names the file, row and column; nothing is set on
/// the solver.
fascia_status run_drive_load(run_drive *drive, fascia_ctx *ctx, const fascia_model *model,
                             const fascia_solver *solver);

/// Before a step ending at time t_end (s): sets each driven organ's coupling
/// frames to its rows at t_end (linear in position, slerp in rotation; the
/// first row before the first time, the last row after the last).
fascia_status run_drive_before_step(run_drive *drive, fascia_solver *solver, fascia_real t_end);

/// A 64-bit digest of what the loaded --drive files feed the run (each
/// driven organ and its rows, in any order of the options); 0 without
/// --drive. A checkpoint records it, so that a resume drives the organs as
/// the run that saved it did.
uint64_t run_drive_digest(const run_drive *drive);

/// Frees the rows and the option lists; accepts a zeroed run_drive.
void run_drive_free(run_drive *drive);

#endif
