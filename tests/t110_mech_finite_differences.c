// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The energy gradient matches central differences of the energy, the
// stiffness product matches central differences of the gradient (rotations
// moved by the solver's update R <- exp([t]x) R, geometric part included),
// and the symmetrized Hessian is symmetric and matches the second difference
// of the energy along the update: for both laws, with and without the
// rotation coupling and the rotation smoothness term, with and without
// volumetric patches (mean dilatation), with and without the patches'
// enhanced strain modes, all nine or the three normal ones (condensed: the
// energy is the minimum over the modes,
// its Hessian K_uu - K_ua K_aa^-1 K_au), at random deformed and rotated states;
// and the laws' closed-form 9x9 tangent matches differences of their stress.
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "random_model.h"
#include "cpu/system.h"

// Step of the differences: with energies of order 1, h = 1e-5 leaves a
// truncation error ~h^2 = 1e-10 and a rounding error ~1e-16/h = 1e-11,
// well under the 1e-6 relative tolerance these checks hold the derivatives to.
#define H 1e-5
#define RTOL 1e-6

static void moved(const fascia_system *sys, const double *x0, const double *q0, const double *v, double h, double *x,
                  double *q) {
  const int32_t N = sys->frame_count;
  memcpy(q, q0, 4 * (size_t)N * sizeof(double));
  for (int32_t i = 0; i < N; ++i) {
    for (int c = 0; c < 3; ++c) x[3 * i + c] = x0[3 * i + c] + h * v[6 * i + c];
    double t[3] = {h * v[6 * i + 3], h * v[6 * i + 4], h * v[6 * i + 5]};
    fascia_pt_quat_rotate_by(t, q + 4 * i);
  }
}

static double max_abs(const double *a, int n) {
  double m = 0;
  for (int k = 0; k < n; ++k) m = fabs(a[k]) > m ? fabs(a[k]) : m;
  return m;
}

static int run_case(fascia_ctx *ctx, unsigned long long seed, int law, double coupling, double curvature,
                    int patches) {
  fascia_model *m = random_model(ctx, seed, 7, 9, law, coupling, curvature);
  CHECK(m != NULL);
  if (!m) return 1;
  if (patches) random_model_patches(m);
  // patches: 0 none, 1 without modes, 2 with the nine, 3 with the three normal ones
  for (int32_t s = 0; s < m->sample_count; ++s)
    m->sample_modes[s] = patches == 2 ? FASCIA_MODES_NINE : patches == 3 ? FASCIA_MODES_NORMAL : FASCIA_MODES_NONE;
  fascia_system *sys = NULL;
  CHECK_OK(fascia_system_create(ctx, m, 1, &sys), ctx);
  const int N = m->frame_count, n = 6 * N;
  double *x0 = malloc(3 * N * sizeof(double)), *q0 = malloc(4 * N * sizeof(double));
  double *x = malloc(3 * N * sizeof(double)), *q = malloc(4 * N * sizeof(double));
  double *g0 = malloc(n * sizeof(double)), *gp = malloc(n * sizeof(double)), *gm = malloc(n * sizeof(double));
  double *v = malloc(n * sizeof(double)), *u = malloc(n * sizeof(double)), *Kv = malloc(n * sizeof(double));
  double *Hv = malloc(n * sizeof(double)), *Hu = malloc(n * sizeof(double)), *fd = malloc(n * sizeof(double));
  unsigned long long st = seed * 7919 + 1;
  // a random deformed and rotated state (large rotations, moderate strain)
  for (int i = 0; i < N; ++i) {
    for (int c = 0; c < 3; ++c) x0[3 * i + c] = m->frame_position[3 * i + c] + rnd_uniform(&st, -0.1, 0.1);
    double r[4];
    rnd_rotation(&st, 1.5, r);
    fascia_pt_quat_mul(r, m->frame_rotation + 4 * i, q0 + 4 * i);
  }
  double e0, ep, em;
  fascia_system_set_state(sys, x0, q0);
  CHECK_OK(fascia_system_evaluate(sys, g0, &e0), ctx);
  // 1. gradient against central differences of the energy, every coordinate
  for (int k = 0; k < n; ++k) {
    memset(v, 0, n * sizeof(double));
    v[k] = 1;
    moved(sys, x0, q0, v, H, x, q);
    fascia_system_set_state(sys, x, q);
    CHECK_OK(fascia_system_evaluate(sys, NULL, &ep), ctx);
    moved(sys, x0, q0, v, -H, x, q);
    fascia_system_set_state(sys, x, q);
    CHECK_OK(fascia_system_evaluate(sys, NULL, &em), ctx);
    fd[k] = (ep - em) / (2 * H);
  }
  const double gscale = max_abs(g0, n);
  for (int k = 0; k < n; ++k) CHECK_NEAR(g0[k], fd[k], 0, RTOL * gscale);
  // 2. stiffness product against central differences of the gradient
  for (int trial = 0; trial < 3; ++trial) {
    for (int k = 0; k < n; ++k) v[k] = rnd_uniform(&st, -1, 1);
    moved(sys, x0, q0, v, H, x, q);
    fascia_system_set_state(sys, x, q);
    CHECK_OK(fascia_system_evaluate(sys, gp, NULL), ctx);
    moved(sys, x0, q0, v, -H, x, q);
    fascia_system_set_state(sys, x, q);
    CHECK_OK(fascia_system_evaluate(sys, gm, NULL), ctx);
    fascia_system_set_state(sys, x0, q0);
    CHECK_OK(fascia_system_evaluate(sys, g0, NULL), ctx);
    fascia_system_gradient_derivative(sys, v, Kv);
    for (int k = 0; k < n; ++k) fd[k] = (gp[k] - gm[k]) / (2 * H);
    const double kscale = max_abs(fd, n);
    for (int k = 0; k < n; ++k) CHECK_NEAR(Kv[k], fd[k], 0, RTOL * kscale);
    // 3. the symmetrized Hessian is symmetric ...
    for (int k = 0; k < n; ++k) u[k] = rnd_uniform(&st, -1, 1);
    fascia_system_hessian_apply(sys, v, Hv);
    fascia_system_hessian_apply(sys, u, Hu);
    const double uHv = fascia_dot(u, Hv, n, sys->threads), vHu = fascia_dot(v, Hu, n, sys->threads);
    CHECK_NEAR(uHv, vHu, 1e-10, 1e-12 * kscale);
    // ... and is the second derivative of the energy along the update
    double e00;
    CHECK_OK(fascia_system_evaluate(sys, NULL, &e00), ctx);
    const double h2 = 1e-4; // second differences: error ~h^2 + 1e-16/h^2
    moved(sys, x0, q0, v, h2, x, q);
    fascia_system_set_state(sys, x, q);
    CHECK_OK(fascia_system_evaluate(sys, NULL, &ep), ctx);
    moved(sys, x0, q0, v, -h2, x, q);
    fascia_system_set_state(sys, x, q);
    CHECK_OK(fascia_system_evaluate(sys, NULL, &em), ctx);
    fascia_system_set_state(sys, x0, q0);
    CHECK_OK(fascia_system_evaluate(sys, NULL, NULL), ctx);
    const double second = (ep - 2 * e00 + em) / (h2 * h2), vHv = fascia_dot(v, Hv, n, sys->threads);
    CHECK_NEAR(vHv, second, 1e-5, 1e-6 * kscale);
  }
  // 4. diagonal blocks equal H applied to unit vectors
  double *blocks = malloc(36 * N * sizeof(double));
  fascia_system_hessian_diagonal(sys, blocks);
  for (int i = 0; i < N; ++i)
    for (int c = 0; c < 6; ++c) {
      memset(v, 0, n * sizeof(double));
      v[6 * i + c] = 1;
      fascia_system_hessian_apply(sys, v, Hv);
      for (int r = 0; r < 6; ++r) CHECK_NEAR(blocks[36 * i + 6 * r + c], Hv[6 * i + r], 1e-9, 1e-9 * gscale);
    }
  free(blocks);
  free(x0), free(q0), free(x), free(q), free(g0), free(gp), free(gm);
  free(v), free(u), free(Kv), free(Hv), free(Hu), free(fd);
  fascia_system_destroy(&sys);
  fascia_model_destroy(&m);
  return 0;
}

// The law's 9x9 tangent in closed form (fascia_pt_stress_tangent, what
// the assembly and the modes take) against central differences of the
// stress plus pressure times the dilatation's gradient, and the
// dilatation's Hessian against differences of its gradient, both laws, at
// random F from stretched to nearly flat (det F 0.05).
static int check_stress_tangent(unsigned long long seed, int law) {
  unsigned long long st = seed * 977 + 5;
  const double lambda = rnd_uniform(&st, 0, 3), mu = rnd_uniform(&st, 0.2, 2), pressure = rnd_uniform(&st, -1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    double F[9], aux[FASCIA_PT_AUX_SIZE], P[9], D[81];
    for (int k = 0; k < 9; ++k) F[k] = (k % 4 == 0) + rnd_uniform(&st, -0.6, 0.6);
    if (trial % 4 == 3) // nearly flat: one column almost in the plane of the others
      for (int r = 0; r < 3; ++r) F[3 * r + 2] = 0.5 * F[3 * r] - 0.7 * F[3 * r + 1] + 0.02 * F[3 * r + 2];
    fascia_pt_stress(law, lambda, mu, F, P, aux);
    fascia_pt_stress_tangent(law, lambda, mu, pressure, F, aux, D);
    for (int kl = 0; kl < 9; ++kl) {
      double Fp[9], Fm[9], Pp[9], Pm[9], tp[9], tm[9], ap[FASCIA_PT_AUX_SIZE], am[FASCIA_PT_AUX_SIZE];
      memcpy(Fp, F, sizeof F), memcpy(Fm, F, sizeof F);
      Fp[kl] += H, Fm[kl] -= H;
      fascia_pt_stress(law, lambda, mu, Fp, Pp, ap);
      fascia_pt_stress(law, lambda, mu, Fm, Pm, am);
      fascia_pt_dilatation(law, Fp, tp);
      fascia_pt_dilatation(law, Fm, tm);
      double column[9], scale = 0;
      for (int ij = 0; ij < 9; ++ij) {
        column[ij] = (Pp[ij] - Pm[ij] + pressure * (tp[ij] - tm[ij])) / (2 * H);
        scale = fmax(scale, fabs(column[ij]));
      }
      for (int ij = 0; ij < 9; ++ij) CHECK_NEAR(D[9 * ij + kl], column[ij], 0, RTOL * (1 + scale));
      // and the directional form the products use, to rounding
      double e[9] = {0}, dP[9];
      e[kl] = 1;
      fascia_pt_stress_diff(law, lambda, mu, F, aux, e, dP);
      fascia_pt_dilatation_diff_add(law, pressure, F, e, dP);
      for (int ij = 0; ij < 9; ++ij) CHECK_NEAR(D[9 * ij + kl], dP[ij], 0, 1e-13 * (1 + scale));
      // the dilatation's Hessian against differences of its gradient
      double Hd[81], hscale = 0;
      fascia_pt_dilatation_hessian(law, F, Hd);
      for (int ij = 0; ij < 9; ++ij) hscale = fmax(hscale, fabs(tp[ij] - tm[ij]) / (2 * H));
      for (int ij = 0; ij < 9; ++ij) CHECK_NEAR(Hd[9 * ij + kl], (tp[ij] - tm[ij]) / (2 * H), 0, RTOL * (1 + hscale));
    }
  }
  return 0;
}

int main(void) {
  for (unsigned long long seed = 1; seed <= 3; ++seed)
    if (check_stress_tangent(seed, FASCIA_LAW_STVK) | check_stress_tangent(seed, FASCIA_LAW_NEOHOOKEAN)) return 1;
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&def, &ctx) != FASCIA_OK) return 1;
  int failed = 0;
  for (unsigned long long seed = 1; seed <= 3; ++seed) {
    failed |= run_case(ctx, seed, FASCIA_LAW_STVK, 0.0, 0.0, 0);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0.0, 0.0, 0);
    failed |= run_case(ctx, seed, FASCIA_LAW_STVK, 0.7, 0.0, 0);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0.7, 0.0, 0);
    failed |= run_case(ctx, seed, FASCIA_LAW_STVK, 0.0, 0.3, 0);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0.4, 0.3, 0);
    failed |= run_case(ctx, seed, FASCIA_LAW_STVK, 0.0, 0.0, 1);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0.0, 0.0, 1);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0.4, 0.3, 1);
    failed |= run_case(ctx, seed, FASCIA_LAW_STVK, 0.0, 0.0, 2);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0.0, 0.0, 2);
    failed |= run_case(ctx, seed, FASCIA_LAW_STVK, 0.7, 0.3, 2);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0.4, 0.3, 2);
    failed |= run_case(ctx, seed, FASCIA_LAW_STVK, 0.0, 0.0, 3);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0.4, 0.3, 3);
  }
  fascia_ctx_destroy(&ctx);
  return failed | CHECK_RESULT();
}
