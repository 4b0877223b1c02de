// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Rigid organs as a reduction of the Newton operator, written once for every
// backend (the CPU's loops in sim/src/, the device's kernels): the math of
// one frame or one body. The design (sim/src/organs/organs.c, docs/organs.md): a
// rigid organ's coupling frames follow its master frame m, whose state is
// the body's pose; a slave i at rest offset r_i from the master sits at
//
//     x_i = x_m + Q r_i,  q_i = Q q_i,rest,   Q = q_m conj(q_m,rest),
//
// so the Newton unknowns of a slave are its master's, through
//
//     increment of slave i = T(a_i) (dx_m, dtheta_m),  T(a) = [[I, -[a]x], [0, I]],
//
// a_i = x_i - x_m its current offset (exact, nonlinear in the rotation, when
// increments are expanded; linear in the operator). A backend applies the
// reduced operator P^T A P as: prolong (w = P v, frame by frame), its own
// operator on all frames, restrict (per body: the slaves' T^T y folded
// into the master), plus the body's own terms: its mass and inertia through
// its centre, its gravity, and the geometric term of the rotating offsets.
#ifndef FASCIA_POINT_BODY_H
#define FASCIA_POINT_BODY_H

#include "linalg.h"

/// The rigid organs of a model, indexed by organ (a body is a rigid organ
/// with coupling frames). The first group is fixed for a solver; active,
/// world_inertia and target change per step; geometric is written by the
/// gradient and read by the operator.
typedef struct fascia_pt_bodies {
  int32_t count;                    ///< organs
  const int32_t *frame_offsets;     ///< [count + 1] each organ's coupling frames in frames
  const int32_t *frames;            ///< a body's master among its frames
  const int32_t *frame_body;        ///< [N] the rigid organ whose body carries frame i, -1 for none
  const int32_t *master;            ///< [count] master frame, -1 for no body
  const fascia_real *rest_position; ///< [3N] the frames at rest
  const fascia_real *rest_rotation; ///< [4N]
  const fascia_real *centre;        ///< [3 count] rest centre of mass
  const fascia_real *mass;          ///< [count] kg
  const unsigned char *active;      ///< [count] 1: a body the solver moves now (not driven by the caller)
  const fascia_real *world_inertia; ///< [9 count] inertia at the step's start, world axes
  const fascia_real *target;        ///< [6 count] h v at the step's start
  fascia_real *geometric;           ///< [9 count] rotation block of the reduced Hessian, from the last gradient
} fascia_pt_bodies;

/// The values of the step objective a body's gradient needs.
typedef struct fascia_pt_body_step {
  fascia_real c1, c2;        ///< inertia 1/h^2 and mass damping alpha/h (0: static)
  fascia_real gravity_scale; ///< load factor
  int32_t jacobian;          ///< 1: increments anchored at the step's start (dynamic)
  fascia_real gravity[3];
} fascia_pt_body_step;

/// Body b's rotation Q = q_m conj(q_m,rest) (and its matrix, R may be NULL)
/// from the frame rotations q.
static inline FASCIA_HD void fascia_pt_body_rotation(const fascia_pt_bodies *B, int32_t b, const fascia_real *q,
                                                     fascia_real *Q, fascia_real *R) {
  const int32_t m = B->master[b];
  const fascia_real *qr = B->rest_rotation + 4 * (int64_t)m;
  const fascia_real conj[4] = {qr[0], -qr[1], -qr[2], -qr[3]};
  fascia_pt_quat_mul(q + 4 * (int64_t)m, conj, Q);
  fascia_pt_quat_normalize(Q);
  if (R) fascia_pt_quat_to_mat(Q, R);
}

/// Rest offset of frame i (the centre when i < 0) from body b's master.
static inline FASCIA_HD void fascia_pt_body_rest_offset(const fascia_pt_bodies *B, int32_t b, int32_t i,
                                                        fascia_real *r) {
  const fascia_real *xm = B->rest_position + 3 * (int64_t)B->master[b];
  const fascia_real *p = i < 0 ? B->centre + 3 * (int64_t)b : B->rest_position + 3 * (int64_t)i;
  for (int c = 0; c < 3; ++c) r[c] = p[c] - xm[c];
}

/// The body whose slave frame i is now (a frame of an active body other
/// than its master), -1 for none.
static inline FASCIA_HD int32_t fascia_pt_body_of_slave(const fascia_pt_bodies *B, int32_t i) {
  const int32_t b = B->count > 0 ? B->frame_body[i] : -1;
  return b >= 0 && B->active[b] && B->master[b] != i ? b : -1;
}

/// Offset a = x_i - x_m of frame i from body b's master at positions x.
static inline FASCIA_HD void fascia_pt_body_offset(const fascia_pt_bodies *B, int32_t b, int32_t i,
                                                   const fascia_real *x, fascia_real *a) {
  const int64_t m = B->master[b];
  for (int c = 0; c < 3; ++c) a[c] = x[3 * (int64_t)i + c] - x[3 * m + c];
}

/// Centre of body b from its master: a_c = Q r_c, at rotations q.
static inline FASCIA_HD void fascia_pt_body_centre_offset(const fascia_pt_bodies *B, int32_t b, const fascia_real *q,
                                                          fascia_real *ac) {
  fascia_real Q[4], R[9], r[3];
  fascia_pt_body_rotation(B, b, q, Q, R);
  fascia_pt_body_rest_offset(B, b, -1, r);
  fascia_pt_mat_vec(R, r, ac);
}

/// Expansion of the increments d [6N] for frame i: a slave's increment is
/// rebuilt, exactly, from its master's (anchor x_base, q_base); every other
/// frame keeps its own.
static inline FASCIA_HD void fascia_pt_body_expand(const fascia_pt_bodies *B, int32_t i, const fascia_real *x_base,
                                                   const fascia_real *q_base, fascia_real *d) {
  const int32_t b = fascia_pt_body_of_slave(B, i);
  if (b < 0) return;
  const int64_t m = B->master[b];
  fascia_real Q0[4], Q[4], t[4], R[9], r[3], a[3];
  fascia_pt_body_rotation(B, b, q_base, Q0, NULL);
  fascia_pt_quat_exp(d + 6 * m + 3, Q);
  fascia_pt_quat_mul(Q, Q0, t);
  fascia_pt_quat_normalize(t);
  fascia_pt_quat_to_mat(t, R);
  fascia_pt_body_rest_offset(B, b, i, r);
  fascia_pt_mat_vec(R, r, a);
  for (int c = 0; c < 3; ++c) {
    d[6 * (int64_t)i + c] = x_base[3 * m + c] + d[6 * m + c] + a[c] - x_base[3 * (int64_t)i + c];
    d[6 * (int64_t)i + 3 + c] = d[6 * m + 3 + c];
  }
}

/// w = T(a) v: (v_x - a x v_theta, v_theta).
static inline FASCIA_HD void fascia_pt_body_prolong6(const fascia_real *a, const fascia_real *v, fascia_real *w) {
  fascia_real av[3];
  fascia_pt_cross(a, v + 3, av);
  for (int c = 0; c < 3; ++c) w[c] = v[c] - av[c], w[3 + c] = v[3 + c];
}

/// Frame i's entries of w = P v [6N] at positions x: a slave's from its
/// master's, every other frame's its own.
static inline FASCIA_HD void fascia_pt_body_prolong(const fascia_pt_bodies *B, int32_t i, const fascia_real *x,
                                                    const fascia_real *v, fascia_real *w) {
  const int32_t b = fascia_pt_body_of_slave(B, i);
  if (b < 0) {
    for (int c = 0; c < 6; ++c) w[6 * (int64_t)i + c] = v[6 * (int64_t)i + c];
    return;
  }
  fascia_real a[3];
  fascia_pt_body_offset(B, b, i, x, a);
  fascia_pt_body_prolong6(a, v + 6 * (int64_t)B->master[b], w + 6 * (int64_t)i);
}

/// T(a)^T y added to a master's sums: force gx, moment mom (kept apart so
/// that the caller can apply the rotation map's Jacobian) and torque gt.
static inline FASCIA_HD void fascia_pt_body_restrict_add(const fascia_real *a, const fascia_real *y, fascia_real *gx,
                                                         fascia_real *mom, fascia_real *gt) {
  fascia_real ay[3];
  fascia_pt_cross(a, y, ay);
  for (int c = 0; c < 3; ++c) gx[c] += y[c], mom[c] += ay[c], gt[c] += y[3 + c];
}

/// G += sym(g a^T) - (g.a) I: the second derivative of g.x under a
/// rotation of the offset a.
static inline FASCIA_HD void fascia_pt_body_geometric_add(const fascia_real *g, const fascia_real *a, fascia_real *G) {
  const fascia_real ga = fascia_pt_dot3(g, a);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) G[3 * r + c] += FASCIA_R(0.5) * (g[r] * a[c] + a[r] * g[c]) - (r == c) * ga;
}

/// out = T(a)^T M T(b) for a 6x6 block M: the block between frames at
/// offsets a and b on bodies, in their masters' unknowns.
static inline FASCIA_HD void fascia_pt_body_transform_block(const fascia_real *M, const fascia_real *a,
                                                            const fascia_real *b, fascia_real *out) {
  fascia_real Ta[36], Tb[36], MT[36];
  const fascia_real *offset[2] = {a, b};
  fascia_real *T[2] = {Ta, Tb};
  for (int t = 0; t < 2; ++t) {
    const fascia_real *o = offset[t];
    for (int k = 0; k < 36; ++k) T[t][k] = 0;
    for (int c = 0; c < 6; ++c) T[t][7 * c] = 1;
    // -[o]x in the upper right block
    T[t][0 * 6 + 4] = o[2], T[t][0 * 6 + 5] = -o[1];
    T[t][1 * 6 + 3] = -o[2], T[t][1 * 6 + 5] = o[0];
    T[t][2 * 6 + 3] = o[1], T[t][2 * 6 + 4] = -o[0];
  }
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) {
      fascia_real sum = 0;
      for (int k = 0; k < 6; ++k) sum += M[6 * r + k] * Tb[6 * k + c];
      MT[6 * r + c] = sum;
    }
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) {
      fascia_real sum = 0;
      for (int k = 0; k < 6; ++k) sum += Ta[6 * k + r] * MT[6 * k + c];
      out[6 * r + c] = sum;
    }
}

/// Folds body b's slaves' entries of y [6N] (at positions x) into its
/// master's sums (fascia_pt_body_restrict_add) and zeroes them; with G, adds
/// each slave's geometric term too.
static inline FASCIA_HD void fascia_pt_body_fold(const fascia_pt_bodies *B, int32_t b, const fascia_real *x,
                                                 fascia_real *y, fascia_real *gx, fascia_real *mom, fascia_real *gt,
                                                 fascia_real *G) {
  const int32_t m = B->master[b];
  for (int32_t f = B->frame_offsets[b]; f < B->frame_offsets[b + 1]; ++f) {
    const int32_t i = B->frames[f];
    if (i == m) continue;
    fascia_real a[3], *yi = y + 6 * (int64_t)i;
    fascia_pt_body_offset(B, b, i, x, a);
    fascia_pt_body_restrict_add(a, yi, gx, mom, gt);
    if (G) fascia_pt_body_geometric_add(yi, a, G);
    for (int c = 0; c < 6; ++c) yi[c] = 0;
  }
}

/// Body b's own block in its master's unknowns at rotations q: mass and
/// inertia (times mass_coefficient) through its centre, plus the geometric
/// term of the last gradient.
static inline FASCIA_HD void fascia_pt_body_own_block(const fascia_pt_bodies *B, int32_t b,
                                                      fascia_real mass_coefficient, const fascia_real *q,
                                                      fascia_real *out) {
  fascia_real ac[3], M[36];
  fascia_pt_body_centre_offset(B, b, q, ac);
  for (int k = 0; k < 36; ++k) M[k] = 0;
  for (int c = 0; c < 3; ++c) M[7 * c] = mass_coefficient * B->mass[b];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) M[6 * (3 + r) + 3 + c] = mass_coefficient * B->world_inertia[9 * b + 3 * r + c];
  fascia_pt_body_transform_block(M, ac, ac, out);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out[6 * (3 + r) + 3 + c] += B->geometric[9 * b + 3 * r + c];
}

/// Increment of body b's centre over the step: x_m + Q r_c - (x_m + Q r_c) at the anchor.
static inline FASCIA_HD void fascia_pt_body_centre_increment(const fascia_pt_bodies *B, int32_t b,
                                                             const fascia_real *x, const fascia_real *q,
                                                             const fascia_real *x_base, const fascia_real *q_base,
                                                             fascia_real *dc) {
  const int64_t m = B->master[b];
  fascia_real a[3], a0[3];
  fascia_pt_body_centre_offset(B, b, q, a);
  fascia_pt_body_centre_offset(B, b, q_base, a0);
  for (int c = 0; c < 3; ++c) dc[c] = x[3 * m + c] + a[c] - x_base[3 * m + c] - a0[c];
}

/// Body b in the step objective at state x, q (increments d from the anchor
/// x_base, q_base): returns its energy (gravity, inertia, mass damping);
/// with a gradient [6N] (the full one of every frame), folds its slaves'
/// entries into the master's (zeroing theirs), adds the body's own, and
/// keeps the geometric term for the operator.
static inline FASCIA_HD fascia_real fascia_pt_body_gradient(const fascia_pt_bodies *B, int32_t b,
                                                            const fascia_pt_body_step *step, const fascia_real *x,
                                                            const fascia_real *q, const fascia_real *x_base,
                                                            const fascia_real *q_base, const fascia_real *d,
                                                            fascia_real *gradient) {
  const int32_t m = B->master[b];
  const fascia_real s = step->gravity_scale, mass = B->mass[b];
  const fascia_real *Iw = B->world_inertia + 9 * (int64_t)b, *t = B->target + 6 * (int64_t)b;
  const fascia_real *phi = d + 6 * (int64_t)m + 3, *gravity = step->gravity;
  fascia_real ac[3], dc[3], cpos[3];
  fascia_pt_body_centre_offset(B, b, q, ac);
  fascia_pt_body_centre_increment(B, b, x, q, x_base, q_base, dc);
  for (int c = 0; c < 3; ++c) cpos[c] = x[3 * (int64_t)m + c] + ac[c];
  fascia_real e[3], p[3], Ie[3], Ip[3];
  for (int c = 0; c < 3; ++c) e[c] = dc[c] - t[c], p[c] = phi[c] - t[3 + c];
  fascia_pt_mat_vec(Iw, p, Ie);
  fascia_pt_mat_vec(Iw, phi, Ip);
  const fascia_real energy = -s * mass * fascia_pt_dot3(gravity, cpos) +
                             FASCIA_R(0.5) * step->c1 * (mass * fascia_pt_dot3(e, e) + fascia_pt_dot3(p, Ie)) +
                             FASCIA_R(0.5) * step->c2 * (mass * fascia_pt_dot3(dc, dc) + fascia_pt_dot3(phi, Ip));
  if (!gradient) return energy;
  fascia_real y[6], gx[3] = {0, 0, 0}, mom[3] = {0, 0, 0}, gt[3] = {0, 0, 0};
  fascia_real *G = B->geometric + 9 * (int64_t)b;
  for (int c = 0; c < 3; ++c) {
    y[c] = -s * mass * gravity[c] + step->c1 * mass * e[c] + step->c2 * mass * dc[c];
    y[3 + c] = step->c1 * Ie[c] + step->c2 * Ip[c];
  }
  for (int k = 0; k < 9; ++k) G[k] = 0;
  fascia_pt_body_restrict_add(ac, y, gx, mom, gt);
  fascia_pt_body_geometric_add(y, ac, G);
  fascia_pt_body_fold(B, b, x, gradient, gx, mom, gt, G);
  fascia_real jm[3];
  if (step->jacobian) fascia_pt_left_jacobian_t(phi, mom, jm);
  else
    for (int c = 0; c < 3; ++c) jm[c] = mom[c];
  for (int c = 0; c < 3; ++c)
    gradient[6 * (int64_t)m + c] += gx[c], gradient[6 * (int64_t)m + 3 + c] += jm[c] + gt[c];
  return energy;
}

/// The restriction of the operator for body b: out [6N] holds A w on every
/// frame (w = P v); folds the slaves' entries into the master's (zeroing
/// theirs) and adds the body's mass, inertia and geometric terms of v.
static inline FASCIA_HD void fascia_pt_body_restrict(const fascia_pt_bodies *B, int32_t b, fascia_real mass_coefficient,
                                                     const fascia_real *x, const fascia_real *q, const fascia_real *v,
                                                     fascia_real *out) {
  const int32_t m = B->master[b];
  const fascia_real *vm = v + 6 * (int64_t)m;
  fascia_real gx[3] = {0, 0, 0}, mom[3] = {0, 0, 0}, gt[3] = {0, 0, 0};
  fascia_pt_body_fold(B, b, x, out, gx, mom, gt, NULL);
  fascia_real ac[3], wc[6], yc[6], Gv[3];
  fascia_pt_body_centre_offset(B, b, q, ac);
  fascia_pt_body_prolong6(ac, vm, wc);
  for (int c = 0; c < 3; ++c) yc[c] = mass_coefficient * B->mass[b] * wc[c];
  fascia_pt_mat_vec(B->world_inertia + 9 * (int64_t)b, wc + 3, yc + 3);
  for (int c = 0; c < 3; ++c) yc[3 + c] *= mass_coefficient;
  fascia_pt_body_restrict_add(ac, yc, gx, mom, gt);
  fascia_pt_mat_vec(B->geometric + 9 * (int64_t)b, vm + 3, Gv);
  for (int c = 0; c < 3; ++c)
    out[6 * (int64_t)m + c] += gx[c], out[6 * (int64_t)m + 3 + c] += mom[c] + gt[c] + Gv[c];
}

/// Body b's diagonal block of the reduced operator, for the preconditioner:
/// blocks [36N] hold the diagonal blocks of every frame; the master's
/// becomes its own plus T^T B_i T of each slave and the body's own block.
static inline FASCIA_HD void fascia_pt_body_diagonal(const fascia_pt_bodies *B, int32_t b,
                                                     fascia_real mass_coefficient, const fascia_real *x,
                                                     const fascia_real *q, fascia_real *blocks) {
  const int32_t m = B->master[b];
  fascia_real *Bm = blocks + 36 * (int64_t)m, T[36];
  for (int32_t f = B->frame_offsets[b]; f < B->frame_offsets[b + 1]; ++f) {
    const int32_t i = B->frames[f];
    if (i == m) continue;
    fascia_real a[3];
    fascia_pt_body_offset(B, b, i, x, a);
    fascia_pt_body_transform_block(blocks + 36 * (int64_t)i, a, a, T);
    for (int k = 0; k < 36; ++k) Bm[k] += T[k];
  }
  fascia_pt_body_own_block(B, b, mass_coefficient, q, T);
  for (int k = 0; k < 36; ++k) Bm[k] += T[k];
}

#endif
