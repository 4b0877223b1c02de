// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A preview for ParaView of what prep built, as VTK XML files
// (fascia/vtk_xml.h): each organ's surface, the region grid, the frames
// (with what holds each), the samples and the shared (coupling) frames, and
// preview.pvd, which opens them all as blocks named after them; strands as
// lines and sheets as surfaces. Each file is
// written under a temporary name and renamed (fascia/files.h), so a reader
// never sees half a file.
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "fascia/files.h"
#include "fascia/vtk_xml.h"
#include "prep_util.h"
#include "reduced.h"

/// What holds a frame, in the preview's `kind` array.
enum { KIND_FREE = 0, KIND_FIXED = 1, KIND_PRESCRIBED = 2, KIND_RIGID = 3, KIND_DEFORMABLE = 4 };

typedef struct preview {
  fascia_ctx *ctx;
  const char *dir;
  fascia_file *pvd; ///< preview.pvd, its parts listed as they are written
  int parts;
} preview;

static fascia_status open_part(preview *p, const char *name, fascia_file **file) {
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", p->dir, name);
  return fascia_file_open(p->ctx, "preview", path, file);
}

// Commits a part's file and lists it in preview.pvd under its block name.
static fascia_status close_part(preview *p, fascia_file **file, const char *file_name, const char *block) {
  PREP_TRY(fascia_file_commit(file));
  FILE *pvd = fascia_file_stream(p->pvd);
  fprintf(pvd, "    <DataSet timestep=\"0\" group=\"\" part=\"%d\" name=\"", p->parts++);
  fascia_xml_text(pvd, block); // names are data
  fputs("\" file=\"", pvd);
  fascia_xml_text(pvd, file_name);
  fputs("\"/>\n", pvd);
  return FASCIA_OK;
}

static fascia_status write_organs(preview *p, const fascia_prep_meshes *meshes) {
  for (int32_t o = 0; o < meshes->count; ++o) {
    const fascia_prep_mesh *m = meshes->organs + o;
    char name[FASCIA_NAME_SIZE + 8];
    snprintf(name, sizeof name, "%s.vtp", m->name);
    fascia_file *file = NULL;
    PREP_TRY(open_part(p, name, &file));
    FILE *f = fascia_file_stream(file);
    fascia_vtk_begin(f, "PolyData", m->vertices, m->vertex_count, 3, m->triangles, m->triangle_count);
    fascia_vtk_end(f, "PolyData");
    PREP_TRY(close_part(p, &file, name, m->name));
  }
  return FASCIA_OK;
}

// The region grid: region (0 none, t + 1 tissue t, then the deformable
// organs' insides) and the signed distance to the nearest organ (contour 0
// shows the organs as voxelized).
static fascia_status write_region(preview *p, const fascia_prep_volume *vol) {
  const int64_t n = (int64_t)vol->dims[0] * vol->dims[1] * vol->dims[2];
  int32_t *region = prep_calloc(n, sizeof(int32_t));
  float *distance = prep_calloc(n, sizeof(float));
  fascia_status status = FASCIA_OK;
  fascia_file *file = NULL;
  PREP_CHECK_GOTO(region && distance, p->ctx, FASCIA_ERR_MEMORY, "preview: out of memory for %lld voxels",
                  (long long)n);
  for (int64_t k = 0; k < n; ++k) {
    double d = INFINITY;
    for (int32_t o = 0; o < vol->organ_count; ++o)
      if (vol->distance[o]) d = fmin(d, vol->distance[o][k]);
    distance[k] = (float)(isfinite(d) ? d : 1);
    region[k] = vol->region[k];
  }
  PREP_TRY_GOTO(open_part(p, "region.vti", &file));
  FILE *f = fascia_file_stream(file);
  fascia_vtk_begin_image(f, vol->dims, vol->origin, vol->voxel_size);
  fascia_vtk_array(f, "region", 1, NULL, region, n);
  fascia_vtk_array_float(f, "organ_distance", distance, n);
  fascia_vtk_end(f, "ImageData");
  status = close_part(p, &file, "region.vti", "region");
cleanup:
  fascia_file_discard(&file);
  free(region);
  free(distance);
  return status;
}

// Points of a set (all, or pick[k] of them) with one vertex each.
static fascia_status begin_points(preview *p, const char *name, fascia_file **file, const double *x, int64_t n,
                                  const int32_t *pick, double *picked) {
  PREP_TRY(open_part(p, name, file));
  if (pick)
    for (int64_t k = 0; k < n; ++k) memcpy(picked + 3 * k, x + 3 * (int64_t)pick[k], 3 * sizeof(double));
  fascia_vtk_begin(fascia_file_stream(*file), "UnstructuredGrid", pick ? picked : x, n, 1, NULL, n);
  return FASCIA_OK;
}

// What holds each frame: the organ it is shared with (its kind), the
// deformable organ whose inside holds it, or nothing (a free tissue frame).
static void frame_kinds(const fascia_prep_scene *scene, const fascia_prep_points *pts, const int32_t *shared,
                        int32_t *kind) {
  static const int32_t of_organ[FASCIA_ORGAN_KIND_COUNT_] = {
      [FASCIA_ORGAN_FIXED] = KIND_FIXED, [FASCIA_ORGAN_PRESCRIBED] = KIND_PRESCRIBED,
      [FASCIA_ORGAN_RIGID] = KIND_RIGID, [FASCIA_ORGAN_DEFORMABLE] = KIND_DEFORMABLE};
  for (int32_t i = 0; i < pts->frame_count; ++i) {
    kind[i] = KIND_FREE;
    if (pts->frame_inside_organ[i] >= 0) kind[i] = KIND_DEFORMABLE;
    if (shared[i] >= 0) kind[i] = of_organ[scene->organs[shared[i]].kind];
  }
}

static fascia_status write_points(preview *p, const fascia_prep_scene *scene, const fascia_prep_points *pts,
                                  const fascia_prep_coupling *cpl) {
  const int64_t N = pts->frame_count, S = pts->sample_count;
  int32_t *shared = prep_calloc(N, sizeof(int32_t)), *kind = prep_calloc(N, sizeof(int32_t));
  double *picked = prep_calloc(3 * (int64_t)cpl->count, sizeof(double));
  fascia_status status = FASCIA_OK;
  fascia_file *file = NULL;
  PREP_CHECK_GOTO(shared && kind && picked, p->ctx, FASCIA_ERR_MEMORY, "preview: out of memory");
  for (int32_t i = 0; i < N; ++i) shared[i] = -1;
  for (int32_t c = cpl->count - 1; c >= 0; --c) shared[cpl->frame[c]] = cpl->organ[c];
  frame_kinds(scene, pts, shared, kind);

  PREP_TRY_GOTO(begin_points(p, "frames.vtu", &file, pts->frame_position, N, NULL, NULL));
  FILE *f = fascia_file_stream(file);
  fascia_vtk_array(f, "kind", 1, NULL, kind, N);
  fascia_vtk_array(f, "tissue", 1, NULL, pts->frame_tissue, N);
  fascia_vtk_array(f, "inside_organ", 1, NULL, pts->frame_inside_organ, N);
  fascia_vtk_array(f, "on_organ", 1, NULL, pts->frame_organ, N);
  fascia_vtk_array(f, "shared_with_organ", 1, NULL, shared, N);
  fascia_vtk_end(f, "UnstructuredGrid");
  PREP_TRY_GOTO(close_part(p, &file, "frames.vtu", "frames"));

  PREP_TRY_GOTO(begin_points(p, "samples.vtu", &file, pts->sample_position, S, NULL, NULL));
  f = fascia_file_stream(file);
  fascia_vtk_array(f, "tissue", 1, NULL, pts->sample_tissue, S);
  fascia_vtk_array(f, "inside_organ", 1, NULL, pts->sample_inside_organ, S);
  fascia_vtk_array(f, "volume", 1, pts->sample_volume, NULL, S);
  fascia_vtk_end(f, "UnstructuredGrid");
  PREP_TRY_GOTO(close_part(p, &file, "samples.vtu", "samples"));

  PREP_TRY_GOTO(begin_points(p, "coupling.vtu", &file, pts->frame_position, cpl->count, cpl->frame, picked));
  f = fascia_file_stream(file);
  fascia_vtk_array(f, "organ", 1, NULL, cpl->organ, cpl->count);
  fascia_vtk_array(f, "triangle", 1, NULL, cpl->triangle, cpl->count);
  fascia_vtk_end(f, "UnstructuredGrid");
  status = close_part(p, &file, "coupling.vtu", "coupling");
cleanup:
  fascia_file_discard(&file);
  free(shared);
  free(kind);
  free(picked);
  return status;
}

// Strands as lines and sheets as surfaces over their frames, one file
// each (strands.vtp, sheets.vtp; ASCII VTK XML): point data tissue, free
// (1: a free frame, 0: shared with an organ) and radius (a strand's
// cross-section radius, a sheet's half thickness), m. Written only when the
// scene has them.
static fascia_status write_reduced(preview *p, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                   const fascia_prep_points *pts, const fascia_prep_coupling *cpl, int form) {
  const int strand = form == FASCIA_PREP_FORM_STRAND;
  int64_t points = 0, cells = 0;
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    if (scene->tissues[t].form != form) continue;
    int64_t n = 0;
    for (int32_t i = 0; i < pts->frame_count; ++i) n += pts->frame_tissue[i] == t;
    points += n;
    cells += strand ? prep_strand_intervals(pts, t, NULL) : meshes->sheets[t].triangle_count;
  }
  if (points == 0) return FASCIA_OK;
  uint8_t *coupled = prep_calloc(pts->frame_count, 1);
  PREP_CHECK(coupled, p->ctx, FASCIA_ERR_MEMORY, "preview: out of memory");
  for (int32_t c = 0; c < cpl->count; ++c) coupled[cpl->frame[c]] = 1;
  const char *name = strand ? "strands.vtp" : "sheets.vtp";
  fascia_file *file = NULL;
  fascia_status status = open_part(p, name, &file);
  if (status != FASCIA_OK) {
    free(coupled);
    return status;
  }
  FILE *f = fascia_file_stream(file);
  fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\">\n<PolyData>\n<Piece "
             "NumberOfPoints=\"%lld\" NumberOfLines=\"%lld\" NumberOfPolys=\"%lld\">\n",
          (long long)points, strand ? (long long)cells : 0LL, strand ? 0LL : (long long)cells);
  // the pass over the tissues is repeated per section: the frames of a
  // strand or a sheet are one contiguous range, in the order it built them
  fprintf(f, "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
  for (int32_t i = 0; i < pts->frame_count; ++i)
    if (pts->frame_tissue[i] >= 0 && scene->tissues[pts->frame_tissue[i]].form == form)
      fprintf(f, "%.9g %.9g %.9g\n", pts->frame_position[3 * (int64_t)i], pts->frame_position[3 * (int64_t)i + 1],
              pts->frame_position[3 * (int64_t)i + 2]);
  fprintf(f, "</DataArray></Points>\n<%s><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">\n",
          strand ? "Lines" : "Polys");
  int64_t base = 0;
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    if (scene->tissues[t].form != form) continue;
    int64_t n = 0;
    for (int32_t i = 0; i < pts->frame_count; ++i) n += pts->frame_tissue[i] == t;
    if (strand) { // its intervals (curve and fibres): frame indices made local to its run
      const int64_t count = prep_strand_intervals(pts, t, NULL);
      int32_t *pairs = prep_calloc(2 * count + 2, sizeof(int32_t));
      int32_t first = 0;
      while (first < pts->frame_count && pts->frame_tissue[first] != t) ++first;
      if (pairs) prep_strand_intervals(pts, t, pairs);
      for (int64_t k = 0; pairs && k < count; ++k)
        fprintf(f, "%lld %lld\n", (long long)(base + pairs[2 * k] - first), (long long)(base + pairs[2 * k + 1] - first));
      free(pairs);
    } else
      for (int32_t k = 0; k < meshes->sheets[t].triangle_count; ++k) {
        const int32_t *c = meshes->sheets[t].triangles + 3 * (int64_t)k;
        fprintf(f, "%lld %lld %lld\n", (long long)(base + c[0]), (long long)(base + c[1]), (long long)(base + c[2]));
      }
    base += n;
  }
  fprintf(f, "</DataArray><DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n");
  for (int64_t c = 1; c <= cells; ++c) fprintf(f, "%lld\n", (long long)(c * (strand ? 2 : 3)));
  fprintf(f, "</DataArray></%s>\n<PointData>\n", strand ? "Lines" : "Polys");
  static const char *const arrays[3] = {"tissue", "free", "radius"};
  for (int a = 0; a < 3; ++a) {
    fprintf(f, "<DataArray type=\"%s\" Name=\"%s\" format=\"ascii\">\n", a == 2 ? "Float64" : "Int32", arrays[a]);
    for (int32_t i = 0; i < pts->frame_count; ++i) {
      const int32_t t = pts->frame_tissue[i];
      if (t < 0 || scene->tissues[t].form != form) continue;
      if (a == 0) fprintf(f, "%d\n", (int)t);
      else if (a == 1) fprintf(f, "%d\n", !coupled[i]);
      else fprintf(f, "%.9g\n", strand ? scene->tissues[t].radius : scene->tissues[t].thickness / 2);
    }
    fprintf(f, "</DataArray>\n");
  }
  fprintf(f, "</PointData>\n</Piece>\n</PolyData>\n</VTKFile>\n");
  free(coupled);
  return close_part(p, &file, name, strand ? "strands" : "sheets");
}

fascia_status fascia_prep_preview(fascia_ctx *ctx, const char *dir, const fascia_prep_scene *scene,
                                  const fascia_prep_meshes *meshes, const fascia_prep_volume *volume,
                                  const fascia_prep_points *points, const fascia_prep_coupling *coupling) {
  PREP_CHECK(ctx && dir && scene && meshes && volume && points && coupling, ctx, FASCIA_ERR_ARGUMENT,
             "fascia_prep_preview: NULL argument");
  struct stat st;
  if (stat(dir, &st) != 0)
    PREP_CHECK(mkdir(dir, 0777) == 0, ctx, FASCIA_ERR_IO, "preview folder '%s': cannot create (%s)", dir,
               strerror(errno));
  else
    PREP_CHECK(S_ISDIR(st.st_mode), ctx, FASCIA_ERR_IO, "preview folder '%s' exists and is not a folder", dir);
  fascia_ctx_progress(ctx, "preview", -1, dir);
  preview p = {ctx, dir, NULL, 0};
  char path[4096];
  snprintf(path, sizeof path, "%s/preview.pvd", dir);
  PREP_TRY(fascia_file_open(ctx, "preview", path, &p.pvd));
  fputs("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n",
        fascia_file_stream(p.pvd));
  fascia_status status = write_organs(&p, meshes);
  if (status == FASCIA_OK) status = write_region(&p, volume);
  if (status == FASCIA_OK) status = write_points(&p, scene, points, coupling);
  if (status == FASCIA_OK) status = write_reduced(&p, scene, meshes, points, coupling, FASCIA_PREP_FORM_STRAND);
  if (status == FASCIA_OK) status = write_reduced(&p, scene, meshes, points, coupling, FASCIA_PREP_FORM_SHEET);
  if (status != FASCIA_OK) {
    fascia_file_discard(&p.pvd);
    return status;
  }
  fputs("  </Collection>\n</VTKFile>\n", fascia_file_stream(p.pvd));
  return fascia_file_commit(&p.pvd);
}
