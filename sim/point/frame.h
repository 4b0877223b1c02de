// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The per-frame math, shared by the CPU (sim/src/cpu/system.c) and the device
// kernels (the device backend): a frame's sum over its pairs, its orientation
// relative to rest, the gravity and load terms of its gradient and tangent,
// the symmetrizing term of the rotation update, its lumped mass block and
// the weight of its unknowns in the Levenberg shift.
// Written once, so both sides do the same operations in the same order.
#ifndef FASCIA_POINT_FRAME_H
#define FASCIA_POINT_FRAME_H

#include "sample.h"

/// sum[6] = the pair buffer (width 6) over frame i's pairs, in the reverse
/// table's order.
static inline FASCIA_HD void fascia_pt_frame_gather(const int32_t *frame_offsets, const int32_t *frame_pairs,
                                                    const fascia_real *buffer, int32_t i, fascia_real *sum) {
  for (int c = 0; c < 6; ++c) sum[c] = 0;
  for (int32_t r = frame_offsets[i]; r < frame_offsets[i + 1]; ++r) {
    const fascia_real *b = buffer + 6 * (int64_t)frame_pairs[r];
    for (int c = 0; c < 6; ++c) sum[c] += b[c];
  }
}

/// A = R(q) R(q_rest): the frame's rotation since rest.
static inline FASCIA_HD void fascia_pt_frame_A(const fascia_real *q, const fascia_real *q_rest, fascia_real *A) {
  fascia_real R[9], Rr[9];
  fascia_pt_quat_to_mat(q, R);
  fascia_pt_quat_to_mat(q_rest, Rr);
  fascia_pt_mat_mult(R, Rr, A);
}

/// Gravity g and the frame's load (force, torque [6]) at load factor gs on
/// a frame of mass M and mass moment D at x: E = -gs (g.(M x + A D) +
/// f.x). Subtracts the gradient from gi[6] (the torque's too), puts the
/// conservative torque (internal + gravity) in torque[3], returns E (the
/// torque's work is the step's: fascia_pt_frame_step_rotation).
static inline FASCIA_HD fascia_real fascia_pt_frame_external(const fascia_real *A, const fascia_real *moment,
                                                             fascia_real mass, const fascia_real *g, fascia_real gs,
                                                             const fascia_real *x, const fascia_real *load,
                                                             fascia_real *gi, fascia_real *torque) {
  fascia_real b[3], bg[3];
  fascia_pt_mat_vec(A, moment, b);
  fascia_real external = -gs * (mass * fascia_pt_dot3(g, x) + fascia_pt_dot3(g, b));
  external -= gs * fascia_pt_dot3(load, x);
  fascia_pt_cross(b, g, bg);
  for (int c = 0; c < 3; ++c) {
    gi[c] -= gs * (mass * g[c] + load[c]);
    gi[3 + c] -= gs * bg[c];
    torque[c] = gi[3 + c];
    gi[3 + c] -= gs * load[3 + c];
  }
  return external;
}

/// The step objective's part of frame i's gradient gi[6] (the energy's at
/// the state, its load included) and its load's torque tau (load[3..5]) at
/// load factor gs. A dead torque has no potential on the rotations: the
/// step takes its work along the step's own rotation increment d_theta
/// from the anchor (d[3..5]), -gs tau.d_theta, returned, whose gradient
/// with respect to d_theta is -gs tau. With the increments' Jacobian
/// (jacobian: dynamic steps, the gradient with respect to d_theta) the
/// rest of the rotation part becomes J^T g; the torque's stays -gs tau.
static inline FASCIA_HD fascia_real fascia_pt_frame_step_rotation(const fascia_real *load, fascia_real gs,
                                                                   const fascia_real *d, int jacobian,
                                                                   fascia_real *gi) {
  if (jacobian) {
    fascia_real t[3];
    for (int c = 0; c < 3; ++c) t[c] = gi[3 + c] + gs * load[3 + c];
    fascia_pt_left_jacobian_t(d + 3, t, gi + 3);
    for (int c = 0; c < 3; ++c) gi[3 + c] -= gs * load[3 + c];
  }
  return -gs * fascia_pt_dot3(load + 3, d + 3);
}

/// Gravity's own stiffness on a variation v[6], frame-local:
/// out[3..5] -= gs ((v_theta x A D) x g).
static inline FASCIA_HD void fascia_pt_frame_gravity_product(const fascia_real *A, const fascia_real *moment,
                                                             const fascia_real *g, fascia_real gs,
                                                             const fascia_real *v, fascia_real *out) {
  fascia_real b[3], vb[3], vbg[3];
  fascia_pt_mat_vec(A, moment, b);
  fascia_pt_cross(v + 3, b, vb);
  fascia_pt_cross(vb, g, vbg);
  for (int c = 0; c < 3; ++c) out[3 + c] -= gs * vbg[c];
}

/// The end of a frame's row of the Newton operator A v = H v +
/// mass_coefficient M v + shift D v (cg.c's operator, the device's frame
/// operator): out, holding H v, gets the mass term (Mv: this frame's M v;
/// NULL: none) and the Levenberg term (damping: D's 6 entries), and the
/// entries the mask fixes become 0.
static inline FASCIA_HD void fascia_pt_frame_operator_end(fascia_real mass_coefficient, const fascia_real *Mv,
                                                          fascia_real shift, const fascia_real *damping,
                                                          const fascia_real *v, const unsigned char *mask,
                                                          fascia_real *out) {
  if (Mv)
    for (int c = 0; c < 6; ++c) out[c] += mass_coefficient * Mv[c];
  if (shift != 0)
    for (int c = 0; c < 6; ++c) out[c] += shift * damping[c] * v[c];
  for (int c = 0; c < 6; ++c)
    if (!mask[c]) out[c] = 0;
}

/// The symmetrizing term of the rotation update (docs/mechanics.md):
/// out[3..5] += 1/2 torque x v_theta.
static inline FASCIA_HD void fascia_pt_frame_symmetrizing_product(const fascia_real *torque, const fascia_real *v,
                                                                  fascia_real *out) {
  fascia_real t[3];
  fascia_pt_cross(torque, v + 3, t);
  for (int c = 0; c < 3; ++c) out[3 + c] += FASCIA_R(0.5) * t[c];
}

/// Completes a frame's diagonal block B[36] of the tangent from the sum of
/// its pairs' blocks: gravity's theta-theta block -gs (b g^T - (b.g) I) with
/// b = A D, plus the symmetrizing 1/2 [torque]x; then averages the two
/// triangles (the exact tangent is symmetric: away with the rounding).
static inline FASCIA_HD void fascia_pt_frame_diagonal_finish(const fascia_real *A, const fascia_real *moment,
                                                             const fascia_real *g, fascia_real gs,
                                                             const fascia_real *torque, fascia_real *B) {
  fascia_real b[3];
  fascia_pt_mat_vec(A, moment, b);
  const fascia_real bg = fascia_pt_dot3(b, g), *t = torque;
  const fascia_real half_skew[9] = {0, -t[2], t[1], t[2], 0, -t[0], -t[1], t[0], 0};
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c)
      B[6 * (3 + a) + 3 + c] += -gs * (b[a] * g[c] - (a == c ? bg : 0)) + FASCIA_R(0.5) * half_skew[3 * a + c];
  for (int a = 0; a < 6; ++a)
    for (int c = a + 1; c < 6; ++c) {
      const fascia_real avg = FASCIA_R(0.5) * (B[6 * a + c] + B[6 * c + a]);
      B[6 * a + c] = B[6 * c + a] = avg;
    }
}

/// A frame's lumped 6x6 mass block B at orientation A (the mass snapshot):
/// the sum over its pairs of point masses m_k at offsets a_k = A d_k,
///   [m I, -m [a]x; m [a]x, m (|a|^2 I - a a^T)],
/// made from the pairs' rest moments (system.h, frame_lumped_moments:
/// M = sum m_k, D = sum m_k d_k, J = sum m_k (|d_k|^2 I - d_k d_k^T)), since
/// sum m_k a_k = A D and |a_k| = |d_k|: [M I, -[A D]x; [A D]x, A J A^T].
static inline FASCIA_HD void fascia_pt_frame_lumped_mass(const fascia_real *moments, const fascia_real *A,
                                                         fascia_real *B) {
  const fascia_real M = moments[0], *J = moments + 4;
  fascia_real a[3], AJ[9], R[9];
  fascia_pt_mat_vec(A, moments + 1, a);
  fascia_pt_mat_mul(A, J, AJ);
  fascia_pt_mat_mult(AJ, A, R); // A J A^T
  const fascia_real skew[9] = {0, -a[2], a[1], a[2], 0, -a[0], -a[1], a[0], 0};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      B[6 * r + c] = r == c ? M : 0;
      B[6 * r + 3 + c] = -skew[3 * r + c];
      B[6 * (3 + r) + c] = skew[3 * r + c];
      B[6 * (3 + r) + 3 + c] = FASCIA_R(0.5) * (R[3 * r + c] + R[3 * c + r]); // symmetric to rounding: exactly so
    }
}

/// The weight of a frame's unknown c (0-2 translation, 3-5 rotation) in the
/// Levenberg shift (the solver adds shift * weight to the tangent's
/// diagonal), from the absolute diagonal entry and the mean of them all
/// (scale): a rotation weighs its diagonal, a translation only the floor
/// 1e-8 scale that keeps every unknown's weight positive. The frame scheme's
/// tangent is indefinite in the rotations (the frames' geometric stiffness,
/// the symmetrizing torque term, the plane-twist mechanisms), while the
/// translations enter the positions linearly; damping them too slowed Newton
/// to a gradient descent after a large step (the static 20 x 3 x 3
/// cantilever at nu = 0.49: 24 to 95 iterations, 13 with this weight;
/// docs/mechanics.md, "Solvers").
static inline FASCIA_HD fascia_real fascia_pt_levenberg_weight(fascia_real diagonal, int c, fascia_real scale) {
  const fascia_real floor = FASCIA_R(1e-8) * scale;
  return c >= 3 && diagonal > floor ? diagonal : floor;
}

#endif
