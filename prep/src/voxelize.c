// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Stage 3, voxelize: inside/outside of every organ near a tissue, signed
// distances (OpenVDB), overlaps, and each tissue's region.
//
// Inside/outside. Real segmentations are open, doubled or self-intersecting,
// so the sign does not come from normals. Instead (the "outer surface" rule):
//
//   1. every axis-parallel segment between two neighbouring voxel centres that
//      a triangle crosses is blocked (exact scan conversion of the triangles);
//   2. a flood fill from the grid's border over unblocked segments reaches
//      exactly the voxels connected to the outside without crossing the
//      surface; everything else is inside. Cavities and the space between the
//      two sheets of a thin shell count as inside, as tissue cannot reach them
//      (a deformable organ's own region leaves a hollow organ's cavity out:
//      organ_material);
//   3. if the surface has holes (border edges) and the fill leaked in, the
//      fill is redone with walls of voxels within (c + 1/2) h of the surface
//      (2c + 1 = close_holes / h), then grown back towards the surface over unblocked
//      segments by 2c + 2 steps: holes up to about 2c voxels across are
//      closed, and away from the holes the surface stays exact.
//
// The report of each organ says which rule was used.
//
// Tissue region of tissue t (voxel centre x): outside every organ, on a
// bridge of length at most max_gap between two organs t connects,
// d_A(x) + d_B(x) <= max_gap for some pair (A, B) of them (the distance to the
// named parts standing in for their organ's), inside the optional box or
// sphere; pieces smaller than min_component are dropped. Such a point and
// the two segments that join it to its closest points on A and on B all pass
// the test (the sum only shrinks along them), so each piece of tissue
// reaches both organs it bridges.
// Overlapping organs: voxels inside two organs are counted and the depth
// (largest penetration of one surface into the other, on the surfaces)
// reported; the tissue is built outside both, the organ surfaces are kept as
// given. Gaps are measured on the surfaces too (measure_pairs).
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <unistd.h>

#include "labels.h"

// grids above this many voxels are refused (2^31: 2 GB per byte array)
#define MAX_VOXELS ((int64_t)1 << 31)

// Refuses, before anything is allocated, a grid of spacing h covering
// [lo, hi] (pad voxels around) with more than MAX_VOXELS voxels, or whose
// arrays (bytes_per_voxel) would not fit in this machine's memory; the sizes
// are computed in double, so absurd boxes or spacings cannot overflow.
static fascia_status check_grid(fascia_ctx *ctx, const char *what, const char *scene_path, double h,
                                const double *lo, const double *hi, int32_t pad, double bytes_per_voxel) {
  double voxels = 1, extent[3];
  for (int r = 0; r < 3; ++r) {
    extent[r] = hi[r] - lo[r];
    const double a = floor(lo[r] / h) - pad, b = ceil(hi[r] / h) + pad;
    PREP_CHECK(isfinite(a) && isfinite(b) && a > -2e9 && b < 2e9, ctx, FASCIA_ERR_ARGUMENT,
               "%s (scene '%s' voxel_size): coordinates up to %g m at voxel_size %g m are beyond the voxel lattice; "
               "check the units and transforms of the meshes, or raise voxel_size",
               what, scene_path, fmax(fabs(lo[r]), fabs(hi[r])), h);
    voxels *= b - a + 1;
  }
  double memory = 0;
#if defined(_SC_PHYS_PAGES) && defined(_SC_PAGESIZE)
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0) memory = (double)pages * (double)page;
#endif
  const double bytes = voxels * bytes_per_voxel;
  char hint[256];
  prep_units_hint_box(fmax(fmax(extent[0], extent[1]), extent[2]), hint, sizeof hint);
  const double limit = memory > 0 ? fmin((double)MAX_VOXELS, memory / bytes_per_voxel) : (double)MAX_VOXELS;
  PREP_CHECK(voxels <= limit, ctx, FASCIA_ERR_ARGUMENT,
             "%s (scene '%s' voxel_size): a box of %.3g x %.3g x %.3g m at voxel_size %g m needs %.3g voxels "
             "(%.1f GiB), more than the limit of %.3g voxels (%lld at most%s%.1f GiB of memory here); set voxel_size "
             "to at least %.3g m%s",
             what, scene_path, extent[0], extent[1], extent[2], h, voxels, bytes / 1073741824.0, limit,
             (long long)MAX_VOXELS, memory > 0 ? ", and " : ", memory unknown: ", memory / 1073741824.0,
             h * cbrt(voxels / limit) * 1.01, hint);
  return FASCIA_OK;
}

void fascia_prep_volume_destroy(fascia_prep_volume **volume) {
  if (!volume || !*volume) return;
  fascia_prep_volume *v = *volume;
  free(v->region);
  for (int32_t k = 0; v->distance && k < v->organ_count; ++k) free(v->distance[k]);
  free(v->distance);
  free(v->band);
  for (int32_t t = 0; v->tissues && t < v->tissue_count; ++t) free(v->tissues[t].pair_volume);
  free(v->tissues);
  free(v->overlaps);
  free(v->closest);
  free(v->organ_label);
  free(v->organ_regions);
  free(v);
  *volume = NULL;
}

int fascia_prep_volume_region_at(const fascia_prep_volume *volume, const fascia_real *point) {
  const prep_grid g = prep_volume_grid(volume);
  const int64_t v = prep_grid_locate(&g, point);
  return v < 0 ? 0 : volume->region[v];
}

// ------------------------------------------------------------ inside/outside

// Marks the grid segments the triangle crosses: bit a of blocked[v] blocks the
// segment from voxel v to its +a neighbour.
static void block_triangle(const prep_grid *g, const double *p0, const double *p1, const double *p2,
                           uint8_t *blocked) {
  double q[3][3];
  for (int r = 0; r < 3; ++r) {
    q[0][r] = p0[r] / g->h - g->lo[r];
    q[1][r] = p1[r] / g->h - g->lo[r];
    q[2][r] = p2[r] / g->h - g->lo[r];
  }
  for (int ax = 0; ax < 3; ++ax) {
    const int u = (ax + 1) % 3, w = (ax + 2) % 3;
    const double area = (q[1][u] - q[0][u]) * (q[2][w] - q[0][w]) - (q[2][u] - q[0][u]) * (q[1][w] - q[0][w]);
    if (fabs(area) < 1e-14) continue; // parallel to the axis: crossed by no line transversally
    const double umin = fmin(q[0][u], fmin(q[1][u], q[2][u])), umax = fmax(q[0][u], fmax(q[1][u], q[2][u]));
    const double wmin = fmin(q[0][w], fmin(q[1][w], q[2][w])), wmax = fmax(q[0][w], fmax(q[1][w], q[2][w]));
    const double eps = 1e-9; // inclusive edges: a line through a shared edge is blocked twice, never zero times
    for (int32_t jw = (int32_t)ceil(wmin - 1e-9); jw <= (int32_t)floor(wmax + 1e-9); ++jw)
      for (int32_t ju = (int32_t)ceil(umin - 1e-9); ju <= (int32_t)floor(umax + 1e-9); ++ju) {
        // barycentric coordinates of the line's foot (ju, jw) in the projected triangle
        const double b0 = ((q[1][u] - ju) * (q[2][w] - jw) - (q[2][u] - ju) * (q[1][w] - jw)) / area;
        const double b1 = ((q[2][u] - ju) * (q[0][w] - jw) - (q[0][u] - ju) * (q[2][w] - jw)) / area;
        const double b2 = 1 - b0 - b1;
        if (b0 < -eps || b1 < -eps || b2 < -eps) continue;
        const double t = b0 * q[0][ax] + b1 * q[1][ax] + b2 * q[2][ax];
        int32_t ijk[3];
        ijk[u] = ju;
        ijk[w] = jw;
        const int32_t i = (int32_t)floor(t);
        const int on_centre = fabs(t - floor(t + 0.5)) < 1e-9;
        for (int32_t a = on_centre ? (int32_t)floor(t + 0.5) - 1 : i; a <= (on_centre ? (int32_t)floor(t + 0.5) : i);
             ++a) {
          ijk[ax] = a;
          if (ijk[0] < 0 || ijk[1] < 0 || ijk[2] < 0 || ijk[0] >= g->dims[0] || ijk[1] >= g->dims[1] ||
              ijk[2] >= g->dims[2])
            continue;
          blocked[prep_grid_index(g, ijk[0], ijk[1], ijk[2])] |= (uint8_t)(1u << ax);
        }
      }
    // parity (bit 3 + ax): the same lines shifted by a tiny irrational-looking
    // offset so that no line meets an edge or a vertex exactly; each crossing
    // toggles the segment it falls in, so two sheets within one segment cancel
    const double du = 1.2345e-4, dw = 2.3456e-4;
    for (int32_t jw = (int32_t)ceil(wmin - dw); jw + dw <= wmax; ++jw)
      for (int32_t ju = (int32_t)ceil(umin - du); ju + du <= umax; ++ju) {
        const double fu = ju + du, fw = jw + dw;
        const double b0 = ((q[1][u] - fu) * (q[2][w] - fw) - (q[2][u] - fu) * (q[1][w] - fw)) / area;
        const double b1 = ((q[2][u] - fu) * (q[0][w] - fw) - (q[0][u] - fu) * (q[2][w] - fw)) / area;
        const double b2 = 1 - b0 - b1;
        if (b0 < 0 || b1 < 0 || b2 < 0) continue;
        const double t = b0 * q[0][ax] + b1 * q[1][ax] + b2 * q[2][ax];
        int32_t ijk[3];
        ijk[u] = ju;
        ijk[w] = jw;
        ijk[ax] = (int32_t)floor(t);
        if (ijk[0] < 0 || ijk[1] < 0 || ijk[2] < 0 || ijk[0] >= g->dims[0] || ijk[1] >= g->dims[1] ||
            ijk[2] >= g->dims[2])
          continue;
        blocked[prep_grid_index(g, ijk[0], ijk[1], ijk[2])] ^= (uint8_t)(8u << ax);
      }
  }
}

// Ray-parity vote (Nooruddin and Turk 2003): along each axis, in both
// directions, a voxel is inside when the rays from the grid border cross the
// surface an odd number of times before it; inside[v] = 1 when at least 4 of
// the 6 rays say so. Holes spoil only the rays that pass through them.
static void parity_vote(const prep_grid *g, const uint8_t *bits, uint8_t *inside) {
  const int64_t n = prep_grid_count(g);
  memset(inside, 0, (size_t)n);
  const int64_t stride[3] = {1, g->dims[0], (int64_t)g->dims[0] * g->dims[1]};
  for (int ax = 0; ax < 3; ++ax) {
    const int u = (ax + 1) % 3, w = (ax + 2) % 3;
    const uint8_t bit = (uint8_t)(8u << ax);
    for (int32_t jw = 0; jw < g->dims[w]; ++jw)
      for (int32_t ju = 0; ju < g->dims[u]; ++ju) {
        int32_t c[3];
        c[u] = ju, c[w] = jw, c[ax] = 0;
        const int64_t start = prep_grid_index(g, c[0], c[1], c[2]);
        const int32_t len = g->dims[ax];
        int state = 0;
        for (int32_t i = 0; i < len; ++i) {
          const int64_t v = start + i * stride[ax];
          inside[v] += (uint8_t)state;
          if (bits[v] & bit) state ^= 1;
        }
        state = 0;
        for (int32_t i = len - 1; i >= 0; --i) {
          const int64_t v = start + i * stride[ax];
          if (i + 1 < len && (bits[v] & bit)) state ^= 1;
          inside[v] += (uint8_t)state;
        }
      }
  }
  for (int64_t v = 0; v < n; ++v) inside[v] = inside[v] >= 4;
}

// Flood fill from the grid border: outside[v] = 1 for voxels reached over
// unblocked segments and non-wall voxels (wall may be NULL).
static void flood_outside(const prep_grid *g, const uint8_t *blocked, const uint8_t *wall, uint8_t *outside,
                          int64_t *queue) {
  const int64_t n = prep_grid_count(g);
  memset(outside, 0, (size_t)n);
  int64_t head = 0, tail = 0;
  for (int64_t v = 0; v < n; ++v) {
    int32_t c[3];
    prep_grid_ijk(g, v, c);
    const int border = c[0] == 0 || c[1] == 0 || c[2] == 0 || c[0] == g->dims[0] - 1 || c[1] == g->dims[1] - 1 ||
                       c[2] == g->dims[2] - 1;
    if (border && !(wall && wall[v])) {
      outside[v] = 1;
      queue[tail++] = v;
    }
  }
  const int64_t stride[3] = {1, g->dims[0], (int64_t)g->dims[0] * g->dims[1]};
  while (head < tail) {
    const int64_t v = queue[head++];
    int32_t c[3];
    prep_grid_ijk(g, v, c);
    for (int ax = 0; ax < 3; ++ax) {
      if (c[ax] + 1 < g->dims[ax] && !(blocked[v] & (1u << ax))) {
        const int64_t nb = v + stride[ax];
        if (!outside[nb] && !(wall && wall[nb])) outside[nb] = 1, queue[tail++] = nb;
      }
      if (c[ax] > 0) {
        const int64_t nb = v - stride[ax];
        if (!(blocked[nb] & (1u << ax)) && !outside[nb] && !(wall && wall[nb])) outside[nb] = 1, queue[tail++] = nb;
      }
    }
  }
}

// Grows outside by up to `layers` steps over unblocked segments: after a fill
// stopped by walls, this brings back the outside voxels between the wall and
// the surface without crossing the surface (except through its holes).
static void grow_outside(const prep_grid *g, const uint8_t *blocked, uint8_t *outside, int32_t layers,
                         int64_t *queue) {
  const int64_t n = prep_grid_count(g);
  const int64_t stride[3] = {1, g->dims[0], (int64_t)g->dims[0] * g->dims[1]};
  int64_t head = 0, tail = 0;
  for (int64_t v = 0; v < n; ++v)
    if (outside[v]) queue[tail++] = v;
  for (int32_t layer = 0; layer < layers; ++layer) {
    const int64_t end = tail;
    while (head < end) {
      const int64_t v = queue[head++];
      int32_t c[3];
      prep_grid_ijk(g, v, c);
      for (int ax = 0; ax < 3; ++ax) {
        if (c[ax] + 1 < g->dims[ax] && !(blocked[v] & (1u << ax)) && !outside[v + stride[ax]])
          outside[v + stride[ax]] = 1, queue[tail++] = v + stride[ax];
        if (c[ax] > 0 && !(blocked[v - stride[ax]] & (1u << ax)) && !outside[v - stride[ax]])
          outside[v - stride[ax]] = 1, queue[tail++] = v - stride[ax];
      }
    }
  }
}

// A further rule of organ_inside, its outside given: what it leaves inside
// becomes the organ's inside when it is more than twice what the rule kept
// so far has (*chosen voxels; that one leaked). Returns 1 when it does.
static int adopt_rule(const uint8_t *outside, int64_t n, uint8_t *inside, int64_t *chosen) {
  int64_t count = 0;
  for (int64_t v = 0; v < n; ++v) count += !outside[v];
  if (*chosen >= count / 2) return 0;
  for (int64_t v = 0; v < n; ++v) inside[v] = !outside[v];
  *chosen = count;
  return 1;
}

// inside[v] = 1 for voxels of the organ grid g inside organ o (see the note).
// parity (may be NULL): the ray-parity vote of the exact surface, for organ_material.
static fascia_status organ_inside(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_mesh *o,
                                  const prep_grid *g, uint8_t *inside, uint8_t *parity) {
  fascia_status status = FASCIA_OK;
  const int64_t n = prep_grid_count(g);
  PREP_CHECK(n > 0, ctx, FASCIA_ERR_INTERNAL, "organ '%s': an empty grid", o->name);
  uint8_t *blocked = prep_calloc(n, 1), *outside = prep_calloc(n, 1), *wall = NULL;
  int64_t *queue = prep_calloc(n, sizeof(int64_t));
  float *udf = NULL;
  PREP_CHECK_GOTO(blocked && outside && queue, ctx, FASCIA_ERR_MEMORY,
                  "organ '%s': out of memory for %lld voxels; raise voxel_size", o->name, (long long)n);
  for (int32_t t = 0; t < o->triangle_count; ++t) {
    const int32_t *tri = o->triangles + 3 * (int64_t)t;
    block_triangle(g, o->vertices + 3 * (int64_t)tri[0], o->vertices + 3 * (int64_t)tri[1],
                   o->vertices + 3 * (int64_t)tri[2], blocked);
  }
  if (parity) parity_vote(g, blocked, parity);
  // rule 1: the exact surface
  flood_outside(g, blocked, NULL, outside, queue);
  int64_t chosen = 0;
  for (int64_t v = 0; v < n; ++v) chosen += inside[v] = !outside[v];
  snprintf(o->report.inside_rule, sizeof o->report.inside_rule,
           "outer surface (flood fill from outside across the exact surface)%s",
           o->report.border_edges ? "; open, but no hole leaks at this voxel size" : "");
  if (o->report.border_edges > 0) {
    // an open surface: two more rules, and the exact one is kept unless it
    // finds less than half of what another rule finds (it leaked)
    // closing radius c voxels: walls of (c + 1/2) h close holes up to (2c + 1) h across
    const int32_t c = (int32_t)ceil(fmax(0, scene->close_holes / scene->voxel_size - 1) / 2);
    wall = prep_calloc(n, 1);
    PREP_CHECK_GOTO(wall, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory for %lld voxels", o->name, (long long)n);
    if (c > 0) { // rule 2: morphological closing of the holes
      udf = prep_calloc(n, sizeof(float));
      PREP_CHECK_GOTO(udf, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory for %lld voxels", o->name, (long long)n);
      PREP_TRY_GOTO(fascia_vdb_unsigned_distance(ctx, o->vertex_count, o->vertices, o->triangle_count, o->triangles,
                                                 g->h, (float)c + 2, g->lo, g->dims, udf));
      for (int64_t v = 0; v < n; ++v) wall[v] = udf[v] <= (c + 0.5) * g->h;
      flood_outside(g, blocked, wall, outside, queue);
      grow_outside(g, blocked, outside, 2 * c + 2, queue);
      if (adopt_rule(outside, n, inside, &chosen))
        snprintf(o->report.inside_rule, sizeof o->report.inside_rule,
                 "outer surface after closing holes up to %.3g mm (open mesh, %d border edges: the exact surface "
                 "leaks at this voxel size)",
                 1e3 * (2 * c + 1) * g->h, (int)o->report.border_edges);
    }
    // rule 3: ray-parity vote, then its outer surface (cavities count as inside)
    parity_vote(g, blocked, wall);
    memset(outside, 0, (size_t)n);
    uint8_t *no_segments = prep_calloc(n, 1);
    PREP_CHECK_GOTO(no_segments, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", o->name);
    flood_outside(g, no_segments, wall, outside, queue);
    free(no_segments);
    if (adopt_rule(outside, n, inside, &chosen))
      snprintf(o->report.inside_rule, sizeof o->report.inside_rule,
               "ray-parity vote of 6 axis rays, then its outer surface (open mesh, %d border edges: holes too large "
               "to close)",
               (int)o->report.border_edges);
  }
  // the surface encloses a volume (checked at the repair), but no voxel centre lies in it
  const double *b = o->bounds, thinnest = fmin(fmin(b[3] - b[0], b[4] - b[1]), b[5] - b[2]);
  if (chosen == 0) {
    char hint[512];
    int32_t k = 0;
    while (k + 1 < scene->organ_count && strcmp(scene->organs[k].name, o->name)) ++k;
    prep_units_hint_organ(scene, k, prep_mesh_extent(o), hint, sizeof hint);
    if (!hint[0]) prep_units_hint_voxel(scene, hint, sizeof hint);
    PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_FORMAT,
                    "organ '%s' (scene '%s' organs[%d].mesh): no voxel lies inside it: it is %.3g x %.3g x %.3g mm, "
                    "smaller or thinner than a voxel (voxel_size %.3g mm); lower voxel_size to %.3g m or less, or "
                    "leave the organ out%s",
                    o->name, scene->path, (int)k, 1e3 * (b[3] - b[0]), 1e3 * (b[4] - b[1]), 1e3 * (b[5] - b[2]),
                    1e3 * g->h, thinnest / 2, hint);
  }
  o->report.enclosed_volume = (double)chosen * g->h * g->h * g->h;
cleanup:
  free(blocked);
  free(outside);
  free(queue);
  free(udf);
  free(wall);
  return status;
}

// The material of a deformable organ, on its grid g: what the outer surface
// rule puts inside, less the cavities of a hollow organ. A closed surface of
// nested shells (an outer shell and, inside it, an inner one) holds material
// where an odd number of shells enclose a point: the ray parity. The repair
// turns every closed shell outward, so the nesting decides, not the
// orientation. Parity is trusted only where it is unambiguous: each shell
// must bound the outside or a cavity, never both (shells that cross, a
// self-overlap, overlapping parts), and the surface must be closed (an
// open one is filled by the outer rule, as before). Otherwise a small
// even-parity volume is filled as before and a large one is refused. material: in, the parity
// vote; out, the material, or NULL'd by the caller when *hollow is 0.
static fascia_status organ_material(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_mesh *o,
                                    const prep_grid *g, const uint8_t *inside, uint8_t *material, int *hollow) {
  const int64_t n = prep_grid_count(g);
  int64_t inside_count = 0, cavity = 0;
  for (int64_t v = 0; v < n; ++v) {
    inside_count += inside[v];
    cavity += inside[v] && !material[v];
  }
  *hollow = 0;
  if (cavity * 1000 <= inside_count) return FASCIA_OK; // round-off where a centre lies on the surface
  // an open surface: the parity's rays pass its holes, and the outer rule
  // may have closed them or leaked through them; it is filled as before
  if (o->report.border_edges > 0) return FASCIA_OK;
  const int large = cavity * 10 >= inside_count;
  int32_t k = 0;
  while (k + 1 < scene->organ_count && strcmp(scene->organs[k].name, o->name)) ++k;
  const double cm3 = 1e6 * (double)cavity * g->h * g->h * g->h;
  // the shells: connected components of the triangles
  const int32_t NV = o->vertex_count, NT = o->triangle_count;
  int32_t *root = prep_calloc(NV, sizeof(int32_t));
  int64_t *tally = prep_calloc(3 * (int64_t)NV, sizeof(int64_t)); // per root: triangles, seeing outside, cavity
  if (!root || !tally) {
    free(root), free(tally);
    return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", o->name);
  }
  for (int32_t v = 0; v < NV; ++v) root[v] = v;
  for (int32_t t = 0; t < NT; ++t)
    for (int r = 1; r < 3; ++r) {
      int32_t a = o->triangles[3 * (int64_t)t], b = o->triangles[3 * (int64_t)t + r];
      while (root[a] != a) a = root[a] = root[root[a]];
      while (root[b] != b) b = root[b] = root[root[b]];
      if (a != b) root[a > b ? a : b] = a < b ? a : b;
    }
  // each triangle looks a voxel to either side of its centroid
  for (int32_t t = 0; t < NT; ++t) {
    const int32_t *tri = o->triangles + 3 * (int64_t)t;
    int32_t c = tri[0];
    while (root[c] != c) c = root[c];
    const double *p0 = o->vertices + 3 * (int64_t)tri[0], *p1 = o->vertices + 3 * (int64_t)tri[1],
                 *p2 = o->vertices + 3 * (int64_t)tri[2];
    double e1[3], e2[3], nrm[3];
    for (int r = 0; r < 3; ++r) e1[r] = p1[r] - p0[r], e2[r] = p2[r] - p0[r];
    nrm[0] = e1[1] * e2[2] - e1[2] * e2[1];
    nrm[1] = e1[2] * e2[0] - e1[0] * e2[2];
    nrm[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    if (!(len > 0)) continue;
    int seen_out = 0, seen_cavity = 0;
    for (int side = -1; side <= 1; side += 2) {
      double q[3];
      for (int r = 0; r < 3; ++r) q[r] = (p0[r] + p1[r] + p2[r]) / 3 + side * g->h * nrm[r] / len;
      const int64_t v = prep_grid_locate(g, q);
      if (v < 0 || !inside[v]) seen_out = 1;
      else if (!material[v]) seen_cavity = 1;
    }
    tally[3 * (int64_t)c] += 1;
    tally[3 * (int64_t)c + 1] += seen_out;
    tally[3 * (int64_t)c + 2] += seen_cavity;
  }
  int32_t crossing = -1, inner = 0;
  for (int32_t c = 0; c < NV; ++c) {
    const int64_t *q = tally + 3 * (int64_t)c;
    if (q[0] == 0) continue;
    const int64_t both = q[1] < q[2] ? q[1] : q[2];
    if (both * 100 > q[0] && crossing < 0) crossing = c;
    inner += q[2] > q[1];
  }
  int64_t crossing_triangles = crossing >= 0 ? tally[3 * (int64_t)crossing] : 0;
  free(root);
  free(tally);
  if (crossing >= 0) {
    PREP_CHECK(!large, ctx, FASCIA_ERR_FORMAT,
               "deformable organ '%s' (scene '%s' organs[%d].mesh): a shell of its surface (%lld triangles) bounds "
               "both the outside and a %.3g cm^3 space inside other shells: its shells cross, so its wall cannot be "
               "told from a cavity; for a hollow organ keep the inner shell strictly inside the outer (a wall of two "
               "voxels or more: lower voxel_size if it is thinner), for overlapping pieces merge them into one surface",
               o->name, scene->path, (int)k, (long long)crossing_triangles, cm3);
    return FASCIA_OK;
  }
  int64_t kept = 0;
  for (int64_t v = 0; v < n; ++v) kept += material[v] = inside[v] && material[v];
  *hollow = 1;
  snprintf(o->report.inside_rule, sizeof o->report.inside_rule,
           "the wall between nested closed shells (ray parity: %d inner shell(s) enclose %.3g cm^3 of cavity)",
           (int)inner, cm3);
  o->report.enclosed_volume = (double)kept * g->h * g->h * g->h;
  return FASCIA_OK;
}

// ------------------------------------------------------------ the tissue domain

// How far from its organs' surfaces tissue td can reach, with two voxels of
// slack for the voxel centres. The grid is built from it (tissue_box) and an
// organ's distance band covers it (organ_band), so every organ a tissue
// connects has a distance field wherever the tissue can be.
static double tissue_reach(const fascia_prep_scene *scene, const fascia_prep_tissue_def *td) {
  if (td->form != FASCIA_PREP_FORM_VOLUME) return 2 * scene->voxel_size; // its own box: reduced_box
  return td->max_gap + 2 * scene->voxel_size;
}

// Width of the band around organ o where its distances are exact: the reach
// of every tissue it belongs to, every tissue's coupling tolerance (sharing
// frames) and a few voxels for the "outside" test.
static double organ_band(const fascia_prep_scene *scene, int32_t o) {
  const double h = scene->voxel_size;
  double band = 3 * h;
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    const fascia_prep_tissue_def *td = scene->tissues + t;
    band = fmax(band, td->coupling_tolerance + 2 * h);
    for (int32_t k = 0; k < td->organ_count; ++k)
      if (td->organs[k] == o) band = fmax(band, tissue_reach(scene, td));
  }
  return band;
}

// 1 when the box [lo, hi] grown by band meets the voxel centres of g: only
// then can the organ of that box have a distance below band on g.
static int box_meets_grid(const prep_grid *g, const double *lo, const double *hi, double band) {
  for (int r = 0; r < 3; ++r)
    if (lo[r] - band > g->h * (g->lo[r] + g->dims[r] - 1) || hi[r] + band < g->h * g->lo[r]) return 0;
  return 1;
}

// Bounding box of the space tissue t can occupy: the union over pairs of its
// organs of the two boxes' intersection, grown by its reach, cut by its box or
// sphere. 0 if empty.
static int tissue_box(const fascia_prep_scene *scene, const fascia_prep_meshes *meshes, int32_t t, double *lo,
                      double *hi) {
  const fascia_prep_tissue_def *td = scene->tissues + t;
  const double grow = tissue_reach(scene, td);
  for (int r = 0; r < 3; ++r) lo[r] = INFINITY, hi[r] = -INFINITY;
  for (int32_t i = 0; i < td->organ_count; ++i)
    for (int32_t j = i + 1; j < td->organ_count; ++j) {
      const double *a = meshes->organs[td->organs[i]].bounds, *b = meshes->organs[td->organs[j]].bounds;
      double plo[3], phi[3];
      int empty = 0;
      for (int r = 0; r < 3; ++r) {
        plo[r] = fmax(a[r], b[r]) - grow;
        phi[r] = fmin(a[3 + r], b[3 + r]) + grow;
        empty |= !(phi[r] > plo[r]);
      }
      if (empty) continue;
      for (int r = 0; r < 3; ++r) lo[r] = fmin(lo[r], plo[r]), hi[r] = fmax(hi[r], phi[r]);
    }
  if (td->region.kind == FASCIA_PREP_REGION_BOX)
    for (int r = 0; r < 3; ++r) {
      lo[r] = fmax(lo[r], td->region.min[r]);
      hi[r] = fmin(hi[r], td->region.max[r]);
    }
  else if (td->region.kind == FASCIA_PREP_REGION_SPHERE)
    for (int r = 0; r < 3; ++r) {
      lo[r] = fmax(lo[r], td->region.center[r] - td->region.radius);
      hi[r] = fmin(hi[r], td->region.center[r] + td->region.radius);
    }
  for (int r = 0; r < 3; ++r)
    if (!(hi[r] > lo[r])) return 0;
  return 1;
}

// The space a strand or a sheet takes, with room for its attachments and
// thickness and a few voxels: the grid covers it, so the organs' distances
// are known along it (the checks of reduced.c).
static void reduced_box(const fascia_prep_scene *scene, const fascia_prep_meshes *meshes, int32_t t, double *lo,
                        double *hi) {
  const fascia_prep_tissue_def *td = scene->tissues + t;
  const double h = scene->voxel_size;
  if (td->form == FASCIA_PREP_FORM_STRAND) {
    const double grow = fmax(td->from.radius, td->to.radius) + td->radius + 3 * h;
    for (int r = 0; r < 3; ++r) {
      lo[r] = fmin(td->from.point[r], td->to.point[r]) - grow;
      hi[r] = fmax(td->from.point[r], td->to.point[r]) + grow;
    }
    return;
  }
  const double *b = meshes->sheets[t].bounds, grow = td->thickness + td->coupling_tolerance + 3 * h;
  for (int r = 0; r < 3; ++r) lo[r] = b[r] - grow, hi[r] = b[3 + r] + grow;
}

static const char *organ_list(const fascia_prep_scene *scene, const fascia_prep_tissue_def *td, char *out,
                              size_t size) {
  out[0] = 0;
  for (int32_t k = 0; k < td->organ_count; ++k) {
    const char *name = scene->organs[td->organs[k]].name;
    if (strlen(out) + strlen(name) + 8 >= size) break;
    if (k) strcat(out, k + 1 == td->organ_count ? " and " : ", ");
    strcat(out, "'");
    strcat(out, name);
    strcat(out, "'");
  }
  return out;
}

// Distance between the surfaces of organs a and b: the smallest distance of
// a vertex of either to the other's surface (exact when the closest points
// include a vertex, as for boxes; else slightly more).
static fascia_status surface_gap(fascia_ctx *ctx, const fascia_prep_meshes *meshes, int32_t a, int32_t b,
                                 double *gap) {
  *gap = INFINITY;
  for (int pass = 0; pass < 2; ++pass) {
    const fascia_prep_mesh *from = meshes->organs + (pass ? b : a), *to = meshes->organs + (pass ? a : b);
    fascia_cgal_tree *tree = NULL;
    PREP_TRY(fascia_cgal_tree_create(ctx, to->vertex_count, to->vertices, to->triangle_count, to->triangles, &tree));
    double *closest = prep_calloc(3 * (int64_t)from->vertex_count, sizeof(double));
    int32_t *triangle = prep_calloc(from->vertex_count, sizeof(int32_t));
    if (closest && triangle) {
      fascia_cgal_tree_closest(tree, from->vertex_count, from->vertices, closest, triangle);
      for (int32_t v = 0; v < from->vertex_count; ++v) {
        const double *p = from->vertices + 3 * (int64_t)v, *q = closest + 3 * (int64_t)v;
        *gap = fmin(*gap, sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                               (p[2] - q[2]) * (p[2] - q[2])));
      }
    }
    free(closest);
    free(triangle);
    fascia_cgal_tree_destroy(&tree);
    PREP_CHECK(closest && triangle, ctx, FASCIA_ERR_MEMORY, "voxelize: out of memory");
  }
  return FASCIA_OK;
}

// The user's message when no path of at most max_gap joins two organs of
// tissue td: it names the two organs closest together, the distance between
// their surfaces and the max_gap that would bridge them. nearest is the
// shortest bridge d_A + d_B through a free voxel (INFINITY: none within the
// distance band).
static fascia_status too_far_apart(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                   const fascia_prep_tissue_def *td, double nearest) {
  const double h = scene->voxel_size;
  int32_t a = td->organs[0], b = td->organs[td->organ_count > 1 ? 1 : 0];
  double gap = INFINITY;
  for (int32_t i = 0; i < td->organ_count; ++i)
    for (int32_t j = i + 1; j < td->organ_count; ++j) {
      double d;
      PREP_TRY(surface_gap(ctx, meshes, td->organs[i], td->organs[j], &d));
      if (d < gap) a = td->organs[i], b = td->organs[j], gap = d;
    }
  // voxel centres between two organs a gap apart lie on bridges of length
  // gap; nearest is the shortest bridge through a voxel centre
  double want = fmax(gap, 0);
  if (isfinite(nearest)) want = fmax(want, nearest);
  want = want * (1 + 1e-3) + 1e-3 * h;
  return PREP_FAIL(ctx, FASCIA_ERR_ARGUMENT,
                   "tissue '%s' (scene '%s'): organs '%s' and '%s' are too far apart for max_gap %g m: their "
                   "surfaces are %.3g mm apart, and every point of a tissue lies on a path of at most max_gap "
                   "between two organs it connects%s; raise max_gap to at least %.3g m, or leave '%s' or '%s' out "
                   "of this tissue",
                   td->name, scene->path, scene->organs[a].name, scene->organs[b].name, td->max_gap,
                   1e3 * fmax(gap, 0), td->region_organ >= 0 ? " (ending on the region's parts)" : "", want,
                   scene->organs[a].name, scene->organs[b].name);
}

// ------------------------------------------------------------ regions

// Labels 26-connected pieces of the region with this label (a tissue or a
// deformable organ's inside); drops pieces below min_component into rep.
static fascia_status keep_components(fascia_ctx *ctx, const char *name, fascia_prep_volume *vol, uint8_t label,
                                     double min_component, fascia_prep_tissue_report *rep) {
  const prep_grid g = prep_volume_grid(vol);
  const int64_t n = prep_grid_count(&g);
  int64_t *queue = prep_calloc(n, sizeof(int64_t));
  uint8_t *seen = prep_calloc(n, 1);
  if (!queue || !seen) {
    free(queue);
    free(seen);
    return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "%s: out of memory", name);
  }
  const double voxel_volume = g.h * g.h * g.h;
  for (int64_t s = 0; s < n; ++s) {
    if (vol->region[s] != label || seen[s]) continue;
    int64_t head = 0, tail = 0;
    queue[tail++] = s;
    seen[s] = 1;
    while (head < tail) {
      int64_t nb[26];
      const int m = prep_grid_neighbours(&g, queue[head++], nb, NULL);
      for (int k = 0; k < m; ++k)
        if (vol->region[nb[k]] == label && !seen[nb[k]]) seen[nb[k]] = 1, queue[tail++] = nb[k];
    }
    const double volume = (double)tail * voxel_volume;
    if (volume < min_component) {
      for (int64_t k = 0; k < tail; ++k) vol->region[queue[k]] = 0;
      rep->dropped_components++;
      rep->dropped_volume += volume;
    } else {
      rep->components++;
      rep->voxels += tail;
      rep->volume += volume;
    }
  }
  free(queue);
  free(seen);
  return FASCIA_OK;
}

// The label that occupies world point x (meshes->occupied: a label the
// scene neither models nor declares connective), 0 for none. A point on a
// face between image voxels is occupied only when the voxels on both sides
// are: a voxel centre of the scene on the face of an organ made of labels
// (or of a mesh organ that follows them) is free.
static int32_t occupied_label(const fascia_prep_meshes *meshes, const double *x) {
  if (!meshes->occupied) return 0;
  const double *w = meshes->occupied_from_world;
  int32_t lo[3], hi[3];
  for (int r = 0; r < 3; ++r) {
    const double f = w[4 * r] * x[0] + w[4 * r + 1] * x[1] + w[4 * r + 2] * x[2] + w[4 * r + 3];
    lo[r] = hi[r] = (int32_t)fmax(-1, fmin(floor(f + 0.5), meshes->occupied_dims[r]));
    if (fabs(f - floor(f) - 0.5) < 1e-6) lo[r] = (int32_t)floor(f), hi[r] = lo[r] + 1;
  }
  int32_t label = 0;
  for (int32_t k = lo[2]; k <= hi[2]; ++k)
    for (int32_t j = lo[1]; j <= hi[1]; ++j)
      for (int32_t i = lo[0]; i <= hi[0]; ++i) {
        const int32_t *d = meshes->occupied_dims;
        if (i < 0 || j < 0 || k < 0 || i >= d[0] || j >= d[1] || k >= d[2]) return 0;
        const int32_t here = meshes->occupied[i + (int64_t)d[0] * (j + (int64_t)d[1] * k)];
        if (!here) return 0;
        label = here;
      }
  return label;
}

// Per label, the voxels of tissue t it occupied; the largest into its report.
static void report_occupied(const int64_t *voxels_of, double voxel_volume, fascia_prep_tissue_report *rep) {
  for (int32_t v = 1; v <= 65535; ++v) {
    if (!voxels_of[v]) continue;
    const double volume = (double)voxels_of[v] * voxel_volume;
    rep->occupied_volume += volume;
    int at = 4;
    while (at > 0 && (!rep->occupied_labels[at - 1] || rep->occupied_label_volume[at - 1] < volume)) --at;
    if (at == 4) continue;
    memmove(rep->occupied_labels + at + 1, rep->occupied_labels + at, (size_t)(3 - at) * sizeof(int32_t));
    memmove(rep->occupied_label_volume + at + 1, rep->occupied_label_volume + at, (size_t)(3 - at) * sizeof(fascia_real));
    rep->occupied_labels[at] = v;
    rep->occupied_label_volume[at] = volume;
  }
}

// The shortest bridge d_A + d_B through voxel v over the pairs (A, B) of
// the organs tissue td connects (parts: the distance to its region's named
// parts, or NULL), and in *pair (when not NULL) that pair's index in the
// order (0, 1), (0, 2) .. (1, 2) .. of td->organs.
static double shortest_bridge(const fascia_prep_tissue_def *td, const fascia_prep_volume *vol, const float *parts,
                              int64_t v, int32_t *pair) {
  double shortest = INFINITY;
  for (int32_t i = 0, p = 0; i < td->organ_count; ++i)
    for (int32_t j = i + 1; j < td->organ_count; ++j, ++p) {
      double d[2];
      for (int e = 0; e < 2; ++e) {
        const int32_t o = td->organs[e ? j : i];
        d[e] = parts && o == td->region_organ ? parts[v] : vol->distance[o][v];
      }
      if (d[0] + d[1] < shortest) {
        shortest = d[0] + d[1];
        if (pair) *pair = p;
      }
    }
  return shortest;
}

// 1 when a face neighbour of voxel v lies inside an organ.
static int on_organ_face(const fascia_prep_volume *vol, const prep_grid *g, int64_t v) {
  int32_t c[3];
  prep_grid_ijk(g, v, c);
  for (int r = 0; r < 3; ++r)
    for (int side = -1; side <= 1; side += 2) {
      int32_t e[3] = {c[0], c[1], c[2]};
      e[r] += side;
      if (e[r] < 0 || e[r] >= g->dims[r]) continue;
      const int64_t w = prep_grid_index(g, e[0], e[1], e[2]);
      for (int32_t o = 0; o < vol->organ_count; ++o)
        if (vol->distance[o] && vol->distance[o][w] <= 0) return 1;
    }
  return 0;
}

// Builds region labels of tissue t on the volume grid; distances are ready.
static fascia_status build_region(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                  fascia_prep_volume *vol, int32_t t) {
  const fascia_prep_tissue_def *td = scene->tissues + t;
  const prep_grid g = prep_volume_grid(vol);
  const int64_t n = prep_grid_count(&g);
  float *parts = NULL;
  int64_t *voxels_of = NULL; // per label, the tissue's voxels it occupies
  fascia_status status = FASCIA_OK;
  char names[256];
  organ_list(scene, td, names, sizeof names);
  if (td->region_organ >= 0) {
    // distance to the named parts only
    const fascia_prep_mesh *o = meshes->organs + td->region_organ;
    int32_t *sub = prep_calloc(3 * (int64_t)o->triangle_count, sizeof(int32_t));
    parts = prep_calloc(n, sizeof(float));
    PREP_CHECK_GOTO(sub && parts, ctx, FASCIA_ERR_MEMORY, "tissue '%s': out of memory", td->name);
    int32_t count = 0;
    for (int32_t k = 0; k < td->region_parts.count; ++k) {
      const int32_t p = prep_mesh_part(o, td->region_parts.names[k]);
      if (p < 0) {
        free(sub);
        PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_FORMAT,
                        "scene '%s' tissues[%d].region.parts.names[%d]: organ '%s' has no part '%s' among the parts "
                        "it uses",
                        scene->path, (int)t, (int)k, o->name, td->region_parts.names[k]);
      }
      for (int32_t f = 0; f < o->triangle_count; ++f)
        if (o->triangle_part[f] == p) memcpy(sub + 3 * (int64_t)count++, o->triangles + 3 * (int64_t)f, 12);
    }
    status = fascia_vdb_unsigned_distance(ctx, o->vertex_count, o->vertices, count, sub, g.h,
                                          (float)(td->max_gap / g.h + 2), g.lo, g.dims, parts);
    free(sub);
    if (status != FASCIA_OK) goto cleanup;
  }
  int64_t gap_voxels = 0, cut_voxels = 0, occupied_voxels = 0;
  if (meshes->occupied) voxels_of = prep_calloc(65536, sizeof(int64_t));
  PREP_CHECK_GOTO(voxels_of || !meshes->occupied, ctx, FASCIA_ERR_MEMORY, "tissue '%s': out of memory", td->name);
  double nearest = INFINITY; // shortest bridge (d_A + d_B over the pairs) through a free voxel
  const int32_t K = td->organ_count;
  for (int64_t v = 0; v < n; ++v) {
    int outside = 1;
    for (int32_t o = 0; o < vol->organ_count && outside; ++o)
      if (vol->distance[o] && vol->distance[o][v] <= 0) outside = 0;
    if (!outside) continue;
    // the voxel lies on a path from organ A to organ B no longer than
    // max_gap when d_A + d_B <= max_gap: the tissue is the union of such
    // bridges over every pair of its organs, so each piece touches both
    const double shortest = shortest_bridge(td, vol, parts, v, NULL);
    if (shortest < nearest) nearest = shortest;
    if (shortest > td->max_gap) continue;
    ++gap_voxels;
    double x[3];
    prep_grid_center(&g, v, x);
    if (!prep_region_contains(&td->region, x)) continue;
    if (vol->region[v]) continue; // an earlier tissue owns it
    if (shortest < td->min_gap) { // organs this close slide on each other: no tissue bonds them
      vol->tissues[t].slide_volume += g.h * g.h * g.h;
      continue;
    }
    const int32_t label = occupied_label(meshes, x);
    if (label) {
      ++occupied_voxels, ++voxels_of[label];
      continue;
    }
    vol->region[v] = (uint8_t)(t + 1);
    ++cut_voxels;
  }
  if (voxels_of) report_occupied(voxels_of, g.h * g.h * g.h, vol->tissues + t);
  if (gap_voxels == 0) {
    double band = INFINITY; // distances are clamped beyond the band: nearest is exact below it
    for (int32_t k = 0; k < td->organ_count; ++k) band = fmin(band, vol->band[td->organs[k]]);
    status = too_far_apart(ctx, scene, meshes, td, nearest < 0.999 * band ? nearest : INFINITY);
    goto cleanup;
  }
  PREP_CHECK_GOTO(cut_voxels > 0 || occupied_voxels > 0 || vol->tissues[t].slide_volume == 0, ctx,
                  FASCIA_ERR_ARGUMENT,
                  "tissue '%s' (scene '%s' tissues[%d].min_gap): its organs %s are nowhere %g m or more apart, so they "
                  "slide on each other everywhere and no tissue joins them; lower min_gap (0 bonds them down to "
                  "contact)",
                  td->name, scene->path, (int)t, names, td->min_gap);
  PREP_CHECK_GOTO(cut_voxels > 0 || occupied_voxels > 0, ctx, FASCIA_ERR_ARGUMENT,
                  "tissue '%s' (scene '%s' tissues[%d].region): the region selects nothing of the %.3g cm^3 between "
                  "organs %s; check its coordinates (metres, scene frame)",
                  td->name, scene->path, (int)t, 1e6 * (double)gap_voxels * g.h * g.h * g.h, names);
  char what[FASCIA_NAME_SIZE + 16];
  snprintf(what, sizeof what, "tissue '%s'", td->name);
  PREP_TRY_GOTO(keep_components(ctx, what, vol, (uint8_t)(t + 1), td->min_component, vol->tissues + t));
  // per pair of its organs, the kept voxels whose shortest bridge joins them
  vol->tissues[t].pair_volume = prep_calloc((int64_t)K * (K - 1) / 2 + 1, sizeof(fascia_real));
  PREP_CHECK_GOTO(vol->tissues[t].pair_volume, ctx, FASCIA_ERR_MEMORY, "tissue '%s': out of memory", td->name);
  for (int64_t v = 0; v < n; ++v) {
    if (vol->region[v] != t + 1) continue;
    vol->tissues[t].organ_face_voxels += on_organ_face(vol, &g, v);
    int32_t pair = 0;
    shortest_bridge(td, vol, parts, v, &pair);
    vol->tissues[t].pair_volume[pair] += g.h * g.h * g.h;
  }
  if (vol->tissues[t].voxels == 0 && occupied_voxels > 0) {
    char labels[512];
    fascia_prep_occupied_text(scene, vol->tissues + t, labels, sizeof labels);
    PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_ARGUMENT,
                    "tissue '%s' (scene '%s'): labels the scene does not model occupy the space between organs %s "
                    "(%s; %.3g cm^3 left, in pieces smaller than min_component); list them in "
                    "segmentation.connective if tissue may take their voxels",
                    td->name, scene->path, names, labels, 1e6 * vol->tissues[t].dropped_volume);
  }
  PREP_CHECK_GOTO(vol->tissues[t].voxels > 0, ctx, FASCIA_ERR_ARGUMENT,
                  "tissue '%s': every piece of its region is smaller than min_component %g m^3 (largest dropped "
                  "volume %g m^3 in %d pieces); lower min_component or frame_spacing",
                  td->name, td->min_component, vol->tissues[t].dropped_volume, (int)vol->tissues[t].dropped_components);
cleanup:
  free(parts);
  free(voxels_of);
  return status;
}

// The inside of deformable organ o becomes a region: its inside voxels
// (signed distance <= 0, the complement of the tissues' "outside every
// organ") that no earlier region holds, so an overlap with another deformable
// organ goes to the one listed first; pieces below min_component are dropped.
// material (on the organ's grid og; NULL: all of the inside): a hollow
// organ's wall (organ_material).
static fascia_status build_organ_region(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_volume *vol,
                                        int32_t o, uint8_t label, const uint8_t *material, const prep_grid *og) {
  const fascia_prep_organ_def *od = scene->organs + o;
  const prep_grid g = prep_volume_grid(vol);
  const int64_t n = prep_grid_count(&g);
  const float *d = vol->distance[o];
  PREP_CHECK(d, ctx, FASCIA_ERR_INTERNAL, "voxelize: deformable organ '%s' has no distance field", od->name);
  int64_t claimed = 0;
  for (int64_t v = 0; v < n; ++v) {
    if (d[v] > 0 || vol->region[v]) continue;
    if (material) {
      int32_t c[3];
      prep_grid_ijk(&g, v, c);
      const int32_t x = c[0] + g.lo[0] - og->lo[0], y = c[1] + g.lo[1] - og->lo[1], z = c[2] + g.lo[2] - og->lo[2];
      if (x < 0 || y < 0 || z < 0 || x >= og->dims[0] || y >= og->dims[1] || z >= og->dims[2] ||
          !material[prep_grid_index(og, x, y, z)])
        continue;
    }
    vol->region[v] = label, ++claimed;
  }
  PREP_CHECK(claimed > 0, ctx, FASCIA_ERR_ARGUMENT,
             "deformable organ '%s' (scene '%s'): no voxel of its inside is left at voxel_size %g m (it is thinner "
             "than a voxel, or inside another deformable organ listed before it); lower voxel_size or make it "
             "\"rigid\"",
             od->name, scene->path, g.h);
  char what[FASCIA_NAME_SIZE + 24];
  snprintf(what, sizeof what, "deformable organ '%s'", od->name);
  vol->organ_label[o] = label;
  PREP_TRY(keep_components(ctx, what, vol, label, od->min_component, vol->organ_regions + o));
  PREP_CHECK(vol->organ_regions[o].voxels > 0, ctx, FASCIA_ERR_ARGUMENT,
             "deformable organ '%s': every piece of its inside is smaller than min_component %g m^3 (%d pieces, "
             "%g m^3); lower min_component or frame_spacing",
             od->name, od->min_component, (int)vol->organ_regions[o].dropped_components,
             vol->organ_regions[o].dropped_volume);
  return FASCIA_OK;
}

// Voxels inside both organs a and b, counted on their own grids (the same
// inside voxels as their enclosed volumes, so never more than the smaller).
static int64_t count_both_inside(const uint8_t *in_a, const prep_grid *ga, const uint8_t *in_b,
                                 const prep_grid *gb) {
  int32_t lo[3], hi[3];
  for (int r = 0; r < 3; ++r) {
    lo[r] = ga->lo[r] > gb->lo[r] ? ga->lo[r] : gb->lo[r];
    const int32_t ea = ga->lo[r] + ga->dims[r], eb = gb->lo[r] + gb->dims[r];
    hi[r] = ea < eb ? ea : eb;
    if (hi[r] <= lo[r]) return 0;
  }
  int64_t both = 0;
  for (int32_t z = lo[2]; z < hi[2]; ++z)
    for (int32_t y = lo[1]; y < hi[1]; ++y)
      for (int32_t x = lo[0]; x < hi[0]; ++x)
        both += in_a[prep_grid_index(ga, x - ga->lo[0], y - ga->lo[1], z - ga->lo[2])] &&
                in_b[prep_grid_index(gb, x - gb->lo[0], y - gb->lo[1], z - gb->lo[2])];
  return both;
}

// How far the vertices of organ `from` reach into organ `to` and how close
// they come to it from outside, on the surfaces: u is the exact distance of a
// vertex to the surface of `to` (closest point q on triangle `tri`). The
// vertex is inside `to` when its voxel on the organ grid of `to` is; within
// half a voxel diagonal of the surface the voxel may lie on the other side,
// so there the outward normal of the closest triangle must agree.
static void vertices_against(const fascia_prep_mesh *from, const fascia_prep_mesh *to, const fascia_cgal_tree *tree,
                             const uint8_t *to_inside, const prep_grid *to_grid, double band, double *points,
                             double *closest, int32_t *tri, double *gap, double *depth) {
  const double sure = 0.8661 * to_grid->h;
  // only vertices within the band around the other organ's box can matter
  int32_t count = 0;
  for (int32_t v = 0; v < from->vertex_count; ++v) {
    const double *p = from->vertices + 3 * (int64_t)v;
    int near = 1;
    for (int r = 0; r < 3; ++r) near &= p[r] >= to->bounds[r] - band && p[r] <= to->bounds[3 + r] + band;
    if (near) memcpy(points + 3 * (int64_t)count++, p, 3 * sizeof(double));
  }
  fascia_cgal_tree_closest(tree, count, points, closest, tri);
  for (int32_t v = 0; v < count; ++v) {
    const double *p = points + 3 * (int64_t)v, *q = closest + 3 * (int64_t)v;
    const double e[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
    const double u = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    const int64_t k = prep_grid_locate(to_grid, p);
    int inside = k >= 0 && to_inside[k];
    if (inside && u <= sure && tri[v] >= 0) {
      const int32_t *t = to->triangles + 3 * (int64_t)tri[v];
      const double *a = to->vertices + 3 * (int64_t)t[0], *b = to->vertices + 3 * (int64_t)t[1],
                   *c = to->vertices + 3 * (int64_t)t[2];
      const double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const double n[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]};
      inside = e[0] * n[0] + e[1] * n[1] + e[2] * n[2] < 0;
    }
    if (inside)
      *depth = fmax(*depth, u);
    else
      *gap = fmin(*gap, u);
  }
}

// Overlap and gap of every pair of organs near the grid, measured on the
// surfaces so that neither depends on the voxel size: the gap is the
// smallest distance of a vertex of either organ to the other's surface (exact
// when the closest points include a vertex, as for boxes), the overlap depth
// the largest distance of a vertex inside the other organ to its surface
// (the penetration), and the overlap volume the voxels inside both on the
// organs' own grids.
static fascia_status measure_pairs(fascia_ctx *ctx, const fascia_prep_meshes *meshes, fascia_prep_volume *vol,
                                   uint8_t *const *insides, const prep_grid *organ_grids) {
  const prep_grid g = prep_volume_grid(vol);
  const int32_t O = vol->organ_count;
  fascia_status status = FASCIA_OK;
  fascia_cgal_tree **trees = prep_calloc(O, sizeof *trees);
  int32_t most = 1;
  for (int32_t o = 0; o < O; ++o) most = meshes->organs[o].vertex_count > most ? meshes->organs[o].vertex_count : most;
  // work arrays of one pass: the vertices queried, their closest points and triangles
  double *points = prep_calloc(3 * (int64_t)most, sizeof(double)), *closest = prep_calloc(3 * (int64_t)most, sizeof(double));
  int32_t *triangle = prep_calloc(most, sizeof(int32_t));
  PREP_CHECK_GOTO(trees && points && closest && triangle, ctx, FASCIA_ERR_MEMORY, "voxelize: out of memory");
  for (int32_t o = 0; o < O; ++o) {
    if (!vol->distance[o]) continue;
    const fascia_prep_mesh *m = meshes->organs + o;
    PREP_TRY_GOTO(fascia_cgal_tree_create(ctx, m->vertex_count, m->vertices, m->triangle_count, m->triangles,
                                          trees + o));
  }
  for (int32_t a = 0; a < O; ++a)
    for (int32_t b = a + 1; b < O; ++b) {
      if (!vol->distance[a] || !vol->distance[b]) continue;
      const double band = fmin(vol->band[a], vol->band[b]);
      const double *ba = meshes->organs[a].bounds, *bb = meshes->organs[b].bounds;
      int apart = 0; // boxes farther apart than the band: nothing to measure
      for (int r = 0; r < 3; ++r) apart |= ba[r] > bb[3 + r] + band || bb[r] > ba[3 + r] + band;
      if (apart) continue;
      const int64_t both = count_both_inside(insides[a], organ_grids + a, insides[b], organ_grids + b);
      double depth = 0, gap = INFINITY;
      const fascia_prep_mesh *ma = meshes->organs + a, *mb = meshes->organs + b;
      vertices_against(ma, mb, trees[b], insides[b], organ_grids + b, band, points, closest, triangle, &gap, &depth);
      vertices_against(mb, ma, trees[a], insides[a], organ_grids + a, band, points, closest, triangle, &gap, &depth);
      if (both > 0 || depth > 0) gap = 0;
      if (both > 0) {
        fascia_prep_overlap *grown = realloc(vol->overlaps, (size_t)(vol->overlap_count + 1) * sizeof *grown);
        PREP_CHECK_GOTO(grown, ctx, FASCIA_ERR_MEMORY, "voxelize: out of memory");
        vol->overlaps = grown;
        fascia_prep_overlap *ov = vol->overlaps + vol->overlap_count++;
        ov->a = a;
        ov->b = b;
        ov->volume = (double)both * g.h * g.h * g.h;
        ov->depth = depth;
      }
      vol->closest[a * O + b] = vol->closest[b * O + a] = gap < band ? gap : -1;
    }
cleanup:
  for (int32_t o = 0; trees && o < O; ++o) fascia_cgal_tree_destroy(trees + o);
  free(trees);
  free(points);
  free(closest);
  free(triangle);
  return status;
}

fascia_status prep_organ_labels(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_meshes *meshes,
                                prep_grid *grid, uint16_t **labels) {
  *labels = NULL;
  PREP_CHECK(meshes->count < 65535, ctx, FASCIA_ERR_ARGUMENT, "scene '%s': %d organs are more than a label map holds",
             scene->path, (int)meshes->count);
  const double h = scene->voxel_size;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int32_t o = 0; o < meshes->count; ++o)
    for (int r = 0; r < 3; ++r)
      lo[r] = fmin(lo[r], meshes->organs[o].bounds[r]), hi[r] = fmax(hi[r], meshes->organs[o].bounds[3 + r]);
  PREP_TRY(check_grid(ctx, "the organs' label map", scene->path, h, lo, hi, 2, 3));
  prep_grid_cover(grid, h, lo, hi, 2);
  uint16_t *out = prep_calloc(prep_grid_count(grid), sizeof(uint16_t));
  PREP_CHECK(out, ctx, FASCIA_ERR_MEMORY, "label map: out of memory for %lld voxels", (long long)prep_grid_count(grid));
  fascia_status status = FASCIA_OK;
  for (int32_t o = 0; o < meshes->count && status == FASCIA_OK; ++o) {
    fascia_prep_mesh *m = meshes->organs + o;
    prep_grid og;
    prep_grid_cover(&og, h, m->bounds, m->bounds + 3, 2);
    uint8_t *inside = prep_calloc(prep_grid_count(&og), 1);
    status = inside ? organ_inside(ctx, scene, m, &og, inside, NULL)
                    : PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", m->name);
    for (int64_t v = 0; status == FASCIA_OK && v < prep_grid_count(&og); ++v) {
      if (!inside[v]) continue;
      int32_t c[3];
      prep_grid_ijk(&og, v, c);
      const int64_t at = prep_grid_index(grid, c[0] + og.lo[0] - grid->lo[0], c[1] + og.lo[1] - grid->lo[1],
                                         c[2] + og.lo[2] - grid->lo[2]);
      if (!out[at]) out[at] = (uint16_t)(o + 1); // an overlap goes to the organ listed first
    }
    free(inside);
  }
  if (status != FASCIA_OK) {
    free(out);
    return status;
  }
  *labels = out;
  return FASCIA_OK;
}

fascia_status fascia_prep_voxelize(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_meshes *meshes,
                                   fascia_prep_volume **out) {
  PREP_CHECK(ctx && scene && meshes && out, ctx, FASCIA_ERR_ARGUMENT, "fascia_prep_voxelize: NULL argument");
  *out = NULL;
  const double h = scene->voxel_size;
  fascia_status status = FASCIA_OK;
  uint8_t **insides = NULL; // [organ] inside voxels on the organ's own grid, NULL: not near the grid
  uint8_t **materials = NULL; // [organ] a hollow deformable organ's wall on its grid, else NULL
  prep_grid *organ_grids = NULL;
  float *udf = NULL;
  fascia_prep_volume *vol = calloc(1, sizeof *vol);
  PREP_CHECK(vol, ctx, FASCIA_ERR_MEMORY, "voxelize: out of memory");

  // 1. checks of scale, the union of the tissues' boxes
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    const fascia_prep_tissue_def *td = scene->tissues + t;
    if (td->form != FASCIA_PREP_FORM_VOLUME) { // no region: the grid covers it for the organs' distances
      double a[3], b[3];
      reduced_box(scene, meshes, t, a, b);
      for (int r = 0; r < 3; ++r) lo[r] = fmin(lo[r], a[r]), hi[r] = fmax(hi[r], b[r]);
      continue;
    }
    char names[256], hint[512];
    prep_units_hint_voxel(scene, hint, sizeof hint);
    PREP_CHECK_GOTO(td->max_gap >= 3 * h, ctx, FASCIA_ERR_ARGUMENT,
                    "scene '%s' voxel_size: %g m is too large for tissue '%s' (max_gap %g m): a gap needs at least 3 "
                    "voxels across; set voxel_size to %g m or less%s",
                    scene->path, h, td->name, td->max_gap, td->max_gap / 3, hint);
    double a[3], b[3];
    if (!tissue_box(scene, meshes, t, a, b)) {
      PREP_CHECK_GOTO(td->region.kind == FASCIA_PREP_REGION_NONE, ctx, FASCIA_ERR_ARGUMENT,
                      "tissue '%s' (scene '%s' tissues[%d].region): the region selects nothing: it does not meet the "
                      "space within max_gap of organs %s; check its coordinates (metres, scene frame)",
                      td->name, scene->path, (int)t, organ_list(scene, td, names, sizeof names));
      PREP_TRY_GOTO(too_far_apart(ctx, scene, meshes, td, INFINITY));
    }
    for (int r = 0; r < 3; ++r) lo[r] = fmin(lo[r], a[r]), hi[r] = fmax(hi[r], b[r]);
  }
  // deformable organs: the whole inside is a region
  int32_t deformable = 0;
  for (int32_t o = 0; o < scene->organ_count; ++o) {
    if (scene->organs[o].kind != FASCIA_ORGAN_DEFORMABLE || scene->organs[o].shell) continue; // a shell: a wall
    ++deformable;
    const double *b = meshes->organs[o].bounds;
    for (int r = 0; r < 3; ++r) lo[r] = fmin(lo[r], b[r] - h), hi[r] = fmax(hi[r], b[3 + r] + h);
  }
  PREP_CHECK_GOTO(scene->tissue_count + deformable < 255, ctx, FASCIA_ERR_ARGUMENT,
                  "scene '%s': %d tissues and %d deformable organs make more than 254 regions", scene->path,
                  (int)scene->tissue_count, (int)deformable);
  // region byte, a distance per organ, the work distance, the organ's inside
  PREP_TRY_GOTO(check_grid(ctx, "the tissues' space", scene->path, h, lo, hi, 2, 6 + 4.0 * meshes->count));
  prep_grid g;
  prep_grid_cover(&g, h, lo, hi, 2);
  const int64_t n = prep_grid_count(&g);
  PREP_CHECK_GOTO(n < MAX_VOXELS, ctx, FASCIA_ERR_ARGUMENT,
                  "scene '%s' voxel_size: %g m gives %lld voxels for the tissues' space, more than %lld; raise "
                  "voxel_size",
                  scene->path, h, (long long)n, (long long)MAX_VOXELS);
  vol->voxel_size = h;
  for (int r = 0; r < 3; ++r) {
    vol->lattice[r] = g.lo[r];
    vol->dims[r] = g.dims[r];
    vol->origin[r] = h * g.lo[r];
  }
  vol->organ_count = meshes->count;
  vol->tissue_count = scene->tissue_count;
  vol->region = prep_calloc(n, 1);
  vol->distance = prep_calloc(meshes->count, sizeof(float *));
  vol->band = prep_calloc(meshes->count, sizeof(float));
  vol->tissues = prep_calloc(scene->tissue_count, sizeof *vol->tissues);
  vol->closest = prep_calloc((int64_t)meshes->count * meshes->count, sizeof(double));
  vol->organ_label = prep_calloc(meshes->count, sizeof(int32_t));
  vol->organ_regions = prep_calloc(meshes->count, sizeof *vol->organ_regions);
  PREP_CHECK_GOTO(vol->region && vol->distance && vol->band && vol->tissues && vol->closest && vol->organ_label &&
                      vol->organ_regions,
                  ctx, FASCIA_ERR_MEMORY,
                  "voxelize: out of memory for %lld voxels; raise voxel_size", (long long)n);
  for (int64_t k = 0; k < (int64_t)meshes->count * meshes->count; ++k) vol->closest[k] = -1;

  // 2. every organ whose distance band reaches the grid (every organ of a
  // tissue does, by construction): inside/outside on its own grid, kept
  // for the overlaps, and the signed distance on the volume grid
  insides = prep_calloc(meshes->count, sizeof(uint8_t *));
  materials = prep_calloc(meshes->count, sizeof(uint8_t *));
  organ_grids = prep_calloc(meshes->count, sizeof(prep_grid));
  PREP_CHECK_GOTO(insides && materials && organ_grids, ctx, FASCIA_ERR_MEMORY, "voxelize: out of memory");
  for (int32_t o = 0; o < meshes->count; ++o) {
    fascia_prep_mesh *m = meshes->organs + o;
    const double band = organ_band(scene, o);
    if (!box_meets_grid(&g, m->bounds, m->bounds + 3, band)) continue;
    fascia_ctx_progress(ctx, "voxelize", (double)o / meshes->count, m->name);
    char what[FASCIA_NAME_SIZE + 16];
    snprintf(what, sizeof what, "organ '%s'", m->name);
    PREP_TRY_GOTO(check_grid(ctx, what, scene->path, h, m->bounds, m->bounds + 3, 2, 1));
    prep_grid *og = organ_grids + o;
    prep_grid_cover(og, h, m->bounds, m->bounds + 3, 2);
    const int64_t on = prep_grid_count(og);
    PREP_CHECK_GOTO(on < MAX_VOXELS, ctx, FASCIA_ERR_ARGUMENT,
                    "organ '%s': voxel_size %g m gives %lld voxels for its box, more than %lld; raise voxel_size",
                    m->name, h, (long long)on, (long long)MAX_VOXELS);
    uint8_t *inside = insides[o] = prep_calloc(on, 1);
    udf = prep_calloc(n, sizeof(float));
    PREP_CHECK_GOTO(inside && udf, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory for %lld voxels", m->name,
                    (long long)on);
    const int solid = scene->organs[o].kind == FASCIA_ORGAN_DEFORMABLE && !scene->organs[o].shell;
    if (solid) {
      materials[o] = prep_calloc(on, 1);
      PREP_CHECK_GOTO(materials[o], ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", m->name);
    }
    PREP_TRY_GOTO(organ_inside(ctx, scene, m, og, inside, materials[o]));
    if (solid) {
      int hollow = 0;
      PREP_TRY_GOTO(organ_material(ctx, scene, m, og, inside, materials[o], &hollow));
      if (!hollow) free(materials[o]), materials[o] = NULL;
    }
    PREP_TRY_GOTO(fascia_vdb_unsigned_distance(ctx, m->vertex_count, m->vertices, m->triangle_count, m->triangles, h,
                                               (float)(band / h), g.lo, g.dims, udf));
    // the sign is the inside rule's alone: d <= 0 exactly for its inside
    // voxels, so a centre on the surface that the rule leaves outside gets
    // a distance just above 0, not the 0 that would count it inside
    for (int64_t v = 0; v < n; ++v) {
      int32_t c[3];
      prep_grid_ijk(&g, v, c);
      const int32_t x = c[0] + g.lo[0] - og->lo[0], y = c[1] + g.lo[1] - og->lo[1], z = c[2] + g.lo[2] - og->lo[2];
      const int in = x >= 0 && y >= 0 && z >= 0 && x < og->dims[0] && y < og->dims[1] && z < og->dims[2] &&
                     inside[prep_grid_index(og, x, y, z)];
      udf[v] = in ? -udf[v] : fmaxf(udf[v], FLT_MIN);
    }
    vol->distance[o] = udf;
    vol->band[o] = (float)band;
    udf = NULL;
  }
  for (int32_t t = 0; t < scene->tissue_count; ++t)
    for (int32_t k = 0; scene->tissues[t].form == FASCIA_PREP_FORM_VOLUME && k < scene->tissues[t].organ_count; ++k)
      PREP_CHECK_GOTO(vol->distance[scene->tissues[t].organs[k]], ctx, FASCIA_ERR_INTERNAL,
                      "voxelize: organ %d of tissue '%s' has no distance field", (int)scene->tissues[t].organs[k],
                      scene->tissues[t].name);

  // 3. overlaps and gaps, then each tissue's region
  PREP_TRY_GOTO(measure_pairs(ctx, meshes, vol, insides, organ_grids));
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    fascia_ctx_progress(ctx, "voxelize", 0.9, scene->tissues[t].name);
    if (scene->tissues[t].form == FASCIA_PREP_FORM_VOLUME) PREP_TRY_GOTO(build_region(ctx, scene, meshes, vol, t));
  }
  for (int32_t o = 0, label = scene->tissue_count + 1; o < scene->organ_count; ++o)
    if (scene->organs[o].kind == FASCIA_ORGAN_DEFORMABLE && !scene->organs[o].shell) {
      fascia_ctx_progress(ctx, "voxelize", 0.95, scene->organs[o].name);
      PREP_TRY_GOTO(build_organ_region(ctx, scene, vol, o, (uint8_t)label++, materials[o], organ_grids + o));
    }
  fascia_ctx_progress(ctx, "voxelize", 1, "done");
  *out = vol;
  vol = NULL;
cleanup:
  for (int32_t o = 0; insides && o < meshes->count; ++o) free(insides[o]);
  free(insides);
  for (int32_t o = 0; materials && o < meshes->count; ++o) free(materials[o]);
  free(materials);
  free(organ_grids);
  free(udf);
  fascia_prep_volume_destroy(&vol);
  return status;
}
