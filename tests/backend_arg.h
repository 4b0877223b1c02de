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

/// Whether a case kept to the CPU backend (say, the direct solver or the
/// assembled matrix, which the device backends refuse: cuda/device_solver.c)
/// runs on backend; where not, says which case is skipped and why, and the
/// rest of the test runs there.
static inline int backend_runs_cpu_case(const char *backend, const char *name, const char *why) {
  if (!strcmp(backend, "cpu")) return 1;
  printf("skipped on %s: %s: %s\n", backend, name, why);
  return 0;
}

/// CG settings for the static solves of the cantilevers, where CG solves
/// them (a device backend's only linear solver): at CG's default tolerance,
/// 1e-3, their Newton iterations stall, on the CPU's CG too. The direct
/// solver, auto's choice on the CPU for these models, ignores them.
static inline void backend_static_cg(fascia_solver_def *sd) {
  sd->cg_tolerance = 1e-6;
  sd->cg_iterations = 1000;
}

#endif
