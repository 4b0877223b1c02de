// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The linear solver of the CPU backend's Newton iterations: one object that
// picks among projected PCG (cg.c) on products or on the assembled block
// matrix (assemble.c) or its float copy, and sparse Cholesky (direct.c) on
// the matrix or on its reduction to rigid organs' masters (organs.c); that
// keeps the factorization and decides when to reuse it (chord steps); and
// that hands a solve whose CG stalls to the direct solver. The backend
// (backend_cpu.c) gives it the operator of each step and asks for
// directions; the choice is docs/mechanics.md's "Choosing the linear solver".
#ifndef FASCIA_SRC_LINEAR_SOLVER_H
#define FASCIA_SRC_LINEAR_SOLVER_H

#include "cpu/operator.h"

typedef struct fascia_linear fascia_linear;

/// Makes the solver the settings ask for (def->linear_solver, assembled,
/// precond; auto by the model's size and the factorization's cost). mask
/// is read at every step; organs (may be NULL) for rigid organs' reduced
/// matrix. On failure nothing is left and the context says why.
FASCIA_INTERN fascia_status fascia_linear_create(fascia_ctx *ctx, const fascia_model *model,
                                                 const fascia_solver_def *def, const unsigned char *mask,
                                                 const fascia_organs *organs, fascia_linear **out);
FASCIA_INTERN void fascia_linear_destroy(fascia_linear **linear);

/// A Newton solve begins: op is the step's operator without the solver's
/// parts (the damping, the assembled matrix and its float copy are the
/// solver's); dynamic and mass_coefficient (c1 + c2) of the step, epoch the
/// solver's linear_epoch (a factorization of another is stale). Says in
/// report which solver the step takes.
FASCIA_INTERN void fascia_linear_begin(fascia_linear *linear, const fascia_operator *op, int dynamic,
                                       uint64_t epoch, fascia_solve_report *report);

/// The tangent at the current iterate (the system's last evaluation):
/// assembled, preconditioner and Levenberg weights, or nothing where the
/// kept factorization is reused (gradient_norm2: |gradient|^2 now).
FASCIA_INTERN fascia_status fascia_linear_prepare(fascia_linear *linear, fascia_real gradient_norm2,
                                                  fascia_solve_report *report);

/// Solves (A + shift D) p = rhs on the free unknowns. The direct solver
/// raises *shift until the matrix factors; a CG that stalls hands this
/// solve and later ones of its kind to the direct solver (where set up).
FASCIA_INTERN fascia_status fascia_linear_solve(fascia_linear *linear, const fascia_real *rhs, fascia_real *p,
                                                fascia_real *shift, fascia_solve_report *report);

/// The preconditioner applied to r (a descent direction where a solve gave none).
FASCIA_INTERN void fascia_linear_precondition(const fascia_linear *linear, const fascia_real *r, fascia_real *z);

/// The kept factorization for checkpoints: its size in values (0: none
/// that fits epoch), the values, and a load that says whether it fits.
FASCIA_INTERN int64_t fascia_linear_state_size(const fascia_linear *linear, uint64_t epoch);
FASCIA_INTERN void fascia_linear_state_save(const fascia_linear *linear, fascia_real *out);
FASCIA_INTERN int fascia_linear_state_load(fascia_linear *linear, const fascia_real *in, int64_t count,
                                           uint64_t epoch);

#endif
