// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// HDF5 plumbing shared by io_model.c and io_results.c: quiet error handling,
// HDF5 error text for our messages, and write-to-temporary-then-rename so a
// reader never sees a half-written file at the final path.
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include "fascia/files.h"
#include "fascia/model.h"
#include "io/h5io.h"

void fascia_h5_quiet_begin(fascia_h5_quiet *quiet) {
  quiet->func = NULL;
  quiet->data = NULL;
  H5Eget_auto2(H5E_DEFAULT, &quiet->func, &quiet->data);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

void fascia_h5_quiet_end(const fascia_h5_quiet *quiet) { H5Eset_auto2(H5E_DEFAULT, quiet->func, quiet->data); }

typedef struct error_walk {
  char outer[256], inner[256];
} error_walk;

// HDF5's descriptions can hold line breaks (a write failure embeds ctime()'s
// text) and a long dump of its write call; a message is one line, so breaks
// become spaces and a system error is cut down to its errno text.
static void one_line(char *out, size_t size, const char *desc) {
  const char *said = strstr(desc, "error message = '");
  if (said) {
    const char *head_end = strchr(desc, ':'), *text = said + strlen("error message = '"), *close = strchr(text, '\'');
    const int head = head_end ? (int)(head_end - desc) : 0;
    const int length = close ? (int)(close - text) : (int)strlen(text);
    snprintf(out, size, "%.*s%s%.*s", head, desc, head ? ": " : "", length, text);
  } else {
    snprintf(out, size, "%s", desc);
  }
  for (char *c = out; *c; ++c)
    if (*c == '\n' || *c == '\r' || *c == '\t') *c = ' ';
}

static herr_t walk_error(unsigned n, const H5E_error2_t *err, void *data) {
  error_walk *w = data;
  const char *desc = err->desc && err->desc[0] ? err->desc : "";
  if (n == 0) one_line(w->outer, sizeof w->outer, desc);
  one_line(w->inner, sizeof w->inner, desc);
  return 0;
}

const char *fascia_h5_error(char *buf, size_t size) {
  // The outermost entry says what failed ("unable to open file"), the
  // innermost why ("file signature not found"); both help a user.
  error_walk w = {{0}, {0}};
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, walk_error, &w);
  if (!w.outer[0] && !w.inner[0])
    snprintf(buf, size, "no detail");
  else if (!strcmp(w.outer, w.inner) || !w.inner[0])
    snprintf(buf, size, "%s", w.outer);
  else
    snprintf(buf, size, "%s (%s)", w.outer, w.inner);
  return buf;
}

// HDF5 1.10 cannot recover from a failed write of its metadata cache: the
// H5Fclose that follows fails and leaves a dangling file id that crashes the
// library's exit handler. So an HDF5 write must never fail on a full disk:
// models and checkpoints are built in memory (the core driver) and written
// out with plain writes whose failure is ours to handle; the results file,
// which grows step by step, is flushed after each step and each step checks
// the free space first (fascia_h5_space_check).

fascia_status fascia_h5_create_temp(fascia_ctx *ctx, const char *what, const char *path, char *tmp, size_t tmp_size,
                                    hid_t *file) {
  *file = H5I_INVALID_HID;
  int fd = -1;
  // the name is reserved with O_EXCL first, so a failing H5Fcreate (no space
  // for the superblock) is a failure, never mistaken for a name taken
  FASCIA_TRY(fascia_temp_reserve(ctx, what, path, tmp, tmp_size, &fd));
  close(fd);
  // a failed H5Fcreate, too, leaves HDF5 unable to shut down cleanly
  const fascia_status room = fascia_h5_space_check(ctx, what, path, tmp, 0);
  if (room != FASCIA_OK) {
    remove(tmp);
    return room;
  }
  *file = H5Fcreate(tmp, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (*file >= 0) return FASCIA_OK;
  char detail[600], folder[4096];
  fascia_h5_error(detail, sizeof detail);
  remove(tmp);
  return FASCIA_FAIL(ctx, FASCIA_ERR_IO, "%s '%s': cannot create an HDF5 file in folder '%s' (HDF5: %s)", what, path,
                     fascia_path_folder(path, folder, sizeof folder), detail);
}

fascia_status fascia_h5_create_memory(fascia_ctx *ctx, const char *what, const char *path, hid_t *file) {
  *file = H5I_INVALID_HID;
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  // grows in steps of 1 MiB; no backing store: fascia_h5_finish_memory writes the image
  if (fapl >= 0 && H5Pset_fapl_core(fapl, (size_t)1 << 20, 0) >= 0)
    *file = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  if (fapl >= 0) H5Pclose(fapl);
  if (*file >= 0) return FASCIA_OK;
  char detail[600];
  fascia_h5_error(detail, sizeof detail);
  return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "%s '%s': cannot build the file in memory (HDF5: %s)", what, path,
                     detail);
}

// Writes all of data to fd: 0, else errno.
static int write_all(int fd, const unsigned char *data, size_t size) {
  while (size > 0) {
    const ssize_t n = write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return n < 0 ? errno : EIO;
    data += n, size -= (size_t)n;
  }
  return 0;
}

fascia_status fascia_h5_finish_memory(fascia_ctx *ctx, const char *what, hid_t *file, const char *path) {
  void *image = NULL;
  ssize_t size = -1;
  if (H5Fflush(*file, H5F_SCOPE_LOCAL) >= 0) size = H5Fget_file_image(*file, NULL, 0);
  if (size > 0 && (image = malloc((size_t)size)) && H5Fget_file_image(*file, image, (size_t)size) != size) size = -1;
  char detail[600];
  if (size <= 0 || !image) fascia_h5_error(detail, sizeof detail);
  H5Fclose(*file); // in memory: nothing to write, cannot fail on a full disk
  *file = H5I_INVALID_HID;
  if (size <= 0 || !image) {
    free(image);
    return FASCIA_FAIL(ctx, size > 0 ? FASCIA_ERR_MEMORY : FASCIA_ERR_IO, "%s '%s': cannot take the file image (%s)",
                       what, path, size > 0 ? "out of memory" : detail);
  }
  char tmp[4200], folder[4096];
  int fd = -1;
  fascia_status status = fascia_temp_reserve(ctx, what, path, tmp, sizeof tmp, &fd);
  if (status == FASCIA_OK) {
    int err = write_all(fd, image, (size_t)size);
    if (close(fd) != 0 && !err) err = errno;
    if (err) {
      remove(tmp);
      status = FASCIA_FAIL(ctx, FASCIA_ERR_IO, "%s '%s': cannot write %lld bytes in folder '%s': %s", what, path,
                           (long long)size, fascia_path_folder(path, folder, sizeof folder), strerror(err));
    } else {
      status = fascia_commit_temp(ctx, what, tmp, path);
    }
  }
  free(image);
  return status;
}

fascia_status fascia_h5_space_check(fascia_ctx *ctx, const char *what, const char *path, const char *tmp,
                                    int64_t bytes) {
  char folder[4096];
  const double needed = (double)bytes + (double)FASCIA_H5_SPACE_MARGIN;
  struct rlimit limit;
  struct stat file;
  if (getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY && stat(tmp, &file) == 0 &&
      (double)file.st_size + needed > (double)limit.rlim_cur)
    return FASCIA_FAIL(ctx, FASCIA_ERR_IO,
                       "%s '%s': the file would pass this process's file size limit of %.0f KiB (ulimit -f); "
                       "raise the limit or save fewer steps",
                       what, path, (double)limit.rlim_cur / 1024);
  struct statvfs fs;
  if (statvfs(tmp, &fs) != 0) return FASCIA_OK; // cannot tell: let the write say
  const double free_bytes = (double)fs.f_bavail * (double)fs.f_frsize;
  if (free_bytes >= needed) return FASCIA_OK;
  return FASCIA_FAIL(ctx, FASCIA_ERR_IO,
                     "%s '%s': the disk holding folder '%s' is full (%.0f KiB free, %.0f KiB needed to go on); "
                     "free some space or write elsewhere",
                     what, path, fascia_path_folder(path, folder, sizeof folder), free_bytes / 1024, needed / 1024);
}

herr_t fascia_h5_attr_string(hid_t loc, const char *name, const char *value) {
  herr_t status = -1;
  hid_t type = H5Tcopy(H5T_C_S1), space = H5Screate(H5S_SCALAR), attr = H5I_INVALID_HID;
  if (type < 0 || space < 0) goto cleanup;
  if (H5Tset_size(type, strlen(value) + 1) < 0 || H5Tset_strpad(type, H5T_STR_NULLTERM) < 0 ||
      H5Tset_cset(type, H5T_CSET_UTF8) < 0)
    goto cleanup;
  attr = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  if (attr < 0) goto cleanup;
  status = H5Awrite(attr, type, value);
cleanup:
  if (attr >= 0) H5Aclose(attr);
  if (space >= 0) H5Sclose(space);
  if (type >= 0) H5Tclose(type);
  return status;
}

herr_t fascia_h5_attr_int(hid_t loc, const char *name, int32_t value) {
  herr_t status = -1;
  hid_t space = H5Screate(H5S_SCALAR), attr = H5I_INVALID_HID;
  if (space < 0) return -1;
  attr = H5Acreate2(loc, name, H5T_STD_I32LE, space, H5P_DEFAULT, H5P_DEFAULT);
  if (attr >= 0) status = H5Awrite(attr, H5T_NATIVE_INT32, &value);
  if (attr >= 0) H5Aclose(attr);
  H5Sclose(space);
  return status;
}

int fascia_h5_link_exists(hid_t file, const char *name) {
  char prefix[512];
  const size_t length = strlen(name);
  if (length >= sizeof prefix) return 0;
  for (size_t k = 1; k <= length; ++k)
    if (k == length || name[k] == '/') {
      memcpy(prefix, name, k);
      prefix[k] = 0;
      if (H5Lexists(file, prefix, H5P_DEFAULT) <= 0) return 0;
    }
  return 1;
}

// ---------------------------------------------------------------------------
// Reading

void fascia_hdf5_quiet(void) { H5Eset_auto2(H5E_DEFAULT, NULL, NULL); }

hid_t fascia_h5_keep(fascia_h5_scope *scope, hid_t id) {
  if (id < 0) return id;
  if (scope->count == FASCIA_H5_SCOPE_SIZE) { // a bug in the caller: fail the call, leak nothing
    H5Idec_ref(id);
    return H5I_INVALID_HID;
  }
  scope->id[scope->count++] = id;
  return id;
}

void fascia_h5_scope_close(fascia_h5_scope *scope) {
  while (scope->count > 0) {
    const hid_t id = scope->id[--scope->count];
    switch (H5Iget_type(id)) {
    case H5I_FILE: H5Fclose(id); break;
    case H5I_GROUP: H5Gclose(id); break;
    case H5I_DATATYPE: H5Tclose(id); break;
    case H5I_DATASPACE: H5Sclose(id); break;
    case H5I_DATASET: H5Dclose(id); break;
    case H5I_ATTR: H5Aclose(id); break;
    case H5I_GENPROP_LST: H5Pclose(id); break;
    default: H5Idec_ref(id); break;
    }
  }
}

int fascia_h5_number_type_ok(hid_t type) {
  const H5T_class_t cls = H5Tget_class(type);
  if (cls != H5T_INTEGER && cls != H5T_FLOAT) return 0;
  const size_t size = H5Tget_size(type), precision = H5Tget_precision(type);
  const int offset = H5Tget_offset(type);
  if ((size != 1 && size != 2 && size != 4 && size != 8) || precision == 0 || offset < 0 ||
      (size_t)offset + precision > 8 * size)
    return 0;
  if (cls == H5T_INTEGER) return 1;
  size_t sign_bit = 0, exponent_at = 0, exponent_bits = 0, mantissa_at = 0, mantissa_bits = 0;
  if (H5Tget_fields(type, &sign_bit, &exponent_at, &exponent_bits, &mantissa_at, &mantissa_bits) < 0) return 0;
  const size_t bits = (size_t)offset + precision;
  return sign_bit < bits && exponent_bits > 0 && exponent_bits < 64 && exponent_at + exponent_bits <= bits &&
         mantissa_bits > 0 && mantissa_at + mantissa_bits <= bits && H5Tget_ebias(type) < ((size_t)1 << exponent_bits);
}

// Bytes [at, at + count) of f into out, those past the end of the file as
// zeros (as HDF5 reads them).
static void read_zero_filled(FILE *f, long long at, unsigned char *out, size_t count) {
  memset(out, 0, count);
  if (at >= 0 && fseeko(f, (off_t)at, SEEK_SET) == 0 && fread(out, 1, count, f) == 0) clearerr(f);
}

// A little-endian address or length of `size` bytes (2 to 8; larger ones
// count their low 8 bytes unless a higher byte is set: then all ones).
static unsigned long long little_endian(const unsigned char *p, int size) {
  unsigned long long v = 0;
  for (int k = size - 1; k >= 0; --k) {
    if (k >= 8) {
      if (p[k]) return ~0ULL;
      continue;
    }
    v = v << 8 | p[k];
  }
  return v;
}

// HDF5 1.10 reads a version 0 or 1 superblock's driver information block,
// allocating and reading (zeros past the end) as many bytes as the block
// says, before it compares the superblock's end-of-file address with the
// file's length: a damaged size field made it fill 4 GB (a fuzzed 50-byte
// file; tests/t208). 1 where that block, if any, fits in the file; else 0
// and why in detail. Later reads stop at the checked end of the file.
static int driver_block_fits(const char *path, char *detail, size_t detail_size) {
  FILE *f = fopen(path, "rb");
  if (!f) return 1; // H5Fopen reports it
  struct stat st;
  const long long length = fstat(fileno(f), &st) == 0 ? (long long)st.st_size : 0;
  static const unsigned char signature[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
  int fits = 1;
  // the superblock is at 0, 512, 1024, 2048, ... (after a user block)
  for (long long at = 0; fits && at + 8 <= length; at = at ? 2 * at : 512) {
    unsigned char sb[128];
    read_zero_filled(f, at, sb, sizeof sb);
    if (memcmp(sb, signature, 8) != 0) continue;
    const int version = sb[8], O = sb[13];
    if (version <= 1 && O >= 2 && O <= 16) {
      const unsigned char *addresses = sb + (version == 0 ? 24 : 28); // base, free space, end of file, driver block
      const unsigned long long driver = little_endian(addresses + 3 * O, O);
      if (driver != ~0ULL && driver < (unsigned long long)length) {
        unsigned char header[16]; // version, 3 reserved, size (4), driver's name (8)
        read_zero_filled(f, at + (long long)driver, header, sizeof header);
        const unsigned long long size = little_endian(header + 4, 4);
        if (at + (long long)driver + 16 + (long long)size > length) {
          snprintf(detail, detail_size,
                   "its superblock's driver information block says %llu bytes at byte %lld, past the end of "
                   "the file at %lld bytes",
                   size, at + (long long)driver + 16, length);
          fits = 0;
        }
      }
    }
    break; // HDF5 takes the first signature
  }
  fclose(f);
  return fits;
}

fascia_status fascia_h5_open_read(fascia_ctx *ctx, const char *what, const char *path, const char *remedy,
                                  hid_t *file) {
  *file = H5I_INVALID_HID;
  // HDF5's own open blocks forever on a FIFO: only a regular file goes on
  FILE *probe = NULL;
  FASCIA_TRY(fascia_file_open_input(ctx, what, path, &probe));
  fclose(probe);
  char detail[600];
  const htri_t is_hdf5 = H5Fis_hdf5(path);
  FASCIA_CHECK(is_hdf5 > 0, ctx, FASCIA_ERR_IO, "%s '%s': not an HDF5 file (%s); %s", what, path,
               is_hdf5 < 0 ? fascia_h5_error(detail, sizeof detail) : "no HDF5 signature", remedy);
  FASCIA_CHECK(driver_block_fits(path, detail, sizeof detail), ctx, FASCIA_ERR_IO,
               "%s '%s': cannot open as HDF5 (%s); the file is damaged or truncated", what, path, detail);
  fascia_h5_scope scope = FASCIA_H5_SCOPE_INIT;
  const hid_t fapl = fascia_h5_keep(&scope, H5Pcreate(H5P_FILE_ACCESS));
  if (fapl >= 0) H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG);
  *file = H5Fopen(path, H5F_ACC_RDONLY, fapl >= 0 ? fapl : H5P_DEFAULT);
  if (*file < 0) fascia_h5_error(detail, sizeof detail);
  fascia_h5_scope_close(&scope);
  FASCIA_CHECK(*file >= 0, ctx, FASCIA_ERR_IO, "%s '%s': cannot open as HDF5 (%s); the file is damaged or truncated",
               what, path, detail);
  return FASCIA_OK;
}
