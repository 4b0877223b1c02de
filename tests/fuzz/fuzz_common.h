// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Helpers shared by the fuzz harnesses (tests/fuzz/fuzz_*.c): a reader that
// consumes the fuzzer's bytes as small integers and doubles, a private
// scratch folder, and the rule every harness checks: a refused input comes
// with a readable message (an error without one is a finding, like a crash).
#ifndef FASCIA_TESTS_FUZZ_COMMON_H
#define FASCIA_TESTS_FUZZ_COMMON_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fascia/fascia.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv);

/// The fuzzer's bytes, consumed from the front; reads past the end give 0.
typedef struct fuzz_bytes {
  const uint8_t *data;
  size_t size, at;
} fuzz_bytes;

static inline int fuzz_left(const fuzz_bytes *b) { return b->at < b->size; }

static inline uint32_t fuzz_u8(fuzz_bytes *b) { return b->at < b->size ? b->data[b->at++] : 0; }

static inline uint32_t fuzz_u16(fuzz_bytes *b) {
  const uint32_t lo = fuzz_u8(b);
  return lo | fuzz_u8(b) << 8;
}

static inline uint32_t fuzz_u32(fuzz_bytes *b) {
  const uint32_t lo = fuzz_u16(b);
  return lo | fuzz_u16(b) << 16;
}

static inline double fuzz_raw_double(fuzz_bytes *b) {
  uint64_t bits = fuzz_u32(b);
  bits |= (uint64_t)fuzz_u32(b) << 32;
  double x;
  memcpy(&x, &bits, sizeof x);
  return x;
}

#define FUZZ_SCRATCH_FILES 16

/// The scratch folder of this process and the files made in it, removed at exit.
typedef struct fuzz_scratch {
  char dir[512];
  char files[FUZZ_SCRATCH_FILES][1024];
  int count;
} fuzz_scratch;

static fuzz_scratch fuzz_scratch_state;

static inline void fuzz_scratch_remove(void) {
  for (int k = 0; k < fuzz_scratch_state.count; ++k) remove(fuzz_scratch_state.files[k]);
  if (fuzz_scratch_state.dir[0]) rmdir(fuzz_scratch_state.dir);
}

/// Path of file `name` in a folder of this process under $TMPDIR (or /tmp),
/// made on first use and removed (with the files named here) at exit. The
/// returned string lives as long as the process.
static inline const char *fuzz_scratch_path(const char *name) {
  fuzz_scratch *s = &fuzz_scratch_state;
  if (!s->dir[0]) {
    const char *base = getenv("TMPDIR");
    snprintf(s->dir, sizeof s->dir, "%s/fascia-fuzz-XXXXXX", base && base[0] ? base : "/tmp");
    if (!mkdtemp(s->dir)) {
      perror("fuzz: mkdtemp");
      abort();
    }
    atexit(fuzz_scratch_remove);
  }
  for (int k = 0; k < s->count; ++k) {
    const char *slash = strrchr(s->files[k], '/');
    if (slash && !strcmp(slash + 1, name)) return s->files[k];
  }
  const size_t dir_length = strlen(s->dir), name_length = strlen(name);
  if (s->count == FUZZ_SCRATCH_FILES || dir_length + name_length + 2 > sizeof s->files[0]) abort();
  char *path = s->files[s->count++];
  memcpy(path, s->dir, dir_length);
  path[dir_length] = '/';
  memcpy(path + dir_length + 1, name, name_length + 1);
  return path;
}

/// Writes size bytes to path; aborts when the scratch folder is unusable
/// (a broken harness, not a finding in fascia).
static inline void fuzz_write_file(const char *path, const void *data, size_t size) {
  FILE *f = fopen(path, "wb");
  if (!f || (size && fwrite(data, 1, size, f) != size) || fclose(f) != 0) {
    perror(path);
    abort();
  }
}

/// Every refusal must say why: a failing status with an empty message is a
/// finding (abort so that libFuzzer keeps the input).
static inline void fuzz_check_refusal(const fascia_ctx *ctx, fascia_status status, const char *what) {
  if (status == FASCIA_OK) return;
  const char *message = fascia_ctx_message(ctx);
  if (!message || !message[0]) {
    fprintf(stderr, "fuzz: %s failed with %s and no message\n", what, fascia_status_name(status));
    abort();
  }
  if (status == FASCIA_ERR_INTERNAL) {
    fprintf(stderr, "fuzz: %s reported an internal error on input: %s\n", what, message);
    abort();
  }
}

#endif
