// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A strand hanging an organ and a sheet under a pull, as scenes for fascia
// prep and as CalculiX decks of the same geometry (docs/mechanics.md,
// "Strands and sheets", "Against CalculiX"). Both put two boxes of edge
// `box` on the x axis with a gap between them: A = [-gap/2 - box, -gap/2] x
// [-box/2, box/2]^2 is fixed, B = [gap/2, gap/2 + box] x [-box/2, box/2]^2
// hangs from the strand (a rigid organ) or is pulled (prescribed).
//  - hang: a straight strand of square section `area` from the centre of A's
//    face to the centre of B's, under gravity -g z. B is rigid, of density
//    FASCIA_ORGAN_DENSITY, its centre of mass box/2 beyond the strand's end:
//    the strand is a cantilever carrying a weight on a lever. CalculiX: B32
//    beams of the same rectangular section, clamped at A, joined to a node at
//    the organ's centre by a beam a million times stiffer that carries the
//    organ's weight; NLGEOM; *ELASTIC (St. Venant-Kirchhoff, as the scene's
//    "stvk" law).
//  - pull: a flat sheet of `thickness` in the plane z = 0 filling the gap
//    (x in [-gap/2, gap/2], y in [-width/2, width/2]), its edges on A and B
//    clamped, B translated by `pull`. fascia: a triangle mesh of cells[0] x
//    cells[1] squares, diagonals alternating (right triangles), or of rows
//    shifted by half a square (near-equilateral), or those jittered; CalculiX: S8R shells on
//    elements[0] x elements[1] squares, the edge on A held in all six
//    degrees of freedom, the edge on B moved by `pull` and not rotated; NLGEOM.
#ifndef FASCIA_TOOLS_TISSUE_CALCULIX_H
#define FASCIA_TOOLS_TISSUE_CALCULIX_H
#include <stdio.h>

#include "fascia/fascia.h"

#ifdef __cplusplus
extern "C" {
#endif

/// The strand hanging an organ. Start from fascia_tissue_hang_def_default().
typedef struct fascia_tissue_hang_def {
  double gap;            ///< m, the strand's length; default 0.02
  double box;            ///< m, the organs' edge; default 0.02
  double area;           ///< m^2, the strand's section (a square); default 4e-6 (2 x 2 mm)
  double youngs_modulus; ///< Pa; default 1e8 (a ligament)
  double poisson_ratio;  ///< default 0.3
  double density;        ///< kg/m^3 of the strand; default 1000
  double gravity;        ///< m/s^2, along -z; default 9.81
  double frame_spacing;  ///< fascia: m between the strand's frames; default 0.002 (11 frames)
  int32_t elements;      ///< CalculiX: B32 elements along the strand; default 40
} fascia_tissue_hang_def;

fascia_tissue_hang_def fascia_tissue_hang_def_default(void);

/// What a solve of the hanging organ gave (either code).
typedef struct fascia_tissue_hang_result {
  double centre[3]; ///< displacement of the organ's centre of mass, m
  double end[3];    ///< displacement of the strand's end on the organ, m
  double angle;     ///< the organ's rotation about +y, rad (positive: its far end down)
  double force[3];  ///< the strand's force on the fixed organ A, N
  int32_t nodes;    ///< fascia: frames; CalculiX: beam nodes
  double ms;        ///< wall time of the solve (fascia: prep excluded; CalculiX: deck, ccx, output)
} fascia_tissue_hang_result;

/// fascia's sheet mesh: squares split by alternating diagonals (right
/// triangles); every other row of vertices shifted by half a square, the
/// rows zipped (isosceles triangles of angles 53-63-63 degrees, as a
/// mesher's near-equilateral ones); those with their inner vertices moved
/// by a fixed pseudo-random fifth of a square (irregular, as a real
/// membrane's mesh). The centre and the free edges' middles stay vertices.
typedef enum fascia_tissue_mesh {
  FASCIA_TISSUE_MESH_RIGHT = 0,
  FASCIA_TISSUE_MESH_SHIFTED = 1,
  FASCIA_TISSUE_MESH_JITTERED = 2,
} fascia_tissue_mesh;
/// "right", "shifted", "jittered"; NULL for another value.
const char *fascia_tissue_mesh_name(int32_t mesh);

/// The sheet under a pull. Start from fascia_tissue_pull_def_default().
typedef struct fascia_tissue_pull_def {
  double gap;            ///< m, the sheet's length along x; default 0.02
  double width;          ///< m, along y, less than box; default 0.016
  double box;            ///< m, the organs' edge; default 0.02
  double thickness;      ///< m; default 0.001
  double youngs_modulus; ///< Pa; default 1e5 (a membrane)
  double poisson_ratio;  ///< default 0.3
  double pull[3];        ///< m, B's translation; default (0, 0.001, 0): in-plane shear
  int32_t cells[2];      ///< fascia: mesh squares along x, y (each split in two triangles), even; default 10 x 8
  int32_t mesh;          ///< fascia: a fascia_tissue_mesh; default FASCIA_TISSUE_MESH_RIGHT
  int32_t elements[2];   ///< CalculiX: S8R elements along x, y, even; default 20 x 16
} fascia_tissue_pull_def;

fascia_tissue_pull_def fascia_tissue_pull_def_default(void);

/// What a solve of the pulled sheet gave (either code).
typedef struct fascia_tissue_pull_result {
  double force[3];  ///< the sheet's force on the pulled organ B, N
  /// displacement of the middle of a free edge, (0, width/2, 0), less the
  /// centre's, m: what the sheet does beyond the half pull that the symmetry
  /// of the case gives its centre
  double edge[3];
  double centre[3]; ///< displacement of the sheet's centre (0, 0, 0), m
  int32_t nodes;    ///< fascia: frames; CalculiX: shell nodes
  double ms;        ///< wall time of the solve
  int32_t newton_iterations;  ///< fascia: of the static solve; CalculiX: 0
  int32_t negative_curvature; ///< fascia: its linear solves that met a tangent not positive definite
} fascia_tissue_pull_result;

/// File names a scene folder gets: the organs' boxes, the sheet's mesh, the scene.
#define FASCIA_TISSUE_BOX_A "a.obj"
#define FASCIA_TISSUE_BOX_B "b.obj"
#define FASCIA_TISSUE_SHEET "sheet.obj"
#define FASCIA_TISSUE_SCENE "scene.json"

/// Writes the fascia scene of a case (the boxes, the sheet's mesh, scene.json
/// with the "stvk" law) into the existing folder `dir` (def passed as void *
/// for fascia_tissue_prepare). Errors: FASCIA_ERR_ARGUMENT (a bad def, naming
/// the field), FASCIA_ERR_IO.
typedef fascia_status (*fascia_tissue_scene_writer)(fascia_ctx *ctx, const void *def, const char *dir);
fascia_status fascia_tissue_hang_write_scene(fascia_ctx *ctx, const void *hang_def, const char *dir);
fascia_status fascia_tissue_pull_write_scene(fascia_ctx *ctx, const void *pull_def, const char *dir);

/// Node number (from 1) of point (i, j) of a rectangle of ex x ey S8R
/// elements: a (2 ex + 1) x (2 ey + 1) grid of corners and mid-sides, i fastest.
int32_t fascia_ccx_s8r_node(int32_t ex, int32_t i, int32_t j);
/// Writes the *NODE (NSET=NALL) and *ELEMENT (S8R, ELSET=EALL) cards of that
/// rectangle over [x0, x0 + lx] x [y0, y0 + ly] in the plane z = 0, its
/// corners counter-clockwise seen from +z, then its mid-sides.
void fascia_ccx_s8r_rectangle(FILE *out, int32_t ex, int32_t ey, double x0, double lx, double y0, double ly);

/// The CalculiX decks of the cases (def passed as void * for fascia_ccx_run_deck).
fascia_status fascia_tissue_hang_write_deck(fascia_ctx *ctx, const void *hang_def, FILE *out);
fascia_status fascia_tissue_pull_write_deck(fascia_ctx *ctx, const void *pull_def, FILE *out);

/// Solves a case with CalculiX (`program`, see fascia_ccx_program; one
/// thread). Errors: those of fascia_ccx_run_deck, FASCIA_ERR_FORMAT when its
/// output lacks a value asked for.
fascia_status fascia_tissue_hang_calculix(fascia_ctx *ctx, const fascia_tissue_hang_def *def, const char *program,
                                          fascia_tissue_hang_result *out);
fascia_status fascia_tissue_pull_calculix(fascia_ctx *ctx, const fascia_tissue_pull_def *def, const char *program,
                                          fascia_tissue_pull_result *out);

/// Solves a case with fascia: the scene written into a temporary folder,
/// fascia prep's stages, a static solve on the CPU (one thread, Newton
/// tolerance 1e-10), the folder removed. Only in builds with prep (the
/// library fascia_tissue_reference). Errors: those of the stages, with
/// their messages; FASCIA_ERR_NUMERIC when the solve does not converge.
fascia_status fascia_tissue_hang_fascia(fascia_ctx *ctx, const fascia_tissue_hang_def *def,
                                        fascia_tissue_hang_result *out);
fascia_status fascia_tissue_pull_fascia(fascia_ctx *ctx, const fascia_tissue_pull_def *def,
                                        fascia_tissue_pull_result *out);

/// Pieces of the cases above for other cases (shell_calculix.c): the box
/// [x0, x0 + edge] x [-edge/2, edge/2]^2 as dir/name (a closed OBJ); the
/// start of the deck's NLGEOM step with its controls; the values of `node`
/// in the last block of a .dat text headed `header` (0 if none).
fascia_status fascia_tissue_write_box(fascia_ctx *ctx, const char *dir, const char *name, double x0, double edge);
void fascia_tissue_deck_step(FILE *out);
int fascia_tissue_dat_node(const char *dat, const char *header, long long node, double v[3]);
/// dir/name opened for writing, its path in `path` (1024 chars); NULL (the
/// context says why) when it cannot be; closed, FASCIA_ERR_IO if writing failed.
FILE *fascia_tissue_open(fascia_ctx *ctx, const char *dir, const char *name, char *path);
fascia_status fascia_tissue_close(fascia_ctx *ctx, FILE *f, const char *path);

/// A case prepared as `fascia prep` does: its scene written by `write` into
/// a fresh folder under $TMPDIR or /tmp, prep's stages run into *stages (to
/// free with fascia_prep_stages_free), the folder removed again. And the
/// cases' static solve at time 1 (CPU, one thread, Newton tolerance 1e-10;
/// the motion at once, or where that fails in 4 and then 16 load steps;
/// FASCIA_ERR_NUMERIC when not converged; *solver, NULL or a solver to
/// replace, to destroy).
struct fascia_prep_stages; // fascia/prep.h: the solved cases need prep
fascia_status fascia_tissue_prepare(fascia_ctx *ctx, fascia_tissue_scene_writer write, const void *def,
                                    struct fascia_prep_stages *stages);
fascia_status fascia_tissue_solve_static(fascia_ctx *ctx, const fascia_model *model, fascia_solver **solver,
                                         fascia_solve_report *report, double *ms);

/// |a - b| / |b| of two 3-vectors (the relative error of a against b); 0 when both are 0.
double fascia_tissue_error3(const double a[3], const double b[3]);

#ifdef __cplusplus
}
#endif
#endif
