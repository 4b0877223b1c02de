// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Per-sample mechanics of the frame scheme (paper sec. 2.1-2.2,
// docs/mechanics.md): deformation gradient, energy, partial forces on each
// neighbour frame, and partial stiffness products. One call handles one
// sample and writes one 6-vector per sample-frame pair; the per-frame sums go
// through the reverse table elsewhere (no atomics, deterministic).
//
// Notation, per pair (i, s): d = p_rest_s - x_rest_i (rest world offset),
// A_i = R_i R_rest_i^T, a = A_i d (= R_i l_is), g = grad w_is, w = w_is,
// C_i = a g^T + w A_i. Then
//   F       = sum_i (x_i + a) g^T + w A_i                       (paper eq. 8)
//   dF      = sum_i dx_i g^T + [dtheta_i]x C_i                  (eq. 10-11)
// for a world-space rotation variation dR_i = [dtheta_i]x R_i.
//
// Energy of a sample: v (psi(F) + sum_i w mu_c |skew(A_i^T F)|^2). The second
// term (Cosserat coupling, mu_c = rotation_coupling * mu) ties each frame's
// rotation to the material rotation around it; mu_c = 0 is the paper's scheme.
// With Pt = dpsi/dF + sum_i 2 mu_c w A_i K_i, K_i = skew(A_i^T F), the energy
// gradient on frame i is
//   g_x     = v Pt g
//   g_theta = v (axial(C_i Pt^T) + 2 mu_c w axial(F K_i A_i^T))
// and the force is its negative (paper eq. 18 in this notation).
//
// A second, independent term smooths the frame rotations (a Cosserat
// curvature energy): v k_c/2 sum_c |M_c|^2 with M_c = sum_i g_c A_i, the
// gradient of the interpolated rotation field along axis c; k_c = mu l^2 with
// an internal length l. It vanishes for any uniform rotation, so rigid
// motions stay free, and it penalizes the zero-energy rotation modes of the
// scheme (planes of frames twisting against each other: large rotation
// jumps) far more than the smooth rotation field of a bent body. Its
// gradient on frame i is v k_c axial(A_i N_i^T), N_i = sum_c g_c M_c. The stiffness
// product is the exact directional derivative of that gradient under the
// update x += dx, R <- exp([dtheta]x) R: it includes the geometric part
// (paper eq. 25-30), here axial([dtheta_i]x C_i Pt^T).
#ifndef FASCIA_POINT_SAMPLE_H
#define FASCIA_POINT_SAMPLE_H

#include "material.h"

/// Read-only arrays of a model, as a backend holds them (host or device).
/// N frames, S samples, P pairs.
typedef struct fascia_pt_model {
  const int32_t *sample_offsets;   ///< [S+1] CSR of pairs
  const int32_t *pair_frame;       ///< [P]
  const fascia_real *pair_weight;  ///< [P] w
  const fascia_real *pair_gradient; ///< [3P] g
  const fascia_real *pair_offset;  ///< [3P] d = p_rest_s - x_rest_i
  const fascia_real *sample_volume; ///< [S] v
  const fascia_real *sample_lambda; ///< [S] Pa
  const fascia_real *sample_mu;     ///< [S] Pa
  const fascia_real *sample_coupling; ///< [S] mu_c, Pa
  const fascia_real *sample_curvature; ///< [S] k_c = mu l^2, Pa m^2 (rotation smoothness)
  const int32_t *sample_law;        ///< [S] FASCIA_PT_LAW_*
  /// [S] the pressure a sample's volumetric patch puts on it (Pa: lambda
  /// times the patch's mean dilatation, sim/src/cpu/dilatation.h), or NULL
  /// without patches: the stress gains pressure * dtheta/dF, the energy
  /// nothing (the patch holds it).
  const fascia_real *sample_pressure;
  /// [9S] the enhanced part of a sample's deformation gradient, from its
  /// patch's strain modes (sim/src/cpu/modes.h, row-major), or NULL without
  /// modes: F = the frames' F + this. The frames do not move it.
  const fascia_real *sample_enhanced;
} fascia_pt_model;

/// Current frame state: positions [3N] and A_i = R_i R_rest_i^T [9N].
typedef struct fascia_pt_state {
  const fascia_real *frame_x;
  const fascia_real *frame_A;
} fascia_pt_state;

/// What the stiffness product reuses per sample: F, Pt, the law's aux.
#define FASCIA_PT_CACHE_SIZE (18 + FASCIA_PT_AUX_SIZE)

/// Flag bits a sample can raise (host reports the lowest flagged sample).
enum { FASCIA_PT_FLAG_INVERTED = 1, FASCIA_PT_FLAG_NONFINITE = 2 };

static inline FASCIA_HD void fascia_pt_pair_C(const fascia_real *A, const fascia_real *d, const fascia_real *g,
                                              fascia_real w, fascia_real *a, fascia_real *C) {
  fascia_pt_mat_vec(A, d, a);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) C[3 * r + c] = a[r] * g[c] + w * A[3 * r + c];
}

/// Coupling term of pair (A, sample F): K = skew(A^T F) and, for the
/// variation dF, dtheta of its frame, dK = skew(A^T (dF - [dtheta]x F));
/// dF and dt may be NULL (K only).
static inline FASCIA_HD void fascia_pt_coupling_K(const fascia_real *A, const fascia_real *F, const fascia_real *dF,
                                                  const fascia_real *dt, fascia_real *K, fascia_real *dK) {
  fascia_real G[9];
  fascia_pt_mat_tmul(A, F, G);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) K[3 * r + c] = FASCIA_R(0.5) * (G[3 * r + c] - G[3 * c + r]);
  if (!dF) return;
  fascia_real tF[9], H[9];
  fascia_pt_skew_mul(dt, F, tF);
  for (int q = 0; q < 9; ++q) tF[q] = dF[q] - tF[q];
  fascia_pt_mat_tmul(A, tF, H);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) dK[3 * r + c] = FASCIA_R(0.5) * (H[3 * r + c] - H[3 * c + r]);
}

/// The rounding error of an energy evaluation, J, for a sum of
/// fascia_pt_sample_energy_scale: 8 ulps of it, whatever the energy's value
/// (StVK's E = (F^T F - I)/2 loses the digits of F^T F near rest). The
/// Newton solver and the modes' local solve take changes within it.
static inline FASCIA_HD fascia_real fascia_pt_energy_roundoff(fascia_real scale) {
  return 8 * FASCIA_R(2.220446049250313e-16) * scale;
}

/// Sample s's share of that scale: v (|lambda| + 2 |mu|), J.
static inline FASCIA_HD fascia_real fascia_pt_sample_energy_scale(const fascia_pt_model *m, int32_t s) {
  return m->sample_volume[s] * (fabs(m->sample_lambda[s]) + 2 * fabs(m->sample_mu[s]));
}

/// Deformed position p_s (paper eq. 3) of sample s.
static inline FASCIA_HD void fascia_pt_sample_position(const fascia_pt_model *m, const fascia_pt_state *st, int32_t s,
                                                       fascia_real *p) {
  p[0] = p[1] = p[2] = 0;
  for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k) {
    const int32_t i = m->pair_frame[k];
    fascia_real a[3];
    fascia_pt_mat_vec(st->frame_A + 9 * i, m->pair_offset + 3 * k, a);
    for (int r = 0; r < 3; ++r) p[r] += m->pair_weight[k] * (st->frame_x[3 * i + r] + a[r]);
  }
}

/// The frames' part of the deformation gradient F_s (paper eq. 8), row-major.
static inline FASCIA_HD void fascia_pt_sample_F_frames(const fascia_pt_model *m, const fascia_pt_state *st, int32_t s,
                                                       fascia_real *F) {
  for (int k = 0; k < 9; ++k) F[k] = 0;
  for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k) {
    const int32_t i = m->pair_frame[k];
    const fascia_real *A = st->frame_A + 9 * i, *g = m->pair_gradient + 3 * k, w = m->pair_weight[k];
    fascia_real a[3];
    fascia_pt_mat_vec(A, m->pair_offset + 3 * k, a);
    for (int r = 0; r < 3; ++r) {
      const fascia_real y = st->frame_x[3 * i + r] + a[r];
      for (int c = 0; c < 3; ++c) F[3 * r + c] += y * g[c] + w * A[3 * r + c];
    }
  }
}

/// Deformation gradient F_s: the frames' part and, with strain modes, the
/// enhanced part.
static inline FASCIA_HD void fascia_pt_sample_F(const fascia_pt_model *m, const fascia_pt_state *st, int32_t s,
                                                fascia_real *F) {
  fascia_pt_sample_F_frames(m, st, s, F);
  if (m->sample_enhanced)
    for (int q = 0; q < 9; ++q) F[q] += m->sample_enhanced[9 * (int64_t)s + q];
}

/// |E| = |F^T F - I| / 2 (Frobenius norm): the strain the blow-up rule and
/// the outputs report.
static inline FASCIA_HD fascia_real fascia_pt_strain_norm(const fascia_real *F) {
  fascia_real C[9];
  fascia_pt_mat_tmul(F, F, C);
  C[0] -= 1;
  C[4] -= 1;
  C[8] -= 1;
  return FASCIA_R(0.5) * sqrt(fascia_pt_ddot(C, C));
}

/// What the outputs report of sample s at st: returns its strain
/// (fascia_pt_strain_norm); where stress is not NULL, *stress gets the
/// Frobenius norm of its law's first Piola-Kirchhoff stress plus its
/// patch's pressure (m->sample_pressure at this state, where there are
/// patches).
static inline FASCIA_HD fascia_real fascia_pt_sample_output(const fascia_pt_model *m, const fascia_pt_state *st,
                                                            int32_t s, fascia_real *stress) {
  fascia_real F[9], P[9], aux[FASCIA_PT_AUX_SIZE];
  fascia_pt_sample_F(m, st, s, F);
  if (stress) {
    fascia_pt_stress(m->sample_law[s], m->sample_lambda[s], m->sample_mu[s], F, P, aux);
    if (m->sample_pressure) {
      fascia_real dtheta[9];
      fascia_pt_dilatation(m->sample_law[s], F, dtheta);
      for (int q = 0; q < 9; ++q) P[q] += m->sample_pressure[s] * dtheta[q];
    }
    *stress = sqrt(fascia_pt_ddot(P, P));
  }
  return fascia_pt_strain_norm(F);
}

/// Energy density of sample s's law at F, rotation coupling included (not
/// the patch's pressure), and its stress Pt into P[9], the law's aux into aux.
static inline FASCIA_HD fascia_real fascia_pt_sample_law_stress(const fascia_pt_model *m, const fascia_pt_state *st,
                                                                int32_t s, const fascia_real *F, fascia_real *P,
                                                                fascia_real *aux) {
  fascia_real psi = fascia_pt_stress(m->sample_law[s], m->sample_lambda[s], m->sample_mu[s], F, P, aux);
  const fascia_real muc = m->sample_coupling[s];
  if (muc > 0) {
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k) {
      const fascia_real *A = st->frame_A + 9 * m->pair_frame[k], w = m->pair_weight[k];
      fascia_real K[9], AK[9];
      fascia_pt_coupling_K(A, F, NULL, NULL, K, NULL);
      psi += w * muc * fascia_pt_ddot(K, K);
      fascia_pt_mat_mul(A, K, AK);
      for (int q = 0; q < 9; ++q) P[q] += 2 * muc * w * AK[q];
    }
  }
  return psi;
}

/// Energy, partial energy gradients and cache of sample s.
/// out: [6n] for the n pairs of s in order: (g_x, g_theta), the gradient of
/// this sample's energy with respect to that pair's frame (the force is its
/// negative); the CPU backend passes pair_buffer + 6 sample_offsets[s].
/// cache: [FASCIA_PT_CACHE_SIZE] for this sample, or NULL. F: the sample's
/// F at st (fascia_pt_sample_F), where the caller has it already.
/// Returns the sample's energy (J); *flags gets FASCIA_PT_FLAG_* bits.
FASCIA_STATIC_FORCE_INLINE FASCIA_HD fascia_real fascia_pt_sample_gradient_at(const fascia_pt_model *m,
                                                                 const fascia_pt_state *st, int32_t s,
                                                                 const fascia_real *F, fascia_real *out6,
                                                                 fascia_real *cache, int *flags) {
  fascia_real P[9], aux[FASCIA_PT_AUX_SIZE];
  const fascia_real v = m->sample_volume[s], muc = m->sample_coupling[s];
  fascia_real psi = fascia_pt_sample_law_stress(m, st, s, F, P, aux);
  const int32_t begin = m->sample_offsets[s], end = m->sample_offsets[s + 1];
  const fascia_real pressure = m->sample_pressure ? m->sample_pressure[s] : 0;
  if (pressure != 0) {
    fascia_real dtheta[9];
    fascia_pt_dilatation(m->sample_law[s], F, dtheta);
    for (int q = 0; q < 9; ++q) P[q] += pressure * dtheta[q];
  }
  const fascia_real kc = m->sample_curvature[s];
  fascia_real Mc[27]; // M_c = sum_i g_c A_i, c = 0..2, each row-major 3x3
  if (kc > 0) {
    for (int q = 0; q < 27; ++q) Mc[q] = 0;
    for (int32_t k = begin; k < end; ++k) {
      const fascia_real *A = st->frame_A + 9 * m->pair_frame[k], *g = m->pair_gradient + 3 * k;
      for (int c = 0; c < 3; ++c)
        for (int q = 0; q < 9; ++q) Mc[9 * c + q] += g[c] * A[q];
    }
    psi += FASCIA_R(0.5) * kc * (fascia_pt_ddot(Mc, Mc) + fascia_pt_ddot(Mc + 9, Mc + 9) + fascia_pt_ddot(Mc + 18, Mc + 18));
  }
  const fascia_real J = fascia_pt_det(F);
  int bad = 0;
  if (!(J > 0)) bad |= FASCIA_PT_FLAG_INVERTED;
  if (!isfinite(psi)) bad |= FASCIA_PT_FLAG_NONFINITE;
  *flags = bad;
  for (int32_t k = begin; k < end; ++k) {
    const fascia_real *A = st->frame_A + 9 * m->pair_frame[k], *g = m->pair_gradient + 3 * k, w = m->pair_weight[k];
    fascia_real a[3], C[9], M[9], t[3], *out = out6 + 6 * (k - begin);
    fascia_pt_pair_C(A, m->pair_offset + 3 * k, g, w, a, C);
    fascia_pt_mat_vec(P, g, out);
    fascia_pt_mat_mult(C, P, M);
    fascia_pt_axial(M, t);
    if (muc > 0) {
      fascia_real K[9], FK[9], FKA[9], u[3];
      fascia_pt_coupling_K(A, F, NULL, NULL, K, NULL);
      fascia_pt_mat_mul(F, K, FK);
      fascia_pt_mat_mult(FK, A, FKA);
      fascia_pt_axial(FKA, u);
      for (int r = 0; r < 3; ++r) t[r] += 2 * muc * w * u[r];
    }
    if (kc > 0) {
      fascia_real Nm[9], AN[9], u[3];
      for (int q = 0; q < 9; ++q) Nm[q] = g[0] * Mc[q] + g[1] * Mc[9 + q] + g[2] * Mc[18 + q];
      fascia_pt_mat_mult(A, Nm, AN);
      fascia_pt_axial(AN, u);
      for (int r = 0; r < 3; ++r) t[r] += kc * u[r];
    }
    for (int r = 0; r < 3; ++r) {
      out[r] *= v;
      out[3 + r] = v * t[r];
    }
  }
  if (cache) {
    for (int q = 0; q < 9; ++q) {
      cache[q] = F[q];
      cache[9 + q] = P[q];
    }
    for (int q = 0; q < FASCIA_PT_AUX_SIZE; ++q) cache[18 + q] = aux[q];
  }
  return v * psi;
}

/// fascia_pt_sample_gradient_at, F computed here.
FASCIA_STATIC_FORCE_INLINE FASCIA_HD fascia_real fascia_pt_sample_gradient(const fascia_pt_model *m, const fascia_pt_state *st,
                                                              int32_t s, fascia_real *out6, fascia_real *cache,
                                                              int *flags) {
  fascia_real F[9];
  fascia_pt_sample_F(m, st, s, F);
  return fascia_pt_sample_gradient_at(m, st, s, F, out6, cache, flags);
}

/// Partial stiffness product of sample s: for the j-th pair (i, s) writes
/// out[6j..6j+5] = (K_exact dq)_i restricted to this sample's energy, K_exact
/// being the directional derivative of the gradient above. The direction of
/// the j-th pair's frame is dq + 6 slot[j] (dx then dtheta): the global
/// product passes the [6N] vector and slot = pair_frame + sample_offsets[s];
/// a per-sample block passes a local [6n] vector and slot = 0, 1, .., n-1.
/// cache: from fascia_pt_sample_gradient at this state.
/// Parts of the stiffness product (bit mask): the paper's terms (material
/// and geometric), and the added rotation coupling and smoothing terms.
enum {
  FASCIA_PT_PART_BASE = 1,      ///< material and geometric (the paper's)
  FASCIA_PT_PART_COUPLING = 2,  ///< rotation coupling
  FASCIA_PT_PART_SMOOTHING = 4, ///< rotation smoothing
  FASCIA_PT_PART_EXTRA = 6,
  FASCIA_PT_PART_ALL = 7
};

/// only: every pair moves (FASCIA_PT_ONLY_ALL), none does and F moves by
/// dF_in (FASCIA_PT_ONLY_NONE, an enhanced mode), or pair j >= 0 alone.
enum { FASCIA_PT_ONLY_ALL = -1, FASCIA_PT_ONLY_NONE = -2 };

// The stiffness product's body. only ALL: every pair moves by dq + 6
// slot[j] and every pair gets its row out6 + 6 j. only = j: pair j alone
// moves, by dq[0..5], and only its row is written, to out6[0..5] (one column
// of the diagonal block per call; the other pairs' zero directions are
// skipped, not multiplied). only NONE: no frame moves, F moves by dF_in, and
// every pair gets its row (out6 NULL: no rows). dP_out, if not NULL, gets
// the stress change dPt.
FASCIA_STATIC_FORCE_INLINE FASCIA_HD void
fascia_pt_stiffness_core(const fascia_pt_model *m, const fascia_pt_state *st, int32_t s, const fascia_real *cache,
                         const fascia_real *dq, const int32_t *slot, fascia_real *out6, int parts, int32_t only,
                         const fascia_real *dF_in, fascia_real *dP_out) {
  const fascia_real *F = cache, *P = cache + 9, *aux = cache + 18;
  const fascia_real v = m->sample_volume[s], muc = m->sample_coupling[s];
  const int32_t begin = m->sample_offsets[s], end = m->sample_offsets[s + 1];
  // the pairs that get a row, and the pairs that move
  const int32_t first = only < 0 ? begin : begin + only, last = only < 0 ? end : begin + only + 1;
  const int32_t move_last = only == FASCIA_PT_ONLY_NONE ? first : last;
  const fascia_real zero[6] = {0, 0, 0, 0, 0, 0};
#define FASCIA_PT_DQ(k) (only == FASCIA_PT_ONLY_ALL ? dq + 6 * slot[(k) - begin] : only >= 0 && (k) == first ? dq : zero)
  // dF = sum_i dx_i g^T + [dtheta_i]x C_i
  fascia_real dF[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  if (dF_in)
    for (int q = 0; q < 9; ++q) dF[q] = dF_in[q];
  for (int32_t k = first; k < move_last; ++k) {
    const int32_t i = m->pair_frame[k];
    const fascia_real *A = st->frame_A + 9 * i, *g = m->pair_gradient + 3 * k, *dx = FASCIA_PT_DQ(k);
    const fascia_real *dt = dx + 3;
    fascia_real a[3], C[9], tC[9];
    fascia_pt_pair_C(A, m->pair_offset + 3 * k, g, m->pair_weight[k], a, C);
    fascia_pt_skew_mul(dt, C, tC);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) dF[3 * r + c] += dx[r] * g[c] + tC[3 * r + c];
  }
  fascia_real dP[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  const int base = parts & FASCIA_PT_PART_BASE, coupling = parts & FASCIA_PT_PART_COUPLING;
  if (base) {
    fascia_pt_stress_diff(m->sample_law[s], m->sample_lambda[s], m->sample_mu[s], F, aux, dF, dP);
    if (m->sample_pressure && m->sample_pressure[s] != 0)
      fascia_pt_dilatation_diff_add(m->sample_law[s], m->sample_pressure[s], F, dF, dP);
  }
  if (coupling && muc > 0) {
    // dPt += sum_j 2 mu_c w_j (dA_j K_j + A_j dK_j), dA_j = [dtheta_j]x A_j,
    // dK_j = skew(A_j^T dF - A_j^T [dtheta_j]x F)
    for (int32_t k = begin; k < end; ++k) {
      const int32_t j = m->pair_frame[k];
      const fascia_real *A = st->frame_A + 9 * j, *dt = FASCIA_PT_DQ(k) + 3, w = m->pair_weight[k];
      fascia_real K[9], dK[9], dA[9], t1[9], t2[9];
      fascia_pt_coupling_K(A, F, dF, dt, K, dK);
      fascia_pt_skew_mul(dt, A, dA);
      fascia_pt_mat_mul(dA, K, t1);
      fascia_pt_mat_mul(A, dK, t2);
      for (int q = 0; q < 9; ++q) dP[q] += 2 * muc * w * (t1[q] + t2[q]);
    }
  }
  // curvature term: M_c and dM_c = sum_i g_c [dtheta_i]x A_i
  const fascia_real kc = (parts & FASCIA_PT_PART_SMOOTHING) ? m->sample_curvature[s] : 0;
  fascia_real Mc[27], dMc[27];
  if (kc > 0) {
    for (int q = 0; q < 27; ++q) Mc[q] = dMc[q] = 0;
    for (int32_t k = begin; k < end; ++k) {
      const fascia_real *A = st->frame_A + 9 * m->pair_frame[k], *g = m->pair_gradient + 3 * k;
      for (int c = 0; c < 3; ++c)
        for (int q = 0; q < 9; ++q) Mc[9 * c + q] += g[c] * A[q];
    }
    for (int32_t k = first; k < move_last; ++k) {
      const fascia_real *A = st->frame_A + 9 * m->pair_frame[k], *g = m->pair_gradient + 3 * k;
      fascia_real tA[9];
      fascia_pt_skew_mul(FASCIA_PT_DQ(k) + 3, A, tA);
      for (int c = 0; c < 3; ++c)
        for (int q = 0; q < 9; ++q) dMc[9 * c + q] += g[c] * tA[q];
    }
  }
  if (dP_out)
    for (int q = 0; q < 9; ++q) dP_out[q] = dP[q];
  if (!out6) return;
  for (int32_t k = first; k < last; ++k) {
    const int32_t i = m->pair_frame[k];
    const fascia_real *A = st->frame_A + 9 * i, *g = m->pair_gradient + 3 * k, *dt = FASCIA_PT_DQ(k) + 3;
    const fascia_real w = m->pair_weight[k];
    fascia_real a[3], C[9], M[9], t[3], *out = out6 + 6 * (k - first);
    fascia_pt_pair_C(A, m->pair_offset + 3 * k, g, w, a, C);
    fascia_pt_mat_vec(dP, g, out);
    // material part axial(C dPt^T) plus geometric part axial([dtheta]x C Pt^T)
    fascia_pt_mat_mult(C, dP, M);
    fascia_pt_axial(M, t);
    if (base) {
      fascia_pt_mat_mult(C, P, M);
      const fascia_real trM = fascia_pt_trace(M);
      for (int r = 0; r < 3; ++r)
        t[r] += M[3 * r] * dt[0] + M[3 * r + 1] * dt[1] + M[3 * r + 2] * dt[2] - trM * dt[r];
    }
    if (coupling && muc > 0) {
      // d axial(F K A^T) = axial(dF K A^T + F dK A^T + F K dA^T), dA^T = -A^T [dtheta]x
      fascia_real K[9], dK[9], X[9], Y[9], u[3], tA[9];
      fascia_pt_coupling_K(A, F, dF, dt, K, dK);
      for (int q = 0; q < 9; ++q) X[q] = 0;
      fascia_pt_mat_mul(dF, K, Y); // dF K
      for (int q = 0; q < 9; ++q) X[q] += Y[q];
      fascia_pt_mat_mul(F, dK, Y); // F dK
      for (int q = 0; q < 9; ++q) X[q] += Y[q];
      fascia_real XA[9];
      fascia_pt_mat_mult(X, A, XA); // (dF K + F dK) A^T
      // F K dA^T = -F K A^T [dtheta]x = ([dtheta]x A K^T F^T)^T ... computed directly:
      fascia_pt_skew_mul(dt, A, tA); // dA = [dtheta]x A
      fascia_pt_mat_mul(F, K, Y);
      fascia_real Z[9];
      fascia_pt_mat_mult(Y, tA, Z); // F K dA^T
      for (int q = 0; q < 9; ++q) XA[q] += Z[q];
      fascia_pt_axial(XA, u);
      for (int r = 0; r < 3; ++r) t[r] += 2 * muc * w * u[r];
    }
    if (kc > 0) {
      // d axial(A N^T) = axial([dtheta]x A N^T + A dN^T)
      fascia_real Nm[9], dN[9], tA[9], X1[9], X2[9], u[3];
      for (int q = 0; q < 9; ++q) {
        Nm[q] = g[0] * Mc[q] + g[1] * Mc[9 + q] + g[2] * Mc[18 + q];
        dN[q] = g[0] * dMc[q] + g[1] * dMc[9 + q] + g[2] * dMc[18 + q];
      }
      fascia_pt_skew_mul(dt, A, tA);
      fascia_pt_mat_mult(tA, Nm, X1);
      fascia_pt_mat_mult(A, dN, X2);
      for (int q = 0; q < 9; ++q) X1[q] += X2[q];
      fascia_pt_axial(X1, u);
      for (int r = 0; r < 3; ++r) t[r] += kc * u[r];
    }
    for (int r = 0; r < 3; ++r) {
      out[r] *= v;
      out[3 + r] = v * t[r];
    }
  }
}
#undef FASCIA_PT_DQ

static inline FASCIA_HD void fascia_pt_sample_stiffness_parts(const fascia_pt_model *m, const fascia_pt_state *st,
                                                              int32_t s, const fascia_real *cache,
                                                              const fascia_real *dq, const int32_t *slot,
                                                              fascia_real *out6, int parts) {
  fascia_pt_stiffness_core(m, st, s, cache, dq, slot, out6, parts, FASCIA_PT_ONLY_ALL, (const fascia_real *)0,
                           (fascia_real *)0);
}

/// Sample s's response to a change dF of its deformation gradient with the
/// frames held (an enhanced strain mode, sim/src/cpu/modes.h): dP_out[9] gets
/// the stress change (law, patch pressure and rotation coupling), and, if
/// out6 is not NULL, out6 + 6 j the change of the gradient on its j-th
/// pair's frame. cache: the sample's, at the state.
static inline FASCIA_HD void fascia_pt_sample_F_response(const fascia_pt_model *m, const fascia_pt_state *st,
                                                         int32_t s, const fascia_real *cache, const fascia_real *dF,
                                                         fascia_real *out6, fascia_real *dP_out) {
  fascia_pt_stiffness_core(m, st, s, cache, (const fascia_real *)0, (const int32_t *)0, out6,
                           FASCIA_PT_PART_BASE | FASCIA_PT_PART_COUPLING, FASCIA_PT_ONLY_NONE, dF, dP_out);
}

/// The 6x6 diagonal block of sample s's stiffness on its j-th pair's frame
/// (row-major; column c is the response to unit c on that frame alone):
/// what six full products with unit vectors give, without the other pairs'
/// zero directions and rows.
static inline FASCIA_HD void fascia_pt_sample_pair_block(const fascia_pt_model *m, const fascia_pt_state *st,
                                                         int32_t s, const fascia_real *cache, int32_t j,
                                                         fascia_real *block) {
  for (int c = 0; c < 6; ++c) {
    fascia_real e[6] = {0, 0, 0, 0, 0, 0}, col[6];
    e[c] = 1;
    fascia_pt_stiffness_core(m, st, s, cache, e, (const int32_t *)0, col, FASCIA_PT_PART_ALL, j,
                             (const fascia_real *)0, (fascia_real *)0);
    for (int row = 0; row < 6; ++row) block[6 * row + c] = col[row];
  }
}

static inline FASCIA_HD void fascia_pt_sample_stiffness(const fascia_pt_model *m, const fascia_pt_state *st,
                                                        int32_t s, const fascia_real *cache, const fascia_real *dq,
                                                        const int32_t *slot, fascia_real *out6) {
  fascia_pt_sample_stiffness_parts(m, st, s, cache, dq, slot, out6, FASCIA_PT_PART_ALL);
}

/// D = dPt/dF of sample s at its cache (9x9, D[9 row + col] = dP_row /
/// dF_col): its law and its patch's pressure, not the rotation coupling.
static inline FASCIA_HD void fascia_pt_sample_tangent(const fascia_pt_model *m, int32_t s, const fascia_real *cache,
                                                      fascia_real *D) {
  fascia_pt_stress_tangent(m->sample_law[s], m->sample_lambda[s], m->sample_mu[s],
                           m->sample_pressure ? m->sample_pressure[s] : 0, cache, cache + 18, D);
}

/// v D: fascia_pt_sample_tangent times the sample's volume, as the
/// assembly and the enhanced strain modes' terms both take it.
static inline FASCIA_HD void fascia_pt_sample_tangent_volume(const fascia_pt_model *m, int32_t s,
                                                             const fascia_real *cache, fascia_real *Dv) {
  fascia_pt_sample_tangent(m, s, cache, Dv);
  for (int q = 0; q < 81; ++q) Dv[q] *= m->sample_volume[s];
}

/// B^T D (6x9, row-major) for the 9x6 map B of paper eq. 11 of a pair with
/// weight gradient g and C = a g^T + w A, from its frame's (dx, dtheta) to
/// dF: rows x_r: sum_c g_c D[(r c), :]; rows theta_r: sum_c (c_c x D[(. c),
/// :])_r, c_c the columns of C.
static inline FASCIA_HD void fascia_pt_BtD(const fascia_real *C, const fascia_real *g, const fascia_real *D,
                                           fascia_real *BtD) {
  for (int j = 0; j < 9; ++j) {
    for (int r = 0; r < 3; ++r)
      BtD[9 * r + j] = g[0] * D[9 * (3 * r) + j] + g[1] * D[9 * (3 * r + 1) + j] + g[2] * D[9 * (3 * r + 2) + j];
    fascia_real th[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c) {
      const fascia_real cc[3] = {C[c], C[3 + c], C[6 + c]};
      const fascia_real dcol[3] = {D[9 * c + j], D[9 * (3 + c) + j], D[9 * (6 + c) + j]};
      fascia_pt_cross_add(cc, dcol, th);
    }
    for (int r = 0; r < 3; ++r) BtD[9 * (3 + r) + j] = th[r];
  }
}

/// B_k^T D for pair k (fascia_pt_BtD at the state).
static inline FASCIA_HD void fascia_pt_pair_BtD(const fascia_pt_model *m, const fascia_pt_state *st, int32_t k,
                                                const fascia_real *D, fascia_real *BtD) {
  const fascia_real *A = st->frame_A + 9 * m->pair_frame[k], *g = m->pair_gradient + 3 * k;
  fascia_real a[3], C[9];
  fascia_pt_pair_C(A, m->pair_offset + 3 * k, g, m->pair_weight[k], a, C);
  fascia_pt_BtD(C, g, D, BtD);
}

/// One row x (9) of B_a^T D times B_b for the pairs b0 <= b < n of a
/// sample, laid out by component (gs[c n + b], Cs[q n + b]: g and C of pair
/// b), into row x's place in consecutive 6x6 blocks: out[36 (b - b0) + k] is
/// entry k of that row of block (a, b). Column x_k of B_b has g_c at F's
/// entry (k c); column theta_k maps x to sum_c (c_c x x_c)_k, with c_c the
/// columns of C_b and x_c = (x[c], x[3+c], x[6+c]). A loop over b, which
/// the compiler makes wide.
static inline FASCIA_HD void fascia_pt_row_times_pairs(const fascia_real *FASCIA_RESTRICT x, int32_t b0, int32_t n,
                                                       const fascia_real *FASCIA_RESTRICT gs,
                                                       const fascia_real *FASCIA_RESTRICT Cs,
                                                       fascia_real *FASCIA_RESTRICT out) {
  for (int32_t b = b0; b < n; ++b) {
    const fascia_real g0 = gs[b], g1 = gs[n + b], g2 = gs[2 * n + b];
    fascia_real *FASCIA_RESTRICT o = out + 36 * (b - b0);
    o[0] = x[0] * g0 + x[1] * g1 + x[2] * g2;
    o[1] = x[3] * g0 + x[4] * g1 + x[5] * g2;
    o[2] = x[6] * g0 + x[7] * g1 + x[8] * g2;
    const fascia_real c00 = Cs[b], c01 = Cs[n + b], c02 = Cs[2 * n + b];
    const fascia_real c10 = Cs[3 * n + b], c11 = Cs[4 * n + b], c12 = Cs[5 * n + b];
    const fascia_real c20 = Cs[6 * n + b], c21 = Cs[7 * n + b], c22 = Cs[8 * n + b];
    o[3] = (c10 * x[6] - c20 * x[3]) + (c11 * x[7] - c21 * x[4]) + (c12 * x[8] - c22 * x[5]);
    o[4] = (c20 * x[0] - c00 * x[6]) + (c21 * x[1] - c01 * x[7]) + (c22 * x[2] - c02 * x[8]);
    o[5] = (c00 * x[3] - c10 * x[0]) + (c01 * x[4] - c11 * x[1]) + (c02 * x[5] - c12 * x[2]);
  }
}

/// Where block (a, b), a <= b, of a sample's n x n blocks is among its
/// upper blocks, row by row: n (n + 1) / 2 of them.
static inline FASCIA_HD int32_t fascia_pt_upper_block(int32_t n, int32_t a, int32_t b) {
  return a * n - a * (a - 1) / 2 + (b - a);
}

/// The paper's part of the stiffness of sample s as a dense local matrix:
/// its upper blocks (a, b), a <= b, of 6x6, at out + 36
/// fascia_pt_upper_block(n, a, b), row-major (block (b, a) is the
/// transpose, but for the geometric part of a diagonal block), the
/// derivative of the gradient on the a-th pair's frame with respect to the
/// b-th pair's frame: v B_a^T D B_b (material, D = dP/dF, B the 9x6 map of
/// paper eq. 11) plus, on diagonal blocks, the geometric v (M - tr(M) I) with
/// M = C Pt^T. Equals fascia_pt_sample_stiffness_parts(.., BASE) applied to
/// unit vectors; it is how the assembled matrix is built without 6n products
/// per sample (the rotation coupling, when on, is added by such products,
/// the rotation smoothing per frame pair: smoothing_rows in sim/src/cpu/assemble.c).
/// frame_moves ([frames], NULL: all): the rows of a frame not in it are not
/// computed, and a block with such a frame is to be left unread (the
/// assembly leaves the blocks of frames a step holds). scratch: 12 n reals
/// (n the sample's pairs). Dv (81) and BtDv (54 n), where not NULL: v D
/// and every pair's B^T v D, moving or not (the enhanced strain modes'
/// terms are made of them, sim/point/modes.h). Forced inline: its caller is
/// compiled for AVX2 too.
FASCIA_STATIC_FORCE_INLINE FASCIA_HD void
fascia_pt_sample_local_stiffness(const fascia_pt_model *m, const fascia_pt_state *st, int32_t s,
                                 const fascia_real *cache, const unsigned char *frame_moves,
                                 fascia_real *FASCIA_RESTRICT scratch, fascia_real *FASCIA_RESTRICT out,
                                 fascia_real *FASCIA_RESTRICT Dv, fascia_real *FASCIA_RESTRICT BtDv) {
  const fascia_real *P = cache + 9;
  const fascia_real v = m->sample_volume[s];
  const int32_t begin = m->sample_offsets[s], n = m->sample_offsets[s + 1] - begin;
  fascia_real D[81];
  fascia_pt_sample_tangent_volume(m, s, cache, D);
  if (Dv)
    for (int q = 0; q < 81; ++q) Dv[q] = D[q];
  // the pairs' g and C by component, for fascia_pt_row_times_pairs
  fascia_real *FASCIA_RESTRICT gs = scratch, *FASCIA_RESTRICT Cs = scratch + 3 * n;
  for (int b = 0; b < n; ++b) {
    const int32_t kb = begin + b;
    const fascia_real *gb = m->pair_gradient + 3 * kb;
    fascia_real ab[3], Cb[9];
    fascia_pt_pair_C(st->frame_A + 9 * m->pair_frame[kb], m->pair_offset + 3 * kb, gb, m->pair_weight[kb], ab, Cb);
    for (int c = 0; c < 3; ++c) gs[c * n + b] = gb[c];
    for (int q = 0; q < 9; ++q) Cs[q * n + b] = Cb[q];
  }
  for (int a = 0; a < n; ++a) {
    const int32_t ka = begin + a;
    const int moving = !frame_moves || frame_moves[m->pair_frame[ka]];
    if (!moving && !BtDv) continue;
    fascia_real Ca[9], own[54], *BtD = BtDv ? BtDv + 54 * a : own;
    for (int q = 0; q < 9; ++q) Ca[q] = Cs[q * n + a];
    fascia_pt_BtD(Ca, m->pair_gradient + 3 * ka, D, BtD);
    if (!moving) continue;
    for (int row = 0; row < 6; ++row) {
      // blocks (a, b), b >= a, are consecutive; K_ba = K_ab^T (D is
      // symmetric) is not written
      fascia_pt_row_times_pairs(BtD + 9 * row, a, n, gs, Cs, out + 36 * fascia_pt_upper_block(n, a, a) + 6 * row);
    }
    // geometric part on the diagonal block: v (M - tr(M) I), M = C Pt^T
    fascia_real M[9];
    fascia_pt_mat_mult(Ca, P, M);
    const fascia_real trM = fascia_pt_trace(M);
    fascia_real *K = out + 36 * fascia_pt_upper_block(n, a, a);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) K[6 * (3 + r) + 3 + c] += v * (M[3 * r + c] - (r == c ? trM : 0));
  }
}

/// Partial consistent-mass product of sample s with mass ms: velocity of the
/// sample dp = sum_i w (dx_i + dtheta_i x a), then per pair ms w (dp, a x dp).
/// dq, slot and out as in fascia_pt_sample_stiffness.
static inline FASCIA_HD void fascia_pt_sample_mass(const fascia_pt_model *m, const fascia_pt_state *st, int32_t s,
                                                   fascia_real ms, const fascia_real *dq, const int32_t *slot,
                                                   fascia_real *out6) {
  const int32_t begin = m->sample_offsets[s], end = m->sample_offsets[s + 1];
  fascia_real dp[3] = {0, 0, 0};
  for (int32_t k = begin; k < end; ++k) {
    const int32_t i = m->pair_frame[k];
    fascia_real a[3];
    fascia_pt_mat_vec(st->frame_A + 9 * i, m->pair_offset + 3 * k, a);
    const fascia_real *dx = dq + 6 * slot[k - begin], *dt = dx + 3, w = m->pair_weight[k];
    fascia_real ta[3];
    fascia_pt_cross(dt, a, ta);
    for (int r = 0; r < 3; ++r) dp[r] += w * (dx[r] + ta[r]);
  }
  for (int32_t k = begin; k < end; ++k) {
    const int32_t i = m->pair_frame[k];
    fascia_real a[3], *out = out6 + 6 * (k - begin);
    fascia_pt_mat_vec(st->frame_A + 9 * i, m->pair_offset + 3 * k, a);
    const fascia_real mw = ms * m->pair_weight[k];
    fascia_real ad[3];
    fascia_pt_cross(a, dp, ad);
    for (int r = 0; r < 3; ++r) {
      out[r] = mw * dp[r];
      out[3 + r] = mw * ad[r];
    }
  }
}

#endif
