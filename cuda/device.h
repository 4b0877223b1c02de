// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The device solver as the core's solver (sim/src/solver.c) sees it: the
// model uploaded once, and the Newton minimization of a step run on the
// device (device_solver.c), on a GPU or in the host emulation.
#ifndef FASCIA_CUDA_DEVICE_H
#define FASCIA_CUDA_DEVICE_H

#include "launch.h"
#include "solver_internal.h"

typedef struct fascia_device fascia_device;

/// The launcher of a backend name ("cuda", "emulated"), NULL when this
/// build has none.
FASCIA_INTERN const fascia_launcher_ops *fascia_device_ops(const char *backend);

/// 1 when the device solver handles S's model and settings; else 0 and why
/// (for the message or the automatic choice).
FASCIA_INTERN int fascia_device_supports(const fascia_solver *S, char *why, size_t size);

/// Opens the device and uploads S's model (S->sys, S->mask must be set).
FASCIA_INTERN fascia_status fascia_device_create(fascia_solver *S, const fascia_launcher_ops *ops,
                                                 fascia_device **out);
FASCIA_INTERN void fascia_device_destroy(fascia_device **dev);
/// The device in words.
FASCIA_INTERN const char *fascia_device_name(const fascia_device *dev);

/// fascia_newton_minimize on the device: the same algorithm, the same
/// inputs (S->x_base, S->q_base, S->d, S->inertia_target, S->mask) and the
/// same outputs (S->x, S->q, S->d, S->gradient, the report); the state
/// crosses to the device once before and once after.
FASCIA_INTERN fascia_status fascia_device_minimize(fascia_solver *S, int dynamic, int max_iterations,
                                                   fascia_solve_report *report);

/// For tests: the potential energy and its gradient [6N] (free DOFs, the
/// others 0) at frame state x, q.
FASCIA_INTERN fascia_status fascia_device_gradient(fascia_solver *S, const fascia_real *x, const fascia_real *q,
                                                   fascia_real *gradient, fascia_real *energy);
/// For tests: out = H v on the free DOFs at the state of the last
/// fascia_device_gradient (the symmetric Hessian, as fascia_system_hessian_apply).
FASCIA_INTERN fascia_status fascia_device_hessian_apply(fascia_solver *S, const fascia_real *v, fascia_real *out);
/// For tests: the 6x6 diagonal blocks of H [36N] at that state.
FASCIA_INTERN fascia_status fascia_device_hessian_diagonal(fascia_solver *S, fascia_real *blocks);

#endif
