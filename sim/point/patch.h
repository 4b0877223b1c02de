// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Per-patch and per-frame work of mean dilatation over volumetric patches
// (sim/src/cpu/dilatation.h has the energy and its derivatives), written once
// for the CPU (dilatation.c) and the device backend. A patch p holds
// samples; its support entries e are the distinct frames its samples hang
// on. G_e is the gradient of sum_{s in p} v_s theta_s on entry e's frame.
#ifndef FASCIA_POINT_PATCH_H
#define FASCIA_POINT_PATCH_H

#include "sample.h"

/// The patch tables (host or device arrays) and what an evaluation leaves.
typedef struct fascia_pt_patches {
  int32_t count;                       ///< patches
  const int32_t *patch_offsets;        ///< [count+1] CSR into patch_samples
  const int32_t *patch_samples;        ///< samples of each patch, ascending
  const int32_t *support_offsets;      ///< [count+1] CSR of support entries
  const int32_t *entry_frame;          ///< [entries] frame of each entry, ascending per patch
  const int32_t *entry_patch;          ///< [entries]
  const int32_t *pair_entry;           ///< [P] support entry of each pair's frame, -1 outside patches
  const int32_t *frame_entry_offsets;  ///< [N+1] CSR into frame_entries
  const int32_t *frame_entries;        ///< entries of each frame, ascending
  const fascia_real *lambda;           ///< [count] Pa
  const fascia_real *volume;           ///< [count] V_p, m^3
  const int32_t *law;                  ///< [count] FASCIA_PT_LAW_*
  fascia_real *theta;                  ///< [count] mean dilatation thetabar_p
  fascia_real *energy;                 ///< [count] V_p lambda_p / 2 thetabar_p^2, J
  fascia_real *rate;                   ///< [count] lambda_p / V_p G_p . v of the last product
  fascia_real *entry_gradient;         ///< [6 entries] G_e, (x, theta) world
  fascia_real *sample_pressure;        ///< [S] lambda_p thetabar_p on the samples of p (pm.sample_pressure)
  const fascia_real *sample_F;         ///< [9 S] F of the samples of patches at the state, made before the patches'
                                       ///< evaluation (in sample order, so the pairs' data stream), or NULL
} fascia_pt_patches;

/// F of sample s of a patch at the state st: from t->sample_F where it is
/// made, else computed into own (9).
FASCIA_STATIC_FORCE_INLINE FASCIA_HD const fascia_real *
fascia_pt_patch_sample_F(const fascia_pt_model *m, const fascia_pt_state *st, const fascia_pt_patches *t, int32_t s,
                         fascia_real *own) {
  if (t->sample_F) return t->sample_F + 9 * (int64_t)s;
  fascia_pt_sample_F(m, st, s, own);
  return own;
}

/// Patch p at the state st: its mean dilatation, energy and its samples'
/// pressure (what the gradient needs); their F by fascia_pt_patch_sample_F.
FASCIA_STATIC_FORCE_INLINE FASCIA_HD void fascia_pt_patch_evaluate(const fascia_pt_model *m, const fascia_pt_state *st,
                                                      const fascia_pt_patches *t, int32_t p) {
  fascia_real sum = 0;
  for (int32_t q = t->patch_offsets[p]; q < t->patch_offsets[p + 1]; ++q) {
    const int32_t s = t->patch_samples[q];
    fascia_real own[9], dtheta[9];
    const fascia_real *F = fascia_pt_patch_sample_F(m, st, t, s, own);
    sum += m->sample_volume[s] * fascia_pt_dilatation(t->law[p], F, dtheta);
  }
  const fascia_real theta = sum / t->volume[p], pressure = t->lambda[p] * theta;
  t->theta[p] = theta;
  t->energy[p] = FASCIA_R(0.5) * t->volume[p] * pressure * theta;
  for (int32_t q = t->patch_offsets[p]; q < t->patch_offsets[p + 1]; ++q) t->sample_pressure[t->patch_samples[q]] = pressure;
}

/// Patch p at the state st: the gradient G_e of sum_{s in p} v_s theta_s on
/// each support entry's frame (what the Hessian's rank-one term needs); F
/// as in fascia_pt_patch_evaluate, at the same state.
FASCIA_STATIC_FORCE_INLINE FASCIA_HD void fascia_pt_patch_gradient(const fascia_pt_model *m, const fascia_pt_state *st,
                                                      const fascia_pt_patches *t, int32_t p) {
  for (int64_t q = 6 * (int64_t)t->support_offsets[p]; q < 6 * (int64_t)t->support_offsets[p + 1]; ++q)
    t->entry_gradient[q] = 0;
  for (int32_t q = t->patch_offsets[p]; q < t->patch_offsets[p + 1]; ++q) {
    const int32_t s = t->patch_samples[q];
    const fascia_real v = m->sample_volume[s];
    fascia_real own[9], dtheta[9];
    const fascia_real *F = fascia_pt_patch_sample_F(m, st, t, s, own);
    fascia_pt_dilatation(t->law[p], F, dtheta);
    // v grad theta_s on each frame of s: (dtheta g, axial(C dtheta^T)), as the stress gradient
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k) {
      const fascia_real *A = st->frame_A + 9 * (int64_t)m->pair_frame[k], *g = m->pair_gradient + 3 * (int64_t)k;
      fascia_real a[3], C[9], M[9], gx[3], gt[3];
      fascia_pt_pair_C(A, m->pair_offset + 3 * (int64_t)k, g, m->pair_weight[k], a, C);
      fascia_pt_mat_vec(dtheta, g, gx);
      fascia_pt_mat_mult(C, dtheta, M);
      fascia_pt_axial(M, gt);
      fascia_real *G = t->entry_gradient + 6 * (int64_t)t->pair_entry[k];
      for (int r = 0; r < 3; ++r) {
        G[r] += v * gx[r];
        G[3 + r] += v * gt[r];
      }
    }
  }
}

/// The rank-one term's coefficient of patch p for the direction v [6N]:
/// rate_p = lambda_p / V_p G_p . v.
static inline FASCIA_HD void fascia_pt_patch_rate(const fascia_pt_patches *t, int32_t p, const fascia_real *v) {
  fascia_real rate = 0;
  for (int32_t e = t->support_offsets[p]; e < t->support_offsets[p + 1]; ++e) {
    const fascia_real *G = t->entry_gradient + 6 * (int64_t)e, *x = v + 6 * (int64_t)t->entry_frame[e];
    for (int r = 0; r < 6; ++r) rate += G[r] * x[r];
  }
  t->rate[p] = t->lambda[p] / t->volume[p] * rate;
}

/// out += frame i's rows of the rank-one terms: sum over its entries of rate_p G_e.
static inline FASCIA_HD void fascia_pt_patch_frame_add(const fascia_pt_patches *t, int32_t i, fascia_real *out) {
  for (int32_t r = t->frame_entry_offsets[i]; r < t->frame_entry_offsets[i + 1]; ++r) {
    const int32_t e = t->frame_entries[r];
    const fascia_real c = t->rate[t->entry_patch[e]], *G = t->entry_gradient + 6 * (int64_t)e;
    for (int k = 0; k < 6; ++k) out[k] += c * G[k];
  }
}

/// B += frame i's 6x6 diagonal block of the rank-one terms: sum over its
/// entries of lambda_p / V_p G_e G_e^T.
static inline FASCIA_HD void fascia_pt_patch_frame_diagonal_add(const fascia_pt_patches *t, int32_t i,
                                                                fascia_real *B) {
  for (int32_t r = t->frame_entry_offsets[i]; r < t->frame_entry_offsets[i + 1]; ++r) {
    const int32_t e = t->frame_entries[r], p = t->entry_patch[e];
    const fascia_real c = t->lambda[p] / t->volume[p], *G = t->entry_gradient + 6 * (int64_t)e;
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b < 6; ++b) B[6 * a + b] += c * G[a] * G[b];
  }
}

#endif
