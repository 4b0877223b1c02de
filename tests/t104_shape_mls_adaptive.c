// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// MLS weights whose linear basis follows the dimension of the frames
// (fascia_shape_mls_adaptive): on frames along a line and in a plane, in
// any orientation, the weights are finite where the 3-D basis of
// fascia_shape_mls is singular, are a partition of unity that reproduces
// linear fields along the span (sum w = 1, sum grad w = 0, sum w x = p on
// the span, sum x (x) grad w = the projector on the span), depend on p only
// through its projection on the span, and their gradients match central
// differences; on a volume they are fascia_shape_mls to the bit; bad input
// is refused.
#include <string.h>

#include "check.h"
#include "fascia/fascia.h"

static uint64_t rng_state = 4343;

static double uniform(double lo, double hi) {
  rng_state = rng_state * 6364136223846793005ULL + 1442695040888963407ULL;
  return lo + (hi - lo) * (double)(rng_state >> 11) * 0x1.0p-53;
}

// A random rotation (rows: an orthonormal frame) from a random unit quaternion.
static void random_rotation(double R[9]) {
  double q[4], n = 0;
  for (int k = 0; k < 4; ++k) {
    q[k] = uniform(-1, 1);
    n += q[k] * q[k];
  }
  n = sqrt(n);
  for (int k = 0; k < 4; ++k) q[k] /= n;
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double M[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                       2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                       2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  memcpy(R, M, sizeof M);
}

// The identities on the span given by its `dim` unit axes (rows of R).
static int check_span(const char *what, int n, const double *x, const double *w, const double *grad, const double *p,
                      const double *R, int dim, double scale) {
  double sum = 0, gsum[3] = {0, 0, 0}, px[3] = {0, 0, 0}, xg[9] = {0}, gscale = 0;
  for (int i = 0; i < n; ++i) {
    CHECK(isfinite(w[i]));
    sum += w[i];
    for (int r = 0; r < 3; ++r) {
      gsum[r] += grad[3 * i + r];
      px[r] += w[i] * x[3 * i + r];
      gscale = fmax(gscale, fabs(grad[3 * i + r]));
      for (int c = 0; c < 3; ++c) xg[3 * r + c] += x[3 * i + r] * grad[3 * i + c];
    }
  }
  const double tol = 1e-11;
  int bad = !(fabs(sum - 1) <= tol);
  for (int r = 0; r < 3; ++r) bad |= !(fabs(gsum[r]) <= tol * (1 + gscale));
  // along the span: sum w (a . x) = a . p
  for (int k = 0; k < dim; ++k) {
    double a_px = 0, a_p = 0;
    for (int r = 0; r < 3; ++r) a_px += R[3 * k + r] * px[r], a_p += R[3 * k + r] * p[r];
    bad |= !(fabs(a_px - a_p) <= tol * scale);
  }
  // sum x (x) grad = P = sum_k a_k a_k^T
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      double P = 0;
      for (int k = 0; k < dim; ++k) P += R[3 * k + r] * R[3 * k + c];
      bad |= !(fabs(xg[3 * r + c] - P) <= tol * (1 + gscale * scale));
    }
  // gradients lie in the span
  for (int i = 0; i < n; ++i) {
    double across = 0;
    for (int k = dim; k < 3; ++k) {
      double d = 0;
      for (int r = 0; r < 3; ++r) d += R[3 * k + r] * grad[3 * i + r];
      across = fmax(across, fabs(d));
    }
    bad |= !(across <= tol * (1 + gscale));
  }
  if (bad) fprintf(stderr, "%s (n = %d, dim %d): sum w - 1 = %.3g\n", what, n, dim, sum - 1);
  CHECK(!bad);
  return bad;
}

// Central differences of the weights against grad, and the weights at p
// moved across the span equal those at p.
static int check_derivatives(fascia_ctx *ctx, int n, const double *x, const double *p, double radius,
                              const double *w, const double *grad, const double *R, int dim) {
  double wp[64], wm[64], gp[192], gm[192], worst = 0, gscale = 0, moved = 0;
  for (int i = 0; i < 3 * n; ++i) gscale = fmax(gscale, fabs(grad[i]));
  const double h = 1e-6 * radius;
  for (int c = 0; c < 3; ++c) {
    double a[3] = {p[0], p[1], p[2]}, b[3] = {p[0], p[1], p[2]};
    a[c] += h;
    b[c] -= h;
    CHECK_OK(fascia_shape_mls_adaptive(ctx, n, x, a, radius, 0, wp, gp, NULL), ctx);
    CHECK_OK(fascia_shape_mls_adaptive(ctx, n, x, b, radius, 0, wm, gm, NULL), ctx);
    for (int i = 0; i < n; ++i) worst = fmax(worst, fabs((wp[i] - wm[i]) / (2 * h) - grad[3 * i + c]));
  }
  if (!(worst <= 1e-6 * (1 + gscale))) fprintf(stderr, "dim %d: finite differences off by %.3g\n", dim, worst);
  CHECK(worst <= 1e-6 * (1 + gscale));
  if (dim < 3) { // across the span, p moves, the weights do not
    double q[3];
    const double t = uniform(-2, 2);
    for (int r = 0; r < 3; ++r) q[r] = p[r] + t * radius * R[3 * (dim) + r];
    CHECK_OK(fascia_shape_mls_adaptive(ctx, n, x, q, radius, 0, wp, gp, NULL), ctx);
    for (int i = 0; i < n; ++i) moved = fmax(moved, fabs(wp[i] - w[i]) + fabs(gp[3 * i] - grad[3 * i]));
    CHECK(moved <= 1e-12 * (1 + gscale));
  }
  return 0;
}

// Frames on a line (dim 1), a plane (dim 2) or in a volume (dim 3), placed
// in the local axes and turned by R, shifted by c.
static int place(int dim, int n, const double R[9], const double c[3], double *x, double spread) {
  for (int i = 0; i < n; ++i) {
    double local[3] = {0, 0, 0};
    if (dim == 1) local[0] = spread * (i + uniform(-0.3, 0.3));
    else if (dim == 2) local[0] = spread * (i % 3 + uniform(-0.2, 0.2)), local[1] = spread * (i / 3 + uniform(-0.2, 0.2));
    else for (int k = 0; k < 3; ++k) local[k] = spread * uniform(0, 2);
    for (int r = 0; r < 3; ++r) {
      x[3 * i + r] = c[r];
      for (int k = 0; k < 3; ++k) x[3 * i + r] += R[3 * k + r] * local[k];
    }
  }
  return n;
}

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  int cases[4] = {0, 0, 0, 0};
  for (int trial = 0; trial < 300; ++trial) {
    const int dim = 1 + trial % 3, n = dim == 1 ? 2 + trial % 5 : dim == 2 ? 4 + trial % 6 : 6 + trial % 6;
    double R[9], c[3], x[3 * 16], p[3], w[16], grad[48];
    // axis-aligned every fifth trial: exactly collinear or coplanar frames
    if (trial % 5 == 0) {
      const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
      memcpy(R, I, sizeof I);
    } else {
      random_rotation(R);
    }
    const double spread = uniform(0.01, 3);
    for (int r = 0; r < 3; ++r) c[r] = uniform(-10, 10);
    place(dim, n, R, c, x, spread);
    // p inside the frames' span box, then moved off the span for lines and planes
    double local[3] = {0, 0, 0};
    local[0] = spread * uniform(0, dim == 1 ? n - 1 : 2);
    if (dim >= 2) local[1] = spread * uniform(0, dim == 2 ? (n - 1) / 3 : 2);
    if (dim == 3) local[2] = spread * uniform(0, 2);
    for (int k = dim; k < 3; ++k) local[k] = spread * uniform(-1, 1);
    for (int r = 0; r < 3; ++r) {
      p[r] = c[r];
      for (int k = 0; k < 3; ++k) p[r] += R[3 * k + r] * local[k];
    }
    double radius = 0;
    for (int i = 0; i < n; ++i) {
      double d2 = 0;
      for (int r = 0; r < 3; ++r) d2 += (x[3 * i + r] - p[r]) * (x[3 * i + r] - p[r]);
      radius = fmax(radius, sqrt(d2));
    }
    radius *= 1.5;
    int32_t found = 0;
    const fascia_status st = fascia_shape_mls_adaptive(ctx, n, x, p, radius, 0, w, grad, &found);
    if (dim == 3 && st == FASCIA_ERR_NUMERIC) continue; // a random cloud can be near-flat; not this test's subject
    CHECK_OK(st, ctx);
    CHECK(found == dim);
    if (found != dim) continue;
    if (check_span("adaptive MLS", n, x, w, grad, p, R, dim, 10 + spread * n)) continue;
    if (check_derivatives(ctx, n, x, p, radius, w, grad, R, dim)) return 1;
    ++cases[dim];
    if (dim == 3) { // the 3-D case is fascia_shape_mls to the bit
      double w3[16], g3[48];
      CHECK_OK(fascia_shape_mls(ctx, n, x, p, radius, w3, g3), ctx);
      CHECK(!memcmp(w3, w, (size_t)n * sizeof w[0]) && !memcmp(g3, grad, 3 * (size_t)n * sizeof grad[0]));
    } else if (trial % 5 == 0 && n >= 4) { // the 3-D basis is singular on these frames
      double w3[16], g3[48];
      CHECK(fascia_shape_mls(ctx, n, x, p, radius, w3, g3) == FASCIA_ERR_NUMERIC);
      fascia_ctx_clear(ctx);
    }
  }
  printf("adaptive MLS: %d lines, %d planes, %d volumes checked\n", cases[1], cases[2], cases[3]);
  CHECK(cases[1] >= 90 && cases[2] >= 90 && cases[3] >= 50);

  // nearly collinear: a spread across the line of 1e-9 of its length counts as a line
  {
    const double x[12] = {0, 0, 0, 1, 1e-9, 0, 2, 0, -1e-9, 3, 0, 0}, p[3] = {1.3, 0.4, 0.2};
    double w[4], grad[12];
    int32_t found = 0;
    CHECK_OK(fascia_shape_mls_adaptive(ctx, 4, x, p, 3, 0, w, grad, &found), ctx);
    CHECK(found == 1);
    // a flatness above that spread keeps it a line, below it the frames span a plane (and a volume)
    found = 0;
    (void)fascia_shape_mls_adaptive(ctx, 4, x, p, 3, 1e-12, w, grad, &found);
    CHECK(found == 3 || found == 2);
    fascia_ctx_clear(ctx);
  }
  // bad input
  {
    const double same[9] = {1, 2, 3, 1, 2, 3, 1, 2, 3}, line[6] = {0, 0, 0, 1, 0, 0}, p[3] = {0.5, 0, 0};
    double w[4], grad[12];
    CHECK(fascia_shape_mls_adaptive(ctx, 3, same, p, 1, 0, w, grad, NULL) == FASCIA_ERR_ARGUMENT);
    CHECK(fascia_shape_mls_adaptive(ctx, 1, line, p, 1, 0, w, grad, NULL) == FASCIA_ERR_ARGUMENT);
    CHECK(fascia_shape_mls_adaptive(ctx, 2, line, p, 0, 0, w, grad, NULL) == FASCIA_ERR_ARGUMENT);
    CHECK(fascia_shape_mls_adaptive(ctx, 2, line, p, 1, 1.5, w, grad, NULL) == FASCIA_ERR_ARGUMENT);
    CHECK(fascia_shape_mls_adaptive(ctx, 2, line, p, 1, NAN, w, grad, NULL) == FASCIA_ERR_ARGUMENT);
    // one frame of two inside the support: no line to fit
    const double far[3] = {-0.6, 0, 0};
    CHECK(fascia_shape_mls_adaptive(ctx, 2, line, far, 1, 0, w, grad, NULL) == FASCIA_ERR_NUMERIC);
    CHECK(strstr(fascia_ctx_message(ctx), "line") != NULL);
    // two frames on a line: the hat functions of linear interpolation
    CHECK_OK(fascia_shape_mls_adaptive(ctx, 2, line, p, 2, 0, w, grad, NULL), ctx);
    CHECK_NEAR(w[0], 0.5, 0, 1e-14);
    CHECK_NEAR(grad[0], -1, 0, 1e-13);
    CHECK_NEAR(grad[3], 1, 0, 1e-13);
  }
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
