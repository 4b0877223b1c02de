// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The device solver against the CPU backend on one model (t330, t331):
// operators at a random deformed state, and whole runs. The backend is the
// one named by --backend ("emulated" by default); a backend that cannot run
// here makes the test skip (exit 77) with a line that says why.
#ifndef FASCIA_TESTS_DEVICE_COMPARE_H
#define FASCIA_TESTS_DEVICE_COMPARE_H

#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "fascia/organs.h"
#include "solve/backend.h"
#include "backend_arg.h"
#include "solve/solver_internal.h"
#include "random_model.h"

static const char *backend = "emulated"; // --backend

// Double precision against the CPU: the same operations in another order
// (reductions, FMA on a GPU) differ by rounding, which CG and Newton
// amplify but do not let grow.
#define TOL_OPERATOR 1e-11 // forces, products, blocks
#define TOL_STEP 1e-8      // states after one step or a static solve (Newton converged to 1e-10)
#define TOL_STEPS 1e-6     // states after 100 steps
#define TOL_FIXED 1e-7     // the paper's mode: 60 CG iterations amplify rounding

static inline double max_abs(const double *a, int64_t n) {
  double m = 0;
  for (int64_t k = 0; k < n; ++k) m = fabs(a[k]) > m ? fabs(a[k]) : m;
  return m;
}

// max |a - b| / max |b|, printed with its label
static inline double relative_difference(const char *label, const double *a, const double *b, int64_t n) {
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
static inline int make_device(fascia_ctx *ctx, const fascia_model *m, fascia_solver_def def, fascia_solver **out) {
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
static inline int check_operators(fascia_ctx *ctx, const char *name, const fascia_model *m, unsigned long long seed) {
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
  CHECK_OK(fascia_solver_backend_gradient(dev, x, q, b, &e_dev), ctx);
  CHECK(relative_difference("gradient", b, a, n) <= TOL_OPERATOR);
  CHECK(relative_difference("energy", &e_dev, &e_cpu, 1) <= TOL_OPERATOR);
  // stiffness product (symmetric Hessian), free DOFs
  fascia_system_hessian_apply(cpu->sys, v, a);
  for (int64_t k = 0; k < n; ++k)
    if (!cpu->mask[k]) a[k] = 0;
  CHECK_OK(fascia_solver_backend_hessian_apply(dev, v, b), ctx);
  CHECK(relative_difference("stiffness product", b, a, n) <= TOL_OPERATOR);
  // diagonal blocks (the block-Jacobi preconditioner's)
  fascia_system_hessian_diagonal(cpu->sys, a);
  CHECK_OK(fascia_solver_backend_hessian_diagonal(dev, b), ctx);
  CHECK(relative_difference("diagonal blocks", b, a, 36 * N) <= TOL_OPERATOR);
  free(x), free(q), free(v), free(a), free(b);
  fascia_solver_destroy(&cpu);
  fascia_solver_destroy(&dev);
  return 0;
}

// Runs `steps` steps (0: a static solve) on the CPU and on the device and
// compares the states; `repeat` also checks that a second device run gives
// the same bits.
static inline int check_run(fascia_ctx *ctx, const char *name, const fascia_model *m, fascia_solver_def def, int steps,
                     double tolerance, int repeat) {
  def.backend = "cpu";
  def.linear_solver = FASCIA_LINEAR_CG;
  // double products on the CPU as on the device (which has no float matrix):
  // the comparison is of the two codes, not of the matrix's rounding
  def.single_precision_matrix = 0;
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
  // the device answers output queries between its steps (sample_outputs,
  // energy_gradient): the repeated run, which asks none, must stay bit-identical
  double *between = malloc(2 * (size_t)m->sample_count * sizeof *between + 6 * (size_t)m->frame_count * sizeof *between + 1);
  for (int k = 0; k < (steps ? steps : 1); ++k) {
    if (steps) {
      CHECK_OK(fascia_solver_step(cpu, &rc_cpu), ctx);
      CHECK_OK(fascia_solver_step(dev, &rc_dev), ctx);
      if (again) {
        CHECK_OK(fascia_solver_step(again, NULL), ctx);
        fascia_solver_sample_strain(dev, between, between + m->sample_count);
        for (int32_t o = 0; o < m->organ_count; ++o)
          if (fascia_solver_organ_frame_count(dev, o) > 0)
            CHECK_OK(fascia_solver_organ_reaction(dev, o, between + 2 * m->sample_count, NULL), ctx);
      }
    } else {
      CHECK_OK(fascia_solver_solve_static(cpu, &rc_cpu), ctx);
      CHECK_OK(fascia_solver_solve_static(dev, &rc_dev), ctx);
      if (again) CHECK_OK(fascia_solver_solve_static(again, NULL), ctx);
    }
    cg_cpu += rc_cpu.cg_iterations;
    cg_dev += rc_dev.cg_iterations;
  }
  free(between);
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
  // what the results report per sample: strain, and stress with the patches' pressure
  const int64_t S = m->sample_count;
  double *ea = malloc(4 * S * sizeof *ea + 1), *eb = ea + S, *sa = ea + 2 * S, *sb = ea + 3 * S;
  fascia_solver_sample_strain(cpu, ea, sa);
  fascia_solver_sample_strain(dev, eb, sb);
  if (max_abs(ea, S) > 1e-8) { // a body in rigid motion has no strain to compare
    CHECK(relative_difference("sample strain", eb, ea, S) <= tolerance);
    CHECK(relative_difference("sample stress", sb, sa, S) <= tolerance);
  }
  if (again) {
    CHECK(!memcmp(fascia_solver_frame_positions(again), xb, 3 * N * sizeof(double)));
    CHECK(!memcmp(fascia_solver_frame_rotations(again), fascia_solver_frame_rotations(dev), 4 * N * sizeof(double)));
    printf("  repeated run: %s\n",
           memcmp(fascia_solver_frame_positions(again), xb, 3 * N * sizeof(double)) ? "DIFFERENT" : "bit-identical");
  }
  // the same queries, and the samples' positions, at a state the caller set
  // after the run (half the CPU's displacement): a device must answer from
  // that state, not from its last step's
  {
    double *xs = malloc(7 * N * sizeof *xs), *qs = xs + 3 * N, *pa = malloc(6 * S * sizeof *pa + 1), *pb = pa + 3 * S;
    for (int64_t k = 0; k < 3 * N; ++k) xs[k] = m->frame_position[k] + 0.5 * ua[k];
    memcpy(qs, fascia_solver_frame_rotations(cpu), 4 * N * sizeof *qs);
    CHECK_OK(fascia_solver_set_state(cpu, xs, qs, NULL), ctx);
    CHECK_OK(fascia_solver_set_state(dev, xs, qs, NULL), ctx);
    fascia_solver_sample_strain(cpu, ea, sa);
    fascia_solver_sample_strain(dev, eb, sb);
    fascia_solver_sample_positions(cpu, pa);
    fascia_solver_sample_positions(dev, pb);
    CHECK(relative_difference("sample positions at a set state", pb, pa, 3 * S) <= tolerance);
    if (max_abs(ea, S) > 1e-8) {
      CHECK(relative_difference("sample strain at a set state", eb, ea, S) <= tolerance);
      CHECK(relative_difference("sample stress at a set state", sb, sa, S) <= tolerance);
    }
    // and the tissue's reaction on each organ there, which the device
    // evaluates too (every frame's gradient, not the free DOFs')
    for (int32_t o = 0; o < m->organ_count; ++o) {
      const int32_t count = fascia_solver_organ_frame_count(cpu, o);
      if (count == 0) continue;
      double *ra = malloc(12 * (size_t)count * sizeof *ra), *rb = ra + 6 * count;
      CHECK_OK(fascia_solver_organ_reaction(cpu, o, ra, ra + 3 * count), ctx);
      CHECK_OK(fascia_solver_organ_reaction(dev, o, rb, rb + 3 * count), ctx);
      CHECK(relative_difference("organ reaction at a set state", rb, ra, 6 * count) <= tolerance);
      free(ra);
    }
    free(xs), free(pa);
  }
  free(ea);
  free(ua), free(ub);
  fascia_solver_destroy(&cpu);
  fascia_solver_destroy(&dev);
  fascia_solver_destroy(&again);
  return 0;
}

/// Reads --backend NAME from the command line ("emulated" without one).
static inline void compare_parse_args(int argc, char **argv) { backend = backend_arg(argc, argv, "emulated"); }

#define RUN(expr)                                                                                                     \
  do {                                                                                                                \
    const int rc_ = (expr);                                                                                           \
    if (rc_) {                                                                                                        \
      fascia_model_destroy(&m);                                                                                       \
      fascia_ctx_destroy(&ctx);                                                                                       \
      return rc_;                                                                                                     \
    }                                                                                                                 \
  } while (0)

#endif
