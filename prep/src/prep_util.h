// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Private helpers of the prep stages: the names of the error macros (prep
// sees only the public sim API), allocation, strings, a seeded random
// generator, and the voxel lattice shared by every grid.
#ifndef FASCIA_PREP_UTIL_H
#define FASCIA_PREP_UTIL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "adapters.h"
#include "fascia/prep.h"

// prep's names for the error macros of fascia/base.h
#define PREP_FAIL FASCIA_FAIL
#define PREP_CHECK FASCIA_CHECK
#define PREP_TRY FASCIA_TRY
#define PREP_TRY_GOTO FASCIA_TRY_GOTO
#define PREP_CHECK_GOTO FASCIA_CHECK_GOTO

/// calloc of count elements (count 0 gives a valid pointer), NULL on overflow.
FASCIA_PREP_INTERN void *prep_calloc(int64_t count, size_t size);
/// Resizes a malloc'ed array to count elements of size bytes, for lists
/// that grow: `array` is the address of the array's pointer (&list->x).
/// Returns 0, the array left as it was, when out of memory or count < 0.
FASCIA_PREP_INTERN int prep_resize(void *array, int64_t count, size_t size);
/// strdup into malloc'ed memory, NULL on failure.
FASCIA_PREP_INTERN char *prep_strdup(const char *s);
/// Opens path for reading ("rb") when it is a regular file; a directory,
/// FIFO, device or socket is refused with a message naming what it is (a
/// FIFO or /dev/zero would block or never end). *size: its size in bytes.
/// what names the file in messages ("scene", "mesh").
FASCIA_PREP_INTERN fascia_status prep_open_regular(fascia_ctx *ctx, const char *path, const char *what, FILE **out,
                                                   int64_t *size);
/// Reads a whole regular file (at most limit bytes) into a malloc'ed,
/// NUL-terminated buffer; a file that changes size while read is refused.
FASCIA_PREP_INTERN fascia_status prep_read_file(fascia_ctx *ctx, const char *path, const char *what, int64_t limit,
                                                char **text, size_t *size);

/// Refuses a mesh file that its importer would read leniently though it is
/// cut short or garbled, by its extension: an STL (binary: its size is not
/// 84 + 50 bytes per triangle its header counts; ASCII: a facet cut short or
/// no "endsolid"), a PLY (a damaged header, or a body with fewer elements
/// than the header declares). f is the open file at its start, size its bytes.
FASCIA_PREP_INTERN fascia_status prep_mesh_precheck(fascia_ctx *ctx, const char *path, FILE *f, int64_t size);

/// Hex SHA-256 of a buffer into hex[65].
FASCIA_PREP_INTERN void prep_sha256_buffer(const void *data, size_t size, char hex[65]);

/// A box of the global voxel lattice: voxel (i,j,k) of the box is lattice
/// voxel lo + (i,j,k), centred at h (lo + (i,j,k)); index i + nx (j + ny k).
typedef struct prep_grid {
  double h;
  int32_t lo[3];
  int32_t dims[3];
} prep_grid;

/// The distance between two points.
static inline double prep_dist3(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/// out = a - b.
static inline void prep_sub3(const double *a, const double *b, double *out) {
  for (int r = 0; r < 3; ++r) out[r] = a[r] - b[r];
}

static inline double prep_dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static inline double prep_norm3(const double *a) { return sqrt(prep_dot3(a, a)); }

/// out = a x b (out must not alias a or b).
static inline void prep_cross3(const double *a, const double *b, double *out) {
  out[0] = a[1] * b[2] - a[2] * b[1], out[1] = a[2] * b[0] - a[0] * b[2], out[2] = a[0] * b[1] - a[1] * b[0];
}

/// The cell of a label map's interface carve (label_organs.c): three cells
/// across each side's half of the layer whatever the voxel size, so the
/// carved faces do not move as the voxels are refined.
static inline double prep_carve_cell(double interface_layer) { return interface_layer / 6; }

static inline int64_t prep_grid_count(const prep_grid *g) {
  return (int64_t)g->dims[0] * g->dims[1] * g->dims[2];
}
static inline int64_t prep_grid_index(const prep_grid *g, int32_t i, int32_t j, int32_t k) {
  return (int64_t)i + (int64_t)g->dims[0] * ((int64_t)j + (int64_t)g->dims[1] * k);
}
static inline void prep_grid_ijk(const prep_grid *g, int64_t v, int32_t *ijk) {
  ijk[0] = (int32_t)(v % g->dims[0]);
  ijk[1] = (int32_t)((v / g->dims[0]) % g->dims[1]);
  ijk[2] = (int32_t)(v / ((int64_t)g->dims[0] * g->dims[1]));
}
static inline void prep_grid_center(const prep_grid *g, int64_t v, double *p) {
  int32_t ijk[3];
  prep_grid_ijk(g, v, ijk);
  for (int r = 0; r < 3; ++r) p[r] = g->h * (double)(g->lo[r] + ijk[r]);
}
/// The voxels next to v that lie in g (sharing a face, an edge or a corner:
/// up to 26), z slowest and x fastest; d2[k] (when d2 is not NULL): the
/// squared length of the step to nb[k] in voxels (1, 2 or 3). Returns how many.
static inline int prep_grid_neighbours(const prep_grid *g, int64_t v, int64_t nb[26], int d2[26]) {
  int32_t c[3];
  prep_grid_ijk(g, v, c);
  int n = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int32_t x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
        if (!(dx || dy || dz) || x < 0 || y < 0 || z < 0 || x >= g->dims[0] || y >= g->dims[1] || z >= g->dims[2])
          continue;
        if (d2) d2[n] = dx * dx + dy * dy + dz * dz;
        nb[n++] = prep_grid_index(g, x, y, z);
      }
  return n;
}
/// Grid covering [min, max] (m) with pad extra voxels on every side.
FASCIA_PREP_INTERN void prep_grid_cover(prep_grid *g, double h, const double *min, const double *max, int32_t pad);
/// Voxel of point p in g, or -1 outside.
FASCIA_PREP_INTERN int64_t prep_grid_locate(const prep_grid *g, const double *p);
/// The grid of a volume.
FASCIA_PREP_INTERN prep_grid prep_volume_grid(const fascia_prep_volume *volume);

/// 1 when p is inside region (a NONE region contains everything).
FASCIA_PREP_INTERN int prep_region_contains(const fascia_prep_region *region, const double *p);
/// 1 when tissue td's coupling rules let its frame at x on organ's triangle
/// be shared with that organ (no rule for the organ: shared anywhere, an
/// organ it does not connect only when td->couple_others).
FASCIA_PREP_INTERN int prep_coupling_allowed(const fascia_prep_tissue_def *td, int32_t organ,
                                             const fascia_prep_mesh *mesh, int32_t triangle, const double *x);
/// Deformable organ whose inside has region label (> 0), -1 for a tissue label.
FASCIA_PREP_INTERN int32_t prep_label_organ(const fascia_prep_volume *volume, uint8_t label);
/// Sampling parameters of the region with this label: a tissue's or a
/// deformable organ's. Any pointer may be NULL.
FASCIA_PREP_INTERN void prep_label_sampling(const fascia_prep_scene *scene, const fascia_prep_volume *volume,
                                            uint8_t label, double *frame_spacing, double *sample_spacing,
                                            int32_t *shape_kind, int32_t *neighbours);
/// "tissue 'name'" or "deformable organ 'name'" into out.
FASCIA_PREP_INTERN const char *prep_label_name(const fascia_prep_scene *scene, const fascia_prep_volume *volume,
                                               uint8_t label, char *out, size_t size);
/// mesh->bounds from its vertices.
FASCIA_PREP_INTERN void prep_mesh_bounds(fascia_prep_mesh *mesh);
/// Index of name among parts names of mesh, -1 if absent.
FASCIA_PREP_INTERN int32_t prep_mesh_part(const fascia_prep_mesh *mesh, const char *name);
/// Closest point on triangle (a, b, c) to p: barycentric coordinates in bary.
FASCIA_PREP_INTERN void prep_triangle_barycentric(const double *a, const double *b, const double *c, const double *p,
                                                  double *bary);

/// Largest edge of a mesh's bounding box, m.
FASCIA_PREP_INTERN double prep_mesh_extent(const fascia_prep_mesh *mesh);
/// Judges the scene's lengths against anatomy's once the meshes are read
/// (magnitudes.c): refuses what cannot be simulated, adds to
/// meshes->warnings what looks like a units mistake but may be meant.
FASCIA_PREP_INTERN fascia_status prep_check_magnitudes(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                                       fascia_prep_meshes *meshes);
/// For a message about organ k, extent (m) across: when no organ is that
/// large or small, "; the units look wrong: ..." with how its file is read
/// and which units would fit, else "".
FASCIA_PREP_INTERN void prep_units_hint_organ(const fascia_prep_scene *scene, int32_t k, double extent, char *out,
                                              size_t size);
/// "; the units look wrong: ..." when voxel_size is coarser than anatomy allows, else "".
FASCIA_PREP_INTERN void prep_units_hint_voxel(const fascia_prep_scene *scene, char *out, size_t size);
/// "; a box larger than a body ..." when a grid's box (extent m) is, else "".
FASCIA_PREP_INTERN void prep_units_hint_box(double extent, char *out, size_t size);

/// Rotation matrix R (row-major) of the unit quaternion q = (w, x, y, z).
FASCIA_PREP_INTERN void prep_quat_matrix(const double *q, double *R);

/// What the tissues look like, in the world (tissue_surface.c): the boundary
/// of the volume tissues' regions (labels 1 .. tissue_count), smoothed and
/// meshed; each strand as a tube of its radius through its frames; each
/// sheet as its mesh over its frames.
FASCIA_PREP_INTERN fascia_status prep_tissue_surface(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                                     const fascia_prep_meshes *meshes, const fascia_prep_volume *vol,
                                                     const fascia_prep_points *points, fascia_surface *out);

/// Heap of (distance, voxel) for Dijkstra over voxels.
typedef struct prep_heap {
  int64_t count, capacity;
  double *key;
  int64_t *value;
} prep_heap;
FASCIA_PREP_INTERN int prep_heap_push(prep_heap *heap, double key, int64_t value);
FASCIA_PREP_INTERN int prep_heap_pop(prep_heap *heap, double *key, int64_t *value);
FASCIA_PREP_INTERN void prep_heap_free(prep_heap *heap);

#endif
