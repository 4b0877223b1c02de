// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// C-only interface of the three C++ adapters: assimp reads
// mesh files, CGAL checks and repairs surfaces and answers closest-point
// queries, OpenVDB computes distances and surfaces of voxel fields. No C++ type crosses; every
// function catches all exceptions into a status and a message on the ctx.
// Arrays returned by the adapters are malloc'ed: free them with free().
#ifndef FASCIA_PREP_ADAPTERS_H
#define FASCIA_PREP_ADAPTERS_H

#include "fascia/base.h"

#ifdef __cplusplus
extern "C" {
#endif

#define FASCIA_PREP_INTERN __attribute__((visibility("hidden")))

// ------------------------------------------------------------------ assimp

/// Every triangle mesh instance in a file: part p is one (node, mesh) pair,
/// vertices in file units with the node's accumulated transform applied.
typedef struct fascia_assimp_file {
  int32_t part_count;
  char **node_names;        ///< [part_count]
  char **mesh_names;        ///< [part_count]
  int32_t *vertex_offset;   ///< [part_count + 1]
  int32_t *triangle_offset; ///< [part_count + 1]
  double *vertices;         ///< [3 vertex_offset[part_count]]
  int32_t *triangles;       ///< [3 triangle_offset[part_count]] indices into vertices (global)
  int32_t skipped_primitives; ///< points and lines ignored
} fascia_assimp_file;

/// Reads path (any format assimp knows). On error *out is NULL and the
/// message names the file and assimp's reason.
FASCIA_PREP_INTERN fascia_status fascia_assimp_read(fascia_ctx *ctx, const char *path, fascia_assimp_file **out);
FASCIA_PREP_INTERN void fascia_assimp_free(fascia_assimp_file **file);

// ------------------------------------------------------------------ CGAL

typedef struct fascia_cgal_report {
  int32_t duplicate_vertices_merged, degenerate_faces_removed, duplicate_faces_removed, nonmanifold_vertices_split;
  int32_t components, closed_components, components_reoriented;
  int32_t border_edges, holes_filled, holes_left, self_intersections;
  double area;
} fascia_cgal_report;

/// Checks and repairs one triangle soup (one part): see fascia_prep_repair.
/// Holes with at most max_hole_edges border edges and a diameter below
/// max_hole_diameter (m) are filled. Self-intersections are counted up to
/// max_intersections (0: not checked). On success *out_vertices and
/// *out_triangles hold the repaired surface (malloc'ed).
FASCIA_PREP_INTERN fascia_status fascia_cgal_repair(fascia_ctx *ctx, const char *what, int32_t vertex_count,
                                                    const double *vertices, int32_t triangle_count,
                                                    const int32_t *triangles, int32_t max_hole_edges,
                                                    double max_hole_diameter, int32_t max_intersections,
                                                    double **out_vertices, int32_t *out_vertex_count,
                                                    int32_t **out_triangles, int32_t *out_triangle_count,
                                                    fascia_cgal_report *report);

/// An AABB tree over a triangle soup for closest-point queries.
typedef struct fascia_cgal_tree fascia_cgal_tree;
FASCIA_PREP_INTERN fascia_status fascia_cgal_tree_create(fascia_ctx *ctx, int32_t vertex_count,
                                                         const double *vertices, int32_t triangle_count,
                                                         const int32_t *triangles, fascia_cgal_tree **out);
/// Closest surface point and its triangle for n query points. Read-only on
/// the tree: threads may query one tree at the same time.
FASCIA_PREP_INTERN void fascia_cgal_tree_closest(const fascia_cgal_tree *tree, int64_t n, const double *points,
                                                 double *closest, int32_t *triangle);
FASCIA_PREP_INTERN void fascia_cgal_tree_destroy(fascia_cgal_tree **tree);

/// Delaunay tetrahedralisation of n points: *out_tets holds 4 point indices
/// per finite tetrahedron (malloc'ed), positively oriented.
FASCIA_PREP_INTERN fascia_status fascia_cgal_delaunay(fascia_ctx *ctx, int32_t n, const double *points,
                                                      int32_t **out_tets, int32_t *out_tet_count);

/// Triangles over n points spread over a surface (a shell's frames): 3
/// point indices each (malloc'ed), each point joined only to its neighbours
/// on the surface (advancing-front reconstruction). The triangles come in a
/// canonical order, a function of the points alone: each from its smallest
/// index, sorted by their indices; their winding is the reconstruction's, not
/// to be relied on. what names the surface in messages.
FASCIA_PREP_INTERN fascia_status fascia_cgal_surface_triangles(fascia_ctx *ctx, const char *what, int32_t n,
                                                               const double *points, int32_t **out_triangles,
                                                               int32_t *out_count);
/// Pairs of triangles of a triangle soup over points that cross (sharing a
/// corner or an edge is not crossing) into *out_pairs.
FASCIA_PREP_INTERN fascia_status fascia_cgal_soup_self_intersections(fascia_ctx *ctx, const char *what, int32_t n,
                                                                     const double *points, int32_t triangle_count,
                                                                     const int32_t *triangles, int64_t *out_pairs);

// ------------------------------------------------------------------ OpenVDB

/// Unsigned distance (m) from a triangle soup, on the dense box of lattice
/// voxels lo .. lo + dims - 1 (voxel (i,j,k) centred at h (i,j,k)), x fastest.
/// Exact within band_voxels voxels of the surface; farther voxels get
/// band_voxels * h.
FASCIA_PREP_INTERN fascia_status fascia_vdb_unsigned_distance(fascia_ctx *ctx, int32_t vertex_count,
                                                              const double *vertices, int32_t triangle_count,
                                                              const int32_t *triangles, double h,
                                                              float band_voxels, const int32_t lo[3],
                                                              const int32_t dims[3], float *out);

/// The surface of a dense indicator (x fastest; 1 inside, 0 outside, the
/// box padded by smoothing + 2 empty voxels): the level midway between inside
/// and outside voxel centres after smoothing passes of a 3x3x3 mean filter.
/// Vertices in the box's index coordinates, triangles wound outward.
FASCIA_PREP_INTERN fascia_status fascia_vdb_indicator_surface(fascia_ctx *ctx, const int32_t dims[3],
                                                              const float *inside, int32_t smoothing,
                                                              double **out_vertices, int32_t *out_vertex_count,
                                                              int32_t **out_triangles, int32_t *out_triangle_count);
/// The closed surface (m) less everything within depth (m) of the other
/// closed surface, as level sets at voxel size h: max(d, depth - d_other),
/// meshed again.
FASCIA_PREP_INTERN fascia_status fascia_vdb_carve(fascia_ctx *ctx, int32_t vertex_count, const double *vertices,
                                                  int32_t triangle_count, const int32_t *triangles,
                                                  int32_t other_vertex_count, const double *other_vertices,
                                                  int32_t other_triangle_count, const int32_t *other_triangles,
                                                  double h, double depth, double **out_vertices,
                                                  int32_t *out_vertex_count, int32_t **out_triangles,
                                                  int32_t *out_triangle_count);

#ifdef __cplusplus
}
#endif
#endif
