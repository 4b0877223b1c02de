// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The scene's organs as a label map (NIfTI, with the NIfTI reference
// library): organ k is label k + 1, at the scene's voxel size, by the
// inside rule voxelize uses. A mesh scene becomes a label-map scene with the
// same geometry (docs/labelmaps.md), and a user can check the organs in a
// segmentation viewer. A TSV label table is written beside it.
#include <nifti2_io.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fascia/files.h"
#include "labels.h"

// "DIR/NAME.tmp-PID.nii.gz" for "DIR/NAME.nii.gz": the library picks the
// compression from the name's ending, so the temporary name keeps it.
static int temporary_name(const char *path, char *out, size_t size) {
  const char *ext = prep_nifti_ending(path);
  if (!ext) return 0;
  const int n = snprintf(out, size, "%.*s.tmp-%ld%s", (int)(ext - path), path, (long)getpid(), ext);
  return n > 0 && (size_t)n < size;
}

fascia_status fascia_prep_labelmap_write(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_meshes *meshes,
                                         const char *path, char *table_path, size_t table_size) {
  char temporary[4096];
  PREP_CHECK(temporary_name(path, temporary, sizeof temporary), ctx, FASCIA_ERR_ARGUMENT,
             "label map '%s': the name must end in .nii or .nii.gz", path);
  PREP_CHECK(fascia_prep_labelmap_table_path(path, table_path, table_size), ctx, FASCIA_ERR_ARGUMENT,
             "label map '%s': path too long", path);
  prep_grid g;
  uint16_t *labels = NULL;
  PREP_TRY(prep_organ_labels(ctx, scene, meshes, &g, &labels));
  const int wide = meshes->count > 254;
  int64_t dims[8] = {3, g.dims[0], g.dims[1], g.dims[2], 1, 1, 1, 1};
  nifti_image *nim = nifti_make_new_nim(dims, wide ? DT_UINT16 : DT_UINT8, 1);
  if (!nim) {
    free(labels);
    return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "label map '%s': out of memory", path);
  }
  for (int64_t v = 0; v < prep_grid_count(&g); ++v) {
    if (wide)
      ((uint16_t *)nim->data)[v] = labels[v];
    else
      ((uint8_t *)nim->data)[v] = (uint8_t)labels[v];
  }
  free(labels);
  // voxel (i, j, k) at h (lo + ijk) m in the world; NIfTI's world is RAS in
  // mm, so a scene in LPS turns x and y
  const double flip = scene->segmentation.frame == FASCIA_PREP_FRAME_LPS ? -1 : 1;
  nim->xyz_units = NIFTI_UNITS_MM;
  nim->qform_code = 0;
  nim->sform_code = NIFTI_XFORM_ALIGNED_ANAT;
  memset(&nim->sto_xyz, 0, sizeof nim->sto_xyz);
  for (int r = 0; r < 3; ++r) {
    const double sign = r < 2 ? flip : 1;
    nim->sto_xyz.m[r][r] = sign * 1e3 * g.h;
    nim->sto_xyz.m[r][3] = sign * 1e3 * g.h * g.lo[r];
  }
  nim->sto_xyz.m[3][3] = 1;
  nim->sto_ijk = nifti_dmat44_inverse(nim->sto_xyz);
  nim->dx = nim->dy = nim->dz = nim->pixdim[1] = nim->pixdim[2] = nim->pixdim[3] = 1e3 * g.h;
  nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
  fascia_status status = FASCIA_OK;
  if (nifti_set_filenames(nim, temporary, 0, 1) != 0) {
    status = PREP_FAIL(ctx, FASCIA_ERR_IO, "label map '%s': cannot name its file", path);
  } else {
    nifti_set_debug_level(0);
    nifti_image_write(nim); // says nothing of failure: the file is checked instead
    FILE *f = fopen(temporary, "rb");
    long size = -1;
    if (f && fseek(f, 0, SEEK_END) == 0) size = ftell(f);
    if (f) fclose(f);
    if (size < 348 || rename(temporary, path) != 0) {
      remove(temporary);
      status = PREP_FAIL(ctx, FASCIA_ERR_IO, "label map '%s': could not be written (disk full, or no write access)",
                         path);
    }
  }
  nifti_image_free(nim);
  PREP_TRY(status);
  fascia_file *table = NULL;
  PREP_TRY(fascia_file_open(ctx, "label table", table_path, &table));
  FILE *out = fascia_file_stream(table);
  fprintf(out, "label\tname\n");
  for (int32_t o = 0; o < meshes->count; ++o) fprintf(out, "%d\t%s\n", (int)o + 1, scene->organs[o].name);
  return fascia_file_commit(&table);
}
