// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Checkpoints: the full state of a dynamic run (time, step index, frame
// positions, rotations and velocities: everything the next implicit step
// depends on) in one small HDF5 file, so that a run killed at any moment
// continues from its last checkpoint and reaches the same state, bit for bit
// on the CPU (same model, time step and thread count), as a run that was
// never interrupted. Format: the schema at the top of sim/src/io/io_checkpoint.c.
#ifndef FASCIA_CHECKPOINT_H
#define FASCIA_CHECKPOINT_H

#include "fascia/solver.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Writes the solver's state after `step` completed steps (0..2^31-1) to
/// `path`, through a temporary name next to it (path.tmp-PID-K) renamed into
/// place once complete: a file at `path` is always a whole checkpoint, and a
/// crash while writing leaves the previous one there. The file records the
/// model's sizes and a fingerprint of its contents, every solver setting that
/// changes the trajectory (see fascia_checkpoint_setting_name) and two
/// checksums, one over these records and one over the state, so that it is
/// only ever resumed, intact, with the model and settings it belongs to. On error nothing is left behind, an older file at
/// `path` is untouched, and the solver is unchanged.
FASCIA_API fascia_status fascia_checkpoint_save(fascia_ctx *ctx, const fascia_solver *solver, int64_t step,
                                                const char *path);

/// Like fascia_checkpoint_save, also recording `inputs`: the caller's own 64-bit digest of what else the run depends on (e.g. drive files; 0 = nothing), covered by the checksum.
FASCIA_API fascia_status fascia_checkpoint_save_inputs(fascia_ctx *ctx, const fascia_solver *solver, int64_t step,
                                                       uint64_t inputs, const char *path);

/// Restores the state saved by fascia_checkpoint_save into `solver` (made
/// for the same model with the same settings) and gives the step count in
/// *step. A checkpoint of another model, or written with other settings, is
/// refused with FASCIA_ERR_ARGUMENT and a message naming the dataset and what
/// differs; a damaged or edited file (checksum, step against time, shapes)
/// with FASCIA_ERR_FORMAT (FASCIA_ERR_IO when unreadable, or not a regular
/// file); a checkpoint of schema version 1 or 2 (older fascia, whose
/// checksum left the settings out) with FASCIA_ERR_FORMAT. On error the solver is unchanged.
FASCIA_API fascia_status fascia_checkpoint_load(fascia_ctx *ctx, fascia_solver *solver, const char *path,
                                                int64_t *step);

/// Reads the settings a checkpoint was written with into *def (only the
/// settings it records; backend, threads and load_steps are left as they
/// are) and its step count into *step, checking the file as
/// fascia_checkpoint_load does short of the state, and, when model is not
/// NULL, that it belongs to that model (FASCIA_ERR_ARGUMENT if not). A solver
/// created from *def can then load the checkpoint. On error *def and *step
/// are unchanged.
FASCIA_API fascia_status fascia_checkpoint_read_settings(fascia_ctx *ctx, const char *path,
                                                         const fascia_model *model, fascia_solver_def *def,
                                                         int64_t *step);

/// The digest a checkpoint recorded (0 when saved by fascia_checkpoint_save), after the same checks as fascia_checkpoint_read_settings (model may be NULL).
FASCIA_API fascia_status fascia_checkpoint_read_inputs(fascia_ctx *ctx, const char *path, const fascia_model *model,
                                                       uint64_t *inputs);

/// The settings a checkpoint records, by index 0..count-1: their names (the
/// fascia_solver_def field names, as stored under /settings; NULL out of
/// range) and their values in a def, as doubles (enumerations and flags as
/// their integer values).
FASCIA_API int fascia_checkpoint_setting_count(void);
FASCIA_API const char *fascia_checkpoint_setting_name(int k);
FASCIA_API double fascia_checkpoint_setting_get(const fascia_solver_def *def, int k);
FASCIA_API void fascia_checkpoint_setting_set(fascia_solver_def *def, int k, double value);

#ifdef __cplusplus
}
#endif
#endif
