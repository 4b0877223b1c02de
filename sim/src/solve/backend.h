// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The contract between the solver's one Newton loop (newton.c) and the
// backends that do its vector work: the CPU (backend_cpu.c) and the device
// solver (cuda/device_solver.c, on a GPU or in its host emulation). A
// backend holds the iterate d, the trial d + alpha p, the direction p and
// their gradients, wherever it keeps them; the loop sees scalars only, and
// every value of a step is passed in (docs/backends.md). The registry
// (backend.c) lists the backends; "auto" walks it in priority order.
// This header is all a backend outside sim/ includes of the core
// (tests/t371 checks cuda/).
#ifndef FASCIA_SRC_BACKEND_H
#define FASCIA_SRC_BACKEND_H

#include "fascia/solver.h"
#include "point/modes.h"
#include "cpu/system.h"
// the arrays a backend uploads: each table row's device column names where
#include "model/model_arrays.h"
#include "cpu/system_arrays.h"

typedef struct fascia_backend_ops fascia_backend_ops;
typedef struct fascia_organs fascia_organs; // organs.c

/// Every backend's state starts with this.
typedef struct fascia_backend {
  const fascia_backend_ops *ops;
} fascia_backend;

/// What a backend is made from. The system is the model compiled for the
/// per-sample math (system.c); the mask marks the free DOFs of the reduced
/// coordinates (read at every step: a caller may fix DOFs, or drive an
/// organ, after the solver is made). Rigid organs come as the bodies'
/// table (point/body.h), whose per-step values and active flags the solver
/// sets before each step, and the full mask of every frame the tissue moves.
/// organs is for the CPU's direct solver, which assembles P^T K P
/// (organs.c); solver is the state the CPU backend works in.
typedef struct fascia_backend_setup {
  fascia_ctx *ctx;
  const fascia_model *model;
  fascia_system *sys;
  const unsigned char *mask;     ///< [6N] 1 free
  const fascia_solver_def *def;
  struct fascia_solver *solver;
  fascia_organs *organs;
  int32_t rigid_bodies; ///< rigid organs simulated as bodies now
  const struct fascia_pt_bodies *bodies; ///< NULL: no rigid organ with coupling frames
  const unsigned char *full_mask;        ///< [6N]; the mask where there are no bodies
  /// the volumetric patches as the per-patch math reads them (host arrays;
  /// count 0: none), and their support entries (the length of entry_frame)
  const fascia_pt_patches *patches;
  int32_t patch_entries;
  /// the enhanced strain modes on those patches as the per-patch math reads
  /// them (host arrays; NULL: none)
  const fascia_pt_modes *modes;
  /// host arrays that cross to a device every step (the step's and the
  /// result's below), for page-locking; count entries
  void *crossing[8];
  size_t crossing_bytes[8];
  int crossing_count;
} fascia_backend_setup;

/// The values of one Newton solve.
typedef struct fascia_step_values {
  int dynamic;              ///< 1: inertia terms, increments anchored at the start (docs/mechanics.md)
  fascia_real c1, c2;       ///< inertia 1/h^2 and mass damping alpha/h (0 for a static solve)
  fascia_real gravity_scale; ///< load factor on gravity and loads
  const fascia_real *x_base, *q_base; ///< anchor [3N], [4N]
  const fascia_real *d;               ///< first iterate [6N]
  const fascia_real *inertia_target;  ///< h u [6N] (dynamic)
} fascia_step_values;

/// The step objective at a trial point.
typedef struct fascia_trial_values {
  fascia_real phi;            ///< the objective Phi
  fascia_real gradient_norm2; ///< |projected gradient|^2
  fascia_real energy_size;    ///< |internal| + |external| potential energy: the line search's round-off scale
} fascia_trial_values;

/// A Newton solve's result as the backend hands it back: its own host
/// arrays (read-only, valid until its next begin), which the solver copies
/// into the run's state, and the potential at that state.
typedef struct fascia_step_result {
  const fascia_real *x, *q;       ///< state [3N], [4N]
  const fascia_real *d;           ///< increments [6N]
  const fascia_real *gradient;    ///< projected gradient [6N]
  fascia_real energy_internal;    ///< the patches' volumetric energy included
  fascia_real energy_external;    ///< gravity and loads times the load factor, the loads' torques' work
  int32_t inverted_count;         ///< samples inverted at that state
  int32_t first_inverted;         ///< the lowest of them, -1 for none
} fascia_step_result;

struct fascia_backend_ops {
  const char *name;  ///< "cpu", "cuda", "emulated"
  int automatic;     ///< 1: "auto" may choose it (the registry's order is the priority)
  /// 1 when this build can run it on this machine, with the device in
  /// words; else 0 and why (for a backend not built: how to build it).
  int (*available)(char *detail, size_t size);
  /// 1 when it handles this model and these settings; else 0 and why.
  int (*supports)(const fascia_backend_setup *setup, char *why, size_t size);
  fascia_status (*create)(const fascia_backend_setup *setup, fascia_backend **out);
  void (*destroy)(fascia_backend *backend);
  /// The backend and its device in words (fascia_solver_device).
  const char *(*describe)(const fascia_backend *backend);

  // --- one Newton solve, in this order (newton.c) -------------------------
  fascia_status (*begin)(fascia_backend *backend, const fascia_step_values *values, fascia_solve_report *report);
  /// The objective at d + alpha p and its projected gradient, kept as the
  /// trial. current = 1 (alpha 0): at d itself, and the gradient becomes the
  /// current one (the start of a solve, or back to the iterate after a
  /// failed line search).
  fascia_status (*evaluate)(fascia_backend *backend, fascia_real alpha, int current, fascia_trial_values *out);
  /// Tangent, preconditioner and Levenberg diagonal at the current iterate
  /// (adds its times to the report's profile).
  fascia_status (*prepare)(fascia_backend *backend, fascia_solve_report *report);
  /// The direction p of A p = -g with the Levenberg shift *shift (a solver
  /// that needs a positive definite A may raise it), and its slope p.g < 0
  /// (a preconditioned gradient where the solve gave no descent).
  fascia_status (*direction)(fascia_backend *backend, fascia_real *shift, fascia_real *slope,
                             fascia_solve_report *report);
  /// The last trial becomes the iterate; a static solve re-anchors there.
  void (*accept)(fascia_backend *backend);
  /// Optional (NULL: the loop's line search stays monotone): keep a copy of
  /// the iterate, and make it the iterate again (its evaluation follows).
  /// They let the loop try full Newton steps that raise Phi for a while
  /// (the watchdog, newton.c).
  void (*save)(fascia_backend *backend);
  void (*restore)(fascia_backend *backend);
  /// The iterate (the state of the last evaluation) on the host, with its
  /// energies and inversions; the backend writes no array of the solver's.
  fascia_status (*finish)(fascia_backend *backend, fascia_step_result *result);
  /// Optional (NULL: the host checks the state finish gave, which is where
  /// the CPU keeps it). The step's
  /// check (solver.c's blow-up rule): whether some sample's strain
  /// |F^T F - I| / 2 at the state finish gave is past limit or not finite
  /// (*past 1, else 0), reduced where the state is kept.
  fascia_status (*strain_past)(fascia_backend *backend, fascia_real limit, int *past);
  /// Optional (NULL: the host evaluates them at the solver's state). The
  /// outputs' per-sample values at the state x [3N], q [4N]: positions
  /// [3S], strain [S] and stress [S] (point/sample.h,
  /// fascia_pt_sample_output); each may be NULL. Called between steps
  /// only: it may use a step's work arrays.
  fascia_status (*sample_outputs)(fascia_backend *backend, const fascia_real *x, const fascia_real *q,
                                  fascia_real *positions, fascia_real *strain, fascia_real *stress);
  /// Optional (NULL: the host evaluates it). The gradient [6N] of the
  /// potential energy at the state x, q under the load factor, every
  /// frame's (not projected on the free DOFs: the organs' reactions read
  /// their fixed and driven frames). Called between steps only.
  fascia_status (*energy_gradient)(fascia_backend *backend, const fascia_real *x, const fascia_real *q,
                                   fascia_real load_factor, fascia_real *gradient);

  // --- optional: the linear solver's state the next step reads -------------
  /// (NULL: none.) A kept factorization the next step may use: its size in
  /// reals (0: none kept), and those reals, so that a checkpoint carries it
  /// and a resumed run takes the path of the run that saved it. load
  /// returns 0 (nothing kept, the next step factors afresh) where they do
  /// not fit this solver.
  int64_t (*linear_state_size)(fascia_backend *backend);
  void (*linear_state_save)(fascia_backend *backend, fascia_real *out);
  int (*linear_state_load)(fascia_backend *backend, const fascia_real *in, int64_t count);

  // --- operators at a given state, for the tests of every backend ---------
  /// Potential energy and projected gradient [6N] at x, q under the load
  /// factor.
  fascia_status (*gradient)(fascia_backend *backend, const fascia_real *x, const fascia_real *q,
                            fascia_real load_factor, fascia_real *gradient, fascia_real *energy);
  /// out = H v on the free DOFs at the state of the last gradient().
  fascia_status (*hessian_apply)(fascia_backend *backend, const fascia_real *v, fascia_real *out);
  /// The 6x6 diagonal blocks of H [36N] at that state.
  fascia_status (*hessian_diagonal)(fascia_backend *backend, fascia_real *blocks);
};

/// The backends (backend.c): a backend not in this build answers available()
/// with how to build it.
extern const fascia_backend_ops fascia_backend_cpu;
extern const fascia_backend_ops fascia_backend_cuda;     ///< cuda/device_solver.c (without CUDA: says how to build it)
extern const fascia_backend_ops fascia_backend_emulated; ///< cuda/device_solver.c

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
