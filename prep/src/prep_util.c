// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Private helpers of the prep stages (see prep_util.h).
#define _POSIX_C_SOURCE 200809L // fstat, fileno
#include "prep_util.h"

#include <errno.h>
#include <sys/stat.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/files.h"

void *prep_calloc(int64_t count, size_t size) {
  if (count < 0 || count > ((int64_t)1 << 36)) return NULL;
  if (count == 0) count = 1;
  return calloc((size_t)count, size);
}

int prep_resize(void *array, int64_t count, size_t size) {
  if (count < 0 || (size > 0 && (uint64_t)count > SIZE_MAX / size)) return 0;
  void *old, *grown;
  memcpy(&old, array, sizeof old); // the pointer whatever its type (T ** is no void **)
  if (!(grown = realloc(old, (size_t)count * size))) return 0;
  memcpy(array, &grown, sizeof grown);
  return 1;
}

char *prep_strdup(const char *s) {
  if (!s) return NULL;
  const size_t n = strlen(s) + 1;
  char *p = malloc(n);
  if (p) memcpy(p, s, n);
  return p;
}

fascia_status prep_open_regular(fascia_ctx *ctx, const char *path, const char *what, FILE **out, int64_t *size) {
  PREP_TRY(fascia_file_open_input(ctx, what, path, out));
  struct stat st;
  if (fstat(fileno(*out), &st) != 0) {
    const int err = errno;
    fclose(*out);
    *out = NULL;
    return PREP_FAIL(ctx, FASCIA_ERR_IO, "%s '%s': cannot stat: %s", what, path, strerror(err));
  }
  *size = (int64_t)st.st_size;
  return FASCIA_OK;
}

fascia_status prep_read_file(fascia_ctx *ctx, const char *path, const char *what, int64_t limit, char **text,
                             size_t *size) {
  *text = NULL;
  FILE *f;
  int64_t expected;
  PREP_TRY(prep_open_regular(ctx, path, what, &f, &expected));
  if (expected > limit) {
    fclose(f);
    return PREP_FAIL(ctx, FASCIA_ERR_IO, "%s '%s': %lld bytes, more than the %lld bytes a %s file may have", what,
                     path, (long long)expected, (long long)limit, what);
  }
  // one byte more than the size says: a file that grows while it is read is refused, not read without end
  char *buf = malloc((size_t)expected + 2);
  if (!buf) {
    fclose(f);
    return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "%s '%s': out of memory for %lld bytes", what, path,
                     (long long)expected);
  }
  const size_t n = fread(buf, 1, (size_t)expected + 1, f);
  const int failed = ferror(f);
  const int err = errno;
  fclose(f);
  if (failed || n != (size_t)expected) {
    free(buf);
    if (failed) return PREP_FAIL(ctx, FASCIA_ERR_IO, "%s '%s': read error (%s)", what, path, strerror(err));
    return PREP_FAIL(ctx, FASCIA_ERR_IO, "%s '%s': changed while it was read (%lld bytes expected, %s); read it again "
                     "once it is complete", what, path, (long long)expected, n > (size_t)expected ? "more came" : "fewer came");
  }
  buf[n] = 0;
  *text = buf;
  if (size) *size = n;
  return FASCIA_OK;
}

void prep_grid_cover(prep_grid *g, double h, const double *min, const double *max, int32_t pad) {
  g->h = h;
  for (int r = 0; r < 3; ++r) {
    const int32_t a = (int32_t)floor(min[r] / h) - pad, b = (int32_t)ceil(max[r] / h) + pad;
    g->lo[r] = a;
    g->dims[r] = b - a + 1;
  }
}

int64_t prep_grid_locate(const prep_grid *g, const double *p) {
  int32_t ijk[3];
  for (int r = 0; r < 3; ++r) {
    const double x = floor(p[r] / g->h + 0.5) - g->lo[r];
    if (!(x >= 0 && x < g->dims[r])) return -1;
    ijk[r] = (int32_t)x;
  }
  return prep_grid_index(g, ijk[0], ijk[1], ijk[2]);
}

prep_grid prep_volume_grid(const fascia_prep_volume *volume) {
  prep_grid g;
  g.h = volume->voxel_size;
  for (int r = 0; r < 3; ++r) {
    g.lo[r] = volume->lattice[r];
    g.dims[r] = volume->dims[r];
  }
  return g;
}

int prep_region_contains(const fascia_prep_region *region, const double *p) {
  switch (region->kind) {
  case FASCIA_PREP_REGION_BOX:
    for (int r = 0; r < 3; ++r)
      if (p[r] < region->min[r] || p[r] > region->max[r]) return 0;
    return 1;
  case FASCIA_PREP_REGION_SPHERE: {
    double d2 = 0;
    for (int r = 0; r < 3; ++r) d2 += (p[r] - region->center[r]) * (p[r] - region->center[r]);
    return d2 <= region->radius * region->radius;
  }
  default: return 1;
  }
}

int fascia_prep_tissue_connects(const fascia_prep_tissue_def *td, int32_t organ) {
  for (int32_t k = 0; k < td->organ_count; ++k)
    if (td->organs[k] == organ) return 1;
  return 0;
}

int prep_coupling_allowed(const fascia_prep_tissue_def *td, int32_t organ, const fascia_prep_mesh *mesh,
                          int32_t triangle, const double *x) {
  const fascia_prep_coupling_def *rule = NULL;
  for (int32_t k = 0; k < td->coupling_count && !rule; ++k)
    if (td->coupling[k].organ == organ) rule = td->coupling + k;
  if (!rule) return td->couple_others || fascia_prep_tissue_connects(td, organ);
  if (!rule->enabled) return 0;
  if (!prep_region_contains(&rule->region, x)) return 0;
  if (rule->parts.count == 0) return 1;
  const char *part = mesh->part_names[mesh->triangle_part[triangle]];
  for (int32_t k = 0; k < rule->parts.count; ++k)
    if (!strcmp(rule->parts.names[k], part)) return 1;
  return 0;
}

int32_t prep_label_organ(const fascia_prep_volume *volume, uint8_t label) {
  if (label == 0 || label <= volume->tissue_count || !volume->organ_label) return -1;
  for (int32_t o = 0; o < volume->organ_count; ++o)
    if (volume->organ_label[o] == label) return o;
  return -1;
}

void prep_label_sampling(const fascia_prep_scene *scene, const fascia_prep_volume *volume, uint8_t label,
                         double *frame_spacing, double *sample_spacing, int32_t *shape_kind, int32_t *neighbours) {
  const int32_t o = prep_label_organ(volume, label);
  const fascia_prep_organ_def *od = o >= 0 ? scene->organs + o : NULL;
  const fascia_prep_tissue_def *td = o >= 0 ? NULL : scene->tissues + (label - 1);
  if (frame_spacing) *frame_spacing = od ? od->frame_spacing : td->frame_spacing;
  if (sample_spacing) *sample_spacing = od ? od->sample_spacing : td->sample_spacing;
  if (shape_kind) *shape_kind = od ? od->shape_kind : td->shape_kind;
  if (neighbours) *neighbours = od ? od->neighbours : td->neighbours;
}

const char *prep_label_name(const fascia_prep_scene *scene, const fascia_prep_volume *volume, uint8_t label,
                            char *out, size_t size) {
  const int32_t o = prep_label_organ(volume, label);
  if (o >= 0)
    snprintf(out, size, "deformable organ '%s'", scene->organs[o].name);
  else
    snprintf(out, size, "tissue '%s'", label >= 1 && label <= scene->tissue_count ? scene->tissues[label - 1].name : "?");
  return out;
}

int32_t prep_mesh_part(const fascia_prep_mesh *mesh, const char *name) {
  for (int32_t p = 0; p < mesh->part_count; ++p)
    if (!strcmp(mesh->part_names[p], name)) return p;
  return -1;
}

// Closest point of a triangle to p, as barycentric coordinates (Ericson,
// Real-Time Collision Detection, sec. 5.1.5).
void prep_triangle_barycentric(const double *a, const double *b, const double *c, const double *p, double *bary) {
  double ab[3], ac[3], ap[3], bp[3], cp[3];
  for (int r = 0; r < 3; ++r) {
    ab[r] = b[r] - a[r];
    ac[r] = c[r] - a[r];
    ap[r] = p[r] - a[r];
    bp[r] = p[r] - b[r];
    cp[r] = p[r] - c[r];
  }
#define DOT(u, w) ((u)[0] * (w)[0] + (u)[1] * (w)[1] + (u)[2] * (w)[2])
  const double d1 = DOT(ab, ap), d2 = DOT(ac, ap);
  const double d3 = DOT(ab, bp), d4 = DOT(ac, bp);
  const double d5 = DOT(ab, cp), d6 = DOT(ac, cp);
#undef DOT
  if (d1 <= 0 && d2 <= 0) {
    bary[0] = 1, bary[1] = 0, bary[2] = 0;
    return;
  }
  if (d3 >= 0 && d4 <= d3) {
    bary[0] = 0, bary[1] = 1, bary[2] = 0;
    return;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    bary[0] = 1 - v, bary[1] = v, bary[2] = 0;
    return;
  }
  if (d6 >= 0 && d5 <= d6) {
    bary[0] = 0, bary[1] = 0, bary[2] = 1;
    return;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    bary[0] = 1 - w, bary[1] = 0, bary[2] = w;
    return;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    bary[0] = 0, bary[1] = 1 - w, bary[2] = w;
    return;
  }
  const double denom = 1 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  bary[0] = 1 - v - w, bary[1] = v, bary[2] = w;
}

int prep_heap_push(prep_heap *heap, double key, int64_t value) {
  if (heap->count == heap->capacity) {
    const int64_t cap = heap->capacity ? 2 * heap->capacity : 256;
    if (!prep_resize(&heap->key, cap, sizeof *heap->key) || !prep_resize(&heap->value, cap, sizeof *heap->value))
      return 0;
    heap->capacity = cap;
  }
  int64_t i = heap->count++;
  while (i > 0) {
    const int64_t parent = (i - 1) / 2;
    // ties broken by value: the order of pops does not depend on push order
    if (heap->key[parent] < key || (heap->key[parent] == key && heap->value[parent] <= value)) break;
    heap->key[i] = heap->key[parent];
    heap->value[i] = heap->value[parent];
    i = parent;
  }
  heap->key[i] = key;
  heap->value[i] = value;
  return 1;
}

int prep_heap_pop(prep_heap *heap, double *key, int64_t *value) {
  if (heap->count == 0) return 0;
  *key = heap->key[0];
  *value = heap->value[0];
  const double k = heap->key[--heap->count];
  const int64_t v = heap->value[heap->count];
  int64_t i = 0;
  for (;;) {
    int64_t child = 2 * i + 1;
    if (child >= heap->count) break;
    if (child + 1 < heap->count &&
        (heap->key[child + 1] < heap->key[child] ||
         (heap->key[child + 1] == heap->key[child] && heap->value[child + 1] < heap->value[child])))
      ++child;
    if (k < heap->key[child] || (k == heap->key[child] && v <= heap->value[child])) break;
    heap->key[i] = heap->key[child];
    heap->value[i] = heap->value[child];
    i = child;
  }
  heap->key[i] = k;
  heap->value[i] = v;
  return 1;
}

void prep_heap_free(prep_heap *heap) {
  free(heap->key);
  free(heap->value);
  heap->key = NULL;
  heap->value = NULL;
  heap->count = heap->capacity = 0;
}

void prep_quat_matrix(const double *q, double *R) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double m[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                       2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                       2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  for (int k = 0; k < 9; ++k) R[k] = m[k];
}

void prep_mesh_bounds(fascia_prep_mesh *mesh) {
  for (int r = 0; r < 3; ++r) mesh->bounds[r] = INFINITY, mesh->bounds[3 + r] = -INFINITY;
  for (int32_t v = 0; v < mesh->vertex_count; ++v)
    for (int r = 0; r < 3; ++r) {
      const double x = mesh->vertices[3 * (int64_t)v + r];
      if (x < mesh->bounds[r]) mesh->bounds[r] = x;
      if (x > mesh->bounds[3 + r]) mesh->bounds[3 + r] = x;
    }
}
