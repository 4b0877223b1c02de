// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The banded Cholesky and CHOLMOD side by side on the same system: for each
// model (a model file, or a paper row by name) the tangent at rest plus the
// lumped mass / dt^2 of an implicit step, factored and solved by both, with
// the time of the analysis, the best of five factorizations and solves (one where it takes over a
// second; none for a band that would take minutes), and
// how far the two solutions are apart. Not a test: a benchmark that prints
// figures (tools/bench/README.md).
//
//   direct_solvers [--threads T] [--dt S] MODEL.h5|PAPER-ROW ...
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "assemble.h"
#include "banded.h"
#include "direct.h"
#include "fascia/solver.h"
#include "scenes.h"
#include "solver_internal.h"

#define REPEATS 5 // fewer where a factorization takes over a second
#define BAND_MAX_FLOPS 1e11 // a band costlier than this (n b^2: minutes) is not factored

static double best_of(double a, double b) { return a < b ? a : b; }

static int bench_model(fascia_ctx *ctx, const char *name, const fascia_model *m, int threads, double dt) {
  fascia_system *sys = NULL;
  if (fascia_system_create(ctx, m, threads, &sys) != FASCIA_OK) return 1;
  const int32_t N = m->frame_count;
  const int64_t n = 6 * (int64_t)N;
  fascia_bsr K;
  unsigned char *mask = calloc((size_t)n, 1);
  double *mass = calloc(36 * (size_t)N, sizeof(double)), *damping = calloc((size_t)n, sizeof(double));
  double *rhs = calloc((size_t)n, sizeof(double)), *xb = calloc((size_t)n, sizeof(double));
  double *xc = calloc((size_t)n, sizeof(double)), *work = calloc((size_t)n, sizeof(double));
  int free_unknowns = 0;
  for (int32_t i = 0; i < N; ++i)
    for (int c = 0; c < 6; ++c) free_unknowns += mask[6 * i + c] = m->frame_kind[i] == FASCIA_FRAME_FREE;
  fascia_system_set_rest(sys);
  fascia_system_mass_snapshot(sys);
  fascia_system_mass_lumped(sys, mass);
  if (fascia_system_evaluate(sys, rhs, NULL) != FASCIA_OK || fascia_bsr_create(ctx, m, &K) != FASCIA_OK) return 1;
  for (int64_t k = 0; k < n; ++k) rhs[k] = mask[k] ? -rhs[k] : 0;
  fascia_system_hessian_assemble(sys, &K);
  for (int32_t i = 0; i < N; ++i)
    for (int q = 0; q < 36; ++q) K.values[36 * (int64_t)K.diagonal[i] + q] += mass[36 * (int64_t)i + q] / (dt * dt);

  double t = fascia_now_ms();
  fascia_banded band;
  int have_band = fascia_banded_create(ctx, &K, (int64_t)2 << 30, &band) == FASCIA_OK;
  const double band_setup = fascia_now_ms() - t;
  const double band_cost = have_band ? fascia_banded_cost(&band) : 0;
  if (have_band && band_cost > BAND_MAX_FLOPS) {
    fascia_banded_destroy(&band);
    have_band = 0;
  }
  double band_factor = 1e300, band_solve = 1e300;
  for (int r = 0; have_band && r < REPEATS && (r == 0 || band_factor < 1000); ++r) {
    t = fascia_now_ms();
    if (!fascia_banded_factor(&band, &K, mask, damping, 0)) fprintf(stderr, "%s: banded: not positive definite\n", name);
    band_factor = best_of(band_factor, fascia_now_ms() - t);
    t = fascia_now_ms();
    fascia_banded_solve(&band, rhs, xb, work);
    band_solve = best_of(band_solve, fascia_now_ms() - t);
  }
  if (!have_band) fascia_ctx_clear(ctx);

  t = fascia_now_ms();
  fascia_direct *direct = NULL;
  if (fascia_direct_create(ctx, &K, mask, &direct) != FASCIA_OK) return 1;
  const double chol_setup = fascia_now_ms() - t;
  double chol_factor = 1e300, chol_solve = 1e300;
  for (int r = 0; r < REPEATS && (r == 0 || chol_factor < 1000); ++r) {
    t = fascia_now_ms();
    if (fascia_direct_factor(direct, ctx, &K, mask, damping, 0) != 1) fprintf(stderr, "%s: cholmod: not positive definite\n", name);
    chol_factor = best_of(chol_factor, fascia_now_ms() - t);
    t = fascia_now_ms();
    fascia_direct_solve(direct, rhs, xc);
    chol_solve = best_of(chol_solve, fascia_now_ms() - t);
  }
  double diff = 0, size = 0;
  for (int64_t k = 0; k < n; ++k) diff += (xb[k] - xc[k]) * (xb[k] - xc[k]), size += xc[k] * xc[k];
  char band_text[1024];
  if (have_band)
    snprintf(band_text, sizeof band_text, "%9.1f %9.2f %8.2f %9lld", band_setup, band_factor, band_solve,
             (long long)band.bandwidth);
  else
    snprintf(band_text, sizeof band_text, "%9s %9s %8.2g %9s", "-", band_cost > 0 ? "(n b^2:" : "(band", band_cost,
             band_cost > 0 ? "minutes)" : "too big)"); // too slow to wait for: its cost instead of a time
  printf("%-24s %6d %7d %s %9.1f %9.2f %8.2f %10.3g %9.2g %9.2g\n", name, (int)N, free_unknowns, band_text,
         chol_setup, chol_factor, chol_solve, fascia_direct_flops(direct),
         have_band ? sqrt(diff / (size > 0 ? size : 1)) : NAN,
         have_band ? band_factor / chol_factor : NAN);
  fflush(stdout);
  fascia_direct_destroy(&direct);
  if (have_band) fascia_banded_destroy(&band);
  fascia_bsr_destroy(&K);
  fascia_system_destroy(&sys);
  free(mask), free(mass), free(damping), free(rhs), free(xb), free(xc), free(work);
  return 0;
}

int main(int argc, char **argv) {
  int threads = 2, first = 1;
  double dt = 0.01;
  for (; first + 1 < argc && argv[first][0] == '-'; first += 2) {
    if (!strcmp(argv[first], "--threads")) threads = atoi(argv[first + 1]);
    else if (!strcmp(argv[first], "--dt")) dt = atof(argv[first + 1]);
  }
  if (first >= argc) {
    fprintf(stderr, "usage: direct_solvers [--threads T] [--dt S] MODEL.h5|PAPER-ROW ...\n");
    return 2;
  }
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  printf("%-24s %6s %7s %9s %9s %8s %9s %9s %9s %8s %10s %9s %9s\n", "model", "frames", "free", "band_ms", "factor",
         "solve", "bandwidth", "chol_ms", "factor", "solve", "chol_flops", "rel_diff", "speedup");
  printf("%-24s %6s %7s %9s %9s %8s %9s %9s %9s %8s %10s %9s %9s\n", "", "", "unknowns", "(setup)", "ms", "ms", "",
         "(analysis)", "ms", "ms", "", "", "factor");
  int failed = 0;
  for (int a = first; a < argc; ++a) {
    fascia_model *m = NULL;
    const fascia_scene_paper_row *row = fascia_scene_paper_find(argv[a]);
    const fascia_status st = row ? fascia_scene_paper_build(ctx, row, NULL, &m) : fascia_model_load(ctx, argv[a], &m);
    if (st != FASCIA_OK || bench_model(ctx, argv[a], m, threads, dt)) {
      fprintf(stderr, "direct_solvers: %s: %s\n", argv[a], fascia_ctx_message(ctx));
      fascia_ctx_clear(ctx);
      failed = 1;
    }
    fascia_model_destroy(&m);
  }
  fascia_ctx_destroy(&ctx);
  return failed;
}
