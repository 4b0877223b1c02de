// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Private layout of the solver and the stages solver.c orchestrates:
// newton.c (minimization with line search and damping) over a backend
// (contract/backend.h), motion.c (prescribed rigid motions).
#ifndef FASCIA_SRC_SOLVER_INTERNAL_H
#define FASCIA_SRC_SOLVER_INTERNAL_H

#include "fascia/solver.h"
#include "cpu/system.h"
#include "solve/motion.h"

typedef struct fascia_organs fascia_organs; // organs.c: rigid organs, organs driven by the caller

struct fascia_backend;
struct fascia_step_values;

struct fascia_solver {
  fascia_ctx *ctx;
  const fascia_model *model;
  fascia_solver_def def;
  fascia_system *sys;
  int32_t frame_count;
  fascia_real time;
  fascia_real placed_time;          ///< the time the state's prescribed frames were placed at
  fascia_real *x, *q, *u;           ///< state [3N], [4N], velocity [6N]
  unsigned char *mask;              ///< [6N]
  // a step's Newton solve: its anchor and iterate, and the result's gradient
  fascia_real *x_base, *q_base;     ///< anchor of the increments d
  fascia_real *d, *inertia_target;  ///< increments [6N], h u [6N]
  fascia_real *gradient;            ///< [6N]
  // the potential and the inversions at the last solve's result
  fascia_real energy_internal, energy_external;
  int32_t inverted_count, first_inverted, nonfinite_count, first_nonfinite;
  int held_failure; ///< the last step attempt failed at a sample whose frames all move as prescribed (solver.c)
  fascia_real *kinetic_blocks, *scratch; ///< the kinetic energy's lumped blocks [36N] and M u [6N]
  // the organs' reactions: the energy's gradient at full load [6N], and the
  // x, q and frame loads [13N] it was taken at (fascia_solver_loads_gradient)
  fascia_real *reaction, *reaction_at;
  int reaction_known;
  struct fascia_backend *backend;   ///< where the Newton solve's vector work runs (backend.h)
  char backend_name[16];
  fascia_organs *organs; ///< NULL without organs (organs.c)
  char device_text[320];        ///< fascia_solver_device()
  // the blow-up rule (solver.c, check_blow_up)
  int closed;                   ///< 1: no prescribed frame (only a driven organ can do work)
  fascia_real weight_scale;     ///< model mass * |g| * size, J: the energy scale of the rule
  fascia_real model_size;       ///< diagonal of the frames' bounding box, m (> 0)
  int energy_known;             ///< 1: energy_last is E_kin + E_pot of the current state
  fascia_real load_factor;      ///< on gravity and the frames' loads: 1, or a static solve's load step's share
  fascia_real energy_last;
  /// the last static Newton solve's first tangent was not positive definite
  /// (a failed factorization, or CG's negative curvature): a mechanism, or a
  /// load large enough to make the start unstable
  int start_indefinite;
  /// bumped where the state is set from outside or restored: a backend
  /// keeps no factorization across it (cpu/linear_solver.c); a checkpoint carries
  /// the one kept (backend.h, linear_state_save)
  uint64_t linear_epoch;
};

struct fascia_step_result;
/// A Newton solve's result (the backend's finish) into the run's state:
/// positions, rotations, increments, gradient, energies and inversions.
/// Every backend's result goes through here: the backends write no array
/// of the solver's.
FASCIA_INTERN void fascia_solver_take_result(fascia_solver *solver, const struct fascia_step_result *result);

/// A checkpoint's state back (io_checkpoint.c): positions, rotations and
/// velocities as stored (no renormalization, so the next step starts from
/// the very same bits), the time, and the organs' saved state (NULL: none).
FASCIA_INTERN void fascia_solver_resume(fascia_solver *solver, const fascia_real *x, const fascia_real *q,
                                        const fascia_real *u, fascia_real time, const fascia_real *organs_state);

/// The gradient [6N] of the potential energy at the solver's state under
/// the full load, every frame's (the organs' reactions): the backend's where
/// it keeps the state, else the host's. Kept while the state and the frame
/// loads stay as they were: the organs' queries of one state evaluate once.
/// The result is the solver's own (valid until the next call).
FASCIA_INTERN fascia_status fascia_solver_loads_gradient(fascia_solver *solver, const fascia_real **gradient);

/// Minimizes the step objective (static: potential energy, re-anchored at
/// every iteration; dynamic: inertia + potential with increments d anchored
/// at the start state) over the free DOFs on the solver's backend. Leaves
/// the result in solver->x/q, d and gradient.
FASCIA_INTERN fascia_status fascia_newton_minimize(fascia_solver *solver, const struct fascia_step_values *values,
                                                   int max_iterations, fascia_solve_report *report);


// Newton globalization (newton.c; the largest shift: contract/backend.h)
#define FASCIA_NEWTON_ARMIJO 1e-4    // sufficient decrease of the line search
#define FASCIA_NEWTON_MAX_CUTS 30    // step halvings before the Levenberg shift grows
#define FASCIA_NEWTON_WATCHDOG 32    // full Newton steps tried before Phi must be below the watched iterate's
#define FASCIA_NEWTON_STALL 4        // iterations without halving |gradient| ...
#define FASCIA_NEWTON_STALL_FLOOR 100 // ... within this many times the forces' round-off: converged there

#endif
