// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Replays files through a fuzz harness without libFuzzer (the regression
// tests of tests/fuzz/CMakeLists.txt): every argument is a file or a folder
// of files; each is passed once to LLVMFuzzerTestOneInput. A crash, a
// sanitizer report or an abort in the harness (an error without a message)
// fails the test; a clean refusal passes. Missing folders are skipped.
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>

// Under AddressSanitizer (which reserves terabytes of address space) the
// allocator itself refuses absurd sizes; elsewhere an address-space limit
// does, so that a regression makes the test fail instead of the machine swap.
#if defined(__SANITIZE_ADDRESS__)
#define REPLAY_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define REPLAY_ASAN 1
#endif
#endif
#define REPLAY_ADDRESS_SPACE ((rlim_t)8 << 30)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv);

static int replay_file(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "replay: cannot open '%s'\n", path);
    return 1;
  }
  size_t size = 0, capacity = 4096;
  uint8_t *data = malloc(capacity);
  size_t got;
  while (data && (got = fread(data + size, 1, capacity - size, f)) > 0) {
    size += got;
    if (size == capacity) {
      uint8_t *bigger = realloc(data, capacity *= 2);
      if (!bigger) free(data);
      data = bigger;
    }
  }
  fclose(f);
  if (!data) {
    fprintf(stderr, "replay: out of memory for '%s'\n", path);
    return 1;
  }
  LLVMFuzzerTestOneInput(data, size);
  free(data);
  return 0;
}

static int compare_names(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

// Replays the regular files of folder dir in name order (deterministic).
static int replay_dir(const char *dir, int *count) {
  DIR *d = opendir(dir);
  if (!d) return 0;
  char **names = NULL;
  size_t n = 0;
  struct dirent *e;
  while ((e = readdir(d)) != NULL) {
    if (e->d_name[0] == '.') continue;
    char **more = realloc(names, (n + 1) * sizeof *names);
    if (!more) break;
    names = more;
    names[n] = malloc(strlen(dir) + strlen(e->d_name) + 2);
    if (!names[n]) break;
    sprintf(names[n++], "%s/%s", dir, e->d_name);
  }
  closedir(d);
  qsort(names, n, sizeof *names, compare_names);
  int failed = 0;
  for (size_t k = 0; k < n; ++k) {
    struct stat st;
    if (stat(names[k], &st) == 0 && S_ISREG(st.st_mode)) {
      failed |= replay_file(names[k]);
      ++*count;
    }
    free(names[k]);
  }
  free(names);
  return failed;
}

int main(int argc, char **argv) {
#ifndef REPLAY_ASAN
  const struct rlimit limit = {REPLAY_ADDRESS_SPACE, REPLAY_ADDRESS_SPACE};
  setrlimit(RLIMIT_AS, &limit);
#endif
  LLVMFuzzerInitialize(&argc, &argv);
  int failed = 0, count = 0;
  for (int k = 1; k < argc; ++k) {
    struct stat st;
    if (stat(argv[k], &st) != 0) continue;
    if (S_ISDIR(st.st_mode))
      failed |= replay_dir(argv[k], &count);
    else
      failed |= replay_file(argv[k]), ++count;
  }
  if (failed) return 1;
  if (count == 0) fprintf(stderr, "replay: no input found\n");
  return 0;
}
