// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The contract between the solver's one Newton loop (newton.c) and the
// backends that do its vector work: the CPU (backend_cpu.c) and the device
// solver (cuda/device_solver.c, on a GPU or in its host emulation). A
// backend holds the iterate d, the trial d + alpha p, the direction p and
// their gradients, wherever it keeps them; the loop sees scalars only, and
// every value of a step is passed in (docs/backends.md). The registry
// (backend.c) lists the backends; "auto" walks it in priority order.
// This folder (sim/contract/) is all a backend outside sim/ sees of the
// core, beside the public headers and the per-sample math (sim/point/):
// cuda/'s build has no other part of sim/ on its include path, and
// tests/t371 checks its includes. The registry: sim/src/solve/backend.h.
#ifndef FASCIA_CONTRACT_BACKEND_H
#define FASCIA_CONTRACT_BACKEND_H

#include "fascia/solver.h"
#include "point/body.h"
#include "point/modes.h"
#include "point/patch.h"
// the arrays a backend uploads: each table row's device column names where
#include "contract/model_table.h"
#include "contract/system_table.h"

typedef struct fascia_backend_ops fascia_backend_ops;
typedef struct fascia_organs fascia_organs; // sim/src/organs/organs.c
typedef struct fascia_system fascia_system; // the CPU backend's, sim/src/cpu/system.h

/// One host array a backend may upload: a row of a table above.
typedef struct fascia_array_data {
  const void *data;
  size_t bytes;
} fascia_array_data;

/// Every backend's state starts with this.
typedef struct fascia_backend {
  const fascia_backend_ops *ops;
} fascia_backend;

/// What a backend is made from. The model, and the arrays the CPU system
/// compiles from it for the per-sample math (system_table.h, by row), with
/// the few values a device reads of it; the mask marks the free DOFs of the reduced
/// coordinates (read at every step: a caller may fix DOFs, or drive an
/// organ, after the solver is made). Rigid organs come as the bodies'
/// table (point/body.h), whose per-step values and active flags the solver
/// sets before each step, and the full mask of every frame the tissue moves.
/// organs is for the CPU's direct solver, which assembles P^T K P
/// (organs.c); sys and linear_epoch are the CPU backend's own (it evaluates
/// the host system, and keeps a factorization while the epoch stays; a
/// device reads neither).
typedef struct fascia_backend_setup {
  fascia_ctx *ctx;
  const fascia_model *model;
  const fascia_array_data *model_arrays;  ///< [FASCIA_MA_COUNT] the model's, by row of model_table.h
  const fascia_array_data *system_arrays; ///< [FASCIA_SA_COUNT] the system's, by row of system_table.h
  int32_t max_neighbours;                 ///< the most frames a sample has
  fascia_real gravity[3];                 ///< m/s^2
  int threads;                            ///< host threads the backend may use
  fascia_system *sys;                     ///< the CPU backend's host system
  const unsigned char *mask;     ///< [6N] 1 free
  const fascia_solver_def *def;
  const uint64_t *linear_epoch; ///< bumped where the run's state is set from outside or restored
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
  /// the solver's host arrays that cross to a device at every step's begin
  /// (the step's values below), for page-locking; count entries
  void *crossing[8];
  size_t crossing_bytes[8];
  int crossing_count;
} fascia_backend_setup;

/// The relative Levenberg shift beyond which the Newton loop gives up; a
/// backend that raises the shift in direction() (a factorization that
/// needs a positive definite matrix) gives up there too.
#define FASCIA_NEWTON_MAX_SHIFT 1e12

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
  int32_t nonfinite_count;        ///< samples whose energy is not finite at that state
  int32_t first_nonfinite;        ///< the lowest of them (read only when nonfinite_count > 0)
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

/// The core's monotonic clock in milliseconds, for a backend's profile
/// (as sim/src/util/status.h declares it).
__attribute__((visibility("hidden"))) double fascia_now_ms(void);

/// The backends (the registry: sim/src/solve/backend.c): a backend not in this build answers available()
/// with how to build it.
extern const fascia_backend_ops fascia_backend_cpu;
extern const fascia_backend_ops fascia_backend_cuda;     ///< cuda/device_solver.c (without CUDA: says how to build it)
extern const fascia_backend_ops fascia_backend_emulated; ///< cuda/device_solver.c

#endif
