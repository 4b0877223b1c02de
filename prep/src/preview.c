// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A preview for ParaView of what prep built, as legacy VTK files (binary,
// big-endian, as the legacy format requires): organ surfaces, the region's
// voxel grid, frames, samples and the shared (coupling) frames. Each file is
// written under a temporary name and renamed (fascia/files.h), so a reader
// never sees half a file.
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "fascia/files.h"
#include "prep_util.h"

static void put_be32(FILE *f, const void *value) {
  uint32_t x;
  memcpy(&x, value, 4);
  const uint8_t b[4] = {(uint8_t)(x >> 24), (uint8_t)(x >> 16), (uint8_t)(x >> 8), (uint8_t)x};
  fwrite(b, 1, 4, f);
}
static void put_float(FILE *f, double v) {
  const float x = (float)v;
  put_be32(f, &x);
}
static void put_int(FILE *f, int32_t v) { put_be32(f, &v); }

typedef struct vtk_file {
  FILE *f;
  fascia_file *file; ///< written under a temporary name, renamed when complete
} vtk_file;

static fascia_status vtk_open(fascia_ctx *ctx, vtk_file *v, const char *dir, const char *name, const char *title,
                              const char *dataset) {
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  v->file = NULL;
  PREP_TRY(fascia_file_open(ctx, "preview", path, &v->file));
  v->f = fascia_file_stream(v->file);
  fprintf(v->f, "# vtk DataFile Version 3.0\n%s\nBINARY\nDATASET %s\n", title, dataset);
  return FASCIA_OK;
}

static fascia_status vtk_close(fascia_ctx *ctx, vtk_file *v) {
  (void)ctx; // the file keeps the ctx it was opened with
  v->f = NULL;
  return fascia_file_commit(&v->file);
}

// Points with one vertex cell each.
static void vtk_points(FILE *f, int64_t n, const double *x, const int32_t *pick) {
  fprintf(f, "POINTS %lld float\n", (long long)n);
  for (int64_t k = 0; k < n; ++k) {
    const double *p = x + 3 * (pick ? pick[k] : k);
    put_float(f, p[0]), put_float(f, p[1]), put_float(f, p[2]);
  }
  fprintf(f, "\nVERTICES %lld %lld\n", (long long)n, (long long)(2 * n));
  for (int64_t k = 0; k < n; ++k) put_int(f, 1), put_int(f, (int32_t)k);
  fprintf(f, "\nPOINT_DATA %lld\n", (long long)n);
}

static void vtk_int_field(FILE *f, const char *name, int64_t n, const int32_t *values, const int32_t *pick) {
  fprintf(f, "SCALARS %s int 1\nLOOKUP_TABLE default\n", name);
  for (int64_t k = 0; k < n; ++k) put_int(f, values[pick ? pick[k] : k]);
  fprintf(f, "\n");
}

static fascia_status write_organs(fascia_ctx *ctx, const char *dir, const fascia_prep_meshes *meshes) {
  vtk_file v;
  PREP_TRY(vtk_open(ctx, &v, dir, "organs.vtk", "fascia prep: organ surfaces", "POLYDATA"));
  int64_t nv = 0, nt = 0;
  for (int32_t o = 0; o < meshes->count; ++o) nv += meshes->organs[o].vertex_count, nt += meshes->organs[o].triangle_count;
  fprintf(v.f, "POINTS %lld float\n", (long long)nv);
  for (int32_t o = 0; o < meshes->count; ++o)
    for (int64_t k = 0; k < 3 * (int64_t)meshes->organs[o].vertex_count; ++k) put_float(v.f, meshes->organs[o].vertices[k]);
  fprintf(v.f, "\nPOLYGONS %lld %lld\n", (long long)nt, (long long)(4 * nt));
  int64_t base = 0;
  for (int32_t o = 0; o < meshes->count; ++o) {
    const fascia_prep_mesh *m = meshes->organs + o;
    for (int64_t t = 0; t < m->triangle_count; ++t) {
      put_int(v.f, 3);
      for (int r = 0; r < 3; ++r) put_int(v.f, (int32_t)(base + m->triangles[3 * t + r]));
    }
    base += m->vertex_count;
  }
  fprintf(v.f, "\nCELL_DATA %lld\nSCALARS organ int 1\nLOOKUP_TABLE default\n", (long long)nt);
  for (int32_t o = 0; o < meshes->count; ++o)
    for (int64_t t = 0; t < meshes->organs[o].triangle_count; ++t) put_int(v.f, o);
  fprintf(v.f, "\nSCALARS part int 1\nLOOKUP_TABLE default\n");
  for (int32_t o = 0; o < meshes->count; ++o)
    for (int64_t t = 0; t < meshes->organs[o].triangle_count; ++t) put_int(v.f, meshes->organs[o].triangle_part[t]);
  fprintf(v.f, "\n");
  return vtk_close(ctx, &v);
}

static fascia_status write_region(fascia_ctx *ctx, const char *dir, const fascia_prep_volume *vol) {
  vtk_file v;
  PREP_TRY(vtk_open(ctx, &v, dir, "region.vtk", "fascia prep: regions (tissue = index + 1, then deformable organs' insides, 0 none)",
                    "STRUCTURED_POINTS"));
  const int64_t n = (int64_t)vol->dims[0] * vol->dims[1] * vol->dims[2];
  fprintf(v.f, "DIMENSIONS %d %d %d\nORIGIN %.9g %.9g %.9g\nSPACING %.9g %.9g %.9g\nPOINT_DATA %lld\n",
          (int)vol->dims[0], (int)vol->dims[1], (int)vol->dims[2], vol->origin[0], vol->origin[1], vol->origin[2],
          vol->voxel_size, vol->voxel_size, vol->voxel_size, (long long)n);
  fprintf(v.f, "SCALARS tissue int 1\nLOOKUP_TABLE default\n");
  for (int64_t k = 0; k < n; ++k) put_int(v.f, vol->region[k]);
  // signed distance to the nearest organ (negative inside one): contour 0 shows the organs as voxelized
  fprintf(v.f, "\nSCALARS organ_distance float 1\nLOOKUP_TABLE default\n");
  for (int64_t k = 0; k < n; ++k) {
    double d = INFINITY;
    for (int32_t o = 0; o < vol->organ_count; ++o)
      if (vol->distance[o]) d = fmin(d, vol->distance[o][k]);
    put_float(v.f, isfinite(d) ? d : 1);
  }
  fprintf(v.f, "\n");
  return vtk_close(ctx, &v);
}

static fascia_status write_points(fascia_ctx *ctx, const char *dir, const fascia_prep_points *pts,
                                  const fascia_prep_coupling *cpl) {
  vtk_file v;
  PREP_TRY(vtk_open(ctx, &v, dir, "frames.vtk", "fascia prep: frames", "POLYDATA"));
  vtk_points(v.f, pts->frame_count, pts->frame_position, NULL);
  vtk_int_field(v.f, "tissue", pts->frame_count, pts->frame_tissue, NULL);
  vtk_int_field(v.f, "inside_organ", pts->frame_count, pts->frame_inside_organ, NULL);
  vtk_int_field(v.f, "on_organ", pts->frame_count, pts->frame_organ, NULL);
  int32_t *shared = prep_calloc(pts->frame_count, sizeof(int32_t));
  if (!shared) fascia_file_discard(&v.file);
  PREP_CHECK(shared, ctx, FASCIA_ERR_MEMORY, "preview: out of memory");
  for (int32_t i = 0; i < pts->frame_count; ++i) shared[i] = -1;
  for (int32_t c = 0; c < cpl->count; ++c) shared[cpl->frame[c]] = cpl->organ[c];
  vtk_int_field(v.f, "shared_with_organ", pts->frame_count, shared, NULL);
  free(shared);
  PREP_TRY(vtk_close(ctx, &v));

  PREP_TRY(vtk_open(ctx, &v, dir, "samples.vtk", "fascia prep: samples", "POLYDATA"));
  vtk_points(v.f, pts->sample_count, pts->sample_position, NULL);
  vtk_int_field(v.f, "tissue", pts->sample_count, pts->sample_tissue, NULL);
  vtk_int_field(v.f, "inside_organ", pts->sample_count, pts->sample_inside_organ, NULL);
  fprintf(v.f, "SCALARS volume float 1\nLOOKUP_TABLE default\n");
  for (int32_t s = 0; s < pts->sample_count; ++s) put_float(v.f, pts->sample_volume[s]);
  fprintf(v.f, "\n");
  PREP_TRY(vtk_close(ctx, &v));

  PREP_TRY(vtk_open(ctx, &v, dir, "coupling.vtk", "fascia prep: frames shared with organs", "POLYDATA"));
  vtk_points(v.f, cpl->count, pts->frame_position, cpl->frame);
  vtk_int_field(v.f, "organ", cpl->count, cpl->organ, NULL);
  vtk_int_field(v.f, "triangle", cpl->count, cpl->triangle, NULL);
  return vtk_close(ctx, &v);
}

fascia_status fascia_prep_preview(fascia_ctx *ctx, const char *dir, const fascia_prep_meshes *meshes,
                                  const fascia_prep_volume *volume, const fascia_prep_points *points,
                                  const fascia_prep_coupling *coupling) {
  PREP_CHECK(ctx && dir && meshes && volume && points && coupling, ctx, FASCIA_ERR_ARGUMENT,
             "fascia_prep_preview: NULL argument");
  struct stat st;
  if (stat(dir, &st) != 0)
    PREP_CHECK(mkdir(dir, 0777) == 0, ctx, FASCIA_ERR_IO, "preview folder '%s': cannot create (%s)", dir,
               strerror(errno));
  else
    PREP_CHECK(S_ISDIR(st.st_mode), ctx, FASCIA_ERR_IO, "preview folder '%s' exists and is not a folder", dir);
  fascia_ctx_progress(ctx, "preview", -1, dir);
  PREP_TRY(write_organs(ctx, dir, meshes));
  PREP_TRY(write_region(ctx, dir, volume));
  PREP_TRY(write_points(ctx, dir, points, coupling));
  return FASCIA_OK;
}
