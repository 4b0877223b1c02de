// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// At rest every sample has F = I and the internal force is zero; under any
// rigid motion of all frames (one rotation R and translation c) every sample
// has F = R and the internal force and energy stay zero, for both laws and
// with the rotation coupling on.
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "random_model.h"
#include "cpu/system.h"

// Forces are sums of stresses times volumes of order 1e3 Pa * 1e-2 m^3: a
// rounding-level residual is ~1e-12; 1e-9 leaves room and still catches any
// real stress (a strain of 1e-12 already gives more).
#define FORCE_ATOL 1e-9

static int run_case(fascia_ctx *ctx, unsigned long long seed, int law, double coupling) {
  fascia_model *m = random_model(ctx, seed, 8, 12, law, coupling, seed == 3 ? 0.2 : 0.0);
  CHECK(m != NULL);
  if (!m) return 1;
  m->gravity[0] = m->gravity[1] = m->gravity[2] = 0;
  fascia_system *sys = NULL;
  CHECK_OK(fascia_system_create(ctx, m, 2, &sys), ctx);
  const int N = m->frame_count, n = 6 * N;
  double *g = malloc(n * sizeof(double)), *x = malloc(3 * N * sizeof(double)), *q = malloc(4 * N * sizeof(double));
  double energy;
  // rest
  CHECK_OK(fascia_system_evaluate(sys, g, &energy), ctx);
  CHECK_NEAR(energy, 0, 0, 1e-14); // every energy term vanishes at rest: no cancellation left
  for (int k = 0; k < n; ++k) CHECK_NEAR(g[k], 0, 0, FORCE_ATOL);
  const fascia_pt_state rest = {sys->x, sys->A};
  for (int s = 0; s < m->sample_count; ++s) {
    double F[9];
    fascia_pt_sample_F(&sys->pm, &rest, s, F);
    for (int c = 0; c < 9; ++c) CHECK_NEAR(F[c], (c % 4 == 0), 0, 1e-13);
  }
  // rigid motions: large rotation, translation
  unsigned long long st = seed + 99;
  for (int trial = 0; trial < 3; ++trial) {
    double r[4], R[9], c0[3];
    rnd_rotation(&st, 3.1, r);
    fascia_pt_quat_to_mat(r, R);
    for (int c = 0; c < 3; ++c) c0[c] = rnd_uniform(&st, -5, 5);
    for (int i = 0; i < N; ++i) {
      fascia_pt_mat_vec(R, m->frame_position + 3 * i, x + 3 * i);
      for (int c = 0; c < 3; ++c) x[3 * i + c] += c0[c];
      fascia_pt_quat_mul(r, m->frame_rotation + 4 * i, q + 4 * i);
    }
    fascia_system_set_state(sys, x, q);
    CHECK_OK(fascia_system_evaluate(sys, g, &energy), ctx);
    CHECK_NEAR(energy, 0, 0, 1e-12);
    for (int k = 0; k < n; ++k) CHECK_NEAR(g[k], 0, 0, FORCE_ATOL);
    const fascia_pt_state moved = {sys->x, sys->A};
    for (int s = 0; s < m->sample_count; ++s) {
      double F[9];
      fascia_pt_sample_F(&sys->pm, &moved, s, F);
      for (int c = 0; c < 9; ++c) CHECK_NEAR(F[c], R[c], 0, 1e-12);
    }
  }
  free(g), free(x), free(q);
  fascia_system_destroy(&sys);
  fascia_model_destroy(&m);
  return 0;
}

int main(void) {
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&def, &ctx) != FASCIA_OK) return 1;
  int failed = 0;
  for (unsigned long long seed = 1; seed <= 3; ++seed)
    for (int law = 0; law < 2; ++law) failed |= run_case(ctx, seed, law, seed == 2 ? 0.5 : 0.0);
  fascia_ctx_destroy(&ctx);
  return failed | CHECK_RESULT();
}
