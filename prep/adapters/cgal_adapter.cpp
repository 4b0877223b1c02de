// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// CGAL adapter: check and repair of one surface part (polygon-soup repair,
// consistent orientation, small-hole filling, self-intersection count), an
// AABB tree for closest-point queries, and the Delaunay tetrahedralisation of
// the mesh-based shape functions. The only translation unit that includes CGAL.
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <map>
#include <vector>

#include "adapters.h"
#include "cgal_fail.hpp"

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using face_descriptor = Mesh::Face_index;
using halfedge_descriptor = Mesh::Halfedge_index;
namespace PMP = CGAL::Polygon_mesh_processing;

// Counts what it is given; never stores (self-intersection pairs can be many).
struct Counter {
  int64_t *count;
  Counter &operator*() { return *this; }
  Counter &operator++() { return *this; }
  Counter operator++(int) { return *this; }
  template <typename T> Counter &operator=(const T &) {
    ++*count;
    return *this;
  }
};

// Signed volume enclosed by the faces of one component (positive: outward).
double component_volume(const Mesh &mesh, const std::vector<face_descriptor> &fs) {
  double v = 0;
  for (face_descriptor f : fs) {
    std::array<Point, 3> p;
    int r = 0;
    for (auto vd : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) p[r++] = mesh.point(vd);
    v += CGAL::to_double(CGAL::determinant(p[0] - CGAL::ORIGIN, p[1] - CGAL::ORIGIN, p[2] - CGAL::ORIGIN)) / 6;
  }
  return v;
}

} // namespace

extern "C" fascia_status fascia_cgal_repair(fascia_ctx *ctx, const char *what, int32_t vertex_count,
                                            const double *vertices, int32_t triangle_count, const int32_t *triangles,
                                            int32_t max_hole_edges, double max_hole_diameter,
                                            int32_t max_intersections, double **out_vertices,
                                            int32_t *out_vertex_count, int32_t **out_triangles,
                                            int32_t *out_triangle_count, fascia_cgal_report *report) {
  *out_vertices = nullptr;
  *out_triangles = nullptr;
  std::memset(report, 0, sizeof *report);
  try {
    // 1. the soup: exact duplicate points, faces with a repeated or collinear
    //    vertex (zero area: removing them leaves the geometry unchanged),
    //    duplicate faces
    std::vector<Point> points((size_t)vertex_count);
    for (int32_t v = 0; v < vertex_count; ++v)
      points[v] = Point(vertices[3 * v], vertices[3 * v + 1], vertices[3 * v + 2]);
    std::vector<std::vector<std::size_t>> polygons;
    polygons.reserve((size_t)triangle_count);
    for (int32_t t = 0; t < triangle_count; ++t)
      polygons.push_back({(std::size_t)triangles[3 * t], (std::size_t)triangles[3 * t + 1],
                          (std::size_t)triangles[3 * t + 2]});
    report->duplicate_vertices_merged = (int32_t)PMP::merge_duplicate_points_in_polygon_soup(points, polygons);
    std::vector<std::vector<std::size_t>> kept;
    kept.reserve(polygons.size());
    for (auto &poly : polygons) {
      const Point &a = points[poly[0]], &b = points[poly[1]], &c = points[poly[2]];
      if (poly[0] == poly[1] || poly[1] == poly[2] || poly[0] == poly[2] || CGAL::collinear(a, b, c))
        ++report->degenerate_faces_removed;
      else
        kept.push_back(poly);
    }
    polygons.swap(kept);
    report->duplicate_faces_removed = (int32_t)PMP::merge_duplicate_polygons_in_polygon_soup(
        points, polygons, CGAL::parameters::erase_all_duplicates(false).require_same_orientation(false));
    PMP::remove_isolated_points_in_polygon_soup(points, polygons);
    if (polygons.empty())
      return fascia_ctx_fail(ctx, FASCIA_ERR_FORMAT, __FILE__, __LINE__,
                             "%s: no face is left after removing %d degenerate faces; the part is empty", what,
                             (int)report->degenerate_faces_removed);

    // 2. consistent orientation; vertices where the surface is pinched
    //    (non-manifold) are split
    const std::size_t before = points.size();
    PMP::orient_polygon_soup(points, polygons);
    report->nonmanifold_vertices_split = (int32_t)(points.size() - before);
    Mesh mesh;
    PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);

    // 3. small holes
    std::vector<halfedge_descriptor> cycles;
    PMP::extract_boundary_cycles(mesh, std::back_inserter(cycles));
    for (halfedge_descriptor h : cycles) {
      int32_t edges = 0;
      CGAL::Bbox_3 box;
      for (halfedge_descriptor g : CGAL::halfedges_around_face(h, mesh)) {
        ++edges;
        box += mesh.point(mesh.source(g)).bbox();
      }
      const double dx = box.xmax() - box.xmin(), dy = box.ymax() - box.ymin(), dz = box.zmax() - box.zmin();
      if (edges <= max_hole_edges && dx * dx + dy * dy + dz * dz <= max_hole_diameter * max_hole_diameter) {
        std::vector<face_descriptor> patch;
        PMP::triangulate_hole(mesh, h, std::back_inserter(patch));
        if (!patch.empty())
          ++report->holes_filled;
        else
          ++report->holes_left;
      } else {
        ++report->holes_left;
      }
    }

    // 4. components, closedness and outward orientation of closed components
    auto fcc = mesh.add_property_map<face_descriptor, std::size_t>("f:cc", 0).first;
    const std::size_t ncc = PMP::connected_components(mesh, fcc);
    report->components = (int32_t)ncc;
    std::vector<std::vector<face_descriptor>> by_cc(ncc);
    std::vector<char> open(ncc, 0);
    for (face_descriptor f : mesh.faces()) by_cc[fcc[f]].push_back(f);
    for (halfedge_descriptor h : mesh.halfedges())
      if (mesh.is_border(h)) {
        ++report->border_edges;
        open[fcc[mesh.face(mesh.opposite(h))]] = 1;
      }
    for (std::size_t c = 0; c < ncc; ++c) {
      if (open[c]) continue;
      ++report->closed_components;
      if (component_volume(mesh, by_cc[c]) < 0) {
        PMP::reverse_face_orientations(by_cc[c], mesh);
        ++report->components_reoriented;
      }
    }

    // 5. self-intersections (counted, not repaired: inside/outside does not
    //    need a simple surface)
    if (max_intersections > 0) {
      int64_t pairs = 0;
      PMP::self_intersections(mesh, Counter{&pairs});
      report->self_intersections = (int32_t)(pairs > INT32_MAX ? INT32_MAX : pairs);
    }
    report->area = CGAL::to_double(PMP::area(mesh));

    // 6. back to arrays
    mesh.remove_property_map(fcc);
    mesh.collect_garbage();
    const int32_t nv = (int32_t)mesh.number_of_vertices(), nf = (int32_t)mesh.number_of_faces();
    double *ov = (double *)std::malloc(3 * (size_t)(nv ? nv : 1) * sizeof(double));
    int32_t *of = (int32_t *)std::malloc(3 * (size_t)(nf ? nf : 1) * sizeof(int32_t));
    if (!ov || !of) {
      std::free(ov);
      std::free(of);
      throw std::bad_alloc();
    }
    for (auto v : mesh.vertices()) {
      const Point &p = mesh.point(v);
      ov[3 * (size_t)v] = p.x();
      ov[3 * (size_t)v + 1] = p.y();
      ov[3 * (size_t)v + 2] = p.z();
    }
    int32_t k = 0;
    for (face_descriptor f : mesh.faces()) {
      int r = 0;
      for (auto vd : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) of[3 * k + r++] = (int32_t)(size_t)vd;
      ++k;
    }
    *out_vertices = ov;
    *out_vertex_count = nv;
    *out_triangles = of;
    *out_triangle_count = nf;
    return FASCIA_OK;
  } catch (...) {
    return fascia_cgal_fail(ctx, what, "repair");
  }
}

// ------------------------------------------------------------------ AABB tree

namespace {
using Triangle = K::Triangle_3;
using TriIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<K, TriIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
} // namespace

struct fascia_cgal_tree {
  std::vector<Triangle> triangles;
  Tree tree;
};

extern "C" fascia_status fascia_cgal_tree_create(fascia_ctx *ctx, int32_t vertex_count, const double *vertices,
                                                 int32_t triangle_count, const int32_t *triangles,
                                                 fascia_cgal_tree **out) {
  *out = nullptr;
  fascia_cgal_tree *t = nullptr;
  try {
    (void)vertex_count;
    t = new fascia_cgal_tree;
    t->triangles.reserve((size_t)triangle_count);
    for (int32_t f = 0; f < triangle_count; ++f) {
      const double *a = vertices + 3 * triangles[3 * f], *b = vertices + 3 * triangles[3 * f + 1],
                   *c = vertices + 3 * triangles[3 * f + 2];
      t->triangles.emplace_back(Point(a[0], a[1], a[2]), Point(b[0], b[1], b[2]), Point(c[0], c[1], c[2]));
    }
    t->tree.insert(t->triangles.cbegin(), t->triangles.cend());
    t->tree.build();
    t->tree.accelerate_distance_queries();
    *out = t;
    return FASCIA_OK;
  } catch (...) {
    delete t;
    return fascia_cgal_fail(ctx, "surface", "AABB tree");
  }
}

extern "C" void fascia_cgal_tree_closest(const fascia_cgal_tree *t, int64_t n, const double *points, double *closest,
                                         int32_t *triangle) {
  for (int64_t q = 0; q < n; ++q) {
    const auto hit = t->tree.closest_point_and_primitive(Point(points[3 * q], points[3 * q + 1], points[3 * q + 2]));
    closest[3 * q] = hit.first.x();
    closest[3 * q + 1] = hit.first.y();
    closest[3 * q + 2] = hit.first.z();
    triangle[q] = (int32_t)(hit.second - t->triangles.cbegin());
  }
}

extern "C" void fascia_cgal_tree_destroy(fascia_cgal_tree **tree) {
  if (!tree) return;
  delete *tree;
  *tree = nullptr;
}

// ------------------------------------------------------------------ Delaunay

extern "C" fascia_status fascia_cgal_delaunay(fascia_ctx *ctx, int32_t n, const double *points, int32_t **out_tets,
                                              int32_t *out_tet_count) {
  using Vb = CGAL::Triangulation_vertex_base_with_info_3<int32_t, K>;
  using Tds = CGAL::Triangulation_data_structure_3<Vb>;
  using Delaunay = CGAL::Delaunay_triangulation_3<K, Tds>;
  *out_tets = nullptr;
  *out_tet_count = 0;
  try {
    std::vector<std::pair<Point, int32_t>> input;
    input.reserve((size_t)n);
    for (int32_t i = 0; i < n; ++i) input.emplace_back(Point(points[3 * i], points[3 * i + 1], points[3 * i + 2]), i);
    Delaunay dt(input.begin(), input.end());
    const size_t count = dt.number_of_finite_cells();
    int32_t *tets = (int32_t *)std::malloc(4 * (count ? count : 1) * sizeof(int32_t));
    if (!tets) throw std::bad_alloc();
    size_t k = 0;
    for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c, ++k)
      for (int r = 0; r < 4; ++r) tets[4 * k + r] = c->vertex(r)->info();
    *out_tets = tets;
    *out_tet_count = (int32_t)count;
    return FASCIA_OK;
  } catch (...) {
    return fascia_cgal_fail(ctx, "frames", "Delaunay tetrahedralisation");
  }
}
