// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Projected preconditioned conjugate gradients for one Newton iteration on
// the CPU: the vector loops around the scalar logic of sim/point/cg.h, which
// the device runs too. Constrained DOFs are kept at zero by the mask.
#include <string.h>

#include "point/body.h"
#include "point/cg.h"
#include "solver_internal.h"

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
  const int64_t n = 6 * (int64_t)sys->frame_count;
  if (op->assembled && op->single) {
    fascia_bsr_apply_single(op->assembled, sys->threads, v, out);
  } else if (op->assembled) {
    fascia_bsr_apply(op->assembled, sys->threads, v, out);
  } else {
    fascia_system_hessian_apply(sys, v, out);
  }
  if (op->mass_coefficient != 0 && !op->assembled) {
    if (op->mass == FASCIA_MASS_LUMPED) {
      for (int32_t i = 0; i < sys->frame_count; ++i) {
        const fascia_real *B = op->mass_blocks + 36 * (int64_t)i, *vi = v + 6 * (int64_t)i;
        for (int r = 0; r < 6; ++r) {
          fascia_real s = 0;
          for (int c = 0; c < 6; ++c) s += B[6 * r + c] * vi[c];
          out[6 * (int64_t)i + r] += op->mass_coefficient * s;
        }
      }
    } else {
      fascia_system_mass_apply(sys, v, op->scratch);
      for (int64_t k = 0; k < n; ++k) out[k] += op->mass_coefficient * op->scratch[k];
    }
  }
  if (op->shift != 0)
    for (int64_t k = 0; k < n; ++k) out[k] += op->shift * op->damping_diagonal[k] * v[k];
  for (int64_t k = 0; k < n; ++k)
    if (!op->mask[k]) out[k] = 0;
}

fascia_cg_result fascia_cg_solve(const fascia_operator *op, const fascia_preconditioner *pc, const fascia_real *b,
                                 fascia_real *p, int max_iterations, int fixed, fascia_real tolerance,
                                 fascia_real *work) {
  const int64_t n = 6 * (int64_t)op->sys->frame_count;
  const int threads = op->sys->threads;
  fascia_real *r = work, *z = work + n, *dir = work + 2 * n, *Ad = work + 3 * n;
  const fascia_pt_cg_limits limits = {tolerance, max_iterations, fixed};
  fascia_pt_cg s;
  memset(p, 0, (size_t)n * sizeof(fascia_real));
  for (int64_t k = 0; k < n; ++k) r[k] = op->mask[k] ? b[k] : 0;
  fascia_precond_apply(pc, op->mask, r, z);
  memcpy(dir, z, (size_t)n * sizeof(fascia_real));
  fascia_pt_cg_start(&s, &limits, fascia_dot(r, r, n, threads), fascia_dot(r, z, n, threads));
  while (s.running) {
    fascia_operator_apply(op, dir, Ad);
    fascia_pt_cg_curvature(&s, op->scale, fascia_dot(dir, Ad, n, threads), fascia_dot(dir, dir, n, threads));
    if (s.action == FASCIA_CG_COPY_Z) memcpy(p, z, (size_t)n * sizeof(fascia_real));
    if (s.action != FASCIA_CG_UPDATE) break;
    for (int64_t k = 0; k < n; ++k) {
      p[k] += s.alpha * dir[k];
      r[k] -= s.alpha * Ad[k];
    }
    fascia_precond_apply(pc, op->mask, r, z);
    fascia_pt_cg_residual(&s, &limits, fascia_dot(r, r, n, threads), fascia_dot(r, z, n, threads));
    if (s.action == FASCIA_CG_DIRECTION)
      for (int64_t k = 0; k < n; ++k) dir[k] = z[k] + s.beta * dir[k];
  }
  const fascia_cg_result result = {s.iterations, s.negative_curvature, s.bnorm > 0 ? s.rnorm / s.bnorm : 0};
  return result;
}
