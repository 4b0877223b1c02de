// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// prep built without its label-map libraries: a scene with a segmentation
// is refused with what to install (the configure summary says so too).
#include <string.h>

#include "labels.h"

void prep_labelmap_destroy(prep_labelmap **map) {
  if (map) *map = NULL;
}

fascia_status prep_labelmap_read(fascia_ctx *ctx, const char *path, int32_t frame, prep_labelmap **out) {
  (void)frame;
  *out = NULL;
  return PREP_FAIL(ctx, FASCIA_ERR_UNSUPPORTED,
                   "label map '%s': this fascia was built without label-map support (missing " FASCIA_LABELMAP_MISSING
                   "); install it and rebuild",
                   path);
}

fascia_status prep_segmentation_table(fascia_ctx *ctx, const char *path, prep_label_table *table) {
  (void)ctx, (void)path;
  memset(table, 0, sizeof *table); // the label map's read says what is missing
  return FASCIA_OK;
}

fascia_status fascia_prep_labelmap_write(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_meshes *meshes,
                                         const char *path, char *table_path, size_t table_size) {
  (void)scene, (void)meshes, (void)table_path, (void)table_size;
  return PREP_FAIL(ctx, FASCIA_ERR_UNSUPPORTED,
                   "label map '%s': this fascia was built without label-map support (missing " FASCIA_LABELMAP_MISSING
                   "); install it and rebuild",
                   path);
}
