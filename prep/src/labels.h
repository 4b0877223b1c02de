// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Private interface of the label-map stages (docs/labelmaps.md): label
// tables, reading a label map, and the surfaces of organs made of labels.
#ifndef FASCIA_PREP_LABELS_H
#define FASCIA_PREP_LABELS_H

#include "prep_util.h"

/// Labels are integers 1 .. PREP_MAX_LABEL (0 is background).
#define PREP_MAX_LABEL 65535
/// The built-in table of TotalSegmentator's task `total`.
#define PREP_TOTALSEGMENTATOR_TOTAL "totalsegmentator:total"

typedef struct prep_label_table {
  int32_t count;
  int32_t *label; ///< [count]
  char **name;    ///< [count]
} prep_label_table;

/// The ".nii" or ".nii.gz" that ends path, NULL when it ends otherwise.
FASCIA_PREP_INTERN const char *prep_nifti_ending(const char *path);
/// A TSV table (label TAB name) read from path; messages name it and the line.
FASCIA_PREP_INTERN fascia_status prep_label_table_load(fascia_ctx *ctx, const char *path, prep_label_table *table);
/// A built-in table by name (PREP_TOTALSEGMENTATOR_TOTAL).
FASCIA_PREP_INTERN fascia_status prep_label_table_builtin(fascia_ctx *ctx, const char *name, prep_label_table *table);
FASCIA_PREP_INTERN void prep_label_table_free(prep_label_table *table);
/// Appends label and a copy of name; messages name origin.
FASCIA_PREP_INTERN fascia_status prep_label_table_add(fascia_ctx *ctx, const char *origin, prep_label_table *table,
                                                      int32_t label, const char *name);
/// The segments a 3D Slicer segmentation (.seg.nrrd) names in its header
/// (Segment<k>_Name, _LabelValue, _Layer): their label values and names, so
/// that a scene names organs as Slicer does. table->count is 0 when the file
/// is no NRRD or names no segments. Refused, one line naming the file and
/// key: a segment without a label value or with one outside 1 ..
/// PREP_MAX_LABEL, two segments of one value, segments in several layers
/// (overlapping segments, which one label map cannot hold).
FASCIA_PREP_INTERN fascia_status prep_segmentation_table(fascia_ctx *ctx, const char *path, prep_label_table *table);
/// Name of label in the table, NULL if absent.
FASCIA_PREP_INTERN const char *prep_label_table_name(const prep_label_table *table, int32_t label);
/// Labels whose name is spec (or matches it, when it holds * ? [): their
/// count; the first capacity go to out.
FASCIA_PREP_INTERN int32_t prep_label_match(const prep_label_table *table, const char *spec, int32_t *out,
                                            int32_t capacity);

/// A label map: one label per voxel, voxel (i, j, k) at index i + nx (j + ny k),
/// its centre at A (i, j, k) + t in the scene's world frame, metres.
typedef struct prep_labelmap {
  int32_t dims[3];
  int32_t *labels;        ///< [nx ny nz] 0: background
  double to_world[12];    ///< row-major [A | t], m
  char format[16];        ///< "NIfTI-1", "NIfTI-2", "NRRD"
} prep_labelmap;

/// Reads a NIfTI-1/-2 (.nii, .nii.gz) or NRRD (.nrrd, .seg.nrrd in its
/// labelmap form) label map and places it in the frame (fascia_prep_frame).
/// Errors, one line naming the file: not a label map of a known format, a
/// damaged or truncated file, a non-integer or 4-D image, no affine, labels
/// out of range, layers that overlap.
FASCIA_PREP_INTERN fascia_status prep_labelmap_read(fascia_ctx *ctx, const char *path, int32_t frame,
                                                    prep_labelmap **out);
FASCIA_PREP_INTERN void prep_labelmap_destroy(prep_labelmap **map);

/// Builds the surfaces of every organ the scene makes of labels into meshes
/// (other organs untouched) and the contacts between them.
FASCIA_PREP_INTERN fascia_status prep_label_organs(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                                   fascia_prep_meshes *meshes);

/// Every organ's inside, by the rule voxelize uses (the flood fill from
/// outside), on one grid of the scene's voxel size covering every organ:
/// labels[v] = o + 1 for the first organ listed whose inside holds voxel v,
/// else 0 (voxelize.c).
FASCIA_PREP_INTERN fascia_status prep_organ_labels(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                                   fascia_prep_meshes *meshes, prep_grid *grid, uint16_t **labels);

#endif
