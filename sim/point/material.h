// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Hyperelastic laws as functions of the deformation gradient F: energy
// density psi(F), first Piola stress P = dpsi/dF, and its directional
// derivative dP = (dP/dF)[dF]. Per-point, compiled by cc and nvcc.
//
//   StVK (paper eq. 19):  E = (F^T F - I)/2,  S = lambda tr(E) I + 2 mu E,
//                         P = F S,  psi = lambda/2 tr(E)^2 + mu E:E
//   stable Neo-Hookean (Smith, de Goes, Kim 2018, without the origin term):
//                         psi = mu/2 (tr(F^T F) - 3) + l/2 (J - a)^2 - mu^2/(2 l)
//                         (evaluated in H = F - I, free of cancellation),
//                         l = lambda + mu, a = 1 + mu/l,
//                         P = mu F + l (J - a) cof(F).
//   The shift l = lambda + mu makes its small-strain limit the same Hooke law
//   as StVK's; a makes the rest state stress free. It stays smooth through
//   J = 0, so inverted samples get a restoring force instead of a NaN.
#ifndef FASCIA_POINT_MATERIAL_H
#define FASCIA_POINT_MATERIAL_H

#include "linalg.h"

enum { FASCIA_PT_LAW_STVK = 0, FASCIA_PT_LAW_NEOHOOKEAN = 1 };

/// Per-sample values the stress derivative reuses: S (StVK) or cof(F) and J
/// (Neo-Hookean).
#define FASCIA_PT_AUX_SIZE 10

/// The volumetric measure theta of a law, the one its lambda term is built
/// on: psi_lambda = lambda/2 theta^2 with theta = tr E (StVK) or J - 1 (the
/// stable Neo-Hookean; its mu part keeps the rest, docs/mechanics.md). Mean
/// dilatation replaces theta per sample by its average over a patch of
/// samples (sim/src/cpu/dilatation.c). Writes dtheta/dF into dtheta[9].
static inline FASCIA_HD fascia_real fascia_pt_dilatation(int law, const fascia_real *F, fascia_real *dtheta) {
  if (law == FASCIA_PT_LAW_NEOHOOKEAN) {
    fascia_pt_cofactor(F, dtheta);
    // J - 1 written in H = F - I, free of cancellation near rest
    fascia_real H[9];
    for (int k = 0; k < 9; ++k) H[k] = F[k] - (k % 4 == 0);
    const fascia_real trH = H[0] + H[4] + H[8];
    const fascia_real trHH = H[0] * H[0] + H[4] * H[4] + H[8] * H[8] + 2 * (H[1] * H[3] + H[2] * H[6] + H[5] * H[7]);
    return trH + FASCIA_R(0.5) * (trH * trH - trHH) + fascia_pt_det(H);
  }
  for (int k = 0; k < 9; ++k) dtheta[k] = F[k];
  // tr E = (|F|^2 - 3)/2 = tr H + |H|^2/2
  fascia_real trH = 0, HH = 0;
  for (int k = 0; k < 9; ++k) {
    const fascia_real h = F[k] - (k % 4 == 0);
    HH += h * h;
    if (k % 4 == 0) trH += h;
  }
  return trH + FASCIA_R(0.5) * HH;
}

/// out += scale (d^2 theta/dF^2)[dF], the derivative of dtheta/dF along dF.
static inline FASCIA_HD void fascia_pt_dilatation_diff_add(int law, fascia_real scale, const fascia_real *F,
                                                           const fascia_real *dF, fascia_real *out) {
  if (law == FASCIA_PT_LAW_NEOHOOKEAN) {
    // column c of cof(F) is f_{c+1} x f_{c+2}; differentiate each product
    for (int c = 0; c < 3; ++c) {
      const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
      const fascia_real f1[3] = {F[c1], F[3 + c1], F[6 + c1]}, f2[3] = {F[c2], F[3 + c2], F[6 + c2]};
      const fascia_real d1[3] = {dF[c1], dF[3 + c1], dF[6 + c1]}, d2[3] = {dF[c2], dF[3 + c2], dF[6 + c2]};
      fascia_real dc[3];
      fascia_pt_cross(d1, f2, dc);
      fascia_pt_cross_add(f1, d2, dc);
      for (int r = 0; r < 3; ++r) out[3 * r + c] += scale * dc[r];
    }
    return;
  }
  for (int k = 0; k < 9; ++k) out[k] += scale * dF[k];
}

/// Energy density (J/m^3); writes P[9] and aux[FASCIA_PT_AUX_SIZE].
static inline FASCIA_HD fascia_real fascia_pt_stress(int law, fascia_real lambda, fascia_real mu,
                                                     const fascia_real *F, fascia_real *P, fascia_real *aux) {
  if (law == FASCIA_PT_LAW_NEOHOOKEAN) {
    // l = 0 only for the volumetric part of a nu = 0 material: no energy at all
    fascia_real l = lambda + mu, a = l > 0 ? 1 + mu / l : 1;
    fascia_pt_cofactor(F, aux);
    fascia_real J = fascia_pt_det(F);
    aux[9] = J;
    for (int k = 0; k < 9; ++k) P[k] = mu * F[k] + l * (J - a) * aux[k];
    // The same psi written in H = F - I so that no term of size mu cancels
    // near rest (the line search compares energies there):
    //   J - 1 = tr H + I2 + det H,  I2 = ((tr H)^2 - tr(H H))/2,
    //   psi = mu/2 |H|^2 - mu (I2 + det H) + l/2 (J - 1)^2
    fascia_real H[9];
    for (int k = 0; k < 9; ++k) H[k] = F[k] - (k % 4 == 0);
    const fascia_real trH = H[0] + H[4] + H[8];
    const fascia_real trHH = H[0] * H[0] + H[4] * H[4] + H[8] * H[8] + 2 * (H[1] * H[3] + H[2] * H[6] + H[5] * H[7]);
    const fascia_real I2 = FASCIA_R(0.5) * (trH * trH - trHH), detH = fascia_pt_det(H);
    const fascia_real Jm1 = trH + I2 + detH;
    return FASCIA_R(0.5) * mu * fascia_pt_ddot(H, H) - mu * (I2 + detH) + FASCIA_R(0.5) * l * Jm1 * Jm1;
  }
  fascia_real C[9], E[9];
  fascia_pt_mat_tmul(F, F, C);
  for (int k = 0; k < 9; ++k) E[k] = FASCIA_R(0.5) * C[k];
  E[0] -= FASCIA_R(0.5);
  E[4] -= FASCIA_R(0.5);
  E[8] -= FASCIA_R(0.5);
  fascia_real trE = fascia_pt_trace(E);
  for (int k = 0; k < 9; ++k) aux[k] = 2 * mu * E[k];
  aux[0] += lambda * trE;
  aux[4] += lambda * trE;
  aux[8] += lambda * trE;
  aux[9] = 0;
  fascia_pt_mat_mul(F, aux, P);
  return FASCIA_R(0.5) * lambda * trE * trE + mu * fascia_pt_ddot(E, E);
}

/// d^2 theta / dF^2 as a 9x9 matrix (H[9 (3i + j) + 3k + l]): the identity
/// for StVK (theta = tr E), d cof_ij / dF_kl = e_ikn e_jlq F_nq for the
/// Neo-Hookean law (theta = J - 1), e the permutation symbol: what
/// fascia_pt_dilatation_diff_add gives for unit dF, in closed form.
static inline FASCIA_HD void fascia_pt_dilatation_hessian(int law, const fascia_real *F, fascia_real *H) {
  for (int q = 0; q < 81; ++q) H[q] = 0;
  if (law != FASCIA_PT_LAW_NEOHOOKEAN) {
    for (int q = 0; q < 9; ++q) H[10 * q] = 1;
    return;
  }
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      if (i == k) continue;
      const int n = 3 - i - k, ik = k == (i + 1) % 3 ? 1 : -1; // e_ikn
      for (int j = 0; j < 3; ++j)
        for (int jl = 1; jl < 3; ++jl) { // l != j
          const int l = (j + jl) % 3, q = 3 - j - l;
          H[9 * (3 * i + j) + 3 * k + l] = (jl == 1 ? ik : -ik) * F[3 * n + q];
        }
    }
}

/// D = dP/dF + pressure d^2 theta/dF^2 as a 9x9 matrix (D[9 (3i + j) + 3k
/// + l] = dP_ij / dF_kl), aux from fascia_pt_stress at the same F: the
/// nine columns fascia_pt_stress_diff and fascia_pt_dilatation_diff_add
/// give for unit dF, in closed form, at about a fifth of their work.
///   StVK:        S_lj [i = k] + lambda F_ij F_kl + mu ((F F^T)_ik [j = l] + F_il F_kj)
///                + pressure [i = k][j = l]
///   Neo-Hookean: mu [i = k][j = l] + l cof_ij cof_kl + (l (J - a) + pressure) e_ikn e_jlq F_nq
/// (d cof_ij / dF_kl = e_ikn e_jlq F_nq, e the permutation symbol).
static inline FASCIA_HD void fascia_pt_stress_tangent(int law, fascia_real lambda, fascia_real mu, fascia_real pressure,
                                                      const fascia_real *F, const fascia_real *aux, fascia_real *D) {
  if (law == FASCIA_PT_LAW_NEOHOOKEAN) {
    const fascia_real l = lambda + mu, a = l > 0 ? 1 + mu / l : 1, s = l * (aux[9] - a) + pressure;
    fascia_real dcof[81];
    fascia_pt_dilatation_hessian(law, F, dcof);
    for (int ij = 0; ij < 9; ++ij)
      for (int kl = 0; kl < 9; ++kl) D[9 * ij + kl] = l * aux[ij] * aux[kl] + (ij == kl ? mu : 0) + s * dcof[9 * ij + kl];
    return;
  }
  fascia_real B[9]; // F F^T
  fascia_pt_mat_mult(F, F, B);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) {
          fascia_real d = lambda * F[3 * i + j] * F[3 * k + l] + mu * F[3 * i + l] * F[3 * k + j];
          if (j == l) d += mu * B[3 * i + k];
          if (i == k) d += aux[3 * l + j] + (j == l ? pressure : 0);
          D[9 * (3 * i + j) + 3 * k + l] = d;
        }
}

/// dP = (dP/dF)[dF], with aux from fascia_pt_stress at the same F.
static inline FASCIA_HD void fascia_pt_stress_diff(int law, fascia_real lambda, fascia_real mu, const fascia_real *F,
                                                   const fascia_real *aux, const fascia_real *dF, fascia_real *dP) {
  if (law == FASCIA_PT_LAW_NEOHOOKEAN) {
    // l = 0 only for the volumetric part of a nu = 0 material: no energy at all
    fascia_real l = lambda + mu, a = l > 0 ? 1 + mu / l : 1;
    const fascia_real dJ = fascia_pt_ddot(aux, dF);
    for (int k = 0; k < 9; ++k) dP[k] = mu * dF[k] + l * dJ * aux[k];
    fascia_pt_dilatation_diff_add(law, l * (aux[9] - a), F, dF, dP); // + l (J - a) d cof(F)
    return;
  }
  fascia_real FtdF[9], dS[9];
  fascia_pt_mat_tmul(F, dF, FtdF);
  fascia_real trdE = fascia_pt_trace(FtdF);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) dS[3 * r + c] = mu * (FtdF[3 * r + c] + FtdF[3 * c + r]);
  dS[0] += lambda * trdE;
  dS[4] += lambda * trdE;
  dS[8] += lambda * trdE;
  fascia_real t1[9], t2[9];
  fascia_pt_mat_mul(dF, aux, t1);
  fascia_pt_mat_mul(F, dS, t2);
  for (int k = 0; k < 9; ++k) dP[k] = t1[k] + t2[k];
}

#endif
