// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Checks of mesh files before assimp reads them, for formats whose loader
// is lenient where a damaged file should be refused: assimp reads an ASCII
// STL without its `endsolid` (a file cut after a whole facet) as a smaller
// mesh, without a word. An STL is binary exactly when its size is 84 + 50 n
// bytes for the n triangles its header counts (assimp's own test); otherwise
// it must be a complete ASCII STL.
#define _POSIX_C_SOURCE 200809L // strcasecmp
#include <ctype.h>
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

static int has_extension(const char *path, const char *ext) {
  const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
  return dot && (!slash || dot > slash) && !strcasecmp(dot + 1, ext);
}

fascia_status prep_mesh_precheck(fascia_ctx *ctx, const char *path, FILE *f, int64_t size) {
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
