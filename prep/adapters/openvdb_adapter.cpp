// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// OpenVDB adapter: unsigned distance of a triangle soup in a narrow band,
// copied onto a dense box of the scene's voxel lattice; the smoothed surface
// of a dense indicator (an organ's labels); a surface carved where another
// comes near. The only translation unit that includes OpenVDB.
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>
#include <openvdb/tools/Filter.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/global_control.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <new>
#include <vector>

#include "adapters.h"

// OpenVDB's tools run on TBB, which takes every core unless told: each
// call holds it to the threads prep was given (--threads), as the
// OpenMP loops are (a global_control lasts while it is in scope).
static size_t tbb_threads(const fascia_ctx *ctx) { return (size_t)std::max(1, fascia_ctx_threads(ctx)); }
#define HOLD_TBB_THREADS(ctx) \
  tbb::global_control tbb_limit(tbb::global_control::max_allowed_parallelism, tbb_threads(ctx))

// OpenVDB runs out of memory inside its worker threads, where a bad_alloc
// can end in a destructor and abort the process: the narrow band's size is
// estimated first (voxels within band of the surface: at most the surface
// area times the band's thickness, at most the grown box) and refused when
// it cannot fit this machine's memory.
static bool band_fits(fascia_ctx *ctx, const char *stage, int32_t vertex_count, const double *vertices,
                      int32_t triangle_count, const int32_t *triangles, double h, double band_voxels,
                      fascia_status *status) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, area = 0;
  for (int32_t v = 0; v < vertex_count; ++v)
    for (int r = 0; r < 3; ++r) lo[r] = std::min(lo[r], vertices[3 * v + r]), hi[r] = std::max(hi[r], vertices[3 * v + r]);
  for (int32_t t = 0; t < triangle_count; ++t) {
    const double *a = vertices + 3 * triangles[3 * t], *b = vertices + 3 * triangles[3 * t + 1],
                 *c = vertices + 3 * triangles[3 * t + 2];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    area += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  }
  double box = 1;
  for (int r = 0; r < 3; ++r) box *= (hi[r] - lo[r]) / h + 2 * band_voxels + 1;
  const double shell = (area / (h * h) + 1) * (2 * band_voxels + 1) + 8.0 * triangle_count;
  const double voxels = std::min(box, shell);
  const double bytes = 12.0 * voxels; // a float, the masks and the tree's nodes
  double memory = 0;
#if defined(_SC_PHYS_PAGES) && defined(_SC_PAGESIZE)
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0) memory = (double)pages * (double)page;
#endif
  if (std::isfinite(bytes) && (memory <= 0 || bytes < 0.8 * memory)) return true;
  *status = fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__,
                            "OpenVDB, %s: a distance band %.3g voxels wide (%.3g m) around %d triangles at voxel size "
                            "%g m needs about %.3g GiB, more than this machine's %.3g GiB; lower the tissues' max_gap "
                            "or coupling tolerance, or raise voxel_size",
                            stage, band_voxels, band_voxels * h, (int)triangle_count, h, bytes / 1073741824.0,
                            memory / 1073741824.0);
  return false;
}

// A triangle soup in index space (world / h), which keeps float precision
// relative to the voxel.
static void in_voxels(int32_t vertex_count, const double *vertices, int32_t triangle_count, const int32_t *triangles,
                      double h, std::vector<openvdb::Vec3s> &points, std::vector<openvdb::Vec3I> &tris) {
  points.resize((size_t)vertex_count);
  for (int32_t v = 0; v < vertex_count; ++v)
    points[v] = openvdb::Vec3s((float)(vertices[3 * v] / h), (float)(vertices[3 * v + 1] / h),
                               (float)(vertices[3 * v + 2] / h));
  tris.resize((size_t)triangle_count);
  for (int32_t t = 0; t < triangle_count; ++t)
    tris[t] = openvdb::Vec3I((uint32_t)triangles[3 * t], (uint32_t)triangles[3 * t + 1], (uint32_t)triangles[3 * t + 2]);
}

// The status of the exception being handled: call it only inside a catch
// block. Out of memory is said with `job`, what was being built; any other
// error in OpenVDB's words.
static fascia_status fail_exception(fascia_ctx *ctx, const char *job) {
  try {
    throw;
  } catch (const std::bad_alloc &) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "OpenVDB: out of memory %s", job);
  } catch (const std::exception &e) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_INTERNAL, __FILE__, __LINE__, "OpenVDB: %s", e.what());
  } catch (...) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_INTERNAL, __FILE__, __LINE__, "OpenVDB: unknown exception");
  }
}

extern "C" fascia_status fascia_vdb_unsigned_distance(fascia_ctx *ctx, int32_t vertex_count, const double *vertices,
                                                      int32_t triangle_count, const int32_t *triangles, double h,
                                                      float band_voxels, const int32_t lo[3], const int32_t dims[3],
                                                      float *out) {
  try {
    // a voxel of the box is never farther from the mesh than the diagonal of
    // the box and the mesh's box together: a wider band changes no value
    double span = 0;
    for (int r = 0; r < 3; ++r) {
      double a = lo[r], b = lo[r] + dims[r];
      for (int32_t v = 0; v < vertex_count; ++v) a = std::min(a, vertices[3 * v + r] / h), b = std::max(b, vertices[3 * v + r] / h);
      span += (b - a + 2) * (b - a + 2);
    }
    const float reach = (float)std::min((double)band_voxels, std::sqrt(span) + 2);
    fascia_status status;
    if (!band_fits(ctx, "distance field", vertex_count, vertices, triangle_count, triangles, h, reach, &status))
      return status;
    HOLD_TBB_THREADS(ctx);
    openvdb::initialize();
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> tris;
    std::vector<openvdb::Vec4I> quads;
    in_voxels(vertex_count, vertices, triangle_count, triangles, h, points, tris);
    auto xform = openvdb::math::Transform::createLinearTransform(1.0);
    openvdb::FloatGrid::Ptr grid =
        openvdb::tools::meshToUnsignedDistanceField<openvdb::FloatGrid>(*xform, points, tris, quads, reach);
    const openvdb::CoordBBox box(openvdb::Coord(lo[0], lo[1], lo[2]),
                                 openvdb::Coord(lo[0] + dims[0] - 1, lo[1] + dims[1] - 1, lo[2] + dims[2] - 1));
    openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(box, out);
    dense.fill(reach);
    openvdb::tools::copyToDense(*grid, dense);
    const size_t count = (size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2];
    const float hf = (float)h;
    for (size_t k = 0; k < count; ++k) {
      const float d = out[k] < 0 ? -out[k] : out[k];
      out[k] = (d > band_voxels ? band_voxels : d) * hf;
    }
    return FASCIA_OK;
  } catch (...) {
    char job[128];
    snprintf(job, sizeof job, "for the distance field of %d triangles at voxel size %g m", (int)triangle_count, h);
    return fail_exception(ctx, job);
  }
}

// The polygons of volumeToMesh as malloc'ed triangles (each quad split in two).
static fascia_status to_triangles(fascia_ctx *ctx, const std::vector<openvdb::Vec3s> &points,
                                  const std::vector<openvdb::Vec3I> &tris, const std::vector<openvdb::Vec4I> &quads,
                                  double scale, double **out_vertices, int32_t *out_vertex_count,
                                  int32_t **out_triangles, int32_t *out_triangle_count) {
  const size_t nt = tris.size() + 2 * quads.size();
  if (points.size() > (size_t)INT32_MAX / 3 || nt > (size_t)INT32_MAX / 3)
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "OpenVDB: the surface is too large");
  double *v = (double *)malloc((points.size() + 1) * 3 * sizeof(double));
  int32_t *t = (int32_t *)malloc((nt + 1) * 3 * sizeof(int32_t));
  if (!v || !t) {
    free(v);
    free(t);
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "OpenVDB: out of memory for a surface");
  }
  for (size_t k = 0; k < points.size(); ++k)
    for (int r = 0; r < 3; ++r) v[3 * k + r] = scale * (double)points[k][r];
  size_t n = 0;
  for (const auto &p : tris)
    for (int r = 0; r < 3; ++r) t[n++] = (int32_t)p[2 - r]; // volumeToMesh winds inward
  for (const auto &q : quads) {
    const int32_t a = (int32_t)q[0], b = (int32_t)q[1], c = (int32_t)q[2], d = (int32_t)q[3];
    t[n++] = a, t[n++] = d, t[n++] = c; // (a, b, c, d) reversed, split along a-c
    t[n++] = a, t[n++] = c, t[n++] = b;
  }
  *out_vertices = v;
  *out_vertex_count = (int32_t)points.size();
  *out_triangles = t;
  *out_triangle_count = (int32_t)nt;
  return FASCIA_OK;
}

extern "C" fascia_status fascia_vdb_indicator_surface(fascia_ctx *ctx, const int32_t dims[3], const float *inside,
                                                      int32_t smoothing, double **out_vertices,
                                                      int32_t *out_vertex_count, int32_t **out_triangles,
                                                      int32_t *out_triangle_count) {
  try {
    HOLD_TBB_THREADS(ctx);
    openvdb::initialize();
    // -1 inside, 0 outside: the -1/2 level lies midway between voxel centres,
    // on the faces of the labelled voxels where no smoothing moves it
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
    const openvdb::CoordBBox box(openvdb::Coord(0, 0, 0), openvdb::Coord(dims[0] - 1, dims[1] - 1, dims[2] - 1));
    std::vector<float> values((size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2]);
    for (size_t k = 0; k < values.size(); ++k) values[k] = -inside[k];
    openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(box, values.data());
    openvdb::tools::copyFromDense(dense, *grid, 0.0f);
    if (smoothing > 0) {
      openvdb::tools::dilateActiveValues(grid->tree(), smoothing + 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                         openvdb::tools::IGNORE_TILES);
      openvdb::tools::Filter<openvdb::FloatGrid> filter(*grid);
      filter.mean(1, smoothing);
    }
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> tris;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(*grid, points, tris, quads, -0.5, 0.0, true);
    return to_triangles(ctx, points, tris, quads, 1.0, out_vertices, out_vertex_count, out_triangles,
                        out_triangle_count);
  } catch (...) {
    char job[128];
    snprintf(job, sizeof job, "for the surface of %d x %d x %d voxels", (int)dims[0], (int)dims[1], (int)dims[2]);
    return fail_exception(ctx, job);
  }
}

static openvdb::FloatGrid::Ptr signed_distance(int32_t vertex_count, const double *vertices, int32_t triangle_count,
                                               const int32_t *triangles, double h, float ex_band, float in_band) {
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> tris;
  std::vector<openvdb::Vec4I> quads;
  in_voxels(vertex_count, vertices, triangle_count, triangles, h, points, tris);
  auto xform = openvdb::math::Transform::createLinearTransform(1.0);
  return openvdb::tools::meshToSignedDistanceField<openvdb::FloatGrid>(*xform, points, tris, quads, ex_band,
                                                                       in_band);
}

extern "C" fascia_status fascia_vdb_carve(fascia_ctx *ctx, int32_t vertex_count, const double *vertices,
                                          int32_t triangle_count, const int32_t *triangles,
                                          int32_t other_vertex_count, const double *other_vertices,
                                          int32_t other_triangle_count, const int32_t *other_triangles, double h,
                                          double depth, double **out_vertices, int32_t *out_vertex_count,
                                          int32_t **out_triangles, int32_t *out_triangle_count) {
  try {
    const float reach = (float)(depth / h) + 3.0f; // voxels: the carve and the band around its surface
    fascia_status status;
    if (!band_fits(ctx, "carving", vertex_count, vertices, triangle_count, triangles, h, reach, &status) ||
        !band_fits(ctx, "carving", other_vertex_count, other_vertices, other_triangle_count, other_triangles, h, reach,
                   &status))
      return status;
    HOLD_TBB_THREADS(ctx);
    openvdb::initialize();
    openvdb::FloatGrid::Ptr grid = signed_distance(vertex_count, vertices, triangle_count, triangles, h, 3.0f, reach);
    openvdb::FloatGrid::Ptr other = signed_distance(other_vertex_count, other_vertices, other_triangle_count,
                                                    other_triangles, h, reach, 3.0f);
    // inside this surface and farther than depth from the other's: max(d, depth - d_other)
    const float d = (float)(depth / h);
    auto near = other->getConstAccessor();
    for (auto it = grid->beginValueOn(); it; ++it) it.setValue(std::max(*it, d - near.getValue(it.getCoord())));
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> tris;
    std::vector<openvdb::Vec4I> quads;
    // adaptive: the carve's cells are a fraction of the layer, far finer than
    // the voxels; merging them where the surface is flat keeps its shape
    // without a triangle per cell for every later stage to voxelize
    openvdb::tools::volumeToMesh(*grid, points, tris, quads, 0.0, 0.3, true);
    return to_triangles(ctx, points, tris, quads, h, out_vertices, out_vertex_count, out_triangles,
                        out_triangle_count);
  } catch (...) {
    char job[128];
    snprintf(job, sizeof job, "carving a surface of %d triangles at voxel size %g m", (int)triangle_count, h);
    return fail_exception(ctx, job);
  }
}
