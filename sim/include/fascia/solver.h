// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Solvers: static equilibrium and implicit (backward) Euler steps, both as
// minimizations solved by Newton iterations with a line search and
// Levenberg damping, each linear system by preconditioned conjugate
// gradients. Every knob that trades time for accuracy is a field of
// fascia_solver_def. See docs/mechanics.md.
//
// Threads: a solver is used by one thread at a time, and so is the context
// it reports to (the context holds the last message). Solvers made on
// contexts of their own run in threads of their own, each giving the same
// bits as it would alone (each may start OpenMP threads of its own, up to
// its def.threads); they may share one model, which no solver writes to.
// Loading and saving files goes through HDF5, which Debian builds without
// its thread-safe option: do that from one thread at a time. Register
// backends (fascia_backend_register) before solvers are made in threads.
#ifndef FASCIA_SOLVER_H
#define FASCIA_SOLVER_H

#include "fascia/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum fascia_precond {
  FASCIA_PRECOND_NONE = 0,
  FASCIA_PRECOND_JACOBI = 1,       ///< inverse of the diagonal
  FASCIA_PRECOND_BLOCK_JACOBI = 2, ///< inverse of each frame's 6x6 diagonal block
} fascia_precond;

typedef enum fascia_linear_solver {
  FASCIA_LINEAR_AUTO = 0,   ///< direct where its factorization is cheap enough, else CG (docs/mechanics.md)
  FASCIA_LINEAR_CG = 1,     ///< preconditioned conjugate gradients
  FASCIA_LINEAR_DIRECT = 2, ///< sparse Cholesky of the assembled tangent (CHOLMOD)
} fascia_linear_solver;

typedef enum fascia_mass_kind {
  FASCIA_MASS_CONSISTENT = 0, ///< M = sum_s m_s J_s^T J_s, samples follow frames exactly
  FASCIA_MASS_LUMPED = 1,     ///< 6x6 blocks per frame: each sample's mass split among its frames (never negative)
} fascia_mass_kind;

/// The shortest time step a solver takes, s: below it the inertia term
/// (mass / dt^2) swamps the stiffness by more than double precision can
/// resolve for any tissue, and the step would compute nothing.
#define FASCIA_MIN_TIME_STEP 1e-8

/// fascia_solver_def.assembled: the product chosen by its measured cost.
#define FASCIA_ASSEMBLED_AUTO (-1)
/// fascia_solver_def.single_precision_matrix: float products where the CG
/// tolerance is at least FASCIA_SINGLE_MIN_CG_TOLERANCE (or CG runs a fixed
/// count), else double.
#define FASCIA_SINGLE_AUTO (-1)
/// The tightest relative CG residual the automatic choice
/// takes float products for: 16x above float's rounding (6e-8), so the
/// matrix's rounding stays far below what each linear solve is asked for
/// (and Newton's gradient, in double, decides convergence either way).
#define FASCIA_SINGLE_MIN_CG_TOLERANCE 1e-6
/// The largest assembled matrix (with its assembly plan) the automatic choice
/// takes, bytes: beyond it the products go matrix-free.
#define FASCIA_AUTO_MAX_MATRIX_BYTES ((double)(2LL << 30))

/// Solver options; start from fascia_solver_def_default().
typedef struct fascia_solver_def {
  /// "cpu", "cuda", "auto" (default: cuda when a GPU is there and the
  /// settings run on it, else cpu; fascia_solver_device says which and why)
  /// or "emulated" (the device solver in host loops: for tests, slow)
  const char *backend;
  int threads;                   ///< 0: the context's
  fascia_real time_step;         ///< s, dynamic steps (default 0.01; at least FASCIA_MIN_TIME_STEP)
  int newton_iterations;         ///< most Newton iterations per solve (default 20; static 100)
  fascia_real newton_tolerance;  ///< stop when |gradient| <= tol * |external load|, in [0, 1) (default 1e-6)
  int cg_iterations;             ///< most CG iterations per linear solve (default 200)
  int cg_fixed;                  ///< 1: always exactly cg_iterations (the paper's benchmark mode)
  fascia_real cg_tolerance;      ///< relative residual of each linear solve (default 1e-3)
  fascia_precond precond;        ///< default block Jacobi
  fascia_linear_solver linear_solver; ///< default auto
  /// CG: 1 multiplies by the assembled 6x6-block matrix, 0 matrix-free,
  /// FASCIA_ASSEMBLED_AUTO (default) assembled on the CPU where the matrix
  /// takes at most FASCIA_AUTO_MAX_MATRIX_BYTES, else matrix-free (the
  /// fastest product: docs/mechanics.md)
  int assembled;
  /// Assembled CG: 1 multiplies by a float copy of the matrix (half the
  /// memory traffic of the products, which bound a paper-mode step; each
  /// product then carries ~1e-7 relative error, which only changes the
  /// linear solve, not the energy or forces), 0 by the double matrix,
  /// FASCIA_SINGLE_AUTO (default) float as that constant says.
  int single_precision_matrix;
  fascia_mass_kind mass;         ///< default lumped (frames carry rotational inertia; docs/mechanics.md)
  fascia_real mass_damping;      ///< Rayleigh mass damping alpha, 1/s (default 0)
  int line_search;               ///< 1: backtracking line search on the energy (default 1)
  /// Static solve: the external load, and the prescribed motion from the
  /// time its frames were last placed at to the solver's time, applied in
  /// this many increments (default 1).
  int load_steps;
  /// Dynamic steps: a step that fails (FASCIA_ERR_NUMERIC from its Newton
  /// solve, or unconverged when require_convergence is set) is rejected and
  /// redone as two steps of half the time step, each of which may be split
  /// again, at most this many halvings deep (default 4: down to dt / 16).
  /// 0: a failed step returns at once.
  int step_retries;
  /// Dynamic steps: 1 counts a step whose Newton solve ends unconverged
  /// after newton_iterations as failed (split as above, then
  /// FASCIA_ERR_NUMERIC; the default: no unconverged state is passed off as
  /// a solution); 0 accepts it (the paper's fixed-cost mode and the
  /// interactive presets, where a capped Newton count per step is the point).
  int require_convergence;
  /// Dynamic steps and static solves: a step (or a load step of a static
  /// solve) after which some sample's Green-Lagrange strain norm exceeds
  /// this has blown up and is failed like an unsolvable one (default 10, a
  /// stretch of about 4.6; tissue tears long before). 0 turns this rule off;
  /// the others stay (docs/mechanics.md, "When a run has diverged").
  fascia_real blow_up_strain;
  int cookie_;                   ///< private
} fascia_solver_def;

FASCIA_API fascia_solver_def fascia_solver_def_default(void);

/// Milliseconds spent per stage in the last solve (wall clock).
typedef struct fascia_profile {
  double evaluate_ms; ///< energy, forces (and the per-sample cache)
  double precond_ms;  ///< diagonal blocks and their inverses
  double assemble_ms; ///< assembly of the block matrix (direct solver or assembled CG)
  double cg_ms;       ///< linear solves: CG (stiffness products included) or factor and solve
  double total_ms;
} fascia_profile;

/// Adds each stage's time of p to sum's (the profile of several solves).
FASCIA_API void fascia_profile_add(fascia_profile *sum, const fascia_profile *p);

/// What a solve did.
typedef struct fascia_solve_report {
  int converged;               ///< 1 when the Newton tolerance was met
  int newton_iterations;
  int cg_iterations;           ///< summed over Newton iterations
  int line_search_cuts;        ///< step halvings summed over iterations
  int watchdog_returns;        ///< full Newton steps undone: back to the watched iterate (docs/mechanics.md, "Solvers")
  int negative_curvature;      ///< CG solves that met negative curvature, or failed factorizations
  int direct;                  ///< 1 when the linear systems were solved directly
  int assembled;               ///< 1 when the tangent was assembled (direct solver or assembled CG)
  int single_precision_matrix; ///< 1 when CG multiplied by the assembled matrix's float copy
  int factorizations;          ///< direct solver: tangents assembled and factored (an iteration may reuse the last)
  fascia_real gradient_norm;   ///< final |gradient| over free DOFs
  fascia_real reference_norm;  ///< |external load|, the tolerance's scale
  fascia_real energy;          ///< final potential energy, J
  int32_t inverted_samples;    ///< samples with det F <= 0 at the end
  int substeps;                ///< dynamic: time steps taken (1, more when the step was split)
  int rejected;                ///< dynamic: attempts rejected and split (step_retries)
  fascia_profile profile;
} fascia_solve_report;

typedef struct fascia_solver fascia_solver;

/// Creates a solver for a validated model (borrowed: it must outlive the
/// solver). The state starts at rest, at rest velocity, time 0. On error *out
/// is NULL and the message says which setting is impossible.
FASCIA_API fascia_status fascia_solver_create(fascia_ctx *ctx, const fascia_model *model,
                                              const fascia_solver_def *def, fascia_solver **out);
FASCIA_API void fascia_solver_destroy(fascia_solver **solver);

/// One implicit Euler step of the time step (def.time_step, or the last
/// fascia_solver_set_time_step), split into shorter steps where
/// a step fails (def.step_retries, def.require_convergence; the report sums
/// the iterations of all of them and counts them in substeps). On
/// FASCIA_ERR_NUMERIC, even at the shortest step, the state and the time are
/// left as they were before the step and the message names the time, the
/// shortest step tried and the cause. After an accepted step the context's
/// progress hook is called with stage "step", fraction -1 (a solver does not
/// know how many steps its caller takes) and a detail line with the time
/// reached and the Newton iterations.
FASCIA_API fascia_status fascia_solver_step(fascia_solver *solver, fascia_solve_report *report);
/// Static equilibrium under gravity and loads at the current time, starting
/// from the current state; velocities are set to zero. Not converging within
/// newton_iterations returns FASCIA_ERR_NUMERIC with the state reached kept;
/// so does a load step whose converged state has blown up by the rules of
/// a dynamic step (a non-finite value, a strain past blow_up_strain), the
/// message naming the load step, the sample and its strain.
FASCIA_API fascia_status fascia_solver_solve_static(fascia_solver *solver, fascia_solve_report *report);

FASCIA_API fascia_real fascia_solver_time(const fascia_solver *solver);
/// Sets the solver's time (s, finite, >= 0) without moving anything: the next
/// static solve places the prescribed frames on their motions at that time
/// (say, fascia_model_motion_end, for the equilibrium once the organs have
/// moved), the next step starts there.
FASCIA_API fascia_status fascia_solver_set_time(fascia_solver *solver, fascia_real time);
/// The time step of the next fascia_solver_step, s.
FASCIA_API fascia_real fascia_solver_time_step(const fascia_solver *solver);
/// Sets the time step of the steps from now on (s, checked as
/// def.time_step; a host simulator's frame time may vary). The state and
/// velocities carry over. A checkpoint (fascia/checkpoint.h) records one
/// time step per run. On error nothing changed.
FASCIA_API fascia_status fascia_solver_set_time_step(fascia_solver *solver, fascia_real time_step);
/// Number of frames and of samples of the solver's model: the sizes of the
/// arrays below ([3N], [3S]).
FASCIA_API int32_t fascia_solver_frame_count(const fascia_solver *solver);
FASCIA_API int32_t fascia_solver_sample_count(const fascia_solver *solver);
/// The backend the solver runs on: "cpu", "cuda" or "emulated".
FASCIA_API const char *fascia_solver_backend(const fascia_solver *solver);
/// What it runs on, in words: the GPU's name, or the CPU threads; for a
/// solver made with backend "auto" that runs on the CPU, also why not on a
/// GPU.
FASCIA_API const char *fascia_solver_device(const fascia_solver *solver);
/// Whether backend ("cpu", "cuda", "emulated") can run here; detail (may
/// be NULL) gets the device in words, or why it cannot.
FASCIA_API int fascia_backend_available(const char *backend, char *detail, size_t size);
/// The name of backend k of this build's registry in priority order
/// (0, 1, ...; NULL past the last): what `--backend` takes besides "auto".
FASCIA_API const char *fascia_backend_name(int k);
/// Current frame positions [3N] (m) and rotations [4N] (unit quaternions).
FASCIA_API const fascia_real *fascia_solver_frame_positions(const fascia_solver *solver);
FASCIA_API const fascia_real *fascia_solver_frame_rotations(const fascia_solver *solver);
/// The axes of count frames of rotations [4 count] (unit quaternions): for
/// each, the columns of its rotation matrix, x axis then y then z (world),
/// into axes [9 count]; what ParaView's Glyph draws.
FASCIA_API void fascia_frame_axes(const fascia_real *rotations, int64_t count, fascia_real *axes);
/// Current generalized velocities [6N]: linear (m/s), angular (rad/s, world).
FASCIA_API const fascia_real *fascia_solver_frame_velocities(const fascia_solver *solver);
/// Sets the state (positions [3N], rotations [4N], velocities [6N] or NULL
/// for zero). Rotations are normalized; a non-finite value is refused.
FASCIA_API fascia_status fascia_solver_set_state(fascia_solver *solver, const fascia_real *positions,
                                                 const fascia_real *rotations, const fascia_real *velocities);
/// Deformed position of a probe (m).
FASCIA_API void fascia_solver_probe_position(const fascia_solver *solver, int32_t probe, fascia_real *out);
/// Deformed sample positions [3S].
FASCIA_API void fascia_solver_sample_positions(const fascia_solver *solver, fascia_real *out);
/// Per-sample Green-Lagrange strain norm [S] and first Piola stress norm
/// [S] (Pa, may be NULL) at the current state.
FASCIA_API void fascia_solver_sample_strain(const fascia_solver *solver, fascia_real *strain, fascia_real *stress);
/// Kinetic energy (consistent or lumped mass, as configured), J.
FASCIA_API fascia_real fascia_solver_kinetic_energy(fascia_solver *solver);
/// Potential energy (internal + gravity + loads), J.
FASCIA_API fascia_status fascia_solver_potential_energy(fascia_solver *solver, fascia_real *energy);

#ifdef __cplusplus
}
#endif
#endif
