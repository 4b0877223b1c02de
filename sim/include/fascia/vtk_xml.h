// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// VTK XML files (ParaView, meshio), as fascia run and prep's preview write
// them: one piece of UnstructuredGrid (points with vertex, line, triangle or
// tetrahedron cells), PolyData (triangles) or ImageData; arrays inline,
// zlib-compressed in 32 KiB blocks behind a UInt64 header, base64, as VTK's
// own writer does. Every file carries field data `length_unit_m` (metres per
// length unit: 1, lengths are in m) and, when given, `TimeValue` (s).
// Every text that goes into an XML file of fascia goes through
// fascia_xml_text: a name is data, never markup.
#ifndef FASCIA_VTK_XML_H
#define FASCIA_VTK_XML_H

#include <stdint.h>
#include <stdio.h>

#include "fascia/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Writes `text` (UTF-8) as XML character data or an attribute value:
/// & < > " ' as entities, tab, newline and carriage return as character
/// references, other control characters and bytes that are not UTF-8 as
/// U+FFFD (XML 1.0 cannot hold them).
FASCIA_API void fascia_xml_text(FILE *f, const char *text);

/// What a piece says beyond its arrays (fascia_vtk_piece_default()).
typedef struct fascia_vtk_piece {
  double time;         ///< s, written as field data TimeValue; NaN: none
  const char *scalars; ///< the point array ParaView colours by when the file opens; NULL: none
  const char *vectors; ///< the point array of active vectors (Warp By Vector); NULL: none
} fascia_vtk_piece;
/// No time, no active arrays.
FASCIA_API fascia_vtk_piece fascia_vtk_piece_default(void);

/// The header, the piece and its points [3 points] (Float64). cells: for
/// "UnstructuredGrid" nodes per cell (1: a vertex per point, cell_count =
/// points; 2 lines, 3 triangles, 4 tetrahedra), for "PolyData" 3
/// (triangles); cell_nodes [nodes cell_count] (NULL for vertices). Point
/// data follows (fascia_vtk_array), then fascia_vtk_end. piece may be NULL
/// (the defaults).
FASCIA_API void fascia_vtk_begin_piece(FILE *f, const char *type, const fascia_vtk_piece *piece,
                                       const fascia_real *points, int64_t point_count, int nodes,
                                       const int32_t *cell_nodes, int64_t cell_count);
/// fascia_vtk_begin_piece with the defaults.
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
