// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Writing a file under a temporary name and renaming it into place when it
// is complete (fascia/files.h), for every writer of fascia: the HDF5 ones
// reserve their name here (h5io.c), the text and VTK ones write through
// fascia_file. Also finds and removes the temporary files a killed writer
// left behind. And opens inputs without blocking on a FIFO.
#define _POSIX_C_SOURCE 200809L
#include "fascia/files.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include "io/tempfile.h"

// Names tried per file: K = 0 .. TEMP_ATTEMPTS - 1 within one process.
#define TEMP_ATTEMPTS 1000
#define TEMP_PATH_SIZE 4096

const char *fascia_path_folder(const char *path, char *out, size_t size) {
  const char *slash = strrchr(path, '/');
  if (!slash) snprintf(out, size, ".");
  else if (slash == path) snprintf(out, size, "/");
  else snprintf(out, size, "%.*s", (int)(slash - path), path);
  return out;
}

static int temp_candidate(const char *path, int attempt, char *tmp, size_t tmp_size) {
  const int n = snprintf(tmp, tmp_size, "%s.tmp-%ld-%d", path, (long)getpid(), attempt);
  return n > 0 && (size_t)n < tmp_size;
}

static fascia_status no_free_name(fascia_ctx *ctx, const char *what, const char *path, const char *tmp) {
  return FASCIA_FAIL(ctx, FASCIA_ERR_IO,
                     "%s '%s': no free temporary name next to it (%s exists); remove stale '*.tmp-*' files", what,
                     path, tmp);
}

fascia_status fascia_temp_name(fascia_ctx *ctx, const char *what, const char *path, char *tmp, size_t tmp_size) {
  for (int attempt = 0; attempt < TEMP_ATTEMPTS; ++attempt) {
    FASCIA_CHECK(temp_candidate(path, attempt, tmp, tmp_size), ctx, FASCIA_ERR_ARGUMENT,
                 "%s '%s': the path is too long", what, path);
    if (access(tmp, F_OK) != 0) return FASCIA_OK;
  }
  return no_free_name(ctx, what, path, tmp);
}

fascia_status fascia_temp_reserve(fascia_ctx *ctx, const char *what, const char *path, char *tmp, size_t tmp_size,
                                  int *fd) {
  *fd = -1;
  FASCIA_CHECK(path && path[0], ctx, FASCIA_ERR_ARGUMENT, "%s: the output path is empty", what);
  for (int attempt = 0; attempt < TEMP_ATTEMPTS; ++attempt) {
    FASCIA_CHECK(temp_candidate(path, attempt, tmp, tmp_size), ctx, FASCIA_ERR_ARGUMENT,
                 "%s '%s': the path is too long", what, path);
    *fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL, 0666);
    if (*fd >= 0) return FASCIA_OK;
    if (errno == EEXIST) continue; // another writer has this name: the next one
    // anything else (no such folder, no space, no permission) fails every name alike
    const int err = errno;
    char folder[TEMP_PATH_SIZE];
    return FASCIA_FAIL(ctx, FASCIA_ERR_IO, "%s '%s': cannot create a file in folder '%s': %s", what, path,
                       fascia_path_folder(path, folder, sizeof folder), strerror(err));
  }
  return no_free_name(ctx, what, path, tmp);
}

fascia_status fascia_commit_temp(fascia_ctx *ctx, const char *what, const char *tmp, const char *path) {
  if (rename(tmp, path) == 0) return FASCIA_OK;
  const int err = errno;
  remove(tmp);
  return FASCIA_FAIL(ctx, FASCIA_ERR_IO, "%s '%s': cannot move the finished file into place: %s", what, path,
                     strerror(err));
}

// --- fascia_file ------------------------------------------------------------

struct fascia_file {
  fascia_ctx *ctx;
  FILE *stream;
  const char *what; ///< a string literal of the caller
  char path[TEMP_PATH_SIZE], tmp[TEMP_PATH_SIZE + 32];
};

fascia_status fascia_file_open(fascia_ctx *ctx, const char *what, const char *path, fascia_file **out) {
  FASCIA_CHECK(out, ctx, FASCIA_ERR_ARGUMENT, "fascia_file_open: NULL out");
  *out = NULL;
  FASCIA_CHECK(what && path && path[0], ctx, FASCIA_ERR_ARGUMENT, "fascia_file_open: NULL name or empty path");
  FASCIA_CHECK(strlen(path) < TEMP_PATH_SIZE, ctx, FASCIA_ERR_ARGUMENT, "%s '%.200s...': the path is too long",
               what, path);
  fascia_file *f = calloc(1, sizeof *f);
  FASCIA_CHECK(f, ctx, FASCIA_ERR_MEMORY, "%s '%s': out of memory", what, path);
  f->ctx = ctx;
  f->what = what;
  snprintf(f->path, sizeof f->path, "%s", path);
  int fd = -1;
  fascia_status status = fascia_temp_reserve(ctx, what, path, f->tmp, sizeof f->tmp, &fd);
  if (status == FASCIA_OK && !(f->stream = fdopen(fd, "w"))) {
    const int err = errno;
    close(fd);
    remove(f->tmp);
    status = FASCIA_FAIL(ctx, FASCIA_ERR_IO, "%s '%s': cannot open '%s': %s", what, path, f->tmp, strerror(err));
  }
  if (status != FASCIA_OK) {
    free(f);
    return status;
  }
  *out = f;
  return FASCIA_OK;
}

const char *fascia_file_kind(mode_t mode) {
  if (S_ISREG(mode)) return "a file";
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISLNK(mode)) return "a symbolic link";
  return "a file of unknown kind";
}

fascia_status fascia_file_open_input(fascia_ctx *ctx, const char *what, const char *path, FILE **out) {
  FASCIA_CHECK(out, ctx, FASCIA_ERR_ARGUMENT, "fascia_file_open_input: NULL out");
  *out = NULL;
  FASCIA_CHECK(what && path && path[0], ctx, FASCIA_ERR_ARGUMENT, "fascia_file_open_input: NULL name or empty path");
  // O_NONBLOCK: opening a FIFO for reading would wait for a writer
  const int fd = open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) {
    const int err = errno;
    return FASCIA_FAIL(ctx, FASCIA_ERR_IO, "%s '%s': cannot open: %s", what, path, strerror(err));
  }
  struct stat st;
  if (fstat(fd, &st) != 0) {
    const int err = errno;
    close(fd);
    return FASCIA_FAIL(ctx, FASCIA_ERR_IO, "%s '%s': cannot stat: %s", what, path, strerror(err));
  }
  if (!S_ISREG(st.st_mode)) {
    close(fd);
    return FASCIA_FAIL(ctx, FASCIA_ERR_IO, "%s '%s' is %s, not a regular file; give the path of the %s file itself",
                       what, path, fascia_file_kind(st.st_mode), what);
  }
  const int flags = fcntl(fd, F_GETFL);
  FILE *f = flags >= 0 && fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) == 0 ? fdopen(fd, "rb") : NULL;
  if (!f) {
    const int err = errno;
    close(fd);
    return FASCIA_FAIL(ctx, FASCIA_ERR_IO, "%s '%s': cannot open: %s", what, path, strerror(err));
  }
  *out = f;
  return FASCIA_OK;
}

FILE *fascia_file_stream(fascia_file *file) { return file ? file->stream : NULL; }

fascia_status fascia_file_commit(fascia_file **file) {
  if (!file || !*file) return FASCIA_OK;
  fascia_file *f = *file;
  *file = NULL;
  // a failed write marks the stream; the flush and close repeat it and give the reason
  int err = 0;
  const int had_error = ferror(f->stream) != 0;
  errno = 0;
  if (fflush(f->stream) != 0) err = errno;
  if (fclose(f->stream) != 0 && !err) err = errno;
  if (had_error && !err) err = EIO;
  fascia_status status = FASCIA_OK;
  if (err) {
    remove(f->tmp);
    char folder[TEMP_PATH_SIZE];
    status = FASCIA_FAIL(f->ctx, FASCIA_ERR_IO, "%s '%s': cannot write in folder '%s': %s", f->what, f->path,
                         fascia_path_folder(f->path, folder, sizeof folder), strerror(err));
  } else {
    status = fascia_commit_temp(f->ctx, f->what, f->tmp, f->path);
  }
  free(f);
  return status;
}

void fascia_file_discard(fascia_file **file) {
  if (!file || !*file) return;
  fclose((*file)->stream);
  remove((*file)->tmp);
  free(*file);
  *file = NULL;
}

// --- stale temporary files ----------------------------------------------------

// The PID of `name` when it is `base.tmp-PID-K` (base NULL: any base); else 0.
static long temp_owner(const char *name, const char *base) {
  const char *tag = NULL;
  if (base) {
    const size_t n = strlen(base);
    if (strncmp(name, base, n) || strncmp(name + n, ".tmp-", 5)) return 0;
    tag = name + n + 5;
  } else {
    const char *at = strstr(name, ".tmp-");
    for (const char *next = at; next; next = strstr(next + 1, ".tmp-")) at = next; // the last one
    if (!at || at == name) return 0;
    tag = at + 5;
  }
  char *end = NULL;
  const long pid = strtol(tag, &end, 10);
  if (pid <= 0 || end == tag || *end != '-' || !end[1]) return 0;
  for (const char *c = end + 1; *c; ++c)
    if (*c < '0' || *c > '9') return 0;
  return pid;
}

// Removes folder/name when it is a regular file of ours whose writer is gone.
static int remove_if_stale(const char *folder, const char *name, long pid) {
  if (pid == (long)getpid() || kill((pid_t)pid, 0) == 0 || errno != ESRCH) return 0; // alive, or not ours to judge
  char path[2 * TEMP_PATH_SIZE];
  snprintf(path, sizeof path, "%s/%s", folder, name);
  struct stat st;
  if (lstat(path, &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != geteuid()) return 0;
  return unlink(path) == 0;
}

static int remove_stale(const char *folder, const char *base) {
  DIR *d = opendir(folder);
  if (!d) return 0;
  int removed = 0;
  for (struct dirent *e = readdir(d); e; e = readdir(d)) {
    const long pid = temp_owner(e->d_name, base);
    if (pid > 0) removed += remove_if_stale(folder, e->d_name, pid);
  }
  closedir(d);
  return removed;
}

int fascia_file_remove_stale(const char *path) {
  if (!path || !path[0] || strlen(path) >= TEMP_PATH_SIZE) return 0;
  char folder[TEMP_PATH_SIZE];
  fascia_path_folder(path, folder, sizeof folder);
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  return base[0] ? remove_stale(folder, base) : 0;
}

int fascia_file_remove_stale_in(const char *dir) {
  return dir && dir[0] && strlen(dir) < TEMP_PATH_SIZE ? remove_stale(dir, NULL) : 0;
}
