// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Shell organs (docs/organs.md, "Shell organs"): a hollow organ is its wall,
// a sheet (docs/mechanics.md, "Strands and sheets") whose mid-surface is the
// organ's surface. Its frames lie on the surface, its samples through the
// wall, and the solver treats them as a deformable organ's (model kind
// DEFORMABLE), so the wall and the tissues on it are one mechanical system.
//
//   frames   the tissue frames on the surface that their coupling rules
//            allow (shared with the tissues), then darts thrown on the
//            surface (random points of its triangles, area-weighted, in a
//            seeded order), kept when no frame lies closer than
//            frame_spacing; an open surface's free edges get theirs
//            before the darts (border_frames);
//   wall     the frames joined into triangles over the surface (CGAL's
//            advancing-front reconstruction: each frame to its neighbours
//            on the surface, never across the organ);
//   samples  per triangle its centroid, section_points through the wall
//            along its normal, volume triangle area x thickness x the Gauss
//            weight, weights linear over its three frames: a sheet's.
//
// An open surface (a bladder cut at its neck) is a wall with a free edge:
// frames lie along that edge, so the wall reaches it and a hold there
// clamps the wall along it.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/shape.h"
#include "shell.h"

// Darts per frame_spacing^2 of surface: enough that the kept frames fill it
// (a maximal Poisson-disk set keeps about one per 1.1 spacing^2).
#define DARTS_PER_SPACING2 12.0
// The wall's faces must lie this fraction of half its thickness from the
// rest of the surface (the tilt of the closest triangle's normal is allowed
// for on a curved, faceted surface).
#define FACE_CLEARANCE 0.7
// ... where the rest of the surface faces the wall's face back: its normal
// more than about 105 degrees from the frame's (a sharp edge's other side
// stands at 90)
#define FACING_COS (-0.25)
// The frames' triangles must cover the organ's surface to this fraction (a
// faceted wall is smaller than a voxel-stepped or wrinkled surface).
#define AREA_TOLERANCE 0.25
// A wall triangle whose centre lies farther than this fraction of
// frame_spacing from the organ's surface spans a hole, not the surface (a
// chord's sag on a surface curved at the spacing's radius is 0.08 of it).
#define OFF_SURFACE 0.2
// A wall triangle of an open surface whose normal turns from the surface's
// by more than 60 degrees (cosine below) stands across it.
#define ACROSS_COS 0.5
// A free edge's vertex where it turns by more than this (cosine of the
// turn below) is a corner of the wall: it gets a frame.
#define CORNER_COS 0.7071
// Frames on a free edge keep this fraction of frame_spacing from the
// frames already there (its corners, shared frames).
#define BORDER_CLEARANCE 0.5

static uint64_t splitmix(uint64_t *state) {
  uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}
static double uniform(uint64_t *state) { return (double)(splitmix(state) >> 11) * 0x1.0p-53; }

// Unit normal and area of triangle k of mesh m.
static double triangle_normal(const fascia_prep_mesh *m, int32_t k, double *n) {
  const int32_t *c = m->triangles + 3 * (int64_t)k;
  double e1[3], e2[3];
  prep_sub3(m->vertices + 3 * (int64_t)c[1], m->vertices + 3 * (int64_t)c[0], e1);
  prep_sub3(m->vertices + 3 * (int64_t)c[2], m->vertices + 3 * (int64_t)c[0], e2);
  prep_cross3(e1, e2, n);
  const double twice = prep_norm3(n);
  for (int r = 0; r < 3; ++r) n[r] = twice > 0 ? n[r] / twice : 0;
  return 0.5 * twice;
}

// ------------------------------------------------------------ dart throwing

// Kept points on a dense grid of cells frame_spacing wide over the organ's
// bounds: a point conflicts with those in its 27 cells.
typedef struct cell_grid {
  double lo[3], size;
  int32_t dims[3];
  int32_t *head, *next; // [cells], [points]: lists of kept points per cell
  const double *x;      // [3 points]
} cell_grid;

static int64_t cell_of(const cell_grid *g, const double *p, int32_t *ijk) {
  for (int r = 0; r < 3; ++r) {
    const double c = floor((p[r] - g->lo[r]) / g->size);
    ijk[r] = (int32_t)fmin(fmax(c, 0), g->dims[r] - 1);
  }
  return ijk[0] + (int64_t)g->dims[0] * (ijk[1] + (int64_t)g->dims[1] * ijk[2]);
}

// Whether a kept point lies closer than r (at most the cell size) to p.
static int conflicts_within(const cell_grid *g, const double *p, double r) {
  int32_t c[3];
  cell_of(g, p, c);
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int32_t i = c[0] + dx, j = c[1] + dy, k = c[2] + dz;
        if (i < 0 || j < 0 || k < 0 || i >= g->dims[0] || j >= g->dims[1] || k >= g->dims[2]) continue;
        for (int32_t q = g->head[i + (int64_t)g->dims[0] * (j + (int64_t)g->dims[1] * k)]; q >= 0; q = g->next[q])
          if (prep_dist3(g->x + 3 * (int64_t)q, p) < r) return 1;
      }
  return 0;
}
static int conflicts(const cell_grid *g, const double *p) { return conflicts_within(g, p, g->size); }

static void keep(cell_grid *g, int32_t q) {
  int32_t c[3];
  const int64_t cell = cell_of(g, g->x + 3 * (int64_t)q, c);
  g->next[q] = g->head[cell];
  g->head[cell] = q;
}

// ------------------------------------------------------------ free edges

typedef struct half_edge {
  int32_t lo, hi;        // vertices, lo < hi: the undirected edge
  int32_t from, to, tri; // as its triangle runs it
} half_edge;
static int by_undirected(const void *pa, const void *pb) {
  const half_edge *a = pa, *b = pb;
  if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
  return (a->hi > b->hi) - (a->hi < b->hi);
}

// Keeps the point at arc length t along the chain of border edges e[0..n)
// (e[k] ends where e[k + 1] starts), if no frame lies within r of it.
static void border_point(cell_grid *g, const fascia_prep_mesh *m, const half_edge *e, int32_t n, double t, double r,
                         int32_t capacity, double *x, int32_t *triangle, int32_t *count) {
  int32_t k = 0;
  double len = 0;
  for (; k < n; ++k) {
    len = prep_dist3(m->vertices + 3 * (int64_t)e[k].from, m->vertices + 3 * (int64_t)e[k].to);
    if (t <= len || k == n - 1) break;
    t -= len;
  }
  const double *a = m->vertices + 3 * (int64_t)e[k].from, *b = m->vertices + 3 * (int64_t)e[k].to;
  const double u = len > 0 ? fmin(fmax(t / len, 0), 1) : 0;
  double p[3];
  for (int c = 0; c < 3; ++c) p[c] = a[c] + u * (b[c] - a[c]);
  if (*count >= capacity || conflicts_within(g, p, r)) return;
  memcpy(x + 3 * (int64_t)*count, p, sizeof p);
  triangle[*count] = e[k].tri;
  keep(g, (*count)++);
}

// Frames along an open surface's free edges (edges of one triangle): at its
// corners, then evenly between corners, about frame_spacing apart (a loop
// without corners evenly from its first vertex). Without them the darts
// leave a ragged margin up to a spacing wide, and a hold along the edge
// clamps a few scattered frames.
static fascia_status border_frames(fascia_ctx *ctx, const fascia_prep_mesh *m, double spacing, cell_grid *g,
                                   int32_t capacity, double *x, int32_t *triangle, int32_t *count) {
  const int64_t H = 3 * (int64_t)m->triangle_count;
  half_edge *h = prep_calloc(H > 0 ? H : 1, sizeof *h);
  int32_t *first = prep_calloc(m->vertex_count > 0 ? m->vertex_count : 1, sizeof(int32_t)); // border edge from v
  int32_t *next = prep_calloc(H > 0 ? H : 1, sizeof(int32_t)); // another border edge from the same vertex
  half_edge *chain = prep_calloc(H > 0 ? H : 1, sizeof *chain);
  uint8_t *used = prep_calloc(H > 0 ? H : 1, 1);
  int32_t *corner = prep_calloc(H + 1, sizeof(int32_t));
  double *arc = prep_calloc(H + 2, sizeof(double)); // arc length at each corner, then the chain's end
  fascia_status status = FASCIA_OK;
  PREP_CHECK_GOTO(h && first && next && chain && used && corner && arc, ctx, FASCIA_ERR_MEMORY,
                  "shell '%s': out of memory", m->name);
  for (int32_t t = 0; t < m->triangle_count; ++t)
    for (int j = 0; j < 3; ++j) {
      const int32_t a = m->triangles[3 * (int64_t)t + j], b = m->triangles[3 * (int64_t)t + (j + 1) % 3];
      h[3 * (int64_t)t + j] = (half_edge){a < b ? a : b, a < b ? b : a, a, b, t};
    }
  qsort(h, (size_t)H, sizeof *h, by_undirected);
  int64_t B = 0; // border edges, compacted to the front of h
  for (int64_t k = 0; k < H;) {
    int64_t j = k;
    while (j < H && !by_undirected(h + j, h + k)) ++j;
    if (j - k == 1) h[B++] = h[k];
    k = j;
  }
  for (int32_t v = 0; v < m->vertex_count; ++v) first[v] = -1;
  for (int64_t k = B - 1; k >= 0; --k) next[k] = first[h[k].from], first[h[k].from] = (int32_t)k;
  for (int64_t start = 0; start < B; ++start) {
    if (used[start]) continue;
    int32_t n = 0; // the loop through start, edge after edge
    for (int64_t k = start; k >= 0 && !used[k];) {
      used[k] = 1;
      chain[n++] = h[k];
      int64_t after = -1;
      for (int32_t q = first[h[k].to]; q >= 0; q = next[q])
        if (!used[q]) after = q;
      k = after;
    }
    double t_at = 0;
    int32_t corners = 0;
    for (int32_t k = 0; k < n; ++k) {
      const double *a = m->vertices + 3 * (int64_t)chain[k].from, *b = m->vertices + 3 * (int64_t)chain[k].to;
      if (chain[(k + n - 1) % n].to != chain[k].from) continue; // an open chain's ends are not turns
      double din[3], dout[3];
      prep_sub3(a, m->vertices + 3 * (int64_t)chain[(k + n - 1) % n].from, din);
      prep_sub3(b, a, dout);
      const double ni = prep_norm3(din), no = prep_norm3(dout);
      if (ni > 0 && no > 0 && prep_dot3(din, dout) < CORNER_COS * ni * no)
        corner[corners++] = k;
    }
    const int closed = chain[n - 1].to == chain[0].from;
    if (corners == 0 || !closed) { // a smooth loop from its first vertex; an open chain from its start
      if (corners == 0 || corner[0] != 0) memmove(corner + 1, corner, (size_t)corners++ * sizeof *corner);
      corner[0] = 0;
    }
    for (int32_t k = 0, c = 0; k < n; ++k) { // each corner's arc length from the chain's start
      if (c < corners && corner[c] == k) arc[c++] = t_at;
      t_at += prep_dist3(m->vertices + 3 * (int64_t)chain[k].from, m->vertices + 3 * (int64_t)chain[k].to);
    }
    if (!(t_at > 0)) continue;
    arc[corners] = closed ? t_at + arc[0] : t_at; // back to the first corner, or the chain's end
    const double r = BORDER_CLEARANCE * spacing;
    for (int32_t c = 0; c < corners; ++c) border_point(g, m, chain, n, arc[c], r, capacity, x, triangle, count);
    if (!closed) border_point(g, m, chain, n, t_at, r, capacity, x, triangle, count);
    for (int32_t c = 0; c < corners; ++c) {
      const double len = arc[c + 1] - arc[c];
      const long pieces = fmax(1, lround(len / spacing));
      for (long j = 1; j < pieces; ++j)
        border_point(g, m, chain, n, fmod(arc[c] + len * (double)j / (double)pieces, t_at), r, capacity, x, triangle,
                     count);
    }
  }
cleanup:
  free(h);
  free(first);
  free(next);
  free(chain);
  free(used);
  free(corner);
  free(arc);
  return status;
}

typedef struct dart {
  uint64_t key;
  int32_t triangle;
  double x[3];
} dart;

static int by_key(const void *a, const void *b) {
  const uint64_t x = ((const dart *)a)->key, y = ((const dart *)b)->key;
  return (x > y) - (x < y);
}

// The shell's frames: shared ones (given) first, then darts. x, triangle:
// [capacity] filled from *count on; *count grows.
static fascia_status throw_frames(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_mesh *m,
                                  int32_t o, double spacing, int32_t capacity, double *x, int32_t *triangle,
                                  int32_t *count) {
  fascia_status status = FASCIA_OK;
  uint64_t state = (uint64_t)scene->seed * 0x9e3779b97f4a7c15ull + 0x5e11ull + (uint64_t)o;
  int64_t darts = 0;
  for (int32_t k = 0; k < m->triangle_count; ++k) {
    double n[3];
    darts += (int64_t)floor(triangle_normal(m, k, n) / (spacing * spacing) * DARTS_PER_SPACING2 + uniform(&state));
  }
  cell_grid g = {{m->bounds[0], m->bounds[1], m->bounds[2]}, spacing, {1, 1, 1}, NULL, NULL, x};
  int64_t cells = 1;
  for (int r = 0; r < 3; ++r) {
    g.dims[r] = (int32_t)fmin(ceil((m->bounds[3 + r] - m->bounds[r]) / spacing) + 1, 1 << 20);
    cells *= g.dims[r];
  }
  PREP_CHECK(cells < ((int64_t)1 << 31) && darts < ((int64_t)1 << 31), ctx, FASCIA_ERR_ARGUMENT,
             "scene '%s' shell organ '%s': frame_spacing %.3g mm is too fine for an organ this large; raise it",
             scene->path, m->name, 1e3 * spacing);
  dart *d = prep_calloc(darts, sizeof *d);
  g.head = prep_calloc(cells, sizeof(int32_t));
  g.next = prep_calloc(capacity, sizeof(int32_t));
  PREP_CHECK_GOTO(d && g.head && g.next, ctx, FASCIA_ERR_MEMORY, "shell '%s': out of memory", m->name);
  for (int64_t c = 0; c < cells; ++c) g.head[c] = -1;
  for (int32_t q = 0; q < *count; ++q) keep(&g, q);
  PREP_TRY_GOTO(border_frames(ctx, m, spacing, &g, capacity, x, triangle, count));
  // the same draws again, now placing the darts
  state = (uint64_t)scene->seed * 0x9e3779b97f4a7c15ull + 0x5e11ull + (uint64_t)o;
  int64_t made = 0;
  for (int32_t k = 0; k < m->triangle_count; ++k) {
    double n[3];
    const int64_t here =
        (int64_t)floor(triangle_normal(m, k, n) / (spacing * spacing) * DARTS_PER_SPACING2 + uniform(&state));
    const int32_t *c = m->triangles + 3 * (int64_t)k;
    for (int64_t j = 0; j < here && made < darts; ++j, ++made) {
      double a = uniform(&state), b = uniform(&state);
      if (a + b > 1) a = 1 - a, b = 1 - b;
      for (int r = 0; r < 3; ++r)
        d[made].x[r] = m->vertices[3 * (int64_t)c[0] + r] +
                       a * (m->vertices[3 * (int64_t)c[1] + r] - m->vertices[3 * (int64_t)c[0] + r]) +
                       b * (m->vertices[3 * (int64_t)c[2] + r] - m->vertices[3 * (int64_t)c[0] + r]);
      d[made].triangle = k;
      d[made].key = splitmix(&state);
    }
  }
  qsort(d, (size_t)made, sizeof *d, by_key);
  for (int64_t j = 0; j < made && *count < capacity; ++j) {
    if (conflicts(&g, d[j].x)) continue;
    memcpy(x + 3 * (int64_t)*count, d[j].x, sizeof d[j].x);
    triangle[*count] = d[j].triangle;
    keep(&g, (*count)++);
  }
cleanup:
  free(d);
  free(g.head);
  free(g.next);
  return status;
}

// ------------------------------------------------------------ checks

typedef struct edge {
  int32_t a, b;
} edge;
static int by_edge(const void *pa, const void *pb) {
  const edge *a = pa, *b = pb;
  if (a->a != b->a) return a->a < b->a ? -1 : 1;
  return (a->b > b->b) - (a->b < b->b);
}

// Edges of more than two of the wall's triangles (not a surface there).
static fascia_status count_fins(fascia_ctx *ctx, const int32_t *tri, int32_t T, int64_t *fins) {
  edge *e = prep_calloc(3 * (int64_t)T, sizeof *e);
  PREP_CHECK(e, ctx, FASCIA_ERR_MEMORY, "shell: out of memory");
  for (int32_t k = 0; k < T; ++k)
    for (int j = 0; j < 3; ++j) {
      const int32_t a = tri[3 * (int64_t)k + j], b = tri[3 * (int64_t)k + (j + 1) % 3];
      e[3 * (int64_t)k + j] = (edge){a < b ? a : b, a < b ? b : a};
    }
  qsort(e, 3 * (size_t)T, sizeof *e, by_edge);
  *fins = 0;
  for (int64_t k = 0; k < 3 * (int64_t)T;) {
    int64_t j = k;
    while (j < 3 * (int64_t)T && !by_edge(e + j, e + k)) ++j;
    *fins += j - k > 2;
    k = j;
  }
  free(e);
  return FASCIA_OK;
}

// The wall, thickness wide about the surface, must not reach another part
// of the surface: at each frame both faces (half the thickness along the
// surface's normal) stay clear of the rest of the surface.
static fascia_status check_thickness(fascia_ctx *ctx, const fascia_prep_scene *scene, int32_t o,
                                     const fascia_prep_mesh *m, fascia_cgal_tree *tree, const double *x,
                                     const int32_t *triangle, int32_t n) {
  const double t = scene->organs[o].thickness;
  for (int32_t i = 0; i < n; ++i) {
    double normal[3];
    triangle_normal(m, triangle[i], normal);
    for (int side = -1; side <= 1; side += 2) {
      double y[3], c[3];
      int32_t k;
      for (int r = 0; r < 3; ++r) y[r] = x[3 * (int64_t)i + r] + side * 0.5 * t * normal[r];
      fascia_cgal_tree_closest(tree, 1, y, c, &k);
      const double clear = prep_dist3(y, c);
      // only a part of the surface that faces the wall's face back counts
      // (the organ thinner than the wall there): beside a sharp edge the
      // inner face comes near the adjacent side, which faces across
      double nearby[3];
      triangle_normal(m, k, nearby);
      const int facing = prep_dot3(normal, nearby) < FACING_COS;
      PREP_CHECK(!facing || clear >= FACE_CLEARANCE * 0.5 * t, ctx, FASCIA_ERR_ARGUMENT,
                 "scene '%s' organs[%d].thickness: the wall of '%s', %.3g mm thick, is thicker than the organ near "
                 "(%.4g %.4g %.4g) m: its face there comes within %.3g mm of another part of the surface (expected "
                 "about %.3g mm); give a thinner wall, or make the organ \"deformable\"",
                 scene->path, (int)o, m->name, 1e3 * t, x[3 * (int64_t)i], x[3 * (int64_t)i + 1],
                 x[3 * (int64_t)i + 2], 1e3 * clear, 0.5e3 * t);
    }
  }
  return FASCIA_OK;
}

// ------------------------------------------------------------ the wall

static fascia_status wall_samples(fascia_ctx *ctx, const fascia_prep_organ_def *od, const double *x,
                                  const int64_t *global, const int32_t *tri, int32_t T, prep_reduced *out,
                                  double *area_sum) {
  const int q = od->section_points, split = prep_shell_split(od);
  int32_t s = 0;
  *area_sum = 0;
  for (int32_t k = 0; k < T; ++k) {
    const int32_t *c = tri + 3 * (int64_t)k;
    const double *p0 = x + 3 * (int64_t)c[0], *p1 = x + 3 * (int64_t)c[1], *p2 = x + 3 * (int64_t)c[2];
    double e1[3], e2[3], n[3];
    prep_sub3(p1, p0, e1);
    prep_sub3(p2, p0, e2);
    prep_cross3(e1, e2, n);
    const double twice = prep_norm3(n);
    if (!(twice > 1e-12 * (e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2] + e2[0] * e2[0] + e2[1] * e2[1] +
                           e2[2] * e2[2])))
      continue; // no area to integrate
    for (int r = 0; r < 3; ++r) n[r] /= twice;
    double offset[3 * 4], fraction[4];
    PREP_TRY(fascia_shape_section_points(ctx, 2, q, n, NULL, od->thickness, 0, offset, fraction));
    *area_sum += 0.5 * twice;
    // the centroids of the split x split parts, at p0 + a e1 + b e2: those
    // pointing as the triangle (third 1/3), then those pointing back (2/3)
    for (int back = 0; back < 2; ++back)
      for (int i = 0; i < split - back; ++i)
        for (int i2 = 0; i + i2 < split - back; ++i2) {
          const double third = back ? 2.0 / 3 : 1.0 / 3, a = (i + third) / split, b = (i2 + third) / split;
          for (int j = 0; j < q; ++j, ++s) {
            for (int r = 0; r < 3; ++r)
              out->sample_position[3 * (int64_t)s + r] = p0[r] + a * e1[r] + b * e2[r] + offset[3 * j + r];
            out->sample_volume[s] = 0.5 * twice * fraction[j] * od->thickness / (split * split);
            for (int r = 0; r < 3; ++r) out->sample_cell[3 * (int64_t)s + r] = (int32_t)global[c[r]];
          }
        }
  }
  out->sample_count = s;
  return FASCIA_OK;
}

// A wall triangle of frames c against the organ's surface under it (its
// triangle on): the dot product of their normals, the wall's unnormalised
// (its length in *length, where length is not NULL).
static double against_surface(const fascia_prep_mesh *m, int32_t on, const double *x, const int32_t *c,
                              double *length) {
  double e1[3], e2[3], n[3], surface[3];
  prep_sub3(x + 3 * (int64_t)c[1], x + 3 * (int64_t)c[0], e1);
  prep_sub3(x + 3 * (int64_t)c[2], x + 3 * (int64_t)c[0], e2);
  prep_cross3(e1, e2, n);
  if (length) *length = prep_norm3(n);
  triangle_normal(m, on, surface);
  return prep_dot3(n, surface);
}

// Whether a wall triangle stands across the organ's surface rather than
// along it: three frames of an open surface's free edge, where it curves,
// join into a sliver in the edge's plane (a lip of the lid the
// reconstruction would put over the opening), its normal in the surface.
static int across_surface(const fascia_prep_mesh *m, int32_t on, const double *x, const int32_t *c) {
  double nn;
  const double along = against_surface(m, on, x, c, &nn);
  return !(nn > 0) || fabs(along) < ACROSS_COS * nn;
}

static double mesh_area(const fascia_prep_mesh *m) {
  double a = 0, n[3];
  for (int32_t k = 0; k < m->triangle_count; ++k) a += triangle_normal(m, k, n);
  return a;
}

fascia_status prep_shell_build(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                               int32_t o, const prep_shell_frames *frames, fascia_cgal_tree **trees,
                               prep_reduced *out) {
  memset(out, 0, sizeof *out);
  const fascia_prep_organ_def *od = scene->organs + o;
  const fascia_prep_mesh *m = meshes->organs + o;
  PREP_CHECK(od->pressure == 0 || m->report.border_edges == 0, ctx, FASCIA_ERR_ARGUMENT,
             "scene '%s' organs[%d].pressure: shell '%s' is open (%d free edges): an open wall holds no pressure "
             "inside; close its mesh or leave pressure out",
             scene->path, (int)o, od->name, (int)m->report.border_edges);
  if (!trees[o])
    PREP_TRY(fascia_cgal_tree_create(ctx, m->vertex_count, m->vertices, m->triangle_count, m->triangles, trees + o));
  const double spacing = od->frame_spacing, area = mesh_area(m);
  // at most one frame per (spacing / 2)^2 pi of surface, and the shared ones
  int64_t shared = 0;
  for (int64_t k = 0; k < frames->tissue_count; ++k) shared += frames->organ[k] == o;
  const int64_t capacity = shared + (int64_t)(area / (0.78 * spacing * spacing / 4)) + 16;
  PREP_CHECK(capacity < INT32_MAX / 4, ctx, FASCIA_ERR_ARGUMENT,
             "scene '%s' organs[%d].frame_spacing: %.3g mm gives too many frames on '%s'; raise it", scene->path,
             (int)o, 1e3 * spacing, od->name);
  double *x = prep_calloc(3 * capacity, sizeof(double));
  int32_t *triangle = prep_calloc(capacity, sizeof(int32_t)), *tri = NULL;
  int64_t *global = prep_calloc(capacity, sizeof(int64_t));
  fascia_status status = FASCIA_OK;
  PREP_CHECK_GOTO(x && triangle && global, ctx, FASCIA_ERR_MEMORY, "shell '%s': out of memory", od->name);
  int32_t n = 0;
  for (int64_t k = 0; k < frames->tissue_count; ++k) {
    if (frames->organ[k] != o) continue;
    const double *p = frames->position + 3 * k;
    if (!prep_coupling_allowed(scene->tissues + frames->tissue[k], o, m, frames->triangle[k], p)) continue;
    memcpy(x + 3 * (int64_t)n, p, 3 * sizeof(double));
    triangle[n] = frames->triangle[k];
    global[n++] = k;
  }
  const int32_t first_own = n;
  PREP_TRY_GOTO(throw_frames(ctx, scene, m, o, spacing, (int32_t)capacity, x, triangle, &n));
  for (int32_t i = first_own; i < n; ++i) global[i] = frames->count + (i - first_own);
  PREP_TRY_GOTO(check_thickness(ctx, scene, o, m, trees[o], x, triangle, n));
  int32_t T = 0;
  PREP_TRY_GOTO(fascia_cgal_surface_triangles(ctx, od->name, n, x, &tri, &T));
  // the reconstruction may bridge an open surface's hole (a lid over a
  // bowl's rim): a triangle whose centre lies off the organ's surface is
  // not the wall's. A closed surface has no hole to bridge, and there a
  // triangle's centre lies off a surface curved tighter than the spacing:
  // dropping it would open the wall.
  const int open = m->report.border_edges > 0;
  int32_t kept = 0;
  for (int32_t k = 0; k < T; ++k) {
    double centre[3], closest[3];
    int32_t on;
    for (int r = 0; r < 3; ++r)
      centre[r] = (x[3 * (int64_t)tri[3 * k] + r] + x[3 * (int64_t)tri[3 * k + 1] + r] +
                   x[3 * (int64_t)tri[3 * k + 2] + r]) / 3;
    fascia_cgal_tree_closest(trees[o], 1, centre, closest, &on);
    if (open && prep_dist3(centre, closest) > OFF_SURFACE * spacing) continue;
    if (open && across_surface(m, on, x, tri + 3 * (int64_t)k)) continue;
    memmove(tri + 3 * (int64_t)kept, tri + 3 * (int64_t)k, 3 * sizeof(int32_t));
    // wound as the organ's surface under it: the samples' order through the
    // wall then follows the geometry, not the reconstruction's winding
    int32_t *c = tri + 3 * (int64_t)kept++;
    if (against_surface(m, on, x, c, NULL) < 0) {
      const int32_t swap = c[1];
      c[1] = c[2], c[2] = swap;
    }
  }
  T = kept;
  int64_t fins = 0;
  PREP_TRY_GOTO(count_fins(ctx, tri, T, &fins));
  PREP_CHECK_GOTO(fins == 0, ctx, FASCIA_ERR_ARGUMENT,
                  "scene '%s' organs[%d].frame_spacing: the frames of shell '%s', %.3g mm apart, do not make one "
                  "wall (%lld edges of more than two triangles): parts of the organ are thinner or closer together "
                  "than the spacing; lower frame_spacing",
                  scene->path, (int)o, od->name, 1e3 * spacing, (long long)fins);
  int64_t crossing = 0;
  PREP_TRY_GOTO(fascia_cgal_soup_self_intersections(ctx, od->name, n, x, T, tri, &crossing));
  PREP_CHECK_GOTO(crossing == 0, ctx, FASCIA_ERR_ARGUMENT,
                  "scene '%s' organs[%d] (shell '%s'): its wall intersects itself (%lld pairs of its triangles cross, "
                  "frames %.3g mm apart; the mesh has %d crossing pairs of its own): a wall cannot pass through "
                  "itself; repair the mesh where it folds, lower frame_spacing, or make the organ \"deformable\"",
                  scene->path, (int)o, od->name, (long long)crossing, 1e3 * spacing,
                  (int)m->report.self_intersections);
  // its own frames and samples
  out->frame_count = n - first_own;
  out->frame_position = prep_calloc(3 * (int64_t)out->frame_count, sizeof(double));
  out->frame_organ = prep_calloc(out->frame_count, sizeof(int32_t));
  out->frame_triangle = prep_calloc(out->frame_count, sizeof(int32_t));
  const int split = prep_shell_split(od);
  const int64_t points = (int64_t)T * od->section_points * split * split;
  PREP_CHECK_GOTO(points < INT32_MAX, ctx, FASCIA_ERR_ARGUMENT,
                  "scene '%s' organs[%d].sample_spacing: %.3g mm gives too many points on '%s'; raise it", scene->path,
                  (int)o, 1e3 * od->sample_spacing, od->name);
  out->sample_position = prep_calloc(3 * points, sizeof(double));
  out->sample_volume = prep_calloc(points, sizeof(double));
  out->sample_cell = prep_calloc(3 * points, sizeof(int32_t));
  PREP_CHECK_GOTO(out->frame_position && out->frame_organ && out->frame_triangle && out->sample_position &&
                      out->sample_volume && out->sample_cell,
                  ctx, FASCIA_ERR_MEMORY, "shell '%s': out of memory", od->name);
  memcpy(out->frame_position, x + 3 * (int64_t)first_own, 3 * (size_t)out->frame_count * sizeof(double));
  for (int32_t i = 0; i < out->frame_count; ++i) out->frame_organ[i] = o, out->frame_triangle[i] = triangle[first_own + i];
  double covered = 0;
  PREP_TRY_GOTO(wall_samples(ctx, od, x, global, tri, T, out, &covered));
  PREP_CHECK_GOTO(fabs(covered - area) <= AREA_TOLERANCE * area, ctx, FASCIA_ERR_ARGUMENT,
                  "scene '%s' organs[%d].frame_spacing: the wall of shell '%s' made of its frames %.3g mm apart has "
                  "%.4g cm^2, the organ's surface %.4g cm^2 (%+.1f %%, at most %.0f %% allowed): the spacing is too "
                  "coarse for the organ's shape; lower frame_spacing",
                  scene->path, (int)o, od->name, 1e3 * spacing, 1e4 * covered, 1e4 * area,
                  100 * (covered - area) / area, 100 * AREA_TOLERANCE);
  // the wall's triangles are chords of the organ's surface and miss some of
  // its area, more where the draw left frames sparse: the samples carry the
  // organ's whole area, so that the wall's mass and stiffness do not depend
  // on the draw
  for (int32_t s = 0; s < out->sample_count; ++s) out->sample_volume[s] *= area / covered;
  out->length = covered;
cleanup:
  free(x);
  free(triangle);
  free(global);
  free(tri);
  if (status != FASCIA_OK) prep_reduced_free(out);
  return status;
}

// ------------------------------------------------------------ inside pressure

fascia_status prep_shell_pressure_loads(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                        const fascia_prep_meshes *meshes, const fascia_prep_points *points,
                                        fascia_model *model) {
  for (int32_t s = 0; s < points->sample_count; ++s) {
    const int32_t o = points->sample_inside_organ[s];
    if (o < 0 || !scene->organs[o].shell || scene->organs[o].pressure == 0) continue;
    const fascia_prep_organ_def *od = scene->organs + o;
    const int32_t *c = points->sample_cell_frame + 3 * (int64_t)s;
    PREP_CHECK(c[0] >= 0 && c[1] >= 0 && c[2] >= 0, ctx, FASCIA_ERR_INTERNAL,
               "shell '%s' sample %d: no wall triangle recorded for its pressure", od->name, (int)s);
    const double *x0 = points->frame_position + 3 * (int64_t)c[0];
    double e1[3], e2[3], n[3], outward[3] = {0, 0, 0}, on[3];
    prep_sub3(points->frame_position + 3 * (int64_t)c[1], x0, e1);
    prep_sub3(points->frame_position + 3 * (int64_t)c[2], x0, e2);
    prep_cross3(e1, e2, n);
    // the wall's triangles are joined without an orientation: the organ's
    // surface under its corners (outward, as repaired) gives it
    for (int j = 0; j < 3; ++j)
      if (points->frame_organ[c[j]] == o && points->frame_triangle[c[j]] >= 0) {
        triangle_normal(meshes->organs + o, points->frame_triangle[c[j]], on);
        for (int r = 0; r < 3; ++r) outward[r] += on[r];
      }
    const double nn = prep_norm3(n), side = prep_dot3(n, outward);
    PREP_CHECK(nn > 0 && side != 0, ctx, FASCIA_ERR_INTERNAL,
               "shell '%s' sample %d: its wall triangle has no area or no side of the organ's surface", od->name,
               (int)s);
    // the sample's share of the wall's area (its volume / thickness) under
    // the pressure, f, carried by its frames as their weights share a
    // point's displacement (u = sum w_i (dx_i + dtheta_i x (x - x_i))):
    // force w_i f and torque w_i (x - x_i) x f on frame i
    const double scale = (side > 0 ? 1 : -1) * od->pressure * model->sample_volume[s] / od->thickness / nn;
    const double *x = points->sample_position + 3 * (int64_t)s;
    for (int32_t k = model->sample_offsets[s]; k < model->sample_offsets[s + 1]; ++k) {
      const int32_t i = model->pair_frame[k];
      fascia_real *load = model->frame_load + 6 * (int64_t)i;
      double f[3], arm[3], torque[3];
      for (int r = 0; r < 3; ++r) f[r] = model->pair_weight[k] * scale * n[r];
      prep_sub3(x, points->frame_position + 3 * (int64_t)i, arm);
      prep_cross3(arm, f, torque);
      for (int r = 0; r < 3; ++r) load[r] += f[r], load[3 + r] += torque[r];
    }
  }
  return FASCIA_OK;
}
