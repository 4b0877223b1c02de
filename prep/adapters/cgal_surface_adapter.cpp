// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// CGAL adapter for shell organs (prep/src/shell.c): the triangles of points
// spread over a surface, by advancing-front surface reconstruction (Cohen-
// Steiner and Da, 2004), which joins each point only to its neighbours on
// the surface. Apart from cgal_adapter.cpp so that its heavy header is
// compiled once, by itself.
//
// Addresses as order. The reconstruction breaks ties by memory address: its
// front is a std::set of (radius, address of an edge record), and vertex and
// cell handles of its Delaunay triangulation compare as pointers. On the
// shared heap those addresses follow whatever the process allocated before,
// so the triangles kept would too. Here every record whose address it
// compares lies in one arena reserved for the call, handed out upwards and
// never reused while the call runs: an address's order is then the order of
// allocation, which follows from the points alone.
//
//   reserved range  [ vertex and cell blocks | border records | ... |  free  )
//                   ^ base                             next ^          end ^
#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <sys/mman.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <memory>
#include <new>
#include <stdexcept>
#include <vector>

#include "adapters.h"
#include "cgal_fail.hpp"

namespace {

// Address space for one reconstruction: reserved, not committed (pages come
// as they are touched), released whole when the call ends.
class Arena {
public:
  explicit Arena(size_t bytes) : size(bytes) {
    void *p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    base = next = (char *)p;
  }
  ~Arena() { munmap(base, size); }
  Arena(const Arena &) = delete;
  Arena &operator=(const Arena &) = delete;
  // bytes aligned to align, above every earlier block
  void *take(size_t bytes, size_t align) {
    const uintptr_t at = ((uintptr_t)next + align - 1) & ~(uintptr_t)(align - 1);
    if (at > (uintptr_t)(base + size) || bytes > (uintptr_t)(base + size) - at) throw Full();
    next = (char *)(at + bytes);
    return (void *)at;
  }
  struct Full {};

private:
  size_t size;
  char *base, *next;
};

// The arena of the reconstruction running on this thread. CGAL builds its
// containers with default-constructed allocators, so the arena cannot ride
// in the allocator; it is set for the length of one call.
thread_local Arena *current_arena = nullptr;

template <class T> struct arena_allocator {
  using value_type = T;
  template <class U> struct rebind { using other = arena_allocator<U>; };
  arena_allocator() = default;
  template <class U> arena_allocator(const arena_allocator<U> &) {}
  T *allocate(size_t n) {
    if (!current_arena) throw std::logic_error("surface reconstruction's record allocated outside its arena");
    if (n > SIZE_MAX / sizeof(T)) throw std::bad_alloc();
    return (T *)current_arena->take(n * sizeof(T), alignof(T));
  }
  void deallocate(T *, size_t) {} // reused only when the arena goes
  // std::allocator_traits calls these on a std::allocator before C++20
  template <class U, class... Args> void construct(U *p, Args &&...args) {
    ::new ((void *)p) U(std::forward<Args>(args)...);
  }
  template <class U> void destroy(U *p) { p->~U(); }
  size_t max_size() const { return SIZE_MAX / sizeof(T); }
  template <class U> bool operator==(const arena_allocator<U> &) const { return true; }
  template <class U> bool operator!=(const arena_allocator<U> &) const { return false; }
};

// The triangulation's vertex and cell, types of this file so that their
// allocator (std::allocator, which CGAL's Compact_container takes by
// default) can be the arena's below.
template <class Base> struct Arena_vertex : Base {
  using Base::Base;
  template <class Tds> struct Rebind_TDS {
    using Other = Arena_vertex<typename Base::template Rebind_TDS<Tds>::Other>;
  };
};
template <class Base> struct Arena_cell : Base {
  using Base::Base;
  template <class Tds> struct Rebind_TDS { using Other = Arena_cell<typename Base::template Rebind_TDS<Tds>::Other>; };
};
} // namespace

namespace std {
template <class Base> struct allocator<Arena_vertex<Base>> : arena_allocator<Arena_vertex<Base>> {
  allocator() = default;
  template <class U> allocator(const allocator<U> &) {}
};
template <class Base> struct allocator<Arena_cell<Base>> : arena_allocator<Arena_cell<Base>> {
  allocator() = default;
  template <class U> allocator(const allocator<U> &) {}
};
} // namespace std

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vertex_base = Arena_vertex<CGAL::Advancing_front_surface_reconstruction_vertex_base_3<Kernel>>;
using Cell_base = Arena_cell<CGAL::Advancing_front_surface_reconstruction_cell_base_3<Kernel>>;
using Afsr_triangulation =
    CGAL::Delaunay_triangulation_3<Kernel, CGAL::Triangulation_data_structure_3<Vertex_base, Cell_base>>;
// The front's records: the reconstruction keeps them in a std::list and its
// front holds their addresses. A std::list allocates its nodes through
// std::allocator<node>, rebound from std::allocator<record> by the library,
// so the nodes' allocator is taken here too: any class template whose first
// argument is the record.
using Border_record = Afsr_triangulation::Vertex::Next_border_elt;
static_assert(std::is_base_of<arena_allocator<Afsr_triangulation::Vertex>,
                              Afsr_triangulation::Triangulation_data_structure::Vertex_range::allocator_type>::value &&
                  std::is_base_of<arena_allocator<Afsr_triangulation::Cell>,
                                  Afsr_triangulation::Triangulation_data_structure::Cell_range::allocator_type>::value,
              "the triangulation's vertices and cells come from the arena");
} // namespace

namespace std {
template <> struct allocator<Border_record> : arena_allocator<Border_record> {
  allocator() = default;
  template <class U> allocator(const allocator<U> &) {}
};
template <template <class...> class Node, class... Rest>
struct allocator<Node<Border_record, Rest...>> : arena_allocator<Node<Border_record, Rest...>> {
  allocator() = default;
  template <class U> allocator(const allocator<U> &) {}
};
} // namespace std

namespace {
// Makes an arena the thread's current one for a scope, however it is left.
class Arena_scope {
public:
  explicit Arena_scope(Arena &arena) : outer(current_arena) { current_arena = &arena; }
  ~Arena_scope() { current_arena = outer; }
  Arena_scope(const Arena_scope &) = delete;
  Arena_scope &operator=(const Arena_scope &) = delete;

private:
  Arena *outer;
};

// Address space reserved for n points: some sixteen times what a surface's
// triangulation and front take (about 1 KiB a point); only the pages
// touched cost memory.
constexpr size_t ARENA_FIXED = (size_t)32 << 20, ARENA_PER_POINT = (size_t)16 << 10;

// CGAL::advancing_front_surface_reconstruction with its default bounds, its
// records in an arena of this call.
void reconstruct(int32_t n, const double *points, std::vector<std::array<std::size_t, 3>> &facets) {
  Arena arena(ARENA_FIXED + (size_t)n * ARENA_PER_POINT);
  Arena_scope scope(arena);
  std::vector<Kernel::Point_3> input;
  input.reserve((size_t)n);
  for (int32_t i = 0; i < n; ++i) input.emplace_back(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
  const CGAL::AFSR::Auto_count<Kernel::Point_3> count; // each vertex's index in points
  Afsr_triangulation dt(boost::make_transform_iterator(input.begin(), count),
                        boost::make_transform_iterator(input.end(), count));
  CGAL::Advancing_front_surface_reconstruction<Afsr_triangulation> reconstruction(dt);
  reconstruction.run(5, 0.52);
  CGAL::write_triple_indices(std::back_inserter(facets), reconstruction);
}
} // namespace

extern "C" fascia_status fascia_cgal_surface_triangles(fascia_ctx *ctx, const char *what, int32_t n,
                                                       const double *points, int32_t **out_triangles,
                                                       int32_t *out_count) {
  *out_triangles = nullptr;
  *out_count = 0;
  try {
    std::vector<std::array<std::size_t, 3>> facets;
    reconstruct(n, points, facets);
    // the triangles in a canonical order: each from its smallest index (its
    // winding kept), sorted
    for (auto &f : facets) std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    std::sort(facets.begin(), facets.end());
    int32_t *triangles = (int32_t *)std::malloc(3 * (facets.empty() ? 1 : facets.size()) * sizeof(int32_t));
    if (!triangles) throw std::bad_alloc();
    for (size_t k = 0; k < facets.size(); ++k)
      for (int r = 0; r < 3; ++r) triangles[3 * k + r] = (int32_t)facets[k][r];
    *out_triangles = triangles;
    *out_count = (int32_t)facets.size();
    return FASCIA_OK;
  } catch (const Arena::Full &) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__,
                           "%s: surface reconstruction of %d frames needed more than the %zu MiB reserved for it "
                           "(ARENA_PER_POINT in cgal_surface_adapter.cpp); space the frames wider, or report the scene",
                           what, (int)n, (ARENA_FIXED + (size_t)n * ARENA_PER_POINT) >> 20);
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
