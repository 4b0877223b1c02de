// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A prepared scene's volume tissue against CalculiX, statically: the
// tissue's region voxels as hexahedra (C3D8I, or C3D20R), every node on a
// voxel face that borders an organ's inside moved with that organ's pose at
// time 1 (fixed organs: held), gravity off, the stable Neo-Hookean written
// exactly as a three-term *HYPERFOAM. fascia prepares the same scene (gravity
// off, its spacings scaled for a refinement ladder) and solves it statically
// at time 1. Compared: the tissue's force on each organ, and fascia's
// displacement, evaluated through its shape functions at CalculiX's nodes
// (tools/bench/demo_calculix.c, docs/measured.md "The demo tissue against
// CalculiX").
#ifndef FASCIA_TOOLS_DEMO_CALCULIX_H
#define FASCIA_TOOLS_DEMO_CALCULIX_H
#include <stdio.h>

#include "fascia/fascia.h"
#include "fascia/prep.h"

#ifdef __cplusplus
extern "C" {
#endif

#define FASCIA_DEMO_ORGANS_MAX 8

/// Which scene and how it is prepared.
typedef struct fascia_demo_def {
  const char *scene;    ///< the scene file (its first tissue is the one compared; a volume)
  double voxel_size;    ///< m; 0: the scene's
  double spacing_scale; ///< the first tissue's frame and sample spacings times this; 0: 1
  double sample_scale;  ///< its sample spacing times this on top; 0: 1
  int32_t neighbours;   ///< MLS neighbours; 0: the scene's
  int32_t no_patches;   ///< 1: the tissue without volumetric patches (its whole energy per sample)
  int32_t attachment;   ///< 0: the scene's; 1: frames; 2: exact (fascia_prep_attachment_kind + 1)
  double layer_scale;   ///< exact: its layer this times the (scaled) sample spacing; 0: the scene's
} fascia_demo_def;

/// The scene prepared as `fascia prep` does, gravity set to zero and the
/// def's changes made, into *out (to free with fascia_prep_stages_free).
fascia_status fascia_demo_prepare(fascia_ctx *ctx, const fascia_demo_def *def, fascia_prep_stages *out);

/// CalculiX's mesh of the first tissue's region.
typedef struct fascia_demo_mesh {
  int quadratic;                 ///< 0: C3D8I, 1: C3D20R (hexahedra) or C3D10 (tetrahedra)
  int tetrahedra;                ///< 1: C3D10 tetrahedra of fascia_demo_tet_mesh_build
  int32_t subdivide;             ///< elements along a voxel's edge
  int64_t node_count, element_count;
  double *node;                  ///< [3 nodes] rest, m
  int32_t *node_organ;           ///< [nodes] organ (scene order) whose inside the node's face borders; -1: free
  double *node_u;                ///< [3 nodes] the organ's displacement there at time 1 (0 for free nodes), m
  /// [nodes] a held node's signed distance to its organ's surface (m,
  /// positive off the organ, into the tissue: where CalculiX holds the
  /// tissue, against fascia's shared frames on the surface); NAN when free
  double *node_distance;
  int32_t *element;              ///< [8, 20 or 10 per element] node indices from 0, ccx's order
  /// tetrahedra: the smallest dihedral angle of the straight tetrahedra
  /// (degrees), the smallest ratio of the quadratic element's Jacobian at a
  /// corner or integration point to its straight one, and the elements where
  /// that ratio is not positive (inverted)
  double min_dihedral, min_jacobian_ratio;
  int64_t inverted;
  int32_t organ_count;           ///< the scene's organs
  char organ_name[FASCIA_DEMO_ORGANS_MAX][FASCIA_NAME_SIZE];
  double youngs_modulus, poisson_ratio; ///< the tissue's
  const char *solver;            ///< ccx's linear solver (*STATIC, SOLVER=...); NULL: its default
  /// 1: linear elasticity (*ELASTIC with the tissue's E and nu, no NLGEOM,
  /// one increment), for a small motion where the nonlinear solve stalls
  int linear;
} fascia_demo_mesh;

/// Builds the mesh from prepared stages (their volume, and the organs'
/// poses at time 1 from a solver on their model). on_surface: the held
/// nodes moved onto the organs' smooth surfaces (where fascia holds the
/// tissue), else left on the voxel faces' staircase. The tissue must be a
/// volume of the stable Neo-Hookean. Errors: FASCIA_ERR_ARGUMENT (subdivide
/// outside 1..4, another law, too many organs), FASCIA_ERR_MEMORY.
fascia_status fascia_demo_mesh_build(fascia_ctx *ctx, const fascia_prep_stages *stages, int quadratic,
                                     int32_t subdivide, int on_surface, fascia_demo_mesh *out);
void fascia_demo_mesh_free(fascia_demo_mesh *mesh);

/// The same region as conforming quadratic tetrahedra (C3D10) whose held
/// nodes lie on the organs' smooth surfaces: the domain is a smoothed
/// indicator of the region's voxels (with the organ voxels beside them)
/// less the organs' insides (their signed distance fields), meshed by CGAL's
/// Mesh_3 with tetrahedra of circumradius at most `size` (m) and facets
/// within `facet_distance` (m; 0: a twentieth of a voxel) of the organs'
/// surfaces. A node is held by
/// an organ when it lies on its surface (corners) or on an edge of a facet
/// whose corners all do (mid-edge nodes, projected onto the surface).
/// Errors: FASCIA_ERR_ARGUMENT (size not positive, another law, too many
/// organs, an empty region), those of the mesher, FASCIA_ERR_MEMORY.
fascia_status fascia_demo_tet_mesh_build(fascia_ctx *ctx, const fascia_prep_stages *stages, double size,
                                         double facet_distance, fascia_demo_mesh *out);

/// What a solve gave (either code).
typedef struct fascia_demo_result {
  int32_t organ_count;
  double force[FASCIA_DEMO_ORGANS_MAX][3]; ///< the tissue's force on each organ (scene order), N
  double ms;                               ///< wall time of the solve (fascia: prep excluded)
  int64_t nodes;                           ///< CalculiX: nodes; fascia: frames
  int64_t elements;                        ///< CalculiX: elements; fascia: samples
  double *u;                               ///< [3 mesh nodes] displacement at the mesh's nodes, m (malloc'd)
  /// fascia: its slip on each organ where the tissue lies on it: at the
  /// organ's rest surface vertices in or beside a voxel of the region,
  /// |u_tissue - u_organ| (m) and the vertex's distance to the organ's
  /// nearest shared frame (m); malloc'd [surface_count[o]]
  int64_t surface_count[FASCIA_DEMO_ORGANS_MAX];
  double *surface_slip[FASCIA_DEMO_ORGANS_MAX], *surface_distance[FASCIA_DEMO_ORGANS_MAX];
} fascia_demo_result;
void fascia_demo_result_free(fascia_demo_result *result);

/// The CalculiX deck of a mesh (fascia_demo_mesh passed as void *).
fascia_status fascia_demo_write_deck(fascia_ctx *ctx, const void *mesh, FILE *out);
/// Solves the mesh with CalculiX (`program`, fascia_ccx_program) on
/// `threads` threads. Errors: those of fascia_ccx_run_deck, FASCIA_ERR_FORMAT
/// when its output lacks a value.
fascia_status fascia_demo_calculix(fascia_ctx *ctx, const fascia_demo_mesh *mesh, const char *program, int threads,
                                   fascia_demo_result *out);
/// Solves the prepared model with fascia, statically at time 1 (CPU, one
/// thread, Newton tolerance 1e-10), and, when `at` is not NULL, evaluates
/// its displacement at the mesh's nodes (fascia_demo_displacement_at) and
/// its slip on the organs' surfaces.
fascia_status fascia_demo_fascia(fascia_ctx *ctx, const fascia_prep_stages *stages, const fascia_demo_mesh *at,
                                 fascia_demo_result *out);

/// fascia's displacement at n points (rest, m) through the model's shape
/// functions: at the nearest sample s, phi(s) + F_s (p - s) - p, with phi
/// and F the frames' interpolated map and its gradient at the solver's
/// state (exact where the weights are linear across the offset).
fascia_status fascia_demo_displacement_at(fascia_ctx *ctx, const fascia_model *model, const fascia_solver *solver,
                                          int64_t n, const double *points, double *u);

/// One C3D8I cube of edge 1 under the homogeneous deformation gradient F
/// (row-major), the stable Neo-Hookean of E, nu as *HYPERFOAM (linear: the
/// linear deck of fascia_demo_mesh.linear instead): CalculiX's first Piola
/// stress P (row-major) from its reactions. A check that the material card
/// is the law.
fascia_status fascia_demo_one_element(fascia_ctx *ctx, const char *program, double youngs_modulus,
                                      double poisson_ratio, int linear, const double F[9], double P[9]);

/// Percentiles of n values (sorted in place): q in [0, 1], nearest rank.
double fascia_demo_percentile(double *values, int64_t n, double q);
/// The tissue's volume by distance to its nearest organ (the stages' signed
/// distance fields): bands [edge[k-1], edge[k]) m for k < bands (edge[-1] =
/// -inf), into volume[bands] (m^3), the last band everything beyond. Of the
/// mesh's tetrahedra (straight, at their centroids) when mesh is not NULL,
/// else of the model's tissue samples (at their positions).
void fascia_demo_volume_bands(const fascia_prep_stages *stages, const fascia_demo_mesh *mesh, int bands,
                              const double *edge, double *volume);

#ifdef __cplusplus
}
#endif
#endif
