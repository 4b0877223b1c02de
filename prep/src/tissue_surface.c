// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// What the connective tissue looks like: the boundary of the tissues'
// regions on the voxel grid, smoothed and meshed (OpenVDB, as the surfaces
// of organs made of labels), stored in the model for drawing. The
// simulation carries it with the frames (fascia_solver_tissue_surface).
#include <stdlib.h>
#include <string.h>

#include "prep_util.h"

#define SURFACE_SMOOTHING 1 // mean-filter passes: voxel steps rounded, thin layers kept

fascia_status prep_tissue_surface(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_volume *vol,
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
