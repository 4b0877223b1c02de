// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Every kind of code-built cantilever (hex, tet, meshless) is a valid model of
// the paper's beam: volume 16 m^3, mass 5 kg, exactly the x = 0 frames
// clamped, a tip probe that reproduces (16, 0, 0), and at the model level a
// patch test: frames moved by x -> G x + c (rotations identity) give F = G at
// every sample.
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "fascia/fascia.h"
#include "point/sample.h"
#include "scenes.h"

static uint64_t rng_state = 777;

static double uniform(double lo, double hi) {
  rng_state = rng_state * 6364136223846793005ULL + 1442695040888963407ULL;
  return lo + (hi - lo) * (double)(rng_state >> 11) * 0x1.0p-53;
}

// F = sum_i (x_i + d_is) (x) grad w_is + w_is I with x_i = G x_rest_i + c,
// identity rotations and d_is = p_rest_s - x_rest_i, through the shared
// per-sample code (sim/point/sample.h). Linear reproduction makes F = G up to
// rounding: the terms are O(16 |grad w|) ~ 1e2 and cancel, so 1e-12 absolute.
static int patch_test(const char *what, const fascia_model *m) {
  double G[9], c[3];
  for (int r = 0; r < 3; ++r) {
    c[r] = uniform(-1, 1);
    for (int q = 0; q < 3; ++q) G[3 * r + q] = (r == q) + uniform(-0.3, 0.3);
  }
  const int32_t N = m->frame_count, P = m->pair_count;
  double *x = malloc(3 * (size_t)N * sizeof *x), *A = calloc(9 * (size_t)N, sizeof *A);
  double *offset = malloc(3 * (size_t)P * sizeof *offset);
  if (!x || !A || !offset) return 1;
  for (int32_t i = 0; i < N; ++i) {
    const double *xr = m->frame_position + 3 * i;
    for (int r = 0; r < 3; ++r) {
      x[3 * i + r] = c[r] + G[3 * r] * xr[0] + G[3 * r + 1] * xr[1] + G[3 * r + 2] * xr[2];
      A[9 * i + 4 * r] = 1;
    }
  }
  for (int32_t s = 0; s < m->sample_count; ++s)
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k)
      for (int r = 0; r < 3; ++r)
        offset[3 * k + r] = m->sample_position[3 * s + r] - m->frame_position[3 * m->pair_frame[k] + r];
  fascia_pt_model pm;
  memset(&pm, 0, sizeof pm);
  pm.sample_offsets = m->sample_offsets;
  pm.pair_frame = m->pair_frame;
  pm.pair_weight = m->pair_weight;
  pm.pair_gradient = m->pair_gradient;
  pm.pair_offset = offset;
  pm.sample_volume = m->sample_volume;
  fascia_pt_state st = {x, A};
  double worst = 0;
  int32_t worst_s = -1;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    double F[9];
    fascia_pt_sample_F(&pm, &st, s, F);
    for (int q = 0; q < 9; ++q)
      if (!(fabs(F[q] - G[q]) <= worst)) {
        worst = fabs(F[q] - G[q]);
        worst_s = s;
      }
  }
  if (!(worst <= 1e-12)) fprintf(stderr, "%s: patch test |F - G| = %.3g at sample %d\n", what, worst, (int)worst_s);
  CHECK(worst <= 1e-12);
  free(x);
  free(A);
  free(offset);
  return 0;
}

static int check_beam(fascia_ctx *ctx, const char *what, const fascia_scene_beam_def *def, int32_t samples,
                      int32_t per_sample) {
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, def, &m), ctx);
  CHECK_OK(fascia_model_validate(ctx, m, what), ctx);
  CHECK(m->frame_count == def->frames[0] * def->frames[1] * def->frames[2]);
  CHECK(m->sample_count == samples);
  for (int32_t s = 0; s < m->sample_count; ++s)
    CHECK(m->sample_offsets[s + 1] - m->sample_offsets[s] == per_sample);
  // sums of a few hundred positive terms: rounding ~1e-15 relative
  CHECK_NEAR(fascia_model_volume(m), 16, 1e-12, 0);
  CHECK_NEAR(fascia_model_mass(m), 5, 1e-12, 0);
  CHECK(m->material_count == 1 && m->materials[0].law == def->law);
  CHECK_NEAR(m->materials[0].youngs_modulus, def->youngs_modulus, 0, 0);
  CHECK_NEAR(m->materials[0].poisson_ratio, def->poisson_ratio, 0, 0);
  CHECK_NEAR(m->gravity[2], -9.81, 0, 0);
  int32_t fixed = 0;
  for (int32_t i = 0; i < m->frame_count; ++i) {
    const int at_root = m->frame_position[3 * i] == 0;
    CHECK(m->frame_kind[i] == (at_root ? FASCIA_FRAME_FIXED : FASCIA_FRAME_FREE));
    fixed += at_root;
  }
  CHECK(fixed == def->frames[1] * def->frames[2]);
  // the tip probe reproduces its point (linear reproduction, rounding 1e-12)
  const int32_t tip = fascia_model_find_probe(m, "tip");
  CHECK(tip >= 0);
  if (tip >= 0) {
    const double expect[3] = {16, 0, 0};
    double p[3] = {0, 0, 0}, sum = 0;
    for (int32_t k = m->probe_offsets[tip]; k < m->probe_offsets[tip + 1]; ++k) {
      sum += m->probe_weight[k];
      for (int r = 0; r < 3; ++r) p[r] += m->probe_weight[k] * m->frame_position[3 * m->probe_frame[k] + r];
    }
    CHECK_NEAR(sum, 1, 0, 1e-12);
    for (int r = 0; r < 3; ++r) {
      CHECK_NEAR(m->probe_position[3 * tip + r], expect[r], 0, 0);
      CHECK_NEAR(p[r], expect[r], 0, 1e-12);
    }
  }
  CHECK(m->provenance && strstr(m->provenance, "fascia_scene_beam_build") &&
        strstr(m->provenance, fascia_scene_shape_name(def->shape)));
  int rc = patch_test(what, m);
  fascia_model_destroy(&m);
  return rc;
}

int main(void) {
  fascia_ctx_def cdef = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cdef, &ctx) != FASCIA_OK) return 1;
  const int32_t cells = 19 * 2 * 2;
  int fail = 0;

  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  fail |= check_beam(ctx, "hex 20x3x3", &def, cells * 8, 8);
  def.samples_per_cell_dir = 3;
  def.frames[1] = 4; // an even section: the tip sits inside a cell face
  fail |= check_beam(ctx, "hex 20x4x3, 27 per cell", &def, 19 * 3 * 2 * 27, 8);

  def = fascia_scene_beam_def_default();
  def.shape = FASCIA_SCENE_TET;
  fail |= check_beam(ctx, "tet, 4 per tet", &def, cells * 6 * 4, 4);
  def.samples_per_tet = 1;
  def.frames[0] = 9;
  def.frames[2] = 4;
  fail |= check_beam(ctx, "tet 9x3x4, centroid", &def, 8 * 2 * 3 * 6, 4);

  def = fascia_scene_beam_def_default();
  def.shape = FASCIA_SCENE_MESHLESS;
  fail |= check_beam(ctx, "meshless k = 8", &def, cells * 8, 8);
  def.neighbours = 12;
  def.law = FASCIA_LAW_NEOHOOKEAN;
  def.density = 0.3125; // 5 kg over 16 m^3, given directly
  def.mass = 0;
  fail |= check_beam(ctx, "meshless k = 12, neohookean", &def, cells * 8, 12);

  // bad defs are refused with a message naming the field; nothing is built
  fascia_model *m = NULL;
  def = fascia_scene_beam_def_default();
  def.frames[1] = 1;
  CHECK(fascia_scene_beam_build(ctx, &def, &m) == FASCIA_ERR_ARGUMENT && m == NULL);
  CHECK(strstr(fascia_ctx_message(ctx), "along y") != NULL);
  def = fascia_scene_beam_def_default();
  def.poisson_ratio = 0.5;
  CHECK(fascia_scene_beam_build(ctx, &def, &m) == FASCIA_ERR_ARGUMENT && m == NULL);
  def = fascia_scene_beam_def_default();
  def.shape = FASCIA_SCENE_TET;
  def.samples_per_tet = 2;
  CHECK(fascia_scene_beam_build(ctx, &def, &m) == FASCIA_ERR_ARGUMENT && m == NULL);
  fascia_scene_beam_def raw;
  memset(&raw, 0, sizeof raw);
  CHECK(fascia_scene_beam_build(ctx, &raw, &m) == FASCIA_ERR_ARGUMENT && m == NULL);

  fascia_ctx_destroy(&ctx);
  return fail | CHECK_RESULT();
}
