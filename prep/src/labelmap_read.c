// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Reading a label map: NIfTI-1/-2 with the NIfTI reference library
// (nifti2_io, which reads both versions and gzip), NRRD with teem's nrrd
// (the format's reference implementation, which 3D Slicer's .seg.nrrd
// follows). The voxel-centre affine goes from the file's frame (NIfTI: RAS+
// by definition; NRRD: its space field) to the scene's frame, in metres
// (docs/labelmaps.md).
#include <math.h>
#include <nifti2_io.h>
#include <stdlib.h>
#include <string.h>
#include <teem/nrrd.h>

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
static fascia_status copy_labels(fascia_ctx *ctx, const char *path, const void *data, int64_t n, int bytes,
                                 int is_signed, int32_t *labels) {
  for (int64_t k = 0; k < n; ++k) {
    int64_t v;
    const unsigned char *p = (const unsigned char *)data + k * bytes;
    switch (bytes) {
    case 1: v = is_signed ? (int64_t) * (const int8_t *)p : (int64_t) * (const uint8_t *)p; break;
    case 2: v = is_signed ? (int64_t) * (const int16_t *)(const void *)p : (int64_t) * (const uint16_t *)(const void *)p; break;
    case 4: v = is_signed ? (int64_t) * (const int32_t *)(const void *)p : (int64_t) * (const uint32_t *)(const void *)p; break;
    default: v = *(const int64_t *)(const void *)p; break; // 8: unsigned above INT64_MAX reads negative, refused
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

static fascia_status read_nifti(fascia_ctx *ctx, const char *path, int32_t frame, prep_labelmap *map) {
  nifti_set_debug_level(0); // its messages go to stderr; ours name the file
  nifti_image *nim = nifti_image_read(path, 0);
  PREP_CHECK(nim, ctx, FASCIA_ERR_FORMAT, "label map '%s': not a NIfTI-1 or NIfTI-2 file (no valid header)", path);
  fascia_status status = FASCIA_OK;
  snprintf(map->format, sizeof map->format, "%s", nim->nifti_type >= NIFTI_FTYPE_NIFTI2_1 ? "NIfTI-2" : "NIfTI-1");
  int64_t extra = 1;
  for (int d = 4; d <= 7 && d <= nim->ndim; ++d) extra *= nim->dim[d] > 0 ? nim->dim[d] : 1;
  PREP_CHECK_GOTO(nim->ndim <= 3 || extra == 1, ctx, FASCIA_ERR_FORMAT,
                  "label map '%s': a %d-D image (%lld volumes); a label map has one 3-D volume (save the "
                  "segmentation as one label map)",
                  path, (int)nim->ndim, (long long)extra);
  int bytes = 0, is_signed = 0;
  switch (nim->datatype) {
  case DT_UINT8: bytes = 1; break;
  case DT_INT8: bytes = 1, is_signed = 1; break;
  case DT_UINT16: bytes = 2; break;
  case DT_INT16: bytes = 2, is_signed = 1; break;
  case DT_UINT32: bytes = 4; break;
  case DT_INT32: bytes = 4, is_signed = 1; break;
  case DT_UINT64:
  case DT_INT64: bytes = 8, is_signed = 1; break;
  default:
    PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_FORMAT,
                    "label map '%s': voxels are %s, not integers; a label map holds integer labels", path,
                    nifti_datatype_string(nim->datatype));
  }
  double affine[3][4];
  if (nim->sform_code > 0) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) affine[r][c] = nim->sto_xyz.m[r][c];
  } else if (nim->qform_code > 0) {
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
  const int64_t dims[3] = {nim->nx, nim->ny > 0 ? nim->ny : 1, nim->nz > 0 ? nim->nz : 1};
  PREP_TRY_GOTO(alloc_labels(ctx, path, map, dims));
  PREP_CHECK_GOTO(nifti_image_load(nim) == 0 && nim->data, ctx, FASCIA_ERR_FORMAT,
                  "label map '%s': its voxel data is cut short or damaged (%lld voxels of %d bytes expected)", path,
                  (long long)(dims[0] * dims[1] * dims[2]), bytes);
  PREP_CHECK_GOTO(nim->scl_slope == 0 || (nim->scl_slope == 1 && nim->scl_inter == 0), ctx, FASCIA_ERR_FORMAT,
                  "label map '%s': its values are scaled (scl_slope %g, scl_inter %g); labels must be stored as they are",
                  path, nim->scl_slope, nim->scl_inter);
  PREP_TRY_GOTO(copy_labels(ctx, path, nim->data, dims[0] * dims[1] * dims[2], bytes, is_signed, map->labels));
cleanup:
  nifti_image_free(nim);
  return status;
}

static fascia_status read_nrrd(fascia_ctx *ctx, const char *path, int32_t frame, prep_labelmap *map) {
  Nrrd *nrrd = nrrdNew();
  PREP_CHECK(nrrd, ctx, FASCIA_ERR_MEMORY, "label map '%s': out of memory", path);
  fascia_status status = FASCIA_OK;
  snprintf(map->format, sizeof map->format, "NRRD");
  if (nrrdLoad(nrrd, path, NULL)) {
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
  PREP_TRY_GOTO(alloc_labels(ctx, path, map, dims));
  PREP_TRY_GOTO(copy_labels(ctx, path, nrrd->data, dims[0] * dims[1] * dims[2], bytes, is_signed, map->labels));
cleanup:
  nrrdNuke(nrrd);
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
