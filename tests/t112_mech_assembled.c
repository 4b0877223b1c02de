// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The assembled 6x6-block tangent (closed-form local blocks plus the added
// terms) multiplies like the matrix-free Hessian product, and the assembled
// consistent mass like the matrix-free mass product, for both laws, with
// and without the rotation coupling and smoothing and volumetric patches
// (whose rank-one terms widen the pattern) and their enhanced strain modes
// (condensed, rank 9 per patch), at random states; and
// the assembly gives bit-identical values for 1 and 2 threads (and teams of
// 1 to 5 on a model of several chunks); its float
// copy multiplies like it to float rounding. Assembled for some frames only
// (the frames a step moves), a block of two such frames is bit-identical to
// the full assembly's and every other block is zero, tangent and mass, and
// its product on those frames is the full product's. The enhanced strain
// modes' factors from the shares the assembly leaves are the matrix-free
// path's, bit for bit. Each frame's lumped mass block, made from its pairs'
// rest moments, is the sum of their point masses at the rotated offsets.
#include <stdlib.h>
#include <string.h>

#include "cpu/assemble.h"
#include "check.h"
#include "cpu/dilatation.h"
#include "cpu/modes.h"
#include "random_model.h"

// Every block of K_part between two frames that move equals K's, the others are zero.
static void check_moving_blocks(const fascia_bsr *K, const fascia_bsr *K_part, const unsigned char *moves) {
  for (int32_t i = 0; i < K->rows; ++i)
    for (int32_t b = K->row_offsets[i]; b < K->row_offsets[i + 1]; ++b) {
      const double *full = K->values + 36 * (int64_t)b, *part = K_part->values + 36 * (int64_t)b;
      if (moves[i] && moves[K->cols[b]]) {
        CHECK(memcmp(full, part, 36 * sizeof(double)) == 0);
      } else {
        for (int q = 0; q < 36; ++q) CHECK(part[q] == 0);
      }
    }
}

// The modes' factors W_e from the assembly's shares are the matrix-free
// path's, bit for bit: after a full assembly (sys), and after one that
// moves no frame (moves all zero), whose samples still leave their shares.
static int check_mode_shares(fascia_ctx *ctx, fascia_model *m, const double *x, const double *q,
                              const fascia_system *sys, const unsigned char *moves) {
  fascia_system *own = NULL, *held = NULL;
  fascia_bsr K;
  CHECK_OK(fascia_system_create(ctx, m, 1, &own), ctx);
  CHECK_OK(fascia_system_create(ctx, m, 1, &held), ctx);
  CHECK_OK(fascia_bsr_create(ctx, m, &K), ctx);
  fascia_system_set_state(own, x, q);
  fascia_system_set_state(held, x, q);
  CHECK_OK(fascia_system_evaluate(own, NULL, NULL), ctx);
  CHECK_OK(fascia_system_evaluate(held, NULL, NULL), ctx);
  fascia_modes_tangent(own, own->modes);
  CHECK(!own->modes->shares_current && sys->modes->shares_current);
  CHECK(fascia_system_hessian_assemble(held, moves, &K));
  CHECK(held->modes->shares_current && held->modes->tangent_current);
  const fascia_pt_patches *t = &own->dilatation->view;
  const size_t bytes = 54 * (size_t)t->support_offsets[t->count] * sizeof(double);
  CHECK(memcmp(sys->modes->entry_factor, own->modes->entry_factor, bytes) == 0);
  CHECK(memcmp(held->modes->entry_factor, own->modes->entry_factor, bytes) == 0);
  fascia_bsr_destroy(&K);
  fascia_system_destroy(&own);
  fascia_system_destroy(&held);
  return 0;
}

// A random state near the model's rest: every frame moved by up to 0.1 m
// along each axis and turned by up to 1 rad.
static void random_state(const fascia_model *m, unsigned long long *st, double *x, double *q) {
  for (int i = 0; i < m->frame_count; ++i) {
    for (int c = 0; c < 3; ++c) x[3 * i + c] = m->frame_position[3 * i + c] + rnd_uniform(st, -0.1, 0.1);
    double r[4];
    rnd_rotation(st, 1.0, r);
    fascia_pt_quat_mul(r, m->frame_rotation + 4 * i, q + 4 * i);
  }
}

static int run_case(fascia_ctx *ctx, unsigned long long seed, int law, double coupling, double smoothing,
                    int patches) {
  fascia_model *m = random_model(ctx, seed, 9, 14, law, coupling, smoothing);
  if (m && patches) random_model_patches(m);
  // patches: 0 none, 1 without modes, 2 with the nine, 3 with the three normal ones
  for (int32_t s = 0; m && s < m->sample_count; ++s)
    m->sample_modes[s] = patches == 2 ? FASCIA_MODES_NINE : patches == 3 ? FASCIA_MODES_NORMAL : FASCIA_MODES_NONE;
  if (getenv("T112_VERBOSE")) fprintf(stderr, "case seed %llu law %d coupling %g smoothing %g\n", seed, law, coupling, smoothing);
  CHECK(m != NULL);
  if (!m) return 1;
  fascia_system *sys = NULL, *sys1 = NULL;
  CHECK_OK(fascia_system_create(ctx, m, 2, &sys), ctx);
  CHECK_OK(fascia_system_create(ctx, m, 1, &sys1), ctx);
  const int N = m->frame_count, n = 6 * N;
  double *x = malloc(3 * N * sizeof(double)), *q = malloc(4 * N * sizeof(double));
  double *v = malloc(n * sizeof(double)), *a = malloc(n * sizeof(double)), *b = malloc(n * sizeof(double));
  unsigned long long st = seed * 31 + 7;
  random_state(m, &st, x, q);
  fascia_bsr K, K1;
  CHECK_OK(fascia_bsr_create(ctx, m, &K), ctx);
  CHECK_OK(fascia_bsr_create(ctx, m, &K1), ctx);
  fascia_system_set_state(sys, x, q);
  fascia_system_set_state(sys1, x, q);
  CHECK_OK(fascia_system_evaluate(sys, NULL, NULL), ctx);
  CHECK_OK(fascia_system_evaluate(sys1, NULL, NULL), ctx);
  fascia_system_hessian_assemble(sys, NULL, &K);
  fascia_system_hessian_assemble(sys1, NULL, &K1);
  CHECK(memcmp(K.values, K1.values, 36 * (size_t)K.blocks * sizeof(double)) == 0);
  unsigned char *moves = calloc(N, 1);
  if (sys->modes && check_mode_shares(ctx, m, x, q, sys, moves)) return 1;
  for (int i = 0; i < N; ++i) moves[i] = i % 3 != 1;
  fascia_system_hessian_assemble(sys1, moves, &K1);
  check_moving_blocks(&K, &K1, moves);
  // the product on moving frames: a vector zero elsewhere gives the full product's bits there, 0 on the others
  for (int k = 0; k < n; ++k) v[k] = moves[k / 6] ? rnd_uniform(&st, -1, 1) : 0;
  fascia_bsr_apply(&K, 2, NULL, v, a);
  fascia_bsr_apply(&K1, 2, moves, v, b);
  for (int k = 0; k < n; ++k) CHECK(b[k] == (moves[k / 6] ? a[k] : 0));
  for (int trial = 0; trial < 3; ++trial) {
    for (int k = 0; k < n; ++k) v[k] = rnd_uniform(&st, -1, 1);
    fascia_system_hessian_apply(sys, v, a);
    fascia_bsr_apply(&K, 2, NULL, v, b);
    double scale = 0;
    for (int k = 0; k < n; ++k) scale = fmax(scale, fabs(a[k]));
    // same arithmetic in another order: rounding level of the largest entry
    for (int k = 0; k < n; ++k) CHECK_NEAR(b[k], a[k], 0, 1e-11 * scale);
    // the float copy: float rounding of the entries (2^-24 relative, summed
    // over the up-to-6x8x6 terms of a row) of the largest product entry
    CHECK_OK(fascia_bsr_make_single(ctx, &K, 2), ctx);
    fascia_bsr_apply_single(&K, 2, NULL, v, b);
    double largest_term = 0;
    for (int64_t e = 0; e < 36 * K.blocks; ++e) largest_term = fmax(largest_term, fabs(K.values[e]));
    for (int k = 0; k < n; ++k) CHECK_NEAR(b[k], a[k], 0, 300 * 6e-8 * largest_term + 1e-11 * scale);
  }
  // consistent mass
  fascia_system_mass_snapshot(sys);
  memset(K.values, 0, 36 * (size_t)K.blocks * sizeof(double));
  fascia_system_mass_assemble_add(sys, NULL, 1.0, &K);
  fascia_system_mass_snapshot(sys1);
  memset(K1.values, 0, 36 * (size_t)K1.blocks * sizeof(double));
  fascia_system_mass_assemble_add(sys1, moves, 1.0, &K1);
  check_moving_blocks(&K, &K1, moves);
  free(moves);
  for (int k = 0; k < n; ++k) v[k] = rnd_uniform(&st, -1, 1);
  fascia_system_mass_apply(sys, v, a);
  fascia_bsr_apply(&K, 2, NULL, v, b);
  double scale = 0;
  for (int k = 0; k < n; ++k) scale = fmax(scale, fabs(a[k]));
  for (int k = 0; k < n; ++k) CHECK_NEAR(b[k], a[k], 0, 1e-11 * scale);
  // lumped mass: each frame's block, made from its pairs' rest moments, is
  // the sum of their point masses m_k at a_k = A d_k, summed here directly
  double *blocks = malloc(36 * (size_t)N * sizeof(double));
  fascia_system_mass_lumped(sys, blocks);
  for (int i = 0; blocks && i < N; ++i) {
    double ref[36] = {0}, largest = 0;
    const double *A = sys->A_mass + 9 * i;
    for (int32_t r = m->frame_offsets[i]; r < m->frame_offsets[i + 1]; ++r) {
      const int32_t k = m->frame_pairs[r];
      const double mk = sys->pair_lumped_mass[k], *d = sys->pair_offset + 3 * (size_t)k;
      double p[3];
      for (int c = 0; c < 3; ++c) p[c] = A[3 * c] * d[0] + A[3 * c + 1] * d[1] + A[3 * c + 2] * d[2];
      const double pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
      const double cross[9] = {0, -p[2], p[1], p[2], 0, -p[0], -p[1], p[0], 0};
      for (int u = 0; u < 3; ++u)
        for (int c = 0; c < 3; ++c) {
          ref[6 * u + c] += mk * (u == c);
          ref[6 * u + 3 + c] -= mk * cross[3 * u + c];
          ref[6 * (3 + u) + c] += mk * cross[3 * u + c];
          ref[6 * (3 + u) + 3 + c] += mk * ((u == c) * pp - p[u] * p[c]);
        }
    }
    for (int e = 0; e < 36; ++e) largest = fmax(largest, fabs(ref[e]));
    for (int e = 0; e < 36; ++e) CHECK_NEAR(blocks[36 * i + e], ref[e], 0, 1e-13 * largest);
  }
  free(blocks);
  fascia_bsr_destroy(&K);
  fascia_bsr_destroy(&K1);
  free(x), free(q), free(v), free(a), free(b);
  fascia_system_destroy(&sys);
  fascia_system_destroy(&sys1);
  fascia_model_destroy(&m);
  return 0;
}

// Teams of any size, each thread adding the blocks it wrote most of
// (fascia_bsr's add lists), give the one-thread assembly's bits, over
// several chunks and with held frames; the lists are planned again as the
// team changes, on the same matrix.
static int check_teams(fascia_ctx *ctx, unsigned long long seed) {
  fascia_model *m = random_model(ctx, seed, 48, 700, FASCIA_LAW_NEOHOOKEAN, 0.5, 0.3);
  CHECK(m != NULL);
  if (!m) return 1;
  random_model_patches(m);
  const int N = m->frame_count;
  double *x = malloc(3 * N * sizeof(double)), *q = malloc(4 * N * sizeof(double));
  unsigned char *moves = calloc(N, 1);
  unsigned long long st = seed * 17 + 3;
  random_state(m, &st, x, q);
  for (int i = 0; i < N; ++i) moves[i] = i % 4 != 2;
  fascia_bsr K, K1;
  CHECK_OK(fascia_bsr_create(ctx, m, &K), ctx);
  CHECK_OK(fascia_bsr_create(ctx, m, &K1), ctx);
  CHECK(K.chunk_count > 1); // the test covers several chunks
  const size_t bytes = 36 * (size_t)K.blocks * sizeof(double);
  for (int held = 0; held < 2; ++held) {
    const int teams[] = {1, 2, 3, 5, 2};
    for (int t = 0; t < 5; ++t) {
      fascia_system *sys = NULL;
      CHECK_OK(fascia_system_create(ctx, m, teams[t], &sys), ctx);
      if (!sys) break;
      fascia_system_set_state(sys, x, q);
      CHECK_OK(fascia_system_evaluate(sys, NULL, NULL), ctx);
      CHECK(fascia_system_hessian_assemble(sys, held ? moves : NULL, t == 0 ? &K1 : &K));
      if (t > 0) CHECK(memcmp(K.values, K1.values, bytes) == 0);
      fascia_system_destroy(&sys);
    }
  }
  fascia_bsr_destroy(&K);
  fascia_bsr_destroy(&K1);
  free(x), free(q), free(moves);
  fascia_model_destroy(&m);
  return 0;
}

int main(void) {
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&def, &ctx) != FASCIA_OK) return 1;
  int failed = 0;
  for (unsigned long long seed = 1; seed <= 3; ++seed) {
    failed |= run_case(ctx, seed, FASCIA_LAW_STVK, 0, 0, 0);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0, 0, 0);
    failed |= run_case(ctx, seed, FASCIA_LAW_STVK, 0.5, 0.3, 0);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0.5, 0.3, 0);
    failed |= run_case(ctx, seed, FASCIA_LAW_STVK, 0, 0, 1);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0.5, 0.3, 1);
    failed |= run_case(ctx, seed, FASCIA_LAW_STVK, 0, 0, 2);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0.5, 0.3, 2);
    failed |= run_case(ctx, seed, FASCIA_LAW_STVK, 0, 0, 3);
    failed |= run_case(ctx, seed, FASCIA_LAW_NEOHOOKEAN, 0.5, 0.3, 3);
    failed |= check_teams(ctx, seed);
  }
  fascia_ctx_destroy(&ctx);
  return failed | CHECK_RESULT();
}
