// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Shape functions (paper sec. 2.1): trilinear, barycentric and moving least
// squares weights with their rest-space gradients, quadrature rules, and a
// uniform grid for k-nearest-frame queries. Pure geometry: no model here.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/shape.h"
#include "util/status.h"

// A tetrahedron is flat when 6 |volume| / (longest edge)^3 is below this.
#define TET_FLAT_TOLERANCE 1e-12
// The MLS moment matrix is singular when a Cholesky pivot falls below this
// fraction of the kernel mass sum(phi) (the basis is scaled by the radius, so
// every entry is at most sum(phi)). Weights then lose ~eps / tolerance of
// their accuracy; 1e-9 keeps the partition of unity within 1e-9 even then.
#define MLS_PIVOT_TOLERANCE 1e-9

fascia_status fascia_shape_hex(fascia_ctx *ctx, const fascia_real lo[3], const fascia_real hi[3],
                               const fascia_real p[3], fascia_real w[8], fascia_real grad[24]) {
  FASCIA_CHECK(lo && hi && p && w && grad, ctx, FASCIA_ERR_ARGUMENT, "fascia_shape_hex: NULL argument");
  fascia_real u[2][3], du[2][3]; // u[0] = 1 - t, u[1] = t per axis; du their derivatives
  for (int d = 0; d < 3; ++d) {
    const fascia_real h = hi[d] - lo[d];
    FASCIA_CHECK(isfinite(h) && h > 0 && isfinite(p[d]), ctx, FASCIA_ERR_ARGUMENT,
                 "hexahedral cell [%g %g %g]-[%g %g %g]: side %d has length %g, expected > 0 (or the point is not "
                 "finite)",
                 lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], d, h);
    const fascia_real t = (p[d] - lo[d]) / h;
    u[0][d] = 1 - t;
    u[1][d] = t;
    du[0][d] = -1 / h;
    du[1][d] = 1 / h;
  }
  for (int c = 0; c < 8; ++c) {
    const int b0 = c & 1, b1 = (c >> 1) & 1, b2 = (c >> 2) & 1;
    w[c] = u[b0][0] * u[b1][1] * u[b2][2];
    grad[3 * c + 0] = du[b0][0] * u[b1][1] * u[b2][2];
    grad[3 * c + 1] = u[b0][0] * du[b1][1] * u[b2][2];
    grad[3 * c + 2] = u[b0][0] * u[b1][1] * du[b2][2];
  }
  return FASCIA_OK;
}

fascia_status fascia_shape_tet(fascia_ctx *ctx, const fascia_real vertex[12], const fascia_real p[3],
                               fascia_real w[4], fascia_real grad[12]) {
  FASCIA_CHECK(vertex && p && w && grad, ctx, FASCIA_ERR_ARGUMENT, "fascia_shape_tet: NULL argument");
  // T has columns e_j = v_j - v_0 (j = 1..3); lambda_1..3 = T^-1 (p - v0)
  fascia_real e[3][3], longest = 0;
  for (int j = 0; j < 3; ++j)
    for (int r = 0; r < 3; ++r) e[j][r] = vertex[3 * (j + 1) + r] - vertex[r];
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) {
      const fascia_real *va = vertex + 3 * a, *vb = vertex + 3 * b;
      const fascia_real dx = va[0] - vb[0], dy = va[1] - vb[1], dz = va[2] - vb[2];
      longest = fmax(longest, sqrt(dx * dx + dy * dy + dz * dz));
    }
  // rows of T^-1 are (e2 x e3, e3 x e1, e1 x e2) / det
  fascia_real inv[3][3];
  for (int j = 0; j < 3; ++j) {
    const fascia_real *a = e[(j + 1) % 3], *b = e[(j + 2) % 3];
    inv[j][0] = a[1] * b[2] - a[2] * b[1];
    inv[j][1] = a[2] * b[0] - a[0] * b[2];
    inv[j][2] = a[0] * b[1] - a[1] * b[0];
  }
  const fascia_real det = e[0][0] * inv[0][0] + e[0][1] * inv[0][1] + e[0][2] * inv[0][2];
  FASCIA_CHECK(isfinite(det) && isfinite(longest) && longest > 0 &&
                   fabs(det) > TET_FLAT_TOLERANCE * longest * longest * longest,
               ctx, FASCIA_ERR_ARGUMENT,
               "tetrahedron (%g %g %g), (%g %g %g), (%g %g %g), (%g %g %g) is degenerate (6 x volume %g, longest "
               "edge %g m); expected four vertices not in one plane",
               vertex[0], vertex[1], vertex[2], vertex[3], vertex[4], vertex[5], vertex[6], vertex[7], vertex[8],
               vertex[9], vertex[10], vertex[11], det, longest);
  const fascia_real d[3] = {p[0] - vertex[0], p[1] - vertex[1], p[2] - vertex[2]};
  fascia_real sum = 0;
  for (int r = 0; r < 3; ++r) grad[r] = 0;
  for (int j = 0; j < 3; ++j) {
    for (int r = 0; r < 3; ++r) {
      inv[j][r] /= det;
      grad[3 * (j + 1) + r] = inv[j][r];
      grad[r] -= inv[j][r];
    }
    w[j + 1] = inv[j][0] * d[0] + inv[j][1] * d[1] + inv[j][2] * d[2];
    sum += w[j + 1];
  }
  w[0] = 1 - sum;
  return FASCIA_OK;
}

fascia_real fascia_shape_kernel(fascia_real q) {
  if (!(q < 1)) return 0;
  if (q < 0) q = -q;
  const fascia_real a = 1 - q, a2 = a * a;
  return a2 * a2 * (4 * q + 1);
}

// Cholesky factor of the leading m x m block (m <= 4) of a symmetric matrix
// stored 4 x 4 (lower, row-major, stride 4). Returns the smallest pivot
// L_jj^2 relative to `scale`, or -1 when a pivot is not positive.
static fascia_real cholesky4(const fascia_real M[16], fascia_real L[16], fascia_real scale, int m) {
  fascia_real smallest = INFINITY;
  memset(L, 0, 16 * sizeof L[0]);
  for (int j = 0; j < m; ++j) {
    fascia_real d = M[5 * j];
    for (int k = 0; k < j; ++k) d -= L[4 * j + k] * L[4 * j + k];
    if (!(d > 0)) return -1;
    smallest = fmin(smallest, d / scale);
    L[5 * j] = sqrt(d);
    for (int i = j + 1; i < m; ++i) {
      fascia_real s = M[4 * i + j];
      for (int k = 0; k < j; ++k) s -= L[4 * i + k] * L[4 * j + k];
      L[4 * i + j] = s / L[5 * j];
    }
  }
  return smallest;
}

// Solves M x = b (leading m x m block) with the Cholesky factor L and one
// step of iterative refinement against M (keeps the residual, hence the
// partition of unity, at rounding level even for a moderately conditioned M).
static void cholesky4_solve(const fascia_real M[16], const fascia_real L[16], const fascia_real b[4],
                            fascia_real x[4], int m) {
  fascia_real rhs[4], y[4], dx[4];
  memcpy(rhs, b, sizeof rhs);
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < m; ++i) {
      fascia_real s = rhs[i];
      for (int k = 0; k < i; ++k) s -= L[4 * i + k] * y[k];
      y[i] = s / L[5 * i];
    }
    for (int i = m - 1; i >= 0; --i) {
      fascia_real s = y[i];
      for (int k = i + 1; k < m; ++k) s -= L[4 * k + i] * dx[k];
      dx[i] = s / L[5 * i];
    }
    if (pass == 0) {
      memcpy(x, dx, (size_t)m * sizeof x[0]);
      for (int i = 0; i < m; ++i) {
        rhs[i] = b[i];
        for (int k = 0; k < m; ++k) rhs[i] -= M[4 * i + k] * x[k];
      }
    } else {
      for (int i = 0; i < m; ++i) x[i] += dx[i];
    }
  }
}

// MLS with a linear basis. The basis is centred at p and scaled by the radius,
//   b(x) = (1, (x - c) / r) with c = p held fixed under differentiation
// (the weights do not depend on c: a shift is an invertible change of basis).
// With phi_i the kernel values and M = sum_i phi_i b_i b_i^T:
//   w_i       = phi_i b_i . a,                a   = M^-1 b(p) = M^-1 e_0
//   d_k w_i   = phi_i b_i . g_k + d_k phi_i b_i . a,
//   g_k       = M^-1 (e_{k+1} / r - (d_k M) a),  d_k M = sum_i d_k phi_i b_i b_i^T
// and d phi_i / dp = phi'(q) (p - x_i) / (|p - x_i| r) = -20 (1 - q)^3 (p - x_i) / r^2.

// Principal axes of n points: the eigenvectors of their covariance by
// cyclic Jacobi rotations, ordered by decreasing variance. axis: [9], row k
// the k-th unit axis; variance: [3], in the units of x squared.
static void principal_axes(int32_t n, const fascia_real *x, fascia_real axis[9], fascia_real variance[3]) {
  fascia_real c[3] = {0, 0, 0}, C[9] = {0}, V[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int32_t i = 0; i < n; ++i)
    for (int r = 0; r < 3; ++r) c[r] += x[3 * i + r] / n;
  for (int32_t i = 0; i < n; ++i)
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q) C[3 * r + q] += (x[3 * i + r] - c[r]) * (x[3 * i + q] - c[q]) / n;
  for (int sweep = 0; sweep < 32; ++sweep) {
    const fascia_real off = C[1] * C[1] + C[2] * C[2] + C[5] * C[5];
    if (!(off > 1e-30 * (C[0] * C[0] + C[4] * C[4] + C[8] * C[8]))) break;
    for (int a = 0; a < 2; ++a)
      for (int b = a + 1; b < 3; ++b) {
        const fascia_real cab = C[3 * a + b];
        if (cab == 0) continue;
        // the rotation in plane (a, b) that zeroes C_ab
        const fascia_real theta = (C[3 * b + b] - C[3 * a + a]) / (2 * cab);
        const fascia_real t = (theta >= 0 ? 1 : -1) / (fabs(theta) + sqrt(theta * theta + 1));
        const fascia_real cs = 1 / sqrt(t * t + 1), sn = t * cs;
        for (int k = 0; k < 3; ++k) { // C <- C J (columns a, b)
          const fascia_real ka = C[3 * k + a], kb = C[3 * k + b];
          C[3 * k + a] = cs * ka - sn * kb;
          C[3 * k + b] = sn * ka + cs * kb;
        }
        for (int k = 0; k < 3; ++k) { // C <- J^T C (rows a, b)
          const fascia_real ak = C[3 * a + k], bk = C[3 * b + k];
          C[3 * a + k] = cs * ak - sn * bk;
          C[3 * b + k] = sn * ak + cs * bk;
        }
        for (int k = 0; k < 3; ++k) { // V <- V J: columns of V are the axes
          const fascia_real ka = V[3 * k + a], kb = V[3 * k + b];
          V[3 * k + a] = cs * ka - sn * kb;
          V[3 * k + b] = sn * ka + cs * kb;
        }
      }
  }
  int order[3] = {0, 1, 2};
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
      if (C[4 * order[b]] > C[4 * order[a]]) {
        const int t = order[a];
        order[a] = order[b];
        order[b] = t;
      }
  for (int k = 0; k < 3; ++k) {
    variance[k] = fmax(C[4 * order[k]], 0);
    for (int r = 0; r < 3; ++r) axis[3 * k + r] = V[3 * r + order[k]];
  }
}

// MLS with a linear basis in a span of dim directions: b(x) = (1, E (x - c) / r)
// with the rows of E the span's axes, c = p held fixed, and the kernel on the
// distance within that span; with dim 3 and E the identity, the 3-D linear
// MLS of fascia_shape_mls (the same arithmetic, the same bits). The weights'
// gradients follow from the moment matrix's: g_k solves M g_k = E e_k / r -
// dM_k a, and the kernel's gradient is projected on the span.
static fascia_status mls_in_span(fascia_ctx *ctx, int32_t n, const fascia_real *frame, const fascia_real p[3],
                                 fascia_real radius, int dim, const fascia_real *E, fascia_real *w,
                                 fascia_real *grad) {
  const int m = dim + 1;
  fascia_real M[16] = {0}, dM[3][16], phi_sum = 0;
  memset(dM, 0, sizeof dM);
  int32_t inside = 0;
  for (int32_t i = 0; i < n; ++i) {
    fascia_real b[4] = {1, 0, 0, 0}, dist2 = 0;
    for (int a = 0; a < dim; ++a) {
      for (int r = 0; r < 3; ++r) b[a + 1] += E[3 * a + r] * (frame[3 * i + r] - p[r]);
      b[a + 1] /= radius;
      dist2 += b[a + 1] * b[a + 1];
    }
    const fascia_real q = sqrt(dist2), phi = fascia_shape_kernel(q);
    const fascia_real h = q < 1 ? 1 - q : 0, dphi_scale = 20 * h * h * h / radius;
    w[i] = phi;
    for (int r = 0; r < 3; ++r) {
      grad[3 * i + r] = 0;
      for (int a = 0; a < dim; ++a) grad[3 * i + r] += dphi_scale * b[a + 1] * E[3 * a + r];
    }
    if (phi <= 0) continue;
    ++inside;
    phi_sum += phi;
    for (int j = 0; j < m; ++j)
      for (int k = 0; k < m; ++k) {
        M[4 * j + k] += phi * b[j] * b[k];
        for (int r = 0; r < 3; ++r) dM[r][4 * j + k] += grad[3 * i + r] * b[j] * b[k];
      }
  }
  fascia_real L[16];
  const fascia_real pivot = inside >= m ? cholesky4(M, L, phi_sum, m) : -1;
  if (dim == 3)
    FASCIA_CHECK(pivot > MLS_PIVOT_TOLERANCE, ctx, FASCIA_ERR_NUMERIC,
                 "MLS at point (%.9g %.9g %.9g): the moment matrix of the %d frames within radius %g m is singular "
                 "(relative pivot %.3g, %d frames in the support); the frames are coplanar, collinear or too few: use "
                 "more neighbours or a larger radius",
                 p[0], p[1], p[2], (int)n, radius, pivot, (int)inside);
  FASCIA_CHECK(pivot > MLS_PIVOT_TOLERANCE, ctx, FASCIA_ERR_NUMERIC,
               "MLS at point (%.9g %.9g %.9g): the moment matrix of the %d frames within radius %g m along their "
               "%s is singular (relative pivot %.3g, %d frames in the support, %d needed); use more neighbours or a "
               "larger radius",
               p[0], p[1], p[2], (int)n, radius, dim == 1 ? "line" : "plane", pivot, (int)inside, m);
  const fascia_real e0[4] = {1, 0, 0, 0};
  fascia_real a[4], g[3][4];
  cholesky4_solve(M, L, e0, a, m);
  for (int r = 0; r < 3; ++r) {
    fascia_real rhs[4];
    for (int j = 0; j < m; ++j) {
      rhs[j] = j == 0 ? 0 : E[3 * (j - 1) + r] / radius;
      for (int k = 0; k < m; ++k) rhs[j] -= dM[r][4 * j + k] * a[k];
    }
    cholesky4_solve(M, L, rhs, g[r], m);
  }
  for (int32_t i = 0; i < n; ++i) {
    const fascia_real phi = w[i];
    if (phi <= 0) {
      w[i] = 0;
      grad[3 * i] = grad[3 * i + 1] = grad[3 * i + 2] = 0;
      continue;
    }
    fascia_real b[4] = {1, 0, 0, 0};
    for (int k = 0; k < dim; ++k) {
      for (int r = 0; r < 3; ++r) b[k + 1] += E[3 * k + r] * (frame[3 * i + r] - p[r]);
      b[k + 1] /= radius;
    }
    fascia_real ba = 0;
    for (int j = 0; j < m; ++j) ba += b[j] * a[j];
    w[i] = phi * ba;
    for (int r = 0; r < 3; ++r) {
      fascia_real bg = 0;
      for (int j = 0; j < m; ++j) bg += b[j] * g[r][j];
      grad[3 * i + r] = phi * bg + grad[3 * i + r] * ba;
    }
  }
  return FASCIA_OK;
}

fascia_status fascia_shape_mls(fascia_ctx *ctx, int32_t n, const fascia_real *frame, const fascia_real p[3],
                               fascia_real radius, fascia_real *w, fascia_real *grad) {
  FASCIA_CHECK(frame && p && w && grad, ctx, FASCIA_ERR_ARGUMENT, "fascia_shape_mls: NULL argument");
  FASCIA_CHECK(n >= 4, ctx, FASCIA_ERR_ARGUMENT,
               "MLS at point (%g %g %g): %d frames, a linear basis needs at least 4", p[0], p[1], p[2], (int)n);
  FASCIA_CHECK(isfinite(radius) && radius > 0, ctx, FASCIA_ERR_ARGUMENT,
               "MLS at point (%g %g %g): kernel radius %g, expected > 0", p[0], p[1], p[2], radius);
  static const fascia_real identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  return mls_in_span(ctx, n, frame, p, radius, 3, identity, w, grad);
}

fascia_status fascia_shape_mls_adaptive(fascia_ctx *ctx, int32_t n, const fascia_real *frame, const fascia_real p[3],
                                        fascia_real radius, fascia_real flatness, fascia_real *w, fascia_real *grad,
                                        int32_t *dimension) {
  FASCIA_CHECK(frame && p && w && grad, ctx, FASCIA_ERR_ARGUMENT, "fascia_shape_mls_adaptive: NULL argument");
  FASCIA_CHECK(n >= 2, ctx, FASCIA_ERR_ARGUMENT,
               "MLS at point (%g %g %g): %d frames, a linear basis needs at least 2 (on a line)", p[0], p[1], p[2],
               (int)n);
  FASCIA_CHECK(isfinite(radius) && radius > 0, ctx, FASCIA_ERR_ARGUMENT,
               "MLS at point (%g %g %g): kernel radius %g, expected > 0", p[0], p[1], p[2], radius);
  FASCIA_CHECK(isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]), ctx, FASCIA_ERR_ARGUMENT,
               "MLS: the point is not finite");
  if (flatness == 0) flatness = FASCIA_SHAPE_FLATNESS;
  FASCIA_CHECK(isfinite(flatness) && flatness > 0 && flatness < 1, ctx, FASCIA_ERR_ARGUMENT,
               "MLS at point (%g %g %g): flatness %g, expected in (0, 1) (0: the default %g)", p[0], p[1], p[2],
               flatness, FASCIA_SHAPE_FLATNESS);
  for (int32_t i = 0; i < 3 * n; ++i)
    FASCIA_CHECK(isfinite(frame[i]), ctx, FASCIA_ERR_ARGUMENT,
                 "MLS at point (%g %g %g): frame %d of %d has a non-finite coordinate", p[0], p[1], p[2],
                 (int)(i / 3), (int)n);
  fascia_real axis[9], variance[3];
  principal_axes(n, frame, axis, variance);
  FASCIA_CHECK(variance[0] > 0, ctx, FASCIA_ERR_ARGUMENT,
               "MLS at point (%g %g %g): the %d frames all sit at one place; expected frames spread along a line, a "
               "plane or a volume",
               p[0], p[1], p[2], (int)n);
  int dim = 1;
  while (dim < 3 && variance[dim] > flatness * flatness * variance[0]) ++dim;
  if (dimension) *dimension = dim;
  if (dim == 3) return fascia_shape_mls(ctx, n, frame, p, radius, w, grad);
  return mls_in_span(ctx, n, frame, p, radius, dim, axis, w, grad);
}

fascia_status fascia_shape_gauss_legendre(fascia_ctx *ctx, int n, fascia_real *point, fascia_real *weight) {
  FASCIA_CHECK(point && weight, ctx, FASCIA_ERR_ARGUMENT, "fascia_shape_gauss_legendre: NULL argument");
  FASCIA_CHECK(n >= 1 && n <= 4, ctx, FASCIA_ERR_ARGUMENT,
               "Gauss-Legendre rule with %d points: expected 1 to 4 points per direction", n);
  // nodes xi on [-1, 1] (ascending) and weights summing to 2
  fascia_real xi[4], om[4];
  switch (n) {
  case 1:
    xi[0] = 0;
    om[0] = 2;
    break;
  case 2:
    xi[0] = -1 / sqrt(3.0);
    xi[1] = -xi[0];
    om[0] = om[1] = 1;
    break;
  case 3:
    xi[0] = -sqrt(0.6);
    xi[1] = 0;
    xi[2] = -xi[0];
    om[0] = om[2] = 5.0 / 9.0;
    om[1] = 8.0 / 9.0;
    break;
  default: {
    const fascia_real inner = sqrt(3.0 / 7.0 - 2.0 / 7.0 * sqrt(1.2)), outer = sqrt(3.0 / 7.0 + 2.0 / 7.0 * sqrt(1.2));
    xi[0] = -outer;
    xi[1] = -inner;
    xi[2] = inner;
    xi[3] = outer;
    om[0] = om[3] = (18 - sqrt(30.0)) / 36;
    om[1] = om[2] = (18 + sqrt(30.0)) / 36;
  }
  }
  for (int k = 0; k < n; ++k) {
    point[k] = (1 + xi[k]) / 2;
    weight[k] = om[k] / 2;
  }
  return FASCIA_OK;
}

fascia_status fascia_shape_tet_quadrature(fascia_ctx *ctx, int n, fascia_real *bary, fascia_real *weight) {
  FASCIA_CHECK(bary && weight, ctx, FASCIA_ERR_ARGUMENT, "fascia_shape_tet_quadrature: NULL argument");
  FASCIA_CHECK(n == 1 || n == 4, ctx, FASCIA_ERR_ARGUMENT,
               "tetrahedron quadrature with %d points: expected 1 (centroid) or 4 (degree 2)", n);
  if (n == 1) {
    bary[0] = bary[1] = bary[2] = bary[3] = 0.25;
    weight[0] = 1;
    return FASCIA_OK;
  }
  // the 4-point degree-2 rule: a = (5 + 3 sqrt 5) / 20 at one vertex, b elsewhere
  const fascia_real a = (5 + 3 * sqrt(5.0)) / 20, b = (5 - sqrt(5.0)) / 20;
  for (int k = 0; k < 4; ++k) {
    for (int j = 0; j < 4; ++j) bary[4 * k + j] = j == k ? a : b;
    weight[k] = 0.25;
  }
  return FASCIA_OK;
}

// ---------------------------------------------------------------------------
// Nearest frames. Frames are bucketed in a uniform grid of about one frame
// per cell (counting sort: cell_start[cell] .. cell_start[cell+1]-1 index
// cell_item). A query visits rings of cells around p's cell, keeping the best
// k+1 by (distance, index), until the (k+1)-th is closer than any cell not
// yet visited.

struct fascia_frame_grid {
  int32_t count;
  fascia_real *position; // [3 count]
  fascia_real origin[3], cell;
  int32_t dim[3];
  int32_t *cell_start; // [cells + 1]
  int32_t *cell_item;  // [count]
};

int32_t fascia_frame_grid_count(const fascia_frame_grid *grid) { return grid ? grid->count : 0; }
const fascia_real *fascia_frame_grid_positions(const fascia_frame_grid *grid) { return grid ? grid->position : NULL; }

static int32_t grid_coord(const fascia_frame_grid *g, int d, fascia_real x) {
  const fascia_real t = floor((x - g->origin[d]) / g->cell);
  if (!(t > 0)) return 0;
  if (t >= g->dim[d] - 1) return g->dim[d] - 1;
  return (int32_t)t;
}

fascia_status fascia_frame_grid_create(fascia_ctx *ctx, int32_t count, const fascia_real *position,
                                       fascia_frame_grid **out) {
  FASCIA_CHECK(out, ctx, FASCIA_ERR_ARGUMENT, "fascia_frame_grid_create: NULL argument");
  *out = NULL;
  FASCIA_CHECK(position && count >= 1 && count <= FASCIA_MAX_COUNT, ctx, FASCIA_ERR_ARGUMENT,
               "frame grid: %d frames, expected at least 1", (int)count);
  fascia_real lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int32_t i = 0; i < count; ++i)
    for (int d = 0; d < 3; ++d) {
      const fascia_real x = position[3 * i + d];
      FASCIA_CHECK(isfinite(x), ctx, FASCIA_ERR_ARGUMENT, "frame grid: frame %d has a non-finite coordinate",
                   (int)i);
      lo[d] = fmin(lo[d], x);
      hi[d] = fmax(hi[d], x);
    }
  // cell side: about one frame per cell over the box, flat axes ignored
  fascia_real extent_max = 0;
  for (int d = 0; d < 3; ++d) extent_max = fmax(extent_max, hi[d] - lo[d]);
  fascia_real cell = extent_max > 0 ? extent_max : 1;
  for (int pass = 0; pass < 2; ++pass) {
    fascia_real volume = 1;
    int dims = 0;
    for (int d = 0; d < 3; ++d)
      if (hi[d] - lo[d] > 1e-9 * cell) {
        volume *= hi[d] - lo[d];
        ++dims;
      }
    if (dims > 0) cell = fmax(cell * 1e-6, pow(volume / count, 1.0 / dims));
  }
  fascia_frame_grid *g = calloc(1, sizeof *g);
  FASCIA_CHECK(g, ctx, FASCIA_ERR_MEMORY, "frame grid: out of memory");
  g->count = count;
  g->cell = cell;
  int64_t cells = 1;
  for (int d = 0; d < 3; ++d) {
    g->origin[d] = lo[d];
    const fascia_real n = floor((hi[d] - lo[d]) / cell) + 1;
    g->dim[d] = (int32_t)fmin(n, 1024);
    cells *= g->dim[d];
  }
  // a degenerate spread (cell tiny against the extent) could ask for too many
  // cells; coarsen until there are at most 8 per frame
  while (cells > 8 * (int64_t)count + 64) {
    g->cell *= 2;
    cells = 1;
    for (int d = 0; d < 3; ++d) {
      g->dim[d] = (int32_t)fmin(floor((hi[d] - lo[d]) / g->cell) + 1, 1024);
      cells *= g->dim[d];
    }
  }
  g->position = fascia_calloc(3 * (int64_t)count, sizeof(fascia_real));
  g->cell_start = fascia_calloc(cells + 1, sizeof(int32_t));
  g->cell_item = fascia_calloc(count, sizeof(int32_t));
  if (!g->position || !g->cell_start || !g->cell_item) {
    fascia_frame_grid_destroy(&g);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "frame grid: out of memory for %d frames", (int)count);
  }
  memcpy(g->position, position, 3 * (size_t)count * sizeof(fascia_real));
  for (int32_t i = 0; i < count; ++i) {
    const fascia_real *x = position + 3 * i;
    const int64_t c = grid_coord(g, 0, x[0]) + g->dim[0] * ((int64_t)grid_coord(g, 1, x[1]) +
                                                             g->dim[1] * (int64_t)grid_coord(g, 2, x[2]));
    g->cell_start[c + 1]++;
  }
  for (int64_t c = 0; c < cells; ++c) g->cell_start[c + 1] += g->cell_start[c];
  for (int32_t i = 0; i < count; ++i) { // ascending frames within a cell
    const fascia_real *x = position + 3 * i;
    const int64_t c = grid_coord(g, 0, x[0]) + g->dim[0] * ((int64_t)grid_coord(g, 1, x[1]) +
                                                             g->dim[1] * (int64_t)grid_coord(g, 2, x[2]));
    g->cell_item[g->cell_start[c]++] = i;
  }
  for (int64_t c = cells; c > 0; --c) g->cell_start[c] = g->cell_start[c - 1];
  g->cell_start[0] = 0;
  *out = g;
  return FASCIA_OK;
}

void fascia_frame_grid_destroy(fascia_frame_grid **grid) {
  if (!grid || !*grid) return;
  free((*grid)->position);
  free((*grid)->cell_start);
  free((*grid)->cell_item);
  free(*grid);
  *grid = NULL;
}

typedef struct candidate {
  fascia_real dist2;
  int32_t index;
} candidate;

static int candidate_less(const candidate *a, const candidate *b) {
  return a->dist2 < b->dist2 || (a->dist2 == b->dist2 && a->index < b->index);
}

// Inserts c into best[0..*used) sorted by (dist2, index), keeping at most cap.
static void candidate_insert(candidate *best, int32_t *used, int32_t cap, candidate c) {
  if (*used == cap && !candidate_less(&c, &best[cap - 1])) return;
  int32_t k = *used < cap ? (*used)++ : cap - 1;
  while (k > 0 && candidate_less(&c, &best[k - 1])) {
    best[k] = best[k - 1];
    --k;
  }
  best[k] = c;
}

static int int32_less(const void *a, const void *b) {
  const int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
  return (x > y) - (x < y);
}

// Visits the cells at Chebyshev ring distance `ring` from cell c.
static void visit_ring(const fascia_frame_grid *g, const int32_t c[3], int32_t ring, const fascia_real p[3],
                       candidate *best, int32_t *used, int32_t cap) {
  int32_t lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = c[d] - ring < 0 ? 0 : c[d] - ring;
    hi[d] = c[d] + ring > g->dim[d] - 1 ? g->dim[d] - 1 : c[d] + ring;
  }
  for (int32_t z = lo[2]; z <= hi[2]; ++z)
    for (int32_t y = lo[1]; y <= hi[1]; ++y)
      for (int32_t x = lo[0]; x <= hi[0]; ++x) {
        const int32_t dz = abs(z - c[2]), dy = abs(y - c[1]), dx = abs(x - c[0]);
        if (dx != ring && dy != ring && dz != ring) continue; // inner rings already seen
        const int64_t cell = x + g->dim[0] * ((int64_t)y + g->dim[1] * (int64_t)z);
        for (int32_t k = g->cell_start[cell]; k < g->cell_start[cell + 1]; ++k) {
          const int32_t i = g->cell_item[k];
          const fascia_real *xi = g->position + 3 * i;
          const fascia_real ex = xi[0] - p[0], ey = xi[1] - p[1], ez = xi[2] - p[2];
          const candidate cand = {ex * ex + ey * ey + ez * ez, i};
          candidate_insert(best, used, cap, cand);
        }
      }
}

fascia_status fascia_frame_grid_nearest(fascia_ctx *ctx, const fascia_frame_grid *g, const fascia_real p[3],
                                        int32_t k, int32_t *index, fascia_real *radius) {
  FASCIA_CHECK(g && p && index && radius, ctx, FASCIA_ERR_ARGUMENT, "fascia_frame_grid_nearest: NULL argument");
  FASCIA_CHECK(k >= 1 && k <= g->count && k <= FASCIA_SHAPE_MAX_NEIGHBOURS, ctx, FASCIA_ERR_ARGUMENT,
               "nearest frames to (%g %g %g): %d asked, expected 1 .. %d (frames) and at most %d", p[0], p[1], p[2],
               (int)k, (int)g->count, FASCIA_SHAPE_MAX_NEIGHBOURS);
  FASCIA_CHECK(isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]), ctx, FASCIA_ERR_ARGUMENT,
               "nearest frames: the query point is not finite");
  candidate best[FASCIA_SHAPE_MAX_NEIGHBOURS + 1];
  const int32_t cap = k < g->count ? k + 1 : k;
  int32_t used = 0, c[3];
  for (int d = 0; d < 3; ++d) c[d] = grid_coord(g, d, p[d]);
  int32_t ring_max = 0;
  for (int d = 0; d < 3; ++d) {
    ring_max = c[d] > ring_max ? c[d] : ring_max;
    ring_max = g->dim[d] - 1 - c[d] > ring_max ? g->dim[d] - 1 - c[d] : ring_max;
  }
  for (int32_t ring = 0; ring <= ring_max; ++ring) {
    visit_ring(g, c, ring, p, best, &used, cap);
    if (used < cap) continue;
    // distance from p to the nearest cell not yet visited
    fascia_real bound = INFINITY;
    for (int d = 0; d < 3; ++d) {
      if (c[d] - ring > 0) bound = fmin(bound, p[d] - (g->origin[d] + (c[d] - ring) * g->cell));
      if (c[d] + ring < g->dim[d] - 1) bound = fmin(bound, g->origin[d] + (c[d] + ring + 1) * g->cell - p[d]);
    }
    if (bound == INFINITY || (bound > 0 && best[cap - 1].dist2 <= bound * bound)) break;
  }
  const fascia_real reach = sqrt(best[cap - 1].dist2);
  FASCIA_CHECK(reach > 0, ctx, FASCIA_ERR_ARGUMENT,
               "nearest frames to (%g %g %g): the %d nearest frames all sit at the point; no kernel radius fits",
               p[0], p[1], p[2], (int)cap);
  for (int32_t j = 0; j < k; ++j) index[j] = best[j].index;
  qsort(index, (size_t)k, sizeof index[0], int32_less);
  *radius = FASCIA_SHAPE_SUPPORT_MARGIN * reach;
  return FASCIA_OK;
}

void fascia_shape_section_moduli(int dimension, fascia_real youngs_modulus, fascia_real poisson_ratio,
                                 fascia_real *section_youngs_modulus, fascia_real *section_poisson_ratio) {
  const fascia_real E = youngs_modulus, nu = poisson_ratio;
  // mu kept; lambda' + 2 mu = E (strand) or lambda' = E nu / (1 - nu^2) (sheet)
  fascia_real nu_s = nu;
  if (dimension == 1) nu_s = nu / (1 + 2 * nu);
  else if (dimension == 2) nu_s = nu / (1 + nu);
  *section_poisson_ratio = nu_s;
  *section_youngs_modulus = E * (1 + nu_s) / (1 + nu);
}

fascia_status fascia_shape_section_points(fascia_ctx *ctx, int dimension, int q, const fascia_real u[3],
                                          const fascia_real v[3], fascia_real width, fascia_real height,
                                          fascia_real *offset, fascia_real *fraction) {
  FASCIA_CHECK(u && offset && fraction && (dimension == 2 || v), ctx, FASCIA_ERR_ARGUMENT,
               "fascia_shape_section_points: NULL argument");
  FASCIA_CHECK(dimension == 1 || dimension == 2, ctx, FASCIA_ERR_ARGUMENT,
               "section points of dimension %d: expected 1 (strand) or 2 (sheet)", dimension);
  FASCIA_CHECK(width > 0 && isfinite(width) && (dimension == 2 || (height > 0 && isfinite(height))), ctx,
               FASCIA_ERR_ARGUMENT, "section of %g x %g m: expected positive finite sizes", width, height);
  fascia_real qp[4], qw[4];
  const fascia_status st = fascia_shape_gauss_legendre(ctx, q, qp, qw);
  if (st != FASCIA_OK) return st;
  const int across = dimension == 1 ? q : 1;
  for (int b = 0, k = 0; b < q; ++b)
    for (int c = 0; c < across; ++c, ++k) {
      const fascia_real a = -width / 2 + width * qp[b];
      const fascia_real e = dimension == 1 ? -height / 2 + height * qp[c] : 0;
      for (int r = 0; r < 3; ++r) offset[3 * k + r] = u[r] * a + (dimension == 1 ? v[r] * e : 0);
      fraction[k] = dimension == 1 ? qw[b] * qw[c] : qw[b];
    }
  return FASCIA_OK;
}
