// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The discrete mechanical system on the CPU: the model's arrays as the
// per-sample math reads them, the current frame state, and the operators the
// solvers need: potential energy and its gradient, the symmetric tangent
// (Hessian) product, mass products, diagonal blocks. Every per-frame sum goes
// through the reverse table in a fixed order, so results are bit-identical
// for any thread count.
//
// Generalized coordinates: per frame 6 entries (x, theta), where a variation
// theta rotates the frame in world space, R <- exp([theta]x) R.
#ifndef FASCIA_SRC_SYSTEM_H
#define FASCIA_SRC_SYSTEM_H

#include "contract/backend.h"
#include "fascia/model.h"
#include "point/sample.h"
#include "util/status.h"

struct fascia_dilatation;
struct fascia_modes;

typedef struct fascia_system {
  fascia_ctx *ctx;
  const fascia_model *model; ///< borrowed, outlives the system
  int32_t frame_count, sample_count, pair_count;
  int threads;     ///< of the parallel loops now: threads_max, or fewer where other work holds the cores
  int threads_max; ///< the solver's setting

  fascia_pt_model pm; ///< views into the arrays below and the model's
  fascia_real *pair_offset;     ///< [3P] p_rest_s - x_rest_i
  fascia_real *sample_lambda;   ///< [S]
  fascia_real *sample_mu;       ///< [S]
  fascia_real *sample_coupling; ///< [S]
  fascia_real *sample_curvature; ///< [S]
  fascia_real *sample_mass;     ///< [S] kg
  int32_t *sample_law;          ///< [S]
  int32_t *local_slot;          ///< [max neighbours] 0, 1, 2, ..
  int32_t *pair_sample;         ///< [P] the sample each pair belongs to
  fascia_real *pair_lumped_mass; ///< [P] kg: the share of its sample's mass the lumped mass puts on the pair's frame
  /// [13N] each frame's lumped mass as rest moments of its pairs' shares m_k
  /// at their offsets d_k (pair_offset): sum m_k, sum m_k d_k (3), sum m_k
  /// (|d_k|^2 I - d_k d_k^T) (9, row-major); the block at rotation A is made
  /// of them (fascia_pt_frame_lumped_mass), so a step costs O(frames)
  fascia_real *frame_lumped_moments;
  /// The rotation smoothing as a weighted graph on the frames: summed over
  /// the samples, its energy is 1/2 sum_ij W_ij <A_i, A_j> (Frobenius), with
  /// W_ij = sum over the samples holding frames i and j of v k_c (g_i . g_j),
  /// rest quantities. Row i lists the frames that share such a sample with i
  /// (i too), in the order met. Made by the first assembly, which adds the
  /// smoothing's blocks from it once per frame pair instead of once per
  /// sample; NULL before, and the weights NULL where no sample has smoothing.
  int32_t *smoothing_offsets;     ///< [N+1]
  int32_t *smoothing_frames;      ///< [smoothing_offsets[N]]
  fascia_real *smoothing_weight;  ///< [smoothing_offsets[N]] W_ij
  struct fascia_dilatation *dilatation; ///< the volumetric patches' term (dilatation.h), NULL without patches
  struct fascia_modes *modes;           ///< the patches' enhanced strain modes (modes.h), NULL without

  // gravity as frame moments: E_g = -sum_i g.(M_i x_i + A_i D_i)
  fascia_real *frame_mass;   ///< [N] M_i = sum_s m_s w_is
  fascia_real *frame_moment; ///< [3N] D_i = sum_s m_s w_is d_is
  fascia_real gravity[3];
  fascia_real gravity_scale; ///< load factor on gravity and loads (continuation)

  // state
  fascia_real *x; ///< [3N]
  fascia_real *q; ///< [4N]
  fascia_real *A; ///< [9N] R_i R_rest_i^T
  fascia_real *A_mass; ///< [9N] A at the mass snapshot

  // per evaluation
  fascia_real *pair_buffer;  ///< [6P]
  fascia_real *cache;        ///< [S * FASCIA_PT_CACHE_SIZE]
  int *sample_flags;         ///< [S]
  fascia_real *conservative_torque; ///< [3N] theta-gradient of internal+gravity energy
  fascia_real *gradient_scratch;    ///< [6N] gradient when the caller asks for none (the Hessian needs the torques)
  fascia_real energy_internal, energy_external; ///< internal includes the patches' volumetric energy
  int32_t max_neighbours;
  int32_t inverted_count;
  int32_t first_inverted, nonfinite_count, first_nonfinite;
} fascia_system;

/// The sample that pair k belongs to (bisection in sample_offsets).
FASCIA_INTERN int32_t fascia_model_pair_owner(const fascia_model *model, int32_t k);

FASCIA_INTERN fascia_status fascia_system_create(fascia_ctx *ctx, const fascia_model *model, int threads,
                                                 fascia_system **out);
FASCIA_INTERN void fascia_system_destroy(fascia_system **sys);
/// The system's arrays by row of contract/system_table.h, for a backend's
/// upload.
FASCIA_INTERN void fascia_system_arrays(const fascia_system *sys, fascia_array_data data[FASCIA_SA_COUNT]);

/// Sets the frame state (x [3N], q [4N] unit quaternions) and A.
FASCIA_INTERN void fascia_system_set_state(fascia_system *sys, const fascia_real *x, const fascia_real *q);
/// Sets the state to the rest state.
FASCIA_INTERN void fascia_system_set_rest(fascia_system *sys);

/// Potential energy (internal + gravity + frame loads, all times
/// gravity_scale for the external part) at the current state, its gradient
/// [6N] (may be NULL), and the per-sample cache the Hessian product reuses.
/// Returns FASCIA_ERR_NUMERIC (with the lowest offending sample in the
/// message) when a value is not finite.
FASCIA_INTERN fascia_status fascia_system_evaluate(fascia_system *sys, fascia_real *gradient, fascia_real *energy);

/// out = H v: the symmetric Hessian of the potential at the state of the
/// last evaluate (exact derivative of the gradient plus the symmetrizing
/// term 1/2 [g_theta]x of the rotation update, see docs/mechanics.md).
FASCIA_INTERN void fascia_system_hessian_apply(fascia_system *sys, const fascia_real *v, fascia_real *out);
/// Same without the symmetrizing term: the exact directional derivative of
/// the gradient (what a finite difference of the force measures).
FASCIA_INTERN void fascia_system_gradient_derivative(fascia_system *sys, const fascia_real *v, fascia_real *out);

/// 6x6 diagonal blocks of H [36N], row-major per frame.
FASCIA_INTERN void fascia_system_hessian_diagonal(fascia_system *sys, fascia_real *blocks);

/// Remembers the current A for the mass operators below.
FASCIA_INTERN void fascia_system_mass_snapshot(fascia_system *sys);
/// out = M v, consistent mass at the snapshot.
FASCIA_INTERN void fascia_system_mass_apply(fascia_system *sys, const fascia_real *v, fascia_real *out);
/// Lumped (row-sum) 6x6 mass blocks at the snapshot [36N].
FASCIA_INTERN void fascia_system_mass_lumped(fascia_system *sys, fascia_real *blocks);

/// Deformed sample positions [3S].
FASCIA_INTERN void fascia_system_sample_positions(const fascia_system *sys, fascia_real *out);

/// Green-Lagrange strain magnitude |E| (Frobenius) per sample [S] at the
/// current state, and von Mises-like stress magnitude |P| (Pa) if stress
/// is not NULL.
FASCIA_INTERN void fascia_system_sample_strain(fascia_system *sys, fascia_real *strain, fascia_real *stress);
/// The largest |E| over the samples at the current state (infinity when one
/// is not finite), and in *sample (if not NULL) the lowest sample that has it.
FASCIA_INTERN fascia_real fascia_system_largest_strain(const fascia_system *sys, int32_t *sample);

/// Deterministic dot product (fixed blocking: the same bits for any thread
/// count) on `threads` threads.
FASCIA_INTERN fascia_real fascia_dot(const fascia_real *a, const fascia_real *b, int64_t n, int threads);

/// Pairs from which a system's passes are long enough to keep every thread
/// on a loaded machine (fascia_threads_free).
#define FASCIA_THREADS_LONG_PASS_PAIRS 32768

/// Threads to use now for a system of `pairs` sample-frame pairs, at most
/// `wanted`. The parallel loops end at a barrier, so a thread that waits for
/// a busy core holds up all of them for up to a scheduler slice (a few ms):
/// where one pass over the pairs is shorter than that (below
/// FASCIA_THREADS_LONG_PASS_PAIRS, about 1 ms a pass on one core), fewer
/// threads finish sooner, and this gives the cores no other runnable task
/// holds (Linux: /proc/loadavg's runnable count, this thread aside), at
/// least 1. Longer passes keep `wanted`: a busy core then costs a fraction
/// of a pass, and more threads get a larger share of a shared machine.
/// Every sum has a fixed blocking, so results do not change.
FASCIA_INTERN int fascia_threads_free(int wanted, int64_t pairs);

#endif
