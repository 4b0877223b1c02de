// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The solver tests that run on every backend (registered with BACKENDS in
// tests/CMakeLists.txt): `--backend NAME` picks it, and
// a backend that cannot run here makes the test skip (exit 77) with a line
// that says why.
#ifndef FASCIA_TESTS_BACKEND_ARG_H
#define FASCIA_TESTS_BACKEND_ARG_H

#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "fascia/solver.h"

/// The value of --backend, or fallback.
static inline const char *backend_arg(int argc, char **argv, const char *fallback) {
  for (int k = 1; k + 1 < argc; ++k)
    if (!strcmp(argv[k], "--backend")) return argv[k + 1];
  return fallback;
}

/// Exits with TEST_SKIP, saying why, when backend cannot run on this machine.
static inline void backend_skip_unless_available(const char *backend) {
  char why[512];
  if (fascia_backend_available(backend, why, sizeof why)) return;
  printf("skipped: backend %s cannot run here: %s\n", backend, why);
  exit(TEST_SKIP);
}

#endif
