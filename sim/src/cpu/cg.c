// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Projected preconditioned conjugate gradients for one Newton iteration on
// the CPU: the vector loops around the scalar logic of sim/point/cg.h, which
// the device runs too. Constrained DOFs are kept at zero by the mask. Each
// vector pass is one parallel loop over fixed blocks of frames, its dot
// products summed per block and then in block order, so the result does not
// depend on the thread count; a pass is fused where the algorithm allows,
// since on two cores a parallel loop's start and end cost about as much as
// a pass over 40,000 numbers.
#include <stdlib.h>
#include <string.h>

#include "point/block6.h"
#include "point/body.h"
#include "point/cg.h"
#include "point/frame.h"
#include "cpu/operator.h"

// Rigid organs: P^T A P v, A on every frame the tissue moves, plus the
// bodies' own terms (point/body.h).
static void reduced_apply(const fascia_operator *op, const fascia_real *v, fascia_real *out) {
  const fascia_pt_bodies *bodies = op->bodies;
  const fascia_system *sys = op->sys;
  const int32_t N = sys->frame_count;
  for (int32_t i = 0; i < N; ++i) fascia_pt_body_prolong(bodies, i, sys->x, v, op->prolonged);
  fascia_operator inner = *op;
  inner.bodies = NULL;
  inner.mask = op->full_mask;
  fascia_operator_apply(&inner, op->prolonged, out);
  for (int32_t b = 0; b < bodies->count; ++b)
    if (bodies->active[b]) fascia_pt_body_restrict(bodies, b, op->mass_coefficient, sys->x, sys->q, v, out);
  for (int64_t k = 0; k < 6 * (int64_t)N; ++k)
    if (!op->mask[k]) out[k] = 0;
}

void fascia_operator_apply(const fascia_operator *op, const fascia_real *v, fascia_real *out) {
  if (op->bodies) {
    reduced_apply(op, v, out);
    return;
  }
  fascia_system *sys = op->sys;
  if (op->assembled && op->single) {
    fascia_bsr_apply_single(op->assembled, sys->threads, op->frame_moves, v, out);
  } else if (op->assembled) {
    fascia_bsr_apply(op->assembled, sys->threads, op->frame_moves, v, out);
  } else {
    fascia_system_hessian_apply(sys, v, out);
  }
  // the assembled matrix holds the mass term already
  const int mass = op->mass_coefficient != 0 && !op->assembled, lumped = op->mass == FASCIA_MASS_LUMPED;
  if (mass && !lumped) fascia_system_mass_apply(sys, v, op->scratch);
  for (int64_t i = 0; i < sys->frame_count; ++i) {
    fascia_real lumped_Mv[6];
    const fascia_real *Mv = !mass ? NULL : lumped ? lumped_Mv : op->scratch + 6 * i;
    if (mass && lumped) fascia_pt_block6_mul(op->mass_blocks + 36 * i, v + 6 * i, lumped_Mv);
    const fascia_real *damping = op->damping_diagonal ? op->damping_diagonal + 6 * i : NULL; // read where shifted
    fascia_pt_frame_operator_end(op->mass_coefficient, Mv, op->shift, damping, v + 6 * i, op->mask + 6 * i, out + 6 * i);
  }
}

#define CG_BLOCK_FRAMES 256 // frames per partial sum (fixed: determinism)

typedef struct cg_pass {
  const fascia_operator *op;
  const fascia_preconditioner *pc;
  int32_t frames, blocks;
  fascia_real *partial; // [2 blocks]
} cg_pass;

static void block_range(const cg_pass *c, int32_t blk, int64_t *begin, int64_t *end) {
  *begin = (int64_t)blk * CG_BLOCK_FRAMES;
  *end = *begin + CG_BLOCK_FRAMES < c->frames ? *begin + CG_BLOCK_FRAMES : c->frames;
}

// partial = (a.b, a.c) over entries [k0, k1)
static void block_dots(const fascia_real *a, const fascia_real *b, const fascia_real *c, int64_t k0, int64_t k1,
                       fascia_real partial[2]) {
  fascia_real ab = 0, ac = 0;
  for (int64_t k = k0; k < k1; ++k) {
    ab += a[k] * b[k];
    ac += a[k] * c[k];
  }
  partial[0] = ab;
  partial[1] = ac;
}

// sums[0] = sum of partial[2 b], sums[1] = sum of partial[2 b + 1], in block order
static void sum_partials(const cg_pass *c, fascia_real sums[2]) {
  sums[0] = sums[1] = 0;
  for (int32_t b = 0; b < c->blocks; ++b) {
    sums[0] += c->partial[2 * b];
    sums[1] += c->partial[2 * b + 1];
  }
}

// The residual's pass: r = b masked (start, b given) or p += alpha dir and
// r -= alpha Ad (a step, b NULL); then z = P r and sums = (r.r, r.z).
static void residual(const cg_pass *c, const fascia_real *b, fascia_real alpha, const fascia_real *dir,
                     const fascia_real *Ad, fascia_real *p, fascia_real *r, fascia_real *z, fascia_real sums[2]) {
#pragma omp parallel for num_threads(c->op->sys->threads) schedule(static)
  for (int32_t blk = 0; blk < c->blocks; ++blk) {
    int64_t i0, i1;
    block_range(c, blk, &i0, &i1);
    if (b) {
      for (int64_t k = 6 * i0; k < 6 * i1; ++k) r[k] = c->op->mask[k] ? b[k] : 0;
    } else {
      for (int64_t k = 6 * i0; k < 6 * i1; ++k) {
        p[k] += alpha * dir[k];
        r[k] -= alpha * Ad[k];
      }
    }
    fascia_precond_apply_frames(c->pc, c->op->mask, r, z, (int32_t)i0, (int32_t)i1);
    block_dots(r, r, z, 6 * i0, 6 * i1, c->partial + 2 * blk);
  }
  sum_partials(c, sums);
}

// sums = (dir.Ad, dir.dir)
static void curvature(const cg_pass *c, const fascia_real *dir, const fascia_real *Ad, fascia_real sums[2]) {
#pragma omp parallel for num_threads(c->op->sys->threads) schedule(static)
  for (int32_t blk = 0; blk < c->blocks; ++blk) {
    int64_t i0, i1;
    block_range(c, blk, &i0, &i1);
    block_dots(dir, Ad, dir, 6 * i0, 6 * i1, c->partial + 2 * blk);
  }
  sum_partials(c, sums);
}

fascia_cg_result fascia_cg_solve(const fascia_operator *op, const fascia_preconditioner *pc, const fascia_real *b,
                                 fascia_real *p, int max_iterations, int fixed, fascia_real tolerance,
                                 fascia_real *work) {
  const int32_t N = op->sys->frame_count;
  const int64_t n = 6 * (int64_t)N;
  fascia_real *r = work, *z = work + n, *dir = work + 2 * n, *Ad = work + 3 * n, sums[2];
  const fascia_pt_cg_limits limits = {tolerance, max_iterations, fixed};
  fascia_pt_cg s;
  cg_pass c = {op, pc, N, (N + CG_BLOCK_FRAMES - 1) / CG_BLOCK_FRAMES, NULL};
  fascia_real partial_stack[128];
  c.partial = c.blocks <= 64 ? partial_stack : malloc(2 * (size_t)c.blocks * sizeof(fascia_real));
  memset(p, 0, (size_t)n * sizeof(fascia_real));
  if (!c.partial) { // out of memory: no step (the caller's line search sees no descent)
    const fascia_cg_result none = {0, 0, 1};
    return none;
  }
  residual(&c, b, 0, NULL, NULL, p, r, z, sums);
  memcpy(dir, z, (size_t)n * sizeof(fascia_real));
  fascia_pt_cg_start(&s, &limits, sums[0], sums[1]);
  while (s.running) {
    fascia_operator_apply(op, dir, Ad);
    curvature(&c, dir, Ad, sums);
    fascia_pt_cg_curvature(&s, op->scale, sums[0], sums[1]);
    if (s.action == FASCIA_CG_COPY_Z) memcpy(p, z, (size_t)n * sizeof(fascia_real));
    if (s.action != FASCIA_CG_UPDATE) break;
    residual(&c, NULL, s.alpha, dir, Ad, p, r, z, sums);
    fascia_pt_cg_residual(&s, &limits, sums[0], sums[1]);
    if (s.action == FASCIA_CG_DIRECTION)
      for (int64_t k = 0; k < n; ++k) dir[k] = z[k] + s.beta * dir[k];
  }
  if (c.partial != partial_stack) free(c.partial);
  const fascia_cg_result result = {s.iterations, s.negative_curvature, s.bnorm > 0 ? s.rnorm / s.bnorm : 0};
  return result;
}
