// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// CGAL Mesh_3 adapter: a domain given by a labelling function meshed as
// conforming tetrahedra (cgal_mesh3.h). The mesh grows from seed points the
// caller puts on the boundary, as CGAL's random rays from the box's centre
// miss a thin domain.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/refine_mesh_3.h>

#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <vector>

#include "cgal_fail.hpp"
#include "cgal_mesh3.h"

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Domain = CGAL::Labeled_mesh_domain_3<K>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;
using Point = K::Point_3;

// The caller's facet distance bound as a Mesh_3 sizing field.
struct Facet_distance {
  const fascia_cgal_tet_def *def;
  typedef K::FT FT;
  typedef Domain::Index Index;
  FT operator()(const Point &p, const int, const Index &) const {
    const double x[3] = {p.x(), p.y(), p.z()};
    return def->facet_distance(def->user, x);
  }
};

} // namespace

extern "C" fascia_status fascia_cgal_tet_mesh(fascia_ctx *ctx, const char *what, const fascia_cgal_tet_def *def,
                                              double **vertices, int64_t *vertex_count, int32_t **tets,
                                              int64_t *tet_count) {
  *vertices = nullptr, *tets = nullptr, *vertex_count = 0, *tet_count = 0;
  try {
    std::function<int(const Point &)> label = [def](const Point &p) {
      const double x[3] = {p.x(), p.y(), p.z()};
      return def->label(def->user, x);
    };
    const CGAL::Bbox_3 box(def->lo[0], def->lo[1], def->lo[2], def->hi[0], def->hi[1], def->hi[2]);
    Domain domain(label, box, def->relative_error_bound);
    namespace params = CGAL::parameters;
    const Facet_distance distance{def};
    Criteria criteria(params::facet_angle = def->facet_angle, params::facet_size = def->facet_size,
                      params::facet_distance = distance,
                      params::cell_radius_edge_ratio = def->cell_radius_edge_ratio,
                      params::cell_size = def->cell_size);
    // the seeds as Mesh_3's own initial points are put: on a surface patch, dimension 2
    C3t3 c3t3;
    Tr &tr = c3t3.triangulation();
    const auto weighted = tr.geom_traits().construct_weighted_point_3_object();
    const Domain::Index on_surface = domain.index_from_surface_patch_index(Domain::Surface_patch_index(0, 1));
    for (int64_t k = 0; k < def->seed_count; ++k) {
      const double *s = def->seeds + 3 * k;
      const Tr::Vertex_handle v = tr.insert(weighted(Point(s[0], s[1], s[2])));
      if (v == Tr::Vertex_handle()) continue;
      c3t3.set_dimension(v, 2);
      c3t3.set_index(v, on_surface);
    }
    if (tr.dimension() < 3)
      return fascia_ctx_fail(ctx, FASCIA_ERR_ARGUMENT, __FILE__, __LINE__,
                             "%s: %lld seed points span no volume; the domain is empty or flat", what,
                             (long long)def->seed_count);
    CGAL::refine_mesh_3(c3t3, domain, criteria, params::perturb(params::time_limit = 60),
                        params::exude(params::time_limit = 60));

    // the cells of the domain, their vertices numbered in visiting order
    std::map<Tr::Vertex_handle, int32_t> id;
    std::vector<double> xyz;
    std::vector<int32_t> cells;
    for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
      int32_t q[4];
      double p[4][3];
      for (int i = 0; i < 4; ++i) {
        const Tr::Vertex_handle v = c->vertex(i);
        const auto found = id.find(v);
        const Point &x = tr.point(c, i).point();
        if (found == id.end()) {
          q[i] = (int32_t)(xyz.size() / 3);
          id.emplace(v, q[i]);
          xyz.push_back(x.x()), xyz.push_back(x.y()), xyz.push_back(x.z());
        } else {
          q[i] = found->second;
        }
        p[i][0] = x.x(), p[i][1] = x.y(), p[i][2] = x.z();
      }
      double a[3], b[3], d[3];
      for (int r = 0; r < 3; ++r) a[r] = p[1][r] - p[0][r], b[r] = p[2][r] - p[0][r], d[r] = p[3][r] - p[0][r];
      const double volume = (a[1] * b[2] - a[2] * b[1]) * d[0] + (a[2] * b[0] - a[0] * b[2]) * d[1] +
                            (a[0] * b[1] - a[1] * b[0]) * d[2];
      if (volume < 0) std::swap(q[2], q[3]);
      cells.insert(cells.end(), q, q + 4);
    }
    if (cells.empty())
      return fascia_ctx_fail(ctx, FASCIA_ERR_ARGUMENT, __FILE__, __LINE__,
                             "%s: Mesh_3 gave no tetrahedron (the seeds lie on no boundary of the domain)", what);
    *vertices = static_cast<double *>(std::malloc(xyz.size() * sizeof(double)));
    *tets = static_cast<int32_t *>(std::malloc(cells.size() * sizeof(int32_t)));
    if (!*vertices || !*tets) {
      std::free(*vertices), std::free(*tets);
      *vertices = nullptr, *tets = nullptr;
      return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "%s: out of memory for %lld tetrahedra",
                             what, (long long)(cells.size() / 4));
    }
    std::memcpy(*vertices, xyz.data(), xyz.size() * sizeof(double));
    std::memcpy(*tets, cells.data(), cells.size() * sizeof(int32_t));
    *vertex_count = (int64_t)(xyz.size() / 3), *tet_count = (int64_t)(cells.size() / 4);
    return FASCIA_OK;
  } catch (...) {
    std::free(*vertices), std::free(*tets);
    *vertices = nullptr, *tets = nullptr;
    return fascia_cgal_fail(ctx, what, "Mesh_3");
  }
}
