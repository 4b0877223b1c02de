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
      nv += (int64_t)TUBE_SIDES * n, nt += 2 * (int64_t)TUBE_SIDES * (n - 1);
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
    const double *x0 = points->frame_position + 3 * (int64_t)list[0];
    if (td->form == FASCIA_PREP_FORM_STRAND && n >= 2) {
      // a ring of TUBE_SIDES vertices around each frame, in the plane normal to the (straight) axis
      const double *x1 = points->frame_position + 3 * (int64_t)list[n - 1];
      double a[3] = {x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2]}, u[3], w[3];
      const double length = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
      for (int c = 0; c < 3; ++c) a[c] /= length;
      const double e[3] = {fabs(a[0]) < 0.9 ? 1 : 0, fabs(a[0]) < 0.9 ? 0 : 1, 0};
      u[0] = a[1] * e[2] - a[2] * e[1], u[1] = a[2] * e[0] - a[0] * e[2], u[2] = a[0] * e[1] - a[1] * e[0];
      const double un = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
      for (int c = 0; c < 3; ++c) u[c] /= un;
      w[0] = a[1] * u[2] - a[2] * u[1], w[1] = a[2] * u[0] - a[0] * u[2], w[2] = a[0] * u[1] - a[1] * u[0];
      const int32_t first = v;
      for (int32_t k = 0; k < n; ++k)
        for (int s = 0; s < TUBE_SIDES; ++s, ++v) {
          const double angle = 2 * acos(-1.0) * s / TUBE_SIDES;
          const double *x = points->frame_position + 3 * (int64_t)list[k];
          for (int c = 0; c < 3; ++c)
            all.vertices[3 * (int64_t)v + c] = x[c] + td->radius * (cos(angle) * u[c] + sin(angle) * w[c]);
        }
      for (int32_t k = 0; k + 1 < n; ++k)
        for (int s = 0; s < TUBE_SIDES; ++s) { // two triangles per side, wound outward
          const int32_t p = first + k * TUBE_SIDES, q = p + TUBE_SIDES, s1 = (s + 1) % TUBE_SIDES;
          const int32_t quad[6] = {p + s, p + s1, q + s1, p + s, q + s1, q + s};
          memcpy(all.triangles + 3 * (int64_t)f, quad, sizeof quad);
          f += 2;
        }
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
