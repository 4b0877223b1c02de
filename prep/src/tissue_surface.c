// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// What the connective tissue looks like, stored in the model for drawing:
// the boundary of the volume tissues' regions on the voxel grid, smoothed
// and meshed (OpenVDB, as the surfaces of organs made of labels); each
// strand as a tube of its radius through its frames; each sheet as its mesh
// over its frames. The simulation carries it with the frames
// (fascia_solver_tissue_surface).
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "prep_util.h"
#include "reduced.h"

#define SURFACE_SMOOTHING 1 // mean-filter passes: voxel steps rounded, thin layers kept

#define TUBE_SIDES 8 // a strand's tube: an octagon around its axis

// The frames of tissue t, in the order its builder made them (one
// contiguous run for a strand or a sheet), into list; their count.
static int32_t tissue_frames(const fascia_prep_points *points, int32_t t, int32_t *list) {
  int32_t n = 0;
  for (int32_t i = 0; i < points->frame_count; ++i)
    if (points->frame_tissue[i] == t) list[n++] = i;
  return n;
}

// Appends the strands' tubes and the sheets' meshes to *out (the volume
// tissues' boundary, possibly empty).
static fascia_status add_reduced(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                 const fascia_prep_points *points, fascia_surface *out) {
  int64_t nv = out->vertex_count, nt = out->triangle_count;
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    int32_t n = 0;
    for (int32_t i = 0; i < points->frame_count; ++i) n += points->frame_tissue[i] == t;
    if (scene->tissues[t].form == FASCIA_PREP_FORM_STRAND && n >= 2)
      nv += (int64_t)TUBE_SIDES * n, nt += 2 * (int64_t)TUBE_SIDES * prep_strand_intervals(points, t, NULL);
    if (scene->tissues[t].form == FASCIA_PREP_FORM_SHEET) nv += n, nt += meshes->sheets[t].triangle_count;
  }
  if (nv == out->vertex_count) return FASCIA_OK;
  PREP_CHECK(nv <= INT32_MAX && nt <= INT32_MAX, ctx, FASCIA_ERR_MEMORY, "tissue surface: too large to draw");
  fascia_surface all = {0};
  int32_t *list = prep_calloc(points->frame_count, sizeof(int32_t));
  fascia_status st = list ? fascia_surface_alloc(ctx, &all, (int32_t)nv, (int32_t)nt)
                          : PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "tissue surface: out of memory");
  if (st != FASCIA_OK) {
    free(list);
    return st;
  }
  memcpy(all.vertices, out->vertices, 3 * (size_t)out->vertex_count * sizeof(fascia_real));
  memcpy(all.triangles, out->triangles, 3 * (size_t)out->triangle_count * sizeof(int32_t));
  int32_t v = out->vertex_count, f = out->triangle_count;
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    const fascia_prep_tissue_def *td = scene->tissues + t;
    const int32_t n = tissue_frames(points, t, list);
    if (td->form == FASCIA_PREP_FORM_STRAND && n >= 2) {
      // a ring of TUBE_SIDES vertices around each frame, normal to the strand
      // there, and a tube along each interval (reduced.c: curve and fibres)
      const int64_t intervals = prep_strand_intervals(points, t, NULL);
      int32_t *pairs = prep_calloc(2 * intervals + 2, sizeof(int32_t));
      double *tangent = prep_calloc(3 * (int64_t)points->frame_count, sizeof(double));
      if (!pairs || !tangent) {
        free(pairs), free(tangent), free(list), free(all.vertices), free(all.triangles);
        return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "tissue surface: out of memory");
      }
      prep_strand_intervals(points, t, pairs);
      for (int64_t k = 0; k < intervals; ++k) { // each frame's tangent: its intervals' directions, signs aligned
        const double *xa = points->frame_position + 3 * (int64_t)pairs[2 * k];
        const double *xb = points->frame_position + 3 * (int64_t)pairs[2 * k + 1];
        double d[3] = {xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]};
        const double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (int e = 0; e < 2; ++e) {
          double *tg = tangent + 3 * (int64_t)pairs[2 * k + e];
          const double sign = tg[0] * d[0] + tg[1] * d[1] + tg[2] * d[2] < 0 ? -1 : 1;
          for (int c = 0; c < 3; ++c) tg[c] += sign * d[c] / len;
        }
      }
      // one reference axis for the whole strand, the one farthest from its tangents: untwisted rings
      int axis = 0;
      double least = INFINITY;
      for (int e = 0; e < 3; ++e) {
        double most = 0;
        for (int32_t k = 0; k < n; ++k) {
          const double *tg = tangent + 3 * (int64_t)list[k];
          const double len = sqrt(tg[0] * tg[0] + tg[1] * tg[1] + tg[2] * tg[2]);
          if (len > 0) most = fmax(most, fabs(tg[e]) / len);
        }
        if (most < least) least = most, axis = e;
      }
      const int32_t first = v;
      for (int32_t k = 0; k < n; ++k) {
        double a[3], u[3], w[3];
        memcpy(a, tangent + 3 * (int64_t)list[k], sizeof a);
        double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        if (!(len > 0)) a[0] = 1, a[1] = a[2] = 0, len = 1;
        for (int c = 0; c < 3; ++c) a[c] /= len;
        const double e[3] = {axis == 0, axis == 1, axis == 2};
        u[0] = a[1] * e[2] - a[2] * e[1], u[1] = a[2] * e[0] - a[0] * e[2], u[2] = a[0] * e[1] - a[1] * e[0];
        const double un = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        for (int c = 0; c < 3; ++c) u[c] /= un;
        w[0] = a[1] * u[2] - a[2] * u[1], w[1] = a[2] * u[0] - a[0] * u[2], w[2] = a[0] * u[1] - a[1] * u[0];
        for (int s = 0; s < TUBE_SIDES; ++s, ++v) {
          const double angle = 2 * acos(-1.0) * s / TUBE_SIDES;
          const double *x = points->frame_position + 3 * (int64_t)list[k];
          for (int c = 0; c < 3; ++c)
            all.vertices[3 * (int64_t)v + c] = x[c] + td->radius * (cos(angle) * u[c] + sin(angle) * w[c]);
        }
      }
      for (int64_t k = 0; k < intervals; ++k) {
        int32_t ring[2] = {-1, -1}; // the rings of the interval's frames: their places in list
        for (int32_t j = 0; j < n; ++j)
          for (int e = 0; e < 2; ++e)
            if (list[j] == pairs[2 * k + e]) ring[e] = j;
        for (int s = 0; s < TUBE_SIDES; ++s) { // two triangles per side, wound outward
          const int32_t p = first + ring[0] * TUBE_SIDES, q = first + ring[1] * TUBE_SIDES, s1 = (s + 1) % TUBE_SIDES;
          const int32_t quad[6] = {p + s, p + s1, q + s1, p + s, q + s1, q + s};
          memcpy(all.triangles + 3 * (int64_t)f, quad, sizeof quad);
          f += 2;
        }
      }
      free(pairs), free(tangent);
    } else if (td->form == FASCIA_PREP_FORM_SHEET) {
      // its frames are its merged vertices, in order: the mesh over them
      for (int32_t k = 0; k < n; ++k, ++v)
        memcpy(all.vertices + 3 * (int64_t)v, points->frame_position + 3 * (int64_t)list[k], 3 * sizeof(fascia_real));
      const fascia_prep_mesh *sheet = meshes->sheets + t;
      for (int64_t k = 0; k < 3 * (int64_t)sheet->triangle_count; ++k)
        all.triangles[3 * (int64_t)f + k] = v - n + sheet->triangles[k];
      f += sheet->triangle_count;
    }
  }
  free(list);
  free(out->vertices), free(out->triangles);
  *out = all;
  return FASCIA_OK;
}

// The volume tissues' boundary.
static fascia_status volume_surface(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_volume *vol,
                                    fascia_surface *out) {
  const int64_t n = (int64_t)vol->dims[0] * vol->dims[1] * vol->dims[2];
  float *inside = prep_calloc(n, sizeof(float));
  PREP_CHECK(inside, ctx, FASCIA_ERR_MEMORY, "tissue surface: out of memory for %lld voxels", (long long)n);
  for (int64_t v = 0; v < n; ++v) inside[v] = vol->region[v] >= 1 && vol->region[v] <= scene->tissue_count;
  double *vertices = NULL;
  int32_t *triangles = NULL, nv = 0, nt = 0;
  const fascia_status status =
      fascia_vdb_indicator_surface(ctx, vol->dims, inside, SURFACE_SMOOTHING, &vertices, &nv, &triangles, &nt);
  free(inside);
  if (status == FASCIA_OK) {
    const fascia_status st = fascia_surface_alloc(ctx, out, nv, nt);
    if (st == FASCIA_OK) {
      // voxel (i, j, k) is centred at origin + h (i, j, k)
      for (int64_t k = 0; k < 3 * (int64_t)nv; ++k) out->vertices[k] = vol->origin[k % 3] + vol->voxel_size * vertices[k];
      memcpy(out->triangles, triangles, 3 * (size_t)nt * sizeof(int32_t));
    }
    free(vertices);
    free(triangles);
    return st;
  }
  return status;
}

fascia_status prep_tissue_surface(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                  const fascia_prep_volume *vol, const fascia_prep_points *points,
                                  fascia_surface *out) {
  PREP_TRY(volume_surface(ctx, scene, vol, out));
  return add_reduced(ctx, scene, meshes, points, out);
}
