// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Helpers of the label-map tests (t57x): label maps written by the test,
// NIfTI with the NIfTI reference library, NRRD by hand (a text header and
// raw bytes), each from a function of the voxel's world position, so one
// geometry can be written through any affine.
#ifndef FASCIA_TESTS_LABELMAP_FIXTURE_H
#define FASCIA_TESTS_LABELMAP_FIXTURE_H

#include <nifti2_io.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/// Label of a world point (RAS, mm).
typedef uint8_t (*labelmap_rule)(const double *x, const void *data);

/// A label map of dims voxels; affine maps voxel (i,j,k) to RAS mm (row-major 3x4).
typedef struct labelmap_def {
  int dims[3];
  double affine[12];
} labelmap_def;

static inline uint8_t *labelmap_fill(const labelmap_def *d, labelmap_rule rule, const void *data) {
  uint8_t *labels = malloc((size_t)d->dims[0] * d->dims[1] * d->dims[2]);
  if (!labels) return NULL;
  for (int k = 0; k < d->dims[2]; ++k)
    for (int j = 0; j < d->dims[1]; ++j)
      for (int i = 0; i < d->dims[0]; ++i) {
        double x[3];
        for (int r = 0; r < 3; ++r)
          x[r] = d->affine[4 * r] * i + d->affine[4 * r + 1] * j + d->affine[4 * r + 2] * k + d->affine[4 * r + 3];
        labels[i + (size_t)d->dims[0] * (j + (size_t)d->dims[1] * k)] = rule(x, data);
      }
  return labels;
}

/// NIfTI (version 1 or 2; .nii or .nii.gz by the name) with the sform set
/// (code 2) unless no_affine, uint8 unless as_float, t volumes (1: 3-D).
static inline int labelmap_write_nifti(const char *path, const labelmap_def *d, labelmap_rule rule, const void *data,
                                       int version, int no_affine, int as_float, int t) {
  uint8_t *labels = labelmap_fill(d, rule, data);
  if (!labels) return 0;
  int64_t dims[8] = {t > 1 ? 4 : 3, d->dims[0], d->dims[1], d->dims[2], t, 1, 1, 1};
  nifti_image *nim = nifti_make_new_nim(dims, as_float ? DT_FLOAT32 : DT_UINT8, 1);
  if (!nim) {
    free(labels);
    return 0;
  }
  const size_t n = (size_t)d->dims[0] * d->dims[1] * d->dims[2];
  for (int v = 0; v < t; ++v)
    for (size_t k = 0; k < n; ++k) {
      if (as_float)
        ((float *)nim->data)[v * n + k] = labels[k];
      else
        ((uint8_t *)nim->data)[v * n + k] = labels[k];
    }
  free(labels);
  nim->xyz_units = NIFTI_UNITS_MM;
  nim->qform_code = 0;
  nim->sform_code = no_affine ? 0 : 2;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) nim->sto_xyz.m[r][c] = r < 3 ? d->affine[4 * r + c] : (c == 3);
  nim->nifti_type = version == 2 ? NIFTI_FTYPE_NIFTI2_1 : NIFTI_FTYPE_NIFTI1_1;
  int ok = nifti_set_filenames(nim, path, 0, 1) == 0;
  if (ok) nifti_image_write(nim);
  nifti_image_free(nim);
  FILE *f = fopen(path, "rb");
  if (f) fclose(f);
  return ok && f;
}

/// NRRD, raw uint8, space LPS or RAS: the same world geometry (the
/// directions and origin are converted from the RAS affine). layers > 1
/// writes a 4-D image (overlapping segment layers, as a .seg.nrrd has).
static inline int labelmap_write_nrrd(const char *path, const labelmap_def *d, labelmap_rule rule, const void *data,
                                      int lps, int layers) {
  uint8_t *labels = labelmap_fill(d, rule, data);
  FILE *f = labels ? fopen(path, "wb") : NULL;
  if (!f) {
    free(labels);
    return 0;
  }
  const double s = lps ? -1 : 1; // x and y flip between RAS and LPS
  const double *a = d->affine;
  if (layers > 1) {
    fprintf(f, "NRRD0004\ntype: uint8\ndimension: 4\nspace: %s\nsizes: %d %d %d %d\n",
            lps ? "left-posterior-superior" : "right-anterior-superior", layers, d->dims[0], d->dims[1], d->dims[2]);
    fprintf(f, "space directions: none (%.17g,%.17g,%.17g) (%.17g,%.17g,%.17g) (%.17g,%.17g,%.17g)\n", s * a[0],
            s * a[4], a[8], s * a[1], s * a[5], a[9], s * a[2], s * a[6], a[10]);
    fprintf(f, "kinds: list domain domain domain\n");
  } else {
    fprintf(f, "NRRD0004\ntype: uint8\ndimension: 3\nspace: %s\nsizes: %d %d %d\n",
            lps ? "left-posterior-superior" : "right-anterior-superior", d->dims[0], d->dims[1], d->dims[2]);
    fprintf(f, "space directions: (%.17g,%.17g,%.17g) (%.17g,%.17g,%.17g) (%.17g,%.17g,%.17g)\n", s * a[0], s * a[4],
            a[8], s * a[1], s * a[5], a[9], s * a[2], s * a[6], a[10]);
    fprintf(f, "kinds: domain domain domain\n");
  }
  fprintf(f, "endian: little\nencoding: raw\nspace origin: (%.17g,%.17g,%.17g)\n\n", s * a[3], s * a[7], a[11]);
  const size_t n = (size_t)d->dims[0] * d->dims[1] * d->dims[2];
  int ok = 1;
  for (size_t k = 0; k < n; ++k)
    for (int l = 0; l < (layers > 1 ? layers : 1); ++l) ok = ok && fputc(l == 0 ? labels[k] : 0, f) != EOF;
  free(labels);
  return fclose(f) == 0 && ok;
}

#endif
