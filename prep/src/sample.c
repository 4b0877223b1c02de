// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Stage 4, sample: Poisson-disk frames and samples in each tissue region.
//
//   surface frames  candidates are points of the organ surfaces (a
//                   lattice on each triangle, a twentieth of the frame
//                   spacing apart) next to region voxels that touch the
//                   organ, so that frames shared with an organ lie exactly
//                   on it;
//   interior frames candidates are cell targets (below) in the region
//                   farther than the coupling tolerance from every organ;
//   mid-layer frames where a gap is thinner than the frame spacing (the
//                   surface frames on both sides refuse every interior
//                   candidate), the midpoints of the two nearest organs'
//                   closest points to cell targets in the gap, thrown against the
//                   interior frames only: a thin tissue keeps a layer of
//                   free frames instead of being all surface frames that
//                   move with the organs;
//   samples         candidates are cell targets in the region (meshless
//                   regions; mesh-based ones: see below).
//
// Candidates are visited in a seeded random order and kept when no kept
// point of the same kind lies closer than the spacing (dart throwing on a
// hash grid): the same scene gives the same points. The order, and the cell
// targets (random points, one per cell of a quarter of the spacing), come
// from the seed and the position in space, not from the voxel grid, so a
// finer voxel size refines the geometry without drawing new points. Each region voxel then
// goes to the nearest sample through the region (multi-source Dijkstra over
// the 26-neighbourhood), so sample volumes add up to the region volume
// exactly, and a sample moves to the centroid of its cell when that stays in
// the region (one Lloyd step: a better quadrature point). Samples finer than
// the voxels split each voxel into cells under half a spacing, each going
// to the nearest sample nearby, so the sample spacing is not floored by the
// voxel size.
// A piece of region that receives fewer than 4 frames, or only coplanar ones,
// gets more frames at its voxels farthest from the frames it has.
//
// Mesh-based regions (shape_functions.kind "tet") get no Poisson-disk
// samples: their frames are tetrahedralised (CGAL Delaunay), a tetrahedron is
// kept when its centroid, the midpoints of its edges and its quadrature
// points lie in the region's voxels, and the samples are the quadrature
// points of the kept tets (fascia_shape_tet_quadrature: 4 points of degree 2,
// or the centroid), each with its quadrature weight times the tet's volume.
// Sample volumes then add up to the kept tets' volume, not to the voxel
// volume: the tets reach at most the frames' hull, and tets poking out of the
// region are dropped. Each sample records its tet's frames, so the shape functions are
// barycentric in the sample's own tet and never extrapolate.
//
// Deformable organs. Their insides are regions too, sampled by the same code
// after the tissues. Their surface frames are not new points: the tissue
// frames on the organ's surface that the tissue's coupling rules allow are
// *shared*, each attached to the organ's inside voxel nearest to it (within
// two voxels; the frame sits exactly on the surface, between the tissue's
// voxels and the organ's). The organ's interior frames are thrown against
// them with the organ's frame_spacing, so both sides see the shared frames
// as their frames on the interface: each side's weights are built from frames
// that surround its samples (a partition of unity with linear reproduction on
// each side, and the two sides move together through the shared frames).
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/shape.h"
#include "prep_util.h"
#include "reduced.h"
#include "shell.h"

// The arrays of fascia_prep_points sized by its frames (N) or samples (S),
// declared once: X(member, type, count, width) gives count * width
// elements; allocation, its check and freeing follow from the list.
#define POINTS_ARRAYS(X)                                                                                               \
  X(frame_position, double, N, 3)                                                                                      \
  X(frame_tissue, int32_t, N, 1)                                                                                       \
  X(frame_inside_organ, int32_t, N, 1)                                                                                 \
  X(frame_organ, int32_t, N, 1)                                                                                        \
  X(frame_triangle, int32_t, N, 1)                                                                                     \
  X(frame_voxel, int64_t, N, 1)                                                                                        \
  X(frame_organ_voxel, int64_t, N, 1)                                                                                  \
  X(sample_position, double, S, 3)                                                                                     \
  X(sample_volume, double, S, 1)                                                                                       \
  X(sample_tissue, int32_t, S, 1)                                                                                      \
  X(sample_inside_organ, int32_t, S, 1)                                                                                \
  X(sample_voxel, int64_t, S, 1)                                                                                       \
  X(sample_tet_frame, int32_t, S, 4)                                                                                   \
  X(sample_cell_frame, int32_t, S, 3)                                                                                  \
  X(sample_drilling, uint8_t, S, 1)

void fascia_prep_points_destroy(fascia_prep_points **points) {
  if (!points || !*points) return;
  fascia_prep_points *p = *points;
#define FREE_ARRAY(member, type, count, width) free(p->member);
  POINTS_ARRAYS(FREE_ARRAY)
#undef FREE_ARRAY
  free(p->tissue_mid_layer_frames); // per tissue, made at the start of the sampling
  free(p->tissue_held_layer_volume);
  free(p);
  *points = NULL;
}

// ------------------------------------------------------------ growable point lists

// The arrays of a point list, declared once: member, type, values per point.
#define POINT_LIST_ARRAYS(X)                                                                                           \
  X(position, double, 3)                                                                                               \
  X(organ, int32_t, 1)                                                                                                 \
  X(triangle, int32_t, 1)                                                                                              \
  X(voxel, int64_t, 1)                                                                                                 \
  X(attach, int64_t, 1) /* voxel of a deformable organ's inside the point is shared with, or -1 */                     \
  X(radius, double, 1)  /* its own dart radius, or 0 for the dart grid's */

#define POINT_LIST_MEMBER(name, type, width) type *name;
typedef struct point_list {
  int64_t count, capacity;
  POINT_LIST_ARRAYS(POINT_LIST_MEMBER)
} point_list;
#undef POINT_LIST_MEMBER

static int list_push(point_list *l, const double *x, int32_t organ, int32_t triangle, int64_t voxel) {
  if (l->count == l->capacity) {
    const int64_t cap = l->capacity ? 2 * l->capacity : 1024;
    int grown = 1;
#define POINT_LIST_GROW(name, type, width) grown = grown && prep_resize(&l->name, (width) * cap, sizeof(type));
    POINT_LIST_ARRAYS(POINT_LIST_GROW)
#undef POINT_LIST_GROW
    if (!grown) return 0;
    l->capacity = cap;
  }
  memcpy(l->position + 3 * l->count, x, 3 * sizeof(double));
  l->organ[l->count] = organ;
  l->triangle[l->count] = triangle;
  l->voxel[l->count] = voxel;
  l->attach[l->count] = -1;
  l->radius[l->count] = 0;
  l->count++;
  return 1;
}

static void list_free(point_list *l) {
#define POINT_LIST_FREE(name, ...) free(l->name);
  POINT_LIST_ARRAYS(POINT_LIST_FREE)
#undef POINT_LIST_FREE
  memset(l, 0, sizeof *l);
}

// ------------------------------------------------------------ dart throwing

// Hash grid of accepted points with cell size = radius: a point conflicts
// only with points in the 27 cells around its own. A point may carry a
// smaller radius of its own (point_list.radius); two points conflict when
// they lie closer than the smaller of their radii.
typedef struct dart_grid {
  double radius;
  int64_t table_size;
  int64_t *head; // [table_size] first point in bucket, -1
  int64_t *next; // [capacity]
  int64_t capacity;
  const point_list *points;
} dart_grid;

static uint64_t cell_hash(int64_t x, int64_t y, int64_t z) {
  uint64_t h = (uint64_t)x * 73856093ull ^ (uint64_t)y * 19349663ull ^ (uint64_t)z * 83492791ull;
  return h ^ (h >> 29);
}

static int dart_init(dart_grid *d, double radius, int64_t expected) {
  d->radius = radius;
  d->table_size = 1;
  while (d->table_size < 2 * expected + 64) d->table_size *= 2;
  d->head = malloc((size_t)d->table_size * sizeof(int64_t));
  d->capacity = 0;
  d->next = NULL;
  if (!d->head) return 0;
  for (int64_t k = 0; k < d->table_size; ++k) d->head[k] = -1;
  return 1;
}

static void dart_free(dart_grid *d) {
  free(d->head);
  free(d->next);
  d->head = d->next = NULL;
}

static double point_radius(const point_list *l, int64_t k, double fallback) {
  return l->radius[k] > 0 ? l->radius[k] : fallback;
}

static int dart_conflicts(const dart_grid *d, const double *x, double radius) {
  const int64_t c[3] = {(int64_t)floor(x[0] / d->radius), (int64_t)floor(x[1] / d->radius),
                        (int64_t)floor(x[2] / d->radius)};
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const uint64_t b = cell_hash(c[0] + dx, c[1] + dy, c[2] + dz) & (uint64_t)(d->table_size - 1);
        for (int64_t k = d->head[b]; k >= 0; k = d->next[k]) {
          const double *y = d->points->position + 3 * k;
          const double e0 = x[0] - y[0], e1 = x[1] - y[1], e2 = x[2] - y[2];
          const double r = fmin(radius, point_radius(d->points, k, d->radius));
          if (e0 * e0 + e1 * e1 + e2 * e2 < r * r) return 1;
        }
      }
  return 0;
}

// Registers point index k (already in d->points).
static int dart_add(dart_grid *d, int64_t k) {
  if (k >= d->capacity) {
    const int64_t cap = 2 * (k + 1) + 1024;
    if (!prep_resize(&d->next, cap, sizeof *d->next)) return 0;
    d->capacity = cap;
  }
  const double *x = d->points->position + 3 * k;
  const uint64_t b = cell_hash((int64_t)floor(x[0] / d->radius), (int64_t)floor(x[1] / d->radius),
                               (int64_t)floor(x[2] / d->radius)) &
                     (uint64_t)(d->table_size - 1);
  d->next[k] = d->head[b];
  d->head[b] = k;
  return 1;
}

// ------------------------------------------------------------ frames

// The dart radius of a surface frame on organ o at voxel v: the gap there
// (the distance to o plus the distance to the nearest other organ) where it
// is thinner than the frame spacing, no less than an eighth of it. Frames of
// a thin layer then face each other across it at about its thickness, so the
// layer's samples are held by both faces the way the organs hold it; with
// face frames a spacing apart, the free frames between them could shear the
// layer at a fraction of its energy. Only faces that move as one body (not a
// deformable organ, whose surface frames are its degrees of freedom) get
// them: they cost no unknowns.
static double surface_radius(const fascia_prep_scene *scene, const fascia_prep_volume *vol, int32_t o, int64_t v,
                             double spacing) {
  if (scene->organs[o].kind == FASCIA_ORGAN_DEFORMABLE) return spacing;
  double other = INFINITY;
  for (int32_t p = 0; p < vol->organ_count; ++p)
    if (p != o && vol->distance[p]) other = fmin(other, vol->distance[p][v]);
  const double gap = vol->distance[o][v] + other;
  return fmin(spacing, fmax(gap, spacing / 8));
}

// normal_hit's quarter-voxel steps to each side of the surface (a voxel and a
// half), and the reach of a candidate's hits from its triangle: that along
// the normal with half a voxel along the surface (surface_candidates).
#define HIT_STEPS 6
#define HIT_REACH_VOXELS 2

// The first voxel of mask along the line through p in direction n (unit),
// within one and a half voxels of p on either side, or -1.
static int64_t normal_hit(const prep_grid *g, const uint8_t *mask, const double *p, const double *n, double h) {
  for (int k = 0; k < 2 * HIT_STEPS; ++k) {
    const double along = (k % 2 ? -1 : 1) * (k / 2 + 1) * h / 4;
    const double x[3] = {p[0] + along * n[0], p[1] + along * n[1], p[2] + along * n[2]};
    const int64_t v = prep_grid_locate(g, x);
    if (v >= 0 && mask[v]) return v;
  }
  return -1;
}

// Whether a voxel of mask lies in the box of triangle (a, a + e1, a + e2)
// grown by as far as a candidate's hits reach.
static int box_meets(const prep_grid *g, const uint8_t *mask, const double *a, const double *e1, const double *e2) {
  const double grow = HIT_REACH_VOXELS * g->h;
  int32_t lo[3], hi[3];
  for (int r = 0; r < 3; ++r) {
    const double min = a[r] + fmin(0, fmin(e1[r], e2[r])), max = a[r] + fmax(0, fmax(e1[r], e2[r]));
    lo[r] = (int32_t)fmax(0, floor((min - grow) / g->h + 0.5) - g->lo[r]);
    hi[r] = (int32_t)fmin(g->dims[r] - 1, floor((max + grow) / g->h + 0.5) - g->lo[r]);
  }
  for (int32_t k = lo[2]; k <= hi[2]; ++k)
    for (int32_t j = lo[1]; j <= hi[1]; ++j)
      for (int32_t i = lo[0]; i <= hi[0]; ++i)
        if (mask[prep_grid_index(g, i, j, k)]) return 1;
  return 0;
}

// Surface candidates of a tissue: points of the organs' surfaces, at most a
// twentieth of the frame spacing apart (the centroids of each triangle cut
// into m^2 similar ones), kept where the normal through the point meets,
// within a voxel and a half of it, a region voxel within two voxels of the
// organ, and so do the normals half a voxel to each side along the surface;
// with their dart radii (surface_radius) from
// that voxel. Their density does not follow the voxels: dart throwing keeps
// more frames from denser candidates, so one candidate per voxel gave a
// thin layer's faces fewer frames at coarser voxels.
static fascia_status surface_candidates(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                        const fascia_prep_meshes *meshes, const fascia_prep_volume *vol,
                                        const int64_t *voxels, int64_t voxel_count, double spacing,
                                        point_list *out) {
  const prep_grid g = prep_volume_grid(vol);
  const double h = g.h, step = spacing / 20;
  // the region voxels next to the organ: a normal leaves the organ through
  // its staircase of voxels, whose centres lie up to a voxel's diagonal
  // beyond the surface where it runs askew to the grid
  const double reach = 2 * h;
  uint8_t *near = prep_calloc(prep_grid_count(&g), 1);
  PREP_CHECK(near, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  fascia_status status = FASCIA_OK;
  for (int32_t o = 0; o < vol->organ_count && status == FASCIA_OK; ++o) {
    if (!vol->distance[o]) continue;
    const float *d = vol->distance[o];
    int64_t count = 0;
    for (int64_t k = 0; k < voxel_count; ++k) count += near[voxels[k]] = d[voxels[k]] <= reach;
    if (count == 0) continue;
    const fascia_prep_mesh *m = meshes->organs + o;
    for (int32_t t = 0; t < m->triangle_count && status == FASCIA_OK; ++t) {
      double a[3], e1[3], e2[3];
      for (int r = 0; r < 3; ++r) {
        a[r] = m->vertices[3 * m->triangles[3 * t] + r];
        e1[r] = m->vertices[3 * m->triangles[3 * t + 1] + r] - a[r];
        e2[r] = m->vertices[3 * m->triangles[3 * t + 2] + r] - a[r];
      }
      if (!box_meets(&g, near, a, e1, e2)) continue; // the most of an organ lies far from the tissue
      const double zero[3] = {0, 0, 0};
      const double longest = fmax(fmax(prep_dist3(e1, zero), prep_dist3(e2, zero)), prep_dist3(e1, e2));
      double normal[3];
      prep_cross3(e1, e2, normal);
      const double twice_area = prep_dist3(normal, zero);
      if (!(twice_area > 0)) continue;
      for (int r = 0; r < 3; ++r) normal[r] /= twice_area;
      double tangent[2][3]; // along the triangle, at right angles
      const double l1 = prep_dist3(e1, zero);
      for (int r = 0; r < 3; ++r) tangent[0][r] = e1[r] / l1;
      prep_cross3(normal, tangent[0], tangent[1]);
      const int cuts = (int)fmax(1, ceil(longest / step));
      for (int i = 0; i < cuts && status == FASCIA_OK; ++i)
        for (int j = 0; i + j < cuts && status == FASCIA_OK; ++j)
          for (int flip = 0; flip < 2 && (flip == 0 || i + j + 2 <= cuts) && status == FASCIA_OK; ++flip) {
            const double u = (i + (flip ? 2.0 : 1.0) / 3) / cuts, w = (j + (flip ? 2.0 : 1.0) / 3) / cuts;
            double p[3];
            for (int r = 0; r < 3; ++r) p[r] = a[r] + u * e1[r] + w * e2[r];
            // the first region voxel next to the organ along the normal, on
            // either side (a winding may be either way; the organ's own
            // voxels are no region's); and the same half a voxel to each
            // side along the surface, so that the candidates stop where the
            // region's voxel centres do, not at their voxels' far faces
            const int64_t from = normal_hit(&g, near, p, normal, h);
            int inside = from >= 0;
            for (int side = 0; side < 4 && inside; ++side) {
              double q[3];
              for (int r = 0; r < 3; ++r) q[r] = p[r] + (side % 2 ? -0.5 : 0.5) * h * tangent[side / 2][r];
              inside = normal_hit(&g, near, q, normal, h) >= 0;
            }
            if (!inside) continue;
            if (!list_push(out, p, o, t, from))
              status = PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
            else
              out->radius[out->count - 1] = surface_radius(scene, vol, o, from, spacing);
          }
    }
    for (int64_t k = 0; k < voxel_count; ++k) near[voxels[k]] = 0;
  }
  free(near);
  return status;
}

// The order darts are thrown in, drawn from the seed but not from the voxel
// grid: space is cut into cells of a quarter of the spacing, each cell gets
// a random rank and a random target point, and candidates are visited in the
// order of their cell's rank, within a cell the nearest to its target first.
// Refining the voxels then moves each kept point by less than a voxel
// instead of drawing the frames and samples anew, so a model converges as
// its voxels are refined.
static uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

static uint64_t dart_cell_rank(uint64_t seed, const int64_t *cell) {
  uint64_t h = mix64(seed + 0x9e3779b97f4a7c15ull);
  for (int r = 0; r < 3; ++r) h = mix64(h ^ ((uint64_t)cell[r] + 0x9e3779b97f4a7c15ull * (uint64_t)(r + 1)));
  return h;
}

// The target point of a cell (edge `size`), uniform in it.
static void dart_cell_target(uint64_t rank, const int64_t *cell, double size, double *x) {
  for (int r = 0; r < 3; ++r) {
    const double u = (double)(mix64(rank + (uint64_t)(r + 1)) >> 11) * (1.0 / 9007199254740992.0);
    x[r] = size * ((double)cell[r] + u);
  }
}

static double dart_cell_size(double spacing) { return spacing / 4; }

typedef struct dart_key {
  uint64_t rank;
  double distance2; // to the cell's target
  int64_t index;
} dart_key;

static int by_dart_key(const void *a, const void *b) {
  const dart_key *x = a, *y = b;
  if (x->rank != y->rank) return x->rank < y->rank ? -1 : 1;
  if (x->distance2 != y->distance2) return x->distance2 < y->distance2 ? -1 : 1;
  return (x->index > y->index) - (x->index < y->index);
}

// Keeps candidates, in the seed's order above, when they do not conflict
// with kept points. taken (NULL: no such rule): one kept point per voxel,
// taken[v] set for each voxel v that has one (samples: a voxel goes to one
// sample's cell, and a voxel larger than the spacing could hold two).
static fascia_status throw_darts(fascia_ctx *ctx, uint64_t seed, const point_list *cand, dart_grid *darts,
                                 uint8_t *taken, point_list *kept) {
  dart_key *order = prep_calloc(cand->count, sizeof(dart_key));
  PREP_CHECK(order, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  const double size = dart_cell_size(darts->radius);
  for (int64_t k = 0; k < cand->count; ++k) {
    const double *x = cand->position + 3 * k;
    int64_t cell[3];
    double t[3];
    for (int r = 0; r < 3; ++r) cell[r] = (int64_t)floor(x[r] / size);
    order[k].rank = dart_cell_rank(seed, cell);
    dart_cell_target(order[k].rank, cell, size, t);
    order[k].distance2 = (x[0] - t[0]) * (x[0] - t[0]) + (x[1] - t[1]) * (x[1] - t[1]) + (x[2] - t[2]) * (x[2] - t[2]);
    order[k].index = k;
  }
  qsort(order, (size_t)cand->count, sizeof(dart_key), by_dart_key);
  for (int64_t r = 0; r < cand->count; ++r) {
    const int64_t k = order[r].index;
    const double *x = cand->position + 3 * k;
    const double radius = point_radius(cand, k, darts->radius);
    if ((taken && taken[cand->voxel[k]]) || dart_conflicts(darts, x, radius)) continue;
    if (taken) taken[cand->voxel[k]] = 1;
    if (!list_push(kept, x, cand->organ[k], cand->triangle[k], cand->voxel[k])) {
      free(order);
      return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
    }
    kept->radius[kept->count - 1] = cand->radius[k];
    if (!dart_add(darts, kept->count - 1)) {
      free(order);
      return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
    }
  }
  free(order);
  return FASCIA_OK;
}

// Candidates inside the given voxels that do not depend on the voxel grid:
// the cell targets (above, for darts of this spacing) that fall in them.
// Each target lies in one voxel, so none is listed twice.
static int region_targets(const prep_grid *g, const int64_t *voxels, int64_t voxel_count, uint64_t seed,
                          double spacing, point_list *out) {
  const double size = dart_cell_size(spacing), h = g->h;
  for (int64_t k = 0; k < voxel_count; ++k) {
    double c[3];
    prep_grid_center(g, voxels[k], c);
    int64_t lo[3], hi[3], cell[3];
    for (int r = 0; r < 3; ++r) lo[r] = (int64_t)floor((c[r] - h / 2) / size), hi[r] = (int64_t)floor((c[r] + h / 2) / size);
    for (cell[2] = lo[2]; cell[2] <= hi[2]; ++cell[2])
      for (cell[1] = lo[1]; cell[1] <= hi[1]; ++cell[1])
        for (cell[0] = lo[0]; cell[0] <= hi[0]; ++cell[0]) {
          double x[3];
          dart_cell_target(dart_cell_rank(seed, cell), cell, size, x);
          if (prep_grid_locate(g, x) != voxels[k]) continue;
          if (!list_push(out, x, -1, -1, voxels[k])) return 0;
        }
  }
  return 1;
}

// The distances from voxel v to its nearest organ (*d1) and the next (*d2):
// d1 + d2 is the gap across v. which (may be NULL): those two organs, -1
// where there is none.
static void nearest_organs(const fascia_prep_volume *vol, int64_t v, double *d1, double *d2, int32_t *which) {
  int32_t os[2] = {-1, -1};
  *d1 = *d2 = INFINITY;
  for (int32_t o = 0; o < vol->organ_count; ++o) {
    if (!vol->distance[o]) continue;
    const double d = vol->distance[o][v];
    if (d < *d1) *d2 = *d1, os[1] = os[0], *d1 = d, os[0] = o;
    else if (d < *d2) *d2 = d, os[1] = o;
  }
  if (which) which[0] = os[0], which[1] = os[1];
}

// Mid-layer frames of a tissue (the header): candidates are points of the
// medial layer between the two nearest organs where the gap is thinner
// than the frame spacing (nearer than half of it to both) but at least two
// sample spacings thick, off the surfaces. They do not depend on the voxel
// grid: the cell targets of a quarter of the sample spacing in the region,
// each moved to the midpoint of its closest points on the two organs'
// surfaces, kept where that midpoint lies in the region about as far from
// both (within a quarter of the gap) and no third organ is nearer: a thin
// gap holds few such frames, and voxel centres would gain or lose one as the
// voxels are refined, moving the gap's force with it. There interior frames are
// refused: the surface frames on both sides lie within a spacing of every
// point. A thinner layer is held by its faces alone (surface_radius): a free
// frame there would reach only the samples within about a gap of it, too
// few to hold its six degrees of freedom (its lumped mass singular, the
// layer sheared at a fraction of its energy). Mid-layer frames are thrown
// with the frame spacing against the frames from index `first` on (the
// interior ones) only.
static fascia_status mid_layer_frames(fascia_ctx *ctx, const fascia_prep_meshes *meshes, const fascia_prep_volume *vol,
                                      uint8_t label, const int64_t *voxels, int64_t voxel_count, double spacing,
                                      double sample_spacing, uint64_t seed, fascia_cgal_tree **trees, int64_t first,
                                      point_list *frames) {
  const prep_grid g = prep_volume_grid(vol);
  const double h = g.h;
  point_list targets = {0}, cand = {0};
  dart_grid darts = {0};
  fascia_status status = FASCIA_OK;
  double *mid = NULL; // per target: its midpoint, or NAN where it gives no candidate
  int64_t *mid_voxel = NULL;
  PREP_CHECK_GOTO(region_targets(&g, voxels, voxel_count, seed ^ 0x5bd1e995ull, sample_spacing, &targets), ctx,
                  FASCIA_ERR_MEMORY, "sample: out of memory");
  for (int32_t o = 0; o < vol->organ_count; ++o)
    if (vol->distance[o] && !trees[o]) {
      const fascia_prep_mesh *mesh = meshes->organs + o;
      PREP_TRY_GOTO(fascia_cgal_tree_create(ctx, mesh->vertex_count, mesh->vertices, mesh->triangle_count,
                                            mesh->triangles, trees + o));
    }
  mid = prep_calloc(3 * targets.count, sizeof(double));
  mid_voxel = prep_calloc(targets.count, sizeof(int64_t));
  PREP_CHECK_GOTO(mid && mid_voxel, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  // the gap through a target bounds twice its midpoint's distances: targets
  // whose voxel (within a voxel's diagonal of them) says the test below
  // cannot pass are left out before the closest-point queries; in a wedge
  // a midpoint is nearer than half the gap, so wider gaps are kept up to
  // twice the spacing
  const double thinnest = 2 * fmax(sample_spacing, h) - sqrt(3.0) * h, widest = 2 * spacing;
#pragma omp parallel for schedule(dynamic, 256) num_threads(fascia_ctx_threads(ctx))
  for (int64_t k = 0; k < targets.count; ++k) {
    const double *x = targets.position + 3 * k;
    const int64_t v = targets.voxel[k];
    mid[3 * k] = NAN;
    int32_t os[2];
    double d1, d2;
    nearest_organs(vol, v, &d1, &d2, os);
    if (os[1] < 0 || d1 + d2 < thinnest || d1 + d2 >= widest) continue;
    double c[2][3], m[3], e[2];
    for (int j = 0; j < 2; ++j) {
      int32_t tri;
      fascia_cgal_tree_closest(trees[os[j]], 1, x, c[j], &tri);
    }
    for (int r = 0; r < 3; ++r) m[r] = 0.5 * (c[0][r] + c[1][r]);
    // the midpoint is no farther than half the chord from either organ, and
    // must lie in the region: both known before its own queries
    const int64_t w = prep_grid_locate(&g, m);
    if (prep_dist3(c[0], c[1]) < 2 * fmax(sample_spacing, h) || w < 0 || vol->region[w] != label) continue;
    for (int j = 0; j < 2; ++j) {
      double q[3];
      int32_t tri;
      fascia_cgal_tree_closest(trees[os[j]], 1, m, q, &tri);
      e[j] = prep_dist3(m, q);
    }
    // (a voxel off the surfaces at least: nearer, a frame beside a surface frame made the wedges where organs
    // meet stiff and strained)
    const double near = fmin(e[0], e[1]);
    if (fabs(e[0] - e[1]) > 0.25 * (e[0] + e[1]) || near < sample_spacing || near < h || near >= 0.5 * spacing) continue;
    int other = 0; // no third organ nearer than these two
    for (int32_t o = 0; o < vol->organ_count && !other; ++o)
      if (o != os[0] && o != os[1] && vol->distance[o] && vol->distance[o][w] < near - h) other = 1;
    if (other) continue;
    for (int r = 0; r < 3; ++r) mid[3 * k + r] = m[r];
    mid_voxel[k] = w;
  }
  for (int64_t k = 0; k < targets.count; ++k)
    if (!isnan(mid[3 * k]))
      PREP_CHECK_GOTO(list_push(&cand, mid + 3 * k, -1, -1, mid_voxel[k]), ctx, FASCIA_ERR_MEMORY,
                      "sample: out of memory");
  if (cand.count == 0) goto cleanup;
  PREP_CHECK_GOTO(dart_init(&darts, spacing, frames->count - first + cand.count), ctx, FASCIA_ERR_MEMORY,
                  "sample: out of memory");
  darts.points = frames;
  for (int64_t k = first; k < frames->count; ++k)
    PREP_CHECK_GOTO(dart_add(&darts, k), ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  PREP_TRY_GOTO(throw_darts(ctx, seed, &cand, &darts, NULL, frames));
cleanup:
  free(mid);
  free(mid_voxel);
  list_free(&targets);
  list_free(&cand);
  dart_free(&darts);
  return status;
}

// 26-connected pieces of tissue label; comp[v] = piece index + 1 on the grid.
static int64_t label_pieces(const prep_grid *g, const uint8_t *region, uint8_t label, int32_t *comp, int64_t *queue) {
  const int64_t n = prep_grid_count(g);
  int32_t count = 0;
  for (int64_t s = 0; s < n; ++s) {
    if (region[s] != label || comp[s]) continue;
    ++count;
    int64_t head = 0, tail = 0;
    queue[tail++] = s;
    comp[s] = count;
    while (head < tail) {
      int64_t nb[26];
      const int m = prep_grid_neighbours(g, queue[head++], nb, NULL);
      for (int k = 0; k < m; ++k)
        if (region[nb[k]] == label && !comp[nb[k]]) comp[nb[k]] = count, queue[tail++] = nb[k];
    }
  }
  return count;
}

// Smallest eigenvalue proxy of the frames' spread: det of the covariance,
// relative to the spacing; 0 for coplanar sets.
static double spread(const double *const *x, int32_t n, double spacing) {
  if (n < 4) return 0;
  double mean[3] = {0, 0, 0}, c[9] = {0};
  for (int32_t k = 0; k < n; ++k)
    for (int r = 0; r < 3; ++r) mean[r] += x[k][r] / n;
  for (int32_t k = 0; k < n; ++k)
    for (int r = 0; r < 3; ++r)
      for (int s = 0; s < 3; ++s) c[3 * r + s] += (x[k][r] - mean[r]) * (x[k][s] - mean[s]) / n;
  const double det = c[0] * (c[4] * c[8] - c[5] * c[7]) - c[1] * (c[3] * c[8] - c[5] * c[6]) +
                     c[2] * (c[3] * c[7] - c[4] * c[6]);
  const double s2 = spacing * spacing;
  return det / (s2 * s2 * s2);
}

// The voxel through which frame k belongs to the region with this label: its
// own voxel, or the organ voxel it is shared with; -1 if neither is labelled.
static int64_t frame_voxel_in(const fascia_prep_volume *vol, const point_list *frames, int64_t k, uint8_t label) {
  if (frames->voxel[k] >= 0 && vol->region[frames->voxel[k]] == label) return frames->voxel[k]; // -1: a strand's, a sheet's
  if (frames->attach[k] >= 0 && vol->region[frames->attach[k]] == label) return frames->attach[k];
  return -1;
}

// Adds frames to pieces of the region with fewer than 4 frames or coplanar
// ones; the frames of a piece are those whose voxel (or shared voxel) is in it.
static fascia_status fill_thin_pieces(fascia_ctx *ctx, const fascia_prep_volume *vol, uint8_t label,
                                      double spacing, point_list *frames) {
  const prep_grid g = prep_volume_grid(vol);
  const int64_t n = prep_grid_count(&g);
  fascia_status status = FASCIA_OK;
  int32_t *comp = prep_calloc(n, sizeof(int32_t));
  int64_t *queue = prep_calloc(n, sizeof(int64_t));
  const double **members = NULL;
  PREP_CHECK_GOTO(comp && queue, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  const int64_t pieces = label_pieces(&g, vol->region, label, comp, queue);
  for (int32_t piece = 1; piece <= pieces; ++piece) {
    for (int guard = 0; guard < 64; ++guard) {
      int32_t count = 0;
      free(members);
      members = prep_calloc(frames->count + 64, sizeof(double *));
      PREP_CHECK_GOTO(members, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
      for (int64_t i = 0; i < frames->count; ++i) {
        const int64_t v = frame_voxel_in(vol, frames, i, label);
        if (v >= 0 && comp[v] == piece) members[count++] = frames->position + 3 * i;
      }
      if (count >= 4 && spread(members, count, spacing) > 1e-6) break;
      // the piece's voxel farthest from its frames becomes a frame
      double best = -1, x[3], far[3] = {0, 0, 0};
      int64_t best_v = -1;
      for (int64_t v = 0; v < n; ++v) {
        if (comp[v] != piece) continue;
        prep_grid_center(&g, v, x);
        double dmin = INFINITY;
        for (int32_t k = 0; k < count; ++k) {
          const double e0 = x[0] - members[k][0], e1 = x[1] - members[k][1], e2 = x[2] - members[k][2];
          dmin = fmin(dmin, e0 * e0 + e1 * e1 + e2 * e2);
        }
        if (dmin > best) best = dmin, best_v = v, memcpy(far, x, sizeof far);
      }
      if (best_v < 0 || best <= 0) break; // a piece of fewer than 4 voxels: left to the shape functions to report
      PREP_CHECK_GOTO(list_push(frames, far, -1, -1, best_v), ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
    }
  }
cleanup:
  free(comp);
  free(queue);
  free(members);
  return status;
}

// ------------------------------------------------------------ samples and volumes

static int by_voxel_then_index(const void *a, const void *b) {
  const int64_t *x = a, *y = b;
  if (x[0] != y[0]) return x[0] < y[0] ? -1 : 1;
  return (x[1] > y[1]) - (x[1] < y[1]);
}

// The first of the (voxel, sample) pairs sorted by voxel whose voxel is v,
// or count where none is.
static int64_t first_in_voxel(const int64_t *pairs, int64_t count, int64_t v) {
  int64_t lo = 0, hi = count;
  while (lo < hi) {
    const int64_t mid = lo + (hi - lo) / 2;
    if (pairs[2 * mid] < v) lo = mid + 1;
    else hi = mid;
  }
  return lo < count && pairs[2 * lo] == v ? lo : count;
}

// Samples finer than the voxels: each region voxel is split into k^3
// sub-cells, each going to the nearest sample among those in the voxel,
// in its region neighbours, and the voxel's owner through the region. A
// sample is nearer its own sub-cell's centre than any other (they are a
// spacing apart, the sub-cells under half a spacing), so each keeps a
// volume. Adds to volume (m^3) and centroid (points weighted by their
// share of a voxel).
static fascia_status sub_voxel_cells(fascia_ctx *ctx, const fascia_prep_volume *vol, uint8_t label,
                                     const point_list *samples, int64_t first, const int64_t *owner, int k,
                                     double *volume, double *centroid) {
  const prep_grid g = prep_volume_grid(vol);
  const int64_t n = prep_grid_count(&g), count = samples->count - first;
  int64_t *pairs = malloc(2 * (size_t)count * sizeof(int64_t) + 1);
  PREP_CHECK(pairs, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  for (int64_t s = 0; s < count; ++s) pairs[2 * s] = samples->voxel[first + s], pairs[2 * s + 1] = first + s;
  qsort(pairs, (size_t)count, 2 * sizeof(int64_t), by_voxel_then_index);
  int64_t most = 1; // samples in one voxel
  for (int64_t r = 0, run = 0; r < count; ++r) {
    run = r > 0 && pairs[2 * r] == pairs[2 * r - 2] ? run + 1 : 1;
    if (run > most) most = run;
  }
  int64_t *near = malloc((27 * (size_t)most + 1) * sizeof(int64_t));
  if (!near) {
    free(pairs);
    return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  }
  const double h = g.h, sub = h / k, cell_volume = sub * sub * sub, share = 1.0 / ((double)k * k * k);
  for (int64_t u = 0; u < n; ++u) {
    if (vol->region[u] != label) continue;
    int64_t nb[27];
    int64_t near_count = 0;
    int d2[26];
    near[near_count++] = owner[u];
    const int m = prep_grid_neighbours(&g, u, nb, d2);
    nb[m] = u;
    for (int j = 0; j <= m; ++j) {
      if (vol->region[nb[j]] != label) continue;
      for (int64_t r = first_in_voxel(pairs, count, nb[j]); r < count && pairs[2 * r] == nb[j]; ++r)
        near[near_count++] = pairs[2 * r + 1];
    }
    double c[3];
    prep_grid_center(&g, u, c);
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b)
        for (int e = 0; e < k; ++e) {
          const double x[3] = {c[0] - h / 2 + (a + 0.5) * sub, c[1] - h / 2 + (b + 0.5) * sub,
                               c[2] - h / 2 + (e + 0.5) * sub};
          int64_t best = owner[u];
          double best_d2 = INFINITY;
          for (int64_t j = 0; j < near_count; ++j) {
            const double *p = samples->position + 3 * near[j];
            const double dd = (x[0] - p[0]) * (x[0] - p[0]) + (x[1] - p[1]) * (x[1] - p[1]) + (x[2] - p[2]) * (x[2] - p[2]);
            if (dd < best_d2 || (dd == best_d2 && near[j] < best)) best_d2 = dd, best = near[j];
          }
          volume[best - first] += cell_volume;
          for (int r = 0; r < 3; ++r) centroid[3 * (best - first) + r] += share * x[r];
        }
  }
  free(near);
  free(pairs);
  return FASCIA_OK;
}

// Assigns every region voxel of label to its nearest sample through the
// region; volumes and centroids per sample. A piece of region that got no
// sample (its candidates all conflicted with samples across a thin organ)
// gets one at its first voxel. Where the samples are finer than the voxels
// (spacing below the voxel size), the voxels are split (sub_voxel_cells):
// the sample spacing is not floored by the voxel size.
// *volume_out: [samples->count - first], malloc'ed.
static fascia_status voronoi_volumes(fascia_ctx *ctx, const fascia_prep_volume *vol, uint8_t label, double spacing,
                                     point_list *samples, int64_t first, double **volume_out) {
  const prep_grid g = prep_volume_grid(vol);
  const int64_t n = prep_grid_count(&g);
  const double h = g.h;
  double *dist = malloc((size_t)n * sizeof(double));
  int64_t *owner = malloc((size_t)n * sizeof(int64_t));
  double *centroid = NULL, *volume = NULL;
  prep_heap heap = {0};
  fascia_status status = FASCIA_OK;
  *volume_out = NULL;
  PREP_CHECK_GOTO(dist && owner, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  for (int64_t v = 0; v < n; ++v) dist[v] = INFINITY, owner[v] = -1;
  for (int64_t s = first; s < samples->count; ++s) {
    const int64_t v = samples->voxel[s];
    dist[v] = 0;
    owner[v] = s;
    PREP_CHECK_GOTO(prep_heap_push(&heap, 0, v), ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  }
  double key;
  int64_t v, unreached = 0;
  for (;;) {
    if (!prep_heap_pop(&heap, &key, &v)) {
      // every voxel reached, or a piece without a sample: seed it and go on
      while (unreached < n && (vol->region[unreached] != label || owner[unreached] >= 0)) ++unreached;
      if (unreached == n) break;
      double x[3];
      prep_grid_center(&g, unreached, x);
      PREP_CHECK_GOTO(list_push(samples, x, -1, -1, unreached), ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
      dist[unreached] = 0;
      owner[unreached] = samples->count - 1;
      PREP_CHECK_GOTO(prep_heap_push(&heap, 0, unreached), ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
      continue;
    }
    if (key > dist[v]) continue;
    int64_t nb[26];
    int d2[26];
    const int m = prep_grid_neighbours(&g, v, nb, d2);
    for (int k = 0; k < m; ++k) {
      if (vol->region[nb[k]] != label) continue;
      const double step = h * sqrt((double)d2[k]);
      if (key + step < dist[nb[k]]) {
        dist[nb[k]] = key + step;
        owner[nb[k]] = owner[v];
        PREP_CHECK_GOTO(prep_heap_push(&heap, key + step, nb[k]), ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
      }
    }
  }
  centroid = prep_calloc(3 * (samples->count - first), sizeof(double));
  volume = prep_calloc(samples->count - first, sizeof(double));
  PREP_CHECK_GOTO(centroid && volume, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  for (int64_t u = 0; u < n; ++u) {
    if (vol->region[u] != label) continue;
    PREP_CHECK_GOTO(owner[u] >= 0, ctx, FASCIA_ERR_INTERNAL, "sample: region voxel %lld reached by no sample",
                    (long long)u);
    if (spacing < h) continue; // split below
    const int64_t s = owner[u] - first;
    double x[3];
    prep_grid_center(&g, u, x);
    volume[s] += h * h * h;
    for (int r = 0; r < 3; ++r) centroid[3 * s + r] += x[r];
  }
  if (spacing < h) { // sub-cells under half a spacing
    const int k = (int)ceil(2 * h / spacing);
    PREP_TRY_GOTO(sub_voxel_cells(ctx, vol, label, samples, first, owner, k < 16 ? k : 16, volume, centroid));
  }
  for (int64_t s = 0; s < samples->count - first; ++s) {
    double c[3];
    for (int r = 0; r < 3; ++r) c[r] = centroid[3 * s + r] / (volume[s] / (h * h * h));
    const int64_t cv = prep_grid_locate(&g, c);
    if (cv >= 0 && vol->region[cv] == label) {
      memcpy(samples->position + 3 * (first + s), c, sizeof c);
      samples->voxel[first + s] = cv;
    }
  }
  *volume_out = volume;
  volume = NULL;
cleanup:
  free(dist);
  free(owner);
  free(centroid);
  free(volume);
  prep_heap_free(&heap);
  return status;
}

// ------------------------------------------------------------ per-sample data

// What a region adds per sample besides its point: volume[s] (m^3) and
// tet_frame[4s..4s+3] (its tet's frames ascending, -1 for MLS samples).
// cell_frame[3s..3s+2]: a strand's or sheet's sample's interval or triangle
// (-1 for the others: what a new entry holds).
typedef struct sample_data {
  int64_t capacity;
  double *volume;
  int32_t *tet_frame;
  int32_t *cell_frame;
  uint8_t *drilling; // a sheet's drilling stabiliser (0 for what a new entry holds)
} sample_data;

static int data_reserve(sample_data *d, int64_t count) {
  if (count <= d->capacity) return 1;
  const int64_t cap = count > 2 * d->capacity ? count : 2 * d->capacity;
  double *v = realloc(d->volume, (size_t)cap * sizeof(double));
  if (!v) return 0;
  d->volume = v;
  int32_t *t = realloc(d->tet_frame, (size_t)(4 * cap) * sizeof(int32_t));
  if (!t) return 0;
  d->tet_frame = t;
  int32_t *c = realloc(d->cell_frame, (size_t)(3 * cap) * sizeof(int32_t));
  if (!c) return 0;
  d->cell_frame = c;
  for (int64_t k = 3 * d->capacity; k < 3 * cap; ++k) c[k] = -1;
  uint8_t *g = realloc(d->drilling, (size_t)cap);
  if (!g) return 0;
  d->drilling = g;
  memset(g + d->capacity, 0, (size_t)(cap - d->capacity));
  d->capacity = cap;
  return 1;
}

// Appends a strand's, a sheet's or a shell's frames and samples (no voxel).
// A sample's interval or triangle is given in r's own frames (cell_offset:
// the index its first frame gets here) or in the scene's (cell_offset -1).
static fascia_status append_reduced(fascia_ctx *ctx, const prep_reduced *r, int64_t cell_offset, point_list *frames,
                                    point_list *samples, sample_data *data) {
  const int64_t first_sample = samples->count;
  for (int32_t i = 0; i < r->frame_count; ++i)
    PREP_CHECK(list_push(frames, r->frame_position + 3 * (int64_t)i, r->frame_organ[i], r->frame_triangle[i], -1),
               ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  for (int32_t s = 0; s < r->sample_count; ++s)
    PREP_CHECK(list_push(samples, r->sample_position + 3 * (int64_t)s, -1, -1, -1), ctx, FASCIA_ERR_MEMORY,
               "sample: out of memory");
  PREP_CHECK(data_reserve(data, samples->count), ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  for (int32_t s = 0; s < r->sample_count; ++s) {
    const int64_t k = first_sample + s;
    data->volume[k] = r->sample_volume[s];
    for (int j = 0; j < 4; ++j) data->tet_frame[4 * k + j] = -1;
    for (int j = 0; j < 3; ++j) {
      const int32_t c = r->sample_cell[3 * (int64_t)s + j];
      data->cell_frame[3 * k + j] = cell_offset < 0 ? c : c < 0 ? -1 : (int32_t)(cell_offset + c);
    }
    data->drilling[k] = r->sample_drilling ? r->sample_drilling[s] : 0;
  }
  return FASCIA_OK;
}

// A strand or a sheet (reduced.c): its frames and samples appended; each
// sample keeps its interval's or triangle's frames.
static fascia_status sample_reduced(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                    const fascia_prep_meshes *meshes, const fascia_prep_volume *vol, int32_t t,
                                    fascia_cgal_tree **trees, point_list *frames, point_list *samples,
                                    sample_data *data) {
  prep_reduced r;
  PREP_TRY(prep_reduced_build(ctx, scene, meshes, vol, t, trees, &r));
  const fascia_status status = append_reduced(ctx, &r, frames->count, frames, samples, data);
  prep_reduced_free(&r);
  return status;
}

// A shell organ's wall (shell.c): its own frames and samples appended; its
// samples' triangles are frame indices of the whole scene already.
static fascia_status sample_shell(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                  int32_t o, int64_t tissue_frames, const int32_t *tissue_of,
                                  fascia_cgal_tree **trees, point_list *frames, point_list *samples,
                                  sample_data *data) {
  const prep_shell_frames seen = {frames->count, frames->position, frames->organ, frames->triangle, tissue_frames,
                                  tissue_of};
  prep_reduced r;
  PREP_TRY(prep_shell_build(ctx, scene, meshes, o, &seen, trees, &r));
  const fascia_status status = append_reduced(ctx, &r, -1, frames, samples, data);
  prep_reduced_free(&r);
  return status;
}

// ------------------------------------------------------------ TET samples

typedef struct tet {
  int32_t v[4];  // frame indices, ascending
  double volume; // m^3
  double q[12];  // quadrature points, m
} tet;

static int by_frame_index(const void *a, const void *b) {
  const int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
  return (x > y) - (x < y);
}

static int by_vertices(const void *a, const void *b) {
  const int32_t *x = ((const tet *)a)->v, *y = ((const tet *)b)->v;
  for (int r = 0; r < 4; ++r)
    if (x[r] != y[r]) return (x[r] > y[r]) - (x[r] < y[r]);
  return 0;
}

static int in_label(const prep_grid *g, const fascia_prep_volume *vol, uint8_t label, const double *x) {
  const int64_t v = prep_grid_locate(g, x);
  return v >= 0 && vol->region[v] == label;
}

// Volume of tet t if it is kept for the region with this label, else 0: not
// flat (6 V above 1e-9 longest edge^3, far above fascia_shape_tet's limit),
// and its centroid, edge midpoints and the `rule` quadrature points (bary
// [4 rule]; into q [3 rule]) in the region.
static double kept_volume(const prep_grid *g, const fascia_prep_volume *vol, uint8_t label, const double *const *x,
                          int rule, const double *bary, double *q) {
  double e[3][3], longest = 0;
  for (int j = 0; j < 3; ++j)
    for (int r = 0; r < 3; ++r) e[j][r] = x[j + 1][r] - x[0][r];
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) {
      const double d0 = x[a][0] - x[b][0], d1 = x[a][1] - x[b][1], d2 = x[a][2] - x[b][2];
      longest = fmax(longest, sqrt(d0 * d0 + d1 * d1 + d2 * d2));
    }
  const double det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                     e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                     e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
  if (!(fabs(det) > 1e-9 * longest * longest * longest)) return 0;
  double c[3] = {0, 0, 0};
  for (int r = 0; r < 4; ++r)
    for (int a = 0; a < 3; ++a) c[a] += x[r][a] / 4;
  if (!in_label(g, vol, label, c)) return 0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) {
      const double m[3] = {(x[a][0] + x[b][0]) / 2, (x[a][1] + x[b][1]) / 2, (x[a][2] + x[b][2]) / 2};
      if (!in_label(g, vol, label, m)) return 0;
    }
  for (int k = 0; k < rule; ++k) {
    for (int a = 0; a < 3; ++a) {
      q[3 * k + a] = 0;
      for (int r = 0; r < 4; ++r) q[3 * k + a] += bary[4 * k + r] * x[r][a];
    }
    if (!in_label(g, vol, label, q + 3 * k)) return 0;
  }
  return fabs(det) / 6;
}

// Samples of a TET region: the quadrature points of the kept tetrahedra of a
// Delaunay tetrahedralisation of the region's frames (those whose voxel, or
// shared voxel, has the label), kept tets in ascending order of their frames
// (deterministic whatever CGAL's cell order). Errors: fewer than 4 frames,
// no kept tet.
static fascia_status tet_samples(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_volume *vol,
                                 uint8_t label, int rule, const point_list *frames, point_list *samples,
                                 sample_data *data) {
  const prep_grid g = prep_volume_grid(vol);
  fascia_status status = FASCIA_OK;
  char name[FASCIA_NAME_SIZE + 32];
  prep_label_name(scene, vol, label, name, sizeof name);
  int32_t *list = prep_calloc(frames->count, sizeof(int32_t)), *cells = NULL, cell_count = 0, count = 0;
  double *position = NULL;
  tet *kept = NULL;
  PREP_CHECK_GOTO(list, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  for (int64_t k = 0; k < frames->count; ++k)
    if (frame_voxel_in(vol, frames, k, label) >= 0) list[count++] = (int32_t)k;
  PREP_CHECK_GOTO(count >= 4, ctx, FASCIA_ERR_NUMERIC,
                  "%s: %d frames, no tetrahedral mesh (shape_functions.kind \"tet\" needs 4 or more); lower "
                  "frame_spacing or use kind \"mls\"",
                  name, (int)count);
  position = prep_calloc(3 * (int64_t)count, sizeof(double));
  PREP_CHECK_GOTO(position, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  for (int32_t k = 0; k < count; ++k) memcpy(position + 3 * k, frames->position + 3 * (int64_t)list[k], 3 * sizeof(double));
  PREP_TRY_GOTO(fascia_cgal_delaunay(ctx, count, position, &cells, &cell_count));
  double bary[16], weight[4];
  PREP_TRY_GOTO(fascia_shape_tet_quadrature(ctx, rule, bary, weight));
  kept = prep_calloc(cell_count, sizeof(tet));
  PREP_CHECK_GOTO(kept, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  int32_t kept_count = 0;
  for (int32_t k = 0; k < cell_count; ++k) {
    tet *t = kept + kept_count;
    for (int r = 0; r < 4; ++r) t->v[r] = list[cells[4 * k + r]];
    qsort(t->v, 4, sizeof(int32_t), by_frame_index); // vertex order, hence points, independent of CGAL's
    const double *x[4];
    for (int r = 0; r < 4; ++r) x[r] = frames->position + 3 * (int64_t)t->v[r];
    t->volume = kept_volume(&g, vol, label, x, rule, bary, t->q);
    kept_count += t->volume > 0;
  }
  PREP_CHECK_GOTO(kept_count > 0, ctx, FASCIA_ERR_NUMERIC,
                  "%s: none of the %d tetrahedra of its %d frames lies inside its region; use "
                  "shape_functions.kind \"mls\" or a smaller frame_spacing",
                  name, (int)cell_count, (int)count);
  qsort(kept, (size_t)kept_count, sizeof(tet), by_vertices);
  PREP_CHECK_GOTO(data_reserve(data, samples->count + (int64_t)rule * kept_count), ctx, FASCIA_ERR_MEMORY,
                  "sample: out of memory");
  for (int32_t k = 0; k < kept_count; ++k) {
    for (int j = 0; j < rule; ++j) {
      const int64_t s = samples->count;
      const double *q = kept[k].q + 3 * j;
      PREP_CHECK_GOTO(list_push(samples, q, -1, -1, prep_grid_locate(&g, q)), ctx, FASCIA_ERR_MEMORY,
                      "sample: out of memory");
      data->volume[s] = weight[j] * kept[k].volume;
      memcpy(data->tet_frame + 4 * s, kept[k].v, 4 * sizeof(int32_t));
    }
  }
cleanup:
  free(list);
  free(position);
  free(cells);
  free(kept);
  return status;
}

// ------------------------------------------------------------ the stage

// Shares with deformable organ o the tissue frames on its surface that their
// tissue's coupling rules allow: each is attached to the organ's inside voxel
// nearest to it within two voxels (ties to the lower voxel index). A frame
// with no inside voxel that near (a sliver of the organ thinner than a voxel)
// stays a tissue frame only. frame_tissue[k]: tissue of frame k.
static void attach_shared(const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                          const fascia_prep_volume *vol, int32_t o, const int32_t *frame_tissue, point_list *frames) {
  const prep_grid g = prep_volume_grid(vol);
  const uint8_t label = (uint8_t)vol->organ_label[o];
  for (int64_t k = 0; k < frames->count; ++k) {
    if (frames->organ[k] != o || frame_tissue[k] < 0) continue;
    const double *x = frames->position + 3 * k;
    if (!prep_coupling_allowed(scene->tissues + frame_tissue[k], o, meshes->organs + o, frames->triangle[k], x))
      continue;
    int32_t c[3];
    for (int r = 0; r < 3; ++r) c[r] = (int32_t)floor(x[r] / g.h + 0.5) - g.lo[r];
    double best = INFINITY;
    int64_t best_v = -1;
    for (int dz = -2; dz <= 2; ++dz)
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
          const int32_t i = c[0] + dx, j = c[1] + dy, l = c[2] + dz;
          if (i < 0 || j < 0 || l < 0 || i >= g.dims[0] || j >= g.dims[1] || l >= g.dims[2]) continue;
          const int64_t v = prep_grid_index(&g, i, j, l);
          if (vol->region[v] != label) continue;
          double y[3];
          prep_grid_center(&g, v, y);
          const double d2 = (x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) + (x[2] - y[2]) * (x[2] - y[2]);
          if (d2 < best || (d2 == best && v < best_v)) best = d2, best_v = v;
        }
    frames->attach[k] = best_v;
  }
}

// Frames and samples of the region with this label: a tissue (surface frames
// on the organs it touches, then interior frames farther than the coupling
// tolerance from every organ) or a deformable organ's inside (its shared
// frames, already attached, then interior frames anywhere inside); then
// samples and their volumes, the same for both: Poisson-disk samples with
// Voronoi volumes (MLS), or the quadrature points of the kept tets (TET).
// *mid_layer (may be NULL): how many of its frames are mid-layer frames.
static fascia_status sample_region(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                   const fascia_prep_meshes *meshes, const fascia_prep_volume *vol, uint8_t label,
                                   fascia_cgal_tree **trees, point_list *frames, point_list *samples,
                                   sample_data *data, int32_t *mid_layer, double *held_volume) {
  const int32_t organ = prep_label_organ(vol, label);
  const fascia_prep_tissue_def *td = organ < 0 ? scene->tissues + (label - 1) : NULL;
  double frame_spacing, sample_spacing;
  int32_t shape_kind;
  prep_label_sampling(scene, vol, label, &frame_spacing, &sample_spacing, &shape_kind, NULL);
  const prep_grid g = prep_volume_grid(vol);
  const int64_t n = prep_grid_count(&g);
  const double h = g.h;
  fascia_status status = FASCIA_OK;
  point_list cand = {0};
  dart_grid darts = {0};
  double *cell_volume = NULL;
  uint8_t *taken = NULL;
  // one seed per region and kind of point, so each kind is drawn apart
  const uint64_t seed = (uint64_t)scene->seed * 0x9e3779b97f4a7c15ull + (uint64_t)label * 4;
  int64_t voxel_count = 0, far_count = 0;
  for (int64_t v = 0; v < n; ++v) voxel_count += vol->region[v] == label;
  int64_t *voxels = prep_calloc(voxel_count, sizeof(int64_t)), *far = prep_calloc(voxel_count, sizeof(int64_t));
  PREP_CHECK_GOTO(voxels && far, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  voxel_count = 0;
  for (int64_t v = 0; v < n; ++v)
    if (vol->region[v] == label) voxels[voxel_count++] = v;

  // frames: surface (tissue) or shared (organ) first, then interior, one dart grid
  PREP_CHECK_GOTO(dart_init(&darts, frame_spacing, voxel_count), ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  darts.points = frames;
  if (td) {
    PREP_TRY_GOTO(surface_candidates(ctx, scene, meshes, vol, voxels, voxel_count, frame_spacing, &cand));
    PREP_TRY_GOTO(throw_darts(ctx, seed, &cand, &darts, NULL, frames));
  } else {
    for (int64_t k = 0; k < frames->count; ++k)
      if (frames->attach[k] >= 0 && vol->region[frames->attach[k]] == label)
        PREP_CHECK_GOTO(dart_add(&darts, k), ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  }
  // interior frames in the voxels farther than the coupling tolerance (plus
  // a voxel, for a target off its voxel's centre) from every organ
  for (int64_t k = 0; k < voxel_count; ++k) {
    double nearest = INFINITY;
    for (int32_t o = 0; td && o < vol->organ_count; ++o)
      if (vol->distance[o]) nearest = fmin(nearest, vol->distance[o][voxels[k]]);
    if (!td || nearest > td->coupling_tolerance + h) far[far_count++] = voxels[k];
  }
  cand.count = 0;
  const int64_t first_interior = frames->count;
  PREP_CHECK_GOTO(region_targets(&g, far, far_count, seed + 1, frame_spacing, &cand), ctx, FASCIA_ERR_MEMORY,
                  "sample: out of memory");
  PREP_TRY_GOTO(throw_darts(ctx, seed + 1, &cand, &darts, NULL, frames));
  const int64_t before_mid_layer = frames->count;
  if (td)
    PREP_TRY_GOTO(mid_layer_frames(ctx, meshes, vol, label, voxels, voxel_count, frame_spacing, sample_spacing,
                                   seed + 2, trees, first_interior, frames));
  for (int64_t k = 0; td && held_volume && k < voxel_count; ++k) { // the layers no mid-layer frame may enter
    double d1, d2;
    nearest_organs(vol, voxels[k], &d1, &d2, NULL);
    if (d1 + d2 < 2 * sample_spacing) *held_volume += h * h * h;
  }
  if (mid_layer) *mid_layer = (int32_t)(frames->count - before_mid_layer);
  PREP_TRY_GOTO(fill_thin_pieces(ctx, vol, label, frame_spacing, frames));
  dart_free(&darts);
  if (shape_kind == FASCIA_PREP_SHAPE_TET) {
    const int rule = td ? td->samples_per_tet : scene->organs[organ].samples_per_tet;
    PREP_TRY_GOTO(tet_samples(ctx, scene, vol, label, rule, frames, samples, data));
    goto cleanup;
  }

  // samples at the cell targets in the region, then Voronoi volumes
  const int64_t first_sample = samples->count;
  cand.count = 0;
  PREP_CHECK_GOTO(region_targets(&g, voxels, voxel_count, seed + 3, sample_spacing, &cand), ctx, FASCIA_ERR_MEMORY,
                  "sample: out of memory");
  PREP_CHECK_GOTO(dart_init(&darts, sample_spacing, cand.count), ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  darts.points = samples;
  if (sample_spacing >= h) { // one sample per voxel; finer samples split the voxels (voronoi_volumes)
    taken = prep_calloc(n, 1);
    PREP_CHECK_GOTO(taken, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  }
  PREP_TRY_GOTO(throw_darts(ctx, seed + 3, &cand, &darts, taken, samples));
  PREP_TRY_GOTO(voronoi_volumes(ctx, vol, label, sample_spacing, samples, first_sample, &cell_volume));
  PREP_CHECK_GOTO(data_reserve(data, samples->count), ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  memcpy(data->volume + first_sample, cell_volume, (size_t)(samples->count - first_sample) * sizeof(double));
  for (int64_t s = 4 * first_sample; s < 4 * samples->count; ++s) data->tet_frame[s] = -1;
cleanup:
  free(voxels);
  free(far);
  free(taken);
  free(cell_volume);
  list_free(&cand);
  dart_free(&darts);
  return status;
}

fascia_status fascia_prep_sample(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                 const fascia_prep_volume *volume, fascia_prep_points **out) {
  PREP_CHECK(ctx && scene && meshes && volume && out, ctx, FASCIA_ERR_ARGUMENT, "fascia_prep_sample: NULL argument");
  *out = NULL;
  fascia_status status = FASCIA_OK;
  point_list frames = {0}, samples = {0};
  sample_data data = {0};
  // regions in order: the tissues, then the deformable organs; region r owns
  // frames [frame_end[r-1], frame_end[r]) and the same for samples
  const int32_t T = scene->tissue_count, O = scene->organ_count;
  int32_t *frame_end = prep_calloc(T + O, sizeof(int32_t)), *sample_end = prep_calloc(T + O, sizeof(int32_t));
  int32_t *region_organ = prep_calloc(T + O, sizeof(int32_t)), *tissue_of = NULL;
  fascia_cgal_tree **trees = prep_calloc(meshes->count, sizeof *trees);
  fascia_prep_points *p = calloc(1, sizeof *p);
  int32_t *mid_layer = p ? (p->tissue_mid_layer_frames = prep_calloc(T, sizeof(int32_t))) : NULL;
  double *held = p ? (p->tissue_held_layer_volume = prep_calloc(T, sizeof(double))) : NULL;
  int32_t regions = 0;
  PREP_CHECK_GOTO(p && mid_layer && held && trees && frame_end && sample_end && region_organ, ctx, FASCIA_ERR_MEMORY,
                  "sample: out of memory");
  for (int32_t t = 0; t < T; ++t) {
    fascia_ctx_progress(ctx, "sample", (double)t / (T + O), scene->tissues[t].name);
    if (scene->tissues[t].form != FASCIA_PREP_FORM_VOLUME)
      PREP_TRY_GOTO(sample_reduced(ctx, scene, meshes, volume, t, trees, &frames, &samples, &data));
    else
      PREP_TRY_GOTO(
          sample_region(ctx, scene, meshes, volume, (uint8_t)(t + 1), trees, &frames, &samples, &data, mid_layer + t,
                                  held + t));
    region_organ[regions] = -1;
    frame_end[regions] = (int32_t)frames.count;
    sample_end[regions++] = (int32_t)samples.count;
  }
  tissue_of = prep_calloc(frames.count, sizeof(int32_t)); // tissue frames only: organ frames come after
  PREP_CHECK_GOTO(tissue_of, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  for (int32_t t = 0, i = 0; t < T; ++t)
    for (; i < frame_end[t]; ++i) tissue_of[i] = t;
  for (int32_t o = 0; o < O; ++o) {
    if (scene->organs[o].kind != FASCIA_ORGAN_DEFORMABLE) continue;
    fascia_ctx_progress(ctx, "sample", (double)(T + o) / (T + O), scene->organs[o].name);
    if (scene->organs[o].shell) { // a hollow organ's wall (shell.c)
      PREP_TRY_GOTO(sample_shell(ctx, scene, meshes, o, frame_end[T - 1], tissue_of, trees, &frames, &samples, &data));
    } else {
      attach_shared(scene, meshes, volume, o, tissue_of, &frames);
      PREP_TRY_GOTO(sample_region(ctx, scene, meshes, volume, (uint8_t)volume->organ_label[o], trees, &frames,
                                  &samples, &data, NULL, NULL));
    }
    region_organ[regions] = o;
    frame_end[regions] = (int32_t)frames.count;
    sample_end[regions++] = (int32_t)samples.count;
  }
  PREP_CHECK_GOTO(frames.count < INT32_MAX && samples.count < INT32_MAX, ctx, FASCIA_ERR_MEMORY,
                  "sample: too many points (%lld frames, %lld samples); raise the spacings", (long long)frames.count,
                  (long long)samples.count);
  const int64_t N = frames.count, S = samples.count;
  p->frame_count = (int32_t)N;
  p->sample_count = (int32_t)S;
  int allocated = 1;
#define ALLOC_ARRAY(member, type, count, width)                                                                       \
  allocated &= (p->member = prep_calloc((width) * (count), sizeof(type))) != NULL;
  POINTS_ARRAYS(ALLOC_ARRAY)
#undef ALLOC_ARRAY
  PREP_CHECK_GOTO(allocated, ctx, FASCIA_ERR_MEMORY, "sample: out of memory");
  if (N) {
    memcpy(p->frame_position, frames.position, (size_t)(3 * N) * sizeof(double));
    memcpy(p->frame_organ, frames.organ, (size_t)N * sizeof(int32_t));
    memcpy(p->frame_triangle, frames.triangle, (size_t)N * sizeof(int32_t));
    memcpy(p->frame_voxel, frames.voxel, (size_t)N * sizeof(int64_t));
    memcpy(p->frame_organ_voxel, frames.attach, (size_t)N * sizeof(int64_t));
  }
  if (S) {
    memcpy(p->sample_position, samples.position, (size_t)(3 * S) * sizeof(double));
    memcpy(p->sample_voxel, samples.voxel, (size_t)S * sizeof(int64_t));
    memcpy(p->sample_volume, data.volume, (size_t)S * sizeof(double));
    memcpy(p->sample_tet_frame, data.tet_frame, (size_t)(4 * S) * sizeof(int32_t));
    memcpy(p->sample_cell_frame, data.cell_frame, (size_t)(3 * S) * sizeof(int32_t));
    memcpy(p->sample_drilling, data.drilling, (size_t)S);
  }
  for (int32_t r = 0, i = 0, s = 0; r < regions; ++r) {
    const int32_t o = region_organ[r], t = o < 0 ? r : -1;
    for (; i < frame_end[r]; ++i) p->frame_tissue[i] = t, p->frame_inside_organ[i] = o;
    for (; s < sample_end[r]; ++s) p->sample_tissue[s] = t, p->sample_inside_organ[s] = o;
  }
  fascia_ctx_progress(ctx, "sample", 1, "done");
  *out = p;
  p = NULL;
cleanup:
  for (int32_t o = 0; trees && o < meshes->count; ++o) fascia_cgal_tree_destroy(trees + o);
  free(trees);
  free(frame_end);
  free(sample_end);
  free(region_organ);
  free(tissue_of);
  list_free(&frames);
  list_free(&samples);
  free(data.volume);
  free(data.tet_frame);
  free(data.cell_frame);
  free(data.drilling);
  fascia_prep_points_destroy(&p);
  return status;
}
