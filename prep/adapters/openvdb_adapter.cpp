// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// OpenVDB adapter: unsigned distance of a triangle soup in a narrow band,
// copied onto a dense box of the scene's voxel lattice. The only translation
// unit that includes OpenVDB.
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>
#include <openvdb/tools/MeshToVolume.h>

#include <cstdlib>
#include <exception>
#include <vector>

#include "adapters.h"

extern "C" fascia_status fascia_vdb_unsigned_distance(fascia_ctx *ctx, int32_t vertex_count, const double *vertices,
                                                      int32_t triangle_count, const int32_t *triangles, double h,
                                                      float band_voxels, const int32_t lo[3], const int32_t dims[3],
                                                      float *out) {
  try {
    openvdb::initialize();
    // points in index space (world / h) keep float precision relative to the voxel
    std::vector<openvdb::Vec3s> points((size_t)vertex_count);
    for (int32_t v = 0; v < vertex_count; ++v)
      points[v] = openvdb::Vec3s((float)(vertices[3 * v] / h), (float)(vertices[3 * v + 1] / h),
                                 (float)(vertices[3 * v + 2] / h));
    std::vector<openvdb::Vec3I> tris((size_t)triangle_count);
    for (int32_t t = 0; t < triangle_count; ++t)
      tris[t] = openvdb::Vec3I((uint32_t)triangles[3 * t], (uint32_t)triangles[3 * t + 1],
                               (uint32_t)triangles[3 * t + 2]);
    std::vector<openvdb::Vec4I> quads;
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
