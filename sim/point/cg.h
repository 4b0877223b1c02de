// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Conjugate gradients' scalar logic, written once: when to stop, and the
// step lengths alpha and beta, from the dot products of an iteration. The
// CPU (sim/src/cpu/cg.c) calls it between its vector loops; the device runs
// it on one thread after each reduction, so that CG never waits for the
// host. What stays per backend is only where the vectors live.
//
// One iteration, with A the Newton operator and P the preconditioner:
//   start:      r = b, z = P r, dir = z                 -> fascia_pt_cg_start(r.r, r.z)
//   curvature:  Ad = A dir                              -> fascia_pt_cg_curvature(dir.Ad, dir.dir)
//   action UPDATE: p += alpha dir, r -= alpha Ad, z = P r -> fascia_pt_cg_residual(r.r, r.z)
//   action COPY_Z: p = z (no progress before a direction of non-positive
//                  curvature: the preconditioned residual still descends)
//   action DIRECTION: dir = z + beta dir, and on to the next curvature
// The tangent of the frame scheme can be singular or indefinite (rotation
// modes, buckling, compressed StVK), so CG stops at the first direction of
// non-positive curvature (Steihaug) with what it has.
#ifndef FASCIA_POINT_CG_H
#define FASCIA_POINT_CG_H

#include "hd.h"

/// A relative residual at which CG has converged as far as doubles go: a
/// fixed iteration count still ends there, since past it the iterations
/// only churn noise (and underflow into slow subnormals).
#define FASCIA_PT_CG_ROUNDOFF 1e-14
/// Curvature below this times the operator's scale (its mean absolute
/// diagonal) and dir.dir counts as none.
#define FASCIA_PT_CG_FLAT 1e-12

/// What the vector work does next (set by the scalar steps).
enum { FASCIA_CG_NONE = 0, FASCIA_CG_UPDATE = 1, FASCIA_CG_COPY_Z = 2, FASCIA_CG_DIRECTION = 3 };

/// The limits of one solve.
typedef struct fascia_pt_cg_limits {
  fascia_real tolerance; ///< relative residual |r| / |b|
  int32_t max;           ///< most iterations
  int32_t fixed;         ///< 1: exactly max (unless round-off or non-positive curvature)
} fascia_pt_cg_limits;

/// The scalars of one solve.
typedef struct fascia_pt_cg {
  fascia_real bnorm, rnorm, rz, alpha, beta;
  int32_t iterations, running, negative_curvature, action;
} fascia_pt_cg;

/// After r = b, z = P r, dir = z: rr = r.r, rz = r.z.
static inline FASCIA_HD void fascia_pt_cg_start(fascia_pt_cg *s, const fascia_pt_cg_limits *limits, fascia_real rr,
                                                fascia_real rz) {
  s->bnorm = s->rnorm = sqrt(rr);
  s->rz = rz;
  s->alpha = s->beta = 0;
  s->iterations = 0;
  s->negative_curvature = 0;
  s->running = s->bnorm > 0 && limits->max > 0;
  s->action = FASCIA_CG_NONE;
}

/// After Ad = A dir: curvature = dir.Ad, dd = dir.dir; sets alpha (action
/// UPDATE), or ends CG on non-positive curvature (action COPY_Z when no
/// iteration was done).
static inline FASCIA_HD void fascia_pt_cg_curvature(fascia_pt_cg *s, fascia_real scale, fascia_real curvature,
                                                    fascia_real dd) {
  s->action = FASCIA_CG_NONE;
  if (!s->running) return;
  if (!(curvature > FASCIA_PT_CG_FLAT * scale * dd) || !isfinite(curvature)) {
    s->negative_curvature = 1;
    s->running = 0;
    if (s->iterations == 0) s->action = FASCIA_CG_COPY_Z;
    return;
  }
  s->alpha = s->rz / curvature;
  s->action = FASCIA_CG_UPDATE;
}

/// After the update and z = P r: rr = r.r, rz_next = r.z; sets beta (action
/// DIRECTION) or ends CG (converged, the count reached, or a preconditioner
/// that is not positive).
static inline FASCIA_HD void fascia_pt_cg_residual(fascia_pt_cg *s, const fascia_pt_cg_limits *limits,
                                                   fascia_real rr, fascia_real rz_next) {
  if (s->action != FASCIA_CG_UPDATE) {
    s->action = FASCIA_CG_NONE;
    return;
  }
  s->iterations += 1;
  s->rnorm = sqrt(rr);
  s->action = FASCIA_CG_NONE;
  if (s->rnorm <= FASCIA_PT_CG_ROUNDOFF * s->bnorm || (!limits->fixed && s->rnorm <= limits->tolerance * s->bnorm) ||
      s->iterations >= limits->max || !(rz_next > 0)) {
    s->running = 0;
    return;
  }
  s->beta = rz_next / s->rz;
  s->rz = rz_next;
  s->action = FASCIA_CG_DIRECTION;
}

#endif
