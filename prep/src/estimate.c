// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// What preparing a scene will take, before it runs: a scheduler packing a
// cohort's jobs needs each job's memory up front. The peak is set by the
// voxel stage, whose arrays scale with the scene's voxel grid over the
// organs; the grid is found from the label map (its organs' voxels) or the
// meshes' bounds, without meshing or voxelizing anything.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "labels.h"
#include "prep_util.h"

// Resident bytes of the process before any stage (libraries, the scene), and
// at the peak per surface triangle (the repair's and the distance trees'
// structures), per voxel of the tissues' grid and of the largest organ's
// grid, and per byte of input (assimp holds a mesh file whole; a label map's
// voxels go through the meshing of its labels). Fitted as upper bounds to
// the shipped scenes' peaks at one and two threads (docs/cohort.md, where
// the figures are): a label map's grids cost more per voxel than a mesh
// scene's, its organs being meshed on grids of their own, and carving their
// interface layer costs per cell of the carve's grid on their surfaces.
#define BASE_BYTES (56.0 * 1048576)
#define BYTES_PER_TRIANGLE 1000.0
#define MESH_BYTES_PER_GRID_VOXEL 32.0
#define MESH_BYTES_PER_ORGAN_VOXEL 4.0
#define MESH_BYTES_PER_FILE_BYTE 6.0
#define LABEL_BYTES_PER_GRID_VOXEL 70.0
#define LABEL_BYTES_PER_MAP_VOXEL 100.0
#define LABEL_BYTES_PER_CARVE_CELL 120.0

static void grow(double *bounds, const double *p) {
  for (int r = 0; r < 3; ++r) {
    bounds[r] = fmin(bounds[r], p[r]);
    bounds[3 + r] = fmax(bounds[3 + r], p[r]);
  }
}

// Bounds (m, world) of each label organ's voxels (bounds[6 o ..]) and the
// faces between an organ's voxel and another value (about two triangles
// each), with their area (m^2).
static fascia_status label_extent(fascia_ctx *ctx, const fascia_prep_scene *scene, double *bounds, double *faces,
                                  double *area, double *map_voxels) {
  prep_labelmap *map = NULL;
  PREP_TRY(prep_labelmap_read(ctx, scene->segmentation.file_path, scene->segmentation.frame, &map));
  *map_voxels = (double)map->dims[0] * map->dims[1] * map->dims[2];
  int32_t *organ = prep_calloc(PREP_MAX_LABEL + 1, sizeof *organ); // organ index + 1 of each label
  int32_t *box = prep_calloc(6 * (int64_t)scene->organ_count, sizeof *box);
  if (!organ || !box) {
    free(organ), free(box);
    prep_labelmap_destroy(&map);
    return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "estimate: out of memory");
  }
  for (int32_t o = scene->organ_count - 1; o >= 0; --o)
    for (int32_t k = 0; k < scene->organs[o].label_count; ++k) organ[scene->organs[o].labels[k]] = o + 1;
  const int32_t *d = map->dims;
  for (int32_t o = 0; o < scene->organ_count; ++o)
    for (int r = 0; r < 3; ++r) box[6 * o + r] = d[r], box[6 * o + 3 + r] = -1;
  const int64_t stride[3] = {1, d[0], (int64_t)d[0] * d[1]};
  double face_area[3]; // of a face across axis r: the other two columns' cross product
  for (int r = 0; r < 3; ++r) {
    const double *m = map->to_world;
    const int s = (r + 1) % 3, t = (r + 2) % 3;
    const double a[3] = {m[s], m[4 + s], m[8 + s]}, b[3] = {m[t], m[4 + t], m[8 + t]};
    double c[3];
    prep_cross3(a, b, c);
    const double zero[3] = {0, 0, 0};
    face_area[r] = prep_dist3(c, zero);
  }
  for (int32_t k = 0; k < d[2]; ++k)
    for (int32_t j = 0; j < d[1]; ++j)
      for (int32_t i = 0; i < d[0]; ++i) {
        const int64_t v = i + stride[1] * j + stride[2] * k;
        const int32_t l = map->labels[v], o = organ[l] - 1;
        if (o < 0) continue;
        const int32_t c[3] = {i, j, k};
        int32_t *b = box + 6 * o;
        for (int r = 0; r < 3; ++r) {
          b[r] = c[r] < b[r] ? c[r] : b[r], b[3 + r] = c[r] > b[3 + r] ? c[r] : b[3 + r];
          const int n = (c[r] == 0 || map->labels[v - stride[r]] != l) + (c[r] == d[r] - 1 || map->labels[v + stride[r]] != l);
          *faces += n;
          *area += n * face_area[r];
        }
      }
  for (int32_t o = 0; o < scene->organ_count; ++o)
    for (int corner = 0; corner < 8 && box[6 * o + 3] >= 0; ++corner) { // the voxels' outer faces
      double ijk[3], p[3];
      for (int r = 0; r < 3; ++r) ijk[r] = (corner >> r & 1) ? box[6 * o + 3 + r] + 0.5 : box[6 * o + r] - 0.5;
      for (int r = 0; r < 3; ++r)
        p[r] = map->to_world[4 * r] * ijk[0] + map->to_world[4 * r + 1] * ijk[1] + map->to_world[4 * r + 2] * ijk[2] +
               map->to_world[4 * r + 3];
      grow(bounds + 6 * o, p);
    }
  free(organ);
  free(box);
  prep_labelmap_destroy(&map);
  return FASCIA_OK;
}

// Bytes of the distinct mesh files the scene reads (0 for one unreadable:
// import names it).
static double mesh_file_bytes(const fascia_prep_scene *scene) {
  double bytes = 0;
  for (int32_t o = 0; o < scene->organ_count; ++o) {
    const char *path = scene->organs[o].mesh_path;
    int seen = scene->organs[o].label_count > 0;
    for (int32_t p = 0; p < o && !seen; ++p) seen = !strcmp(scene->organs[p].mesh_path, path);
    FILE *f = seen ? NULL : fopen(path, "rb");
    if (f && !fseek(f, 0, SEEK_END)) bytes += (double)ftell(f);
    if (f) fclose(f);
  }
  return bytes;
}

static double box_voxels(const double *lo, const double *hi, double h) {
  double n = 1;
  for (int r = 0; r < 3; ++r) n *= hi[r] > lo[r] ? floor((hi[r] - lo[r]) / h) + 1 : 0;
  return n;
}

// Voxels of the grid voxelize builds: the union of the volume tissues'
// boxes (the pairwise overlaps of their organs' bounds grown by max_gap, cut
// by a region box or sphere); strands and sheets add little.
static double tissue_grid_voxels(const fascia_prep_scene *scene, const double *bounds) {
  const double h = scene->voxel_size;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    const fascia_prep_tissue_def *td = scene->tissues + t;
    if (td->form != FASCIA_PREP_FORM_VOLUME) continue;
    const double reach = td->max_gap + 2 * h;
    for (int32_t i = 0; i < td->organ_count; ++i)
      for (int32_t j = i + 1; j < td->organ_count; ++j) {
        const double *a = bounds + 6 * td->organs[i], *b = bounds + 6 * td->organs[j];
        double plo[3], phi[3];
        int empty = 0;
        for (int r = 0; r < 3; ++r) {
          plo[r] = fmax(a[r], b[r]) - reach, phi[r] = fmin(a[3 + r], b[3 + r]) + reach;
          if (td->region.kind == FASCIA_PREP_REGION_BOX)
            plo[r] = fmax(plo[r], td->region.min[r]), phi[r] = fmin(phi[r], td->region.max[r]);
          else if (td->region.kind == FASCIA_PREP_REGION_SPHERE)
            plo[r] = fmax(plo[r], td->region.center[r] - td->region.radius),
            phi[r] = fmin(phi[r], td->region.center[r] + td->region.radius);
          empty |= !(phi[r] > plo[r]);
        }
        if (empty) continue;
        for (int r = 0; r < 3; ++r) lo[r] = fmin(lo[r], plo[r]), hi[r] = fmax(hi[r], phi[r]);
      }
  }
  return box_voxels(lo, hi, h);
}

fascia_status fascia_prep_estimate(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_estimate_report *out) {
  PREP_CHECK(ctx && scene && out, ctx, FASCIA_ERR_ARGUMENT, "fascia_prep_estimate: NULL argument");
  memset(out, 0, sizeof *out);
  double *bounds = prep_calloc(6 * (int64_t)scene->organ_count, sizeof *bounds), faces = 0, area = 0;
  PREP_CHECK(bounds, ctx, FASCIA_ERR_MEMORY, "estimate: out of memory");
  for (int32_t o = 0; o < scene->organ_count; ++o)
    for (int r = 0; r < 3; ++r) bounds[6 * o + r] = INFINITY, bounds[6 * o + 3 + r] = -INFINITY;
  int meshes = 0;
  fascia_status status = FASCIA_OK;
  for (int32_t o = 0; o < scene->organ_count; ++o) meshes |= !scene->organs[o].label_count;
  if (meshes) { // assimp reads meshes quickly; label organs are meshed here too when the scene mixes both
    fascia_prep_meshes *m = NULL;
    PREP_TRY_GOTO(fascia_prep_import(ctx, scene, &m));
    for (int32_t o = 0; o < m->count; ++o) {
      const fascia_prep_mesh *mesh = m->organs + o;
      for (int32_t v = 0; v < mesh->vertex_count; ++v) grow(bounds + 6 * o, mesh->vertices + 3 * v);
      out->triangles += mesh->triangle_count;
    }
    fascia_prep_meshes_destroy(&m);
    out->input_bytes = mesh_file_bytes(scene);
  } else {
    PREP_TRY_GOTO(label_extent(ctx, scene, bounds, &faces, &area, &out->input_voxels));
    out->triangles = 2 * faces;
  }
  const double h = scene->voxel_size;
  for (int r = 0; r < 6; ++r) out->bounds[r] = r < 3 ? INFINITY : -INFINITY;
  for (int32_t o = 0; o < scene->organ_count; ++o) {
    double lo[3], hi[3];
    for (int r = 0; r < 3; ++r) {
      out->bounds[r] = fmin(out->bounds[r], bounds[6 * o + r]);
      out->bounds[3 + r] = fmax(out->bounds[3 + r], bounds[6 * o + 3 + r]);
      lo[r] = bounds[6 * o + r] - 3 * h, hi[r] = bounds[6 * o + 3 + r] + 3 * h;
    }
    out->organ_voxels = fmax(out->organ_voxels, box_voxels(lo, hi, h));
  }
  out->grid_voxels = tissue_grid_voxels(scene, bounds);
  if (meshes)
    out->peak_bytes = BASE_BYTES + BYTES_PER_TRIANGLE * out->triangles + MESH_BYTES_PER_GRID_VOXEL * out->grid_voxels +
                      MESH_BYTES_PER_ORGAN_VOXEL * out->organ_voxels + MESH_BYTES_PER_FILE_BYTE * out->input_bytes;
  else {
    const double carve_cell = prep_carve_cell(scene->segmentation.interface_layer);
    out->peak_bytes = BASE_BYTES + BYTES_PER_TRIANGLE * out->triangles + LABEL_BYTES_PER_GRID_VOXEL * out->grid_voxels +
                      LABEL_BYTES_PER_MAP_VOXEL * out->input_voxels +
                      (carve_cell > 0 ? LABEL_BYTES_PER_CARVE_CELL * area / (carve_cell * carve_cell) : 0);
  }
cleanup:
  free(bounds);
  return status;
}
