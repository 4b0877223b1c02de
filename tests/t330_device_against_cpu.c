// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The device solver against the CPU backend (issue 4), for the backend named
// by --backend: "cuda" on an NVIDIA GPU (skipped, exit 77, where there is
// none), "emulated" (the same device code in host loops) anywhere.
//   - forces, energy, stiffness products and diagonal blocks at a random
//     deformed state of random models (1 to 6 neighbours per sample, rest
//     rotations not identity, coupling and smoothing on, fixed frames) and of
//     a meshless beam with 20 neighbours per sample;
//   - one full step, 100 steps and a static solve of the cantilever;
//   - the paper's fixed-cost mode (1 Newton iteration, 60 CG iterations);
//   - consistent mass, Jacobi and no preconditioner;
//   - a model larger than one block (320 frames), a frame with no samples,
//     no fixed frame at all (free fall);
//   - a run repeated gives bit-identical states (no atomics in any sum).
// Tolerances are relative to the largest entry of the CPU's result; the
// figures each case reached are printed.
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "device.h"
#include "random_model.h"
#include "scenes.h"

static const char *backend = "emulated";

// Double precision against the CPU: the same operations in another order
// (reductions, FMA on a GPU) differ by rounding, which CG and Newton
// amplify but do not let grow.
#define TOL_OPERATOR 1e-11 // forces, products, blocks
#define TOL_STEP 1e-8      // states after one step or a static solve (Newton converged to 1e-10)
#define TOL_STEPS 1e-6     // states after 100 steps
#define TOL_FIXED 1e-7     // the paper's mode: 60 CG iterations amplify rounding

static double max_abs(const double *a, int64_t n) {
  double m = 0;
  for (int64_t k = 0; k < n; ++k) m = fabs(a[k]) > m ? fabs(a[k]) : m;
  return m;
}

// max |a - b| / max |b|, printed with its label
static double relative_difference(const char *label, const double *a, const double *b, int64_t n) {
  double diff = 0;
  for (int64_t k = 0; k < n; ++k) {
    const double e = fabs(a[k] - b[k]);
    diff = e > diff || e != e ? e : diff;
  }
  const double scale = max_abs(b, n), rel = scale > 0 ? diff / scale : diff;
  printf("  %-44s %.3g\n", label, rel);
  return rel;
}

// Creates the device solver, or tells the caller to skip (no GPU here).
static int make_device(fascia_ctx *ctx, const fascia_model *m, fascia_solver_def def, fascia_solver **out) {
  def.backend = backend;
  const fascia_status st = fascia_solver_create(ctx, m, &def, out);
  if (st == FASCIA_OK) return 0;
  if (st == FASCIA_ERR_UNSUPPORTED) {
    printf("skipped: backend %s cannot run here: %s\n", backend, fascia_ctx_message(ctx));
    return TEST_SKIP;
  }
  fprintf(stderr, "creating the %s solver: %s\n", backend, fascia_ctx_message(ctx));
  return 1;
}

// Forces, energy, products and diagonal blocks at a random deformed state.
static int check_operators(fascia_ctx *ctx, const char *name, const fascia_model *m, unsigned long long seed) {
  printf("%s: %d frames, %d samples\n", name, (int)m->frame_count, (int)m->sample_count);
  fascia_solver_def def = fascia_solver_def_default();
  def.backend = "cpu";
  def.threads = 1;
  def.linear_solver = FASCIA_LINEAR_CG;
  fascia_solver *cpu = NULL, *dev = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &def, &cpu), ctx);
  const int rc = make_device(ctx, m, def, &dev);
  if (rc) {
    fascia_solver_destroy(&cpu);
    return rc;
  }
  const int64_t N = m->frame_count, n = 6 * N;
  double *x = malloc(3 * N * sizeof *x), *q = malloc(4 * N * sizeof *q), *v = malloc(n * sizeof *v);
  double *a = malloc(36 * N * sizeof *a), *b = malloc(36 * N * sizeof *b);
  unsigned long long st = seed;
  for (int64_t i = 0; i < N; ++i) {
    double t[3];
    for (int c = 0; c < 3; ++c) {
      x[3 * i + c] = m->frame_position[3 * i + c] + rnd_uniform(&st, -0.05, 0.05);
      t[c] = rnd_uniform(&st, -0.2, 0.2);
    }
    memcpy(q + 4 * i, m->frame_rotation + 4 * i, 4 * sizeof *q);
    fascia_pt_quat_rotate_by(t, q + 4 * i);
  }
  for (int64_t k = 0; k < n; ++k) v[k] = rnd_uniform(&st, -1, 1);
  // forces and energy
  double e_cpu, e_dev;
  fascia_system_set_state(cpu->sys, x, q);
  CHECK_OK(fascia_system_evaluate(cpu->sys, a, &e_cpu), ctx);
  for (int64_t k = 0; k < n; ++k)
    if (!cpu->mask[k]) a[k] = 0;
  CHECK_OK(fascia_device_gradient(dev, x, q, b, &e_dev), ctx);
  CHECK(relative_difference("gradient", b, a, n) <= TOL_OPERATOR);
  CHECK(relative_difference("energy", &e_dev, &e_cpu, 1) <= TOL_OPERATOR);
  // stiffness product (symmetric Hessian), free DOFs
  fascia_system_hessian_apply(cpu->sys, v, a);
  for (int64_t k = 0; k < n; ++k)
    if (!cpu->mask[k]) a[k] = 0;
  CHECK_OK(fascia_device_hessian_apply(dev, v, b), ctx);
  CHECK(relative_difference("stiffness product", b, a, n) <= TOL_OPERATOR);
  // diagonal blocks (the block-Jacobi preconditioner's)
  fascia_system_hessian_diagonal(cpu->sys, a);
  CHECK_OK(fascia_device_hessian_diagonal(dev, b), ctx);
  CHECK(relative_difference("diagonal blocks", b, a, 36 * N) <= TOL_OPERATOR);
  free(x), free(q), free(v), free(a), free(b);
  fascia_solver_destroy(&cpu);
  fascia_solver_destroy(&dev);
  return 0;
}

// Runs `steps` steps (0: a static solve) on the CPU and on the device and
// compares the states; `repeat` also checks that a second device run gives
// the same bits.
static int check_run(fascia_ctx *ctx, const char *name, const fascia_model *m, fascia_solver_def def, int steps,
                     double tolerance, int repeat) {
  def.backend = "cpu";
  def.linear_solver = FASCIA_LINEAR_CG;
  fascia_solver *cpu = NULL, *dev = NULL, *again = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &def, &cpu), ctx);
  int rc = make_device(ctx, m, def, &dev);
  if (!rc && repeat) rc = make_device(ctx, m, def, &again);
  if (rc) {
    fascia_solver_destroy(&cpu);
    fascia_solver_destroy(&dev);
    return rc;
  }
  fascia_solve_report rc_cpu, rc_dev;
  memset(&rc_cpu, 0, sizeof rc_cpu);
  memset(&rc_dev, 0, sizeof rc_dev);
  int cg_cpu = 0, cg_dev = 0;
  for (int k = 0; k < (steps ? steps : 1); ++k) {
    if (steps) {
      CHECK_OK(fascia_solver_step(cpu, &rc_cpu), ctx);
      CHECK_OK(fascia_solver_step(dev, &rc_dev), ctx);
      if (again) CHECK_OK(fascia_solver_step(again, NULL), ctx);
    } else {
      CHECK_OK(fascia_solver_solve_static(cpu, &rc_cpu), ctx);
      CHECK_OK(fascia_solver_solve_static(dev, &rc_dev), ctx);
      if (again) CHECK_OK(fascia_solver_solve_static(again, NULL), ctx);
    }
    cg_cpu += rc_cpu.cg_iterations;
    cg_dev += rc_dev.cg_iterations;
  }
  const int64_t N = m->frame_count;
  printf("%s (%d frames, %s): CG iterations cpu %d, %s %d\n", name, (int)N,
         steps ? "steps" : "static", cg_cpu, backend, cg_dev);
  // displacements, so that the tolerance is relative to the motion
  double *ua = malloc(3 * N * sizeof *ua), *ub = malloc(3 * N * sizeof *ub);
  const double *xa = fascia_solver_frame_positions(cpu), *xb = fascia_solver_frame_positions(dev);
  for (int64_t k = 0; k < 3 * N; ++k) {
    ua[k] = xa[k] - m->frame_position[k];
    ub[k] = xb[k] - m->frame_position[k];
  }
  CHECK(relative_difference("displacements", ub, ua, 3 * N) <= tolerance);
  CHECK(relative_difference("rotations", fascia_solver_frame_rotations(dev), fascia_solver_frame_rotations(cpu),
                            4 * N) <= tolerance);
  if (steps)
    CHECK(relative_difference("velocities", fascia_solver_frame_velocities(dev), fascia_solver_frame_velocities(cpu),
                              6 * N) <= tolerance);
  if (again) {
    CHECK(!memcmp(fascia_solver_frame_positions(again), xb, 3 * N * sizeof(double)));
    CHECK(!memcmp(fascia_solver_frame_rotations(again), fascia_solver_frame_rotations(dev), 4 * N * sizeof(double)));
    printf("  repeated run: %s\n",
           memcmp(fascia_solver_frame_positions(again), xb, 3 * N * sizeof(double)) ? "DIFFERENT" : "bit-identical");
  }
  free(ua), free(ub);
  fascia_solver_destroy(&cpu);
  fascia_solver_destroy(&dev);
  fascia_solver_destroy(&again);
  return 0;
}

#define RUN(expr)                                                                                                     \
  do {                                                                                                                \
    const int rc_ = (expr);                                                                                           \
    if (rc_) {                                                                                                        \
      fascia_model_destroy(&m);                                                                                       \
      fascia_ctx_destroy(&ctx);                                                                                       \
      return rc_;                                                                                                     \
    }                                                                                                                 \
  } while (0)

int main(int argc, char **argv) {
  for (int k = 1; k + 1 < argc; ++k)
    if (!strcmp(argv[k], "--backend")) backend = argv[k + 1];
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
    fascia_model_destroy(&m);
  }
  // many neighbours: meshless beam, 20 frames per sample
  fascia_scene_beam_def bd = fascia_scene_beam_def_default();
  bd.frames[0] = 8, bd.frames[1] = 3, bd.frames[2] = 3;
  bd.shape = FASCIA_SCENE_MESHLESS;
  bd.neighbours = 20;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  RUN(check_operators(ctx, "meshless beam, 20 neighbours", m, 7));
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
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
