// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The device solver against the CPU backend, for the backend named
// by --backend: "cuda" on an NVIDIA GPU (skipped, exit 77, where there is
// none), "emulated" (the same device code in host loops) anywhere.
//   - forces, energy, stiffness products and diagonal blocks at a random
//     deformed state of random models (1 to 6 neighbours per sample, rest
//     rotations not identity, coupling and smoothing on, fixed frames) and of
//     meshless beams with 20 and 80 neighbours per sample;
//   - one full step, 100 steps and a static solve of the cantilever;
//   - the paper's fixed-cost mode (1 Newton iteration, 60 CG iterations);
//   - consistent mass, Jacobi and no preconditioner;
//   - each stiffness kernel: all terms, no coupling, the paper's terms alone;
//   - a model larger than one block (320 frames), a frame with no samples,
//     no fixed frame at all (free fall);
//   - volumetric patches (mean dilatation): random models, and the cantilever
//     at nu = 0.49 in cell patches, in steps and static;
//   - their enhanced strain modes (sim/src/cpu/modes.h), the nine and the three
//     normal ones: random models with coupling and smoothing, both laws, the
//     tetrahedral cantilever with its nine (fascia beam's default) in steps
//     and static, the hexahedral one with its three normal ones static;
//   - every run's sample strain and stress (the patches' pressure included);
//   - rigid organs (the reduction P^T A P, sim/point/body.h): a rigid organ
//     hanging from the tissue under gravity, in steps and static, and a
//     free one under a load, with consistent mass;
//   - a run repeated gives bit-identical states (no atomics in any sum).
// Tolerances are relative to the largest entry of the CPU's result; the
// figures each case reached are printed.
#include "device_compare.h"
#include "organ_fixture.h"
#include "scenes.h"

int main(int argc, char **argv) {
  compare_parse_args(argc, argv);
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 2;
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  fascia_model *m = NULL;

  // random models: 1 to 6 neighbours per sample, both laws, coupling and
  // smoothing on, two fixed frames
  for (int law = 0; law < 2; ++law) {
    m = random_model(ctx, 11 + law, 12, 40, law, law ? 0.5 : 0, 0.3);
    CHECK(m != NULL);
    if (!m) return 1;
    m->frame_kind[0] = m->frame_kind[5] = FASCIA_FRAME_FIXED;
    RUN(check_operators(ctx, law ? "random model, Neo-Hookean" : "random model, StVK", m, 99 + law));
    random_model_patches(m); // the same in volumetric patches (mean dilatation)
    RUN(check_operators(ctx, law ? "random model in patches, Neo-Hookean" : "random model in patches, StVK", m,
                        97 + law));
    for (int32_t s = 0; s < m->sample_count; ++s) m->sample_modes[s] = FASCIA_MODES_NINE; // and their modes
    RUN(check_operators(ctx, law ? "random model, patches with modes, Neo-Hookean" : "random model, patches with modes, StVK",
                        m, 95 + law));
    for (int32_t s = 0; s < m->sample_count; ++s) m->sample_modes[s] = FASCIA_MODES_NORMAL; // the three normal ones
    RUN(check_operators(ctx, law ? "random model, patches with normal modes, Neo-Hookean"
                                 : "random model, patches with normal modes, StVK",
                        m, 93 + law));
    fascia_model_destroy(&m);
  }
  // many neighbours: meshless beams, 20 and 80 frames per sample (no
  // per-sample limit on the device)
  fascia_scene_beam_def bd = fascia_scene_beam_def_default();
  bd.frames[0] = 8, bd.frames[1] = 3, bd.frames[2] = 3;
  bd.shape = FASCIA_SCENE_MESHLESS;
  bd.neighbours = 20;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  RUN(check_operators(ctx, "meshless beam, 20 neighbours", m, 7));
  fascia_model_destroy(&m);
  bd.frames[0] = 10, bd.neighbours = 80, bd.samples_per_cell_dir = 1;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  RUN(check_operators(ctx, "meshless beam, 80 neighbours", m, 8));
  fascia_model_destroy(&m);

  // the cantilever (hex, 8 neighbours): steps, static, the paper's mode
  bd = fascia_scene_beam_def_default();
  bd.frames[0] = 10, bd.frames[1] = 2, bd.frames[2] = 2;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  RUN(check_operators(ctx, "cantilever", m, 3));
  fascia_solver_def def = fascia_solver_def_default();
  def.newton_tolerance = 1e-10;
  def.cg_tolerance = 1e-6;
  RUN(check_run(ctx, "cantilever, one step", m, def, 1, TOL_STEP, 1));
  fascia_solver_def loose = def; // fewer CG iterations per step: Newton still converges to 1e-10
  loose.cg_tolerance = 1e-3;
  RUN(check_run(ctx, "cantilever, 100 steps", m, loose, 100, TOL_STEPS, 0));
  fascia_solver_def statics = def;
  statics.newton_iterations = 100;
  statics.newton_tolerance = 1e-9;
  RUN(check_run(ctx, "cantilever, static", m, statics, 0, TOL_STEP, 0));
  fascia_solver_def paper = fascia_solver_def_default();
  paper.newton_iterations = 1;
  paper.require_convergence = 0;
  paper.cg_fixed = 1;
  paper.cg_iterations = 60;
  paper.line_search = 0;
  RUN(check_run(ctx, "cantilever, paper's mode, 5 steps", m, paper, 5, TOL_FIXED, 1));
  fascia_solver_def variant = def;
  variant.mass = FASCIA_MASS_CONSISTENT;
  variant.mass_damping = 0.5;
  RUN(check_run(ctx, "cantilever, consistent mass, damping", m, variant, 3, TOL_STEP, 0));
  variant = def;
  variant.precond = FASCIA_PRECOND_JACOBI;
  RUN(check_run(ctx, "cantilever, Jacobi", m, variant, 3, TOL_STEP, 0));
  variant.precond = FASCIA_PRECOND_NONE;
  RUN(check_run(ctx, "cantilever, no preconditioner", m, variant, 3, TOL_STEP, 0));
  // no fixed frame at all: free fall
  for (int32_t i = 0; i < m->frame_count; ++i) m->frame_kind[i] = FASCIA_FRAME_FREE;
  RUN(check_run(ctx, "free beam (no fixed frame)", m, def, 3, TOL_STEP, 0));
  fascia_model_destroy(&m);

  // nearly incompressible, in cell patches (mean dilatation): a few steps
  bd.volumetric_patch = FASCIA_SCENE_PATCH_CELL;
  bd.poisson_ratio = 0.49;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  RUN(check_operators(ctx, "cantilever in cell patches, nu 0.49", m, 4));
  RUN(check_run(ctx, "cantilever in cell patches, nu 0.49, 3 steps", m, def, 3, TOL_STEP, 0));
  // static (stiff, small deflection): nothing but the solve
  // evaluates, so the stress reported must take the patches' pressure at
  // the solution on either backend
  fascia_model_destroy(&m);
  bd.youngs_modulus = 4e6;
  bd.poisson_ratio = 0.3; // at 0.49 CG stalls short of the static tolerance
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  RUN(check_run(ctx, "stiff cantilever in cell patches, nu 0.3, static", m, statics, 0, TOL_STEP, 0));
  fascia_model_destroy(&m);
  // hexahedral with its cells' three normal modes (fascia beam's default for hex)
  bd.enhanced_modes = FASCIA_MODES_NORMAL;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  RUN(check_run(ctx, "stiff hex cantilever with normal modes, nu 0.3, static", m, statics, 0, TOL_STEP, 0));
  fascia_model_destroy(&m);
  // tetrahedral, its cells' patches with enhanced strain modes
  bd.shape = FASCIA_SCENE_TET;
  bd.enhanced_modes = FASCIA_MODES_NINE;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  RUN(check_run(ctx, "stiff tet cantilever with enhanced modes, nu 0.3, static", m, statics, 0, TOL_STEP, 0));
  fascia_model_destroy(&m);
  bd.youngs_modulus = fascia_scene_beam_def_default().youngs_modulus;
  bd.poisson_ratio = 0.45;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  RUN(check_operators(ctx, "tet cantilever with enhanced modes, nu 0.45", m, 6));
  RUN(check_run(ctx, "tet cantilever with enhanced modes, nu 0.45, 3 steps", m, def, 3, TOL_STEP, 0));
  fascia_model_destroy(&m);
  bd = fascia_scene_beam_def_default();
  bd.frames[0] = 10, bd.frames[1] = 2, bd.frames[2] = 2;

  // the paper's scheme (no rotation smoothing or coupling): the device's
  // lean stiffness kernel
  bd.rotation_smoothing = 0;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  RUN(check_operators(ctx, "cantilever, paper's scheme", m, 5));
  RUN(check_run(ctx, "cantilever, paper's scheme and mode", m, paper, 5, TOL_FIXED, 0));
  fascia_model_destroy(&m);
  bd = fascia_scene_beam_def_default();

  // larger than one block of 256 frames
  bd.frames[0] = 20, bd.frames[1] = 4, bd.frames[2] = 4;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  RUN(check_run(ctx, "cantilever 20x4x4", m, loose, 2, TOL_STEP, 0));
  fascia_model_destroy(&m);

  // a frame with no samples (fixed: free, it would have no stiffness)
  bd.frames[0] = 6, bd.frames[1] = 2, bd.frames[2] = 2;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  fascia_model *lonely = NULL;
  {
    fascia_model_sizes z = {m->frame_count + 1, m->sample_count, m->pair_count, 1, 0, 0, 0, 0, 0};
    CHECK_OK(fascia_model_alloc(ctx, &z, &lonely), ctx);
    const int64_t N = m->frame_count, S = m->sample_count, P = m->pair_count;
    memcpy(lonely->frame_position, m->frame_position, 3 * N * sizeof(double));
    memcpy(lonely->frame_rotation, m->frame_rotation, 4 * N * sizeof(double));
    memcpy(lonely->frame_kind, m->frame_kind, N * sizeof(int32_t));
    for (int c = 0; c < 3; ++c) lonely->frame_position[3 * N + c] = 100 + c;
    lonely->frame_rotation[4 * N] = 1;
    lonely->frame_kind[N] = FASCIA_FRAME_FIXED;
    memcpy(lonely->sample_position, m->sample_position, 3 * S * sizeof(double));
    memcpy(lonely->sample_volume, m->sample_volume, S * sizeof(double));
    memcpy(lonely->sample_offsets, m->sample_offsets, (S + 1) * sizeof(int32_t));
    memcpy(lonely->pair_frame, m->pair_frame, P * sizeof(int32_t));
    memcpy(lonely->pair_weight, m->pair_weight, P * sizeof(double));
    memcpy(lonely->pair_gradient, m->pair_gradient, 3 * P * sizeof(double));
    lonely->materials[0] = m->materials[0];
    memcpy(lonely->gravity, m->gravity, sizeof m->gravity);
    CHECK_OK(fascia_model_build_reverse(ctx, lonely), ctx);
  }
  fascia_model_destroy(&m);
  m = lonely;
  RUN(check_run(ctx, "a frame with no samples", m, def, 3, TOL_STEP, 0));
  fascia_model_destroy(&m);

  // rigid organs: organ A fixed, B a rigid body hanging from the tissue
  organ_fixture_def fd = organ_fixture_def_default();
  fd.gravity[2] = -9.81;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  fascia_solver_def organs = def;
  organs.time_step = 0.01;
  RUN(check_run(ctx, "rigid organ hanging, 5 steps", m, organs, 5, TOL_STEP, 1));
  organs.newton_iterations = 100;
  organs.newton_tolerance = 1e-9;
  // Under full gravity B hangs statically so far (6 of the tissue's 6 cm)
  // that the bent tissue has two equilibria of equal energy, swung to +y and
  // to -y, and rounding picks one: a change of the assembly's rounding took
  // the CPU to the other one, as a sideways gravity of 0.5 or 2 m/s^2 or ten
  // load steps did not prevent. A tenth of gravity gives one equilibrium, on
  // which the two codes are compared.
  m->gravity[2] = -0.981;
  RUN(check_run(ctx, "rigid organ hanging, static", m, organs, 0, TOL_STEP, 0));
  fascia_model_destroy(&m);
  // B free of the tissue (cut), under a load on one coupling frame
  fd = organ_fixture_def_default();
  fd.cut = 1;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  for (int32_t k = 0; k < m->coupling_count; ++k)
    if (m->coupling_organ[k] == 1) {
      m->frame_load[6 * m->coupling_frame[k] + 1] = 0.02;
      m->frame_load[6 * m->coupling_frame[k] + 2] = -0.01;
      break;
    }
  organs = def;
  organs.time_step = 0.01;
  organs.mass = FASCIA_MASS_CONSISTENT;
  RUN(check_run(ctx, "rigid organ under a load, consistent mass, 5 steps", m, organs, 5, TOL_STEP, 0));
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
