// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Checkpoints: the full state of a dynamic run (time, step index, frame
// positions, rotations and velocities: everything the next implicit step
// depends on) in one small HDF5 file, so that a run killed at any moment
// continues from its last checkpoint and reaches the same state, bit for bit
// on the CPU (same model, time step and thread count), as a run that was
// never interrupted. Format: the schema at the top of sim/src/io_checkpoint.c.
#ifndef FASCIA_CHECKPOINT_H
#define FASCIA_CHECKPOINT_H

#include "fascia/solver.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Writes the solver's state after `step` completed steps (>= 0) to `path`,
/// through a temporary name next to it (path.tmp-PID-K) renamed into place
/// once complete: a file at `path` is always a whole checkpoint, and a crash
/// while writing leaves the previous one there. The file records the model's
/// sizes and a fingerprint of its contents and the time step, so that it is
/// only ever resumed with the model and step it belongs to. On error nothing
/// is left behind, an older file at `path` is untouched, and the solver is
/// unchanged.
FASCIA_API fascia_status fascia_checkpoint_save(fascia_ctx *ctx, const fascia_solver *solver, int64_t step,
                                                const char *path);

/// Restores the state saved by fascia_checkpoint_save into `solver` (made
/// for the same model with the same time step) and gives the step count in
/// *step. A checkpoint of another model, or written with another time step,
/// is refused with FASCIA_ERR_ARGUMENT and a message saying what differs; a
/// damaged file with FASCIA_ERR_FORMAT (FASCIA_ERR_IO when unreadable). On
/// error the solver is unchanged.
FASCIA_API fascia_status fascia_checkpoint_load(fascia_ctx *ctx, fascia_solver *solver, const char *path,
                                                int64_t *step);

#ifdef __cplusplus
}
#endif
#endif
