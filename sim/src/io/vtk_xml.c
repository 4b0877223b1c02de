// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// VTK XML writing for the ParaView files of fascia run and prep's preview
// (fascia/vtk_xml.h), and the one escaping path of every XML text fascia
// writes (fascia_xml_text: the PVD collections, the XDMF sidecar).
#include "fascia/vtk_xml.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

// VTK's own writer compresses in blocks of this many bytes; readers take any.
#define BLOCK_BYTES 32768

static const char replacement[] = "\xEF\xBF\xBD"; // U+FFFD

// Bytes of the well-formed UTF-8 sequence that starts at s (1 to 4), 0 when
// it is not one (overlong forms, surrogates and values past U+10FFFF are not).
static int utf8_length(const unsigned char *s) {
  if (s[0] < 0x80) return 1;
  int n = s[0] >= 0xF0 ? 4 : s[0] >= 0xE0 ? 3 : s[0] >= 0xC2 ? 2 : 0;
  if (n == 0 || s[0] > 0xF4) return 0;
  for (int k = 1; k < n; ++k)
    if ((s[k] & 0xC0) != 0x80) return 0;
  if (n == 3 && ((s[0] == 0xE0 && s[1] < 0xA0) || (s[0] == 0xED && s[1] >= 0xA0))) return 0;
  if (n == 4 && ((s[0] == 0xF0 && s[1] < 0x90) || (s[0] == 0xF4 && s[1] >= 0x90))) return 0;
  return n;
}

void fascia_xml_text(FILE *f, const char *text) {
  const unsigned char *s = (const unsigned char *)(text ? text : "");
  while (*s) {
    const unsigned char c = *s;
    const char *entity = c == '&'    ? "&amp;"
                         : c == '<'  ? "&lt;"
                         : c == '>'  ? "&gt;"
                         : c == '"'  ? "&quot;"
                         : c == '\'' ? "&apos;"
                         : c == '\t' ? "&#9;"
                         : c == '\n' ? "&#10;"
                         : c == '\r' ? "&#13;"
                         : c < 0x20 || c == 0x7F ? replacement
                                                 : NULL;
    if (entity) {
      fputs(entity, f);
      ++s;
      continue;
    }
    const int n = utf8_length(s);
    if (n == 0) {
      fputs(replacement, f);
      ++s;
    } else {
      fwrite(s, 1, (size_t)n, f);
      s += n;
    }
  }
}

fascia_vtk_piece fascia_vtk_piece_default(void) {
  fascia_vtk_piece p;
  memset(&p, 0, sizeof p);
  p.time = NAN;
  return p;
}

static int little_endian(void) {
  const uint16_t one = 1;
  unsigned char first;
  memcpy(&first, &one, 1);
  return first == 1;
}

// Base64 of bytes, padded: VTK decodes the header and the data as two runs.
static void base64(FILE *f, const unsigned char *d, size_t bytes) {
  static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (size_t k = 0; k < bytes; k += 3) {
    const unsigned b0 = d[k], b1 = k + 1 < bytes ? d[k + 1] : 0, b2 = k + 2 < bytes ? d[k + 2] : 0;
    fputc(tab[b0 >> 2], f);
    fputc(tab[((b0 & 3) << 4) | (b1 >> 4)], f);
    fputc(k + 1 < bytes ? tab[((b1 & 15) << 2) | (b2 >> 6)] : '=', f);
    fputc(k + 2 < bytes ? tab[b2 & 63] : '=', f);
  }
}

// VTK's compressed binary layout (header_type UInt64): the header [blocks,
// block size, last block's size, compressed size of each block], base64,
// then the blocks' zlib streams one after the other, base64. On failure the
// array's text says so, which makes the file unreadable: a reader names it.
static void compressed_block(FILE *f, const void *data, size_t bytes) {
  const size_t blocks = bytes ? (bytes + BLOCK_BYTES - 1) / BLOCK_BYTES : 0;
  uint64_t *header = malloc(sizeof(uint64_t) * (3 + blocks));
  const uLong bound = compressBound(BLOCK_BYTES);
  unsigned char *packed = malloc(bound * (blocks ? blocks : 1));
  size_t packed_bytes = 0;
  int ok = header && packed;
  if (ok) {
    header[0] = blocks;
    header[1] = BLOCK_BYTES;
    header[2] = blocks ? bytes - (blocks - 1) * BLOCK_BYTES : 0;
  }
  for (size_t b = 0; ok && b < blocks; ++b) {
    const size_t in = b + 1 < blocks ? BLOCK_BYTES : (size_t)header[2];
    uLongf out = bound;
    ok = compress2(packed + packed_bytes, &out, (const Bytef *)data + b * BLOCK_BYTES, (uLong)in, Z_BEST_SPEED) == Z_OK;
    header[3 + b] = out;
    packed_bytes += out;
  }
  if (ok) {
    base64(f, (const unsigned char *)header, sizeof(uint64_t) * (3 + blocks));
    base64(f, packed, packed_bytes);
  } else {
    fputs("out of memory or zlib failed", f);
  }
  free(header);
  free(packed);
}

static void data_array(FILE *f, const char *vtk_type, const char *name, int components, const void *data,
                       size_t bytes) {
  fprintf(f, "<DataArray type=\"%s\"", vtk_type);
  if (name) {
    fputs(" Name=\"", f);
    fascia_xml_text(f, name);
    fputc('"', f);
  }
  fprintf(f, " NumberOfComponents=\"%d\" format=\"binary\">", components);
  compressed_block(f, data, bytes);
  fprintf(f, "</DataArray>\n");
}

static void file_header(FILE *f, const char *type) {
  fprintf(f,
          "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<VTKFile type=\"%s\" version=\"1.0\" byte_order=\"%s\" "
          "header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">\n",
          type, little_endian() ? "LittleEndian" : "BigEndian");
}

// Field data of the whole data set: the length unit, and the time if any.
static void field_data(FILE *f, double time) {
  const double metre = 1;
  fputs("<FieldData>\n", f);
  data_array(f, "Float64", "length_unit_m", 1, &metre, sizeof metre);
  if (!isnan(time)) data_array(f, "Float64", "TimeValue", 1, &time, sizeof time);
  fputs("</FieldData>\n", f);
}

static void point_data_open(FILE *f, const fascia_vtk_piece *piece) {
  fputs("<PointData", f);
  if (piece && piece->scalars) {
    fputs(" Scalars=\"", f);
    fascia_xml_text(f, piece->scalars);
    fputc('"', f);
  }
  if (piece && piece->vectors) {
    fputs(" Vectors=\"", f);
    fascia_xml_text(f, piece->vectors);
    fputc('"', f);
  }
  fputs(">\n", f);
}

static uint8_t cell_type(int nodes) {
  switch (nodes) {
  case 2: return 3;  // VTK_LINE
  case 3: return 5;  // VTK_TRIANGLE
  case 4: return 10; // VTK_TETRA
  default: return 1; // VTK_VERTEX
  }
}

void fascia_vtk_begin_piece(FILE *f, const char *type, const fascia_vtk_piece *piece, const fascia_real *points,
                            int64_t point_count, int nodes, const int32_t *cell_nodes, int64_t cell_count) {
  const int poly = !strcmp(type, "PolyData");
  file_header(f, type);
  fprintf(f, "<%s>\n", type);
  field_data(f, piece ? piece->time : NAN);
  fprintf(f, "<Piece NumberOfPoints=\"%lld\" %s=\"%lld\">\n", (long long)point_count,
          poly ? "NumberOfPolys" : "NumberOfCells", (long long)cell_count);
  fprintf(f, "<Points>");
  data_array(f, "Float64", NULL, 3, points, 3 * sizeof(fascia_real) * (size_t)point_count);
  fprintf(f, "</Points>\n<%s>\n", poly ? "Polys" : "Cells");
  int64_t *offsets = malloc(sizeof(int64_t) * (size_t)(cell_count + 1));
  int32_t *vertices = cell_nodes ? NULL : malloc(sizeof(int32_t) * (size_t)(cell_count + 1));
  uint8_t *types = poly ? NULL : malloc((size_t)cell_count + 1);
  if (offsets && (cell_nodes || vertices) && (poly || types)) {
    for (int64_t c = 0; c < cell_count; ++c) {
      offsets[c] = nodes * (c + 1);
      if (vertices) vertices[c] = (int32_t)c;
      if (types) types[c] = cell_type(nodes);
    }
    data_array(f, "Int32", "connectivity", 1, cell_nodes ? cell_nodes : vertices,
               sizeof(int32_t) * (size_t)nodes * (size_t)cell_count);
    data_array(f, "Int64", "offsets", 1, offsets, sizeof(int64_t) * (size_t)cell_count);
    if (types) data_array(f, "UInt8", "types", 1, types, (size_t)cell_count);
  } else {
    fprintf(f, "out of memory"); // an unreadable file: the reader says where
  }
  free(offsets), free(vertices), free(types);
  fprintf(f, "</%s>\n", poly ? "Polys" : "Cells");
  point_data_open(f, piece);
}

void fascia_vtk_begin(FILE *f, const char *type, const fascia_real *points, int64_t point_count, int nodes,
                      const int32_t *cell_nodes, int64_t cell_count) {
  fascia_vtk_begin_piece(f, type, NULL, points, point_count, nodes, cell_nodes, cell_count);
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
  file_header(f, "ImageData");
  fprintf(f,
          "<ImageData WholeExtent=\"0 %d 0 %d 0 %d\" Origin=\"%.17g %.17g %.17g\" Spacing=\"%.17g %.17g %.17g\">\n",
          (int)dims[0] - 1, (int)dims[1] - 1, (int)dims[2] - 1, origin[0], origin[1], origin[2], spacing, spacing,
          spacing);
  field_data(f, NAN);
  fprintf(f, "<Piece Extent=\"0 %d 0 %d 0 %d\">\n<PointData>\n", (int)dims[0] - 1, (int)dims[1] - 1,
          (int)dims[2] - 1);
}

void fascia_vtk_array_float(FILE *f, const char *name, const float *values, int64_t point_count) {
  data_array(f, "Float32", name, 1, values, sizeof(float) * (size_t)point_count);
}
