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

#include <algorithm>
#include <cstdlib>
#include <exception>
#include <vector>

#include "adapters.h"

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

extern "C" fascia_status fascia_vdb_unsigned_distance(fascia_ctx *ctx, int32_t vertex_count, const double *vertices,
                                                      int32_t triangle_count, const int32_t *triangles, double h,
                                                      float band_voxels, const int32_t lo[3], const int32_t dims[3],
                                                      float *out) {
  try {
    openvdb::initialize();
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> tris;
    std::vector<openvdb::Vec4I> quads;
    in_voxels(vertex_count, vertices, triangle_count, triangles, h, points, tris);
    auto xform = openvdb::math::Transform::createLinearTransform(1.0);
    openvdb::FloatGrid::Ptr grid =
        openvdb::tools::meshToUnsignedDistanceField<openvdb::FloatGrid>(*xform, points, tris, quads, band_voxels);
    const openvdb::CoordBBox box(openvdb::Coord(lo[0], lo[1], lo[2]),
                                 openvdb::Coord(lo[0] + dims[0] - 1, lo[1] + dims[1] - 1, lo[2] + dims[2] - 1));
    openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(box, out);
    dense.fill(band_voxels);
    openvdb::tools::copyToDense(*grid, dense);
    const size_t count = (size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2];
    const float hf = (float)h;
    for (size_t k = 0; k < count; ++k) {
      const float d = out[k] < 0 ? -out[k] : out[k];
      out[k] = (d > band_voxels ? band_voxels : d) * hf;
    }
    return FASCIA_OK;
  } catch (const std::bad_alloc &) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__,
                           "OpenVDB: out of memory for the distance field of %d triangles at voxel size %g m",
                           (int)triangle_count, h);
  } catch (const std::exception &e) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_INTERNAL, __FILE__, __LINE__, "OpenVDB: %s", e.what());
  } catch (...) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_INTERNAL, __FILE__, __LINE__, "OpenVDB: unknown exception");
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
  } catch (const std::bad_alloc &) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__,
                           "OpenVDB: out of memory for the surface of %d x %d x %d voxels", (int)dims[0], (int)dims[1],
                           (int)dims[2]);
  } catch (const std::exception &e) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_INTERNAL, __FILE__, __LINE__, "OpenVDB: %s", e.what());
  } catch (...) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_INTERNAL, __FILE__, __LINE__, "OpenVDB: unknown exception");
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
    openvdb::initialize();
    const float reach = (float)(depth / h) + 3.0f; // voxels: the carve and the band around its surface
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
    openvdb::tools::volumeToMesh(*grid, points, tris, quads, 0.0, 0.0, true);
    return to_triangles(ctx, points, tris, quads, h, out_vertices, out_vertex_count, out_triangles,
                        out_triangle_count);
  } catch (const std::bad_alloc &) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__,
                           "OpenVDB: out of memory carving a surface of %d triangles at voxel size %g m",
                           (int)triangle_count, h);
  } catch (const std::exception &e) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_INTERNAL, __FILE__, __LINE__, "OpenVDB: %s", e.what());
  } catch (...) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_INTERNAL, __FILE__, __LINE__, "OpenVDB: unknown exception");
  }
}
