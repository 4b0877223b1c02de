// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Private helpers of the code-built scenes: the regular frame grid and its
// cells, the 6-tetrahedron (Kuhn) split of a cell, shape functions at a point
// in grid terms, sample pair storage, and the common finishing steps
// (material, clamping, probe, provenance, reverse table, validation).
#ifndef FASCIA_TOOLS_SCENE_UTIL_H
#define FASCIA_TOOLS_SCENE_UTIL_H

#include "fascia/shape.h"
#include "scenes.h"

// The generators' names for the error macros of fascia/base.h
#define SCENE_FAIL FASCIA_FAIL
#define SCENE_CHECK FASCIA_CHECK
#define SCENE_TRY FASCIA_TRY
#define SCENE_TRY_GOTO FASCIA_TRY_GOTO
#define SCENE_CHECK_GOTO FASCIA_CHECK_GOTO

/// Most pairs a probe keeps (MLS probes may grow k to avoid coplanar sets).
#define SCENE_PROBE_MAX (FASCIA_SHAPE_MAX_NEIGHBOURS)

/// A regular grid of n[0] x n[1] x n[2] frames from lo with spacing step.
/// Frame (ix, iy, iz) has index (ix n[1] + iy) n[2] + iz: x slowest, so the
/// clamped frames (ix = 0) come first.
typedef struct scene_grid {
  int32_t n[3];
  fascia_real lo[3], hi[3], step[3];
} scene_grid;

/// Private cookie of fascia_scene_beam_def.
#define FASCIA_SCENE_BEAM_COOKIE_ 0x5cee4b

/// Monotonic wall-clock time in milliseconds, for the peers' timings.
double scene_now_ms(void);

/// Coordinate along axis d of grid index idx (the last one is exactly hi).
fascia_real scene_grid_coord(const scene_grid *g, int d, int32_t idx);

/// The frame grid of a beam def with the given frame counts.
scene_grid scene_grid_of_beam(const fascia_scene_beam_def *def, const int32_t frames[3]);
int32_t scene_grid_frame_count(const scene_grid *g);
int32_t scene_grid_cell_count(const scene_grid *g);
/// Writes the frame positions [3N] of the grid.
void scene_grid_positions(const scene_grid *g, fascia_real *position);
/// Cell (clamped to the grid) containing p, as three indices.
void scene_grid_cell_of(const scene_grid *g, const fascia_real p[3], int32_t cell[3]);
/// Cell c (0 .. cells-1, x slowest) as three indices.
void scene_grid_cell_unflatten(const scene_grid *g, int32_t c, int32_t cell[3]);
/// Corners of a cell in fascia_shape_hex order: frame[8] indices, lo/hi corners.
void scene_grid_cell_corners(const scene_grid *g, const int32_t cell[3], int32_t frame[8], fascia_real lo[3],
                             fascia_real hi[3]);

/// Corner numbers (fascia_shape_hex order) of tetrahedron t (0..5) of the
/// Kuhn split: 0 -> 0 + e_a -> 0 + e_a + e_b -> 7 for each permutation (a, b, c).
void scene_kuhn_tet(int t, int corner[4]);
/// Vertex positions [12] and frames [4] of tetrahedron t of a cell.
void scene_cell_tet(const scene_grid *g, const int32_t cell[3], int t, int32_t frame[4], fascia_real vertex[12]);

/// Trilinear weights at p in its (clamped) cell: frame[8], w[8], grad[24].
fascia_status scene_hex_at(fascia_ctx *ctx, const scene_grid *g, const fascia_real p[3], int32_t frame[8],
                           fascia_real w[8], fascia_real grad[24]);
/// Barycentric weights at p in the tetrahedron of its cell that contains it
/// (the one whose smallest barycentric coordinate is largest).
fascia_status scene_tet_at(fascia_ctx *ctx, const scene_grid *g, const fascia_real p[3], int32_t frame[4],
                           fascia_real w[4], fascia_real grad[12]);
/// MLS weights at p over its k nearest frames (radius from the grid query).
fascia_status scene_mls_at(fascia_ctx *ctx, const fascia_frame_grid *grid, const fascia_real p[3], int32_t k,
                           int32_t *frame, fascia_real *w, fascia_real *grad);

/// Stores the n pairs of sample s at sample_offsets[s], sorted by frame
/// index, and sets sample_offsets[s + 1]. Needs sample_offsets[s] set.
void scene_set_pairs(fascia_model *m, int32_t s, int32_t n, const int32_t *frame, const fascia_real *w,
                     const fascia_real *grad);

/// A probe before it enters the model: nonzero weights only.
typedef struct scene_probe {
  int32_t count;
  int32_t frame[SCENE_PROBE_MAX];
  fascia_real weight[SCENE_PROBE_MAX];
  fascia_real position[3];
} scene_probe;

/// Keeps the nonzero weights of (frame, w)[n] in ascending frame order.
void scene_probe_set(scene_probe *probe, const fascia_real position[3], int32_t n, const int32_t *frame,
                     const fascia_real *w);

/// A model of `frames` frames at `position` (3 per frame, copied),
/// `samples` samples with `pairs` pairs in all, `materials` materials and
/// one probe (`probe`, for its pair count); the rest as fascia_model_alloc
/// leaves it. On error *out is NULL.
fascia_status scene_model_alloc(fascia_ctx *ctx, int32_t frames, const fascia_real *position, int32_t samples,
                                int32_t pairs, int32_t materials, const scene_probe *probe, fascia_model **out);

/// Bytes of a generator's provenance text.
#define SCENE_PROVENANCE_SIZE 4096

/// What a generator holds while it builds a model, freed together by
/// scene_build_end: the frames' rest positions, the provenance text, the
/// frames' search grid (NULL where the weights need none) and the model.
typedef struct scene_build {
  fascia_real *position; ///< [3 frames]
  char *provenance;      ///< SCENE_PROVENANCE_SIZE bytes
  fascia_frame_grid *grid;
  fascia_model *m;
} scene_build;

/// Allocates the positions of `frames` frames and the provenance text, the
/// grid and the model still NULL; `who` names the generator in the message.
fascia_status scene_build_begin(fascia_ctx *ctx, int32_t frames, const char *who, scene_build *b);
/// Hands the model to *out when status is FASCIA_OK, frees the rest, and
/// returns status.
fascia_status scene_build_end(scene_build *b, fascia_status status, fascia_model **out);

/// Checks the body and material fields of a beam def (cookie, sizes, law,
/// E, nu, mass or density, coupling, gravity).
fascia_status scene_check_body(fascia_ctx *ctx, const fascia_scene_beam_def *def, const char *who);
/// Density the def asks for: def->density if > 0, else mass / box volume.
fascia_real scene_density(const fascia_scene_beam_def *def);

/// The rotation smoothing the def asks for, FASCIA_SCENE_SMOOTHING_AUTO
/// resolved by its shape kind.
fascia_real scene_smoothing(const fascia_scene_beam_def *def);

/// The moduli of the material of a def's samples: E and nu for the volume
/// shapes; for STRAND and SHEET, whose section is carried by the frames'
/// rotations and keeps its shape, those for which the constrained law is
/// the unconstrained one: the shear modulus kept and lambda' = E nu / (1 +
/// nu) (uniaxial stress along a strand: lambda' + 2 mu = E), or lambda' = E
/// nu / (1 - nu^2) (plane stress in a sheet).
void scene_section_moduli(const fascia_scene_beam_def *def, fascia_real *youngs_modulus, fascia_real *poisson_ratio);

/// Final steps shared by the builders, on a model whose frames, samples and
/// pairs are filled and that was allocated with 1 material, 1 probe and
/// probe->count probe pairs: material "beam" from def, gravity, frames with
/// x == grid lo clamped (FIXED), the probe named "tip", provenance, reverse
/// table, validation under `origin`.
fascia_status scene_finish(fascia_ctx *ctx, fascia_model *m, const fascia_scene_beam_def *def,
                           const scene_probe *probe, const char *provenance, const char *origin);

/// Appends printf-style text to buf (size bytes), never overflowing.
void scene_append(char *buf, size_t size, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/// Appends the JSON fields that describe the body and material of a def.
void scene_append_body_json(char *buf, size_t size, const fascia_scene_beam_def *def);

#endif
