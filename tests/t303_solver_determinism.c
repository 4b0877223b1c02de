// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The same run gives bit-identical frame states for 1 and 2 threads and from
// one run to the next: every per-frame sum goes through the reverse table in
// a fixed order and every dot product uses a fixed blocking. Checked for
// dynamic steps with matrix-free CG, assembled CG and the direct solver, and
// for a static solve. On every backend (`--backend`): the device backends
// (their kernels' sums in a fixed order too) run the matrix-free and static
// cases and skip the assembled and direct ones, which are the CPU's alone.
#include <stdlib.h>
#include <string.h>

#include "backend_arg.h"
#include "check.h"
#include "fascia/solver.h"
#include "scenes.h"

static const char *backend = "cpu";

// 64-bit FNV-1a over the bytes of the state
static unsigned long long hash_state(const fascia_solver *s, int frames) {
  unsigned long long h = 1469598103934665603ULL;
  const unsigned char *parts[3] = {(const unsigned char *)fascia_solver_frame_positions(s),
                                   (const unsigned char *)fascia_solver_frame_rotations(s),
                                   (const unsigned char *)fascia_solver_frame_velocities(s)};
  const size_t sizes[3] = {3 * sizeof(double), 4 * sizeof(double), 6 * sizeof(double)};
  for (int p = 0; p < 3; ++p)
    for (size_t k = 0; k < sizes[p] * (size_t)frames; ++k) h = (h ^ parts[p][k]) * 1099511628211ULL;
  return h;
}

static int run(fascia_ctx *ctx, const fascia_model *m, int threads, fascia_linear_solver linear, int assembled,
               int dynamic, unsigned long long *hash) {
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = backend;
  sd.threads = threads;
  sd.linear_solver = linear;
  sd.assembled = assembled;
  sd.time_step = 0.02;
  sd.newton_tolerance = 1e-8;
  if (!dynamic) backend_static_cg(&sd);
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  if (dynamic)
    for (int k = 0; k < 4; ++k) CHECK_OK(fascia_solver_step(s, NULL), ctx);
  else
    CHECK_OK(fascia_solver_solve_static(s, NULL), ctx);
  *hash = hash_state(s, m->frame_count);
  fascia_solver_destroy(&s);
  return 0;
}

int main(int argc, char **argv) {
  backend = backend_arg(argc, argv, "cpu");
  backend_skip_unless_available(backend);
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  // trilinear weights: 8 neighbours per sample, each frame summing over
  // the samples of up to 8 cells (the sums that could reorder)
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 6, def.frames[1] = 3, def.frames[2] = 3;
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &def, &m), ctx);
  const struct {
    fascia_linear_solver linear;
    int assembled, dynamic;
    const char *name;
  } cases[] = {{FASCIA_LINEAR_CG, 0, 1, "dynamic, matrix-free CG"},
               {FASCIA_LINEAR_CG, 1, 1, "dynamic, assembled CG"},
               {FASCIA_LINEAR_DIRECT, 0, 1, "dynamic, direct solver"},
               {FASCIA_LINEAR_AUTO, 0, 0, "static, auto"}};
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
    if ((cases[c].assembled || cases[c].linear == FASCIA_LINEAR_DIRECT) &&
        !backend_runs_cpu_case(backend, cases[c].name, "the device backends refuse it (CPU only)"))
      continue;
    unsigned long long h1, h2, h2again;
    if (run(ctx, m, 1, cases[c].linear, cases[c].assembled, cases[c].dynamic, &h1) ||
        run(ctx, m, 2, cases[c].linear, cases[c].assembled, cases[c].dynamic, &h2) ||
        run(ctx, m, 2, cases[c].linear, cases[c].assembled, cases[c].dynamic, &h2again))
      return 1;
    if (h1 != h2 || h2 != h2again)
      fprintf(stderr, "case %zu (%s): state hashes differ: 1 thread %016llx, 2 threads %016llx then %016llx\n", c,
              cases[c].name, h1, h2, h2again);
    CHECK(h1 == h2);
    CHECK(h2 == h2again);
  }
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
