// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Shape functions of the frame scheme (paper sec. 2.1, "Depending on whether
// the method is used with a mesh based or meshfree scheme"): the weights w_is
// and rest-space gradients grad w_is that tie a sample to its neighbour
// frames. Pure geometry, no model: hexahedral trilinear, tetrahedral linear
// (barycentric), meshless moving least squares (MLS, linear basis), a
// k-nearest-frames search, and quadrature rules for placing samples in cells.
//
// Every kind here is a partition of unity that reproduces linear fields:
//   sum_i w_i = 1,  sum_i grad w_i = 0,  sum_i w_i x_i = p,
//   sum_i x_i (x) grad w_i = I,
// which is what makes the frame scheme's F exact under affine frame motion.
#ifndef FASCIA_SHAPE_H
#define FASCIA_SHAPE_H

#include "fascia/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Largest k fascia_frame_grid_nearest accepts.
#define FASCIA_SHAPE_MAX_NEIGHBOURS 128

/// Kernel support of fascia_frame_grid_nearest: the radius is this factor
/// times the distance to the (k+1)-th nearest frame, so that every one of the
/// k chosen frames, ties included, gets a clearly positive kernel weight.
#define FASCIA_SHAPE_SUPPORT_MARGIN 1.25

/// Trilinear (hexahedral) weights at p for the axis-aligned box cell [lo, hi].
/// Corner order: corner c in 0..7 sits at x = (c & 1 ? hi : lo)[0],
/// y = (c & 2 ? hi : lo)[1], z = (c & 4 ? hi : lo)[2] (x varies fastest).
/// w: [8] weights; grad: [24], grad[3c + r] = d w_c / d p_r (1/m, rest space).
/// p may lie outside the cell (the weights then extrapolate and some are
/// negative). Errors: FASCIA_ERR_ARGUMENT if a side of the cell is not
/// positive and finite; w and grad are then untouched.
FASCIA_API fascia_status fascia_shape_hex(fascia_ctx *ctx, const fascia_real lo[3], const fascia_real hi[3],
                                          const fascia_real p[3], fascia_real w[8], fascia_real grad[24]);

/// Linear (barycentric) weights at p for the tetrahedron with vertices
/// vertex[0..2], vertex[3..5], vertex[6..8], vertex[9..11] (m, any
/// orientation). w: [4], grad: [12] constant gradients (1/m), vertex order.
/// p may lie outside (some weights negative). Errors: FASCIA_ERR_ARGUMENT for
/// a degenerate (flat, relative volume below 1e-12) or non-finite
/// tetrahedron, naming its vertices; w and grad are then untouched.
FASCIA_API fascia_status fascia_shape_tet(fascia_ctx *ctx, const fascia_real vertex[12], const fascia_real p[3],
                                          fascia_real w[4], fascia_real grad[12]);

/// Kernel of the MLS weights: Wendland's C2 function
///   phi(q) = (1 - q)^4 (4 q + 1) for q = |p - x| / radius < 1, else 0,
/// smooth, compactly supported, positive inside the support.
FASCIA_API fascia_real fascia_shape_kernel(fascia_real q);

/// Moving least squares weights with a linear basis (1, x, y, z) at p over
/// the n frames at frame[3n] (m), kernel fascia_shape_kernel of the given
/// support radius (m). w: [n]; grad: [3n], grad[3i + r] = d w_i / d p_r, the
/// exact analytic derivative with the radius and the frame set held fixed.
/// Frames at distance >= radius get weight 0 (and do not count towards the
/// moment matrix). Errors: FASCIA_ERR_ARGUMENT (n < 4, radius not positive);
/// FASCIA_ERR_NUMERIC when the moment matrix is singular or too badly
/// conditioned (fewer than 4 frames in the support, or those frames coplanar
/// or collinear), naming the point. w and grad are undefined after an error.
FASCIA_API fascia_status fascia_shape_mls(fascia_ctx *ctx, int32_t n, const fascia_real *frame,
                                          const fascia_real p[3], fascia_real radius, fascia_real *w,
                                          fascia_real *grad);

/// Default flatness of fascia_shape_mls_adaptive: frames whose spread
/// across a direction is at most this fraction of their largest spread lie
/// in a line or a plane.
#define FASCIA_SHAPE_FLATNESS 1e-6

/// Moving least squares whose linear basis follows the dimension of the
/// frames: for strands (frames on a curve) and sheets (frames on a
/// surface), where the 3-D basis of fascia_shape_mls is singular. The
/// principal axes of the n frames (frame[3n], m; eigenvectors of their
/// covariance) decide: axes whose RMS spread is at most `flatness` (0: the
/// default FASCIA_SHAPE_FLATNESS) times the largest are dropped. With all
/// three kept this is fascia_shape_mls, to the bit. With one (a line) or two
/// (a plane) the basis is (1, the coordinates of x along the kept axes) and
/// the kernel (fascia_shape_kernel, support `radius`) takes the distance
/// along them: the weights depend only on where p projects, so samples
/// across a strand's section or a sheet's thickness share their station's
/// weights, and grad (d w_i / d p, exact, radius and frames fixed) lies in
/// the span. On that span the weights are a partition of unity that
/// reproduces linear fields: sum w_i = 1, sum grad w_i = 0,
/// sum w_i x_i = p and sum x_i (x) grad w_i = I on the span's coordinates;
/// across it, sum x_i (x) grad w_i = P, the projector on the span (the
/// frames' rotations carry the section: docs/mechanics.md). *dimension
/// (may be NULL) gets 1, 2 or 3. Errors: FASCIA_ERR_ARGUMENT (n < 2, or < 4
/// for a volume; radius not positive; flatness outside (0, 1); a non-finite
/// input; all frames at one point); FASCIA_ERR_NUMERIC when the moment
/// matrix in the span is singular (fewer frames in the support than the
/// basis has terms), naming the point. w and grad are undefined after an
/// error.
FASCIA_API fascia_status fascia_shape_mls_adaptive(fascia_ctx *ctx, int32_t n, const fascia_real *frame,
                                                   const fascia_real p[3], fascia_real radius, fascia_real flatness,
                                                   fascia_real *w, fascia_real *grad, int32_t *dimension);

/// Gauss-Legendre rule with n = 1..4 points on [0, 1]: point[n] ascending,
/// weight[n] summing to 1. Exact for polynomials of degree 2n - 1.
/// Errors: FASCIA_ERR_ARGUMENT for other n.
FASCIA_API fascia_status fascia_shape_gauss_legendre(fascia_ctx *ctx, int n, fascia_real *point,
                                                     fascia_real *weight);

/// Moduli of a section carried by the frames' rotations (strands and
/// sheets, docs/mechanics.md "Strands and sheets"): the shear modulus is
/// kept and Poisson's ratio chosen so that the law, its section held by the
/// frames, is uniaxial stress along a strand (dimension 1) or plane stress
/// in a sheet (dimension 2); dimension 3 returns E and nu unchanged.
FASCIA_API void fascia_shape_section_moduli(int dimension, fascia_real youngs_modulus, fascia_real poisson_ratio,
                                            fascia_real *section_youngs_modulus, fascia_real *section_poisson_ratio);

/// Sample points across the section at one station of a strand or a sheet,
/// Gauss-Legendre with q = 1..4 points per direction. Strand (dimension 1):
/// q x q points over a width x height rectangle centred on the station and
/// spanned by the unit vectors u (width) and v (height), u slow. Sheet
/// (dimension 2): q points through its thickness `width` along its unit
/// normal u (v and height are not used). offset[3 m] from the station (m)
/// and fraction[m] of the section each point stands for (summing to 1),
/// m = q^2 (strand) or q (sheet). Errors: FASCIA_ERR_ARGUMENT.
FASCIA_API fascia_status fascia_shape_section_points(fascia_ctx *ctx, int dimension, int q, const fascia_real u[3],
                                                     const fascia_real v[3], fascia_real width, fascia_real height,
                                                     fascia_real *offset, fascia_real *fraction);

/// Quadrature on a tetrahedron in barycentric coordinates: n = 1 (centroid,
/// degree 1) or n = 4 (degree 2). bary: [4n], weight: [n] fractions of the
/// tetrahedron's volume, summing to 1. Errors: FASCIA_ERR_ARGUMENT for other n.
FASCIA_API fascia_status fascia_shape_tet_quadrature(fascia_ctx *ctx, int n, fascia_real *bary, fascia_real *weight);

/// A uniform grid over frame positions for nearest-frame queries.
typedef struct fascia_frame_grid fascia_frame_grid;

/// Builds a grid over frame_count positions (position: [3 frame_count], m,
/// copied). Errors: FASCIA_ERR_ARGUMENT (no frame, non-finite position),
/// FASCIA_ERR_MEMORY; *out is NULL then.
FASCIA_API fascia_status fascia_frame_grid_create(fascia_ctx *ctx, int32_t frame_count, const fascia_real *position,
                                                  fascia_frame_grid **out);
/// Frees a grid; accepts NULL, sets *grid to NULL.
FASCIA_API void fascia_frame_grid_destroy(fascia_frame_grid **grid);

/// The k nearest frames to p: index[k] in ascending frame order (ties in
/// distance go to the lower frame index, so the choice is deterministic), and
/// *radius = FASCIA_SHAPE_SUPPORT_MARGIN times the distance of the (k+1)-th
/// nearest frame (of the k-th when k is the frame count), a kernel support
/// that gives every chosen frame a positive weight. Errors:
/// FASCIA_ERR_ARGUMENT (k < 1, k > frame count or FASCIA_SHAPE_MAX_NEIGHBOURS,
/// all chosen frames at p so no positive radius exists).
FASCIA_API fascia_status fascia_frame_grid_nearest(fascia_ctx *ctx, const fascia_frame_grid *grid,
                                                   const fascia_real p[3], int32_t k, int32_t *index,
                                                   fascia_real *radius);

/// Frame count and positions ([3 count], m) held by a grid.
FASCIA_API int32_t fascia_frame_grid_count(const fascia_frame_grid *grid);
FASCIA_API const fascia_real *fascia_frame_grid_positions(const fascia_frame_grid *grid);

#ifdef __cplusplus
}
#endif
#endif
