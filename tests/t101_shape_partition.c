// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Shape functions are partitions of unity that reproduce linear fields
// (sum w = 1, sum grad w = 0, sum w x = p, sum x (x) grad w = I) for
// trilinear, barycentric and MLS weights; MLS gradients match central
// differences; degenerate input is refused; quadrature rules and the
// nearest-frame grid agree with independent oracles.
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "fascia/fascia.h"

static uint64_t rng_state = 12345;

static double uniform(double lo, double hi) {
  rng_state = rng_state * 6364136223846793005ULL + 1442695040888963407ULL;
  return lo + (hi - lo) * (double)(rng_state >> 11) * 0x1.0p-53;
}

// Checks the four linear-reproduction identities of n weights at p;
// `scale` is the size of the coordinates (the identities hold to rounding,
// ~1e-15 relative; 1e-12 leaves room for the conditioning of the MLS solve).
static void check_partition(const char *what, int n, const double *x, const double *w, const double *grad,
                            const double *p, double scale) {
  double sum = 0, gsum[3] = {0, 0, 0}, px[3] = {0, 0, 0}, id[9] = {0}, gscale = 0;
  for (int i = 0; i < n; ++i) {
    sum += w[i];
    for (int r = 0; r < 3; ++r) {
      gsum[r] += grad[3 * i + r];
      px[r] += w[i] * x[3 * i + r];
      gscale = fmax(gscale, fabs(grad[3 * i + r]));
      for (int c = 0; c < 3; ++c) id[3 * r + c] += x[3 * i + r] * grad[3 * i + c];
    }
  }
  const double tol = 1e-12;
  int bad = !(fabs(sum - 1) <= tol);
  for (int r = 0; r < 3; ++r) {
    bad |= !(fabs(gsum[r]) <= tol * (1 + gscale));
    bad |= !(fabs(px[r] - p[r]) <= tol * scale);
    for (int c = 0; c < 3; ++c) bad |= !(fabs(id[3 * r + c] - (r == c)) <= tol * (1 + gscale * scale));
  }
  if (bad)
    fprintf(stderr, "%s (n = %d): sum w - 1 = %.3g, sum grad = (%.3g %.3g %.3g), sum w x - p = (%.3g %.3g %.3g), "
                    "sum x grad^T - I diagonal (%.3g %.3g %.3g)\n",
            what, n, sum - 1, gsum[0], gsum[1], gsum[2], px[0] - p[0], px[1] - p[1], px[2] - p[2], id[0] - 1,
            id[4] - 1, id[8] - 1);
  CHECK(!bad);
}

static int test_hex(fascia_ctx *ctx) {
  for (int trial = 0; trial < 200; ++trial) {
    double lo[3], hi[3], p[3], x[24], w[8], grad[24];
    for (int d = 0; d < 3; ++d) {
      lo[d] = uniform(-5, 5);
      hi[d] = lo[d] + uniform(0.1, 3);
      // inside, and sometimes a little outside (extrapolation is still linear)
      p[d] = lo[d] + (hi[d] - lo[d]) * uniform(trial % 4 ? 0 : -0.2, trial % 4 ? 1 : 1.2);
    }
    for (int c = 0; c < 8; ++c)
      for (int d = 0; d < 3; ++d) x[3 * c + d] = (c >> d) & 1 ? hi[d] : lo[d];
    CHECK_OK(fascia_shape_hex(ctx, lo, hi, p, w, grad), ctx);
    check_partition("trilinear", 8, x, w, grad, p, 10);
  }
  // at a corner the weight is 1 there: the documented corner order
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 2, 3}, corner5[3] = {1, 0, 3};
  double w[8], grad[24];
  CHECK_OK(fascia_shape_hex(ctx, lo, hi, corner5, w, grad), ctx);
  for (int c = 0; c < 8; ++c) CHECK_NEAR(w[c], c == 5 ? 1 : 0, 0, 1e-15);
  const double flat_hi[3] = {1, 0, 1};
  CHECK(fascia_shape_hex(ctx, lo, flat_hi, corner5, w, grad) == FASCIA_ERR_ARGUMENT);
  return 0;
}

static int test_tet(fascia_ctx *ctx) {
  for (int trial = 0; trial < 200; ++trial) {
    double v[12], p[3], w[4], grad[12], b[4], bsum = 0;
    for (int k = 0; k < 12; ++k) v[k] = uniform(-2, 2);
    // a random point from random barycentric coordinates, some outside
    for (int j = 0; j < 4; ++j) bsum += (b[j] = uniform(trial % 5 ? 0 : -0.3, 1));
    for (int d = 0; d < 3; ++d) {
      p[d] = 0;
      for (int j = 0; j < 4; ++j) p[d] += b[j] / bsum * v[3 * j + d];
    }
    const fascia_status st = fascia_shape_tet(ctx, v, p, w, grad);
    if (st == FASCIA_ERR_ARGUMENT) continue; // a nearly flat random tet; refused by design
    CHECK_OK(st, ctx);
    check_partition("barycentric", 4, v, w, grad, p, 2);
    // the weights are the barycentric coordinates we started from
    // (rounding of the inverse, amplified by the tet's shape: 1e-9)
    for (int j = 0; j < 4; ++j) CHECK_NEAR(w[j], b[j] / bsum, 0, 1e-9);
  }
  const double flat[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0}, p[3] = {0.2, 0.2, 0};
  double w[4], grad[12];
  fascia_ctx_clear(ctx);
  CHECK(fascia_shape_tet(ctx, flat, p, w, grad) == FASCIA_ERR_ARGUMENT);
  CHECK(strstr(fascia_ctx_message(ctx), "degenerate") != NULL);
  return 0;
}

// 6 |volume| / longest edge^3 of the tetrahedron x[0..11].
static double flatness(const double *x) {
  double e[3][3], longest = 0;
  for (int j = 0; j < 3; ++j)
    for (int r = 0; r < 3; ++r) e[j][r] = x[3 * (j + 1) + r] - x[r];
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) {
      const double dx = x[3 * a] - x[3 * b], dy = x[3 * a + 1] - x[3 * b + 1], dz = x[3 * a + 2] - x[3 * b + 2];
      longest = fmax(longest, sqrt(dx * dx + dy * dy + dz * dz));
    }
  const double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                     e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
  return fabs(det) / (longest * longest * longest);
}

static int test_mls(fascia_ctx *ctx) {
  for (int n = 4; n <= 12; ++n)
    for (int trial = 0; trial < 40; ++trial) {
      double x[36], p[3], w[12], grad[36], centre[3], reach = 0;
      for (int d = 0; d < 3; ++d) centre[d] = uniform(-3, 3);
      for (int i = 0; i < n; ++i)
        for (int d = 0; d < 3; ++d) x[3 * i + d] = centre[d] + uniform(-1, 1);
      for (int d = 0; d < 3; ++d) p[d] = centre[d] + uniform(-0.5, 0.5);
      for (int i = 0; i < n; ++i) {
        const double dx = x[3 * i] - p[0], dy = x[3 * i + 1] - p[1], dz = x[3 * i + 2] - p[2];
        reach = fmax(reach, sqrt(dx * dx + dy * dy + dz * dz));
      }
      const double radius = 1.25 * reach;
      // with 4 frames MLS is the barycentric interpolation of their
      // tetrahedron, kernel or not: skip flat ones (6 V < 0.05 longest^3,
      // a regular tet has 0.71), whose weights are ill-conditioned
      double wt[4], gt[12];
      if (n == 4 && (fascia_shape_tet(NULL, x, p, wt, gt) != FASCIA_OK || flatness(x) < 0.05)) continue;
      CHECK_OK(fascia_shape_mls(ctx, n, x, p, radius, w, grad), ctx);
      check_partition("MLS", n, x, w, grad, p, 4);
      for (int i = 0; n == 4 && i < 4; ++i) { // the oracle, to rounding amplified by the shape (1e-12)
        CHECK_NEAR(w[i], wt[i], 0, 1e-12);
        for (int d = 0; d < 3; ++d) CHECK_NEAR(grad[3 * i + d], gt[3 * i + d], 0, 1e-12 * (1 + fabs(gt[3 * i + d])));
      }
      // central differences of the weights, radius and frames fixed: truncation
      // h^2 w''' ~ 1e-12, rounding eps / h ~ 1e-10 times the conditioning
      const double h = 1e-6;
      for (int d = 0; d < 3; ++d) {
        double pp[3] = {p[0], p[1], p[2]}, pm[3] = {p[0], p[1], p[2]}, wp[12], wm[12], scratch[36];
        pp[d] += h;
        pm[d] -= h;
        CHECK_OK(fascia_shape_mls(ctx, n, x, pp, radius, wp, scratch), ctx);
        CHECK_OK(fascia_shape_mls(ctx, n, x, pm, radius, wm, scratch), ctx);
        for (int i = 0; i < n; ++i) CHECK_NEAR(grad[3 * i + d], (wp[i] - wm[i]) / (2 * h), 0, 1e-6);
      }
    }
  // coplanar frames: the moment matrix is singular
  const double plane[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0.5, 0.5, 0, 0.2, 0.7, 0};
  const double p[3] = {0.4, 0.4, 0.3};
  double w[6], grad[18];
  fascia_ctx_clear(ctx);
  CHECK(fascia_shape_mls(ctx, 6, plane, p, 3, w, grad) == FASCIA_ERR_NUMERIC);
  CHECK(strstr(fascia_ctx_message(ctx), "MLS at point (0.4 0.4 0.3)") != NULL);
  CHECK(fascia_shape_mls(ctx, 3, plane, p, 3, w, grad) == FASCIA_ERR_ARGUMENT);
  // the kernel: 1 at the centre, 0 at and beyond the radius, decreasing
  CHECK_NEAR(fascia_shape_kernel(0), 1, 0, 0);
  CHECK(fascia_shape_kernel(1) == 0 && fascia_shape_kernel(2) == 0);
  CHECK(fascia_shape_kernel(0.3) > fascia_shape_kernel(0.6) && fascia_shape_kernel(0.99) > 0);
  return 0;
}

static int test_quadrature(fascia_ctx *ctx) {
  for (int n = 1; n <= 4; ++n) {
    double x[4], w[4];
    CHECK_OK(fascia_shape_gauss_legendre(ctx, n, x, w), ctx);
    // exact for degree 2n - 1: int_0^1 t^m = 1 / (m + 1), to rounding
    for (int m = 0; m <= 2 * n - 1; ++m) {
      double sum = 0;
      for (int k = 0; k < n; ++k) sum += w[k] * pow(x[k], m);
      CHECK_NEAR(sum, 1.0 / (m + 1), 0, 1e-15);
    }
    for (int k = 1; k < n; ++k) CHECK(x[k] > x[k - 1]);
  }
  double x[4], w[4];
  CHECK(fascia_shape_gauss_legendre(ctx, 5, x, w) == FASCIA_ERR_ARGUMENT);
  // tetrahedron rules: int l0^2 = 2! 3! / 5! = 1/10, int l0 l1 = 3! / 5! = 1/20
  // of the volume; the 4-point rule is exact for degree 2, the centroid for 1
  for (int n = 1; n <= 4; n += 3) {
    double b[16], q[4], one = 0, l0 = 0, l00 = 0, l01 = 0;
    CHECK_OK(fascia_shape_tet_quadrature(ctx, n, b, q), ctx);
    for (int k = 0; k < n; ++k) {
      CHECK_NEAR(b[4 * k] + b[4 * k + 1] + b[4 * k + 2] + b[4 * k + 3], 1, 0, 1e-15);
      one += q[k];
      l0 += q[k] * b[4 * k];
      l00 += q[k] * b[4 * k] * b[4 * k];
      l01 += q[k] * b[4 * k] * b[4 * k + 1];
    }
    CHECK_NEAR(one, 1, 0, 1e-15);
    CHECK_NEAR(l0, 0.25, 0, 1e-15);
    if (n == 4) {
      CHECK_NEAR(l00, 0.1, 0, 1e-15);
      CHECK_NEAR(l01, 0.05, 0, 1e-15);
    }
  }
  CHECK(fascia_shape_tet_quadrature(ctx, 2, x, w) == FASCIA_ERR_ARGUMENT);
  return 0;
}

typedef struct {
  double d2;
  int32_t i;
} ranked;

static int ranked_less(const void *a, const void *b) {
  const ranked *x = a, *y = b;
  if (x->d2 != y->d2) return x->d2 < y->d2 ? -1 : 1;
  return (x->i > y->i) - (x->i < y->i);
}

// The grid query against brute force, on random frames and on a regular
// lattice (many ties in distance), for points inside and outside the cloud.
static int test_nearest(fascia_ctx *ctx) {
  enum { N = 600 };
  static double x[3 * N];
  static ranked all[N];
  for (int lattice = 0; lattice < 2; ++lattice) {
    for (int i = 0; i < N; ++i)
      if (lattice) {
        x[3 * i] = i % 20 * 0.8;
        x[3 * i + 1] = i / 20 % 5 * 0.25;
        x[3 * i + 2] = i / 100 * 0.2;
      } else {
        x[3 * i] = uniform(0, 16);
        x[3 * i + 1] = uniform(-0.5, 0.5);
        x[3 * i + 2] = uniform(-0.5, 0.5);
      }
    fascia_frame_grid *grid = NULL;
    CHECK_OK(fascia_frame_grid_create(ctx, N, x, &grid), ctx);
    for (int trial = 0; trial < 300; ++trial) {
      const int32_t k = 1 + trial % 24;
      double p[3] = {uniform(-2, 18), uniform(-1, 1), uniform(-1, 1.5)};
      if (lattice && trial % 3 == 0) memcpy(p, x + 3 * (trial % N), sizeof p); // on a frame: ties
      for (int i = 0; i < N; ++i) {
        const double dx = x[3 * i] - p[0], dy = x[3 * i + 1] - p[1], dz = x[3 * i + 2] - p[2];
        all[i].d2 = dx * dx + dy * dy + dz * dz;
        all[i].i = i;
      }
      qsort(all, N, sizeof all[0], ranked_less);
      int32_t index[32];
      double radius;
      CHECK_OK(fascia_frame_grid_nearest(ctx, grid, p, k, index, &radius), ctx);
      // the k first by (distance, index), in ascending frame order
      int same = 1;
      for (int j = 0; j < k; ++j) {
        int found = 0;
        for (int q = 0; q < k; ++q) found |= all[q].i == index[j];
        same &= found;
        if (j > 0) same &= index[j] > index[j - 1];
      }
      CHECK(same);
      CHECK_NEAR(radius, FASCIA_SHAPE_SUPPORT_MARGIN * sqrt(all[k].d2), 1e-15, 0);
    }
    fascia_frame_grid_destroy(&grid);
    CHECK(grid == NULL);
  }
  fascia_frame_grid *grid = NULL;
  CHECK_OK(fascia_frame_grid_create(ctx, N, x, &grid), ctx);
  int32_t index[4];
  double radius, p[3] = {0, 0, 0};
  CHECK(fascia_frame_grid_nearest(ctx, grid, p, 0, index, &radius) == FASCIA_ERR_ARGUMENT);
  fascia_frame_grid_destroy(&grid);
  return 0;
}

int main(void) {
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&def, &ctx) != FASCIA_OK) return 1;
  int fail = test_hex(ctx) | test_tet(ctx) | test_mls(ctx) | test_quadrature(ctx) | test_nearest(ctx);
  fascia_ctx_destroy(&ctx);
  return fail | CHECK_RESULT();
}
