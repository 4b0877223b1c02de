// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Strands and sheets of a scene (reduced.c): their frames and samples.
#ifndef FASCIA_PREP_REDUCED_H
#define FASCIA_PREP_REDUCED_H
#include "prep_util.h"

/// The frames and samples of one strand or sheet tissue. Frame indices in
/// sample_cell are local (0 .. frame_count - 1).
typedef struct prep_reduced {
  int32_t frame_count, sample_count;
  double *frame_position;  ///< [3 frame_count] m
  int32_t *frame_organ;    ///< [frame_count] organ it sits on (shared), or -1
  int32_t *frame_triangle; ///< [frame_count] that organ's triangle, or -1
  double *sample_position; ///< [3 sample_count] m
  double *sample_volume;   ///< [sample_count] m^3
  int32_t *sample_cell;    ///< [3 sample_count] frames of its interval (two, -1) or triangle
  uint8_t *sample_drilling; ///< [sample_count] 1 .. 3: a sheet triangle's drilling stabiliser's gauge; NULL: none
  double length;           ///< strand: m; sheet: its area, m^2
} prep_reduced;

/// A sheet's drilling stabiliser (docs/mechanics.md, "Against CalculiX"):
/// PREP_SHEET_DRILLING_GAUGES samples per triangle at its centroid, each of
/// the triangle's volume, whose material integrates the volumetric energy
/// alone (their volume repeats the points' through the thickness, and they
/// have no mass), with a first Lame modulus PREP_SHEET_DRILLING_LAMBDA times
/// the sheet's shear modulus. Gauge 1's gradients (a, b) in the triangle's
/// axes are the linear triangle's less the quadratic fit's, so it sees that
/// difference's change of area; gauges 2 and 3 take (a, -b) and (b, a),
/// whose traces are its two in-plane deviatoric parts: together they hold
/// the whole in-plane strain of linear minus fit, which a drilling field
/// puts in shear without a change of area on a near-equilateral triangle,
/// and none of the shear across the sheet. Their F carries one corner
/// frame's rotation (weight 1 there), not the corners' weighted mean.
#define PREP_SHEET_DRILLING_LAMBDA 4.0
#define PREP_SHEET_DRILLING_GAUGES 3

/// Builds tissue t (a strand or a sheet; its sheet mesh in meshes->sheets)
/// and refuses what cannot be one with a line naming the scene key: an
/// attachment farther than its radius from its organ, a region on no organ,
/// a part or label the organ lacks or with no surface, a strand's curve or
/// a spread end's fibres through an organ, a sheet thicker than the gap it
/// fills. A strand's frames: its curve's in order, then its fans'. trees: one per
/// organ, created here when NULL (the caller destroys them).
FASCIA_PREP_INTERN fascia_status prep_reduced_build(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                                    const fascia_prep_meshes *meshes, const fascia_prep_volume *vol,
                                                    int32_t t, fascia_cgal_tree **trees, prep_reduced *out);
FASCIA_PREP_INTERN void prep_reduced_free(prep_reduced *r);

/// The intervals of strand tissue t in prepared points: the distinct frame
/// pairs of its samples' cells (its curve's intervals, then its fans'
/// fibres), into pairs [2 count] when not NULL; their count. For drawing.
FASCIA_PREP_INTERN int64_t prep_strand_intervals(const fascia_prep_points *points, int32_t t, int32_t *pairs);

/// A sheet's mesh as read: merges vertices at the same position, drops
/// triangles with a repeated corner, refuses a mesh with no triangle left, a
/// closed surface and edges of more than two triangles (naming
/// tissues[t].mesh); sets the bounds.
FASCIA_PREP_INTERN fascia_status prep_sheet_prepare(fascia_ctx *ctx, const fascia_prep_scene *scene, int32_t t,
                                                    fascia_prep_mesh *m);
#endif
