// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The device solver against the CPU on a prepared tissue model:
// the README's demo scene, vesicouterine tissue between the HRA uterus and
// bladder (MLS shape functions, 8 neighbours, volumetric patches; fixed
// bladder frames, uterus frames on a prescribed motion). Forces, products and diagonal blocks at a
// random deformed state; one step, and 100 steps of the demo's traction.
// Arguments: --backend NAME and the scene file, or a model file prepared
// from it (`fascia prep`: how the GPU check carries it to a GPU machine
// without the prep stage's libraries, tools/gpu-check.sh).
#define _POSIX_C_SOURCE 200809L // mkdtemp in prep_fixture.h
#include "device_compare.h"
#ifdef FASCIA_HAVE_PREP
#include "prep_fixture.h"
#endif

int main(int argc, char **argv) {
  const char *scene = NULL;
  for (int k = 1; k < argc; ++k) {
    if (!strcmp(argv[k], "--backend")) ++k;
    else scene = argv[k];
  }
  if (!scene) {
    fprintf(stderr, "usage: t331_device_tissue [--backend NAME] SCENE.json\n");
    return 2;
  }
  compare_parse_args(argc, argv);
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  fascia_model *m = NULL;
  const size_t length = strlen(scene);
  if (length > 5 && !strcmp(scene + length - 5, ".json")) {
#ifndef FASCIA_HAVE_PREP
    fprintf(stderr, "t331: this build has no prep stage; give a model file prepared from %s\n", scene);
    return 1;
#else
    fixture_run r;
    CHECK_OK(fixture_prep(ctx, scene, &r), ctx);
    m = r.model;
    r.model = NULL;
    fixture_free(&r);
#endif
  } else {
    CHECK_OK(fascia_model_load(ctx, scene, &m), ctx);
  }
  int kinds[3] = {0, 0, 0};
  for (int32_t i = 0; i < m->frame_count; ++i) ++kinds[m->frame_kind[i]];
  printf("prepared tissue: %d frames (%d free, %d fixed, %d prescribed), %d samples\n", (int)m->frame_count, kinds[0],
         kinds[1], kinds[2], (int)m->sample_count);
  CHECK(kinds[0] > 0 && kinds[1] > 0 && kinds[2] > 0);
  RUN(check_operators(ctx, "tissue", m, 21));
  fascia_solver_def def = fascia_solver_def_default();
  def.time_step = 0.01;
  def.newton_tolerance = 1e-10;
  def.cg_tolerance = 1e-4;
  RUN(check_run(ctx, "tissue, one step", m, def, 1, TOL_STEP, 1));
  def.cg_tolerance = 1e-3; // fewer CG iterations; Newton still converges to 1e-10
  RUN(check_run(ctx, "tissue, 100 steps (1 s of traction)", m, def, 100, TOL_STEPS, 0));
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
