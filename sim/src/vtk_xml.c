// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// VTK XML writing for the ParaView files of fascia run and prep's preview
// (fascia/vtk_xml.h).
#include "fascia/vtk_xml.h"

#include <stdlib.h>
#include <string.h>

static int little_endian(void) {
  const uint16_t one = 1;
  unsigned char first;
  memcpy(&first, &one, 1);
  return first == 1;
}

// Base64 of a VTK binary block: a UInt32 byte count, then the data; blocks
// past 4 GB cannot be counted in the header and are refused by the caller.
static void base64_block(FILE *f, const void *data, size_t bytes) {
  static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const uint32_t count = (uint32_t)bytes;
  const unsigned char *d = data;
  unsigned char carry[3];
  int held = 0;
  for (size_t k = 0; k < 4 + bytes; ++k) { // the count's 4 bytes, then the data's
    carry[held++] = k < 4 ? ((const unsigned char *)&count)[k] : d[k - 4];
    if (held < 3 && k + 1 < 4 + bytes) continue;
    const unsigned b0 = carry[0], b1 = held > 1 ? carry[1] : 0, b2 = held > 2 ? carry[2] : 0;
    fputc(tab[b0 >> 2], f);
    fputc(tab[((b0 & 3) << 4) | (b1 >> 4)], f);
    fputc(held > 1 ? tab[((b1 & 15) << 2) | (b2 >> 6)] : '=', f);
    fputc(held > 2 ? tab[b2 & 63] : '=', f);
    held = 0;
  }
}

static void data_array(FILE *f, const char *vtk_type, const char *name, int components, const void *data,
                       size_t bytes) {
  fprintf(f, "<DataArray type=\"%s\"", vtk_type);
  if (name) fprintf(f, " Name=\"%s\"", name);
  fprintf(f, " NumberOfComponents=\"%d\" format=\"binary\">", components);
  base64_block(f, data, bytes);
  fprintf(f, "</DataArray>\n");
}

void fascia_vtk_begin(FILE *f, const char *type, const fascia_real *points, int64_t point_count, int nodes,
                   const int32_t *cell_nodes, int64_t cell_count) {
  const int poly = !strcmp(type, "PolyData");
  fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"%s\" version=\"0.1\" byte_order=\"%s\" header_type=\"UInt32\">\n"
             "<%s>\n<Piece NumberOfPoints=\"%lld\" %s=\"%lld\">\n",
          type, little_endian() ? "LittleEndian" : "BigEndian", type, (long long)point_count,
          poly ? "NumberOfPolys" : "NumberOfCells", (long long)cell_count);
  fprintf(f, "<Points>");
  data_array(f, "Float64", NULL, 3, points, 3 * sizeof(fascia_real) * (size_t)point_count);
  fprintf(f, "</Points>\n<%s>\n", poly ? "Polys" : "Cells");
  int32_t *offsets = malloc(sizeof(int32_t) * (size_t)(cell_count + 1));
  int32_t *vertices = cell_nodes ? NULL : malloc(sizeof(int32_t) * (size_t)(cell_count + 1));
  uint8_t *types = poly ? NULL : malloc((size_t)cell_count + 1);
  if (offsets && (cell_nodes || vertices) && (poly || types)) {
    for (int64_t c = 0; c < cell_count; ++c) {
      offsets[c] = (int32_t)(nodes * (c + 1));
      if (vertices) vertices[c] = (int32_t)c;
      if (types) types[c] = nodes == 4 ? 10 : 1; // VTK_TETRA, VTK_VERTEX
    }
    data_array(f, "Int32", "connectivity", 1, cell_nodes ? cell_nodes : vertices,
               sizeof(int32_t) * (size_t)nodes * (size_t)cell_count);
    data_array(f, "Int32", "offsets", 1, offsets, sizeof(int32_t) * (size_t)cell_count);
    if (types) data_array(f, "UInt8", "types", 1, types, (size_t)cell_count);
  } else {
    fprintf(f, "out of memory"); // an unreadable file: the reader says where
  }
  free(offsets), free(vertices), free(types);
  fprintf(f, "</%s>\n<PointData>\n", poly ? "Polys" : "Cells");
}

void fascia_vtk_array(FILE *f, const char *name, int components, const fascia_real *real, const int32_t *ints,
                   int64_t point_count) {
  const size_t n = (size_t)components * (size_t)point_count;
  if (real)
    data_array(f, "Float64", name, components, real, n * sizeof(fascia_real));
  else
    data_array(f, "Int32", name, components, ints, n * sizeof(int32_t));
}

void fascia_vtk_end(FILE *f, const char *type) {
  fprintf(f, "</PointData>\n</Piece>\n</%s>\n</VTKFile>\n", type);
}

void fascia_vtk_begin_image(FILE *f, const int32_t *dims, const fascia_real *origin, fascia_real spacing) {
  fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"0.1\" byte_order=\"%s\" header_type=\"UInt32\">\n"
             "<ImageData WholeExtent=\"0 %d 0 %d 0 %d\" Origin=\"%.17g %.17g %.17g\" Spacing=\"%.17g %.17g %.17g\">\n"
             "<Piece Extent=\"0 %d 0 %d 0 %d\">\n<PointData>\n",
          little_endian() ? "LittleEndian" : "BigEndian", (int)dims[0] - 1, (int)dims[1] - 1, (int)dims[2] - 1,
          origin[0], origin[1], origin[2], spacing, spacing, spacing, (int)dims[0] - 1, (int)dims[1] - 1,
          (int)dims[2] - 1);
}

void fascia_vtk_array_float(FILE *f, const char *name, const float *values, int64_t point_count) {
  data_array(f, "Float32", name, 1, values, sizeof(float) * (size_t)point_count);
}
