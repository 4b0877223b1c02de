// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// VTK XML files (ParaView, meshio) written by fascia run: one piece of
// UnstructuredGrid (points with vertex or tetrahedron cells) or PolyData
// (triangles), arrays inline in base64 behind a UInt32 byte count.
#ifndef FASCIA_TOOLS_VTK_XML_H
#define FASCIA_TOOLS_VTK_XML_H

#include <stdint.h>
#include <stdio.h>

#include "fascia/fascia.h"

/// The header, the piece and its points [3 points] (Float64). cells: for
/// "UnstructuredGrid" nodes per cell (1: a vertex per point, cell_count =
/// points; 4: tetrahedra), for "PolyData" 3 (triangles); cell_nodes
/// [nodes cell_count] (NULL for vertices). Point data follows
/// (vtk_xml_array), then vtk_xml_end.
void vtk_xml_begin(FILE *f, const char *type, const fascia_real *points, int64_t point_count, int nodes,
                   const int32_t *cell_nodes, int64_t cell_count);
/// A point-data array: components per point, Float64 (real) or Int32 (ints);
/// exactly one of real and ints is given.
void vtk_xml_array(FILE *f, const char *name, int components, const fascia_real *real, const int32_t *ints,
                   int64_t point_count);
/// Closes the point data, the piece and the file.
void vtk_xml_end(FILE *f, const char *type);

#endif
