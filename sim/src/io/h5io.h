// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// HDF5 plumbing shared by the model and results files (io_model.c,
// io_results.c): silencing HDF5's own error printing, turning its error stack
// into one readable phrase, and writing a file under a temporary name that is
// renamed into place only once it is complete.
#ifndef FASCIA_SRC_H5IO_H
#define FASCIA_SRC_H5IO_H

#include <hdf5.h>

#include "fascia/results.h"
#include "util/status.h"
#include "io/tempfile.h"

/// HDF5's automatic error printer, saved while fascia has it switched off.
typedef struct fascia_h5_quiet {
  H5E_auto2_t func;
  void *data;
} fascia_h5_quiet;

/// Switches HDF5's automatic error printing off (libraries never print) and
/// remembers the previous printer; pair with fascia_h5_quiet_end.
FASCIA_INTERN void fascia_h5_quiet_begin(fascia_h5_quiet *quiet);
FASCIA_INTERN void fascia_h5_quiet_end(const fascia_h5_quiet *quiet);

/// Writes a short description of HDF5's current error stack into buf, e.g.
/// "unable to open file (file signature not found)", or "no detail" when
/// the stack is empty. Call it right after the failing HDF5 call: the next
/// HDF5 call clears the stack. Returns buf.
FASCIA_INTERN const char *fascia_h5_error(char *buf, size_t size);

/// Creates an empty HDF5 file next to `path` under a name no other file has
/// (`path.tmp-PID-K`, tempfile.h), and writes that name into tmp. `what`
/// names the kind of file in messages ("results"). On error nothing is
/// created and the status is FASCIA_ERR_IO (or _ARGUMENT for a path too
/// long); the message names the folder and the reason.
FASCIA_INTERN fascia_status fascia_h5_create_temp(fascia_ctx *ctx, const char *what, const char *path, char *tmp,
                                                  size_t tmp_size, hid_t *file);

/// Creates an HDF5 file in memory (nothing on disk yet) for a file written
/// in one go (model, checkpoint); fascia_h5_finish_memory puts it on disk.
FASCIA_INTERN fascia_status fascia_h5_create_memory(fascia_ctx *ctx, const char *what, const char *path, hid_t *file);
/// Closes a file of fascia_h5_create_memory (*file becomes invalid) and
/// writes its bytes to a temporary file next to path, renamed to path when
/// complete. On error (disk full) no temporary file is left and path is
/// untouched; the message names the folder and the reason.
FASCIA_INTERN fascia_status fascia_h5_finish_memory(fascia_ctx *ctx, const char *what, hid_t *file, const char *path);

/// Free space, bytes, kept beyond the next write of a growing HDF5 file:
/// room for the metadata HDF5 writes when it flushes.
#define FASCIA_H5_SPACE_MARGIN FASCIA_RESULTS_SPACE_MARGIN
/// FASCIA_ERR_IO with a message naming the folder and the free space when
/// the disk holding tmp has less than bytes + FASCIA_H5_SPACE_MARGIN free.
FASCIA_INTERN fascia_status fascia_h5_space_check(fascia_ctx *ctx, const char *what, const char *path,
                                                  const char *tmp, int64_t bytes);

/// Small attribute writers; each returns a negative value on failure (the
/// HDF5 error stack tells why).
/// 1 when every link along the absolute path `name` exists (H5Lexists fails
/// on a missing intermediate group, so each prefix is tested in turn).
FASCIA_INTERN int fascia_h5_link_exists(hid_t file, const char *name);
FASCIA_INTERN herr_t fascia_h5_attr_string(hid_t loc, const char *name, const char *value);
FASCIA_INTERN herr_t fascia_h5_attr_int(hid_t loc, const char *name, int32_t value);

// --- reading ---------------------------------------------------------------

/// The HDF5 ids one reader function holds, closed together on its single
/// cleanup path (newest first, whatever their kind: file, group, dataset,
/// dataspace, datatype, attribute, property list), so that no error path can
/// forget one. Start with FASCIA_H5_SCOPE_INIT.
#define FASCIA_H5_SCOPE_SIZE 16
typedef struct fascia_h5_scope {
  hid_t id[FASCIA_H5_SCOPE_SIZE];
  int count;
} fascia_h5_scope;
#define FASCIA_H5_SCOPE_INIT {{0}, 0}

/// Records id (when valid) in scope and returns it; an invalid id is
/// returned as it is. A full scope closes id at once and returns
/// H5I_INVALID_HID, so the caller sees a failed call.
FASCIA_INTERN hid_t fascia_h5_keep(fascia_h5_scope *scope, hid_t id);

/// Closes every id recorded in scope, newest first, and empties it.
FASCIA_INTERN void fascia_h5_scope_close(fascia_h5_scope *scope);

/// 1 when `type`, a file's integer or floating-point type, has a layout HDF5
/// can convert safely: 1, 2, 4 or 8 bytes, its bits (offset, precision, and
/// for reals the sign, exponent and mantissa fields) inside them. HDF5 1.10
/// converts a damaged type without these checks and writes past its own
/// buffers (a crash on a corrupt file), so readers call this before H5Dread
/// or H5Aread of numbers. 0 for any other type.
FASCIA_INTERN int fascia_h5_number_type_ok(hid_t type);

/// Opens `path` read-only for a reader of `what` ("model", "checkpoint"),
/// with strong close (closing the file closes anything left open in it). A
/// missing or unreadable file, one that is not HDF5, or one HDF5 cannot open
/// is FASCIA_ERR_IO with a message naming the file; `remedy` ends the
/// not-HDF5 message ("expected a model written by 'fascia prep'"). On error
/// *file is H5I_INVALID_HID.
FASCIA_INTERN fascia_status fascia_h5_open_read(fascia_ctx *ctx, const char *what, const char *path,
                                                const char *remedy, hid_t *file);

#endif
