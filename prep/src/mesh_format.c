// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Checks of mesh files before assimp reads them, for formats whose loader
// is lenient where a damaged file should be refused: assimp reads an ASCII
// STL without its `endsolid` (a file cut after a whole facet), or an ASCII
// PLY with fewer faces than its header declares, as a smaller mesh, without
// a word. An STL is binary exactly when its size is 84 + 50 n bytes for the
// n triangles its header counts (assimp's own test); otherwise it must be a
// complete ASCII STL. OBJ and OFF are text: a NUL or other control byte
// (which assimp's parsers read as a line's or the file's end, dropping the
// rest of a face) is refused; an OFF's faces are read against its header
// (assimp clamps an index past the vertices to the last one, and reads a
// negative one as another vertex).
#define _POSIX_C_SOURCE 200809L // strcasecmp
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "prep_util.h"

#define STL_HEADER 84
#define STL_TRIANGLE 50
#define TOKEN_SIZE 64

typedef struct stl_reader {
  FILE *f;
  int64_t line;       // line of the last token read (from 1)
  char token[TOKEN_SIZE];
  int binary_bytes;   // a byte that no text file holds was seen
} stl_reader;

// The next whitespace-separated token into rd->token (cut at TOKEN_SIZE - 1
// characters); 0 at the end of the file.
static int next_token(stl_reader *rd) {
  int c;
  while ((c = getc(rd->f)) != EOF && isspace(c))
    if (c == '\n') ++rd->line;
  if (c == EOF) return 0;
  size_t n = 0;
  do {
    if ((c < 32 && c != '\t' && c != '\r') || c == 127) rd->binary_bytes = 1;
    if (n + 1 < TOKEN_SIZE) rd->token[n++] = (char)c;
  } while ((c = getc(rd->f)) != EOF && !isspace(c));
  rd->token[n] = 0;
  if (c == '\n') ungetc(c, rd->f);
  return 1;
}

static void skip_line(stl_reader *rd) {
  int c;
  while ((c = getc(rd->f)) != EOF && c != '\n') {}
  if (c == '\n') ++rd->line;
}

static int is_number(const char *text) {
  char *end;
  strtod(text, &end);
  return end != text && *end == 0;
}

static fascia_status stl_fail(fascia_ctx *ctx, const char *path, const stl_reader *rd, int64_t facets, int at_end,
                              const char *expected) {
  if (rd->binary_bytes)
    return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                     "mesh '%s': starts like an ASCII STL (\"solid\") but holds binary bytes, and its size does not "
                     "fit a binary STL either (84 + 50 bytes per triangle); the file is truncated or damaged",
                     path);
  if (at_end)
    return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                     "mesh '%s': ASCII STL cut short at line %lld, after %lld complete facets (expected %s, found "
                     "the end of the file; no \"endsolid\"): the file is truncated; export it again",
                     path, (long long)rd->line, (long long)facets, expected);
  return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                   "mesh '%s': ASCII STL line %lld: expected %s, found '%s' (after %lld complete facets); the file is "
                   "damaged",
                   path, (long long)rd->line, expected, rd->token, (long long)facets);
}

// Reads the keyword word (case-insensitive), or fails naming it.
#define EXPECT_WORD(word, what)                                                                                     \
  do {                                                                                                              \
    if (!next_token(&rd)) return stl_fail(ctx, path, &rd, facets, 1, what);                                         \
    if (strcasecmp(rd.token, word)) return stl_fail(ctx, path, &rd, facets, 0, what);                               \
  } while (0)
#define EXPECT_NUMBERS(count, what)                                                                                 \
  do {                                                                                                              \
    for (int k_ = 0; k_ < (count); ++k_) {                                                                          \
      if (!next_token(&rd)) return stl_fail(ctx, path, &rd, facets, 1, what);                                       \
      if (!is_number(rd.token)) return stl_fail(ctx, path, &rd, facets, 0, what);                                   \
    }                                                                                                               \
  } while (0)

static fascia_status check_ascii_stl(fascia_ctx *ctx, const char *path, FILE *f) {
  stl_reader rd = {f, 1, "", 0};
  int64_t facets = 0;
  if (!next_token(&rd)) return stl_fail(ctx, path, &rd, facets, 1, "\"solid\"");
  for (;;) { // one solid: "solid NAME" facet* "endsolid NAME"
    if (strncasecmp(rd.token, "solid", 5)) return stl_fail(ctx, path, &rd, facets, 0, "\"solid\"");
    skip_line(&rd);
    for (;;) {
      if (!next_token(&rd)) return stl_fail(ctx, path, &rd, facets, 1, "\"facet\" or \"endsolid\"");
      if (!strcasecmp(rd.token, "endsolid")) break;
      if (strcasecmp(rd.token, "facet")) return stl_fail(ctx, path, &rd, facets, 0, "\"facet\" or \"endsolid\"");
      EXPECT_WORD("normal", "\"normal\"");
      EXPECT_NUMBERS(3, "the three numbers of a facet normal");
      EXPECT_WORD("outer", "\"outer loop\"");
      EXPECT_WORD("loop", "\"outer loop\"");
      for (int v = 0; v < 3; ++v) {
        EXPECT_WORD("vertex", v ? "the next \"vertex\" of the facet (3 per facet)" : "\"vertex\"");
        EXPECT_NUMBERS(3, "the three coordinates of a vertex");
      }
      EXPECT_WORD("endloop", "\"endloop\" (3 vertices per facet)");
      EXPECT_WORD("endfacet", "\"endfacet\"");
      ++facets;
    }
    skip_line(&rd); // the solid's name
    if (!next_token(&rd)) break;
  }
  if (rd.binary_bytes) return stl_fail(ctx, path, &rd, facets, 0, "text");
  return FASCIA_OK;
}

// ----------------------------------------------------------------- PLY
// The header declares each element's count and properties; assimp reads an
// ASCII body with fewer elements than declared as a smaller mesh. The body
// is walked element by element (lists by their counts) to its end.

#define PLY_MAX_ELEMENTS 16
#define PLY_MAX_PROPERTIES 32

typedef struct ply_property {
  int size;       // bytes of a scalar or of each list item
  int count_size; // bytes of a list's count, 0 for a scalar
} ply_property;

typedef struct ply_element {
  char name[TOKEN_SIZE];
  int64_t count;
  int property_count;
  ply_property property[PLY_MAX_PROPERTIES];
} ply_element;

static int ply_type_size(const char *type) {
  static const char *const names[] = {"char", "uchar", "int8", "uint8", "short", "ushort", "int16", "uint16",
                                      "int", "uint", "int32", "uint32", "float", "float32", "double", "float64"};
  static const int sizes[] = {1, 1, 1, 1, 2, 2, 2, 2, 4, 4, 4, 4, 4, 4, 8, 8};
  for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; ++k)
    if (!strcmp(type, names[k])) return sizes[k];
  return 0;
}

// Reads one header line into line[size] (cut there); 0 at the end of the file.
static int ply_line(FILE *f, char *line, size_t size) {
  size_t n = 0;
  int c;
  while ((c = getc(f)) != EOF && c != '\n')
    if (n + 1 < size && c != '\r') line[n++] = (char)c;
  line[n] = 0;
  return c != EOF || n > 0;
}

static fascia_status ply_header_fail(fascia_ctx *ctx, const char *path, int line, const char *what) {
  return PREP_FAIL(ctx, FASCIA_ERR_FORMAT, "mesh '%s': PLY header line %d: %s; the file is damaged", path, line,
                   what);
}

// Little- or big-endian unsigned integer of size bytes (a list count).
static int64_t ply_count(const unsigned char *b, int size, int big) {
  int64_t v = 0;
  for (int k = 0; k < size; ++k) v |= (int64_t)b[big ? size - 1 - k : k] << (8 * k);
  return v;
}

static fascia_status ply_body_fail(fascia_ctx *ctx, const char *path, const ply_element *e, int64_t done,
                                   const char *how) {
  return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                   "mesh '%s': %s PLY whose header declares %lld '%s' elements ends after %lld of them; the file is "
                   "truncated",
                   path, how, (long long)e->count, e->name, (long long)done);
}

static fascia_status check_ply(fascia_ctx *ctx, const char *path, FILE *f, int64_t size) {
  ply_element element[PLY_MAX_ELEMENTS];
  int elements = 0, format = -1; // 0 ascii, 1 little, 2 big endian
  char line[256], word[3][TOKEN_SIZE];
  for (int number = 1;; ++number) {
    if (!ply_line(f, line, sizeof line)) return ply_header_fail(ctx, path, number, "the file ends before \"end_header\"");
    word[0][0] = word[1][0] = word[2][0] = 0;
    char rest[TOKEN_SIZE] = "";
    const int words = sscanf(line, "%63s %63s %63s %63s", word[0], word[1], word[2], rest);
    if (number == 1) {
      if (strcmp(word[0], "ply") || words != 1) return ply_header_fail(ctx, path, number, "expected \"ply\"");
      continue;
    }
    if (words <= 0 || !strcmp(word[0], "comment") || !strcmp(word[0], "obj_info")) continue;
    if (!strcmp(word[0], "end_header")) break;
    if (!strcmp(word[0], "format")) {
      format = !strcmp(word[1], "ascii") ? 0 : !strcmp(word[1], "binary_little_endian") ? 1
             : !strcmp(word[1], "binary_big_endian")                              ? 2
                                                                                   : -1;
      if (format < 0) return ply_header_fail(ctx, path, number, "unknown format");
    } else if (!strcmp(word[0], "element")) {
      char *end;
      const long long count = strtoll(word[2], &end, 10);
      if (words != 3 || *end || end == word[2] || count < 0)
        return ply_header_fail(ctx, path, number, "expected \"element NAME COUNT\"");
      if (elements == PLY_MAX_ELEMENTS) return ply_header_fail(ctx, path, number, "more than 16 elements");
      ply_element *e = element + elements++;
      snprintf(e->name, sizeof e->name, "%s", word[1]);
      e->count = count;
      e->property_count = 0;
    } else if (!strcmp(word[0], "property")) {
      if (!elements) return ply_header_fail(ctx, path, number, "a property before any element");
      ply_element *e = element + elements - 1;
      if (e->property_count == PLY_MAX_PROPERTIES)
        return ply_header_fail(ctx, path, number, "more than 32 properties in an element");
      ply_property *q = e->property + e->property_count++;
      if (!strcmp(word[1], "list")) {
        q->count_size = ply_type_size(word[2]);
        char item[TOKEN_SIZE] = "";
        sscanf(line, "%*s %*s %*s %63s", item);
        q->size = ply_type_size(item);
        if (!q->count_size || !q->size || words != 4)
          return ply_header_fail(ctx, path, number, "expected \"property list COUNT_TYPE ITEM_TYPE NAME\"");
      } else {
        q->count_size = 0;
        q->size = ply_type_size(word[1]);
        if (!q->size || words != 3) return ply_header_fail(ctx, path, number, "expected \"property TYPE NAME\"");
      }
    } else {
      return ply_header_fail(ctx, path, number, "unknown line");
    }
  }
  if (format < 0) return ply_header_fail(ctx, path, 2, "no \"format\" line");
  for (int k = 0; k < elements; ++k) {
    const ply_element *e = element + k;
    for (int64_t i = 0; i < e->count; ++i)
      for (int p = 0; p < e->property_count; ++p) {
        const ply_property *q = e->property + p;
        if (format == 0) { // a token per scalar; a list's count, then its items
          stl_reader rd = {f, 1, "", 0};
          if (!next_token(&rd)) return ply_body_fail(ctx, path, e, i, "ASCII");
          if (!is_number(rd.token))
            return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                             "mesh '%s': ASCII PLY '%s' element %lld: expected a number, found '%s'; the file is "
                             "damaged",
                             path, e->name, (long long)i, rd.token);
          const int64_t items = q->count_size ? (int64_t)strtod(rd.token, NULL) : 0;
          for (int64_t j = 0; j < items; ++j)
            if (!next_token(&rd)) return ply_body_fail(ctx, path, e, i, "ASCII");
        } else {
          unsigned char b[8];
          if (q->count_size) {
            if (fread(b, 1, (size_t)q->count_size, f) != (size_t)q->count_size)
              return ply_body_fail(ctx, path, e, i, "binary");
            const int64_t skip = ply_count(b, q->count_size, format == 2) * q->size;
            if (skip > size - ftell(f) || fseek(f, (long)skip, SEEK_CUR)) return ply_body_fail(ctx, path, e, i, "binary");
          } else if (fread(b, 1, (size_t)q->size, f) != (size_t)q->size) {
            return ply_body_fail(ctx, path, e, i, "binary");
          }
        }
      }
  }
  return FASCIA_OK;
}

// A control byte in a text mesh: its line, 0 if none.
static int64_t control_byte_line(const char *text, size_t size, unsigned *byte) {
  int64_t line = 1;
  for (size_t k = 0; k < size; ++k) {
    const unsigned char c = (unsigned char)text[k];
    if (c == '\n') ++line;
    else if ((c < 32 && c != '\t' && c != '\r' && c != '\f' && c != '\v') || c == 127) {
      *byte = c;
      return line;
    }
  }
  return 0;
}

typedef struct off_reader {
  const char *text;
  size_t size, at;
  int64_t line;
  char token[TOKEN_SIZE];
} off_reader;

// The next token (comments from # to the line's end skipped); 0 at the end.
// same_line: 0 when it must stay on the current line (returns 0 at its end).
static int off_token(off_reader *rd, int same_line) {
  for (;;) {
    while (rd->at < rd->size && isspace((unsigned char)rd->text[rd->at]) && rd->text[rd->at] != '\n') ++rd->at;
    if (rd->at < rd->size && rd->text[rd->at] == '#')
      while (rd->at < rd->size && rd->text[rd->at] != '\n') ++rd->at;
    if (rd->at >= rd->size) return 0;
    if (rd->text[rd->at] != '\n') break;
    if (same_line) return 0;
    ++rd->at, ++rd->line;
  }
  size_t n = 0;
  while (rd->at < rd->size && !isspace((unsigned char)rd->text[rd->at])) {
    if (n + 1 < TOKEN_SIZE) rd->token[n++] = rd->text[rd->at];
    ++rd->at;
  }
  rd->token[n] = 0;
  return 1;
}

static void off_skip_line(off_reader *rd) {
  while (rd->at < rd->size && rd->text[rd->at] != '\n') ++rd->at;
}

static int off_integer(const char *token, int64_t *value) {
  char *end;
  errno = 0;
  const long long v = strtoll(token, &end, 10);
  *value = v;
  return end != token && *end == 0 && errno == 0;
}

// An ASCII OFF ("OFF" then vertex, face and edge counts): every face's
// vertex count and indices read and checked against the vertex count.
static fascia_status check_off(fascia_ctx *ctx, const char *path, const char *text, size_t size) {
  off_reader rd = {.text = text, .size = size, .line = 1};
  if (!off_token(&rd, 0) || strcmp(rd.token, "OFF")) return FASCIA_OK; // COFF, NOFF, binary: assimp's checks
  int64_t counts[3];
  for (int k = 0; k < 3; ++k)
    PREP_CHECK(off_token(&rd, 0) && off_integer(rd.token, counts + k) && counts[k] >= 0, ctx, FASCIA_ERR_FORMAT,
               "mesh '%s' line %lld: OFF header's %s count is '%s', expected a whole number; the file is damaged",
               path, (long long)rd.line, k == 0 ? "vertex" : k == 1 ? "face" : "edge", rd.token);
  const int64_t nv = counts[0], nf = counts[1];
  for (int64_t v = 0; v < nv; ++v) {
    for (int c = 0; c < 3; ++c)
      PREP_CHECK(off_token(&rd, c > 0) && is_number(rd.token), ctx, FASCIA_ERR_FORMAT,
                 "mesh '%s' line %lld: vertex %lld of the %lld the OFF header declares %s; the file is truncated or "
                 "damaged",
                 path, (long long)rd.line, (long long)v, (long long)nv,
                 rd.at >= rd.size ? "is missing" : "does not hold 3 coordinates");
    off_skip_line(&rd); // colours may follow
  }
  for (int64_t f = 0; f < nf; ++f) {
    int64_t n;
    PREP_CHECK(off_token(&rd, 0), ctx, FASCIA_ERR_FORMAT,
               "mesh '%s': the file ends after %lld faces of the %lld its OFF header declares; the file is truncated",
               path, (long long)f, (long long)nf);
    PREP_CHECK(off_integer(rd.token, &n) && n >= 3 && n <= 1000000, ctx, FASCIA_ERR_FORMAT,
               "mesh '%s' line %lld: face %lld starts with '%s', expected its vertex count (3 or more); the file is "
               "damaged",
               path, (long long)rd.line, (long long)f, rd.token);
    for (int64_t i = 0; i < n; ++i) {
      int64_t index;
      PREP_CHECK(off_token(&rd, 1), ctx, FASCIA_ERR_FORMAT,
                 "mesh '%s' line %lld: face %lld has %lld vertex indices, its count says %lld; the file is damaged",
                 path, (long long)rd.line, (long long)f, (long long)i, (long long)n);
      PREP_CHECK(off_integer(rd.token, &index) && index >= 0 && index < nv, ctx, FASCIA_ERR_FORMAT,
                 "mesh '%s' line %lld: face %lld has vertex index '%s', expected 0 to %lld (the file declares %lld "
                 "vertices); the file is damaged",
                 path, (long long)rd.line, (long long)f, rd.token, (long long)nv - 1, (long long)nv);
    }
    off_skip_line(&rd); // colours may follow
  }
  return FASCIA_OK;
}

// OBJ and OFF: no control bytes; an OFF's faces within its vertices.
static fascia_status check_text_mesh(fascia_ctx *ctx, const char *path, int off) {
  char *text;
  size_t size;
  PREP_TRY(prep_read_file(ctx, path, "mesh", INT64_MAX / 4, &text, &size));
  unsigned byte = 0;
  const int64_t line = control_byte_line(text, size, &byte);
  fascia_status status = FASCIA_OK;
  if (line)
    status = PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                       "mesh '%s' line %lld: a control byte (0x%02x) in a text mesh, which the reader would take for the "
                       "line's or the file's end; the file is damaged",
                       path, (long long)line, byte);
  else if (off)
    status = check_off(ctx, path, text, size);
  free(text);
  return status;
}

static int has_extension(const char *path, const char *ext) {
  const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
  return dot && (!slash || dot > slash) && !strcasecmp(dot + 1, ext);
}

fascia_status prep_mesh_precheck(fascia_ctx *ctx, const char *path, FILE *f, int64_t size) {
  if (has_extension(path, "ply")) return check_ply(ctx, path, f, size);
  if (has_extension(path, "obj") || has_extension(path, "off")) return check_text_mesh(ctx, path, has_extension(path, "off"));
  if (!has_extension(path, "stl")) return FASCIA_OK;
  unsigned char header[STL_HEADER];
  const size_t got = fread(header, 1, sizeof header, f);
  PREP_CHECK(!ferror(f), ctx, FASCIA_ERR_IO, "mesh '%s': read error", path);
  if (got == STL_HEADER) {
    const uint32_t count = (uint32_t)header[80] | (uint32_t)header[81] << 8 | (uint32_t)header[82] << 16 |
                           (uint32_t)header[83] << 24;
    if (size == STL_HEADER + STL_TRIANGLE * (int64_t)count) return FASCIA_OK;
  }
  // a binary header holds control bytes (at least in its triangle count); text does not
  int binary = 0;
  for (size_t k = 0; k < got; ++k) binary |= header[k] == 127 || (header[k] < 32 && !isspace(header[k]));
  size_t start = 0;
  while (start < got && isspace(header[start])) ++start;
  if (!binary && got - start >= 5 && !strncasecmp((const char *)header + start, "solid", 5)) {
    rewind(f);
    return check_ascii_stl(ctx, path, f);
  }
  if (got < STL_HEADER)
    return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                     "mesh '%s': %lld bytes, shorter than the 84-byte header of a binary STL and not an ASCII STL "
                     "(\"solid\" ...); the file is truncated or damaged",
                     path, (long long)size);
  const uint32_t count = (uint32_t)header[80] | (uint32_t)header[81] << 8 | (uint32_t)header[82] << 16 |
                         (uint32_t)header[83] << 24;
  return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                   "mesh '%s': binary STL whose header counts %lu triangles, which take %lld bytes, but the file has "
                   "%lld bytes; the file is truncated or damaged",
                   path, (unsigned long)count, (long long)(STL_HEADER + STL_TRIANGLE * (int64_t)count),
                   (long long)size);
}
