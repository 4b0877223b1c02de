// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Output files that never appear half written: every file fascia writes
// (models, results, checkpoints, text and VTK outputs) is created under a
// temporary name next to its final path, `PATH.tmp-PID-K` (PID: the
// writing process, K: 0, 1, ... within it), and renamed into place only
// once it is complete. A killed writer leaves its temporary file behind;
// fascia_file_remove_stale removes those whose process is gone.
#ifndef FASCIA_FILES_H
#define FASCIA_FILES_H

#include <stdio.h>
#include <sys/types.h>

#include "fascia/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/// A text or binary file being written under its temporary name.
typedef struct fascia_file fascia_file;

/// Creates `path.tmp-PID-K` exclusively (a name no other file has) and opens
/// it for writing. `what` names the file in messages ("history",
/// "preview"). On error *out is NULL, nothing is created, and the message
/// names the folder and the reason (FASCIA_ERR_IO; _ARGUMENT for an empty or
/// too long path).
FASCIA_API fascia_status fascia_file_open(fascia_ctx *ctx, const char *what, const char *path, fascia_file **out);
/// The stream to write to (valid until commit or discard).
FASCIA_API FILE *fascia_file_stream(fascia_file *file);
/// Flushes and closes the file and renames it to its final path, replacing
/// any file there. On error (a write failed, disk full) the temporary file is
/// removed, the file at the final path is untouched and the message names
/// the folder and the reason. Frees *file either way and sets it to NULL;
/// accepts NULL (returns FASCIA_OK).
FASCIA_API fascia_status fascia_file_commit(fascia_file **file);
/// Closes and removes the temporary file; the final path is untouched.
/// Accepts NULL and sets *file to NULL.
FASCIA_API void fascia_file_discard(fascia_file **file);

/// Opens the input file `path` for reading ("rb") without ever blocking:
/// the path is opened non-blocking and refused unless it is a regular file
/// (a FIFO would block the open, or the read, forever; a device or a folder
/// is no input). `what` names the file in messages ("model", "drive"). On
/// error *out is NULL and the status is FASCIA_ERR_IO with a message naming
/// the path and what it is ("'P' is a FIFO, not a regular file") or why it
/// cannot be opened.
FASCIA_API fascia_status fascia_file_open_input(fascia_ctx *ctx, const char *what, const char *path, FILE **out);

/// What a file's type (the st_mode of stat or lstat) makes it, for messages
/// such as "'P' is a folder, not a regular file": "a file" (regular), "a
/// folder", "a FIFO (named pipe)", "a character device", "a block device",
/// "a socket", "a symbolic link", or "a file of unknown kind".
FASCIA_API const char *fascia_file_kind(mode_t mode);

/// The folder of path, into out (size bytes) and returned: "." when path
/// names none, "/" for the root.
FASCIA_API const char *fascia_path_folder(const char *path, char *out, size_t size);

/// Removes the temporary files `path.tmp-PID-K` that a process of this host
/// no longer running left next to `path` (a kill during a write). Files of
/// running processes, of other users and other names are left alone.
/// Returns how many were removed.
FASCIA_API int fascia_file_remove_stale(const char *path);
/// The same for every temporary file `NAME.tmp-PID-K` in folder `dir`.
FASCIA_API int fascia_file_remove_stale_in(const char *dir);

#ifdef __cplusplus
}
#endif

#endif
