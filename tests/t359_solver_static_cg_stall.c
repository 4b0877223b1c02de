// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The automatic linear solver above the direct solver's bound (one
// factorization over 2e9 flops: CG by default), where CG stalls. A slender
// beam's large deflection needs about a thousand CG iterations per solve:
// on the 60x8x8 cantilever (8.2e9 flops) the first CG solve of a static
// solve stops at its 200-iteration cap, and the solve goes on with the
// direct solver, whose analysis was kept for this: it converges, within
// 0.5 % of the converged CalculiX tip, where capped CG alone does not
// converge. A later static solve of the same solver (from
// rest again) starts with the direct solver. A dynamic step (0.01 s)
// switches the same way, the next step direct at once, and a
// run resumed from a checkpoint after that first step takes the next two to
// the same bits (its kept factorization says CG had stalled); with one
// Newton iteration per step (the interactive preset, whose CG cap bounds a
// step's cost) it stays on CG. A compact block above the bound, whose CG
// converges within its cap, keeps CG and never factors.
#define _POSIX_C_SOURCE 200809L // mkstemp
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "beam_calculix.h"
#include "check.h"
#include "fascia/checkpoint.h"
#include "fascia/solver.h"
#include "scenes.h"

static fascia_solver *solver_of(fascia_ctx *ctx, const fascia_model *m) {
  fascia_solver_def sd = fascia_solver_def_default(); // auto: CG above the bound
  sd.backend = "cpu";
  sd.newton_iterations = 100; // fascia run --static's limit
  fascia_solver *s = NULL;
  const fascia_status st = fascia_solver_create(ctx, m, &sd, &s);
  CHECK(st == FASCIA_OK);
  return s;
}

static void print_report(const char *what, const fascia_solve_report *r) {
  printf("t359: %-34s %s, %d Newton iterations, %d CG iterations, %d factorizations, %s\n", what,
         r->direct ? "direct" : "cg", r->newton_iterations, r->cg_iterations, r->factorizations,
         r->converged ? "converged" : "NOT converged");
}

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;

  // the slender cantilever: CG stalls, the direct solver takes over
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.frames[0] = 60, def.frames[1] = 8, def.frames[2] = 8;
  def.volumetric_patch = FASCIA_SCENE_PATCH_AUTO; // fascia beam's rule: cell patches with their modes
  def.enhanced_modes = -1;
  const fascia_ccx_reference *ref = fascia_ccx_reference_find(&def);
  CHECK(ref != NULL);
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &def, &m), ctx);
  fascia_solver *s = m ? solver_of(ctx, m) : NULL;
  const int32_t tip = m ? fascia_model_find_probe(m, "tip") : -1;
  CHECK(tip >= 0);
  if (s && ref && tip >= 0) {
    fascia_solve_report r;
    CHECK_OK(fascia_solver_solve_static(s, &r), ctx);
    print_report("60x8x8 static:", &r);
    CHECK(r.converged && r.direct && r.factorizations > 0);
    CHECK(r.cg_iterations == fascia_solver_def_default().cg_iterations); // one CG solve, stopped at its cap
    fascia_real at[3];
    fascia_solver_probe_position(s, tip, at);
    const double error = 100 * (at[2] - m->probe_position[3 * tip + 2] - ref->tip_uz) / fabs(ref->tip_uz);
    printf("t359: tip uz error against CalculiX %+.3f %%\n", error);
    CHECK(fabs(error) < 0.5);
    // from rest again: the next static solve starts with the direct solver
    CHECK_OK(fascia_solver_set_state(s, m->frame_position, m->frame_rotation, NULL), ctx);
    CHECK_OK(fascia_solver_solve_static(s, &r), ctx);
    print_report("60x8x8 static from rest, again:", &r);
    CHECK(r.converged && r.direct && r.cg_iterations == 0 && r.factorizations > 0);
    // dynamic steps from rest: the first one's CG stalls too, the direct solver finishes it and takes the next
    CHECK_OK(fascia_solver_set_state(s, m->frame_position, m->frame_rotation, NULL), ctx);
    CHECK_OK(fascia_solver_step(s, &r), ctx);
    print_report("60x8x8 dynamic step from rest:", &r);
    CHECK(r.converged && r.direct && r.cg_iterations == fascia_solver_def_default().cg_iterations);
    char path[] = "/tmp/t359-XXXXXX";
    const int fd = mkstemp(path);
    CHECK(fd >= 0);
    if (fd >= 0) close(fd);
    CHECK_OK(fascia_checkpoint_save(ctx, s, 1, path), ctx);
    CHECK_OK(fascia_solver_step(s, &r), ctx);
    print_report("60x8x8 the next step:", &r);
    CHECK(r.converged && r.direct && r.cg_iterations == 0);
    CHECK_OK(fascia_solver_step(s, &r), ctx);
    // resumed from the checkpoint after the first step, a new solver takes the same two steps to the same bits
    fascia_solver *resumed = solver_of(ctx, m);
    int64_t step = 0;
    if (resumed) {
      CHECK_OK(fascia_checkpoint_load(ctx, resumed, path, &step), ctx);
      CHECK(step == 1);
      for (int k = 0; k < 2; ++k) CHECK_OK(fascia_solver_step(resumed, &r), ctx);
      print_report("60x8x8 resumed, its second step:", &r);
      const size_t bytes = 3 * sizeof(fascia_real) * (size_t)m->frame_count;
      CHECK(!memcmp(fascia_solver_frame_positions(resumed), fascia_solver_frame_positions(s), bytes));
      CHECK(fascia_solver_time(resumed) == fascia_solver_time(s));
    }
    fascia_solver_destroy(&resumed);
    remove(path);
  }
  fascia_solver_destroy(&s);
  // one Newton iteration per step, as the interactive preset runs (no convergence asked): CG's cap
  // bounds the step, no switch
  s = NULL;
  if (m) {
    fascia_solver_def sd = fascia_solver_def_default();
    sd.backend = "cpu";
    sd.newton_iterations = 1;
    sd.require_convergence = 0;
    CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
    fascia_solve_report r;
    CHECK_OK(fascia_solver_step(s, &r), ctx);
    print_report("60x8x8 one Newton iteration per step:", &r);
    CHECK(!r.direct && r.factorizations == 0 && r.cg_iterations == sd.cg_iterations);
  }
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);

  // a compact block above the bound: CG converges within its cap, no factorization
  def = fascia_scene_beam_def_default();
  def.length = 1;
  def.frames[0] = def.frames[1] = def.frames[2] = 14;
  CHECK_OK(fascia_scene_beam_build(ctx, &def, &m), ctx);
  s = m ? solver_of(ctx, m) : NULL;
  if (s) {
    fascia_solve_report r;
    CHECK_OK(fascia_solver_solve_static(s, &r), ctx);
    print_report("14x14x14 block static:", &r);
    CHECK(r.converged && !r.direct && r.factorizations == 0);
  }
  fascia_solver_destroy(&s);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
