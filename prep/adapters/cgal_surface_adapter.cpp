// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// CGAL adapter for shell organs (prep/src/shell.c): the triangles of points
// spread over a surface, by advancing-front surface reconstruction (Cohen-
// Steiner and Da, 2004), which joins each point only to its neighbours on
// the surface. Apart from cgal_adapter.cpp so that its heavy header is
// compiled once, by itself.
#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <array>
#include <cstdlib>
#include <exception>
#include <new>
#include <vector>

#include "adapters.h"
#include "cgal_fail.hpp"

extern "C" fascia_status fascia_cgal_surface_triangles(fascia_ctx *ctx, const char *what, int32_t n,
                                                       const double *points, int32_t **out_triangles,
                                                       int32_t *out_count) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  *out_triangles = nullptr;
  *out_count = 0;
  try {
    std::vector<K::Point_3> input;
    input.reserve((size_t)n);
    for (int32_t i = 0; i < n; ++i) input.emplace_back(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
    std::vector<std::array<std::size_t, 3>> facets;
    CGAL::advancing_front_surface_reconstruction(input.begin(), input.end(), std::back_inserter(facets));
    int32_t *triangles = (int32_t *)std::malloc(3 * (facets.empty() ? 1 : facets.size()) * sizeof(int32_t));
    if (!triangles) throw std::bad_alloc();
    for (size_t k = 0; k < facets.size(); ++k)
      for (int r = 0; r < 3; ++r) triangles[3 * k + r] = (int32_t)facets[k][r];
    *out_triangles = triangles;
    *out_count = (int32_t)facets.size();
    return FASCIA_OK;
  } catch (...) {
    return fascia_cgal_fail(ctx, what, "surface reconstruction");
  }
}

extern "C" fascia_status fascia_cgal_soup_self_intersections(fascia_ctx *ctx, const char *what, int32_t n,
                                                             const double *points, int32_t triangle_count,
                                                             const int32_t *triangles, int64_t *out_pairs) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Mesh = CGAL::Surface_mesh<K::Point_3>;
  *out_pairs = 0;
  try {
    std::vector<K::Point_3> input;
    input.reserve((size_t)n);
    for (int32_t i = 0; i < n; ++i) input.emplace_back(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
    std::vector<std::vector<std::size_t>> faces((size_t)triangle_count);
    for (int32_t k = 0; k < triangle_count; ++k)
      faces[(size_t)k] = {(std::size_t)triangles[3 * k], (std::size_t)triangles[3 * k + 1],
                          (std::size_t)triangles[3 * k + 2]};
    CGAL::Polygon_mesh_processing::orient_polygon_soup(input, faces);
    Mesh mesh;
    CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(input, faces, mesh);
    std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
    CGAL::Polygon_mesh_processing::self_intersections(mesh, std::back_inserter(pairs));
    *out_pairs = (int64_t)pairs.size();
    return FASCIA_OK;
  } catch (...) {
    return fascia_cgal_fail(ctx, what, "self-intersection test");
  }
}
