// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Strands and sheets in a scene (data/scenes/README.md, "Strands and sheets"): the
// frames and samples of a tissue whose form is a curve or a surface, built
// from the scene's geometry instead of a voxel region.
//
//   strand  the straight segment between its two attachments, each the
//           closest point of its organ's surface to the point given (within
//           the attachment's radius); frames at equal intervals no longer
//           than frame_spacing, the two end frames on the organs (shared:
//           the coupling stage couples them); per interval one station at
//           its middle with q x q section points over a square of the
//           strand's area (fascia_shape_section_points, as the beam's
//           strand), each of volume interval x area x its fraction;
//   sheet   the mesh's (merged) vertices are its frames, a vertex within the
//           coupling tolerance of an organ moved onto it (shared); per
//           triangle its centroid, with q points through the thickness
//           along the triangle's normal, volume triangle area x thickness x
//           weights.
//
// Each sample records the frames of its interval or triangle; the shape
// functions stage gives it fascia_shape_mls_adaptive's weights over them
// (linear along the interval or over the triangle). So the samples of a
// strand add up to length x area, of a sheet to area x thickness.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/shape.h"
#include "prep_util.h"
#include "reduced.h"

void prep_reduced_free(prep_reduced *r) {
  free(r->frame_position);
  free(r->frame_organ);
  free(r->frame_triangle);
  free(r->sample_position);
  free(r->sample_volume);
  free(r->sample_cell);
  memset(r, 0, sizeof *r);
}

static void sub3(const double *a, const double *b, double *out) {
  for (int r = 0; r < 3; ++r) out[r] = a[r] - b[r];
}
static double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void cross3(const double *a, const double *b, double *out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}
static double norm3(const double *a) { return sqrt(dot3(a, a)); }

static fascia_status tree_of(fascia_ctx *ctx, const fascia_prep_meshes *meshes, fascia_cgal_tree **trees, int32_t o) {
  if (trees[o]) return FASCIA_OK;
  const fascia_prep_mesh *m = meshes->organs + o;
  return fascia_cgal_tree_create(ctx, m->vertex_count, m->vertices, m->triangle_count, m->triangles, trees + o);
}

static fascia_status reserve(fascia_ctx *ctx, prep_reduced *r, int64_t frames, int64_t samples) {
  PREP_CHECK(frames < INT32_MAX / 4 && samples < INT32_MAX / 4, ctx, FASCIA_ERR_MEMORY,
             "strand or sheet: %lld frames and %lld samples is too many", (long long)frames, (long long)samples);
  r->frame_position = prep_calloc(3 * frames, sizeof(double));
  r->frame_organ = prep_calloc(frames, sizeof(int32_t));
  r->frame_triangle = prep_calloc(frames, sizeof(int32_t));
  r->sample_position = prep_calloc(3 * samples, sizeof(double));
  r->sample_volume = prep_calloc(samples, sizeof(double));
  r->sample_cell = prep_calloc(3 * samples, sizeof(int32_t));
  PREP_CHECK(r->frame_position && r->frame_organ && r->frame_triangle && r->sample_position && r->sample_volume &&
                 r->sample_cell,
             ctx, FASCIA_ERR_MEMORY, "strand or sheet: out of memory for %lld samples", (long long)samples);
  return FASCIA_OK;
}

// Signed distance of organ o at x from the voxel holding it; INFINITY when
// the organ has no field or x lies off the grid (far from it).
static double distance_at(const fascia_prep_volume *vol, const prep_grid *g, int32_t o, const double *x) {
  if (!vol->distance[o]) return INFINITY;
  const int64_t v = prep_grid_locate(g, x);
  return v < 0 ? INFINITY : vol->distance[o][v];
}

// ------------------------------------------------------------ strands

// The attachment's point moved onto its organ: the closest surface point,
// refused when farther than its radius.
static fascia_status attach(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                            fascia_cgal_tree **trees, int32_t t, const char *key, const fascia_prep_attachment *a,
                            double *x, int32_t *triangle) {
  PREP_TRY(tree_of(ctx, meshes, trees, a->organ));
  fascia_cgal_tree_closest(trees[a->organ], 1, a->point, x, triangle);
  double d[3];
  sub3(x, a->point, d);
  const double dist = norm3(d);
  PREP_CHECK(dist <= a->radius, ctx, FASCIA_ERR_ARGUMENT,
             "scene '%s' tissues[%d].%s: point (%g %g %g) lies on no organ: the surface of '%s' is %.3g mm from it, "
             "farther than its radius %.3g mm; move the point onto the organ (nearest surface point (%g %g %g)) or "
             "raise %s.radius",
             scene->path, (int)t, key, a->point[0], a->point[1], a->point[2], scene->organs[a->organ].name, 1e3 * dist,
             1e3 * a->radius, x[0], x[1], x[2], key);
  return FASCIA_OK;
}

// A part of an organ's mesh as a closest-point tree of its own; *first_of
// maps the tree's triangle k back to the organ's: part_triangles[k].
typedef struct part_tree {
  fascia_cgal_tree *tree;
  int32_t *triangles; ///< [count] the organ's triangle indices of the part
  int32_t count;
} part_tree;

static fascia_status part_tree_create(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                      int32_t t, const char *key, const fascia_prep_attachment *a, part_tree *out) {
  memset(out, 0, sizeof *out);
  const fascia_prep_mesh *m = meshes->organs + a->organ;
  const int32_t part = prep_mesh_part(m, a->part);
  PREP_CHECK(part >= 0, ctx, FASCIA_ERR_ARGUMENT,
             "scene '%s' tissues[%d].%s.part: organ '%s' uses no part named '%s' (fascia prep --preview lists what it "
             "read; an organ of one label has one part, named after the organ, an organ of several one per label)",
             scene->path, (int)t, key, m->name, a->part);
  for (int32_t k = 0; k < m->triangle_count; ++k) out->count += m->triangle_part[k] == part;
  PREP_CHECK(out->count > 0, ctx, FASCIA_ERR_ARGUMENT, "scene '%s' tissues[%d].%s.part: part '%s' of organ '%s' has no "
             "triangle", scene->path, (int)t, key, a->part, m->name);
  out->triangles = prep_calloc(out->count, sizeof(int32_t));
  int32_t *corners = prep_calloc(3 * (int64_t)out->count, sizeof(int32_t));
  fascia_status status = out->triangles && corners ? FASCIA_OK
                                                   : PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "strand: out of memory");
  for (int32_t k = 0, n = 0; status == FASCIA_OK && k < m->triangle_count; ++k)
    if (m->triangle_part[k] == part) {
      memcpy(corners + 3 * (int64_t)n, m->triangles + 3 * (int64_t)k, 3 * sizeof(int32_t));
      out->triangles[n++] = k;
    }
  if (status == FASCIA_OK)
    status = fascia_cgal_tree_create(ctx, m->vertex_count, m->vertices, out->count, corners, &out->tree);
  free(corners);
  return status;
}

static void part_tree_free(part_tree *p) {
  fascia_cgal_tree_destroy(&p->tree);
  free(p->triangles);
  p->triangles = NULL;
}

// The point of part p nearest to x, and the organ's triangle holding it.
static void part_closest(const part_tree *p, const double *x, double *out, int32_t *triangle) {
  int32_t k = 0;
  fascia_cgal_tree_closest(p->tree, 1, x, out, &k);
  *triangle = p->triangles[k];
}

// A strand's ends, one or both on parts of their organs: the nearest points
// of the two (alternate projections from a point end, or from part A's
// first vertex; a few rounds settle on the nearest pair of convex-ish parts).
static fascia_status attach_ends(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                 fascia_cgal_tree **trees, int32_t t, double *a, int32_t *ta, double *b,
                                 int32_t *tb) {
  const fascia_prep_tissue_def *td = scene->tissues + t;
  const int on_a = td->from.part[0] != '\0', on_b = td->to.part[0] != '\0';
  if (!on_a) PREP_TRY(attach(ctx, scene, meshes, trees, t, "from", &td->from, a, ta));
  if (!on_b) PREP_TRY(attach(ctx, scene, meshes, trees, t, "to", &td->to, b, tb));
  if (!on_a && !on_b) return FASCIA_OK;
  part_tree pa = {0}, pb = {0};
  fascia_status status = FASCIA_OK;
  if (on_a) PREP_TRY_GOTO(part_tree_create(ctx, scene, meshes, t, "from", &td->from, &pa));
  if (on_b) PREP_TRY_GOTO(part_tree_create(ctx, scene, meshes, t, "to", &td->to, &pb));
  if (on_a && on_b) {
    const fascia_prep_mesh *m = meshes->organs + td->from.organ;
    memcpy(a, m->vertices + 3 * (int64_t)m->triangles[3 * (int64_t)pa.triangles[0]], 3 * sizeof(double));
  }
  for (int round = 0; round < 8; ++round) {
    if (on_b) part_closest(&pb, a, b, tb);
    if (on_a) part_closest(&pa, b, a, ta);
  }
cleanup:
  part_tree_free(&pa);
  part_tree_free(&pb);
  return status;
}

static fascia_status build_strand(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                  const fascia_prep_volume *vol, int32_t t, fascia_cgal_tree **trees,
                                  prep_reduced *out) {
  const fascia_prep_tissue_def *td = scene->tissues + t;
  double a[3], b[3], axis[3];
  int32_t ta, tb;
  PREP_TRY(attach_ends(ctx, scene, meshes, trees, t, a, &ta, b, &tb));
  sub3(b, a, axis);
  const double length = norm3(axis);
  PREP_CHECK(length > 2 * vol->voxel_size, ctx, FASCIA_ERR_ARGUMENT,
             "scene '%s' tissues[%d]: the strand's ends on '%s' and '%s' are %.3g mm apart, less than two voxels "
             "(%.3g mm); give attachment points farther apart",
             scene->path, (int)t, scene->organs[td->from.organ].name, scene->organs[td->to.organ].name, 1e3 * length,
             2e3 * vol->voxel_size);
  for (int r = 0; r < 3; ++r) axis[r] /= length;
  // the straight segment must stay outside every organ (its ends excepted:
  // two voxels at each end, where it leaves its organs' surfaces)
  const prep_grid g = prep_volume_grid(vol);
  const double h = vol->voxel_size, step = h / 2, skip = 2 * h;
  for (double s = skip; s <= length - skip; s += step) {
    double x[3];
    for (int r = 0; r < 3; ++r) x[r] = a[r] + s * axis[r];
    for (int32_t o = 0; o < scene->organ_count; ++o) {
      const double d = distance_at(vol, &g, o, x);
      PREP_CHECK(!(d < -h), ctx, FASCIA_ERR_ARGUMENT,
                 "scene '%s' tissues[%d]: the strand from '%s' to '%s' is straight and would pass through organ '%s' "
                 "(at (%g %g %g), %.3g mm from its end on '%s', %.3g mm inside); move from.point or to.point so the "
                 "line between them stays outside the organs",
                 scene->path, (int)t, scene->organs[td->from.organ].name, scene->organs[td->to.organ].name,
                 scene->organs[o].name, x[0], x[1], x[2], 1e3 * s, scene->organs[td->from.organ].name, -1e3 * d);
    }
  }
  const int32_t intervals = (int32_t)fmax(1, ceil(length / td->frame_spacing - 1e-9));
  const int q = td->section_points;
  const int per_station = q * q;
  PREP_TRY(reserve(ctx, out, intervals + 1, (int64_t)intervals * per_station));
  out->frame_count = intervals + 1;
  for (int32_t i = 0; i <= intervals; ++i) {
    double *x = out->frame_position + 3 * (int64_t)i;
    for (int r = 0; r < 3; ++r) x[r] = i == intervals ? b[r] : a[r] + length * axis[r] * ((double)i / intervals);
    out->frame_organ[i] = i == 0 ? td->from.organ : i == intervals ? td->to.organ : -1;
    out->frame_triangle[i] = i == 0 ? ta : i == intervals ? tb : -1;
  }
  // the section: a square of the strand's area, across the axis
  double u[3], v[3], other[3] = {1, 0, 0};
  if (fabs(axis[0]) > 0.9) other[0] = 0, other[1] = 1;
  cross3(axis, other, u);
  const double nu = norm3(u);
  for (int r = 0; r < 3; ++r) u[r] /= nu;
  cross3(axis, u, v);
  const double side = sqrt(td->area);
  double offset[3 * 16], fraction[16];
  PREP_TRY(fascia_shape_section_points(ctx, 1, q, u, v, side, side, offset, fraction));
  const double interval = length / intervals;
  int32_t s = 0;
  for (int32_t i = 0; i < intervals; ++i) {
    double station[3];
    for (int r = 0; r < 3; ++r)
      station[r] = 0.5 * (out->frame_position[3 * (int64_t)i + r] + out->frame_position[3 * (int64_t)(i + 1) + r]);
    for (int k = 0; k < per_station; ++k, ++s) {
      for (int r = 0; r < 3; ++r) out->sample_position[3 * (int64_t)s + r] = station[r] + offset[3 * k + r];
      out->sample_volume[s] = fraction[k] * interval * td->area;
      out->sample_cell[3 * (int64_t)s] = i;
      out->sample_cell[3 * (int64_t)s + 1] = i + 1;
      out->sample_cell[3 * (int64_t)s + 2] = -1;
    }
  }
  out->sample_count = s;
  out->length = length;
  return FASCIA_OK;
}

// ------------------------------------------------------------ sheets

// One point per triangle, its centroid (times the points through the
// thickness): with weights linear on the triangle, the degree-2 rule's three
// points locked the sheet in bending (as two stations per interval lock a
// strand), and the centroid leaves no mode without stiffness where frames
// carry rotations (docs/mechanics.md, "Strands and sheets").
static const double TRI_RULE[1][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3}};
#define TRI_POINTS 1

static fascia_status build_sheet(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                 const fascia_prep_volume *vol, int32_t t, fascia_cgal_tree **trees,
                                 prep_reduced *out) {
  const fascia_prep_tissue_def *td = scene->tissues + t;
  const fascia_prep_mesh *m = meshes->sheets + t;
  const int32_t V = m->vertex_count, T = m->triangle_count;
  const int q = td->section_points;
  PREP_TRY(reserve(ctx, out, V, TRI_POINTS * (int64_t)T * q));
  out->frame_count = V;
  memcpy(out->frame_position, m->vertices, 3 * (size_t)V * sizeof(double));
  // vertex normals (area-weighted) for the thickness check
  double *normal = prep_calloc(3 * (int64_t)V, sizeof(double));
  PREP_CHECK(normal, ctx, FASCIA_ERR_MEMORY, "sheet: out of memory");
  for (int32_t k = 0; k < T; ++k) {
    const int32_t *c = m->triangles + 3 * (int64_t)k;
    double e1[3], e2[3], n[3];
    sub3(m->vertices + 3 * (int64_t)c[1], m->vertices + 3 * (int64_t)c[0], e1);
    sub3(m->vertices + 3 * (int64_t)c[2], m->vertices + 3 * (int64_t)c[0], e2);
    cross3(e1, e2, n);
    for (int j = 0; j < 3; ++j)
      for (int r = 0; r < 3; ++r) normal[3 * (int64_t)c[j] + r] += n[r];
  }
  // vertices within the coupling tolerance of an organ go onto it (shared)
  const double tol = td->coupling_tolerance;
  fascia_status status = FASCIA_OK;
  for (int32_t i = 0; i < V; ++i) {
    double *x = out->frame_position + 3 * (int64_t)i;
    out->frame_organ[i] = -1;
    out->frame_triangle[i] = -1;
    double best = INFINITY, best_x[3] = {0, 0, 0};
    int32_t best_o = -1, best_tri = -1;
    for (int32_t o = 0; o < scene->organ_count; ++o) {
      const double *bb = meshes->organs[o].bounds;
      int near = 1;
      for (int r = 0; r < 3; ++r) near &= x[r] >= bb[r] - tol && x[r] <= bb[3 + r] + tol;
      if (!near) continue;
      PREP_TRY_GOTO(tree_of(ctx, meshes, trees, o));
      double c[3], d[3];
      int32_t tri;
      fascia_cgal_tree_closest(trees[o], 1, x, c, &tri);
      sub3(c, x, d);
      const double dist = norm3(d);
      if (dist < best) best = dist, best_o = o, best_tri = tri, memcpy(best_x, c, sizeof best_x);
    }
    if (best_o >= 0 && best <= tol) {
      memcpy(x, best_x, sizeof best_x);
      out->frame_organ[i] = best_o;
      out->frame_triangle[i] = best_tri;
    }
  }
  // the layer, thickness wide about the mid-surface, must fit the gap: at a
  // free vertex neither face may lie inside an organ (beyond a voxel)
  {
    const prep_grid g = prep_volume_grid(vol);
    const double h = vol->voxel_size;
    for (int32_t i = 0; i < V; ++i) {
      if (out->frame_organ[i] >= 0) continue;
      double *n = normal + 3 * (int64_t)i;
      const double len = norm3(n);
      if (!(len > 0)) continue;
      const double *x = out->frame_position + 3 * (int64_t)i;
      for (int32_t o = 0; o < scene->organ_count; ++o) {
        const double d0 = distance_at(vol, &g, o, x);
        PREP_CHECK_GOTO(!(d0 < -h), ctx, FASCIA_ERR_ARGUMENT,
                        "scene '%s' tissues[%d].mesh: vertex %d (%g %g %g) lies %.3g mm inside organ '%s', farther "
                        "than the coupling tolerance %.3g mm from its surface; a sheet lies between organs: move or "
                        "cut the mesh there",
                        scene->path, (int)t, (int)i, x[0], x[1], x[2], -1e3 * d0, scene->organs[o].name, 1e3 * tol);
      }
      for (int side = -1; side <= 1; side += 2) {
        double y[3];
        for (int r = 0; r < 3; ++r) y[r] = x[r] + side * 0.5 * td->thickness * n[r] / len;
        for (int32_t o = 0; o < scene->organ_count; ++o) {
          const double d = distance_at(vol, &g, o, y), d0 = distance_at(vol, &g, o, x);
          PREP_CHECK_GOTO(!(d < -h), ctx, FASCIA_ERR_ARGUMENT,
                          "scene '%s' tissues[%d].thickness: %.3g mm is larger than the gap the sheet fills: at "
                          "vertex %d (%g %g %g) its face reaches %.3g mm into organ '%s', whose surface is about "
                          "%.3g mm from the mid-surface; give a thickness of at most about %.3g mm there, or move the "
                          "mesh",
                          scene->path, (int)t, 1e3 * td->thickness, (int)i, x[0], x[1], x[2], -1e3 * d,
                          scene->organs[o].name, 1e3 * fmax(d0, 0), 2e3 * fmax(d0, 0));
        }
      }
    }
  }
  int32_t s = 0;
  double area_sum = 0;
  for (int32_t k = 0; k < T; ++k) {
    const int32_t *c = m->triangles + 3 * (int64_t)k;
    const double *p0 = out->frame_position + 3 * (int64_t)c[0], *p1 = out->frame_position + 3 * (int64_t)c[1],
                 *p2 = out->frame_position + 3 * (int64_t)c[2];
    double e1[3], e2[3], n[3];
    sub3(p1, p0, e1);
    sub3(p2, p0, e2);
    cross3(e1, e2, n);
    const double twice = norm3(n);
    if (!(twice > 1e-12 * (dot3(e1, e1) + dot3(e2, e2)))) continue; // degenerate: no area to integrate
    for (int r = 0; r < 3; ++r) n[r] /= twice;
    double offset[3 * 4], fraction[4];
    PREP_TRY_GOTO(fascia_shape_section_points(ctx, 2, q, n, NULL, td->thickness, 0, offset, fraction));
    const double area = 0.5 * twice;
    area_sum += area;
    for (int a = 0; a < TRI_POINTS; ++a) {
      double station[3];
      for (int r = 0; r < 3; ++r) station[r] = TRI_RULE[a][0] * p0[r] + TRI_RULE[a][1] * p1[r] + TRI_RULE[a][2] * p2[r];
      for (int j = 0; j < q; ++j, ++s) {
        for (int r = 0; r < 3; ++r) out->sample_position[3 * (int64_t)s + r] = station[r] + offset[3 * j + r];
        out->sample_volume[s] = area / TRI_POINTS * fraction[j] * td->thickness;
        memcpy(out->sample_cell + 3 * (int64_t)s, c, 3 * sizeof(int32_t));
      }
    }
  }
  out->sample_count = s;
  out->length = area_sum;
cleanup:
  free(normal);
  return status;
}

fascia_status prep_reduced_build(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                 const fascia_prep_volume *vol, int32_t t, fascia_cgal_tree **trees,
                                 prep_reduced *out) {
  memset(out, 0, sizeof *out);
  const int form = scene->tissues[t].form;
  const fascia_status st = form == FASCIA_PREP_FORM_STRAND ? build_strand(ctx, scene, meshes, vol, t, trees, out)
                                                           : build_sheet(ctx, scene, meshes, vol, t, trees, out);
  if (st != FASCIA_OK) prep_reduced_free(out);
  return st;
}

// ------------------------------------------------------------ a sheet's mesh

static int by_position(const void *pa, const void *pb, void *arg) {
  const double *x = arg;
  const int32_t a = *(const int32_t *)pa, b = *(const int32_t *)pb;
  for (int r = 0; r < 3; ++r) {
    if (x[3 * (int64_t)a + r] < x[3 * (int64_t)b + r]) return -1;
    if (x[3 * (int64_t)a + r] > x[3 * (int64_t)b + r]) return 1;
  }
  return a < b ? -1 : a > b;
}

typedef struct edge_key {
  int32_t a, b;
} edge_key;
static int by_edge(const void *pa, const void *pb) {
  const edge_key *a = pa, *b = pb;
  if (a->a != b->a) return a->a < b->a ? -1 : 1;
  return a->b < b->b ? -1 : a->b > b->b;
}

// Sorts order[n] by the positions x (ties by index): a merge sort, as
// qsort cannot see x (qsort_r is not C11).
static void sort_by_position(int32_t *order, int32_t *work, int32_t n, const double *x) {
  if (n < 2) return;
  const int32_t half = n / 2;
  sort_by_position(order, work, half, x);
  sort_by_position(order + half, work, n - half, x);
  int32_t i = 0, j = half, k = 0;
  while (i < half && j < n) work[k++] = by_position(order + i, order + j, (void *)x) <= 0 ? order[i++] : order[j++];
  while (i < half) work[k++] = order[i++];
  while (j < n) work[k++] = order[j++];
  memcpy(order, work, (size_t)n * sizeof(int32_t));
}

fascia_status prep_sheet_prepare(fascia_ctx *ctx, const fascia_prep_scene *scene, int32_t t, fascia_prep_mesh *m) {
  const int32_t V = m->vertex_count, T = m->triangle_count;
  fascia_status status = FASCIA_OK;
  int32_t *order = prep_calloc(V, sizeof(int32_t)), *work = prep_calloc(V, sizeof(int32_t));
  int32_t *map = prep_calloc(V, sizeof(int32_t));
  edge_key *edges = prep_calloc(3 * (int64_t)T, sizeof(edge_key));
  PREP_CHECK_GOTO(order && work && map && edges, ctx, FASCIA_ERR_MEMORY, "sheet: out of memory");
  // merge vertices at the same position (an STL repeats them per triangle)
  for (int32_t i = 0; i < V; ++i) order[i] = i;
  sort_by_position(order, work, V, m->vertices);
  int32_t unique = 0;
  for (int32_t k = 0; k < V; ++k) {
    const int32_t i = order[k];
    if (k > 0 && !memcmp(m->vertices + 3 * (int64_t)i, m->vertices + 3 * (int64_t)order[k - 1], 3 * sizeof(double))) {
      map[i] = map[order[k - 1]];
      continue;
    }
    map[i] = unique++;
  }
  {
    double *x = prep_calloc(3 * (int64_t)unique, sizeof(double));
    PREP_CHECK_GOTO(x, ctx, FASCIA_ERR_MEMORY, "sheet: out of memory");
    for (int32_t i = 0; i < V; ++i) memcpy(x + 3 * (int64_t)map[i], m->vertices + 3 * (int64_t)i, 3 * sizeof(double));
    free(m->vertices);
    m->vertices = x;
    m->vertex_count = unique;
  }
  // triangles with a repeated corner have no area: dropped
  int32_t kept = 0;
  for (int32_t k = 0; k < T; ++k) {
    int32_t c[3];
    for (int j = 0; j < 3; ++j) c[j] = map[m->triangles[3 * (int64_t)k + j]];
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    memcpy(m->triangles + 3 * (int64_t)kept, c, sizeof c);
    m->triangle_part[kept++] = m->triangle_part[k];
  }
  m->triangle_count = kept;
  PREP_CHECK_GOTO(kept > 0, ctx, FASCIA_ERR_FORMAT,
                  "scene '%s' tissues[%d].mesh: '%s' has no triangle with three distinct corners; a sheet needs a "
                  "triangulated surface",
                  scene->path, (int)t, scene->tissues[t].mesh_path);
  // a membrane has a border: a closed surface bounds a volume
  int64_t E = 0;
  for (int32_t k = 0; k < kept; ++k)
    for (int j = 0; j < 3; ++j) {
      const int32_t a = m->triangles[3 * (int64_t)k + j], b = m->triangles[3 * (int64_t)k + (j + 1) % 3];
      edges[E].a = a < b ? a : b;
      edges[E++].b = a < b ? b : a;
    }
  qsort(edges, (size_t)E, sizeof *edges, by_edge);
  int64_t border = 0, over = 0;
  for (int64_t k = 0; k < E;) {
    int64_t j = k;
    while (j < E && !by_edge(edges + j, edges + k)) ++j;
    border += j - k == 1;
    over += j - k > 2;
    k = j;
  }
  PREP_CHECK_GOTO(border > 0, ctx, FASCIA_ERR_FORMAT,
                  "scene '%s' tissues[%d].mesh: '%s' is a closed surface (no border edge), which bounds a volume; a "
                  "sheet is an open surface (a membrane): cut it open, or make the space a volume tissue",
                  scene->path, (int)t, scene->tissues[t].mesh_path);
  PREP_CHECK_GOTO(over == 0, ctx, FASCIA_ERR_FORMAT,
                  "scene '%s' tissues[%d].mesh: '%s' is not a surface: %lld edges are shared by more than two "
                  "triangles; give a manifold triangulated membrane",
                  scene->path, (int)t, scene->tissues[t].mesh_path, (long long)over);
  prep_mesh_bounds(m);
cleanup:
  free(order);
  free(work);
  free(map);
  free(edges);
  return status;
}
