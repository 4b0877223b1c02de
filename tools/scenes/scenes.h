// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Code-built scenes shared by the tests, the benchmarks and the CLI: the
// paper's cantilever (Bosman et al. 2013 sec. 4.1) with hexahedral,
// tetrahedral or meshless shape functions, and the models behind the paper's
// timing tables (sec. 4.3, Tables 2 and 3) and larger ones of the same
// density for the GPU goals. Each builder fills a
// fascia_model, builds its reverse table and validates it before returning.
#ifndef FASCIA_TOOLS_SCENES_H
#define FASCIA_TOOLS_SCENES_H

#include "fascia/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Shape-function kind of a code-built scene.
typedef enum fascia_scene_shape {
  FASCIA_SCENE_HEX = 0,      ///< trilinear weights of the grid cell, 8 neighbours
  FASCIA_SCENE_TET = 1,      ///< barycentric weights of a tetrahedral split of the grid, 4 neighbours
  FASCIA_SCENE_MESHLESS = 2, ///< moving least squares over the k nearest frames
  /// A 1-D model: frames on the axis, MLS along it (fascia_shape_mls_adaptive),
  /// samples at points of the section carried by the frames' rotations
  FASCIA_SCENE_STRAND = 3,
  /// A 2-D model: frames in the mid-plane z = 0, MLS in the plane, samples
  /// through the thickness carried by the frames' rotations
  FASCIA_SCENE_SHEET = 4,
  FASCIA_SCENE_SHAPE_COUNT_
} fascia_scene_shape;

/// "hex", "tet", "meshless", "strand", "sheet"; "unknown" otherwise.
const char *fascia_scene_shape_name(int shape);
/// Shape from its name; -1 if unknown.
int fascia_scene_shape_from_name(const char *name);
/// Dimension of a shape's frame layout: 1 strand, 2 sheet, 3 the others.
int fascia_scene_shape_dimension(int shape);
/// A frame grid from text: "NX" (strand), "NXxNY" (sheet) or "NXxNYxNZ",
/// each count >= 2; the missing counts are set to 1. Returns the number of
/// counts read (1 to 3), or 0 for text that is none of these.
int fascia_scene_frames_parse(const char *text, int32_t frames[3]);

/// The cantilever of paper sec. 4.1: a box [0, length] x [-width/2, width/2]
/// x [-height/2, height/2] (m), frames on a regular nx x ny x nz grid that
/// includes the faces, frames at x == 0 FIXED (clamped), all others FREE,
/// loaded by gravity. Start from fascia_scene_beam_def_default().
/// How the beam groups samples into volumetric patches.
/// AUTO: CELL from FASCIA_PATCH_MIN_POISSON on, else NONE (fascia beam's default).
enum {
  FASCIA_SCENE_PATCH_AUTO = -1,
  FASCIA_SCENE_PATCH_NONE = 0,
  FASCIA_SCENE_PATCH_CELL = 1,
  FASCIA_SCENE_PATCH_FRAME = 2,
  FASCIA_SCENE_PATCH_POISSON = 3
};
/// "auto", "full" (NONE), "cell", "frame", "poisson"; "unknown" otherwise.
const char *fascia_scene_patch_name(int patch);
/// A patch kind from its name; -2 if unknown.
int fascia_scene_patch_from_name(const char *name);

typedef struct fascia_scene_beam_def {
  fascia_real length, width, height; ///< m; defaults 16, 1, 1
  int32_t frames[3];                 ///< frames along x, y, z, each >= 2; default 20 x 3 x 3
  int32_t shape;                     ///< fascia_scene_shape; default HEX
  /// HEX and MESHLESS: samples at the n x n x n Gauss-Legendre points of every
  /// grid cell (n = 1..4), volume = Gauss weight x cell volume; default 2.
  int32_t samples_per_cell_dir;
  /// TET: samples per tetrahedron, 1 (centroid) or 4 (degree-2 rule); default 4.
  int32_t samples_per_tet;
  /// MESHLESS: k nearest frames per sample (4 .. 128); STRAND, SHEET: the
  /// same (2 .. 128; 3 .. 128 for SHEET), at most the frame count, which a
  /// larger k is cut to; default 8 (fascia_scene_beam_def_of_shape: 4 for
  /// STRAND)
  int32_t neighbours;
  /// STRAND: the section is integrated on n x n Gauss-Legendre points over
  /// width x height; SHEET: on n points through the height (the thickness);
  /// n = 1..4, default 2 (exact for the bending energy of small strains)
  int32_t section_points;
  int32_t law;                    ///< fascia_law; default FASCIA_LAW_STVK
  fascia_real youngs_modulus;     ///< Pa; default 40000
  fascia_real poisson_ratio;      ///< default 0.3
  fascia_real mass;               ///< kg, total; used when density <= 0; default 5
  fascia_real density;            ///< kg/m^3; > 0 overrides mass; default 0 (from mass)
  fascia_real rotation_coupling;  ///< fascia_material.rotation_coupling; default 0
  /// fascia_material.rotation_smoothing (docs/mechanics.md), >= 0; the
  /// default, FASCIA_SCENE_SMOOTHING_AUTO, is fascia beam's rule: 0.05 for
  /// TET, whose frames carry the whole rotation of a bent beam (twice the
  /// hexahedral and meshless frames'), so the same energy as 0.1 for the others
  fascia_real rotation_smoothing;
  /// 1: selective reduced integration (beam only): the samples above carry
  /// the deviatoric energy, one more sample per cell (per tetrahedron for
  /// TET) at its centre carries the volumetric energy over the whole cell:
  /// cures locking as nu -> 1/2 (docs/mechanics.md). Default 0.
  int32_t reduced_volumetric;
  /// Mean dilatation (docs/mechanics.md): the volumetric energy evaluated on
  /// the volume-averaged dilatation of a patch of samples. PATCH_NONE (the
  /// samples integrate all of it), PATCH_CELL (the samples of each grid
  /// cell), PATCH_FRAME (the samples nearest each frame: its Voronoi cell),
  /// PATCH_POISSON (fascia_model_make_patches, as prep makes them),
  /// PATCH_AUTO (the rule of fascia beam). Not with reduced_volumetric.
  /// Default PATCH_NONE.
  int32_t volumetric_patch;
  fascia_real patch_radius; ///< PATCH_POISSON: radius of the patches, m (default 0.5)
  /// Enhanced strain modes on the patches (a fascia_modes_set,
  /// docs/mechanics.md): 1 the nine, 2 the three normal ones (both need
  /// patches), 0 off, -1 auto (the rule of fascia beam: the nine for TET
  /// with 4 samples per tetrahedron, the three normal ones for HEX, where
  /// there are patches; the centroid rule and MLS are soft enough already).
  /// Default 0.
  int32_t enhanced_modes;
  fascia_real gravity[3];         ///< m/s^2; default (0, 0, -9.81)
  int cookie_;                    ///< private: set by fascia_scene_beam_def_default
} fascia_scene_beam_def;

fascia_scene_beam_def fascia_scene_beam_def_default(void);
/// The default def with `shape` and that shape's frame grid and neighbours
/// (fascia beam's defaults): 20 x 3 x 3 for the volume shapes, 20 x 1 x 1
/// and k = 4 for STRAND, 20 x 3 x 1 and k = 8 for SHEET.
fascia_scene_beam_def fascia_scene_beam_def_of_shape(int shape);

/// rotation_smoothing's default: fascia beam's rule by shape kind.
#define FASCIA_SCENE_SMOOTHING_AUTO (-1.0)

/// The set of enhanced strain modes that suits a shape (a fascia_modes_set):
/// the nine for TET (constant strain per tetrahedron), the three normal ones
/// for HEX and MLS, whose weights already vary the strain across a cell.
int32_t fascia_scene_beam_modes_of_shape(int32_t shape);

/// Builds the cantilever. Samples: HEX and MESHLESS on the Gauss grid of the
/// frame cells; STRAND: frames[0] frames on the axis (y = z = 0; the other
/// counts are not used), samples_per_cell_dir Gauss stations per interval, each
/// with section_points^2 points over the section; SHEET: frames[0] x
/// frames[1] frames in the mid-plane z = 0 (frames[2] not used),
/// samples_per_cell_dir^2 Gauss points per cell, each with section_points
/// points through the thickness. STRAND and SHEET weights: MLS in the
/// frames' span over the k nearest frames of the sample's station (its
/// projection on the axis or the mid-plane), so a station's section points
/// share its weights; their section is carried by the frames' rotations and
/// cannot deform, so the material gets the moduli for which that
/// constrained law is the unconstrained one (uniaxial stress along a
/// strand, plane stress in a sheet, shear modulus kept: docs/mechanics.md),
/// named in the provenance; no volumetric patches, no enhanced modes, and
/// rotation smoothing 0 by default (the section's points make twisting a
/// frame cost energy). TET on the tetrahedra of the 6-tetrahedron (Kuhn) split of
/// every cell along its main diagonal (conforming: every cell is split the
/// same way). One material "beam", gravity from the def, one probe "tip" at
/// (length, 0, 0) carried by the shape function there (trilinear weights of
/// the end cell, barycentric weights of the containing tetrahedron, or MLS;
/// zero weights dropped). Provenance names the generator and every
/// parameter. Errors: FASCIA_ERR_ARGUMENT for a bad def (naming the field),
/// FASCIA_ERR_NUMERIC if MLS weights cannot be formed at a sample,
/// FASCIA_ERR_MEMORY; *out is NULL after an error.
fascia_status fascia_scene_beam_build(fascia_ctx *ctx, const fascia_scene_beam_def *def, fascia_model **out);

/// One row of the paper's timing tables (sec. 4.3), or a larger row of
/// the same kind (table 0).
typedef struct fascia_scene_paper_row {
  const char *name;       ///< e.g. "t2-f72-s400-k4", "t3-s12700", "big-f200000-s1000000-k4"
  int table;              ///< 2 or 3; 0: not in the paper
  int32_t frames;         ///< requested frame count (the model gets within 10 %)
  int32_t samples;        ///< exact sample count
  int32_t neighbours;     ///< frames per sample
  double paper_cpu_ms;    ///< paper's CPU time per step (Xeon W3520, one thread); 0 for table 0
  double paper_gpu_ms;    ///< paper's GPU time per step (GTX 570); 0 where not given (Table 2, table 0)
  double gpu_goal_ms;     ///< the goal for a step on the GPU, ms (docs/gpu.md); 0 where none is set
} fascia_scene_paper_row;

/// The rows of Tables 2 and 3, in the paper's order; *count gets their number.
const fascia_scene_paper_row *fascia_scene_paper_rows(int *count);
/// Rows beyond the paper (table 0): Table 3's density (4 neighbours, one
/// frame per five samples) at 100k, 300k, 1M and 2M samples, smallest first.
const fascia_scene_paper_row *fascia_scene_large_rows(int *count);
/// Row by name among both lists, NULL if absent.
const fascia_scene_paper_row *fascia_scene_paper_find(const char *name);

/// Builds the model of one row: the beam body of `body` (the cantilever box,
/// material, gravity; NULL for fascia_scene_beam_def_default(); its frames,
/// shape and sample fields are ignored), frames on a regular grid chosen to
/// get close to row->frames with cells as close to cubes as possible, exactly
/// row->samples samples placed by stratified jittered sampling with a fixed
/// seed (one per stratum, stratum volume as sample volume, so the volumes sum
/// to the body volume), frames at x == 0 fixed. Weights: for 4 neighbours the
/// barycentric weights of the containing tetrahedron of the Kuhn split of the
/// frame grid; for more, MLS over the k nearest frames. Probe "tip" as in the
/// beam. Errors as fascia_scene_beam_build.
fascia_status fascia_scene_paper_build(fascia_ctx *ctx, const fascia_scene_paper_row *row,
                                       const fascia_scene_beam_def *body, fascia_model **out);

#ifdef __cplusplus
}
#endif
#endif
