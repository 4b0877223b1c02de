// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The device backend's work, one item at a time: what one GPU thread does
// for one sample, pair, frame or vector entry, and the scalar steps that one
// thread runs after a reduction. nvcc compiles these bodies into kernels
// (launch_cuda.cu); the C compiler compiles the same bodies into loops
// (launch_emulated.c), so the device code paths are tested on any machine.
//
// The scheme is the paper's two kernels (sec. 3.2): one thread per sample
// writes its partial contribution for each neighbour frame into a pair
// buffer; one thread per frame sums its pairs through the reverse table.
// No atomics: every sum has a fixed order, so runs are bit-reproducible.
//
// Everything lives in device memory; the host changes only the settings
// block between launches and reads the scalars block once per Newton
// iteration (never per CG iteration).
#ifndef FASCIA_CUDA_ITEMS_H
#define FASCIA_CUDA_ITEMS_H

#include "point/block6.h"
#include "point/body.h"
#include "point/cg.h"
#include "point/frame.h"
#include "point/modes.h"
#include "point/patch.h"
#include "point/sample.h"

/// What the host sets between launches (never written on the device).
typedef struct fascia_dev_settings {
  fascia_real c1, c2;            ///< inertia and mass damping coefficients of the step objective
  fascia_real mass_coefficient;  ///< c1 + c2: the mass term of the Newton operator
  fascia_real shift;             ///< Levenberg shift
  fascia_real gravity_scale;     ///< load factor on gravity and loads
  int32_t jacobian;              ///< 1: gradient with respect to anchored increments (dynamic)
  int32_t consistent_mass;       ///< 1: consistent mass products; 0: lumped blocks
  int32_t precond;               ///< FASCIA_PRECOND_* (solver.h)
  fascia_real strain_limit;      ///< the blow-up rule's strain (FASCIA_T_STRAIN)
  int32_t project;               ///< 1: g_trial on the DOFs the tissue moves (steps); 0: every frame's (reactions)
  fascia_pt_cg_limits cg_limits; ///< of every linear solve
} fascia_dev_settings;

/// What the device computes for the host and for later kernels.
typedef struct fascia_dev_scalars {
  fascia_real sum[4];           ///< last stored reduction
  fascia_real energy_internal, energy_external, phi, gradient_norm2;
  fascia_real inverted, nonfinite; ///< sample counts (exact in double)
  fascia_real modes_failed;     ///< patches whose enhanced strain modes found no minimum
  fascia_real target_norm;      ///< (h u).M(h u) of the inertia target
  fascia_real scale;            ///< mean absolute tangent diagonal
  fascia_pt_cg cg;              ///< conjugate gradients (point/cg.h)
} fascia_dev_scalars;

/// Device views of the model, the state and the work arrays (all device
/// pointers; passed to every kernel by value).
typedef struct fascia_dev {
  fascia_pt_model pm;
  int32_t frame_count, sample_count, max_neighbours;
  int64_t pair_count;
  const int32_t *frame_offsets, *frame_pairs, *pair_sample; ///< reverse table, pair -> sample
  const fascia_real *sample_mass;    ///< [S] kg
  const fascia_real *frame_lumped_moments; ///< [13N] the lumped mass's rest moments per frame (system.h)
  const fascia_real *frame_mass;     ///< [N] sum_s m_s w_is
  const fascia_real *frame_moment;   ///< [3N] sum_s m_s w_is d_is
  const fascia_real *frame_load;     ///< [6N] force, torque
  const fascia_real *rest_rotation;  ///< [4N] quaternions at rest
  fascia_real gravity[3];
  const unsigned char *mask;         ///< [6N] 1 free (the reduced coordinates: of a body only its master)
  const unsigned char *full_mask;    ///< [6N] every frame the tissue moves (mask itself without bodies)
  fascia_pt_bodies bodies;           ///< rigid organs (count 0: none); the operator is then P^T A P
  fascia_real *prolonged, *product;  ///< [6N] P z, and A P z on every frame (bodies only)
  // state: anchor, increments, current iterate
  fascia_real *x_base, *q_base, *x, *q, *A, *A_mass; ///< [3N] [4N] [3N] [4N] [9N] [9N]
  fascia_real *d, *d_trial, *target, *target_M;     ///< [6N] each
  fascia_real *saved;                               ///< [13N] a saved iterate: x_base, q_base, d (the watchdog)
  fascia_real *g, *g_trial, *p;                     ///< gradient at d and at d_trial, direction
  fascia_real *r, *z, *dir, *Ad;                    ///< CG vectors [6N]
  fascia_real *mass_blocks, *blocks, *inverse;      ///< [36N] lumped mass, tangent diagonal, preconditioner
  fascia_real *damping, *torque, *frame_terms;      ///< [6N] Levenberg diagonal, [3N], [4N]
  fascia_real *pair_buffer, *pair_mass, *pair_blocks; ///< [6P] [6P] [36P]
  fascia_real *cache, *sample_energy;               ///< [S * FASCIA_PT_CACHE_SIZE], [S]
  int *sample_flags;                                ///< [S]
  fascia_pt_patches patches;                        ///< volumetric patches (count 0: none); pm.sample_pressure is theirs
  fascia_pt_modes modes;                            ///< their enhanced strain modes; pm.sample_enhanced is theirs
  int32_t modes_count;                              ///< patches.count with modes, 0 without
  const fascia_dev_settings *set;
  fascia_dev_scalars *sc;
} fascia_dev;

/// Per-item kernels; the comment gives the item count.
typedef enum fascia_dev_kernel {
  FASCIA_K_TRIAL = 0,        ///< 6N: d_trial = d + value p (value 0: d)
  FASCIA_K_STATE,            ///< N: x, q, A at x_base, q_base (+) d_trial
  FASCIA_K_MASS_SNAPSHOT,    ///< N: A_mass = A at the anchor q_base
  FASCIA_K_LUMPED_MASS,      ///< N: lumped 6x6 mass blocks at A_mass
  FASCIA_K_SAMPLE_GRADIENT,  ///< S: energy, partial gradients, cache
  FASCIA_K_SAMPLE_MASS,      ///< S: partial consistent-mass products of in
  FASCIA_K_FRAME_GRADIENT,   ///< N: g_trial and frame_terms of the step objective
  FASCIA_K_FRAME_MASS_APPLY, ///< N: out = M in (after FASCIA_K_SAMPLE_MASS for consistent mass)
  FASCIA_K_SAMPLE_STIFFNESS, ///< S: partial stiffness products of in (skipped when CG is not running)
  FASCIA_K_SAMPLE_STIFFNESS_SMOOTHING, ///< S: the same for models without rotation coupling
  FASCIA_K_SAMPLE_STIFFNESS_PAPER,     ///< S: the same for models with neither coupling nor smoothing
  FASCIA_K_CG_SAMPLE_MASS,   ///< S: FASCIA_K_SAMPLE_MASS inside CG: only with consistent mass and a mass term
  FASCIA_K_PAIR_DIAGONAL,    ///< P: one pair's 6x6 block of its sample's stiffness
  FASCIA_K_FRAME_PRECOND,    ///< N: tangent diagonal blocks, preconditioner blocks
  FASCIA_K_DAMPING,          ///< 6N: Levenberg diagonal |diag(blocks)|
  FASCIA_K_DAMPING_WEIGHT,   ///< 6N: the Levenberg weights from the diagonal and the scale
  FASCIA_K_PRECOND_DESCENT,  ///< N: p = -P^-1 g (fallback descent direction)
  FASCIA_K_COPY_GRADIENT,    ///< 6N: g = g_trial
  FASCIA_K_STEP_ROTATION,    ///< N: dynamic: the direction p back to increments of d (linalg.h)
  FASCIA_K_ACCEPT_STATIC,    ///< N: re-anchor at the iterate, d = 0, g = g_trial
  FASCIA_K_ACCEPT_DYNAMIC,   ///< 6N: d = d_trial, g = g_trial
  FASCIA_K_PATCH_EVALUATE,   ///< patches: mean dilatation, energy, pressures, G_e (before the samples' gradient)
  FASCIA_K_PATCH_RATE,       ///< patches: rank-one coefficients of in (skipped when CG is not running)
  FASCIA_K_MODES_EVALUATE,   ///< patches: enhanced strain modes' amplitudes, enhanced F (before FASCIA_K_PATCH_EVALUATE)
  FASCIA_K_MODES_TANGENT,    ///< patches: the modes' factors W_e at the last objective's state
  FASCIA_K_MODES_REDUCE,     ///< patches: the condensed terms' coefficients of in (skipped when CG is not running)
  FASCIA_K_SAVE,             ///< N: saved = the iterate (x_base, q_base, d)
  FASCIA_K_RESTORE,          ///< N: the iterate = saved
  FASCIA_K_SAMPLE_OUTPUT,    ///< S: out [5S]: strain, stress, position [3] (point/sample.h, the outputs' queries)
  // rigid organs (point/body.h); the operator's three run only inside CG
  FASCIA_K_BODY_EXPAND,      ///< N: slaves' d_trial from their master's
  FASCIA_K_BODY_GRADIENT,    ///< organs: g_trial folded into the masters, the bodies' energy and terms
  FASCIA_K_BODY_PROLONG,     ///< N: prolonged = P z
  FASCIA_K_FRAME_OPERATOR,   ///< N: product = A prolonged on every frame the tissue moves
  FASCIA_K_BODY_OPERATOR,    ///< organs: product folded into the masters, the bodies' terms of z
  FASCIA_K_BODY_DIAGONAL,    ///< organs: a master's block and preconditioner become its body's
  FASCIA_K_COUNT
} fascia_dev_kernel;

/// Reduction terms: each item gives up to four values, summed over items.
typedef enum fascia_dev_terms {
  FASCIA_T_SAMPLES = 0, ///< S: energy, inverted, not finite
  FASCIA_T_FRAMES,      ///< N: frame_terms (external energy, d.Md, d.target_M, |g|^2)
  FASCIA_T_DOT,         ///< n: a.b
  FASCIA_T_SUM,         ///< n: a
  FASCIA_T_CG_START,    ///< N: r = -g, p = 0, z = P^-1 r, dir = z; gives r.r, r.z
  FASCIA_T_OPERATOR,    ///< N: dir = z + beta dir, Ad = A dir (skipped unless CG runs); gives dir.Ad, dir.dir
  FASCIA_T_CG_UPDATE,   ///< N: p, r, z by the step's action; gives r.r, r.z
  FASCIA_T_PATCHES,     ///< patches: their volumetric energy
  FASCIA_T_STRAIN,      ///< S: 1 where the strain at the state is past strain_limit or not finite
  FASCIA_T_COUNT
} fascia_dev_terms;

/// Scalar steps run by one thread on the reduced sums.
typedef enum fascia_dev_step {
  FASCIA_S_STORE = 0,    ///< sum -> sc->sum
  FASCIA_S_SAMPLES,      ///< internal energy, inverted and non-finite counts
  FASCIA_S_OBJECTIVE,    ///< external energy, the step objective phi, |g|^2
  FASCIA_S_TARGET,       ///< target norm
  FASCIA_S_SCALE,        ///< mean absolute diagonal
  FASCIA_S_CG_START,
  FASCIA_S_CG_CURVATURE,
  FASCIA_S_CG_RESIDUAL,
  FASCIA_S_PATCHES,      ///< internal energy += the patches' (after FASCIA_S_SAMPLES)
  FASCIA_S_COUNT
} fascia_dev_step;

/// The state views the per-sample math reads.
static inline FASCIA_HD fascia_pt_state fascia_dev_state(const fascia_dev *D) {
  fascia_pt_state st;
  st.frame_x = D->x;
  st.frame_A = D->A;
  return st;
}

static inline FASCIA_HD fascia_pt_state fascia_dev_mass_state(const fascia_dev *D) {
  fascia_pt_state st;
  st.frame_x = D->x;
  st.frame_A = D->A_mass;
  return st;
}

// sum over the reverse table of frame i of a pair buffer of width 6
static inline FASCIA_HD void fascia_dev_gather6(const fascia_dev *D, const fascia_real *buffer, int32_t i,
                                                fascia_real *sum) {
  fascia_pt_frame_gather(D->frame_offsets, D->frame_pairs, buffer, i, sum);
}

// frame i's share of M v: lumped block, or the gathered consistent products
static inline FASCIA_HD void fascia_dev_frame_mass(const fascia_dev *D, int32_t i, const fascia_real *v,
                                                   fascia_real *out) {
  if (D->set->consistent_mass) fascia_dev_gather6(D, D->pair_mass, i, out);
  else fascia_pt_block6_mul(D->mass_blocks + 36 * (int64_t)i, v + 6 * (int64_t)i, out);
}

static inline FASCIA_HD void fascia_dev_rest_A(const fascia_dev *D, int32_t i, const fascia_real *q, fascia_real *A) {
  fascia_pt_frame_A(q, D->rest_rotation + 4 * (int64_t)i, A);
}

// ------------------------------------------------------------------ items --

static inline FASCIA_HD void fascia_dev_state_item(const fascia_dev *D, int32_t i) {
  const fascia_real *d = D->d_trial + 6 * (int64_t)i;
  fascia_real *x = D->x + 3 * (int64_t)i, *q = D->q + 4 * (int64_t)i;
  for (int c = 0; c < 3; ++c) x[c] = D->x_base[3 * (int64_t)i + c] + d[c];
  for (int c = 0; c < 4; ++c) q[c] = D->q_base[4 * (int64_t)i + c];
  fascia_pt_quat_rotate_by(d + 3, q);
  fascia_dev_rest_A(D, i, q, D->A + 9 * (int64_t)i);
}

// lumped 6x6 mass block of frame i at A_mass (as system.c)
static inline FASCIA_HD void fascia_dev_lumped_mass_item(const fascia_dev *D, int32_t i) {
  fascia_pt_frame_lumped_mass(D->frame_lumped_moments + 13 * (int64_t)i, D->A_mass + 9 * (int64_t)i,
                              D->mass_blocks + 36 * (int64_t)i);
}

static inline FASCIA_HD void fascia_dev_sample_gradient_item(const fascia_dev *D, int32_t s) {
  const fascia_pt_state st = fascia_dev_state(D);
  int flags = 0;
  D->sample_energy[s] = fascia_pt_sample_gradient(&D->pm, &st, s, D->pair_buffer + 6 * (int64_t)D->pm.sample_offsets[s],
                                                  D->cache + (int64_t)s * FASCIA_PT_CACHE_SIZE, &flags);
  D->sample_flags[s] = flags;
}

static inline FASCIA_HD void fascia_dev_sample_mass_item(const fascia_dev *D, int32_t s, const fascia_real *v) {
  const fascia_pt_state st = fascia_dev_mass_state(D);
  const int32_t begin = D->pm.sample_offsets[s];
  fascia_pt_sample_mass(&D->pm, &st, s, D->sample_mass[s], v, D->pm.pair_frame + begin,
                        D->pair_mass + 6 * (int64_t)begin);
}

// Sample s's partial stiffness products of in (the CG direction). parts is
// a constant in each caller: a model without rotation coupling (or also
// without smoothing) gets a kernel without that code, in far fewer
// registers (sm_90: 94 for the paper's terms alone, 255 and spilling for
// all three).
FASCIA_STATIC_FORCE_INLINE FASCIA_HD void fascia_dev_sample_stiffness_item(const fascia_dev *D, int32_t s,
                                                                           const fascia_real *in, int parts) {
  if (!D->sc->cg.running) return;
  const fascia_pt_state st = fascia_dev_state(D);
  const int32_t begin = D->pm.sample_offsets[s];
  fascia_pt_sample_stiffness_parts(&D->pm, &st, s, D->cache + (int64_t)s * FASCIA_PT_CACHE_SIZE, in,
                                   D->pm.pair_frame + begin, D->pair_buffer + 6 * (int64_t)begin, parts);
}

// The step objective's gradient on frame i at d_trial (newton.c objective()
// and system.c fascia_system_evaluate, frame by frame), and the frame's terms
// of the objective: external energy, d.Md, d.target_M, |g_i|^2.
static inline FASCIA_HD void fascia_dev_frame_gradient_item(const fascia_dev *D, int32_t i) {
  const fascia_dev_settings *set = D->set;
  const int64_t i6 = 6 * (int64_t)i;
  fascia_real gi[6];
  fascia_dev_gather6(D, D->pair_buffer, i, gi);
  // gravity and frame loads, scaled by the load factor
  fascia_real external = fascia_pt_frame_external(
      D->A + 9 * (int64_t)i, D->frame_moment + 3 * (int64_t)i, D->frame_mass[i], D->gravity, set->gravity_scale,
      D->x + 3 * (int64_t)i, D->frame_load + i6, gi, D->torque + 3 * (int64_t)i);
  const fascia_real *d = D->d_trial + i6;
  external += fascia_pt_frame_step_rotation(D->frame_load + i6, set->gravity_scale, d, set->jacobian, gi);
  fascia_real dMd = 0, dz = 0;
  if (set->c1 != 0 || set->c2 != 0) {
    fascia_real Md[6];
    fascia_dev_frame_mass(D, i, D->d_trial, Md);
    const fascia_real *tM = D->target_M + i6;
    for (int c = 0; c < 6; ++c) {
      dMd += d[c] * Md[c];
      dz += d[c] * tM[c];
      gi[c] += (set->c1 + set->c2) * Md[c] - set->c1 * tM[c];
    }
  }
  fascia_real gg = 0;
  for (int c = 0; c < 6; ++c) { // a body's slaves keep theirs until the body folds them (FASCIA_K_BODY_GRADIENT)
    if (set->project && !D->full_mask[i6 + c]) gi[c] = 0;
    D->g_trial[i6 + c] = gi[c];
    gg += gi[c] * gi[c];
  }
  fascia_real *terms = D->frame_terms + 4 * (int64_t)i;
  terms[0] = external;
  terms[1] = dMd;
  terms[2] = dz;
  terms[3] = gg;
}

// One pair's 6x6 diagonal block of its sample's stiffness (as
// fascia_system_hessian_diagonal does on the CPU, frame by frame).
static inline FASCIA_HD void fascia_dev_pair_diagonal_item(const fascia_dev *D, int64_t k) {
  const int32_t s = D->pair_sample[k];
  const fascia_pt_state st = fascia_dev_state(D);
  fascia_pt_sample_pair_block(&D->pm, &st, s, D->cache + (int64_t)s * FASCIA_PT_CACHE_SIZE,
                              (int32_t)(k - D->pm.sample_offsets[s]), D->pair_blocks + 36 * k);
}

// Frame i's diagonal block of the Newton operator and its preconditioner
// block (system.c fascia_system_hessian_diagonal + precond.c)
static inline FASCIA_HD void fascia_dev_frame_precond_item(const fascia_dev *D, int32_t i) {
  const fascia_dev_settings *set = D->set;
  fascia_real *B = D->blocks + 36 * (int64_t)i;
  for (int c = 0; c < 36; ++c) B[c] = 0;
  for (int32_t r = D->frame_offsets[i]; r < D->frame_offsets[i + 1]; ++r) {
    const fascia_real *P = D->pair_blocks + 36 * (int64_t)D->frame_pairs[r];
    for (int c = 0; c < 36; ++c) B[c] += P[c];
  }
  fascia_pt_frame_diagonal_finish(D->A + 9 * (int64_t)i, D->frame_moment + 3 * (int64_t)i, D->gravity,
                                  set->gravity_scale, D->torque + 3 * (int64_t)i, B);
  if (D->patches.count > 0) fascia_pt_patch_frame_diagonal_add(&D->patches, i, B);
  if (D->modes_count > 0) fascia_pt_modes_frame_diagonal_add(&D->patches, &D->modes, i, B);
  if (set->mass_coefficient != 0) // lumped blocks stand in for consistent ones (precond.c)
    for (int c = 0; c < 36; ++c) B[c] += set->mass_coefficient * D->mass_blocks[36 * (int64_t)i + c];
  for (int c = 0; c < 6; ++c) B[7 * c] += set->shift * D->damping[6 * (int64_t)i + c];
  fascia_pt_block6_precond(B, set->precond == 1 /* FASCIA_PRECOND_JACOBI */, D->inverse + 36 * (int64_t)i);
}

static inline FASCIA_HD const fascia_real *fascia_dev_inverse(const fascia_dev *D, int32_t i) {
  return D->set->precond == 0 /* FASCIA_PRECOND_NONE */ ? (const fascia_real *)0 : D->inverse + 36 * (int64_t)i;
}

static inline FASCIA_HD void fascia_dev_precond_descent_item(const fascia_dev *D, int32_t i) {
  const int64_t i6 = 6 * (int64_t)i;
  fascia_pt_block6_apply(fascia_dev_inverse(D, i), D->mask + i6, D->g + i6, D->p + i6);
  for (int c = 0; c < 6; ++c) D->p[i6 + c] = -D->p[i6 + c];
}

static inline FASCIA_HD void fascia_dev_accept_static_item(const fascia_dev *D, int32_t i) {
  for (int c = 0; c < 3; ++c) D->x_base[3 * (int64_t)i + c] = D->x[3 * (int64_t)i + c];
  for (int c = 0; c < 4; ++c) D->q_base[4 * (int64_t)i + c] = D->q[4 * (int64_t)i + c];
  for (int c = 0; c < 6; ++c) {
    D->d[6 * (int64_t)i + c] = 0;
    D->g[6 * (int64_t)i + c] = D->g_trial[6 * (int64_t)i + c];
  }
}

// Frame i's part of the iterate to the saved copy (save 1) or back (0).
static inline FASCIA_HD void fascia_dev_saved_item(const fascia_dev *D, int32_t i, int save) {
  const int64_t N = D->frame_count;
  fascia_real *parts[3] = {D->x_base + 3 * (int64_t)i, D->q_base + 4 * (int64_t)i, D->d + 6 * (int64_t)i};
  fascia_real *copies[3] = {D->saved + 3 * (int64_t)i, D->saved + 3 * N + 4 * (int64_t)i, D->saved + 7 * N + 6 * (int64_t)i};
  const int sizes[3] = {3, 4, 6};
  for (int k = 0; k < 3; ++k)
    for (int c = 0; c < sizes[k]; ++c) {
      if (save) copies[k][c] = parts[k][c];
      else parts[k][c] = copies[k][c];
    }
}

// Frame i's entries of the Newton operator's product of v (H + mass_coefficient
// M + shift D, cg.c fascia_operator_apply frame by frame), on the entries
// mask frees; the stiffness kernels have left H's pair products of v.
static inline FASCIA_HD void fascia_dev_frame_operator(const fascia_dev *D, int32_t i, const fascia_real *v,
                                                       const unsigned char *mask, fascia_real *out) {
  const fascia_dev_settings *set = D->set;
  const int64_t i6 = 6 * (int64_t)i;
  fascia_dev_gather6(D, D->pair_buffer, i, out);
  if (D->patches.count > 0) fascia_pt_patch_frame_add(&D->patches, i, out);
  if (D->modes_count > 0) fascia_pt_modes_frame_add(&D->patches, &D->modes, i, out);
  fascia_pt_frame_gravity_product(D->A + 9 * (int64_t)i, D->frame_moment + 3 * (int64_t)i, D->gravity,
                                  set->gravity_scale, v + i6, out);
  fascia_pt_frame_symmetrizing_product(D->torque + 3 * (int64_t)i, v + i6, out);
  fascia_real Mv[6];
  if (set->mass_coefficient != 0) fascia_dev_frame_mass(D, i, v, Mv);
  fascia_pt_frame_operator_end(set->mass_coefficient, set->mass_coefficient != 0 ? Mv : NULL, set->shift,
                               D->damping + i6, v + i6, mask + i6, out);
}

// Body b's part of the objective: its slaves' gradient folded into the
// master's, its energy added to the master's external term, and the two
// frames' |g|^2 terms made again (as the CPU's objective, organs.c).
static inline FASCIA_HD void fascia_dev_body_gradient_item(const fascia_dev *D, int32_t b) {
  const fascia_pt_bodies *B = &D->bodies;
  if (!B->active[b]) return;
  const fascia_dev_settings *set = D->set;
  const fascia_pt_body_step step = {set->c1, set->c2, set->gravity_scale, set->jacobian,
                                    {D->gravity[0], D->gravity[1], D->gravity[2]}};
  const int32_t m = B->master[b];
  D->frame_terms[4 * (int64_t)m] += fascia_pt_body_gradient(B, b, &step, D->x, D->q, D->x_base, D->q_base, D->d_trial,
                                                            D->g_trial);
  for (int32_t f = B->frame_offsets[b]; f < B->frame_offsets[b + 1]; ++f) {
    const int64_t i = B->frames[f];
    fascia_real gg = 0;
    for (int c = 0; c < 6; ++c) gg += D->g_trial[6 * i + c] * D->g_trial[6 * i + c];
    D->frame_terms[4 * i + 3] = gg;
  }
}

// Body b's master block of the reduced operator, and its preconditioner
// block (after FASCIA_K_FRAME_PRECOND; precond.c)
static inline FASCIA_HD void fascia_dev_body_diagonal_item(const fascia_dev *D, int32_t b) {
  const fascia_pt_bodies *B = &D->bodies;
  if (!B->active[b]) return;
  const int64_t m = B->master[b];
  fascia_pt_body_diagonal(B, b, D->set->mass_coefficient, D->x, D->q, D->blocks);
  fascia_pt_block6_precond(D->blocks + 36 * m, D->set->precond == 1 /* FASCIA_PRECOND_JACOBI */, D->inverse + 36 * m);
}

/// Runs item i of a per-item kernel; in, out and value as the kernel's
/// comment says.
static inline FASCIA_HD void fascia_dev_item(const fascia_dev *D, int kernel, int64_t i, const fascia_real *in,
                                             fascia_real *out, fascia_real value) {
  const int32_t i32 = (int32_t)i;
  switch (kernel) {
  case FASCIA_K_TRIAL:
    D->d_trial[i] = value == 0 ? D->d[i] : D->d[i] + value * D->p[i];
    break;
  case FASCIA_K_STATE: fascia_dev_state_item(D, i32); break;
  case FASCIA_K_MASS_SNAPSHOT: fascia_dev_rest_A(D, i32, D->q_base + 4 * i, D->A_mass + 9 * i); break;
  case FASCIA_K_LUMPED_MASS: fascia_dev_lumped_mass_item(D, i32); break;
  case FASCIA_K_SAMPLE_GRADIENT: fascia_dev_sample_gradient_item(D, i32); break;
  case FASCIA_K_CG_SAMPLE_MASS:
    if (!D->sc->cg.running || !D->set->consistent_mass || D->set->mass_coefficient == 0) break;
    fascia_dev_sample_mass_item(D, i32, in);
    break;
  case FASCIA_K_SAMPLE_MASS: fascia_dev_sample_mass_item(D, i32, in); break;
  case FASCIA_K_FRAME_GRADIENT: fascia_dev_frame_gradient_item(D, i32); break;
  case FASCIA_K_FRAME_MASS_APPLY: fascia_dev_frame_mass(D, i32, in, out + 6 * i); break;
  case FASCIA_K_SAMPLE_STIFFNESS: fascia_dev_sample_stiffness_item(D, i32, in, FASCIA_PT_PART_ALL); break;
  case FASCIA_K_SAMPLE_STIFFNESS_SMOOTHING:
    fascia_dev_sample_stiffness_item(D, i32, in, FASCIA_PT_PART_BASE | FASCIA_PT_PART_SMOOTHING);
    break;
  case FASCIA_K_SAMPLE_STIFFNESS_PAPER: fascia_dev_sample_stiffness_item(D, i32, in, FASCIA_PT_PART_BASE); break;
  case FASCIA_K_PAIR_DIAGONAL: fascia_dev_pair_diagonal_item(D, i); break;
  case FASCIA_K_FRAME_PRECOND: fascia_dev_frame_precond_item(D, i32); break;
  case FASCIA_K_DAMPING: D->damping[i] = fabs(D->blocks[36 * (i / 6) + 7 * (i % 6)]); break;
  case FASCIA_K_DAMPING_WEIGHT: D->damping[i] = fascia_pt_levenberg_weight(D->damping[i], (int)(i % 6), D->sc->scale); break;
  case FASCIA_K_PRECOND_DESCENT: fascia_dev_precond_descent_item(D, i32); break;
  case FASCIA_K_COPY_GRADIENT: D->g[i] = D->g_trial[i]; break;
  case FASCIA_K_STEP_ROTATION: fascia_pt_step_rotation_map(D->d + 6 * i, D->mask + 6 * i, 1, D->p + 6 * i); break;
  case FASCIA_K_ACCEPT_STATIC: fascia_dev_accept_static_item(D, i32); break;
  case FASCIA_K_ACCEPT_DYNAMIC:
    D->d[i] = D->d_trial[i];
    D->g[i] = D->g_trial[i];
    break;
  case FASCIA_K_PATCH_EVALUATE: {
    const fascia_pt_state st = fascia_dev_state(D);
    fascia_pt_patch_evaluate(&D->pm, &st, &D->patches, i32);
    fascia_pt_patch_gradient(&D->pm, &st, &D->patches, i32);
    break;
  }
  case FASCIA_K_PATCH_RATE:
    if (D->sc->cg.running) fascia_pt_patch_rate(&D->patches, i32, in);
    break;
  case FASCIA_K_MODES_EVALUATE: {
    const fascia_pt_state st = fascia_dev_state(D);
    const fascia_pt_model own = fascia_pt_modes_local_model(&D->pm);
    fascia_pt_modes_evaluate(&own, &st, &D->patches, &D->modes, i32);
    break;
  }
  case FASCIA_K_MODES_TANGENT: {
    const fascia_pt_state st = fascia_dev_state(D);
    fascia_pt_modes_tangent(&D->pm, &st, &D->patches, &D->modes, i32, D->cache, D->pair_buffer, (const fascia_real *)0,
                            (const fascia_real *)0);
    break;
  }
  case FASCIA_K_MODES_REDUCE:
    if (D->sc->cg.running) fascia_pt_modes_reduce(&D->patches, &D->modes, i32, in);
    break;
  case FASCIA_K_SAVE:
  case FASCIA_K_RESTORE: fascia_dev_saved_item(D, i32, kernel == FASCIA_K_SAVE); break;
  case FASCIA_K_SAMPLE_OUTPUT: {
    const fascia_pt_state st = fascia_dev_state(D);
    const int64_t S = D->sample_count;
    out[i] = fascia_pt_sample_output(&D->pm, &st, i32, out + S + i);
    fascia_pt_sample_position(&D->pm, &st, i32, out + 2 * S + 3 * i);
    break;
  }
  case FASCIA_K_BODY_EXPAND: fascia_pt_body_expand(&D->bodies, i32, D->x_base, D->q_base, D->d_trial); break;
  case FASCIA_K_BODY_GRADIENT: fascia_dev_body_gradient_item(D, i32); break;
  case FASCIA_K_BODY_PROLONG:
    if (D->sc->cg.running) fascia_pt_body_prolong(&D->bodies, i32, D->x, D->z, D->prolonged);
    break;
  case FASCIA_K_FRAME_OPERATOR:
    if (D->sc->cg.running) fascia_dev_frame_operator(D, i32, D->prolonged, D->full_mask, D->product + 6 * i);
    break;
  case FASCIA_K_BODY_OPERATOR:
    if (D->sc->cg.running && D->bodies.active[i])
      fascia_pt_body_restrict(&D->bodies, i32, D->set->mass_coefficient, D->x, D->q, D->z, D->product);
    break;
  case FASCIA_K_BODY_DIAGONAL: fascia_dev_body_diagonal_item(D, i32); break;
  default: break;
  }
}

// ------------------------------------------------------------- reductions --

// Newton operator on frame i: w_i = (A z)_i on the free DOFs (with rigid
// organs, P^T A P z, which FASCIA_K_BODY_OPERATOR has left in product),
// then CG's new direction and its image, dir = z + beta dir and Ad = w +
// beta Ad (A dir by recurrence: the product takes z, which the previous
// reduction left complete, so no launch of its own updates dir); t gets
// dir_i.Ad_i and dir_i.dir_i. Right after CG starts dir = z and Ad = w.
static inline FASCIA_HD void fascia_dev_operator_term(const fascia_dev *D, int32_t i, fascia_real *t) {
  const int64_t i6 = 6 * (int64_t)i;
  const fascia_real *v = D->z + i6;
  fascia_real out[6];
  if (D->bodies.count > 0)
    for (int c = 0; c < 6; ++c) out[c] = D->mask[i6 + c] ? D->product[i6 + c] : 0;
  else
    fascia_dev_frame_operator(D, i, D->z, D->mask, out);
  const int next = D->sc->cg.action == FASCIA_CG_DIRECTION;
  const fascia_real beta = D->sc->cg.beta;
  t[0] = t[1] = 0;
  for (int c = 0; c < 6; ++c) {
    const fascia_real dir = next ? v[c] + beta * D->dir[i6 + c] : v[c];
    const fascia_real Ad = next ? out[c] + beta * D->Ad[i6 + c] : out[c];
    D->dir[i6 + c] = dir;
    D->Ad[i6 + c] = Ad;
    t[0] += dir * Ad;
    t[1] += dir * dir;
  }
}

static inline FASCIA_HD void fascia_dev_cg_start_term(const fascia_dev *D, int32_t i, fascia_real *t) {
  const int64_t i6 = 6 * (int64_t)i;
  for (int c = 0; c < 6; ++c) {
    D->r[i6 + c] = D->mask[i6 + c] ? -D->g[i6 + c] : 0;
    D->p[i6 + c] = 0;
  }
  if (D->set->jacobian) fascia_pt_step_rotation_map(D->d + i6, D->mask + i6, 0, D->r + i6);
  fascia_pt_block6_apply(fascia_dev_inverse(D, i), D->mask + i6, D->r + i6, D->z + i6);
  t[0] = t[1] = 0;
  for (int c = 0; c < 6; ++c) {
    D->dir[i6 + c] = D->z[i6 + c];
    t[0] += D->r[i6 + c] * D->r[i6 + c];
    t[1] += D->r[i6 + c] * D->z[i6 + c];
  }
}

static inline FASCIA_HD void fascia_dev_cg_update_term(const fascia_dev *D, int32_t i, fascia_real *t) {
  const int64_t i6 = 6 * (int64_t)i;
  const int action = D->sc->cg.action;
  if (action == FASCIA_CG_COPY_Z)
    for (int c = 0; c < 6; ++c) D->p[i6 + c] = D->z[i6 + c];
  if (action != FASCIA_CG_UPDATE) return;
  const fascia_real alpha = D->sc->cg.alpha;
  for (int c = 0; c < 6; ++c) {
    D->p[i6 + c] += alpha * D->dir[i6 + c];
    D->r[i6 + c] -= alpha * D->Ad[i6 + c];
  }
  fascia_pt_block6_apply(fascia_dev_inverse(D, i), D->mask + i6, D->r + i6, D->z + i6);
  for (int c = 0; c < 6; ++c) {
    t[0] += D->r[i6 + c] * D->r[i6 + c];
    t[1] += D->r[i6 + c] * D->z[i6 + c];
  }
}

/// Item i's values of a reduction (t: four values, zero on entry).
static inline FASCIA_HD void fascia_dev_term(const fascia_dev *D, int terms, int64_t i, const fascia_real *a,
                                             const fascia_real *b, fascia_real *t) {
  switch (terms) {
  case FASCIA_T_SAMPLES: {
    const int f = D->sample_flags[i];
    t[0] = D->sample_energy[i];
    t[1] = (f & FASCIA_PT_FLAG_INVERTED) ? 1 : 0;
    t[2] = (f & FASCIA_PT_FLAG_NONFINITE) ? 1 : 0;
    break;
  }
  case FASCIA_T_FRAMES:
    for (int c = 0; c < 4; ++c) t[c] = D->frame_terms[4 * i + c];
    break;
  case FASCIA_T_DOT: t[0] = a[i] * b[i]; break;
  case FASCIA_T_SUM: t[0] = a[i]; break;
  case FASCIA_T_CG_START: fascia_dev_cg_start_term(D, (int32_t)i, t); break;
  case FASCIA_T_OPERATOR:
    if (D->sc->cg.running) fascia_dev_operator_term(D, (int32_t)i, t);
    break;
  case FASCIA_T_CG_UPDATE: fascia_dev_cg_update_term(D, (int32_t)i, t); break;
  case FASCIA_T_STRAIN: {
    const fascia_pt_state st = fascia_dev_state(D);
    fascia_real F[9];
    fascia_pt_sample_F(&D->pm, &st, (int32_t)i, F);
    t[0] = fascia_pt_strain_norm(F) <= D->set->strain_limit ? 0 : 1;
    break;
  }
  case FASCIA_T_PATCHES:
    t[0] = D->patches.energy[i];
    t[1] = D->modes_count > 0 ? D->modes.failed[i] : 0;
    break;
  default: break;
  }
}

/// The scalar step after a reduction, run by one thread (CG's scalar logic
/// is point/cg.h's, so that CG never waits for the host).
static inline FASCIA_HD void fascia_dev_scalar_step(const fascia_dev *D, int step, const fascia_real *sum) {
  fascia_dev_scalars *sc = D->sc;
  const fascia_dev_settings *set = D->set;
  switch (step) {
  case FASCIA_S_STORE:
    for (int c = 0; c < 4; ++c) sc->sum[c] = sum[c];
    break;
  case FASCIA_S_SAMPLES:
    sc->energy_internal = sum[0];
    sc->inverted = sum[1];
    sc->nonfinite = sum[2];
    break;
  case FASCIA_S_OBJECTIVE: {
    sc->energy_external = sum[0];
    const fascia_real dMd = sum[1], dz = sum[2];
    sc->phi = sc->energy_internal + sc->energy_external;
    if (set->c1 != 0 || set->c2 != 0)
      sc->phi += FASCIA_R(0.5) * set->c1 * (dMd - 2 * dz + sc->target_norm) + FASCIA_R(0.5) * set->c2 * dMd;
    sc->gradient_norm2 = sum[3];
    break;
  }
  case FASCIA_S_TARGET: sc->target_norm = sum[0]; break;
  case FASCIA_S_PATCHES:
    sc->energy_internal += sum[0];
    sc->modes_failed = sum[1];
    break;
  case FASCIA_S_SCALE: {
    const fascia_real n = 6 * (fascia_real)D->frame_count;
    sc->scale = sum[0] > 0 ? sum[0] / n : 1;
    break;
  }
  case FASCIA_S_CG_START: fascia_pt_cg_start(&sc->cg, &set->cg_limits, sum[0], sum[1]); break;
  case FASCIA_S_CG_CURVATURE: fascia_pt_cg_curvature(&sc->cg, sc->scale, sum[0], sum[1]); break;
  case FASCIA_S_CG_RESIDUAL: fascia_pt_cg_residual(&sc->cg, &set->cg_limits, sum[0], sum[1]); break;
  default: break;
  }
}

#endif
