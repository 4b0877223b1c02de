// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Small fixed-size algebra for the per-point math: 3-vectors, 3x3 matrices
// (row-major, m[3*row + col]), unit quaternions (w, x, y, z). Pure functions,
// compiled by cc and nvcc alike.
#ifndef FASCIA_POINT_LINALG_H
#define FASCIA_POINT_LINALG_H

#include "hd.h"

static inline FASCIA_HD fascia_real fascia_pt_dot3(const fascia_real *a, const fascia_real *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/// out = a x b (out may not alias a or b)
static inline FASCIA_HD void fascia_pt_cross(const fascia_real *a, const fascia_real *b, fascia_real *out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

/// out += a x b
static inline FASCIA_HD void fascia_pt_cross_add(const fascia_real *a, const fascia_real *b, fascia_real *out) {
  out[0] += a[1] * b[2] - a[2] * b[1];
  out[1] += a[2] * b[0] - a[0] * b[2];
  out[2] += a[0] * b[1] - a[1] * b[0];
}

/// out = m v
static inline FASCIA_HD void fascia_pt_mat_vec(const fascia_real *m, const fascia_real *v, fascia_real *out) {
  for (int r = 0; r < 3; ++r) out[r] = m[3 * r] * v[0] + m[3 * r + 1] * v[1] + m[3 * r + 2] * v[2];
}

/// out = m^T v
static inline FASCIA_HD void fascia_pt_mat_tvec(const fascia_real *m, const fascia_real *v, fascia_real *out) {
  for (int c = 0; c < 3; ++c) out[c] = m[c] * v[0] + m[3 + c] * v[1] + m[6 + c] * v[2];
}

/// out = a b
static inline FASCIA_HD void fascia_pt_mat_mul(const fascia_real *a, const fascia_real *b, fascia_real *out) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      out[3 * r + c] = a[3 * r] * b[c] + a[3 * r + 1] * b[3 + c] + a[3 * r + 2] * b[6 + c];
}

/// out = a^T b
static inline FASCIA_HD void fascia_pt_mat_tmul(const fascia_real *a, const fascia_real *b, fascia_real *out) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out[3 * r + c] = a[r] * b[c] + a[3 + r] * b[3 + c] + a[6 + r] * b[6 + c];
}

/// out = a b^T
static inline FASCIA_HD void fascia_pt_mat_mult(const fascia_real *a, const fascia_real *b, fascia_real *out) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      out[3 * r + c] = a[3 * r] * b[3 * c] + a[3 * r + 1] * b[3 * c + 1] + a[3 * r + 2] * b[3 * c + 2];
}

static inline FASCIA_HD fascia_real fascia_pt_trace(const fascia_real *m) { return m[0] + m[4] + m[8]; }

/// a : b
static inline FASCIA_HD fascia_real fascia_pt_ddot(const fascia_real *a, const fascia_real *b) {
  fascia_real s = 0;
  for (int k = 0; k < 9; ++k) s += a[k] * b[k];
  return s;
}

static inline FASCIA_HD fascia_real fascia_pt_det(const fascia_real *m) {
  return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
         m[2] * (m[3] * m[7] - m[4] * m[6]);
}

/// Cofactor matrix dJ/dF: columns are f1 x f2, f2 x f0, f0 x f1 for columns
/// f0, f1, f2 of m. Defined for every m, singular or inverted.
static inline FASCIA_HD void fascia_pt_cofactor(const fascia_real *m, fascia_real *out) {
  out[0] = m[4] * m[8] - m[5] * m[7];
  out[1] = m[5] * m[6] - m[3] * m[8];
  out[2] = m[3] * m[7] - m[4] * m[6];
  out[3] = m[2] * m[7] - m[1] * m[8];
  out[4] = m[0] * m[8] - m[2] * m[6];
  out[5] = m[1] * m[6] - m[0] * m[7];
  out[6] = m[1] * m[5] - m[2] * m[4];
  out[7] = m[2] * m[3] - m[0] * m[5];
  out[8] = m[0] * m[4] - m[1] * m[3];
}

/// Axial vector of the antisymmetric part: tr([t]x m) = t . axial(m), i.e.
/// axial(m) = (m12 - m21, m20 - m02, m01 - m10); axial(u v^T) = u x v.
static inline FASCIA_HD void fascia_pt_axial(const fascia_real *m, fascia_real *out) {
  out[0] = m[5] - m[7];
  out[1] = m[6] - m[2];
  out[2] = m[1] - m[3];
}

/// out = [t]x m  (column k of out is t x column k of m)
static inline FASCIA_HD void fascia_pt_skew_mul(const fascia_real *t, const fascia_real *m, fascia_real *out) {
  for (int c = 0; c < 3; ++c) {
    out[c] = t[1] * m[6 + c] - t[2] * m[3 + c];
    out[3 + c] = t[2] * m[c] - t[0] * m[6 + c];
    out[6 + c] = t[0] * m[3 + c] - t[1] * m[c];
  }
}

/// Rotation matrix of a unit quaternion q = (w, x, y, z).
static inline FASCIA_HD void fascia_pt_quat_to_mat(const fascia_real *q, fascia_real *m) {
  fascia_real w = q[0], x = q[1], y = q[2], z = q[3];
  m[0] = 1 - 2 * (y * y + z * z);
  m[1] = 2 * (x * y - w * z);
  m[2] = 2 * (x * z + w * y);
  m[3] = 2 * (x * y + w * z);
  m[4] = 1 - 2 * (x * x + z * z);
  m[5] = 2 * (y * z - w * x);
  m[6] = 2 * (x * z - w * y);
  m[7] = 2 * (y * z + w * x);
  m[8] = 1 - 2 * (x * x + y * y);
}

/// out = a b (Hamilton product; the rotation of out is rot(a) rot(b)).
static inline FASCIA_HD void fascia_pt_quat_mul(const fascia_real *a, const fascia_real *b, fascia_real *out) {
  out[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
  out[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
  out[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
  out[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

/// Quaternion of the rotation by angle |t| about t (exponential map).
static inline FASCIA_HD void fascia_pt_quat_exp(const fascia_real *t, fascia_real *q) {
  fascia_real angle = sqrt(fascia_pt_dot3(t, t));
  fascia_real half = FASCIA_R(0.5) * angle;
  // sin(half)/angle, with its series near 0 so tiny rotations stay exact
  fascia_real s = angle > FASCIA_R(1e-8) ? sin(half) / angle : FASCIA_R(0.5) - angle * angle / FASCIA_R(48.0);
  q[0] = cos(half);
  q[1] = s * t[0];
  q[2] = s * t[1];
  q[3] = s * t[2];
}

/// Rotation vector of a unit quaternion (inverse of fascia_pt_quat_exp, angle
/// in [0, pi]).
static inline FASCIA_HD void fascia_pt_quat_log(const fascia_real *q, fascia_real *t) {
  fascia_real w = q[0], sign = w < 0 ? FASCIA_R(-1.0) : FASCIA_R(1.0);
  fascia_real v = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  fascia_real angle = 2 * atan2(v, w * sign);
  fascia_real s = v > FASCIA_R(1e-12) ? angle / v : FASCIA_R(2.0);
  t[0] = sign * s * q[1];
  t[1] = sign * s * q[2];
  t[2] = sign * s * q[3];
}

static inline FASCIA_HD void fascia_pt_quat_normalize(fascia_real *q) {
  fascia_real n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (int k = 0; k < 4; ++k) q[k] /= n;
}

/// q <- exp(t) q : rotates frame rotation q by the world-space angle t (the
/// solver's rotation update, docs/mechanics.md).
static inline FASCIA_HD void fascia_pt_quat_rotate_by(const fascia_real *t, fascia_real *q) {
  fascia_real e[4], r[4];
  fascia_pt_quat_exp(t, e);
  fascia_pt_quat_mul(e, q, r);
  fascia_pt_quat_normalize(r);
  for (int k = 0; k < 4; ++k) q[k] = r[k];
}

/// J_l(phi)^T g: the left Jacobian of the exponential map, transposed (the
/// gradient with respect to increments phi anchored at a rotation, from the
/// gradient with respect to a world-space rotation at exp(phi) R).
static inline FASCIA_HD void fascia_pt_left_jacobian_t(const fascia_real *phi, const fascia_real *g, fascia_real *out) {
  const fascia_real t2 = fascia_pt_dot3(phi, phi), t = sqrt(t2);
  fascia_real a, b;
  if (t < 1e-4) { // series: exact to rounding for small angles
    a = FASCIA_R(0.5) - t2 / 24;
    b = FASCIA_R(1.0) / 6 - t2 / 120;
  } else {
    a = (1 - cos(t)) / t2;
    b = (t - sin(t)) / (t2 * t);
  }
  fascia_real pg[3], ppg[3];
  fascia_pt_cross(phi, g, pg);
  fascia_pt_cross(phi, pg, ppg);
  for (int c = 0; c < 3; ++c) out[c] = g[c] - a * pg[c] + b * ppg[c];
}

/// J_l(phi)^-1 v, or J_l(phi)^-T v where transpose is set: the inverse of
/// the left Jacobian above (a world-space rotation increment at exp(phi) R
/// as an increment of phi, and a gradient back).
static inline FASCIA_HD void fascia_pt_left_jacobian_inv(const fascia_real *phi, const fascia_real *v, int transpose,
                                                         fascia_real *out) {
  const fascia_real t2 = fascia_pt_dot3(phi, phi), t = sqrt(t2);
  fascia_real c;
  if (t < 1e-3) // series: exact to rounding for small angles
    c = FASCIA_R(1.0) / 12 + t2 / 720;
  else
    c = 1 / t2 - (1 + cos(t)) / (2 * t * sin(t));
  const fascia_real half = transpose ? FASCIA_R(0.5) : FASCIA_R(-0.5);
  fascia_real pv[3], ppv[3];
  fascia_pt_cross(phi, v, pv);
  fascia_pt_cross(phi, pv, ppv);
  for (int k = 0; k < 3; ++k) out[k] = v[k] + half * pv[k] + c * ppv[k];
}

/// The dynamic Newton step's change of coordinates for one frame (6 values
/// v, its increments d, its mask): the tangent is the energy's for
/// world-space rotation increments at the iterate, so the right-hand side
/// goes there (inverse = 0: J_l(d)^-T on the rotation) and the step comes
/// back to increments of d (inverse = 1: J_l(d)^-1). A frame with a rotation
/// held (masked) keeps the identity.
static inline FASCIA_HD void fascia_pt_step_rotation_map(const fascia_real *d, const unsigned char *mask, int back,
                                                         fascia_real *v) {
  if (!mask[3] || !mask[4] || !mask[5]) return;
  const fascia_real r[3] = {v[3], v[4], v[5]};
  fascia_pt_left_jacobian_inv(d + 3, r, !back, v + 3);
}

/// Cholesky factor of an n x n matrix in place (row-major, lower triangle
/// written); 0 if it is not positive definite.
static inline FASCIA_HD int fascia_pt_cholesky(fascia_real *a, int n) {
  for (int j = 0; j < n; ++j) {
    fascia_real d = a[n * j + j];
    for (int k = 0; k < j; ++k) d -= a[n * j + k] * a[n * j + k];
    if (!(d > 0)) return 0;
    d = sqrt(d);
    a[n * j + j] = d;
    for (int i = j + 1; i < n; ++i) {
      fascia_real s = a[n * i + j];
      for (int k = 0; k < j; ++k) s -= a[n * i + k] * a[n * j + k];
      a[n * i + j] = s / d;
    }
  }
  return 1;
}

/// Inverse of an SPD n x n matrix from its Cholesky factor L: solves L L^T X = I.
static inline FASCIA_HD void fascia_pt_cholesky_inverse(const fascia_real *L, int n, fascia_real *inv) {
  for (int col = 0; col < n; ++col) {
    fascia_real y[16]; // n <= 16
    for (int i = 0; i < n; ++i) {
      fascia_real s = (i == col);
      for (int k = 0; k < i; ++k) s -= L[n * i + k] * y[k];
      y[i] = s / L[n * i + i];
    }
    for (int i = n - 1; i >= 0; --i) {
      fascia_real s = y[i];
      for (int k = i + 1; k < n; ++k) s -= L[n * k + i] * inv[n * k + col];
      inv[n * i + col] = s / L[n * i + i];
    }
  }
}

#endif
