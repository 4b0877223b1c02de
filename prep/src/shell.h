// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Shell organs (shell.c): the wall of a hollow organ, its frames on the
// organ's surface and its samples through the wall.
#ifndef FASCIA_PREP_SHELL_H
#define FASCIA_PREP_SHELL_H
#include "prep_util.h"
#include "reduced.h"

/// The frames a sampling stage has made so far, as a shell sees them.
typedef struct prep_shell_frames {
  int64_t count;           ///< frames so far
  const double *position;  ///< [3 count] m
  const int32_t *organ;    ///< [count] organ whose surface it lies on, or -1
  const int32_t *triangle; ///< [count] that organ's triangle, or -1
  int64_t tissue_count;    ///< the first tissue_count frames are tissue frames
  const int32_t *tissue;   ///< [tissue_count] their tissue
} prep_shell_frames;

/// Each wall triangle is split into split x split alike triangles, one
/// point each (times the section's): split = frame_spacing /
/// sample_spacing, rounded, 1..PREP_SHELL_SPLIT_MAX.
#define PREP_SHELL_SPLIT_MAX 8
static inline int prep_shell_split(const fascia_prep_organ_def *od) {
  const int k = (int)(od->frame_spacing / od->sample_spacing + 0.5);
  return k < 1 ? 1 : k > PREP_SHELL_SPLIT_MAX ? PREP_SHELL_SPLIT_MAX : k;
}

/// The wall of shell organ o: its frames are the tissue frames on its
/// surface that their tissue's coupling rules allow (shared, as the
/// coupling stage couples them) and its own frames, Poisson-disk on the
/// surface at its frame_spacing from those; the frames are joined into
/// triangles over the surface, and each triangle's parts (prep_shell_split)
/// give section_points samples each through the wall at their centroids,
/// area x thickness in all.
/// out: its own frames (appended after frames->count), its samples, their
/// triangles in sample_cell as frame indices of the whole scene (not local).
/// Refuses, naming the scene key: a surface that intersects itself, frames
/// too sparse to cover it, a wall thicker than the organ.
FASCIA_PREP_INTERN fascia_status prep_shell_build(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                                  const fascia_prep_meshes *meshes, int32_t o,
                                                  const prep_shell_frames *frames, fascia_cgal_tree **trees,
                                                  prep_reduced *out);

/// A shell organ's inside pressure (its "pressure", Pa) as dead forces on
/// the frames of its wall (model->frame_load, added to): each wall sample's
/// share of the wall's area times the pressure, f, along the organ's
/// outward normal, shared by its frames as their weights (w f; no torque).
/// The model's samples and pairs are the points'.
FASCIA_PREP_INTERN fascia_status prep_shell_pressure_loads(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                                           const fascia_prep_meshes *meshes,
                                                           const fascia_prep_points *points, fascia_model *model);
#endif
