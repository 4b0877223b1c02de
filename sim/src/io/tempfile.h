// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Temporary names next to an output path (`PATH.tmp-PID-K`) and the rename
// that puts a finished file in place; shared by the HDF5 writers (h5io.c)
// and the text writer of fascia/files.h (files.c).
#ifndef FASCIA_SRC_TEMPFILE_H
#define FASCIA_SRC_TEMPFILE_H

#include <stddef.h>

#include "util/status.h"

/// Creates a file under the first free name `path.tmp-PID-K` exclusively
/// (O_EXCL, so two writers never share one) and writes that name into tmp;
/// *fd is its descriptor, open for writing. A name taken is skipped; any
/// other failure (no such folder, disk full, permission) stops at once with
/// FASCIA_ERR_IO and a message naming the folder and the reason. On error
/// nothing is left behind.
FASCIA_INTERN fascia_status fascia_temp_reserve(fascia_ctx *ctx, const char *what, const char *path, char *tmp,
                                                size_t tmp_size, int *fd);

/// Finds a free temporary name next to path without creating it.
FASCIA_INTERN fascia_status fascia_temp_name(fascia_ctx *ctx, const char *what, const char *path, char *tmp,
                                             size_t tmp_size);

/// Renames tmp to path (replacing any file there). On error tmp is removed
/// and the file at path is untouched.
FASCIA_INTERN fascia_status fascia_commit_temp(fascia_ctx *ctx, const char *what, const char *tmp, const char *path);

#endif
