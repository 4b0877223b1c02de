// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Organ models in the solver (docs/organs.md, paper sec. 4.2 "coupling
// with a rigid object": the frames of the tissue that lie on the rigid
// surface have a rigid motion with respect to the body), and the C API of
// fascia/organs.h for an outside simulator.
//
// Design note: rigid organs by elimination of the slave DOFs.
//
//   A rigid organ b has mass m, rest centre c_rest and inertia I (from its
//   closed surface, density FASCIA_ORGAN_DENSITY). Its coupling frames are
//   tissue frames; one of them, the master m(b) (the one nearest the
//   centre), carries the body's 6 DOFs, the others (slaves i) follow:
//
//       Q   = q_m conj(q_m,rest)                 body rotation
//       x_i = x_m + Q r_i,  q_i = Q q_i,rest      r_i = x_i,rest - x_m,rest
//       c   = x_m + Q r_c                         r_c = c_rest - x_m,rest
//
//   so the body's pose is the master frame's state (saved, restored and set
//   with it) and no DOF is added. The Newton unknowns stay a vector of 6N
//   entries: free tissue frames and masters are free (the solver's mask),
//   slaves are masked. What changes is the map from those unknowns to the
//   frames (the prolongation P):
//
//       increment of slave i = T_i (dx_m, dtheta_m),  T_i = [[I, -[a_i]x], [0, I]],
//       a_i = Q r_i the slave's current offset from the master,
//
//   taken exactly (nonlinear in the rotation) when the increments are
//   expanded, linearly in the operator. The math of one frame or body is
//   sim/point/body.h's, which every backend runs; this file keeps the
//   bodies' table (fascia_pt_bodies) and their state between steps. Gradients
//   restrict as T_i^T g_i (plus the Jacobian of the rotation map for
//   dynamic steps, as newton.c does per frame), the Newton operator is
//   P^T A P applied matrix-free (expand, the existing operator on all
//   frames, restrict), plus the body's own terms: its mass and inertia
//   (T_c^T diag(m, I_world) T_c with T_c the map to the centre), its
//   gravity -m g.c, and the geometric term sum_i sym(g_i a_i^T) - (g_i.a_i) I
//   of the rotation of the offsets. The body's inertia in a step is that of
//   the frames: c1/2 |d_c - h v_c|^2_M with its world inertia frozen at the
//   step's start, so its momentum balance is exact to the Newton tolerance.
//
//   Linear solvers: the matrix-free and the assembled CG both work (the
//   assembled block matrix of all frames sits inside P^T . P); the direct
//   solver factors P^T K P, assembled here with its new fill
//   (fascia_organs_reduced_pattern, fascia_organs_reduce_matrix).
//
//   A rigid organ without coupling frames flies freely under gravity.
//   An organ driven by the caller (fascia_solver_organ_set_frames) has its
//   coupling frames prescribed to the caller's targets; its body, if rigid,
//   is not simulated until it is released.
#include <stdlib.h>
#include <string.h>

#include "fascia/organs.h"
#include "util/index_set.h"
#include "organs/organs.h"
#include "point/block6.h"
#include "point/body.h"

struct fascia_organs {
  const fascia_model *model;
  int32_t organ_count, frame_count;
  // per organ
  int32_t *frame_offsets;   ///< [O+1] CSR into frames: each organ's coupling frames, once each
  int32_t *frames;          ///< coupling-table order
  unsigned char *driven;    ///< [O] 1 while the caller drives the organ
  unsigned char *posed;     ///< [O] 1 while it is driven by fascia_solver_organ_set_pose
  fascia_real *pose;        ///< [7O] that pose: translation, rotation
  fascia_real *reference;   ///< [3O] rest reference point of the wrench (fascia_solver_organ_wrench)
  int32_t *master;          ///< [O] master frame of a rigid organ, -1 without coupling frames or not rigid
  fascia_real *mass;        ///< [O] kg (rigid organs)
  fascia_real *centre;      ///< [3O] rest centre of mass, m
  fascia_real *inertia;     ///< [9O] about the centre, rest, world axes
  fascia_real *velocity;    ///< [6O] body: centre velocity, angular velocity (state)
  fascia_real *free_pose;   ///< [7O] rigid organs without coupling frames: centre, rotation (state)
  fascia_real *target;      ///< [6O] h v at the step's start
  fascia_real *world_inertia; ///< [9O] Q0 I Q0^T at the step's start
  fascia_real *geometric;   ///< [9O] rotation block of the reduced Hessian from the last gradient
  // per frame
  int32_t *frame_body;      ///< [N] rigid organ the frame is a slave of (master included), -1
  fascia_real *target_x;    ///< [3N] targets of frames driven by the caller
  fascia_real *target_q;    ///< [4N]
  unsigned char *full_mask; ///< [6N]
  unsigned char *active;    ///< [O] 1: a body the solver moves now (rigid, with coupling frames, not driven)
  fascia_pt_bodies bodies;  ///< the table every backend's body math reads (point/body.h)
};

int32_t fascia_model_find_organ(const fascia_model *m, const char *name) {
  for (int32_t k = 0; m && name && k < m->organ_count; ++k)
    if (!strcmp(m->organs[k].name, name)) return k;
  return -1;
}

// ---------------------------------------------------------------- helpers

static void quat_conj(const fascia_real *q, fascia_real *out) {
  out[0] = q[0], out[1] = -q[1], out[2] = -q[2], out[3] = -q[3];
}


// Mass properties of a closed triangle surface at density rho: signed
// tetrahedra from a reference point (divergence theorem); the covariance of
// a tetrahedron with one vertex at the origin is V/20 (sum_j w_j w_j^T + s s^T).
static int mass_properties(const fascia_organ *o, fascia_real rho, fascia_real *mass, fascia_real *centre,
                           fascia_real *inertia) {
  if (o->vertex_count < 4 || o->triangle_count < 4) return 0;
  fascia_real ref[3] = {0, 0, 0};
  for (int32_t v = 0; v < o->vertex_count; ++v)
    for (int c = 0; c < 3; ++c) ref[c] += o->vertices[3 * v + c] / o->vertex_count;
  fascia_real V = 0, first[3] = {0, 0, 0}, C[9] = {0};
  for (int32_t t = 0; t < o->triangle_count; ++t) {
    fascia_real w[3][3], s[3] = {0, 0, 0};
    for (int j = 0; j < 3; ++j)
      for (int c = 0; c < 3; ++c) {
        w[j][c] = o->vertices[3 * o->triangles[3 * t + j] + c] - ref[c];
        s[c] += w[j][c];
      }
    fascia_real bc[3];
    fascia_pt_cross(w[1], w[2], bc);
    const fascia_real vol = fascia_pt_dot3(w[0], bc) / 6;
    V += vol;
    for (int c = 0; c < 3; ++c) first[c] += vol * s[c] / 4;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        C[3 * r + c] += vol / 20 * (w[0][r] * w[0][c] + w[1][r] * w[1][c] + w[2][r] * w[2][c] + s[r] * s[c]);
  }
  if (!(fabs(V) > 0) || !isfinite(V)) return 0;
  if (V < 0) { // inward orientation
    V = -V;
    for (int c = 0; c < 3; ++c) first[c] = -first[c];
    for (int k = 0; k < 9; ++k) C[k] = -C[k];
  }
  fascia_real g[3];
  for (int c = 0; c < 3; ++c) g[c] = first[c] / V, centre[c] = ref[c] + g[c];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) C[3 * r + c] -= V * g[r] * g[c];
  const fascia_real tr = C[0] + C[4] + C[8];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) inertia[3 * r + c] = rho * ((r == c) * tr - C[3 * r + c]);
  *mass = rho * V;
  return 1;
}

// The rest point an organ's wrench is taken about: the centre of the volume
// its surface encloses, else (an open or empty surface) its vertices' mean.
static void reference_point(const fascia_organ *o, fascia_real *point) {
  fascia_real mass, inertia[9];
  if (mass_properties(o, 1, &mass, point, inertia)) return;
  point[0] = point[1] = point[2] = 0;
  for (int32_t v = 0; v < o->vertex_count; ++v)
    for (int c = 0; c < 3; ++c) point[c] += o->vertices[3 * v + c] / o->vertex_count;
}

// ---------------------------------------------------------------- create

void fascia_organs_destroy(fascia_organs **organs) {
  if (!organs || !*organs) return;
  fascia_organs *O = *organs;
  free(O->frame_offsets), free(O->frames), free(O->driven), free(O->master), free(O->mass), free(O->centre);
  free(O->inertia), free(O->velocity), free(O->free_pose), free(O->target), free(O->world_inertia);
  free(O->geometric), free(O->frame_body), free(O->target_x), free(O->target_q), free(O->full_mask);
  free(O->active), free(O->posed), free(O->pose), free(O->reference);
  free(O);
  *organs = NULL;
}

// Each organ's coupling frames, once each, in coupling-table order.
static fascia_status list_frames(fascia_ctx *ctx, fascia_organs *O) {
  const fascia_model *m = O->model;
  const int32_t N = m->frame_count, K = m->organ_count;
  int32_t *seen = malloc(((size_t)N + 1) * sizeof(int32_t));
  FASCIA_CHECK(seen, ctx, FASCIA_ERR_MEMORY, "organs: out of memory");
  for (int32_t i = 0; i < N; ++i) seen[i] = -1;
  int32_t count = 0;
  for (int32_t k = 0; k < K; ++k) {
    O->frame_offsets[k] = count;
    for (int32_t c = 0; c < m->coupling_count; ++c) {
      const int32_t i = m->coupling_frame[c];
      if (m->coupling_organ[c] != k || seen[i] == k) continue;
      seen[i] = k;
      O->frames[count++] = i;
    }
  }
  O->frame_offsets[K] = count;
  free(seen);
  return FASCIA_OK;
}

// Masters, mass properties, and the frame -> body table of rigid organs.
static fascia_status setup_bodies(fascia_ctx *ctx, fascia_organs *O) {
  const fascia_model *m = O->model;
  for (int32_t k = 0; k < m->organ_count; ++k) {
    O->master[k] = -1;
    O->free_pose[7 * k + 3] = 1;
    if (m->organs[k].kind != FASCIA_ORGAN_RIGID) continue;
    const fascia_organ *o = m->organs + k;
    // model problems, not settings: FASCIA_ERR_FORMAT (fascia_model_validate checks what it can with the file's name)
    FASCIA_CHECK(mass_properties(o, FASCIA_ORGAN_DENSITY, O->mass + k, O->centre + 3 * k, O->inertia + 9 * k), ctx,
                 FASCIA_ERR_FORMAT,
                 "organ '%s' is rigid but its surface (%d vertices, %d triangles) encloses no volume; give it a "
                 "closed surface or make it fixed or prescribed",
                 o->name, (int)o->vertex_count, (int)o->triangle_count);
    memcpy(O->free_pose + 7 * k, O->centre + 3 * k, 3 * sizeof(fascia_real));
    fascia_real best = INFINITY;
    for (int32_t f = O->frame_offsets[k]; f < O->frame_offsets[k + 1]; ++f) {
      const int32_t i = O->frames[f];
      FASCIA_CHECK(m->frame_kind[i] == FASCIA_FRAME_FREE, ctx, FASCIA_ERR_FORMAT,
                   "organ '%s' is rigid but its coupling frame %d is %s in the model; a frame on a rigid organ "
                   "must be free (re-run 'fascia prep')",
                   o->name, (int)i, m->frame_kind[i] == FASCIA_FRAME_FIXED ? "fixed" : "prescribed");
      FASCIA_CHECK(O->frame_body[i] < 0, ctx, FASCIA_ERR_FORMAT,
                   "frame %d is a coupling frame of the rigid organs '%s' and '%s'; it can follow one only", (int)i,
                   m->organs[O->frame_body[i]].name, o->name);
      O->frame_body[i] = k;
      fascia_real r[3];
      for (int c = 0; c < 3; ++c) r[c] = m->frame_position[3 * i + c] - O->centre[3 * k + c];
      if (fascia_pt_dot3(r, r) < best) best = fascia_pt_dot3(r, r), O->master[k] = i;
    }
  }
  return FASCIA_OK;
}

fascia_status fascia_organs_create(fascia_ctx *ctx, const fascia_model *m, fascia_organs **out) {
  *out = NULL;
  if (m->organ_count == 0) return FASCIA_OK;
  fascia_organs *O = calloc(1, sizeof *O);
  FASCIA_CHECK(O, ctx, FASCIA_ERR_MEMORY, "organs: out of memory");
  const int64_t N = m->frame_count, K = m->organ_count;
  O->model = m;
  O->organ_count = m->organ_count;
  O->frame_count = m->frame_count;
  O->frame_offsets = fascia_calloc(K + 1, sizeof(int32_t));
  O->frames = fascia_calloc(m->coupling_count + 1, sizeof(int32_t));
  O->driven = fascia_calloc(K, 1);
  O->master = fascia_calloc(K, sizeof(int32_t));
  O->mass = fascia_calloc(K, sizeof(fascia_real));
  O->centre = fascia_calloc(3 * K, sizeof(fascia_real));
  O->inertia = fascia_calloc(9 * K, sizeof(fascia_real));
  O->velocity = fascia_calloc(6 * K, sizeof(fascia_real));
  O->free_pose = fascia_calloc(7 * K, sizeof(fascia_real));
  O->target = fascia_calloc(6 * K, sizeof(fascia_real));
  O->world_inertia = fascia_calloc(9 * K, sizeof(fascia_real));
  O->geometric = fascia_calloc(9 * K, sizeof(fascia_real));
  O->frame_body = fascia_calloc(N, sizeof(int32_t));
  O->target_x = fascia_calloc(3 * N, sizeof(fascia_real));
  O->target_q = fascia_calloc(4 * N, sizeof(fascia_real));
  O->full_mask = fascia_calloc(6 * N, 1);
  O->active = fascia_calloc(K, 1);
  O->posed = fascia_calloc(K, 1);
  O->pose = fascia_calloc(7 * K, sizeof(fascia_real));
  O->reference = fascia_calloc(3 * K, sizeof(fascia_real));
  fascia_status status = FASCIA_OK;
  if (!O->frame_offsets || !O->frames || !O->driven || !O->master || !O->mass || !O->centre || !O->inertia ||
      !O->velocity || !O->free_pose || !O->target || !O->world_inertia || !O->geometric || !O->frame_body ||
      !O->target_x || !O->target_q || !O->full_mask || !O->active || !O->posed || !O->pose ||
      !O->reference) {
    status = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "organs: out of memory for %lld frames", (long long)N);
    goto cleanup;
  }
  for (int64_t i = 0; i < N; ++i) O->frame_body[i] = -1;
  for (int64_t k = 0; k < K; ++k)
    for (int c = 0; c < 3; ++c) O->world_inertia[9 * k + 4 * c] = 1;
  FASCIA_TRY_GOTO(list_frames(ctx, O));
  FASCIA_TRY_GOTO(setup_bodies(ctx, O));
  for (int32_t k = 0; k < O->organ_count; ++k) reference_point(m->organs + k, O->reference + 3 * k);
  const fascia_pt_bodies table = {O->organ_count, O->frame_offsets, O->frames,  O->frame_body,
                                  O->master,      m->frame_position, m->frame_rotation, O->centre,
                                  O->mass,        O->active,       O->world_inertia, O->target,
                                  O->geometric};
  O->bodies = table;
  *out = O;
  return FASCIA_OK;
cleanup:
  fascia_organs_destroy(&O);
  return status;
}

int fascia_organs_any_driven(const fascia_organs *O) {
  for (int32_t b = 0; O && b < O->model->organ_count; ++b)
    if (O->driven[b]) return 1;
  return 0;
}

int fascia_organs_driven(const fascia_organs *O, int32_t organ) { return O && O->driven[organ]; }

int32_t fascia_organs_frame_body(const fascia_organs *O, int32_t i) { return O ? O->frame_body[i] : -1; }

// A body is simulated when it is rigid, has a master and is not driven.
static int active(const fascia_organs *O, int32_t b) { return O->active[b]; }

const fascia_pt_bodies *fascia_organs_bodies(const fascia_organs *O) {
  for (int32_t b = 0; O && b < O->organ_count; ++b)
    if (O->master[b] >= 0) return &O->bodies;
  return NULL;
}

const unsigned char *fascia_organs_full_mask(const fascia_organs *O) { return O ? O->full_mask : NULL; }

int32_t fascia_organs_body_count(const fascia_organs *O) {
  int32_t count = 0;
  for (int32_t b = 0; O && b < O->organ_count; ++b) count += active(O, b);
  return count;
}

void fascia_organs_masks(const fascia_model *m, fascia_organs *O, unsigned char *mask) {
  if (!O) { // no organ: the free frames
    for (int32_t i = 0; i < m->frame_count; ++i)
      for (int c = 0; c < 6; ++c) mask[6 * (int64_t)i + c] = m->frame_kind[i] == FASCIA_FRAME_FREE;
    return;
  }
  for (int32_t k = 0; k < O->organ_count; ++k) O->active[k] = O->master[k] >= 0 && !O->driven[k];
  for (int32_t i = 0; i < O->frame_count; ++i)
    for (int c = 0; c < 6; ++c) O->full_mask[6 * i + c] = m->frame_kind[i] == FASCIA_FRAME_FREE;
  for (int32_t k = 0; k < O->organ_count; ++k)
    for (int32_t f = O->frame_offsets[k]; O->driven[k] && f < O->frame_offsets[k + 1]; ++f)
      memset(O->full_mask + 6 * (int64_t)O->frames[f], 0, 6);
  memcpy(mask, O->full_mask, 6 * (size_t)O->frame_count);
  for (int32_t i = 0; i < O->frame_count; ++i) {
    const int32_t b = O->frame_body[i];
    if (b >= 0 && active(O, b) && O->master[b] != i) memset(mask + 6 * (int64_t)i, 0, 6);
  }
}

// ---------------------------------------------------------------- steps

void fascia_organs_place(const fascia_organs *O, fascia_real *x, fascia_real *q) {
  for (int32_t k = 0; O && k < O->organ_count; ++k)
    for (int32_t f = O->frame_offsets[k]; O->driven[k] && f < O->frame_offsets[k + 1]; ++f) {
      const int32_t i = O->frames[f];
      memcpy(x + 3 * i, O->target_x + 3 * i, 3 * sizeof(fascia_real));
      memcpy(q + 4 * i, O->target_q + 4 * i, 4 * sizeof(fascia_real));
    }
}

void fascia_organs_expand(const fascia_organs *O, const fascia_real *x_base, const fascia_real *q_base,
                          fascia_real *d) {
  for (int32_t i = 0; fascia_organs_body_count(O) > 0 && i < O->frame_count; ++i)
    fascia_pt_body_expand(&O->bodies, i, x_base, q_base, d);
}

void fascia_organs_step_begin(fascia_organs *O, const fascia_organs_state *st, fascia_real h) {
  if (!O) return;
  for (int32_t b = 0; b < O->organ_count; ++b) {
    if (O->driven[b]) {
      for (int32_t f = O->frame_offsets[b]; f < O->frame_offsets[b + 1]; ++f) {
        const int32_t i = O->frames[f];
        fascia_real *d = st->d + 6 * i, qc[4], rel[4];
        for (int c = 0; c < 3; ++c) d[c] = O->target_x[3 * i + c] - st->x_base[3 * i + c];
        quat_conj(st->q_base + 4 * i, qc);
        fascia_pt_quat_mul(O->target_q + 4 * i, qc, rel);
        fascia_pt_quat_log(rel, d + 3);
      }
      continue;
    }
    if (!active(O, b)) continue;
    fascia_real Q0[4], R0[9], IR[9];
    fascia_pt_body_rotation(&O->bodies, b, st->q_base, Q0, R0);
    fascia_pt_mat_mult(O->inertia + 9 * b, R0, IR); // I R0^T
    fascia_pt_mat_mul(R0, IR, O->world_inertia + 9 * b);
    for (int c = 0; c < 6; ++c) O->target[6 * b + c] = h * O->velocity[6 * b + c];
  }
  fascia_organs_expand(O, st->x_base, st->q_base, st->d);
}

void fascia_organs_step_end(fascia_organs *O, const fascia_organs_state *st, const fascia_real *g, fascia_real h) {
  if (!O) return;
  for (int32_t b = 0; b < O->organ_count; ++b) {
    fascia_real *v = O->velocity + 6 * b;
    if (active(O, b)) {
      fascia_pt_body_centre_increment(&O->bodies, b, st->x, st->q, st->x_base, st->q_base, v);
      for (int c = 0; c < 3; ++c) v[c] /= h, v[3 + c] = st->d[6 * O->master[b] + 3 + c] / h;
    } else if (O->model->organs[b].kind == FASCIA_ORGAN_RIGID && O->master[b] < 0) {
      // free flight, backward Euler: no torque, constant angular velocity
      fascia_real *pose = O->free_pose + 7 * b, phi[3];
      for (int c = 0; c < 3; ++c) v[c] += h * g[c], pose[c] += h * v[c], phi[c] = h * v[3 + c];
      fascia_pt_quat_rotate_by(phi, pose + 3);
    }
  }
}

// ---------------------------------------------------------------- reduction

fascia_real fascia_organs_reduce(const fascia_organs *O, const fascia_pt_body_step *step, const fascia_real *x,
                                 const fascia_real *q, const fascia_real *x_base, const fascia_real *q_base,
                                 const fascia_real *d, fascia_real *gradient) {
  fascia_real energy = 0;
  for (int32_t b = 0; O && b < O->organ_count; ++b)
    if (active(O, b)) energy += fascia_pt_body_gradient(&O->bodies, b, step, x, q, x_base, q_base, d, gradient);
  return energy;
}

// The frame a frame's unknowns are reduced to: its body's master for a
// frame of a simulated rigid organ, else itself.
static int32_t reduced_frame(const fascia_organs *O, int32_t i) {
  const int32_t b = O->frame_body[i];
  return b >= 0 && active(O, b) ? O->master[b] : i;
}

fascia_status fascia_organs_reduced_pattern(fascia_ctx *ctx, const fascia_organs *O, const fascia_bsr *K,
                                            fascia_bsr *R) {
  memset(R, 0, sizeof *R);
  const int32_t N = K->rows;
  // each reduced row gets a slice: its diagonal, then the columns its frames reach
  int64_t *begin = calloc((size_t)N + 1, sizeof *begin), *cursor = calloc((size_t)N + 1, sizeof *cursor);
  R->rows = N;
  R->row_offsets = calloc((size_t)N + 1, sizeof *R->row_offsets);
  R->diagonal = calloc((size_t)N + 1, sizeof *R->diagonal);
  int32_t *cols = NULL;
  fascia_status st = begin && cursor && R->row_offsets && R->diagonal
                         ? FASCIA_OK
                         : FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "solver: out of memory for the reduced matrix");
  if (st == FASCIA_OK) {
    for (int32_t i = 0; i < N; ++i) begin[reduced_frame(O, i) + 1] += K->row_offsets[i + 1] - K->row_offsets[i];
    for (int32_t r = 0; r < N; ++r) begin[r + 1] += begin[r] + 1;
    cols = malloc((size_t)begin[N] * sizeof *cols + 1);
    if (!cols) st = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "solver: out of memory for the reduced matrix");
  }
  if (st == FASCIA_OK) {
    for (int32_t r = 0; r < N; ++r) cols[begin[r]] = r, cursor[r] = begin[r] + 1;
    for (int32_t i = 0; i < N; ++i)
      for (int32_t k = K->row_offsets[i]; k < K->row_offsets[i + 1]; ++k)
        cols[cursor[reduced_frame(O, i)]++] = reduced_frame(O, K->cols[k]);
    int32_t packed = 0; // each slice sorted, unique, moved down
    for (int32_t r = 0; r < N; ++r) {
      const int32_t unique = fascia_index_set_make(cols + begin[r], (int32_t)(cursor[r] - begin[r]));
      memmove(cols + packed, cols + begin[r], (size_t)unique * sizeof *cols);
      R->row_offsets[r] = packed;
      R->diagonal[r] = fascia_index_set_find(cols, packed, packed + unique, r);
      packed += unique;
    }
    R->row_offsets[N] = packed;
    R->blocks = packed;
    R->cols = cols;
    R->values = calloc(36 * (size_t)packed + 1, sizeof *R->values);
    if (!R->values) st = FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "solver: out of memory for the reduced matrix");
  } else {
    free(cols);
  }
  free(begin), free(cursor);
  if (st != FASCIA_OK) fascia_bsr_destroy(R);
  return st;
}

void fascia_organs_reduce_matrix(const fascia_organs *O, const fascia_system *sys, const unsigned char *moves,
                                 fascia_real mass_coefficient, const fascia_bsr *K, fascia_bsr *R) {
  const int32_t N = K->rows;
  memset(R->values, 0, 36 * (size_t)R->blocks * sizeof *R->values);
  // slave rows and columns fold into their master's through T(a), a = x_i - x_master
  for (int32_t i = 0; i < N; ++i) {
    if (!fascia_frame_moving(moves, i)) continue;
    const int32_t ri = reduced_frame(O, i);
    for (int32_t k = K->row_offsets[i]; k < K->row_offsets[i + 1]; ++k) {
      if (!fascia_frame_moving(moves, K->cols[k])) continue;
      const int32_t j = K->cols[k], rj = reduced_frame(O, j);
      const fascia_real *block = K->values + 36 * (int64_t)k;
      fascia_real *out = R->values + 36 * (int64_t)fascia_index_set_find(R->cols, R->row_offsets[ri],
                                                                          R->row_offsets[ri + 1], rj);
      if (ri == i && rj == j) { // neither frame on a body: the block as it is
        for (int q = 0; q < 36; ++q) out[q] += block[q];
        continue;
      }
      fascia_real folded[36], ai[3], aj[3];
      for (int c = 0; c < 3; ++c) ai[c] = sys->x[3 * (int64_t)i + c] - sys->x[3 * (int64_t)ri + c];
      for (int c = 0; c < 3; ++c) aj[c] = sys->x[3 * (int64_t)j + c] - sys->x[3 * (int64_t)rj + c];
      fascia_pt_body_transform_block(block, ai, aj, folded);
      for (int q = 0; q < 36; ++q) out[q] += folded[q];
    }
  }
  // each body's own mass and inertia through its centre, and the geometric term
  for (int32_t b = 0; b < O->organ_count; ++b) {
    if (!active(O, b)) continue;
    const int32_t m = O->master[b];
    fascia_real folded[36];
    fascia_pt_body_own_block(&O->bodies, b, mass_coefficient, sys->q, folded);
    fascia_real *out = R->values + 36 * (int64_t)R->diagonal[m];
    for (int q = 0; q < 36; ++q) out[q] += folded[q];
  }
}

fascia_real fascia_organs_load_norm2(const fascia_organs *O, const fascia_system *sys, fascia_real gs) {
  fascia_real sum = 0;
  for (int32_t b = 0; O && b < O->organ_count; ++b) {
    if (!active(O, b)) continue;
    fascia_real f[3];
    for (int c = 0; c < 3; ++c) f[c] = O->mass[b] * sys->gravity[c];
    for (int32_t k = O->frame_offsets[b]; k < O->frame_offsets[b + 1]; ++k) {
      const int32_t i = O->frames[k];
      if (i == O->master[b]) continue;
      for (int c = 0; c < 3; ++c) f[c] += sys->frame_mass[i] * sys->gravity[c] + O->model->frame_load[6 * i + c];
    }
    sum += gs * gs * fascia_pt_dot3(f, f);
  }
  return sum;
}

// ---------------------------------------------------------------- state

size_t fascia_organs_state_size(const fascia_organs *O) { return O ? 13 * (size_t)O->organ_count : 0; }

void fascia_organs_save(const fascia_organs *O, fascia_real *buffer) {
  if (!O) return;
  memcpy(buffer, O->velocity, 6 * (size_t)O->organ_count * sizeof(fascia_real));
  memcpy(buffer + 6 * O->organ_count, O->free_pose, 7 * (size_t)O->organ_count * sizeof(fascia_real));
}

void fascia_organs_restore(fascia_organs *O, const fascia_real *buffer) {
  if (!O) return;
  memcpy(O->velocity, buffer, 6 * (size_t)O->organ_count * sizeof(fascia_real));
  memcpy(O->free_pose, buffer + 6 * O->organ_count, 7 * (size_t)O->organ_count * sizeof(fascia_real));
}

// Puts body b's slaves rigidly on its master, with the rigid velocity field.
static void place_slaves(fascia_organs *O, const fascia_organs_state *st, int32_t b) {
  const int32_t m = O->master[b];
  fascia_real Q[4], R[9], r[3], a[3];
  fascia_pt_body_rotation(&O->bodies, b, st->q, Q, R);
  const fascia_real *um = st->u + 6 * m;
  for (int32_t f = O->frame_offsets[b]; f < O->frame_offsets[b + 1]; ++f) {
    const int32_t i = O->frames[f];
    if (i == m) continue;
    fascia_pt_body_rest_offset(&O->bodies, b, i, r);
    fascia_pt_mat_vec(R, r, a);
    fascia_real wa[3];
    fascia_pt_cross(um + 3, a, wa);
    for (int c = 0; c < 3; ++c) {
      st->x[3 * i + c] = st->x[3 * m + c] + a[c];
      st->u[6 * i + c] = um[c] + wa[c];
      st->u[6 * i + 3 + c] = um[3 + c];
    }
    fascia_pt_quat_mul(Q, O->model->frame_rotation + 4 * i, st->q + 4 * i);
    fascia_pt_quat_normalize(st->q + 4 * i);
  }
  fascia_pt_body_rest_offset(&O->bodies, b, -1, r);
  fascia_pt_mat_vec(R, r, a);
  fascia_real wa[3];
  fascia_pt_cross(um + 3, a, wa);
  for (int c = 0; c < 3; ++c) O->velocity[6 * b + c] = um[c] + wa[c], O->velocity[6 * b + 3 + c] = um[3 + c];
}

void fascia_organs_sync(fascia_organs *O, const fascia_organs_state *st) {
  for (int32_t b = 0; O && b < O->organ_count; ++b)
    if (active(O, b)) place_slaves(O, st, b);
}

fascia_real fascia_organs_kinetic_energy(const fascia_organs *O, const fascia_real *q) {
  fascia_real e = 0;
  for (int32_t b = 0; O && b < O->organ_count; ++b) {
    if (O->model->organs[b].kind != FASCIA_ORGAN_RIGID || O->driven[b]) continue;
    const fascia_real *v = O->velocity + 6 * b;
    fascia_real Q[4], R[9], Rw[3], IRw[3], w[3];
    if (O->master[b] >= 0) fascia_pt_body_rotation(&O->bodies, b, q, Q, R);
    else fascia_pt_quat_to_mat(O->free_pose + 7 * b + 3, R);
    fascia_pt_mat_tvec(R, v + 3, Rw); // body-axes angular velocity
    fascia_pt_mat_vec(O->inertia + 9 * b, Rw, IRw);
    fascia_pt_mat_vec(R, IRw, w);
    e += FASCIA_R(0.5) * (O->mass[b] * fascia_pt_dot3(v, v) + fascia_pt_dot3(v + 3, w));
  }
  return e;
}

// The pose of rigid organ b (not driven) at positions x, rotations q: its
// master frame's where it has coupling frames, else its free flight's.
static void rigid_pose(const fascia_organs *O, int32_t b, const fascia_real *x, const fascia_real *q,
                       fascia_real *translation, fascia_real *rotation) {
  fascia_real R[9], p[3];
  if (O->master[b] >= 0) { // x_m = t + Q x_m,rest
    const int32_t m = O->master[b];
    fascia_pt_body_rotation(&O->bodies, b, q, rotation, R);
    fascia_pt_mat_vec(R, O->model->frame_position + 3 * m, p);
    for (int c = 0; c < 3; ++c) translation[c] = x[3 * m + c] - p[c];
  } else { // c = t + Q c_rest
    memcpy(rotation, O->free_pose + 7 * b + 3, 4 * sizeof(fascia_real));
    fascia_pt_quat_to_mat(rotation, R);
    fascia_pt_mat_vec(R, O->centre + 3 * b, p);
    for (int c = 0; c < 3; ++c) translation[c] = O->free_pose[7 * b + c] - p[c];
  }
}

fascia_real fascia_organs_potential_energy(const fascia_organs *O, const fascia_real *x, const fascia_real *q,
                                           const fascia_real *gravity) {
  fascia_real e = 0;
  for (int32_t b = 0; O && b < O->organ_count; ++b) {
    if (O->model->organs[b].kind != FASCIA_ORGAN_RIGID || O->driven[b]) continue;
    fascia_real t[3], rotation[4], R[9], c[3];
    rigid_pose(O, b, x, q, t, rotation);
    fascia_pt_quat_to_mat(rotation, R);
    fascia_pt_mat_vec(R, O->centre + 3 * b, c);
    for (int k = 0; k < 3; ++k) c[k] += t[k];
    e -= O->mass[b] * fascia_pt_dot3(gravity, c);
  }
  return e;
}

// ---------------------------------------------------------------- the organ API's parts (solve/organ_api.c)

int fascia_organs_mass_properties(const fascia_organ *o, fascia_real *mass, fascia_real *centre, fascia_real *inertia) {
  return mass_properties(o, FASCIA_ORGAN_DENSITY, mass, centre, inertia);
}

int32_t fascia_organs_frames(const fascia_organs *O, int32_t organ, const int32_t **frames) {
  if (!O) return 0;
  *frames = O->frames + O->frame_offsets[organ];
  return O->frame_offsets[organ + 1] - O->frame_offsets[organ];
}

int fascia_organs_pose(const fascia_organs *O, int32_t organ, fascia_real time, const fascia_real *x,
                       const fascia_real *q, fascia_real *translation, fascia_real *rotation) {
  const fascia_organ *o = O->model->organs + organ;
  if (O->driven[organ] && O->posed[organ]) {
    memcpy(translation, O->pose + 7 * organ, 3 * sizeof(fascia_real));
    memcpy(rotation, O->pose + 7 * organ + 3, 4 * sizeof(fascia_real));
    return 1;
  }
  if (O->driven[organ]) return 0;
  fascia_real R[9], p[3];
  if (o->kind == FASCIA_ORGAN_PRESCRIBED && o->motion >= 0) {
    // x = pivot + T + Q (x_rest - pivot)
    const fascia_motion *mo = O->model->motions + o->motion;
    fascia_real T[3];
    fascia_motion_pose(mo, time, T, rotation);
    fascia_pt_quat_to_mat(rotation, R);
    fascia_pt_mat_vec(R, mo->pivot, p);
    for (int c = 0; c < 3; ++c) translation[c] = mo->pivot[c] + T[c] - p[c];
  } else if (o->kind == FASCIA_ORGAN_RIGID) {
    rigid_pose(O, organ, x, q, translation, rotation);
  } else {
    for (int c = 0; c < 3; ++c) translation[c] = 0;
    rotation[0] = 1, rotation[1] = rotation[2] = rotation[3] = 0;
  }
  return 1;
}

void fascia_organs_velocity(const fascia_organs *O, int32_t organ, fascia_real *linear, fascia_real *angular) {
  const int rigid = O->model->organs[organ].kind == FASCIA_ORGAN_RIGID && !O->driven[organ];
  for (int c = 0; c < 3; ++c) {
    if (linear) linear[c] = rigid ? O->velocity[6 * organ + c] : 0;
    if (angular) angular[c] = rigid ? O->velocity[6 * organ + 3 + c] : 0;
  }
}

void fascia_organs_drive(fascia_organs *O, int32_t organ, const fascia_real *positions, const fascia_real *rotations,
                         const fascia_real *pose, unsigned char *mask) {
  for (int32_t f = O->frame_offsets[organ]; f < O->frame_offsets[organ + 1]; ++f) {
    const int32_t i = O->frames[f], k = f - O->frame_offsets[organ];
    const fascia_real *q = rotations + 4 * k;
    const fascia_real norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    memcpy(O->target_x + 3 * i, positions + 3 * k, 3 * sizeof(fascia_real));
    for (int c = 0; c < 4; ++c) O->target_q[4 * i + c] = q[c] / norm;
  }
  O->posed[organ] = pose != NULL;
  if (pose) memcpy(O->pose + 7 * organ, pose, 7 * sizeof(fascia_real));
  if (!O->driven[organ]) {
    O->driven[organ] = 1;
    fascia_organs_masks(O->model, O, mask);
  }
}

int fascia_organs_release(fascia_organs *O, int32_t organ, const fascia_organs_state *st, unsigned char *mask) {
  if (!O->driven[organ]) return 0;
  O->driven[organ] = 0;
  O->posed[organ] = 0;
  fascia_organs_masks(O->model, O, mask);
  if (active(O, organ)) place_slaves(O, st, organ);
  return 1;
}

void fascia_organs_reaction(const fascia_organs *O, int32_t organ, const fascia_real *g, fascia_real *forces,
                            fascia_real *torques) {
  // the gradient holds -frame_load too: take it out
  const fascia_real *load = O->model->frame_load;
  for (int32_t f = O->frame_offsets[organ]; f < O->frame_offsets[organ + 1]; ++f) {
    const int32_t i = O->frames[f], k = f - O->frame_offsets[organ];
    for (int c = 0; c < 3; ++c) {
      forces[3 * k + c] = -(g[6 * i + c] + load[6 * i + c]);
      if (torques) torques[3 * k + c] = -(g[6 * i + 3 + c] + load[6 * i + 3 + c]);
    }
  }
}

// The pose that carries the organ's reference point: its own where it has
// one, its first coupling frame's rigid motion where it is driven frame by
// frame, the rest pose for a deformable organ.
void fascia_organs_reference_point(const fascia_organs *O, int32_t organ, fascia_real time, const fascia_real *x,
                                   const fascia_real *q, fascia_real *point) {
  const int32_t begin = O->frame_offsets[organ];
  fascia_real translation[3] = {0, 0, 0}, rotation[4] = {1, 0, 0, 0}, R[9], p[3];
  if (O->driven[organ] && !O->posed[organ] && begin < O->frame_offsets[organ + 1]) {
    const int32_t f = O->frames[begin];
    fascia_real qc[4];
    quat_conj(O->model->frame_rotation + 4 * (int64_t)f, qc);
    fascia_pt_quat_mul(q + 4 * (int64_t)f, qc, rotation);
    fascia_pt_quat_normalize(rotation);
    fascia_pt_quat_to_mat(rotation, R);
    fascia_pt_mat_vec(R, O->model->frame_position + 3 * (int64_t)f, p);
    for (int c = 0; c < 3; ++c) translation[c] = x[3 * (int64_t)f + c] - p[c];
  } else if (!fascia_organs_pose(O, organ, time, x, q, translation, rotation)) {
    translation[0] = translation[1] = translation[2] = 0;
    rotation[0] = 1, rotation[1] = rotation[2] = rotation[3] = 0;
  }
  fascia_pt_quat_to_mat(rotation, R);
  fascia_pt_mat_vec(R, O->reference + 3 * organ, point);
  for (int c = 0; c < 3; ++c) point[c] += translation[c];
}

int32_t fascia_model_organ_count(const fascia_model *m) { return m ? m->organ_count : 0; }

const char *fascia_model_organ_name(const fascia_model *m, int32_t organ) {
  return m && organ >= 0 && organ < m->organ_count ? m->organs[organ].name : "";
}

const fascia_surface *fascia_model_tissue_surface(const fascia_model *m) { return &m->tissue_surface; }
