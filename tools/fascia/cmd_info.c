// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia info`: version, build options, which parts were built and which
// solver backends can run here (fascia_backend_available).
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "fascia/fascia.h"

enum { PREP_STATUS_SIZE = 8192 }; // the line holds two folders
// OpenBLAS's own count, read as it loaded (weak: another BLAS may stand in for it)
extern int openblas_get_num_threads(void) __attribute__((weak));

int cmd_info(int argc, char **argv) {
  for (int k = 1; k < argc; ++k)
    if (!strcmp(argv[k], "--help")) {
      printf("usage: fascia info\n\nPrints the version, the worker threads, OpenMP's wait policy and spin\n"
             "count, OpenBLAS's thread count (as set, and as the library took it), where fascia prep's\n"
             "module is (or why there is none) and, one line each, whether the solver backends cpu, cuda\n"
             "and emulated can run here (and on what, or why not).\n");
      return 0;
    } else if (strcmp(argv[k], "--verbose")) {
      fprintf(stderr, "fascia info: unknown option '%s'\n", argv[k]);
      return 2;
    }
  printf("fascia %s\n", fascia_version());
  fascia_ctx *ctx = cli_ctx(0, 0);
  printf("threads: %d\n", fascia_ctx_threads(ctx));
  const char *policy = getenv("OMP_WAIT_POLICY"); // main.c sets PASSIVE unless the user chose
  const char *spin = getenv("GOMP_SPINCOUNT");
  printf("openmp wait policy: %s\n", policy ? policy : "the runtime's default");
  printf("openmp spin count: %s\n", spin ? spin : "the runtime's default");
  const char *blas = getenv("OPENBLAS_NUM_THREADS"); // main.c sets 1 unless the user chose
  printf("openblas threads: %s\n", blas ? blas : "the library's default");
  if (openblas_get_num_threads) printf("openblas threads in use: %d\n", openblas_get_num_threads());
  char prep[PREP_STATUS_SIZE];
  cli_prep_status(prep, sizeof prep);
  printf("prep: %s\n", prep);
  fascia_ctx_destroy(&ctx);
  // "auto" is not listed: it is the first of these that is available and
  // runs the model (the emulation is never chosen by itself)
  for (int k = 0; fascia_backend_name(k); ++k) {
    const char *name = fascia_backend_name(k);
    char detail[512];
    if (fascia_backend_available(name, detail, sizeof detail))
      printf("backend %s: available (%s)\n", name, detail);
    else
      printf("backend %s: not available: %s\n", name, detail);
  }
  return 0;
}
