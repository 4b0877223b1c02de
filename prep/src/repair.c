// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Stage 2, check and repair: each part of each organ goes through the CGAL
// adapter (duplicate vertices, degenerate and duplicate faces, pinched
// vertices, consistent orientation, closed components outward, small holes,
// self-intersections counted). Parts are repaired one by one, so that part
// names survive for coupling rules and region selections.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "prep_util.h"

// Largest hole filled: at most this many border edges ...
#define MAX_HOLE_EDGES 64

// Enclosed volume of a surface, open or closed: per connected component,
// the signed volume of its triangles with every border loop capped by a fan
// to the component's vertex centroid (the fan triangles themselves add
// nothing about that point, so they need not be built); |sum| per component,
// added. Exact for closed components; for an open one, the volume its holes
// close around. A flat surface (one triangle, a square, a box of zero height)
// gives 0 however its holes are closed. -1 when out of memory.
static double enclosed_volume(const fascia_prep_mesh *o) {
  const int32_t NV = o->vertex_count;
  int32_t *root = prep_calloc(NV, sizeof(int32_t));
  double *sum = prep_calloc(4 * (int64_t)NV, sizeof(double)); // per root: x, y, z sums, vertex count
  double *volume = prep_calloc(NV, sizeof(double));
  if (!root || !sum || !volume) {
    free(root);
    free(sum);
    free(volume);
    return -1;
  }
  for (int32_t v = 0; v < NV; ++v) root[v] = v;
#define FIND(x)                                                                                                       \
  do {                                                                                                                \
    while (root[x] != x) x = root[x] = root[root[x]];                                                                 \
  } while (0)
  for (int32_t t = 0; t < o->triangle_count; ++t)
    for (int r = 1; r < 3; ++r) {
      int32_t a = o->triangles[3 * (int64_t)t], b = o->triangles[3 * (int64_t)t + r];
      FIND(a);
      FIND(b);
      if (a != b) root[a > b ? a : b] = a < b ? a : b;
    }
  for (int32_t v = 0; v < NV; ++v) {
    int32_t c = v;
    FIND(c);
    root[v] = c;
    for (int r = 0; r < 3; ++r) sum[4 * (int64_t)c + r] += o->vertices[3 * (int64_t)v + r];
    sum[4 * (int64_t)c + 3] += 1;
  }
#undef FIND
  for (int32_t t = 0; t < o->triangle_count; ++t) {
    const int32_t *tri = o->triangles + 3 * (int64_t)t;
    const int32_t c = root[tri[0]];
    double e[3][3];
    for (int k = 0; k < 3; ++k)
      for (int r = 0; r < 3; ++r)
        e[k][r] = o->vertices[3 * (int64_t)tri[k] + r] - sum[4 * (int64_t)c + r] / sum[4 * (int64_t)c + 3];
    volume[c] += (e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                  e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0])) / 6;
  }
  double total = 0;
  for (int32_t v = 0; v < NV; ++v) total += fabs(volume[v]);
  free(root);
  free(sum);
  free(volume);
  return total;
}

// An organ must enclose something: a flat or otherwise empty surface would
// become, by the hole closing of the inside/outside rules, a slab that is
// not in the mesh. "No volume" is relative to the organ's size (rounding).
static fascia_status check_encloses(fascia_ctx *ctx, const fascia_prep_scene *scene, int32_t k,
                                    const fascia_prep_mesh *o) {
  const double volume = enclosed_volume(o);
  PREP_CHECK(volume >= 0, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", o->name);
  double diagonal = 0;
  for (int r = 0; r < 3; ++r) diagonal += (o->bounds[3 + r] - o->bounds[r]) * (o->bounds[3 + r] - o->bounds[r]);
  diagonal = sqrt(diagonal);
  PREP_CHECK(volume > 1e-9 * diagonal * diagonal * diagonal, ctx, FASCIA_ERR_FORMAT,
             "organ '%s' (scene '%s' organs[%d].mesh '%s'): its surface encloses no volume (%.3g m^3 inside %.3g "
             "cm^2 of surface, %d border edges: flat, or an open patch); closing its holes would only make a slab. "
             "Give a closed surface, or choose the parts that enclose the organ",
             o->name, scene->path, (int)k, scene->organs[k].mesh, volume, 1e4 * o->report.area,
             (int)o->report.border_edges);
  return FASCIA_OK;
}

static fascia_status repair_organ(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_mesh *o) {
  fascia_status status = FASCIA_OK;
  const int32_t NV = o->vertex_count, NT = o->triangle_count;
  int32_t *map = prep_calloc(NV, sizeof(int32_t));
  double *pv = prep_calloc(3 * (int64_t)NV, sizeof(double));
  int32_t *pt = prep_calloc(3 * (int64_t)NT, sizeof(int32_t));
  double *nv_all = NULL, *rv = NULL;
  int32_t *nt_all = NULL, *np_all = NULL, *rt = NULL;
  int64_t nv_count = 0, nt_count = 0, nv_cap = 0, nt_cap = 0;
  PREP_CHECK_GOTO(map && pv && pt, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory for the repair", o->name);
  fascia_prep_mesh_report *rep = &o->report;
  const int32_t parts_used = rep->parts_used;
  memset(rep, 0, sizeof *rep);
  rep->parts_used = parts_used;
  // holes up to close_holes across (at least 2 voxels) are filled with triangles
  const double max_hole = fmax(2 * scene->voxel_size, scene->close_holes);
  for (int32_t part = 0; part < o->part_count; ++part) {
    for (int32_t v = 0; v < NV; ++v) map[v] = -1;
    int32_t n_v = 0, n_t = 0;
    for (int32_t t = 0; t < NT; ++t) {
      if (o->triangle_part[t] != part) continue;
      for (int r = 0; r < 3; ++r) {
        const int32_t v = o->triangles[3 * (int64_t)t + r];
        if (map[v] < 0) {
          map[v] = n_v;
          memcpy(pv + 3 * (int64_t)n_v, o->vertices + 3 * (int64_t)v, 3 * sizeof(double));
          ++n_v;
        }
        pt[3 * (int64_t)n_t + r] = map[v];
      }
      ++n_t;
    }
    if (n_t == 0) continue;
    char what[192];
    snprintf(what, sizeof what, "organ '%s' part '%s'", o->name, o->part_names[part]);
    fascia_ctx_progress(ctx, "check and repair", -1, what);
    fascia_cgal_report r;
    int32_t rnv = 0, rnt = 0;
    PREP_TRY_GOTO(fascia_cgal_repair(ctx, what, n_v, pv, n_t, pt, MAX_HOLE_EDGES, max_hole, 1, &rv, &rnv, &rt, &rnt,
                                     &r));
    rep->duplicate_vertices_merged += r.duplicate_vertices_merged;
    rep->degenerate_faces_removed += r.degenerate_faces_removed;
    rep->duplicate_faces_removed += r.duplicate_faces_removed;
    rep->nonmanifold_vertices_split += r.nonmanifold_vertices_split;
    rep->components += r.components;
    rep->closed_components += r.closed_components;
    rep->components_reoriented += r.components_reoriented;
    rep->border_edges += r.border_edges;
    rep->holes_filled += r.holes_filled;
    rep->holes_left += r.holes_left;
    rep->self_intersections += r.self_intersections;
    rep->area += r.area;
    if (nv_count + rnv > nv_cap) {
      nv_cap = 2 * (nv_count + rnv);
      double *g = realloc(nv_all, (size_t)(3 * nv_cap) * sizeof(double));
      PREP_CHECK_GOTO(g, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", o->name);
      nv_all = g;
    }
    if (nt_count + rnt > nt_cap) {
      nt_cap = 2 * (nt_count + rnt);
      int32_t *g = realloc(nt_all, (size_t)(3 * nt_cap) * sizeof(int32_t));
      PREP_CHECK_GOTO(g, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", o->name);
      nt_all = g;
      g = realloc(np_all, (size_t)nt_cap * sizeof(int32_t));
      PREP_CHECK_GOTO(g, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", o->name);
      np_all = g;
    }
    memcpy(nv_all + 3 * nv_count, rv, 3 * (size_t)rnv * sizeof(double));
    for (int32_t t = 0; t < rnt; ++t) {
      for (int r3 = 0; r3 < 3; ++r3) nt_all[3 * (nt_count + t) + r3] = (int32_t)nv_count + rt[3 * t + r3];
      np_all[nt_count + t] = part;
    }
    nv_count += rnv;
    nt_count += rnt;
    free(rv);
    free(rt);
    rv = NULL;
    rt = NULL;
  }
  PREP_CHECK_GOTO(nt_count > 0, ctx, FASCIA_ERR_FORMAT, "organ '%s': no usable triangle is left after the repair",
                  o->name);
  free(o->vertices);
  free(o->triangles);
  free(o->triangle_part);
  o->vertices = nv_all;
  o->triangles = nt_all;
  o->triangle_part = np_all;
  o->vertex_count = (int32_t)nv_count;
  o->triangle_count = (int32_t)nt_count;
  nv_all = NULL;
  nt_all = np_all = NULL;
cleanup:
  free(map);
  free(pv);
  free(pt);
  free(rv);
  free(rt);
  free(nv_all);
  free(nt_all);
  free(np_all);
  return status;
}

fascia_status fascia_prep_repair(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_meshes *meshes) {
  PREP_CHECK(ctx && scene && meshes, ctx, FASCIA_ERR_ARGUMENT, "fascia_prep_repair: NULL argument");
  for (int32_t k = 0; k < meshes->count; ++k) {
    fascia_ctx_progress(ctx, "check and repair", (double)k / meshes->count, meshes->organs[k].name);
    PREP_TRY(repair_organ(ctx, scene, meshes->organs + k));
    // a shell is its wall, the surface itself: an open or flat patch is one (docs/organs.md)
    if (!scene->organs[k].shell) PREP_TRY(check_encloses(ctx, scene, k, meshes->organs + k));
  }
  fascia_ctx_progress(ctx, "check and repair", 1, "done");
  return FASCIA_OK;
}
