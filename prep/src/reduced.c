// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Strands and sheets in a scene (data/scenes/README.md, "Strands and sheets"): the
// frames and samples of a tissue whose form is a curve or a surface, built
// from the scene's geometry instead of a voxel region.
//
//   strand  the polyline from its start through its "through" points to
//           its end (straight without them); an end at the point of its
//           attachment's area (a point moved onto the organ's surface, a
//           part, a label, a region) nearest the strand's next point,
//           shared with the organ, or spread: a free apex and a fan of
//           fibres from it to frames over the area's side that faces the
//           strand, those shared (the coupling stage couples them). Frames
//           at equal intervals no longer than frame_spacing along each
//           segment; per interval (and fibre) one station at its middle
//           with q x q section points over a square of the strand's area
//           (a fibre's share of it) across it (fascia_shape_section_points,
//           as the beam's strand), each of volume interval x area x its
//           fraction;
//   sheet   the mesh's (merged) vertices are its frames, a vertex within the
//           coupling tolerance of an organ moved onto it (shared); per
//           triangle its centroid, with q points through the thickness
//           along the triangle's normal, volume triangle area x thickness x
//           weights.
//
// Each sample records the frames of its interval or triangle; the shape
// functions stage gives it fascia_shape_mls_adaptive's weights over them
// (linear along the interval or over the triangle). So the samples of a
// strand's curve add up to length x area (its fans' fibres besides), of a
// sheet to area x thickness.
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
  free(r->sample_drilling);
  memset(r, 0, sizeof *r);
}

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
  r->sample_drilling = prep_calloc(samples, sizeof(uint8_t));
  PREP_CHECK(r->frame_position && r->frame_organ && r->frame_triangle && r->sample_position && r->sample_volume &&
                 r->sample_cell && r->sample_drilling,
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

// A spread end's fibres: enough frames to spread its load over the area,
// few enough to keep the strand cheap.
#define FAN_FRAMES_MAX 32
#define FAN_FRAMES_MIN 3
#define PI_ 3.14159265358979323846

// The attachment's point moved onto its organ: the closest surface point,
// refused when farther than its radius.
static fascia_status attach(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                            fascia_cgal_tree **trees, int32_t t, const char *key, const fascia_prep_attachment *a,
                            double *x, int32_t *triangle) {
  PREP_TRY(tree_of(ctx, meshes, trees, a->organ));
  fascia_cgal_tree_closest(trees[a->organ], 1, a->point, x, triangle);
  double d[3];
  prep_sub3(x, a->point, d);
  const double dist = prep_norm3(d);
  PREP_CHECK(dist <= a->radius, ctx, FASCIA_ERR_ARGUMENT,
             "scene '%s' tissues[%d].%s: point (%g %g %g) lies on no organ: the surface of '%s' is %.3g mm from it, "
             "farther than its radius %.3g mm; move the point onto the organ (nearest surface point (%g %g %g)) or "
             "raise %s.radius",
             scene->path, (int)t, key, a->point[0], a->point[1], a->point[2], scene->organs[a->organ].name, 1e3 * dist,
             1e3 * a->radius, x[0], x[1], x[2], key);
  return FASCIA_OK;
}

// A part of an organ's mesh as a closest-point tree of its own; triangles
// maps the tree's triangle k back to the organ's: triangles[k].
typedef struct part_tree {
  fascia_cgal_tree *tree;
  int32_t *triangles; ///< [count] the organ's triangle indices of the part
  int32_t count;
  int32_t part;       ///< its index among the organ's parts
} part_tree;

// The part a label of a label organ is: the organ's only part, or the part
// of that label (label_organs.c names them by the label table).
static fascia_status label_part(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_mesh *m, int32_t t,
                                const char *key, const fascia_prep_attachment *a, const char **name) {
  const fascia_prep_organ_def *od = scene->organs + a->organ;
  const fascia_prep_segmentation *seg = &scene->segmentation;
  int32_t value = -1;
  if (strspn(a->label, "0123456789") == strlen(a->label)) value = (int32_t)atoi(a->label);
  for (int32_t k = 0; value < 0 && k < seg->table_count; ++k)
    if (!strcmp(seg->table_name[k], a->label)) value = seg->table_label[k];
  int32_t p = -1;
  for (int32_t k = 0; k < od->label_count; ++k)
    if (od->labels[k] == value) p = k;
  char list[256] = "";
  for (int32_t k = 0; k < od->label_count && strlen(list) < sizeof list - 40; ++k) {
    const char *n = fascia_prep_label_name(seg, od->labels[k]);
    snprintf(list + strlen(list), sizeof list - strlen(list), "%s%d%s%s%s", k ? ", " : "", (int)od->labels[k],
             n ? " (" : "", n ? n : "", n ? ")" : "");
  }
  PREP_CHECK(p >= 0, ctx, FASCIA_ERR_ARGUMENT,
             "scene '%s' tissues[%d].%s.label: organ '%s' has no label '%s' (its labels: %s); name one of them",
             scene->path, (int)t, key, od->name, a->label, list);
  *name = m->part_count == 1 ? m->part_names[0] : p < m->part_count ? m->part_names[p] : "";
  return FASCIA_OK;
}

static fascia_status part_tree_create(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                      int32_t t, const char *key, const fascia_prep_attachment *a, part_tree *out) {
  memset(out, 0, sizeof *out);
  const fascia_prep_mesh *m = meshes->organs + a->organ;
  const int by_label = a->label[0] != '\0';
  const char *name = a->part;
  if (by_label) PREP_TRY(label_part(ctx, scene, m, t, key, a, &name));
  out->part = prep_mesh_part(m, name);
  PREP_CHECK(by_label || out->part >= 0, ctx, FASCIA_ERR_ARGUMENT,
             "scene '%s' tissues[%d].%s.part: organ '%s' uses no part named '%s' (fascia prep --preview lists what it "
             "read; an organ of one label has one part, named after the organ, an organ of several one per label)",
             scene->path, (int)t, key, m->name, a->part);
  for (int32_t k = 0; out->part >= 0 && k < m->triangle_count; ++k) out->count += m->triangle_part[k] == out->part;
  PREP_CHECK(out->count > 0, ctx, FASCIA_ERR_ARGUMENT,
             "scene '%s' tissues[%d].%s.%s: %s '%s' of organ '%s' has no surface (no triangle%s); attach the strand "
             "to a %s that has one",
             scene->path, (int)t, key, by_label ? "label" : "part", by_label ? "label" : "part",
             by_label ? a->label : a->part, m->name, by_label ? " of the organ's surface: its voxels lie inside the organ" : "",
             by_label ? "label" : "part");
  out->triangles = prep_calloc(out->count, sizeof(int32_t));
  int32_t *corners = prep_calloc(3 * (int64_t)out->count, sizeof(int32_t));
  fascia_status status = out->triangles && corners ? FASCIA_OK
                                                   : PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "strand: out of memory");
  for (int32_t k = 0, n = 0; status == FASCIA_OK && k < m->triangle_count; ++k)
    if (m->triangle_part[k] == out->part) {
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

// Points on an organ's surface (an attachment's area), with their triangles.
typedef struct surface_points {
  double *x;
  int32_t *triangle;
  int64_t count, capacity;
} surface_points;

static int points_push(surface_points *p, const double *x, int32_t triangle) {
  if (p->count == p->capacity) {
    const int64_t cap = p->capacity ? 2 * p->capacity : 256;
    if (!prep_resize(&p->x, 3 * cap, sizeof *p->x) || !prep_resize(&p->triangle, cap, sizeof *p->triangle)) return 0;
    p->capacity = cap;
  }
  memcpy(p->x + 3 * p->count, x, 3 * sizeof(double));
  p->triangle[p->count++] = triangle;
  return 1;
}

static void points_free(surface_points *p) {
  free(p->x);
  free(p->triangle);
  memset(p, 0, sizeof *p);
}

// One end of a strand as it is built.
typedef struct strand_end {
  const fascia_prep_attachment *a;
  const char *key;         ///< "from" or "to"
  double x[3];             ///< the curve's end: on the organ, or (spread) the apex of its fan
  int32_t triangle;        ///< not spread: the organ's triangle at x
  int fixed;               ///< x does not depend on the strand's other points (a point end, not spread)
  part_tree part;          ///< part or label: its triangles
  surface_points area;     ///< region or spread: points of the area; spread: then its fan's frames
  double centre[3];        ///< spread: the mean of its fan's frames
  double reach;            ///< spread: the farthest fan frame from centre, m
  double spacing;          ///< spread: between its fan's frames, m
} strand_end;

static void end_free(strand_end *e) {
  part_tree_free(&e->part);
  points_free(&e->area);
}

// Is x in the end's area: its region, its part's triangle, within its radius of its point.
static int in_area(const strand_end *e, const fascia_prep_mesh *m, const double *point, int32_t tri, const double *x) {
  const fascia_prep_attachment *a = e->a;
  if (a->region.kind != FASCIA_PREP_REGION_NONE) return prep_region_contains(&a->region, x);
  if (a->part[0] || a->label[0]) return m->triangle_part[tri] == e->part.part;
  double d[3];
  prep_sub3(x, point, d);
  return prep_norm3(d) <= a->radius;
}

// The end's area sampled on its organ's triangles at about `step`: a
// lattice on each triangle that may reach it, the points in it kept.
static fascia_status area_points(fascia_ctx *ctx, const fascia_prep_meshes *meshes, strand_end *e, const double *point,
                                 double step) {
  const fascia_prep_mesh *m = meshes->organs + e->a->organ;
  const fascia_prep_attachment *a = e->a;
  double lo[3], hi[3];
  for (int r = 0; r < 3; ++r) {
    lo[r] = a->region.kind == FASCIA_PREP_REGION_BOX      ? a->region.min[r]
            : a->region.kind == FASCIA_PREP_REGION_SPHERE ? a->region.center[r] - a->region.radius
            : a->part[0] || a->label[0]                    ? -INFINITY
                                                           : point[r] - a->radius;
    hi[r] = a->region.kind == FASCIA_PREP_REGION_BOX      ? a->region.max[r]
            : a->region.kind == FASCIA_PREP_REGION_SPHERE ? a->region.center[r] + a->region.radius
            : a->part[0] || a->label[0]                    ? INFINITY
                                                           : point[r] + a->radius;
  }
  for (int32_t k = 0; k < m->triangle_count; ++k) {
    const int32_t *c = m->triangles + 3 * (int64_t)k;
    const double *p[3] = {m->vertices + 3 * (int64_t)c[0], m->vertices + 3 * (int64_t)c[1],
                          m->vertices + 3 * (int64_t)c[2]};
    int near = 1;
    for (int r = 0; r < 3; ++r)
      near &= fmax(fmax(p[0][r], p[1][r]), p[2][r]) >= lo[r] && fmin(fmin(p[0][r], p[1][r]), p[2][r]) <= hi[r];
    if (!near || ((a->part[0] || a->label[0]) && m->triangle_part[k] != e->part.part)) continue;
    double e1[3], e2[3], e3[3];
    prep_sub3(p[1], p[0], e1);
    prep_sub3(p[2], p[0], e2);
    prep_sub3(p[2], p[1], e3);
    const double longest = fmax(fmax(prep_norm3(e1), prep_norm3(e2)), prep_norm3(e3));
    const int n = (int)fmin(64, fmax(1, ceil(longest / step)));
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        double x[3];
        for (int r = 0; r < 3; ++r) x[r] = p[0][r] + e1[r] * i / n + e2[r] * j / n;
        if (in_area(e, m, point, k, x))
          PREP_CHECK(points_push(&e->area, x, k), ctx, FASCIA_ERR_MEMORY, "strand: out of memory");
      }
  }
  return FASCIA_OK;
}

typedef struct by_distance_item {
  double d;
  int64_t k;
} by_distance_item;
static int by_distance(const void *pa, const void *pb) {
  const by_distance_item *a = pa, *b = pb;
  if (a->d != b->d) return a->d < b->d ? -1 : 1;
  return (a->k > b->k) - (a->k < b->k);
}

// A spread end's fan: points of its area at least `spacing` apart, taken
// from the area's middle outwards (FAN_FRAMES_MIN to FAN_FRAMES_MAX where
// the area allows: the spacing halved or widened), replacing the area's
// points; their centre and reach.
static fascia_status pick_fan(fascia_ctx *ctx, strand_end *e, double spacing, double floor_spacing) {
  surface_points *all = &e->area;
  double mid[3] = {0, 0, 0};
  for (int64_t k = 0; k < all->count; ++k)
    for (int r = 0; r < 3; ++r) mid[r] += all->x[3 * k + r] / (double)all->count;
  by_distance_item *order = prep_calloc(all->count, sizeof *order);
  int64_t *kept = prep_calloc(FAN_FRAMES_MAX + 1, sizeof(int64_t));
  fascia_status status = FASCIA_OK;
  PREP_CHECK_GOTO(order && kept, ctx, FASCIA_ERR_MEMORY, "strand: out of memory");
  for (int64_t k = 0; k < all->count; ++k) {
    double d[3];
    prep_sub3(all->x + 3 * k, mid, d);
    order[k].d = prep_norm3(d), order[k].k = k;
  }
  qsort(order, (size_t)all->count, sizeof *order, by_distance);
  int count = 0;
  for (int attempt = 0; attempt < 12; ++attempt) {
    count = 0;
    int over = 0;
    for (int64_t o = 0; o < all->count && !over; ++o) {
      const double *x = all->x + 3 * order[o].k;
      int free_place = 1;
      for (int j = 0; j < count && free_place; ++j) {
        double d[3];
        prep_sub3(x, all->x + 3 * kept[j], d);
        free_place = prep_norm3(d) >= spacing;
      }
      if (!free_place) continue;
      if (count == FAN_FRAMES_MAX) over = 1;
      else kept[count++] = order[o].k;
    }
    // too many: widen, at once to about what FAN_FRAMES_MAX discs cover of the area's reach
    if (over) spacing = fmax(1.25 * spacing, order[all->count - 1].d * sqrt(PI_ / FAN_FRAMES_MAX));
    else if (count < FAN_FRAMES_MIN && spacing / 2 >= floor_spacing) spacing /= 2;
    else break;
  }
  surface_points fan = {0};
  for (int j = 0; j < count; ++j)
    PREP_CHECK_GOTO(points_push(&fan, all->x + 3 * kept[j], all->triangle[kept[j]]), ctx, FASCIA_ERR_MEMORY,
                    "strand: out of memory");
  points_free(all);
  *all = fan;
  memset(e->centre, 0, sizeof e->centre);
  for (int j = 0; j < count; ++j)
    for (int r = 0; r < 3; ++r) e->centre[r] += fan.x[3 * j + r] / count;
  e->reach = 0;
  for (int j = 0; j < count; ++j) {
    double d[3];
    prep_sub3(fan.x + 3 * j, e->centre, d);
    e->reach = fmax(e->reach, prep_norm3(d));
  }
cleanup:
  free(order);
  free(kept);
  return status;
}

// What an end's area is made of, named for messages: "to.region" etc.
static const char *area_key(const strand_end *e, char *out, size_t size) {
  const fascia_prep_attachment *a = e->a;
  snprintf(out, size, "%s.%s", e->key,
           a->region.kind != FASCIA_PREP_REGION_NONE ? "region" : a->part[0] ? "part" : a->label[0] ? "label" : "point");
  return out;
}

// Sets an end up: a point end moved onto its organ, a part's or a label's
// tree, a region's or a spread end's area (its points, from which end_fan
// makes a spread end's fan).
static fascia_status end_setup(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                               const fascia_prep_volume *vol, fascia_cgal_tree **trees, int32_t t, strand_end *e) {
  const fascia_prep_tissue_def *td = scene->tissues + t;
  const fascia_prep_attachment *a = e->a;
  const fascia_prep_organ_def *od = scene->organs + a->organ;
  const int by_part = a->part[0] || a->label[0], by_region = a->region.kind != FASCIA_PREP_REGION_NONE;
  char key[64];
  area_key(e, key, sizeof key);
  e->triangle = -1;
  if (!by_part && !by_region) PREP_TRY(attach(ctx, scene, meshes, trees, t, e->key, a, e->x, &e->triangle));
  e->fixed = !by_part && !by_region && !a->spread;
  if (by_part) {
    PREP_TRY(part_tree_create(ctx, scene, meshes, t, e->key, a, &e->part));
    const fascia_prep_mesh *m = meshes->organs + a->organ; // a first guess: the part's first corner
    memcpy(e->x, m->vertices + 3 * (int64_t)m->triangles[3 * (int64_t)e->part.triangles[0]], 3 * sizeof(double));
  }
  if (!by_region && !a->spread) return FASCIA_OK;
  // a deformable organ's frames keep its own spacing (the fan's frames join them)
  const double spacing = od->kind == FASCIA_ORGAN_DEFORMABLE && !od->shell ? fmax(od->frame_spacing, td->frame_spacing)
                                                                           : td->frame_spacing;
  const double step = a->spread ? fmin(spacing / 3, vol->voxel_size) : vol->voxel_size / 2;
  const double point[3] = {e->x[0], e->x[1], e->x[2]};
  PREP_TRY(area_points(ctx, meshes, e, point, step));
  if (!by_part && !by_region) PREP_CHECK(points_push(&e->area, point, e->triangle), ctx, FASCIA_ERR_MEMORY,
                                         "strand: out of memory");
  if (e->area.count == 0) {
    double c[3], d[3];
    int32_t tri;
    PREP_TRY(tree_of(ctx, meshes, trees, a->organ));
    const double *centre = a->region.kind == FASCIA_PREP_REGION_BOX ? NULL : a->region.center;
    double box_centre[3];
    for (int r = 0; r < 3; ++r) box_centre[r] = 0.5 * (a->region.min[r] + a->region.max[r]);
    fascia_cgal_tree_closest(trees[a->organ], 1, centre ? centre : box_centre, c, &tri);
    prep_sub3(c, centre ? centre : box_centre, d);
    return PREP_FAIL(ctx, FASCIA_ERR_ARGUMENT,
                     "scene '%s' tissues[%d].%s: the %s lies on no organ: it holds no surface of '%s', whose nearest "
                     "surface point (%g %g %g) is %.3g mm from its centre; move the region onto the organ or widen it",
                     scene->path, (int)t, key, a->region.kind == FASCIA_PREP_REGION_BOX ? "box" : "sphere", od->name,
                     c[0], c[1], c[2], 1e3 * prep_norm3(d));
  }
  e->spacing = spacing;
  if (!by_part) { // a first guess: the area's first point
    memcpy(e->x, e->area.x, sizeof e->x);
    e->triangle = e->area.triangle[0];
  }
  return FASCIA_OK;
}

// A spread end's fan, once the strand's next point `target` is known: the
// area's points that face it (their triangle's outward normal toward it:
// the strand's fibres insert on the side it comes from), thinned to the
// fan's frames; its apex off their centre toward the target by the area's
// reach (its fibres then meet the surface at 45 degrees or steeper), at
// least a frame spacing, at most a third of the way.
static fascia_status end_fan(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                             const fascia_prep_volume *vol, int32_t t, strand_end *e, const double *target) {
  const fascia_prep_tissue_def *td = scene->tissues + t;
  const fascia_prep_mesh *m = meshes->organs + e->a->organ;
  const double h = vol->voxel_size;
  // the mesh's winding: outward where it encloses a positive volume
  double volume = 0;
  for (int32_t k = 0; k < m->triangle_count; ++k) {
    const int32_t *c = m->triangles + 3 * (int64_t)k;
    double n[3];
    prep_cross3(m->vertices + 3 * (int64_t)c[1], m->vertices + 3 * (int64_t)c[2], n);
    volume += prep_dot3(m->vertices + 3 * (int64_t)c[0], n);
  }
  const double outward = volume < 0 ? -1 : 1;
  surface_points *all = &e->area;
  int64_t kept = 0;
  for (int64_t k = 0; k < all->count; ++k) {
    const int32_t *c = m->triangles + 3 * (int64_t)all->triangle[k];
    double e1[3], e2[3], n[3], d[3];
    prep_sub3(m->vertices + 3 * (int64_t)c[1], m->vertices + 3 * (int64_t)c[0], e1);
    prep_sub3(m->vertices + 3 * (int64_t)c[2], m->vertices + 3 * (int64_t)c[0], e2);
    prep_cross3(e1, e2, n);
    prep_sub3(target, all->x + 3 * k, d);
    if (!(outward * prep_dot3(n, d) > 0)) continue;
    memmove(all->x + 3 * kept, all->x + 3 * k, 3 * sizeof(double));
    all->triangle[kept++] = all->triangle[k];
  }
  char key[64];
  PREP_CHECK(kept > 0, ctx, FASCIA_ERR_ARGUMENT,
             "scene '%s' tissues[%d].%s: no point of the area faces the strand, which comes from (%g %g %g): the "
             "area lies on the far side of organ '%s'; move it to the side the strand comes from",
             scene->path, (int)t, area_key(e, key, sizeof key), target[0], target[1], target[2],
             scene->organs[e->a->organ].name);
  all->count = kept;
  PREP_TRY(pick_fan(ctx, e, e->spacing, 2 * h));
  double d[3];
  prep_sub3(target, e->centre, d);
  const double far = prep_norm3(d);
  const double lift = fmin(fmax(e->reach, td->frame_spacing), far / 3);
  for (int r = 0; r < 3; ++r) e->x[r] = e->centre[r] + (far > 0 ? lift * d[r] / far : 0);
  return FASCIA_OK;
}

// Moves an end that depends on where the strand goes to the point of its
// area (part, label, region; spread: its area before the fan is made)
// nearest `target`.
static void end_toward(strand_end *e, const double *target) {
  const fascia_prep_attachment *a = e->a;
  if (e->fixed) return;
  if (a->part[0] || a->label[0]) {
    part_closest(&e->part, target, e->x, &e->triangle);
    return;
  }
  double best = INFINITY;
  for (int64_t k = 0; k < e->area.count; ++k) {
    double d[3];
    prep_sub3(e->area.x + 3 * k, target, d);
    const double dist = prep_norm3(d);
    if (dist < best) best = dist, memcpy(e->x, e->area.x + 3 * k, sizeof e->x), e->triangle = e->area.triangle[k];
  }
}

// Refuses a piece of the strand, from p to q, that passes through an organ
// (more than a voxel inside; `skip_p`, `skip_q`: lengths at its ends left
// unchecked, where it leaves an organ's surface). 1: clear; else *organ,
// *at, *depth, *s say where.
static int path_clear(const fascia_prep_scene *scene, const fascia_prep_volume *vol, const prep_grid *g,
                      const double *p, const double *q, double skip_p, double skip_q, int32_t *organ, double *at,
                      double *depth, double *s_at) {
  double axis[3];
  prep_sub3(q, p, axis);
  const double length = prep_norm3(axis), h = vol->voxel_size;
  if (!(length > 0)) return 1;
  for (double s = skip_p; s <= length - skip_q; s += h / 2) {
    double x[3];
    for (int r = 0; r < 3; ++r) x[r] = p[r] + s * axis[r] / length;
    for (int32_t o = 0; o < scene->organ_count; ++o) {
      const double d = distance_at(vol, g, o, x);
      if (d < -h) {
        *organ = o, *depth = -d, *s_at = s;
        memcpy(at, x, 3 * sizeof(double));
        return 0;
      }
    }
  }
  return 1;
}

// Appends one station of a strand's interval or fibre from p to q: q x q
// section points over a square of `area` across it, weighted by frames i, j.
static fascia_status add_station(fascia_ctx *ctx, const fascia_prep_tissue_def *td, const double *p, const double *q,
                                 double area, int32_t i, int32_t j, prep_reduced *out, int32_t *s) {
  double axis[3], u[3], v[3], other[3] = {1, 0, 0};
  prep_sub3(q, p, axis);
  const double length = prep_norm3(axis);
  for (int r = 0; r < 3; ++r) axis[r] /= length;
  if (fabs(axis[0]) > 0.9) other[0] = 0, other[1] = 1;
  prep_cross3(axis, other, u);
  const double nu = prep_norm3(u);
  for (int r = 0; r < 3; ++r) u[r] /= nu;
  prep_cross3(axis, u, v);
  const int q_points = td->section_points;
  const double side = sqrt(area);
  double offset[3 * 16], fraction[16];
  PREP_TRY(fascia_shape_section_points(ctx, 1, q_points, u, v, side, side, offset, fraction));
  for (int k = 0; k < q_points * q_points; ++k, ++*s) {
    for (int r = 0; r < 3; ++r) out->sample_position[3 * (int64_t)*s + r] = 0.5 * (p[r] + q[r]) + offset[3 * k + r];
    out->sample_volume[*s] = fraction[k] * length * area;
    out->sample_cell[3 * (int64_t)*s] = i;
    out->sample_cell[3 * (int64_t)*s + 1] = j;
    out->sample_cell[3 * (int64_t)*s + 2] = -1;
  }
  return FASCIA_OK;
}

// The name of the curve's point k of n (0: its start, n - 1: its end) in the scene.
static const char *curve_point_name(int32_t k, int32_t n, char *out, size_t size) {
  if (k == 0) snprintf(out, size, "its start (from)");
  else if (k == n - 1) snprintf(out, size, "its end (to)");
  else snprintf(out, size, "through[%d]", (int)(k - 1));
  return out;
}

static fascia_status build_strand(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                  const fascia_prep_volume *vol, int32_t t, fascia_cgal_tree **trees,
                                  prep_reduced *out) {
  const fascia_prep_tissue_def *td = scene->tissues + t;
  strand_end ends[2];
  memset(ends, 0, sizeof ends);
  ends[0].a = &td->from, ends[0].key = "from";
  ends[1].a = &td->to, ends[1].key = "to";
  const int32_t n_through = td->through_count, n_points = n_through + 2;
  double *curve = prep_calloc(3 * (int64_t)n_points, sizeof(double));
  fascia_status status = FASCIA_OK;
  PREP_CHECK_GOTO(curve, ctx, FASCIA_ERR_MEMORY, "strand: out of memory");
  for (int k = 0; k < 2; ++k) PREP_TRY_GOTO(end_setup(ctx, scene, meshes, vol, trees, t, ends + k));
  // the ends that depend on the strand's path: toward the through points,
  // or toward each other (alternate projections: a few rounds settle on
  // the nearest points of convex-ish areas)
  double target[2][3];
  for (int round = 0; round < (n_through ? 1 : 8); ++round)
    for (int k = 0; k < 2; ++k) {
      memcpy(target[k], n_through ? td->through + (k == 0 ? 0 : 3 * (int64_t)(n_through - 1)) : ends[1 - k].x,
             sizeof target[k]);
      end_toward(ends + k, target[k]);
    }
  for (int k = 0; k < 2; ++k)
    if (ends[k].a->spread) PREP_TRY_GOTO(end_fan(ctx, scene, meshes, vol, t, ends + k, target[k]));
  memcpy(curve, ends[0].x, 3 * sizeof(double));
  for (int32_t k = 0; k < n_through; ++k)
    for (int r = 0; r < 3; ++r) curve[3 * (k + 1) + r] = td->through[3 * k + r];
  memcpy(curve + 3 * (int64_t)(n_points - 1), ends[1].x, 3 * sizeof(double));
  double length = 0;
  int32_t intervals = 0;
  for (int32_t k = 0; k + 1 < n_points; ++k) {
    double d[3];
    prep_sub3(curve + 3 * (k + 1), curve + 3 * k, d);
    length += prep_norm3(d);
    intervals += (int32_t)fmax(1, ceil(prep_norm3(d) / td->frame_spacing - 1e-9));
  }
  const prep_grid g = prep_volume_grid(vol);
  const double h = vol->voxel_size, skip = 2 * h;
  PREP_CHECK_GOTO(length > 2 * h, ctx, FASCIA_ERR_ARGUMENT,
                  "scene '%s' tissues[%d]: the strand's ends on '%s' and '%s' are %.3g mm apart, less than two voxels "
                  "(%.3g mm); give attachment points farther apart%s",
                  scene->path, (int)t, scene->organs[td->from.organ].name, scene->organs[td->to.organ].name,
                  1e3 * length, 2e3 * h, td->from.spread || td->to.spread ? " or smaller spread areas" : "");
  // the curve must stay outside every organ (two voxels at each end excepted,
  // where it leaves its organs' surfaces)
  for (int32_t k = 0; k + 1 < n_points; ++k) {
    int32_t o;
    double x[3], depth, s;
    if (path_clear(scene, vol, &g, curve + 3 * k, curve + 3 * (k + 1), k == 0 ? skip : 0,
                   k + 2 == n_points ? skip : 0, &o, x, &depth, &s))
      continue;
    char a_name[40], b_name[40];
    if (n_through == 0)
      PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_ARGUMENT,
                      "scene '%s' tissues[%d]: the strand from '%s' to '%s' is straight and would pass through organ "
                      "'%s' (at (%g %g %g), %.3g mm from its end on '%s', %.3g mm inside); move from.point or "
                      "to.point so the line between them stays outside the organs, or route it with \"through\"",
                      scene->path, (int)t, scene->organs[td->from.organ].name, scene->organs[td->to.organ].name,
                      scene->organs[o].name, x[0], x[1], x[2], 1e3 * s, scene->organs[td->from.organ].name,
                      1e3 * depth);
    PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_ARGUMENT,
                    "scene '%s' tissues[%d].through: the strand's curve between %s and %s would pass through organ '%s' "
                    "(at (%g %g %g), %.3g mm inside); move the through points so the curve stays outside the organs",
                    scene->path, (int)t, curve_point_name(k, n_points, a_name, sizeof a_name),
                    curve_point_name(k + 1, n_points, b_name, sizeof b_name), scene->organs[o].name, x[0], x[1], x[2],
                    1e3 * depth);
  }
  // a spread end's fibres, from its apex to its area, must stay outside the organs too
  for (int k = 0; k < 2; ++k) {
    if (!ends[k].a->spread) continue;
    for (int64_t j = 0; j < ends[k].area.count; ++j) {
      int32_t o;
      double x[3], depth, s;
      if (path_clear(scene, vol, &g, ends[k].x, ends[k].area.x + 3 * j, 0, skip, &o, x, &depth, &s)) continue;
      char key[64];
      PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_ARGUMENT,
                      "scene '%s' tissues[%d].%s: the fibres spreading the strand's end over its area on '%s' would "
                      "pass through organ '%s' (at (%g %g %g), %.3g mm inside): the area is too wide or too curved; "
                      "make it smaller, or set %s.spread false",
                      scene->path, (int)t, area_key(ends + k, key, sizeof key), scene->organs[ends[k].a->organ].name,
                      scene->organs[o].name, x[0], x[1], x[2], 1e3 * depth, ends[k].key);
    }
  }
  // frames: the curve's (its points and equal intervals between them), then the fans'
  const int32_t curve_frames = intervals + 1, fan_frames = (int32_t)(ends[0].area.count * !!td->from.spread +
                                                                     ends[1].area.count * !!td->to.spread);
  const int per_station = td->section_points * td->section_points;
  PREP_TRY_GOTO(reserve(ctx, out, curve_frames + fan_frames, (int64_t)(intervals + fan_frames) * per_station));
  out->frame_count = curve_frames + fan_frames;
  int32_t i = 0;
  for (int32_t k = 0; k + 1 < n_points; ++k) {
    double d[3];
    prep_sub3(curve + 3 * (k + 1), curve + 3 * k, d);
    const int32_t n = (int32_t)fmax(1, ceil(prep_norm3(d) / td->frame_spacing - 1e-9));
    for (int32_t j = 0; j < n; ++j, ++i)
      for (int r = 0; r < 3; ++r) out->frame_position[3 * (int64_t)i + r] = curve[3 * k + r] + d[r] * j / n;
  }
  memcpy(out->frame_position + 3 * (int64_t)i, ends[1].x, 3 * sizeof(double));
  for (int32_t j = 0; j < out->frame_count; ++j) out->frame_organ[j] = -1, out->frame_triangle[j] = -1;
  for (int k = 0; k < 2; ++k)
    if (!ends[k].a->spread) {
      const int32_t at = k == 0 ? 0 : curve_frames - 1;
      out->frame_organ[at] = ends[k].a->organ;
      out->frame_triangle[at] = ends[k].triangle;
    }
  int32_t s = 0;
  for (int32_t j = 0; j < intervals; ++j)
    PREP_TRY_GOTO(add_station(ctx, td, out->frame_position + 3 * (int64_t)j, out->frame_position + 3 * (int64_t)(j + 1),
                              td->area, j, j + 1, out, &s));
  // each fan frame: on the organ (shared), one fibre to its apex. The
  // fibres share a section a = A / sum cos^2 (their angles off the fan's
  // axis, apex to centre): pulled along that axis the fan is as stiff per
  // length of lift as the strand, so spreading the end does not soften it
  int32_t f = curve_frames;
  for (int k = 0; k < 2; ++k) {
    if (!ends[k].a->spread) continue;
    const int32_t apex = k == 0 ? 0 : curve_frames - 1;
    const surface_points *fan = &ends[k].area;
    const double *x_apex = out->frame_position + 3 * (int64_t)apex;
    double axis[3], cos2 = 0;
    prep_sub3(ends[k].centre, x_apex, axis);
    const double lift = prep_norm3(axis);
    for (int64_t j = 0; j < fan->count; ++j) {
      double d[3];
      prep_sub3(fan->x + 3 * j, x_apex, d);
      const double c = prep_dot3(d, axis) / (prep_norm3(d) * lift);
      cos2 += c * c;
    }
    const double fibre_area = td->area / fmax(cos2, 1e-3);
    for (int64_t j = 0; j < fan->count; ++j, ++f) {
      memcpy(out->frame_position + 3 * (int64_t)f, fan->x + 3 * j, 3 * sizeof(double));
      out->frame_organ[f] = ends[k].a->organ;
      out->frame_triangle[f] = fan->triangle[j];
      PREP_TRY_GOTO(add_station(ctx, td, x_apex, fan->x + 3 * j, fibre_area, apex, f, out, &s));
    }
  }
  out->sample_count = s;
  out->length = length;
cleanup:
  free(curve);
  end_free(ends);
  end_free(ends + 1);
  return status;
}

int64_t prep_strand_intervals(const fascia_prep_points *points, int32_t t, int32_t *pairs) {
  int64_t n = 0;
  int32_t last_a = -1, last_b = -1;
  for (int32_t s = 0; s < points->sample_count; ++s) {
    const int32_t *c = points->sample_cell_frame + 3 * (int64_t)s;
    if (points->sample_tissue[s] != t || c[0] < 0 || c[1] < 0 || c[2] >= 0) continue;
    if (c[0] == last_a && c[1] == last_b) continue; // the other section points of the same station
    last_a = c[0], last_b = c[1];
    if (pairs) pairs[2 * n] = c[0], pairs[2 * n + 1] = c[1];
    ++n;
  }
  return n;
}

// ------------------------------------------------------------ sheets

// One point per triangle, its centroid (times the points through the
// thickness), and there its drilling stabiliser's gauges (reduced.h): the
// points' gradients are a quadratic fit's (shape_functions.c), free of the
// linear triangle's shear locking, and the gauges hold the frames' rotations
// about the normal that the fit leaves free (docs/mechanics.md, "Against
// CalculiX").
static const double TRI_RULE[1][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3}};
#define TRI_POINTS 1

static fascia_status build_sheet(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                 const fascia_prep_volume *vol, int32_t t, fascia_cgal_tree **trees,
                                 prep_reduced *out) {
  const fascia_prep_tissue_def *td = scene->tissues + t;
  const fascia_prep_mesh *m = meshes->sheets + t;
  const int32_t V = m->vertex_count, T = m->triangle_count;
  const int q = td->section_points;
  PREP_TRY(reserve(ctx, out, V, (TRI_POINTS * (int64_t)q + PREP_SHEET_DRILLING_GAUGES) * T));
  out->frame_count = V;
  memcpy(out->frame_position, m->vertices, 3 * (size_t)V * sizeof(double));
  // vertex normals (area-weighted) for the thickness check
  double *normal = prep_calloc(3 * (int64_t)V, sizeof(double));
  PREP_CHECK(normal, ctx, FASCIA_ERR_MEMORY, "sheet: out of memory");
  for (int32_t k = 0; k < T; ++k) {
    const int32_t *c = m->triangles + 3 * (int64_t)k;
    double e1[3], e2[3], n[3];
    prep_sub3(m->vertices + 3 * (int64_t)c[1], m->vertices + 3 * (int64_t)c[0], e1);
    prep_sub3(m->vertices + 3 * (int64_t)c[2], m->vertices + 3 * (int64_t)c[0], e2);
    prep_cross3(e1, e2, n);
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
      prep_sub3(c, x, d);
      const double dist = prep_norm3(d);
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
      const double len = prep_norm3(n);
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
    prep_sub3(p1, p0, e1);
    prep_sub3(p2, p0, e2);
    prep_cross3(e1, e2, n);
    const double twice = prep_norm3(n);
    if (!(twice > 1e-12 * (prep_dot3(e1, e1) + prep_dot3(e2, e2)))) continue; // degenerate: no area to integrate
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
    for (int g = 1; g <= PREP_SHEET_DRILLING_GAUGES; ++g, ++s) {
      for (int r = 0; r < 3; ++r) out->sample_position[3 * (int64_t)s + r] = (p0[r] + p1[r] + p2[r]) / 3;
      out->sample_volume[s] = area * td->thickness;
      memcpy(out->sample_cell + 3 * (int64_t)s, c, 3 * sizeof(int32_t));
      out->sample_drilling[s] = (uint8_t)g;
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
