// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The Newton loop (newton.c) runs on any backend that keeps the contract of
// backend.h, with nothing of the CPU's behind it: a toy backend minimizing a
// quadratic of its own, Phi(d) = sum_k a_k (d_k - t_k)^2 / 2, in its own
// storage, is solved in one Newton iteration, with the operations called in
// the contract's order. A backend that never finds a descent ends in the
// loop's "no decrease" failure, adding its iterations to the report (the
// device loop added, the CPU loop overwrote). The watchdog: on Rosenbrock's
// function from (-1.2, 1), where a full Newton step raises Phi on the way,
// a backend that can save and restore its iterate converges in fewer
// iterations than the monotone search; on sqrt(1 + x^2) from x = 2, where
// full Newton steps run away to overflow, it goes back to the watched
// iterate and still converges. And the registry: the toy registered from
// this file (fascia_backend_register) is a backend like the others, chosen
// by name through the public API, solving a static problem; unknown names
// list the valid ones; a backend this build lacks says how to build it.
#include <stdlib.h>
#include <string.h>

#include "solve/backend.h"
#include "check.h"
#include "scenes.h"
#include "solve/solver_internal.h"

typedef struct toy {
  fascia_backend base;
  int64_t n;
  int descends; ///< 0: directions point uphill
  double *a, *t, *d, *d_trial, *p, *g, *g_trial;
  double *x, *q; ///< the state of the result (toy_finish), [3N], [4N]
  char calls[4096]; ///< the operations, a letter each
  int call_count;
  int nonlinear; ///< 0: the quadratic; 1: Rosenbrock in d0, d1; 2: sqrt(1 + d0^2) (both plus |d_rest|^2 / 2)
  double *saved;  ///< the saved iterate, or NULL: no save/restore
  const double *x_base, *q_base; ///< the step's anchor (the registered toy writes the state from it)
} toy;

// Phi, gradient and the 2x2 Hessian of the first two entries of the
// nonlinear toys (the rest: |d_k|^2 / 2, Hessian 1).
static double nonlinear_phi(int kind, const double *d, int64_t n, double *g, double *H) {
  double phi = 0;
  for (int64_t k = 2; k < n; ++k) phi += 0.5 * d[k] * d[k], g[k] = d[k];
  const double x = d[0], y = d[1];
  if (kind == 1) {
    phi += 100 * (y - x * x) * (y - x * x) + (1 - x) * (1 - x);
    g[0] = -400 * x * (y - x * x) - 2 * (1 - x), g[1] = 200 * (y - x * x);
    H[0] = 1200 * x * x - 400 * y + 2, H[1] = H[2] = -400 * x, H[3] = 200;
  } else {
    const double r = sqrt(1 + x * x);
    phi += r + 0.5 * y * y;
    g[0] = x / r, g[1] = y;
    H[0] = 1 / (r * r * r), H[1] = H[2] = 0, H[3] = 1;
  }
  return phi;
}

static void called(toy *T, char c) {
  if (T->call_count + 1 < (int)sizeof T->calls) T->calls[T->call_count++] = c, T->calls[T->call_count] = 0;
}

static fascia_status toy_begin(fascia_backend *b, const fascia_step_values *v, fascia_solve_report *r) {
  toy *T = (toy *)b;
  (void)r;
  called(T, 'B');
  memcpy(T->d, v->d, (size_t)T->n * sizeof(double));
  T->x_base = v->x_base, T->q_base = v->q_base;
  return FASCIA_OK;
}

static fascia_status toy_evaluate(fascia_backend *b, double alpha, int current, fascia_trial_values *out) {
  toy *T = (toy *)b;
  called(T, current ? 'C' : 'E');
  double phi = 0, gg = 0, *g = current ? T->g : T->g_trial;
  if (T->nonlinear) {
    double H[4];
    for (int64_t k = 0; k < T->n; ++k) T->d_trial[k] = current ? T->d[k] : T->d[k] + alpha * T->p[k];
    phi = nonlinear_phi(T->nonlinear, T->d_trial, T->n, g, H);
    for (int64_t k = 0; k < T->n; ++k) gg += g[k] * g[k];
    out->phi = phi, out->gradient_norm2 = gg, out->energy_size = fabs(phi);
    return isfinite(phi) && isfinite(gg) ? FASCIA_OK : FASCIA_ERR_NUMERIC;
  }
  for (int64_t k = 0; k < T->n; ++k) {
    T->d_trial[k] = current ? T->d[k] : T->d[k] + alpha * T->p[k];
    const double e = T->d_trial[k] - T->t[k];
    phi += 0.5 * T->a[k] * e * e;
    g[k] = T->a[k] * e;
    gg += g[k] * g[k];
  }
  out->phi = phi, out->gradient_norm2 = gg, out->energy_size = phi;
  return FASCIA_OK;
}

static fascia_status toy_prepare(fascia_backend *b, fascia_solve_report *r) {
  (void)r;
  called((toy *)b, 'P');
  return FASCIA_OK;
}

static fascia_status toy_direction(fascia_backend *b, double *shift, double *slope, fascia_solve_report *r) {
  toy *T = (toy *)b;
  (void)r;
  called(T, 'D');
  double s = 0;
  if (T->nonlinear) { // Newton on the 2x2 block, its shift raised until positive definite (as direct.c)
    double g[2], H[4], *scratch = T->g_trial;
    memcpy(scratch, T->g, (size_t)T->n * sizeof(double));
    nonlinear_phi(T->nonlinear, T->d, T->n, scratch, H);
    memcpy(T->g_trial, T->g, (size_t)T->n * sizeof(double));
    g[0] = T->g[0], g[1] = T->g[1];
    for (;;) {
      const double a = H[0] + *shift * fabs(H[0]), o = H[1], c = H[3] + *shift * fabs(H[3]), det = a * c - o * o;
      if (a > 0 && det > 0) {
        T->p[0] = -(c * g[0] - o * g[1]) / det, T->p[1] = -(a * g[1] - o * g[0]) / det;
        break;
      }
      *shift = *shift == 0 ? 1e-8 : 10 * *shift;
    }
    for (int64_t k = 2; k < T->n; ++k) T->p[k] = -T->g[k] / (1 + *shift);
    for (int64_t k = 0; k < T->n; ++k) s += T->p[k] * T->g[k];
    *slope = s;
    return FASCIA_OK;
  }
  for (int64_t k = 0; k < T->n; ++k) {
    T->p[k] = (T->descends ? -1 : 1) * T->g[k] / (T->a[k] * (1 + *shift));
    s += T->p[k] * T->g[k];
  }
  *slope = s;
  return FASCIA_OK;
}

static void toy_accept(fascia_backend *b) {
  toy *T = (toy *)b;
  called(T, 'A');
  memcpy(T->d, T->d_trial, (size_t)T->n * sizeof(double));
  memcpy(T->g, T->g_trial, (size_t)T->n * sizeof(double));
}

// The result from the toy's own arrays: its iterate, gradient and the
// state x = x_base + d, q = q_base rotated by d.
static fascia_status toy_finish(fascia_backend *b, fascia_step_result *result) {
  toy *T = (toy *)b;
  called(T, 'F');
  const int64_t N = T->n / 6;
  for (int64_t i = 0; i < N; ++i) {
    for (int c = 0; c < 3; ++c) T->x[3 * i + c] = T->x_base[3 * i + c] + T->d[6 * i + c];
    memcpy(T->q + 4 * i, T->q_base + 4 * i, 4 * sizeof(double));
    fascia_pt_quat_rotate_by(T->d + 6 * i + 3, T->q + 4 * i);
  }
  *result = (fascia_step_result){.x = T->x, .q = T->q, .d = T->d, .gradient = T->g, .first_inverted = -1};
  return FASCIA_OK;
}

static void toy_save(fascia_backend *b) {
  toy *T = (toy *)b;
  called(T, 'S');
  memcpy(T->saved, T->d, (size_t)T->n * sizeof(double));
}

static void toy_restore(fascia_backend *b) {
  toy *T = (toy *)b;
  called(T, 'R');
  memcpy(T->d, T->saved, (size_t)T->n * sizeof(double));
}

// The toy as a registered backend: made from the setup like any other, its
// quadratic over the model's 6N unknowns; it writes the state x = x_base +
// d, q = q_base rotated by d back.
static int toy_available(char *detail, size_t size) {
  if (detail) snprintf(detail, size, "a quadratic of its own (t370)");
  return 1;
}
static int toy_supports(const fascia_backend_setup *setup, char *why, size_t size) {
  (void)setup, (void)why, (void)size;
  return 1;
}
static void toy_destroy(fascia_backend *b) {
  toy *T = (toy *)b;
  if (!T) return;
  free(T->a), free(T->t), free(T->d), free(T->d_trial), free(T->p), free(T->g), free(T->g_trial);
  free(T->x), free(T->q);
  free(T);
}
static fascia_status toy_create(const fascia_backend_setup *setup, fascia_backend **out);
static const char *toy_describe(const fascia_backend *b) {
  (void)b;
  return "toy, a quadratic in its own storage";
}
static const fascia_backend_ops toy_registered_ops = {.name = "toy",
                                                      .automatic = 0,
                                                      .available = toy_available,
                                                      .supports = toy_supports,
                                                      .create = toy_create,
                                                      .destroy = toy_destroy,
                                                      .describe = toy_describe,
                                                      .begin = toy_begin,
                                                      .evaluate = toy_evaluate,
                                                      .prepare = toy_prepare,
                                                      .direction = toy_direction,
                                                      .accept = toy_accept,
                                                      .finish = toy_finish};
static fascia_status toy_create(const fascia_backend_setup *setup, fascia_backend **out) {
  toy *T = calloc(1, sizeof *T);
  FASCIA_CHECK(T, setup->ctx, FASCIA_ERR_MEMORY, "toy: out of memory");
  T->base.ops = &toy_registered_ops;
  T->n = 6 * (int64_t)setup->model->frame_count;
  T->descends = 1;
  double **arrays[9] = {&T->a, &T->t, &T->d, &T->d_trial, &T->p, &T->g, &T->g_trial, &T->x, &T->q};
  for (int k = 0; k < 9; ++k) *arrays[k] = calloc((size_t)T->n, sizeof(double));
  if (!T->a || !T->t || !T->d || !T->d_trial || !T->p || !T->g || !T->g_trial || !T->x || !T->q) {
    toy_destroy(&T->base);
    return FASCIA_FAIL(setup->ctx, FASCIA_ERR_MEMORY, "toy: out of memory");
  }
  // fixed DOFs stay where they are: their target is the start
  for (int64_t k = 0; k < T->n; ++k)
    T->a[k] = 1 + (double)(k % 7), T->t[k] = setup->mask[k] ? 0.01 * (double)((k % 5) - 2) : 0;
  *out = &T->base;
  return FASCIA_OK;
}

static const fascia_backend_ops toy_ops = {.name = "toy",
                                           .begin = toy_begin,
                                           .evaluate = toy_evaluate,
                                           .prepare = toy_prepare,
                                           .direction = toy_direction,
                                           .accept = toy_accept,
                                           .finish = toy_finish};
static const fascia_backend_ops toy_watchdog_ops = {.name = "toy",
                                                    .begin = toy_begin,
                                                    .evaluate = toy_evaluate,
                                                    .prepare = toy_prepare,
                                                    .direction = toy_direction,
                                                    .accept = toy_accept,
                                                    .save = toy_save,
                                                    .restore = toy_restore,
                                                    .finish = toy_finish};

// A nonlinear toy (kind 1 or 2) from (x0, y0), with or without save and
// restore; the report, and the solution in x.
static fascia_status nonlinear_solve(fascia_solver *S, int kind, int watchdog, double x0, double y0,
                                     fascia_solve_report *report, double *x) {
  toy T = {.base = {watchdog ? &toy_watchdog_ops : &toy_ops}, .n = 6 * (int64_t)S->frame_count, .descends = 1,
           .nonlinear = kind};
  double *buffers[10];
  for (int k = 0; k < 10; ++k) buffers[k] = calloc((size_t)T.n, sizeof(double));
  T.a = buffers[0], T.t = buffers[1], T.d = buffers[2], T.d_trial = buffers[3], T.p = buffers[4], T.g = buffers[5];
  T.g_trial = buffers[6], T.saved = buffers[7], T.x = buffers[8], T.q = buffers[9];
  fascia_backend *cpu = S->backend;
  S->backend = &T.base;
  memcpy(S->x_base, S->x, (size_t)T.n / 2 * sizeof(double)); // the anchor the result's state is taken from
  memcpy(S->q_base, S->q, (size_t)T.n / 6 * 4 * sizeof(double));
  memset(S->d, 0, (size_t)T.n * sizeof(double));
  S->d[0] = x0, S->d[1] = y0, S->d[2] = 0.5;
  memset(report, 0, sizeof *report);
  const fascia_step_values values = {1, 0, 0, 1, S->x_base, S->q_base, S->d, NULL}; // dynamic: d stays anchored
  const fascia_status st = fascia_newton_minimize(S, &values, 100, report);
  S->backend = cpu;
  x[0] = S->d[0], x[1] = S->d[1];
  printf("%s toy, %s: status %s, %d Newton iterations, %d watchdog returns, x = (%.12g, %.12g)\n",
         kind == 1 ? "Rosenbrock" : "sqrt(1 + x^2)", watchdog ? "watchdog" : "monotone", fascia_status_name(st),
         report->newton_iterations, report->watchdog_returns, x[0], x[1]);
  for (int k = 0; k < 10; ++k) free(buffers[k]);
  return st;
}

// One Newton solve of the toy on solver S (its model gives only the sizes
// and the load scale); 0 when it behaved as the contract says.
static int toy_solve(fascia_ctx *ctx, fascia_solver *S, int descends) {
  toy T = {.base = {&toy_ops}, .n = 6 * (int64_t)S->frame_count, .descends = descends};
  double *buffers[9];
  for (int k = 0; k < 9; ++k) buffers[k] = calloc((size_t)T.n, sizeof(double));
  T.a = buffers[0], T.t = buffers[1], T.d = buffers[2], T.d_trial = buffers[3], T.p = buffers[4], T.g = buffers[5];
  T.g_trial = buffers[6], T.x = buffers[7], T.q = buffers[8];
  for (int64_t k = 0; k < T.n; ++k) T.a[k] = 1 + (double)(k % 7), T.t[k] = 0.01 * (double)((k % 5) - 2);
  fascia_backend *cpu = S->backend;
  S->backend = &T.base;
  memcpy(S->x_base, S->x, (size_t)T.n / 2 * sizeof(double)); // the anchor the result's state is taken from
  memcpy(S->q_base, S->q, (size_t)T.n / 6 * 4 * sizeof(double));
  memset(S->d, 0, (size_t)T.n * sizeof(double));
  fascia_solve_report report;
  memset(&report, 0, sizeof report);
  report.newton_iterations = 5; // what earlier solves of the step did
  const fascia_step_values values = {0, 0, 0, 1, S->x_base, S->q_base, S->d, NULL};
  const fascia_status st = fascia_newton_minimize(S, &values, 20, &report);
  S->backend = cpu;
  printf("%s toy: status %s, calls %.80s%s (%d), %d Newton iterations in the report\n",
         descends ? "descending" : "uphill", fascia_status_name(st), T.calls, T.call_count > 80 ? "..." : "",
         T.call_count, report.newton_iterations);
  if (descends) {
    CHECK_OK(st, ctx);
    CHECK(report.converged && report.newton_iterations == 6);
    CHECK(!strcmp(T.calls, "BCPDEAF")); // begin, current, prepare, direction, trial, accept, finish
    double err = 0;
    for (int64_t k = 0; k < T.n; ++k) err = fmax(err, fabs(S->d[k] - T.t[k]));
    CHECK(err < 1e-15);
  } else {
    CHECK(st == FASCIA_ERR_NUMERIC && strstr(fascia_ctx_message(ctx), "found no decrease"));
    CHECK(report.newton_iterations == 5); // added to, not replaced
    CHECK(T.calls[T.call_count - 1] == 'F'); // the state goes back to the host even on failure
    fascia_ctx_clear(ctx);
  }
  for (int k = 0; k < 9; ++k) free(buffers[k]);
  return 0;
}

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  fascia_scene_beam_def bd = fascia_scene_beam_def_default();
  bd.frames[0] = 4, bd.frames[1] = 2, bd.frames[2] = 2;
  fascia_model *m = NULL;
  CHECK_OK(fascia_scene_beam_build(ctx, &bd, &m), ctx);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.backend = "cpu";
  fascia_solver *S = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &S), ctx);
  int failed = toy_solve(ctx, S, 1);
  failed |= toy_solve(ctx, S, 0);
  // the watchdog
  fascia_solve_report monotone, watched;
  double x[2];
  S->def.newton_tolerance = 1e-10;
  CHECK_OK(nonlinear_solve(S, 1, 0, -1.2, 1, &monotone, x), ctx);
  CHECK(monotone.converged && fabs(x[0] - 1) < 1e-8 && fabs(x[1] - 1) < 1e-8);
  CHECK_OK(nonlinear_solve(S, 1, 1, -1.2, 1, &watched, x), ctx);
  CHECK(watched.converged && fabs(x[0] - 1) < 1e-8 && fabs(x[1] - 1) < 1e-8);
  CHECK(watched.newton_iterations < monotone.newton_iterations && watched.watchdog_returns == 0);
  CHECK_OK(nonlinear_solve(S, 2, 1, 2, 0, &watched, x), ctx);
  CHECK(watched.converged && fabs(x[0]) < 1e-8 && watched.watchdog_returns > 0);
  fascia_solver_destroy(&S);

  // the registry: the toy registered from here, then used by name through
  // the public API; a second "toy", or one without its operations, refused
  CHECK_OK(fascia_backend_register(ctx, &toy_registered_ops), ctx);
  CHECK(fascia_backend_register(ctx, &toy_registered_ops) == FASCIA_ERR_ARGUMENT);
  printf("registered twice: %s\n", fascia_ctx_message(ctx));
  fascia_ctx_clear(ctx);
  fascia_backend_ops partial = toy_registered_ops;
  partial.name = "partial", partial.direction = NULL;
  CHECK(fascia_backend_register(ctx, &partial) == FASCIA_ERR_ARGUMENT);
  fascia_ctx_clear(ctx);
  sd.backend = "toy";
  sd.newton_tolerance = 1e-12;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &S), ctx);
  CHECK(!strcmp(fascia_solver_backend(S), "toy"));
  fascia_solve_report rep;
  CHECK_OK(fascia_solver_solve_static(S, &rep), ctx);
  double err = 0;
  const double *xs = fascia_solver_frame_positions(S);
  for (int32_t i = 0; i < m->frame_count; ++i)
    for (int c = 0; c < 3; ++c) {
      const int64_t k = 6 * (int64_t)i + c;
      const double t = m->frame_kind[i] == FASCIA_FRAME_FREE ? 0.01 * (double)((k % 5) - 2) : 0;
      err = fmax(err, fabs(xs[3 * i + c] - m->frame_position[3 * i + c] - t));
    }
  printf("registered toy through fascia_solver_solve_static: %d Newton iterations, converged %d, |x - target| %.3g\n",
         rep.newton_iterations, rep.converged, err);
  CHECK(rep.converged && rep.newton_iterations == 1 && err < 1e-14); // x_base + d rounds
  fascia_solver_destroy(&S);
  sd.newton_tolerance = fascia_solver_def_default().newton_tolerance;
  sd.backend = "vulkan";
  CHECK(fascia_solver_create(ctx, m, &sd, &S) == FASCIA_ERR_ARGUMENT);
  printf("unknown backend: %s\n", fascia_ctx_message(ctx));
  CHECK(strstr(fascia_ctx_message(ctx), "valid: auto, cuda, cpu, emulated, toy"));
  char detail[256];
  if (!fascia_backend_available("cuda", detail, sizeof detail)) {
    printf("cuda: %s\n", detail);
    // built without CUDA: how to build it; with CUDA but no GPU: why not
    CHECK(strstr(detail, "CUDA toolkit") || strstr(detail, "device") || strstr(detail, "driver"));
    sd.backend = "auto";
    CHECK_OK(fascia_solver_create(ctx, m, &sd, &S), ctx);
    printf("auto: %s\n", fascia_solver_device(S));
    CHECK(!strcmp(fascia_solver_backend(S), "cpu") && strstr(fascia_solver_device(S), "(auto: not on a GPU: "));
    fascia_solver_destroy(&S);
  }
  CHECK(fascia_backend_available("emulated", detail, sizeof detail) && fascia_backend_available("cpu", NULL, 0));
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return failed | CHECK_RESULT();
}
