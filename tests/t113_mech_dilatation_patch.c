// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Mean dilatation (volumetric patches), with and without the patches'
// enhanced strain modes, passes the patch test and keeps rigid motions free,
// on the code-built cantilevers (hex cells, tet cubes, meshless Poisson
// patches), both laws, nu = 0.45:
//  - under an affine frame motion x -> G x + c (rotations identity) every
//    sample has F = G, so every patch's mean dilatation is the samples' own:
//    the patched model's energy and gradient equal the unpatched model's, and
//    the frames inside the beam (not on its faces) get no force; the modes
//    stay at zero;
//  - at rest and under a rigid motion the energy and the forces are zero.
// The finite-difference checks of the term are in t110, its assembly in t112.
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "random_model.h"
#include "scenes.h"
#include "cpu/modes.h"
#include "cpu/system.h"
#include "cpu/dilatation.h"

static unsigned long long rng_state = 4242;

static double uniform(double lo, double hi) { return rnd_uniform(&rng_state, lo, hi); }

static fascia_model *beam(fascia_ctx *ctx, int shape, int law, int patch, int modes) {
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 6;
  def.shape = shape;
  def.law = law;
  def.neighbours = 16; // k = 8 finds coplanar frames on so short a beam
  def.poisson_ratio = 0.45;
  def.volumetric_patch = patch;
  def.patch_radius = 1.0;
  def.enhanced_modes = modes;
  fascia_model *m = NULL;
  if (fascia_scene_beam_build(ctx, &def, &m) != FASCIA_OK) return NULL;
  return m;
}

static double max_abs(const double *a, int64_t n) {
  double w = 0;
  for (int64_t k = 0; k < n; ++k) w = fmax(w, fabs(a[k]));
  return w;
}

static double largest_amplitude(const fascia_system *sys) {
  if (!sys->modes) return 0;
  return max_abs(sys->modes->amplitude, 9 * (int64_t)sys->dilatation->table.patch_count);
}

static int run_case(fascia_ctx *ctx, int shape, int law, int patch, int modes) {
  fascia_model *full = beam(ctx, shape, law, FASCIA_SCENE_PATCH_NONE, 0);
  fascia_model *patched = beam(ctx, shape, law, patch, modes);
  CHECK(full && patched);
  if (!full || !patched) return 1;
  CHECK(fascia_model_patch_count(patched, NULL) > 1);
  fascia_system *a = NULL, *b = NULL;
  CHECK_OK(fascia_system_create(ctx, full, 1, &a), ctx);
  CHECK_OK(fascia_system_create(ctx, patched, 2, &b), ctx);
  CHECK(b->dilatation != NULL);
  CHECK((b->modes != NULL) == modes);
  a->gravity_scale = b->gravity_scale = 0; // internal forces alone
  const int32_t N = full->frame_count, n = 6 * N;
  double *x = malloc(3 * (size_t)N * sizeof *x), *q = malloc(4 * (size_t)N * sizeof *q);
  double *ga = malloc((size_t)n * sizeof *ga), *gb = malloc((size_t)n * sizeof *gb);
  double ea, eb;
  // rest: nothing
  CHECK_OK(fascia_system_evaluate(b, gb, &eb), ctx);
  CHECK_NEAR(eb, 0, 0, 1e-12);
  CHECK(max_abs(gb, n) < 1e-9);
  // affine motion, identity rotations
  double G[9], c[3];
  for (int r = 0; r < 3; ++r) {
    c[r] = uniform(-1, 1);
    for (int k = 0; k < 3; ++k) G[3 * r + k] = (r == k) + uniform(-0.2, 0.2);
  }
  for (int32_t i = 0; i < N; ++i) {
    const double *xr = full->frame_position + 3 * i;
    for (int r = 0; r < 3; ++r) x[3 * i + r] = c[r] + G[3 * r] * xr[0] + G[3 * r + 1] * xr[1] + G[3 * r + 2] * xr[2];
    q[4 * i] = 1, q[4 * i + 1] = q[4 * i + 2] = q[4 * i + 3] = 0;
  }
  fascia_system_set_state(a, x, q);
  fascia_system_set_state(b, x, q);
  CHECK_OK(fascia_system_evaluate(a, ga, &ea), ctx);
  CHECK_OK(fascia_system_evaluate(b, gb, &eb), ctx);
  CHECK(ea > 0);
  CHECK_NEAR(eb, ea, 0, 1e-11 * ea);
  const double scale = max_abs(ga, n);
  for (int k = 0; k < n; ++k) CHECK_NEAR(gb[k], ga[k], 0, 1e-10 * scale);
  CHECK(largest_amplitude(b) < 1e-12);
  // a rigid motion: rotation about a random axis by 1.1 rad, and a translation
  double R[9], axis[3] = {uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)}, rq[4];
  const double len = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  rq[0] = cos(0.55);
  for (int r = 0; r < 3; ++r) rq[1 + r] = sin(0.55) * axis[r] / len;
  fascia_pt_quat_to_mat(rq, R);
  for (int32_t i = 0; i < N; ++i) {
    fascia_pt_mat_vec(R, full->frame_position + 3 * i, x + 3 * i);
    for (int r = 0; r < 3; ++r) x[3 * i + r] += c[r];
    fascia_pt_quat_mul(rq, full->frame_rotation + 4 * i, q + 4 * i);
  }
  fascia_system_set_state(b, x, q);
  CHECK_OK(fascia_system_evaluate(b, gb, &eb), ctx);
  CHECK_NEAR(eb, 0, 0, 1e-9 * ea);
  CHECK(max_abs(gb, n) < 1e-8 * scale);
  CHECK(largest_amplitude(b) < 1e-12);
  free(x), free(q), free(ga), free(gb);
  fascia_system_destroy(&a);
  fascia_system_destroy(&b);
  fascia_model_destroy(&full);
  fascia_model_destroy(&patched);
  return 0;
}

int main(void) {
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&def, &ctx) != FASCIA_OK) return 1;
  int failed = 0;
  for (int law = FASCIA_LAW_STVK; law <= FASCIA_LAW_NEOHOOKEAN; ++law) {
    for (int modes = 0; modes <= 1; ++modes) {
      failed |= run_case(ctx, FASCIA_SCENE_HEX, law, FASCIA_SCENE_PATCH_CELL, modes);
      failed |= run_case(ctx, FASCIA_SCENE_TET, law, FASCIA_SCENE_PATCH_CELL, modes);
      failed |= run_case(ctx, FASCIA_SCENE_MESHLESS, law, FASCIA_SCENE_PATCH_POISSON, modes);
      failed |= run_case(ctx, FASCIA_SCENE_HEX, law, FASCIA_SCENE_PATCH_FRAME, modes);
    }
  }
  fascia_ctx_destroy(&ctx);
  return failed | CHECK_RESULT();
}
