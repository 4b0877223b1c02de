// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Organs made of labels (docs/labelmaps.md): each organ's surface is the
// smoothed indicator of its labels, meshed at the image's voxels and placed
// in the world by the image's affine; the voxelize stage then treats it
// like any mesh, at the scene's voxel size. Organs whose labels touch (no
// voxel between) are carved at the interface: each gives up half of the
// segmentation's interface_layer, so a tissue layer that thick can lie there.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "labels.h"

// Organ of each label value, -1 for none (background, unnamed labels).
static int32_t *organ_of_labels(fascia_ctx *ctx, const fascia_prep_scene *scene) {
  int32_t *organ_of = prep_calloc(PREP_MAX_LABEL + 1, sizeof(int32_t));
  if (!organ_of) {
    PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "label organs: out of memory");
    return NULL;
  }
  for (int32_t v = 0; v <= PREP_MAX_LABEL; ++v) organ_of[v] = -1;
  for (int32_t o = 0; o < scene->organ_count; ++o)
    for (int32_t k = 0; k < scene->organs[o].label_count; ++k) organ_of[scene->organs[o].labels[k]] = o;
  return organ_of;
}

// "5 (liver), 6 (stomach), ..." of the labels the image holds.
static void labels_present(const fascia_prep_segmentation *seg, const int64_t *count, char *out, size_t size) {
  const prep_label_table table = {seg->table_count, seg->table_label, seg->table_name};
  out[0] = 0;
  for (int32_t v = 1; v <= PREP_MAX_LABEL; ++v) {
    if (!count[v]) continue;
    const char *name = prep_label_table_name(&table, v);
    char item[96];
    snprintf(item, sizeof item, "%s%d%s%s%s", out[0] ? ", " : "", (int)v, name ? " (" : "", name ? name : "",
             name ? ")" : "");
    if (strlen(out) + strlen(item) + 8 >= size) {
      strncat(out, ", ...", size - strlen(out) - 1);
      return;
    }
    strcat(out, item);
  }
  if (!out[0]) snprintf(out, size, "none (every voxel is background)");
}

static fascia_status check_present(fascia_ctx *ctx, const fascia_prep_scene *scene, const prep_labelmap *map) {
  int64_t *count = prep_calloc(PREP_MAX_LABEL + 1, sizeof(int64_t));
  PREP_CHECK(count, ctx, FASCIA_ERR_MEMORY, "label organs: out of memory");
  const int64_t n = (int64_t)map->dims[0] * map->dims[1] * map->dims[2];
  for (int64_t k = 0; k < n; ++k) count[map->labels[k]]++;
  fascia_status status = FASCIA_OK;
  char list[1024];
  for (int32_t o = 0; o < scene->organ_count && status == FASCIA_OK; ++o) {
    const fascia_prep_organ_def *def = scene->organs + o;
    int64_t voxels = 0;
    for (int32_t k = 0; k < def->label_count && status == FASCIA_OK; ++k) {
      const int32_t v = def->labels[k];
      voxels += count[v];
      if (count[v] || !def->label_named[k]) continue; // a pattern takes the labels the image has
      labels_present(&scene->segmentation, count, list, sizeof list);
      status = PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                         "organ '%s' (scene '%s'): label map '%s' has no voxel labelled %d; the labels it holds: %s "
                         "(an organ a segmentation may lack: \"optional\": true)",
                         def->name, scene->path, scene->segmentation.file_path, (int)v, list);
    }
    if (status == FASCIA_OK && def->label_count && !voxels) {
      labels_present(&scene->segmentation, count, list, sizeof list);
      status = PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                         "organ '%s' (scene '%s'): label map '%s' has no voxel of the labels its pattern matches; "
                         "the labels it holds: %s (an organ a segmentation may lack: \"optional\": true)",
                         def->name, scene->path, scene->segmentation.file_path, list);
    }
  }
  free(count);
  return status;
}

static double determinant3(const double *a) { // of the 3x3 part of a row-major 3x4
  return a[0] * (a[5] * a[10] - a[6] * a[9]) - a[1] * (a[4] * a[10] - a[6] * a[8]) +
         a[2] * (a[4] * a[9] - a[5] * a[8]);
}

const char *fascia_prep_label_name(const fascia_prep_segmentation *seg, int32_t label) {
  const prep_label_table table = {seg->table_count, seg->table_label, seg->table_name};
  return prep_label_table_name(&table, label);
}

void fascia_prep_occupied_text(const fascia_prep_scene *scene, const fascia_prep_tissue_report *report, char *out,
                               size_t size) {
  out[0] = 0;
  size_t used = 0;
  for (int k = 0; k < 4 && report->occupied_labels[k] && used < size; ++k) {
    const int32_t v = report->occupied_labels[k];
    const char *name = fascia_prep_label_name(&scene->segmentation, v);
    char label[96];
    if (name)
      snprintf(label, sizeof label, "%s (%d)", name, (int)v);
    else
      snprintf(label, sizeof label, "label %d", (int)v);
    const int n = snprintf(out + used, size - used, "%s%s %.3g cm^3", k ? ", " : "", label,
                           1e6 * report->occupied_label_volume[k]);
    used += n > 0 ? (size_t)n : 0;
  }
  double listed = 0;
  for (int k = 0; k < 4; ++k) listed += report->occupied_label_volume[k];
  if (used < size && report->occupied_volume > listed * (1 + 1e-9))
    snprintf(out + used, size - used, ", others %.3g cm^3", 1e6 * (report->occupied_volume - listed));
}

// The voxels of labels that are neither an organ's nor connective: tissue
// stays out of them (an unmodelled structure such as a vessel or the bowel
// is not connective tissue). meshes->occupied stays NULL when there are none.
static fascia_status find_occupied(fascia_ctx *ctx, const fascia_prep_scene *scene, const prep_labelmap *map,
                                   const int32_t *organ_of, fascia_prep_meshes *meshes) {
  const fascia_prep_segmentation *seg = &scene->segmentation;
  uint8_t *space = prep_calloc(PREP_MAX_LABEL + 1, 1); // 1: tissue may take the label's voxels
  PREP_CHECK(space, ctx, FASCIA_ERR_MEMORY, "label organs: out of memory");
  space[0] = 1;
  for (int32_t k = 0; k < seg->connective_count; ++k) space[seg->connective[k]] = 1;
  const int64_t n = (int64_t)map->dims[0] * map->dims[1] * map->dims[2];
  int64_t count = 0;
  for (int64_t v = 0; v < n; ++v) count += !space[map->labels[v]] && organ_of[map->labels[v]] < 0;
  if (count) meshes->occupied = prep_calloc(n, sizeof(uint16_t));
  if (count && meshes->occupied)
    for (int64_t v = 0; v < n; ++v)
      if (!space[map->labels[v]] && organ_of[map->labels[v]] < 0) meshes->occupied[v] = (uint16_t)map->labels[v];
  free(space);
  PREP_CHECK(!count || meshes->occupied, ctx, FASCIA_ERR_MEMORY, "label organs: out of memory");
  if (!count) return FASCIA_OK;
  memcpy(meshes->occupied_dims, map->dims, sizeof map->dims);
  // [A | t]^-1 = [A^-1 | -A^-1 t], A^-1 by cofactors (the reader refused singular affines)
  const double *a = map->to_world, det = determinant3(a);
  double *w = meshes->occupied_from_world;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      const int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
      w[4 * r + c] = (a[4 * r1 + c1] * a[4 * r2 + c2] - a[4 * r1 + c2] * a[4 * r2 + c1]) / det;
    }
  for (int r = 0; r < 3; ++r)
    w[4 * r + 3] = -(w[4 * r] * a[3] + w[4 * r + 1] * a[7] + w[4 * r + 2] * a[11]);
  return FASCIA_OK;
}

// The parts of organ o's surface (grid coordinates in grid[3 nv]): one
// part named after the organ when it is one label; else one per label,
// named by the label table (or "label N"), each triangle in the part of
// the organ's voxel nearest its centroid (a strand can then attach to one
// vertebra of "vertebrae_*").
static fascia_status label_parts(fascia_ctx *ctx, const fascia_prep_scene *scene, const prep_labelmap *map,
                                 const int32_t *organ_of, int32_t o, const double *grid, fascia_prep_mesh *mesh) {
  const fascia_prep_organ_def *od = scene->organs + o;
  const int32_t parts = od->label_count > 1 ? od->label_count : 1;
  mesh->triangle_part = prep_calloc(mesh->triangle_count, sizeof(int32_t));
  mesh->part_names = prep_calloc(parts, sizeof(char *));
  PREP_CHECK(mesh->triangle_part && mesh->part_names, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", mesh->name);
  mesh->part_count = parts;
  for (int32_t p = 0; p < parts; ++p) {
    char name[FASCIA_NAME_SIZE];
    const char *label = fascia_prep_label_name(&scene->segmentation, od->labels[p]);
    if (parts == 1) snprintf(name, sizeof name, "%s", mesh->name);
    else if (label) snprintf(name, sizeof name, "%s", label);
    else snprintf(name, sizeof name, "label %d", (int)od->labels[p]);
    mesh->part_names[p] = prep_strdup(name);
    PREP_CHECK(mesh->part_names[p], ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", mesh->name);
  }
  if (parts == 1) return FASCIA_OK;
  const int32_t *d = map->dims;
  for (int32_t t = 0; t < mesh->triangle_count; ++t) {
    double c[3] = {0, 0, 0};
    for (int j = 0; j < 3; ++j)
      for (int r = 0; r < 3; ++r) c[r] += grid[3 * (int64_t)mesh->triangles[3 * (int64_t)t + j] + r] / 3;
    double best = INFINITY;
    int32_t part = 0;
    for (int dk = -2; dk <= 2; ++dk) // the organ's voxels within two of the centroid
      for (int dj = -2; dj <= 2; ++dj)
        for (int di = -2; di <= 2; ++di) {
          const int32_t ijk[3] = {(int32_t)lround(c[0]) + di, (int32_t)lround(c[1]) + dj, (int32_t)lround(c[2]) + dk};
          if (ijk[0] < 0 || ijk[1] < 0 || ijk[2] < 0 || ijk[0] >= d[0] || ijk[1] >= d[1] || ijk[2] >= d[2]) continue;
          const int32_t label = map->labels[ijk[0] + (int64_t)d[0] * (ijk[1] + (int64_t)d[1] * ijk[2])];
          if (organ_of[label] != o) continue;
          const double e0 = ijk[0] - c[0], e1 = ijk[1] - c[1], e2 = ijk[2] - c[2], dist = e0 * e0 + e1 * e1 + e2 * e2;
          if (dist >= best) continue;
          for (int32_t p = 0; p < parts; ++p)
            if (od->labels[p] == label) best = dist, part = p;
        }
    mesh->triangle_part[t] = part;
  }
  return FASCIA_OK;
}

// The surface of organ o's labels, in the world, into mesh, with its parts (label_parts).
static fascia_status label_surface(fascia_ctx *ctx, const fascia_prep_scene *scene, const prep_labelmap *map,
                                   const int32_t *organ_of, int32_t o, fascia_prep_mesh *mesh) {
  const int32_t *d = map->dims;
  int32_t lo[3] = {d[0], d[1], d[2]}, hi[3] = {-1, -1, -1};
  for (int32_t k = 0; k < d[2]; ++k)
    for (int32_t j = 0; j < d[1]; ++j)
      for (int32_t i = 0; i < d[0]; ++i) {
        if (organ_of[map->labels[i + (int64_t)d[0] * (j + (int64_t)d[1] * k)]] != o) continue;
        const int32_t ijk[3] = {i, j, k};
        for (int r = 0; r < 3; ++r) {
          if (ijk[r] < lo[r]) lo[r] = ijk[r];
          if (ijk[r] > hi[r]) hi[r] = ijk[r];
        }
      }
  const int32_t pad = scene->segmentation.smoothing + 2;
  int32_t box[3];
  for (int r = 0; r < 3; ++r) box[r] = hi[r] - lo[r] + 1 + 2 * pad;
  float *inside = prep_calloc((int64_t)box[0] * box[1] * box[2], sizeof(float));
  PREP_CHECK(inside, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory for its labels' box", mesh->name);
  for (int32_t k = lo[2]; k <= hi[2]; ++k)
    for (int32_t j = lo[1]; j <= hi[1]; ++j)
      for (int32_t i = lo[0]; i <= hi[0]; ++i)
        if (organ_of[map->labels[i + (int64_t)d[0] * (j + (int64_t)d[1] * k)]] == o)
          inside[(i - lo[0] + pad) + (int64_t)box[0] * ((j - lo[1] + pad) + (int64_t)box[1] * (k - lo[2] + pad))] = 1;
  double *vertices = NULL;
  int32_t *triangles = NULL, nv = 0, nt = 0;
  const fascia_status status = fascia_vdb_indicator_surface(ctx, box, inside, scene->segmentation.smoothing,
                                                            &vertices, &nv, &triangles, &nt);
  free(inside);
  PREP_TRY(status);
  const double *A = map->to_world;
  double *grid = prep_calloc(3 * (int64_t)nv + 3, sizeof(double)); // the vertices on the label map's grid
  if (!grid) {
    free(vertices), free(triangles);
    return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory for its surface", mesh->name);
  }
  for (int32_t v = 0; v < nv; ++v) {
    double *x = grid + 3 * (int64_t)v;
    for (int r = 0; r < 3; ++r) x[r] = vertices[3 * v + r] + lo[r] - pad;
    for (int r = 0; r < 3; ++r) vertices[3 * v + r] = A[4 * r] * x[0] + A[4 * r + 1] * x[1] + A[4 * r + 2] * x[2] + A[4 * r + 3];
  }
  if (determinant3(A) < 0) // a mirroring affine turns the winding inward: turn it back
    for (int32_t t = 0; t < nt; ++t) {
      const int32_t swap = triangles[3 * t + 1];
      triangles[3 * t + 1] = triangles[3 * t + 2];
      triangles[3 * t + 2] = swap;
    }
  mesh->vertices = vertices;
  mesh->vertex_count = nv;
  mesh->triangles = triangles;
  mesh->triangle_count = nt;
  const fascia_status parts = label_parts(ctx, scene, map, organ_of, o, grid, mesh);
  free(grid);
  return parts;
}

// Voxel faces where labels of two different organs meet, per pair.
static fascia_status find_contacts(fascia_ctx *ctx, const fascia_prep_scene *scene, const prep_labelmap *map,
                                   const int32_t *organ_of, fascia_prep_meshes *meshes) {
  const int32_t O = scene->organ_count, *d = map->dims;
  int64_t *faces = prep_calloc((int64_t)O * O * 3, sizeof(int64_t));
  PREP_CHECK(faces, ctx, FASCIA_ERR_MEMORY, "label organs: out of memory");
  const int64_t step[3] = {1, d[0], (int64_t)d[0] * d[1]};
  for (int32_t k = 0; k < d[2]; ++k)
    for (int32_t j = 0; j < d[1]; ++j)
      for (int32_t i = 0; i < d[0]; ++i) {
        const int64_t v = i + step[1] * j + step[2] * k;
        const int32_t a = organ_of[map->labels[v]];
        if (a < 0) continue;
        const int32_t ijk[3] = {i, j, k};
        for (int r = 0; r < 3; ++r) {
          if (ijk[r] + 1 >= d[r]) continue;
          const int32_t b = organ_of[map->labels[v + step[r]]];
          if (b >= 0 && b != a) faces[3 * ((int64_t)(a < b ? a : b) * O + (a < b ? b : a)) + r]++;
        }
      }
  // area of a face across axis r: |column s x column t| of the affine
  double area[3];
  const double *A = map->to_world;
  for (int r = 0; r < 3; ++r) {
    const int s = (r + 1) % 3, t = (r + 2) % 3;
    const double u[3] = {A[s], A[4 + s], A[8 + s]}, w[3] = {A[t], A[4 + t], A[8 + t]};
    const double c[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    area[r] = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  }
  int32_t n = 0;
  for (int64_t p = 0; p < (int64_t)O * O; ++p) n += faces[3 * p] + faces[3 * p + 1] + faces[3 * p + 2] > 0;
  meshes->contacts = prep_calloc(n, sizeof *meshes->contacts);
  if (!meshes->contacts) {
    free(faces);
    return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "label organs: out of memory");
  }
  for (int32_t a = 0; a < O; ++a)
    for (int32_t b = a + 1; b < O; ++b) {
      const int64_t *f = faces + 3 * ((int64_t)a * O + b);
      if (f[0] + f[1] + f[2] == 0) continue;
      fascia_prep_label_contact *c = meshes->contacts + meshes->contact_count++;
      c->a = a, c->b = b;
      c->faces = f[0] + f[1] + f[2];
      c->area = f[0] * area[0] + f[1] * area[1] + f[2] * area[2];
      c->layer = scene->segmentation.interface_layer;
    }
  free(faces);
  return FASCIA_OK;
}

static int bounds_near(const double *a, const double *b, double reach) {
  for (int r = 0; r < 3; ++r)
    if (a[r] > b[3 + r] + reach || b[r] > a[3 + r] + reach) return 0;
  return 1;
}

// Carves organ o from its neighbours (the original, uncarved surfaces): each
// gives up half the interface layer.
static fascia_status carve(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *original,
                           int32_t o, fascia_prep_mesh *mesh) {
  // the carved faces set the layer's thinnest gap, and with it the force
  // across it: their cell does not follow the voxels (prep_carve_cell)
  const double depth = 0.5 * scene->segmentation.interface_layer;
  const double h = prep_carve_cell(scene->segmentation.interface_layer);
  const fascia_prep_mesh *self = original->organs + o;
  int64_t nv = 0, nt = 0;
  for (int32_t k = 0; k < scene->organ_count; ++k)
    if (k != o && scene->organs[k].label_count && bounds_near(self->bounds, original->organs[k].bounds, depth + 3 * h))
      nv += original->organs[k].vertex_count, nt += original->organs[k].triangle_count;
  if (nt == 0) return FASCIA_OK;
  PREP_CHECK(nv < INT32_MAX && nt < INT32_MAX, ctx, FASCIA_ERR_MEMORY, "organ '%s': neighbours too large", mesh->name);
  double *vertices = prep_calloc(3 * nv, sizeof(double));
  int32_t *triangles = prep_calloc(3 * nt, sizeof(int32_t));
  fascia_status status = FASCIA_OK;
  PREP_CHECK_GOTO(vertices && triangles, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", mesh->name);
  int32_t v0 = 0, t0 = 0;
  for (int32_t k = 0; k < scene->organ_count; ++k) {
    const fascia_prep_mesh *m = original->organs + k;
    if (k == o || !scene->organs[k].label_count || !bounds_near(self->bounds, m->bounds, depth + 3 * h)) continue;
    memcpy(vertices + 3 * (int64_t)v0, m->vertices, 3 * (size_t)m->vertex_count * sizeof(double));
    for (int64_t t = 0; t < 3 * (int64_t)m->triangle_count; ++t) triangles[3 * (int64_t)t0 + t] = v0 + m->triangles[t];
    v0 += m->vertex_count, t0 += m->triangle_count;
  }
  double *cv = NULL;
  int32_t *ct = NULL, cnv = 0, cnt = 0;
  PREP_TRY_GOTO(fascia_vdb_carve(ctx, self->vertex_count, self->vertices, self->triangle_count, self->triangles,
                                 (int32_t)nv, vertices, (int32_t)nt, triangles, h, depth, &cv, &cnv, &ct, &cnt));
  if (cnt == 0) {
    free(cv);
    free(ct);
    PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_FORMAT,
                    "organ '%s' (scene '%s'): nothing is left of it after carving the interface layer of %g m; "
                    "lower segmentation.interface_layer",
                    mesh->name, scene->path, scene->segmentation.interface_layer);
  }
  free(mesh->vertices);
  free(mesh->triangles);
  free(mesh->triangle_part);
  mesh->vertices = cv, mesh->vertex_count = cnv;
  mesh->triangles = ct, mesh->triangle_count = cnt;
  mesh->triangle_part = prep_calloc(cnt, sizeof(int32_t));
  PREP_CHECK_GOTO(mesh->triangle_part, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", mesh->name);
cleanup:
  free(vertices);
  free(triangles);
  return status;
}

fascia_status prep_label_organs(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_meshes *meshes) {
  int any = 0;
  for (int32_t o = 0; o < scene->organ_count; ++o) any |= scene->organs[o].label_count > 0;
  if (!any) return FASCIA_OK;
  const fascia_prep_segmentation *seg = &scene->segmentation;
  prep_labelmap *map = NULL;
  int32_t *organ_of = NULL;
  fascia_prep_meshes original = {0};
  char sha256[65];
  fascia_status status = FASCIA_OK;
  fascia_ctx_progress(ctx, "import", 0, seg->file);
  status = prep_labelmap_read(ctx, seg->file_path, seg->frame, &map);
  if (status != FASCIA_OK) {
    char reason[1024];
    snprintf(reason, sizeof reason, "%s", fascia_ctx_message(ctx));
    return PREP_FAIL(ctx, status, "scene '%s' segmentation.file: %s", scene->path, reason);
  }
  PREP_TRY_GOTO(fascia_prep_file_sha256(ctx, seg->file_path, sha256));
  organ_of = organ_of_labels(ctx, scene);
  PREP_CHECK_GOTO(organ_of, ctx, FASCIA_ERR_MEMORY, "label organs: out of memory");
  PREP_TRY_GOTO(check_present(ctx, scene, map));
  for (int32_t o = 0; o < scene->organ_count; ++o) {
    if (!scene->organs[o].label_count) continue;
    fascia_ctx_progress(ctx, "import", (double)o / scene->organ_count, scene->organs[o].name);
    fascia_prep_mesh *m = meshes->organs + o;
    PREP_TRY_GOTO(label_surface(ctx, scene, map, organ_of, o, m));
    memcpy(m->sha256, sha256, sizeof sha256);
    prep_mesh_bounds(m);
    m->report.parts_used = 0; // the parts that got triangles: labels named by a pattern may be absent
    for (int32_t p = 0; p < m->part_count; ++p)
      for (int32_t t = 0; t < m->triangle_count; ++t)
        if (m->triangle_part[t] == p) {
          ++m->report.parts_used;
          break;
        }
  }
  PREP_TRY_GOTO(find_contacts(ctx, scene, map, organ_of, meshes));
  PREP_TRY_GOTO(find_occupied(ctx, scene, map, organ_of, meshes));
  if (seg->interface_layer > 0) {
    // carve each organ against its neighbours as they were, so the order does not matter
    original.count = meshes->count;
    original.organs = prep_calloc(meshes->count, sizeof *original.organs);
    PREP_CHECK_GOTO(original.organs, ctx, FASCIA_ERR_MEMORY, "label organs: out of memory");
    for (int32_t o = 0; o < meshes->count; ++o) {
      const fascia_prep_mesh *m = meshes->organs + o;
      fascia_prep_mesh *c = original.organs + o;
      if (!scene->organs[o].label_count) continue;
      c->vertices = prep_calloc(3 * (int64_t)m->vertex_count, sizeof(double));
      c->triangles = prep_calloc(3 * (int64_t)m->triangle_count, sizeof(int32_t));
      PREP_CHECK_GOTO(c->vertices && c->triangles, ctx, FASCIA_ERR_MEMORY, "label organs: out of memory");
      memcpy(c->vertices, m->vertices, 3 * (size_t)m->vertex_count * sizeof(double));
      memcpy(c->triangles, m->triangles, 3 * (size_t)m->triangle_count * sizeof(int32_t));
      c->vertex_count = m->vertex_count, c->triangle_count = m->triangle_count;
      memcpy(c->bounds, m->bounds, sizeof c->bounds);
    }
    for (int32_t o = 0; o < meshes->count; ++o) {
      if (!scene->organs[o].label_count) continue;
      PREP_TRY_GOTO(carve(ctx, scene, &original, o, meshes->organs + o));
      prep_mesh_bounds(meshes->organs + o);
    }
  }
cleanup:
  for (int32_t o = 0; original.organs && o < original.count; ++o) {
    free(original.organs[o].vertices);
    free(original.organs[o].triangles);
  }
  free(original.organs);
  free(organ_of);
  prep_labelmap_destroy(&map);
  return status;
}
