// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Results: a time series of frame (and optionally sample) states written to
// one HDF5 file plus an XDMF sidecar that ParaView opens as an animation.
// The file is written under a temporary name next to the final one and
// renamed into place by fascia_results_close, so a file at the final path is
// always complete. Format: docs/results-format.md.
#ifndef FASCIA_RESULTS_H
#define FASCIA_RESULTS_H

#include <stdbool.h>

#include "fascia/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Most named per-sample fields one results file holds.
#define FASCIA_RESULTS_MAX_FIELDS 32

typedef struct fascia_results fascia_results;

/// Options of a results file; start from fascia_results_def_default().
typedef struct fascia_results_def {
  /// Also write the deformed sample positions of every step (and allow
  /// per-sample fields). Default false: frames only, S times smaller.
  bool write_samples;
  /// Solver steps between two appended steps, >= 1 (default 1). Recorded in
  /// the file for readers; which steps to append is the caller's choice.
  int32_t every;
  int cookie_; ///< private: set by fascia_results_def_default
} fascia_results_def;

FASCIA_API fascia_results_def fascia_results_def_default(void);

/// Free space, bytes, the results writer keeps beyond each step it writes
/// (room for the metadata HDF5 writes when it flushes): a step that would
/// leave less fails before writing. A caller estimating up front whether a
/// run's results fit adds it to the steps' bytes.
#define FASCIA_RESULTS_SPACE_MARGIN ((int64_t)1 << 20)

/// Starts a results file for `model` at `path` (conventionally *.h5; the
/// XDMF sidecar goes to the same path with .xdmf instead of .h5). Nothing
/// appears at `path` before fascia_results_close. The model is only read
/// here (counts, frame kinds, sample materials and volumes, provenance).
/// ctx must outlive the results object: later calls report errors on it.
/// On error *out is NULL and no file is left behind.
FASCIA_API fascia_status fascia_results_open(fascia_ctx *ctx, const char *path, const fascia_model *model,
                                             const fascia_results_def *def, fascia_results **out);

/// Appends one step at `time` (s; finite, greater than the previous step's):
/// frame_position [3N] m and frame_rotation [4N] unit quaternions (w, x, y,
/// z), world; sample_position [3S] m, required when the results were opened
/// with write_samples, ignored otherwise. On error the step is not counted;
/// the object stays usable (close keeps the steps appended before).
FASCIA_API fascia_status fascia_results_append(fascia_results *results, fascia_real time,
                                               const fascia_real *frame_position, const fascia_real *frame_rotation,
                                               const fascia_real *sample_position);

/// Stores the per-sample scalar field `name` (e.g. "strain", "stress"; at
/// most 63 characters, no '/') for the step appended last: values [S]. Needs
/// write_samples. A field first given at a later step reads NaN in earlier
/// steps; one not given at some step reads NaN there. Giving a field twice in
/// one step overwrites it.
FASCIA_API fascia_status fascia_results_append_field(fascia_results *results, const char *name,
                                                     const fascia_real *values);

/// Records the unit and the meaning of per-sample field `name` (as the
/// field's attributes `unit` and `meaning`), e.g. "1" and "Frobenius norm of
/// the Green-Lagrange strain E = (F^T F - I) / 2"; the field is created if it
/// was not given yet. A field never described reads unit "unknown".
FASCIA_API fascia_status fascia_results_describe_field(fascia_results *results, const char *name, const char *unit,
                                                       const char *meaning);

/// Records what made the results, as root attributes: `model_file`, the
/// model's path, and `run_settings`, the run's settings as the caller
/// spells them (fascia run: a JSON object of the solver settings, the
/// backend and the command). The model's fingerprint
/// (fascia_model_fingerprint, 16 hex digits) is always recorded, as
/// `model_fingerprint`. Either text any length.
FASCIA_API fascia_status fascia_results_set_run(fascia_results *results, const char *model_file, const char *settings);

/// What /steps/time means, stored as its attribute `time_meaning` (default
/// "simulation time"); a static run, say, saves rest and equilibrium as two
/// steps of a load factor. At most 255 characters.
FASCIA_API fascia_status fascia_results_set_time_meaning(fascia_results *results, const char *meaning);

/// Steps appended so far.
FASCIA_API int32_t fascia_results_step_count(const fascia_results *results);

/// Finishes the file: moves it to its final path and writes the XDMF sidecar
/// (also through a temporary name). Frees the object and sets *results to
/// NULL in every case; accepts NULL. On error the temporary file is removed;
/// if only the sidecar failed, the .h5 file is complete at its path.
FASCIA_API fascia_status fascia_results_close(fascia_results **results);

/// Abandons a results file: removes the temporary file, frees the object,
/// sets *results to NULL; accepts NULL. Nothing is left at the final path.
FASCIA_API void fascia_results_destroy(fascia_results **results);
/// The XDMF sidecar's path for results path `path`: its .h5 (or .hdf5)
/// suffix replaced by .xdmf, else .xdmf appended. Truncated to size.
FASCIA_API void fascia_results_sidecar_path(const char *path, char *out, size_t size);

#ifdef __cplusplus
}
#endif
#endif
