// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// VTK XML files (ParaView, meshio), as fascia run and prep's preview write
// them: one piece of UnstructuredGrid (points with vertex or tetrahedron
// cells), PolyData (triangles) or ImageData, arrays inline in base64 behind
// a UInt32 byte count (so at most 4 GB an array).
#ifndef FASCIA_VTK_XML_H
#define FASCIA_VTK_XML_H

#include <stdint.h>
#include <stdio.h>

#include "fascia/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/// The header, the piece and its points [3 points] (Float64). cells: for
/// "UnstructuredGrid" nodes per cell (1: a vertex per point, cell_count =
/// points; 4: tetrahedra), for "PolyData" 3 (triangles); cell_nodes
/// [nodes cell_count] (NULL for vertices). Point data follows
/// (fascia_vtk_array), then fascia_vtk_end.
FASCIA_API void fascia_vtk_begin(FILE *f, const char *type, const fascia_real *points, int64_t point_count, int nodes,
                   const int32_t *cell_nodes, int64_t cell_count);
/// A point-data array: components per point, Float64 (real) or Int32 (ints);
/// exactly one of real and ints is given.
FASCIA_API void fascia_vtk_array(FILE *f, const char *name, int components, const fascia_real *real, const int32_t *ints,
                                                int64_t point_count);
/// Closes the point data, the piece and the file.
FASCIA_API void fascia_vtk_end(FILE *f, const char *type);
/// An "ImageData" header and piece: dims points per axis, the first at
/// origin, spacing apart (m); point data follows, then fascia_vtk_end.
FASCIA_API void fascia_vtk_begin_image(FILE *f, const int32_t *dims, const fascia_real *origin, fascia_real spacing);
/// A point-data array of float32 (a large grid's field shown, not computed with).
FASCIA_API void fascia_vtk_array_float(FILE *f, const char *name, const float *values, int64_t point_count);

#ifdef __cplusplus
}
#endif
#endif
