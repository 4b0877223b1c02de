// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Degenerate discretizations stay stable: the fewest frames a body
// can have (2 x 2 x 2: one cell) with hexahedral, tetrahedral and meshless
// weights; flat tetrahedra (a 16 m x 1 m x 1 cm plate, cells 2.3 m x 1 m x
// 1 cm); samples with a single neighbour frame (w = 1, grad w = 0: they follow
// their frame rigidly, carry mass but no strain). A frame reached only by such
// samples has no stiffness at all: it falls freely, exactly, in dynamics, and
// the static solve, which has no equilibrium, is refused with a message that
// names the cause, a deformation that costs no energy (it had advised more
// iterations or load steps). So is the static solve of a hexahedral beam
// with one sample per cell (its hourglass modes cost nothing), and not the
// unconverged solve of the same beam with 2 x 2 x 2 samples per cell.
#include "stability.h"

#define G 9.81

// The static solve of a 10x2x2 hexahedral beam with `samples` per cell
// direction, stopped after `iterations`: refused, its message naming a
// mechanism or not.
static int static_refused(fascia_ctx *ctx, int samples, int iterations, int mechanism) {
  fascia_scene_beam_def bd = fascia_scene_beam_def_default();
  bd.frames[0] = 10, bd.frames[1] = 2, bd.frames[2] = 2;
  bd.samples_per_cell_dir = samples;
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  if (!m) return 1;
  fascia_solver_def sd = stab_solver_def();
  sd.newton_iterations = iterations;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  if (s) {
    CHECK(fascia_solver_solve_static(s, NULL) == FASCIA_ERR_NUMERIC);
    printf("hex 10x2x2, %d^3 samples per cell, %d Newton iterations: %s\n", samples, iterations,
           fascia_ctx_message(ctx));
    CHECK((strstr(fascia_ctx_message(ctx), "costs no energy") != NULL) == mechanism);
    fascia_ctx_clear(ctx);
  }
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  return 0;
}

static int run_case(fascia_ctx *ctx, const char *name, const fascia_model *m, int steps) {
  fascia_solver_def sd = stab_solver_def();
  const stab_result r = stab_run(ctx, name, m, &sd, steps, 0, 1);
  CHECK(!r.bad);
  CHECK(r.steps == steps);
  CHECK(r.energy_end < r.energy_start);
  return 0;
}

// The 3 x 2 x 2 beam (2 m) plus: one single-neighbour sample at every free
// frame, and a dangling free frame at (2.5, 0, 0) reached only by one
// single-neighbour sample.
static fascia_model *single_neighbour_model(fascia_ctx *ctx, int law, int32_t *dangling) {
  fascia_scene_beam_def bd = stab_beam_def(3, law);
  bd.length = 2;
  fascia_model *src = NULL;
  if (fascia_scene_beam_build(ctx, &bd, &src) != FASCIA_OK) return NULL;
  int extra = 1;
  for (int32_t i = 0; i < src->frame_count; ++i) extra += src->frame_kind[i] == FASCIA_FRAME_FREE;
  fascia_model *m = stab_copy_model(ctx, src, 1, extra, extra, 1, 0);
  if (!m) {
    fascia_model_destroy(&src);
    return NULL;
  }
  const int32_t N = src->frame_count;
  *dangling = N;
  m->frame_position[3 * N] = 2.5;
  m->frame_kind[N] = FASCIA_FRAME_FREE;
  int32_t s = src->sample_count, p = src->pair_count;
  const double volume = 0.01; // m^3, a small lump of tissue
  for (int32_t i = 0; i <= N; ++i) {
    if (i < N && src->frame_kind[i] != FASCIA_FRAME_FREE) continue;
    m->sample_offsets[s] = p;
    memcpy(m->sample_position + 3 * s, m->frame_position + 3 * i, 3 * sizeof(fascia_real));
    m->sample_volume[s] = volume;
    m->sample_material[s] = 0;
    m->pair_frame[p] = i;
    m->pair_weight[p] = 1;
    ++s, ++p;
    m->sample_offsets[s] = p;
  }
  fascia_model_destroy(&src);
  m->allow_floating = 1; // the dangling frame's lump is held by nothing, on purpose
  if (fascia_model_build_reverse(ctx, m) != FASCIA_OK || fascia_model_validate(ctx, m, "single neighbours") != FASCIA_OK) {
    fprintf(stderr, "single-neighbour model: %s\n", fascia_ctx_message(ctx));
    fascia_model_destroy(&m);
  }
  return m;
}

int main(int argc, char **argv) {
  stab_backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(stab_backend);
  fascia_ctx *ctx = stab_ctx();
  if (!ctx) return 1;
  for (int law = 0; law < FASCIA_LAW_COUNT_; ++law) {
    // one cell
    for (int shape = 0; shape < FASCIA_SCENE_SHAPE_COUNT_; ++shape) {
      fascia_scene_beam_def bd = stab_beam_def(2, law);
      bd.length = 2;
      bd.shape = shape;
      bd.neighbours = 8; // meshless: all frames there are
      fascia_model *m = NULL;
      CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
      char name[64];
      snprintf(name, sizeof name, "%s 2x2x2 %s", fascia_law_name(law), fascia_scene_shape_name(shape));
      if (run_case(ctx, name, m, 20)) return 1;
      fascia_model_destroy(&m);
    }
    // flat tetrahedra: aspect ratio 230
    fascia_scene_beam_def bd = fascia_scene_beam_def_default();
    bd.frames[0] = 8, bd.frames[1] = 2, bd.frames[2] = 2;
    bd.height = 0.01;
    bd.shape = FASCIA_SCENE_TET;
    bd.law = law;
    fascia_model *m = NULL;
    CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
    char name[64];
    snprintf(name, sizeof name, "%s flat tet", fascia_law_name(law));
    if (run_case(ctx, name, m, 20)) return 1;
    fascia_model_destroy(&m);
    // single neighbours
    int32_t dangling = -1;
    m = single_neighbour_model(ctx, law, &dangling);
    CHECK(m != NULL);
    if (!m) return 1;
    snprintf(name, sizeof name, "%s single neighbours", fascia_law_name(law));
    if (run_case(ctx, name, m, 10)) return 1;
    // the dangling frame falls freely: z_n = -g h^2 n (n + 1) / 2 (implicit Euler)
    fascia_solver_def sd = stab_solver_def();
    sd.newton_tolerance = 1e-10;
    fascia_solver *s = NULL;
    CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
    for (int n = 0; n < 10; ++n) CHECK_OK(fascia_solver_step(s, NULL), ctx);
    const double h = sd.time_step;
    CHECK_NEAR(fascia_solver_frame_positions(s)[3 * dangling + 2], -G * h * h * 10 * 11 / 2, 1e-8, 1e-12);
    // no static equilibrium: refused with a message, the state reached finite
    fascia_ctx_clear(ctx);
    const fascia_status st = fascia_solver_solve_static(s, NULL);
    CHECK(st == FASCIA_ERR_NUMERIC);
    printf("%s, static: %s\n", name, fascia_ctx_message(ctx));
    CHECK(strstr(fascia_ctx_message(ctx), "costs no energy") != NULL);
    CHECK(stab_finite(s, m->frame_count));
    fascia_solver_destroy(&s);
    fascia_model_destroy(&m);
  }
  if (static_refused(ctx, 1, 100, 1) || static_refused(ctx, 2, 2, 0)) return 1;
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
