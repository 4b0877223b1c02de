// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Reading a label map: NIfTI-1/-2 with the NIfTI reference library
// (nifti2_io, which reads both versions and gzip), NRRD with teem's nrrd
// (the format's reference implementation, which 3D Slicer's .seg.nrrd
// follows). The voxel-centre affine goes from the file's frame (NIfTI: RAS+
// by definition; NRRD: its space field) to the scene's frame, in metres
// (docs/labelmaps.md).
#include <math.h>
#include <stdint.h>
#include <nifti2_io.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <teem/nrrd.h>
#include <zlib.h>
#include <bzlib.h>

#include "labels.h"

void prep_labelmap_destroy(prep_labelmap **map) {
  if (!map || !*map) return;
  free((*map)->labels);
  free(*map);
  *map = NULL;
}

static int ends_with(const char *s, const char *tail) {
  const size_t n = strlen(s), m = strlen(tail);
  return n >= m && !strcmp(s + n - m, tail);
}

// Copies n integer values of a type (bytes per value, signed or not) into labels.
// swap: the file's byte order is not this machine's.
static fascia_status copy_labels(fascia_ctx *ctx, const char *path, const void *data, int64_t n, int bytes,
                                 int is_signed, int swap, int32_t *labels) {
  for (int64_t k = 0; k < n; ++k) {
    int64_t v;
    union {
      unsigned char b[8];
      int8_t i8;
      uint8_t u8;
      int16_t i16;
      uint16_t u16;
      int32_t i32;
      uint32_t u32;
      int64_t i64;
    } p;
    const unsigned char *src = (const unsigned char *)data + k * bytes;
    for (int b = 0; b < bytes; ++b) p.b[b] = src[swap ? bytes - 1 - b : b];
    switch (bytes) {
    case 1: v = is_signed ? (int64_t)p.i8 : (int64_t)p.u8; break;
    case 2: v = is_signed ? (int64_t)p.i16 : (int64_t)p.u16; break;
    case 4: v = is_signed ? (int64_t)p.i32 : (int64_t)p.u32; break;
    default: v = p.i64; break; // 8: unsigned above INT64_MAX reads negative, refused
    }
    if (v < 0 || v > PREP_MAX_LABEL)
      return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                       "label map '%s': voxel %lld holds %lld, not a label (expected 0 .. %d, 0 the background)", path,
                       (long long)k, (long long)v, PREP_MAX_LABEL);
    labels[k] = (int32_t)v;
  }
  return FASCIA_OK;
}

// A RAS or LPS affine (mm) into the scene's frame in metres: x and y flip
// between the two.
static void place(prep_labelmap *map, double affine[3][4], int lps, int32_t frame, double scale) {
  const double flip = (lps != (frame == FASCIA_PREP_FRAME_LPS)) ? -1 : 1;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) map->to_world[4 * r + c] = (r < 2 ? flip : 1) * scale * affine[r][c];
}

static fascia_status check_affine(fascia_ctx *ctx, const char *path, const double *a) {
  const double det = a[0] * (a[5] * a[10] - a[6] * a[9]) - a[1] * (a[4] * a[10] - a[6] * a[8]) +
                     a[2] * (a[4] * a[9] - a[5] * a[8]);
  for (int k = 0; k < 12; ++k)
    PREP_CHECK(isfinite(a[k]), ctx, FASCIA_ERR_FORMAT, "label map '%s': its affine has a non-finite entry", path);
  PREP_CHECK(fabs(det) > 1e-30, ctx, FASCIA_ERR_FORMAT,
             "label map '%s': its affine is singular (zero voxel size or collapsed axes)", path);
  return FASCIA_OK;
}

static fascia_status alloc_labels(fascia_ctx *ctx, const char *path, prep_labelmap *map, const int64_t *dims) {
  for (int r = 0; r < 3; ++r)
    PREP_CHECK(dims[r] >= 1 && dims[r] <= 1 << 15, ctx, FASCIA_ERR_FORMAT,
               "label map '%s': axis %d has %lld voxels (expected 1 .. 32768)", path, r, (long long)dims[r]);
  for (int r = 0; r < 3; ++r) map->dims[r] = (int32_t)dims[r];
  map->labels = prep_calloc(dims[0] * dims[1] * dims[2], sizeof(int32_t));
  PREP_CHECK(map->labels, ctx, FASCIA_ERR_MEMORY, "label map '%s': out of memory for %lld voxels", path,
             (long long)(dims[0] * dims[1] * dims[2]));
  return FASCIA_OK;
}

// A gzip file inflated member after member to its end: zlib checks each
// member's CRC32 and length there, so a flipped bit or a cut file is caught
// even when the voxels were all read before the damage.
typedef struct gz_reader {
  z_stream z;
  const unsigned char *in; // bytes not yet given to zlib
  size_t left;
  int end;          // the last member ended with the file
  int after_member; // at least one member ended: more bytes must be another member
} gz_reader;

static void gz_feed(gz_reader *g) {
  if (g->z.avail_in == 0 && g->left) {
    const size_t n = g->left > ((size_t)1 << 30) ? (size_t)1 << 30 : g->left;
    g->z.next_in = (Bytef *)(uintptr_t)g->in;
    g->z.avail_in = (uInt)n;
    g->in += n;
    g->left -= n;
  }
}

// Up to want bytes into out (fewer only at the end of the file); NULL, or
// why the stream is bad.
static const char *gz_pull(gz_reader *g, unsigned char *out, size_t want, size_t *got) {
  *got = 0;
  while (*got < want && !g->end) {
    gz_feed(g);
    const size_t chunk = want - *got > ((size_t)1 << 30) ? (size_t)1 << 30 : want - *got;
    g->z.next_out = out + *got;
    g->z.avail_out = (uInt)chunk;
    const int rc = inflate(&g->z, Z_NO_FLUSH);
    *got += chunk - g->z.avail_out;
    if (rc == Z_STREAM_END) {
      gz_feed(g);
      if (g->z.avail_in == 0) {
        g->end = 1;
        break;
      }
      g->after_member = 1; // concatenated members are one gzip file (RFC 1952)
      if (inflateReset(&g->z) != Z_OK) return "zlib could not restart";
      continue;
    }
    if (rc == Z_DATA_ERROR && g->after_member && g->z.total_in <= 10)
      return "bytes after the end of the gzip stream that are not another gzip member";
    if (rc == Z_BUF_ERROR && g->z.avail_in == 0 && g->left == 0)
      return "the gzip stream is cut short (the file ends before the stream's end)";
    if (rc != Z_OK && rc != Z_BUF_ERROR) return g->z.msg ? g->z.msg : "damaged gzip data";
  }
  return NULL;
}

// The header fields fascia trusts, read from the raw bytes before nifti2_io
// interprets them, so each damage is named for what it is.
typedef struct nifti_head {
  int version, swap, bytes, is_signed;
  nifti_1_header h1; // as in the file, for nifti2_io
  nifti_2_header h2;
  int64_t dim[8], vox_offset, total; // total: vox_offset + the voxels' bytes
  int datatype, bitpix, qform_code, sform_code;
  double pixdim[8];
} nifti_head;

static uint32_t swap32(uint32_t v) {
  return (v >> 24) | ((v >> 8) & 0xff00u) | ((v << 8) & 0xff0000u) | (v << 24);
}

// sizeof_hdr (the first 4 bytes): the version and byte order.
static fascia_status nifti_version(fascia_ctx *ctx, const char *path, const unsigned char *b, size_t have,
                                   nifti_head *h) {
  PREP_CHECK(have >= 4, ctx, FASCIA_ERR_FORMAT, "label map '%s': not a NIfTI-1 or NIfTI-2 file (%zu bytes)", path,
             have);
  uint32_t v;
  memcpy(&v, b, 4);
  if (v == 348 || swap32(v) == 348) h->version = 1;
  else if (v == 540 || swap32(v) == 540) h->version = 2;
  else
    return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                     "label map '%s': not a NIfTI-1 or NIfTI-2 file (its first 4 bytes, sizeof_hdr, read %lld; "
                     "expected 348 or 540)",
                     path, (long long)(int32_t)v);
  h->swap = v != 348 && v != 540;
  return FASCIA_OK;
}

// The fields both NIfTI versions have, from header c (nifti_1_header or
// nifti_2_header, in host byte order) into h.
#define COPY_SHARED_FIELDS(h, c)                                                                                      \
  do {                                                                                                                \
    for (int d = 0; d < 8; ++d) (h)->dim[d] = (c).dim[d], (h)->pixdim[d] = (c).pixdim[d];                             \
    (h)->datatype = (c).datatype, (h)->bitpix = (c).bitpix;                                                           \
    (h)->qform_code = (c).qform_code, (h)->sform_code = (c).sform_code;                                               \
  } while (0)

static fascia_status nifti_header(fascia_ctx *ctx, const char *path, const unsigned char *b, size_t have,
                                  nifti_head *h) {
  const size_t size = h->version == 1 ? sizeof(nifti_1_header) : sizeof(nifti_2_header);
  PREP_CHECK(have >= size, ctx, FASCIA_ERR_FORMAT,
             "label map '%s': cut short inside its header (%zu bytes, a NIfTI-%d header has %zu)", path, have,
             h->version, size);
  if (h->version == 1) {
    memcpy(&h->h1, b, sizeof h->h1);
    nifti_1_header c = h->h1;
    if (h->swap) swap_nifti_header(&c, 1);
    if (!memcmp(c.magic, "ni1", 4))
      return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                       "label map '%s': the header of a two-file NIfTI (magic 'ni1': voxels in a separate .img); "
                       "save it as one .nii or .nii.gz",
                       path);
    PREP_CHECK(!memcmp(c.magic, "n+1", 4), ctx, FASCIA_ERR_FORMAT,
               "label map '%s': bad magic at byte 344 (expected 'n+1'): not a NIfTI-1 file, or its header is "
               "damaged",
               path);
    COPY_SHARED_FIELDS(h, c);
    PREP_CHECK(isfinite(c.vox_offset) && c.vox_offset == floor(c.vox_offset) && c.vox_offset < 0x1p62, ctx,
               FASCIA_ERR_FORMAT, "label map '%s': vox_offset %g is not a byte offset; the header is damaged", path,
               (double)c.vox_offset);
    h->vox_offset = (int64_t)c.vox_offset;
  } else {
    memcpy(&h->h2, b, sizeof h->h2);
    nifti_2_header c = h->h2;
    if (h->swap) swap_nifti_header(&c, 2);
    PREP_CHECK(!memcmp(c.magic, "n+2\0\r\n\032\n", 8), ctx, FASCIA_ERR_FORMAT,
               "label map '%s': bad magic at byte 4 (expected 'n+2' and its 4 check bytes): not a single-file "
               "NIfTI-2, or its header is damaged",
               path);
    COPY_SHARED_FIELDS(h, c);
    h->vox_offset = c.vox_offset;
  }
  const int64_t ndim = h->dim[0];
  PREP_CHECK(ndim >= 1 && ndim <= 7, ctx, FASCIA_ERR_FORMAT,
             "label map '%s': dim[0] (the number of dimensions) is %lld, expected 1 to 7; the header is damaged", path,
             (long long)ndim);
  int64_t nvox = 1;
  for (int d = 1; d <= ndim; ++d) {
    PREP_CHECK(h->dim[d] >= 1 && h->dim[d] <= INT32_MAX, ctx, FASCIA_ERR_FORMAT,
               "label map '%s': dim[%d] is %lld voxels, expected at least 1; the header is damaged", path, d,
               (long long)h->dim[d]);
    PREP_CHECK(nvox <= INT64_MAX / 16 / h->dim[d], ctx, FASCIA_ERR_FORMAT,
               "label map '%s': dim[1..%lld] give more voxels than a file can hold; the header is damaged", path,
               (long long)ndim);
    nvox *= h->dim[d];
  }
  int64_t extra = 1;
  for (int d = 4; d <= ndim; ++d) extra *= h->dim[d];
  PREP_CHECK(extra == 1, ctx, FASCIA_ERR_FORMAT,
             "label map '%s': a %lld-D image (%lld volumes); a label map has one 3-D volume (save the segmentation "
             "as one label map)",
             path, (long long)ndim, (long long)extra);
  switch (h->datatype) {
  case DT_UINT8: h->bytes = 1; break;
  case DT_INT8: h->bytes = 1, h->is_signed = 1; break;
  case DT_UINT16: h->bytes = 2; break;
  case DT_INT16: h->bytes = 2, h->is_signed = 1; break;
  case DT_UINT32: h->bytes = 4; break;
  case DT_INT32: h->bytes = 4, h->is_signed = 1; break;
  case DT_UINT64:
  case DT_INT64: h->bytes = 8, h->is_signed = 1; break;
  default:
    return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                     "label map '%s': voxels are %s (datatype %d), not integers; a label map holds integer labels",
                     path, nifti_datatype_string(h->datatype), h->datatype);
  }
  PREP_CHECK(h->bitpix == 8 * h->bytes, ctx, FASCIA_ERR_FORMAT,
             "label map '%s': bitpix %d does not match datatype %s (%d bits); the header is damaged", path, h->bitpix,
             nifti_datatype_string(h->datatype), 8 * h->bytes);
  for (int d = 1; d <= 3 && d <= ndim; ++d)
    PREP_CHECK(isfinite(h->pixdim[d]) && h->pixdim[d] > 0, ctx, FASCIA_ERR_FORMAT,
               "label map '%s': pixdim[%d] (the voxel size along axis %d) is %g, expected a positive size; the header "
               "is damaged",
               path, d, d, h->pixdim[d]);
  PREP_CHECK(h->qform_code >= NIFTI_XFORM_UNKNOWN && h->qform_code <= NIFTI_XFORM_TEMPLATE_OTHER, ctx,
             FASCIA_ERR_FORMAT, "label map '%s': qform_code %d is not a NIfTI code (expected 0 to 5); the header is "
             "damaged", path, h->qform_code);
  PREP_CHECK(h->sform_code >= NIFTI_XFORM_UNKNOWN && h->sform_code <= NIFTI_XFORM_TEMPLATE_OTHER, ctx,
             FASCIA_ERR_FORMAT, "label map '%s': sform_code %d is not a NIfTI code (expected 0 to 5); the header is "
             "damaged", path, h->sform_code);
  PREP_CHECK(h->vox_offset >= (int64_t)size + 4 && h->vox_offset <= INT64_MAX / 2, ctx, FASCIA_ERR_FORMAT,
             "label map '%s': vox_offset %lld lies inside the header (a single-file NIfTI-%d's voxels start at byte "
             "%zu or later); the header is damaged",
             path, (long long)h->vox_offset, h->version, size + 4);
  h->total = h->vox_offset + nvox * h->bytes;
  return FASCIA_OK;
}

// The whole file's bytes in *data (*size of them) after its header checks:
// .nii.gz inflated to the end of its last member, and either form exactly
// as long as the header declares.
static fascia_status nifti_bytes(fascia_ctx *ctx, const char *path, nifti_head *h, unsigned char **data) {
  *data = NULL;
  char *raw;
  size_t n;
  PREP_TRY(prep_read_file(ctx, path, "label map", INT64_MAX / 4, &raw, &n));
  const unsigned char *file = (const unsigned char *)raw;
  fascia_status status = FASCIA_OK;
  if (!prep_nifti_ending(path) || strcmp(prep_nifti_ending(path), ".nii.gz")) {
    PREP_TRY_GOTO(nifti_version(ctx, path, file, n, h));
    PREP_TRY_GOTO(nifti_header(ctx, path, file, n, h));
    PREP_CHECK_GOTO((int64_t)n == h->total, ctx, FASCIA_ERR_FORMAT,
                    "label map '%s': %zu bytes, but its header declares %lld (voxels from byte %lld, %lld x %lld x "
                    "%lld of %d bytes); the file is %s",
                    path, n, (long long)h->total, (long long)h->vox_offset, (long long)h->dim[1],
                    (long long)(h->dim[0] >= 2 ? h->dim[2] : 1), (long long)(h->dim[0] >= 3 ? h->dim[3] : 1),
                    h->bytes, (int64_t)n < h->total ? "cut short" : "longer than its header says (damaged)");
    *data = (unsigned char *)raw;
    return FASCIA_OK;
  }
  PREP_CHECK_GOTO(n >= 2 && file[0] == 0x1f && file[1] == 0x8b, ctx, FASCIA_ERR_FORMAT,
                  "label map '%s': named .nii.gz but not gzip-compressed (no gzip signature); rename it .nii or "
                  "compress it",
                  path);
  gz_reader g = {.in = file, .left = n};
  PREP_CHECK_GOTO(inflateInit2(&g.z, 15 + 16) == Z_OK, ctx, FASCIA_ERR_MEMORY,
                  "label map '%s': out of memory for zlib", path);
  unsigned char head[sizeof(nifti_2_header)];
  size_t got = 0, more = 0;
  const char *why = gz_pull(&g, head, 4, &got);
  if (!why && got == 4) status = nifti_version(ctx, path, head, got, h);
  if (!why && !status) {
    const size_t size = h->version == 1 ? sizeof(nifti_1_header) : sizeof(nifti_2_header);
    why = gz_pull(&g, head + 4, size - 4, &more);
    got += more;
    if (!why) status = nifti_header(ctx, path, head, got, h);
  }
  unsigned char *full = NULL;
  if (!why && !status) {
    // a gzip stream inflates at most about 1032 times: a larger declared size is a damaged header
    const double most = 1100.0 * (double)n + 4096;
    if ((double)h->total > most)
      status = PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                         "label map '%s': its header declares %lld bytes, more than its %zu compressed bytes can hold; "
                         "the header is damaged",
                         path, (long long)h->total, n);
    else if (!(full = malloc((size_t)h->total)))
      status = PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "label map '%s': out of memory for its %lld bytes", path,
                         (long long)h->total);
  }
  if (!why && !status) {
    memcpy(full, head, got);
    why = gz_pull(&g, full + got, (size_t)h->total - got, &more);
    got += more;
  }
  if (!why && !status && (int64_t)got == h->total) {
    unsigned char extra[4096];
    do { // the rest: none expected, but the members' checks come at their ends
      why = gz_pull(&g, extra, sizeof extra, &more);
      got += more;
    } while (!why && more == sizeof extra);
  }
  inflateEnd(&g.z);
  if (!status && why)
    status = PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                       "label map '%s': damaged gzip data (%s); the file is corrupt or incomplete: copy or export it "
                       "again",
                       path, why);
  if (!status && (int64_t)got != h->total)
    status = PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                       "label map '%s': %zu bytes once inflated, but its header declares %lld (voxels from byte %lld, "
                       "%d bytes each); the file is %s",
                       path, got, (long long)h->total, (long long)h->vox_offset, h->bytes,
                       (int64_t)got < h->total ? "cut short" : "longer than its header says (damaged)");
  if (status) free(full);
  else *data = full;
cleanup:
  free(raw);
  return status;
}

static fascia_status read_nifti(fascia_ctx *ctx, const char *path, int32_t frame, prep_labelmap *map) {
  nifti_set_debug_level(0); // its messages go to stderr; ours name the file
  nifti_head h = {0};
  unsigned char *data;
  PREP_TRY(nifti_bytes(ctx, path, &h, &data));
  nifti_image *nim = h.version == 1 ? nifti_convert_n1hdr2nim(h.h1, path) : nifti_convert_n2hdr2nim(h.h2, path);
  fascia_status status = FASCIA_OK;
  PREP_CHECK_GOTO(nim, ctx, FASCIA_ERR_FORMAT, "label map '%s': the NIfTI library cannot read its header", path);
  snprintf(map->format, sizeof map->format, "NIfTI-%d", h.version);
  double affine[3][4];
  if (h.sform_code > 0) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) affine[r][c] = nim->sto_xyz.m[r][c];
  } else if (h.qform_code > 0) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) affine[r][c] = nim->qto_xyz.m[r][c];
  } else {
    PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_FORMAT,
                    "label map '%s': no affine (sform and qform codes are both 0), so it cannot be placed in the world",
                    path);
  }
  const double scale = nim->xyz_units == NIFTI_UNITS_METER ? 1 : nim->xyz_units == NIFTI_UNITS_MICRON ? 1e-6 : 1e-3;
  place(map, affine, 0, frame, scale);
  PREP_TRY_GOTO(check_affine(ctx, path, map->to_world));
  const int64_t dims[3] = {h.dim[1], h.dim[0] >= 2 ? h.dim[2] : 1, h.dim[0] >= 3 ? h.dim[3] : 1};
  PREP_TRY_GOTO(alloc_labels(ctx, path, map, dims));
  PREP_CHECK_GOTO(nim->scl_slope == 0 || (nim->scl_slope == 1 && nim->scl_inter == 0), ctx, FASCIA_ERR_FORMAT,
                  "label map '%s': its values are scaled (scl_slope %g, scl_inter %g); labels must be stored as they are",
                  path, nim->scl_slope, nim->scl_inter);
  PREP_TRY_GOTO(copy_labels(ctx, path, data + h.vox_offset, dims[0] * dims[1] * dims[2], h.bytes, h.is_signed, h.swap,
                            map->labels));
cleanup:
  if (nim) nifti_image_free(nim);
  free(data);
  return status;
}

// A whole compressed stream, inflated to scratch: NULL when every gzip
// member (or the one bzip2 stream) ends with the data and passes its checks,
// *length the bytes it holds; else why not.
static const char *gzip_whole(const unsigned char *in, size_t n, int64_t *length) {
  *length = 0;
  if (n < 2 || in[0] != 0x1f || in[1] != 0x8b) return "no gzip signature";
  gz_reader g = {.in = in, .left = n};
  if (inflateInit2(&g.z, 15 + 16) != Z_OK) return "zlib could not start";
  static unsigned char scratch[1 << 16];
  const char *why;
  size_t got;
  do {
    why = gz_pull(&g, scratch, sizeof scratch, &got);
    *length += (int64_t)got;
  } while (!why && !g.end);
  inflateEnd(&g.z);
  return why;
}

static const char *bzip2_whole(const unsigned char *in, size_t n, int64_t *length) {
  *length = 0;
  bz_stream b = {0};
  if (BZ2_bzDecompressInit(&b, 0, 0) != BZ_OK) return "libbz2 could not start";
  static char scratch[1 << 16];
  const char *why = NULL;
  b.next_in = (char *)(uintptr_t)in;
  size_t left = n;
  for (;;) {
    if (b.avail_in == 0 && left) {
      const size_t k = left > ((size_t)1 << 30) ? (size_t)1 << 30 : left;
      b.avail_in = (unsigned)k;
      left -= k;
    }
    b.next_out = scratch;
    b.avail_out = sizeof scratch;
    const int rc = BZ2_bzDecompress(&b);
    *length += (int64_t)(sizeof scratch - b.avail_out);
    if (rc == BZ_STREAM_END) {
      if (b.avail_in || left) why = "bytes after the end of the bzip2 stream";
      break;
    }
    if (rc != BZ_OK) {
      why = rc == BZ_DATA_ERROR ? "a bzip2 block's CRC does not match" : "damaged bzip2 data";
      break;
    }
    if (b.avail_in == 0 && left == 0 && b.avail_out == sizeof scratch) {
      why = "the bzip2 stream is cut short (the file ends before the stream's end)";
      break;
    }
  }
  BZ2_bzDecompressEnd(&b);
  return why;
}

// The detached data files an NRRD header names ("data file:" one name, a
// numbered format "name%03d.raw min max step", or LIST then one name a line
// to the end of the header), relative to the header's folder; each must be
// a regular file before teem opens it (a FIFO would block). *count of them
// in *names.
static fascia_status nrrd_data_files(fascia_ctx *ctx, const char *path, const char *header, size_t size,
                                     char ***names, int32_t *count) {
  *names = NULL;
  *count = 0;
  char dir[4096] = "";
  const char *slash = strrchr(path, '/');
  if (slash) snprintf(dir, sizeof dir, "%.*s/", (int)(slash - path), path);
  fascia_status status = FASCIA_OK;
  int listing = 0;
  char **list = NULL;
  int32_t n = 0, cap = 0;
  for (size_t at = 0; at < size;) {
    size_t end = at;
    while (end < size && header[end] != '\n') ++end;
    size_t len = end - at;
    if (len && header[at + len - 1] == '\r') --len;
    char line[4096];
    PREP_CHECK_GOTO(len < sizeof line, ctx, FASCIA_ERR_FORMAT, "label map '%s': a header line of %zu characters", path,
                    len);
    memcpy(line, header + at, len);
    line[len] = 0;
    at = end + 1;
    const char *value = NULL;
    if (!strncmp(line, "data file:", 10)) value = line + 10;
    else if (!strncmp(line, "datafile:", 9)) value = line + 9;
    char names_here[1][4096];
    int64_t first = 0, last = -1, step = 1;
    const char *pattern = NULL;
    int numbered = 0;
    if (listing) {
      if (!len) continue;
      pattern = line, first = last = 0;
    } else if (value) {
      while (*value == ' ' || *value == '\t') ++value;
      char fmt[4096];
      long long lo, hi, st;
      if (!strncmp(value, "LIST", 4) && (value[4] == 0 || value[4] == ' ')) {
        listing = 1;
        continue;
      }
      if (strchr(value, '%') && sscanf(value, "%4095s %lld %lld %lld", fmt, &lo, &hi, &st) == 4) {
        snprintf(names_here[0], sizeof names_here[0], "%s", fmt);
        pattern = names_here[0], first = lo, last = hi, step = st, numbered = 1;
        PREP_CHECK_GOTO(step != 0 && (last - first) / step >= 0 && (last - first) / step < 100000, ctx,
                        FASCIA_ERR_FORMAT, "label map '%s': data file numbers %lld to %lld by %lld", path, lo, hi, st);
      } else {
        pattern = value, first = last = 0;
      }
    } else {
      continue;
    }
    // pattern: a name with at most one %[0]<width>d
    const char *pc = strchr(pattern, '%');
    int width = 0, zero = 0;
    size_t head_len = pc ? (size_t)(pc - pattern) : strlen(pattern);
    const char *tail = "";
    if (numbered) {
      const char *q = pc + 1;
      if (*q == '0') zero = 1, ++q;
      while (*q >= '0' && *q <= '9' && width < 100) width = width * 10 + (*q++ - '0');
      PREP_CHECK_GOTO(*q == 'd' && !strchr(q + 1, '%'), ctx, FASCIA_ERR_FORMAT,
                      "label map '%s': data file format '%s' is not a name with one %%d", path, pattern);
      tail = q + 1;
    } else {
      pc = NULL, head_len = strlen(pattern);
    }
    for (int64_t k = first; step > 0 ? k <= last : k >= last; k += step) {
      char name[4096], number[128] = "";
      if (pc) snprintf(number, sizeof number, zero ? "%0*lld" : "%*lld", width, (long long)k);
      snprintf(name, sizeof name, "%s%.*s%s%s", pattern[0] == '/' ? "" : dir, (int)head_len, pattern, number, tail);
      if (n == cap) {
        cap = cap ? 2 * cap : 4;
        char **grown = realloc(list, (size_t)cap * sizeof *grown);
        PREP_CHECK_GOTO(grown, ctx, FASCIA_ERR_MEMORY, "label map '%s': out of memory", path);
        list = grown;
      }
      list[n] = prep_strdup(name);
      PREP_CHECK_GOTO(list[n], ctx, FASCIA_ERR_MEMORY, "label map '%s': out of memory", path);
      ++n;
      FILE *f;
      int64_t bytes;
      PREP_TRY_GOTO(prep_open_regular(ctx, name, "label map data", &f, &bytes));
      fclose(f);
      if (!pc) break;
    }
  }
cleanup:
  if (status) {
    for (int32_t k = 0; k < n; ++k) free(list[k]);
    free(list);
    return status;
  }
  *names = list;
  *count = n;
  return FASCIA_OK;
}

// After teem read the data: every compressed stream whole and as long as
// the header declares, raw data not longer than declared.
static fascia_status nrrd_verify_data(fascia_ctx *ctx, const char *path, const NrrdIoState *nio,
                                      const unsigned char *file, size_t file_size, size_t data_at, char **names,
                                      int32_t count, int64_t need) {
  const int gz = nio->encoding == nrrdEncodingGzip, bz = nio->encoding == nrrdEncodingBzip2;
  if (!gz && !bz && nio->encoding != nrrdEncodingRaw) return FASCIA_OK; // text: parsed value by value
  if (gz || bz)
    PREP_CHECK(nio->lineSkip == 0, ctx, FASCIA_ERR_FORMAT,
               "label map '%s': compressed data after a line skip, which fascia cannot verify; save it without "
               "'line skip'",
               path);
  if (nio->lineSkip || nio->dataFSkip || nio->byteSkip < 0) return FASCIA_OK; // position not known here
  int64_t total = 0;
  fascia_status status = FASCIA_OK;
  for (int32_t k = 0; k < (count ? count : 1) && !status; ++k) {
    char *text = NULL;
    size_t n = file_size - data_at;
    const unsigned char *data = file + data_at;
    const char *where = path;
    if (count) {
      PREP_TRY(prep_read_file(ctx, names[k], "label map data", INT64_MAX / 4, &text, &n));
      data = (const unsigned char *)text, where = names[k];
    }
    int64_t length = (int64_t)n;
    const char *why = gz ? gzip_whole(data, n, &length) : bz ? bzip2_whole(data, n, &length) : NULL;
    if (why)
      status = PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                         "label map '%s': damaged %s data in '%s' (%s); the file is corrupt or incomplete: copy or "
                         "export it again",
                         path, gz ? "gzip" : "bzip2", where, why);
    total += length - nio->byteSkip;
    free(text);
  }
  if (status) return status;
  PREP_CHECK(total == need, ctx, FASCIA_ERR_FORMAT,
             "label map '%s': its data holds %lld bytes%s, but its header declares %lld; the file is %s", path,
             (long long)total, gz || bz ? " once inflated" : "", (long long)need,
             total < need ? "cut short" : "longer than its header says (damaged)");
  return FASCIA_OK;
}

static fascia_status read_nrrd(fascia_ctx *ctx, const char *path, int32_t frame, prep_labelmap *map) {
  char *raw, **names = NULL;
  size_t size;
  int32_t count = 0;
  PREP_TRY(prep_read_file(ctx, path, "label map", INT64_MAX / 4, &raw, &size));
  // the header ends at its first empty line; attached data follow it
  size_t data_at = size;
  for (size_t k = 0; k + 1 < size; ++k)
    if (raw[k] == '\n' && (raw[k + 1] == '\n' || (raw[k + 1] == '\r' && k + 2 < size && raw[k + 2] == '\n'))) {
      data_at = k + (raw[k + 1] == '\n' ? 2 : 3);
      break;
    }
  Nrrd *nrrd = nrrdNew();
  NrrdIoState *nio = nrrdIoStateNew();
  fascia_status status = FASCIA_OK;
  PREP_CHECK_GOTO(nrrd && nio, ctx, FASCIA_ERR_MEMORY, "label map '%s': out of memory", path);
  snprintf(map->format, sizeof map->format, "NRRD");
  PREP_TRY_GOTO(nrrd_data_files(ctx, path, raw, data_at, &names, &count));
  nrrdStateVerboseIO = 0; // teem's warnings go to stderr; ours name the file
  if (nrrdLoad(nrrd, path, nio)) {
    char *err = biffGetDone(NRRD);
    char reason[256] = "";
    if (err) { // teem's messages are several lines: keep the innermost reason on one line
      const char *last = err;
      for (const char *c = err; *c; ++c)
        if (*c == '\n' && c[1]) last = c + 1;
      snprintf(reason, sizeof reason, "%s", last);
      for (char *c = reason; *c; ++c)
        if (*c == '\n' || *c == '\t') *c = ' ';
      free(err);
    }
    PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_FORMAT, "label map '%s': not a readable NRRD file (%s)", path, reason);
  }
  PREP_CHECK_GOTO(nrrd->dim == 3, ctx, FASCIA_ERR_FORMAT,
                  "label map '%s': a %u-D image%s; a label map has one 3-D volume", path, nrrd->dim,
                  nrrd->dim == 4 ? " (a segmentation with overlapping layers, which cannot be read as one label map: "
                                   "in 3D Slicer export it as a labelmap volume)"
                                 : "");
  int bytes = 0, is_signed = 0;
  switch (nrrd->type) {
  case nrrdTypeUChar: bytes = 1; break;
  case nrrdTypeChar: bytes = 1, is_signed = 1; break;
  case nrrdTypeUShort: bytes = 2; break;
  case nrrdTypeShort: bytes = 2, is_signed = 1; break;
  case nrrdTypeUInt: bytes = 4; break;
  case nrrdTypeInt: bytes = 4, is_signed = 1; break;
  case nrrdTypeLLong:
  case nrrdTypeULLong: bytes = 8, is_signed = 1; break;
  default:
    PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_FORMAT,
                    "label map '%s': voxels are %s, not integers; a label map holds integer labels", path,
                    airEnumStr(nrrdType, nrrd->type));
  }
  int lps;
  switch (nrrd->space) {
  case nrrdSpaceRightAnteriorSuperior: lps = 0; break;
  case nrrdSpaceLeftPosteriorSuperior: lps = 1; break;
  default:
    PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_FORMAT,
                    "label map '%s': space '%s' is not a patient frame fascia can place (expected "
                    "right-anterior-superior or left-posterior-superior, with space directions)",
                    path, nrrd->space ? airEnumStr(nrrdSpace, nrrd->space) : "(none)");
  }
  double affine[3][4];
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) affine[r][c] = nrrd->axis[c].spaceDirection[r];
  for (int r = 0; r < 3; ++r) affine[r][3] = nrrd->spaceOrigin[r];
  double scale = 1e-3;
  if (nrrd->spaceUnits[0] && !strcmp(nrrd->spaceUnits[0], "m")) scale = 1;
  if (nrrd->spaceUnits[0] && !strcmp(nrrd->spaceUnits[0], "cm")) scale = 1e-2;
  place(map, affine, lps, frame, scale);
  PREP_TRY_GOTO(check_affine(ctx, path, map->to_world));
  const int64_t dims[3] = {(int64_t)nrrd->axis[0].size, (int64_t)nrrd->axis[1].size, (int64_t)nrrd->axis[2].size};
  PREP_TRY_GOTO(nrrd_verify_data(ctx, path, nio, (const unsigned char *)raw, size, data_at, names, count,
                                 dims[0] * dims[1] * dims[2] * bytes));
  PREP_TRY_GOTO(alloc_labels(ctx, path, map, dims));
  PREP_TRY_GOTO(copy_labels(ctx, path, nrrd->data, dims[0] * dims[1] * dims[2], bytes, is_signed, 0, map->labels));
cleanup:
  if (nrrd) nrrdNuke(nrrd);
  if (nio) nrrdIoStateNix(nio);
  for (int32_t k = 0; k < count; ++k) free(names[k]);
  free(names);
  free(raw);
  return status;
}

// Value of header key "Segment<k>_<field>" (teem's copy, to free), NULL when absent.
static char *segment_value(const Nrrd *nrrd, int k, const char *field) {
  char key[64];
  snprintf(key, sizeof key, "Segment%d_%s", k, field);
  return nrrdKeyValueGet(nrrd, key);
}

// An integer header value: 1 when all of text is one, within lo .. hi.
static int parse_int(const char *text, long lo, long hi, long *out) {
  char *end;
  if (!text || !*text) return 0;
  const long v = strtol(text, &end, 10);
  while (*end == ' ') ++end;
  *out = v;
  return *end == 0 && v >= lo && v <= hi;
}

// Checks segment k's layer and label value, then adds it to the table.
static fascia_status add_segment(fascia_ctx *ctx, const char *path, const Nrrd *nrrd, int k, long *first_layer,
                                 prep_label_table *table) {
  char *name = segment_value(nrrd, k, "Name"), *value = segment_value(nrrd, k, "LabelValue");
  char *layer = segment_value(nrrd, k, "Layer");
  long label = 0, in_layer = 0;
  fascia_status status = FASCIA_OK;
  if (!value)
    status = PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                       "segmentation '%s' Segment%d_LabelValue: absent (segment '%s'; 3D Slicer 4.11 and later write "
                       "it); save the segmentation again in a current Slicer, or export it as a labelmap volume",
                       path, k, name);
  else if (!parse_int(value, 1, PREP_MAX_LABEL, &label))
    status = PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                       "segmentation '%s' Segment%d_LabelValue: '%s' is not a label (expected an integer 1 .. %d)",
                       path, k, value, PREP_MAX_LABEL);
  else if (layer && !parse_int(layer, 0, INT32_MAX, &in_layer))
    status = PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                       "segmentation '%s' Segment%d_Layer: '%s' is not a layer index (expected an integer from 0)",
                       path, k, layer);
  else if (k > 0 && in_layer != *first_layer)
    status = PREP_FAIL(ctx, FASCIA_ERR_UNSUPPORTED,
                       "segmentation '%s' Segment%d_Layer: segment '%s' is in layer %ld, segment '%s' in layer %ld: "
                       "its segments overlap, and fascia reads one layer; in 3D Slicer export it as a labelmap volume "
                       "(overlaps resolved) or remove the overlaps",
                       path, k, name, in_layer, table->name[0], *first_layer);
  for (int32_t e = 0; status == FASCIA_OK && e < table->count; ++e)
    if (table->label[e] == label)
      status = PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                         "segmentation '%s' Segment%d_LabelValue: %ld is also segment '%s''s; a label value names one "
                         "segment",
                         path, k, label, table->name[e]);
  if (status == FASCIA_OK) {
    *first_layer = in_layer;
    status = prep_label_table_add(ctx, path, table, (int32_t)label, name);
  }
  free(name), free(value), free(layer);
  return status;
}

fascia_status prep_segmentation_table(fascia_ctx *ctx, const char *path, prep_label_table *table) {
  memset(table, 0, sizeof *table);
  struct stat st; // a FIFO would block; what is wrong with the file the label map's read says
  if ((!ends_with(path, ".nrrd") && !ends_with(path, ".nhdr")) || stat(path, &st) != 0 || !S_ISREG(st.st_mode))
    return FASCIA_OK;
  Nrrd *nrrd = nrrdNew();
  NrrdIoState *nio = nrrdIoStateNew();
  fascia_status status = FASCIA_OK;
  PREP_CHECK_GOTO(nrrd && nio, ctx, FASCIA_ERR_MEMORY, "segmentation '%s': out of memory", path);
  nio->skipData = AIR_TRUE; // the header alone: the voxels are read (and checked) with the label map
  nrrdStateVerboseIO = 0;
  if (nrrdLoad(nrrd, path, nio)) {
    free(biffGetDone(NRRD)); // prep_labelmap_read says what is wrong with the file, in full
    goto cleanup;
  }
  long first_layer = 0;
  for (int k = 0;; ++k) {
    char *name = segment_value(nrrd, k, "Name");
    if (!name) break;
    free(name);
    PREP_TRY_GOTO(add_segment(ctx, path, nrrd, k, &first_layer, table));
  }
cleanup:
  if (nrrd) nrrdNuke(nrrd);
  if (nio) nrrdIoStateNix(nio);
  if (status != FASCIA_OK) prep_label_table_free(table);
  return status;
}

fascia_status prep_labelmap_read(fascia_ctx *ctx, const char *path, int32_t frame, prep_labelmap **out) {
  *out = NULL;
  FILE *f;
  int64_t size;
  PREP_TRY(prep_open_regular(ctx, path, "label map", &f, &size));
  fclose(f);
  prep_labelmap *map = calloc(1, sizeof *map);
  PREP_CHECK(map, ctx, FASCIA_ERR_MEMORY, "label map '%s': out of memory", path);
  fascia_status status;
  if (ends_with(path, ".nrrd") || ends_with(path, ".nhdr"))
    status = read_nrrd(ctx, path, frame, map);
  else if (ends_with(path, ".nii") || ends_with(path, ".nii.gz"))
    status = read_nifti(ctx, path, frame, map);
  else
    status = PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                       "label map '%s': unknown format (expected .nii, .nii.gz, .nrrd, .seg.nrrd or .nhdr)", path);
  if (status != FASCIA_OK) {
    prep_labelmap_destroy(&map);
    return status;
  }
  *out = map;
  return FASCIA_OK;
}
