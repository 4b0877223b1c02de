// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The backends' registry (backend.c) and the operators of a solver's
// backend for the tests; the contract itself: sim/contract/backend.h.
#ifndef FASCIA_SRC_BACKEND_H
#define FASCIA_SRC_BACKEND_H

#include "contract/backend.h"
#include "util/status.h"


/// The registry in priority order, count entries.
FASCIA_INTERN const fascia_backend_ops *const *fascia_backends(int *count);
/// Most backends in the registry: the built-in three and those registered.
#define FASCIA_BACKEND_MAX 8
/// Adds a backend after the built-in ones (lower priority for "auto", which
/// takes it only when ops->automatic is set); its name must be new. The
/// registry is the program's: register before making solvers, from one
/// thread.
FASCIA_INTERN fascia_status fascia_backend_register(fascia_ctx *ctx, const fascia_backend_ops *ops);
/// The backend of a name, NULL if there is none of that name.
FASCIA_INTERN const fascia_backend_ops *fascia_backend_find(const char *name);

/// Creates the backend def->backend names ("auto": the first in priority
/// order that is available and supports the setup). describe gets what runs
/// and, for "auto", why each backend before it was skipped.
FASCIA_INTERN fascia_status fascia_backend_pick(const fascia_backend_setup *setup, fascia_backend **out,
                                                char *describe, size_t size);

/// The same for the tests: the operators of a solver's backend.
FASCIA_INTERN fascia_status fascia_solver_backend_gradient(struct fascia_solver *S, const fascia_real *x,
                                                           const fascia_real *q, fascia_real *gradient,
                                                           fascia_real *energy);
FASCIA_INTERN fascia_status fascia_solver_backend_hessian_apply(struct fascia_solver *S, const fascia_real *v,
                                                                fascia_real *out);
FASCIA_INTERN fascia_status fascia_solver_backend_hessian_diagonal(struct fascia_solver *S, fascia_real *blocks);

#endif
