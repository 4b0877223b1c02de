// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// C-only interface of the CGAL Mesh_3 adapter (cgal_mesh3_adapter.cpp): a
// domain given by a labelling function meshed as conforming tetrahedra, for
// finite-element references of a tissue region (tools/scenes/demo_calculix.c).
#ifndef FASCIA_PREP_CGAL_MESH3_H
#define FASCIA_PREP_CGAL_MESH3_H

#include "fascia/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/// What to mesh and how finely. Lengths in m.
typedef struct fascia_cgal_tet_def {
  double lo[3], hi[3];    ///< a box that holds the domain
  /// 1 where x lies in the domain, 0 outside; its boundary is found by
  /// bisection to relative_error_bound of the box's diagonal
  int (*label)(void *user, const double x[3]);
  /// the facet distance bound at surface point x (how far a boundary
  /// facet may lie from the surface there)
  double (*facet_distance)(void *user, const double x[3]);
  void *user;
  double cell_size;       ///< the tetrahedra's circumradius bound
  double facet_size;      ///< the boundary facets' circumradius bound
  double facet_angle;     ///< degrees, the boundary facets' smallest angle bound
  double cell_radius_edge_ratio;
  double relative_error_bound;
  /// [3 seed_count] points on the domain's boundary, at least one on every
  /// component (the mesher grows the mesh from them)
  const double *seeds;
  int64_t seed_count;
} fascia_cgal_tet_def;

/// Meshes the domain with CGAL's Mesh_3 (Delaunay refinement, then sliver
/// perturbation and exudation): *vertices [3 vertex_count] (malloc'ed) and
/// *tets [4 tet_count] indices into them, each ordered with a positive
/// volume ((x1 - x0) x (x2 - x0) . (x3 - x0) > 0). `what` names the domain in
/// messages. On error both are NULL.
fascia_status fascia_cgal_tet_mesh(fascia_ctx *ctx, const char *what, const fascia_cgal_tet_def *def,
                                   double **vertices, int64_t *vertex_count, int32_t **tets, int64_t *tet_count);

#ifdef __cplusplus
}
#endif
#endif
