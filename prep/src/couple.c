// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Stage 6, coupling: which tissue frames are shared with which organ, and
// where each sits on the organ's surface (docs/organs.md). Surface
// frames were placed exactly on an organ surface by the sampling (closest
// point, so the triangle is known); interior frames keep farther than the
// tissue's coupling tolerance from every organ, so the shared frames are
// exactly the surface frames that the tissue's rules allow: an organ can be
// switched off, or limited to a box, a sphere or named parts. For a
// deformable organ the sampling already applied the rules when it attached
// the surface frames to the organ's inside; the frames it attached are the
// shared ones (one frame index used by the tissue's and the organ's samples).
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "prep_util.h"

void fascia_prep_coupling_destroy(fascia_prep_coupling **coupling) {
  if (!coupling || !*coupling) return;
  fascia_prep_coupling *c = *coupling;
  free(c->organ);
  free(c->frame);
  free(c->triangle);
  free(c->barycentric);
  free(c->per_organ);
  free(c);
  *coupling = NULL;
}

fascia_status fascia_prep_couple(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                 const fascia_prep_points *points, fascia_prep_coupling **out) {
  PREP_CHECK(ctx && scene && meshes && points && out, ctx, FASCIA_ERR_ARGUMENT, "fascia_prep_couple: NULL argument");
  *out = NULL;
  // part names in the rules must exist
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    const fascia_prep_tissue_def *td = scene->tissues + t;
    for (int32_t k = 0; k < td->coupling_count; ++k) {
      const fascia_prep_coupling_def *rule = td->coupling + k;
      const fascia_prep_mesh *m = meshes->organs + rule->organ;
      for (int32_t p = 0; p < rule->parts.count; ++p)
        PREP_CHECK(prep_mesh_part(m, rule->parts.names[p]) >= 0, ctx, FASCIA_ERR_FORMAT,
                   "scene '%s' tissues[%d].coupling.organs.%s.parts[%d]: organ '%s' uses no part named '%s'",
                   scene->path, (int)t, m->name, (int)p, m->name, rule->parts.names[p]);
    }
  }
  fascia_status status = FASCIA_OK;
  fascia_prep_coupling *c = calloc(1, sizeof *c);
  const int32_t N = points->frame_count;
  PREP_CHECK(c, ctx, FASCIA_ERR_MEMORY, "coupling: out of memory");
  c->organ_count = meshes->count;
  c->organ = prep_calloc(N, sizeof(int32_t));
  c->frame = prep_calloc(N, sizeof(int32_t));
  c->triangle = prep_calloc(N, sizeof(int32_t));
  c->barycentric = prep_calloc(3 * (int64_t)N, sizeof(double));
  c->per_organ = prep_calloc(meshes->count, sizeof(int32_t));
  PREP_CHECK_GOTO(c->organ && c->frame && c->triangle && c->barycentric && c->per_organ, ctx, FASCIA_ERR_MEMORY,
                  "coupling: out of memory");
  for (int32_t i = 0; i < N; ++i) {
    const int32_t o = points->frame_organ[i], tri = points->frame_triangle[i];
    if (o < 0) continue;
    const fascia_prep_mesh *m = meshes->organs + o;
    const double *x = points->frame_position + 3 * (int64_t)i;
    if (points->frame_tissue[i] < 0) continue; // a deformable organ's own frame (never on a surface today)
    if (!prep_coupling_allowed(scene->tissues + points->frame_tissue[i], o, m, tri, x)) continue;
    // a deformable organ shares exactly the frames its inside reaches (a
    // shell every tissue frame on its surface: its wall's frames)
    if (scene->organs[o].kind == FASCIA_ORGAN_DEFORMABLE && !scene->organs[o].shell &&
        points->frame_organ_voxel[i] < 0)
      continue;
    const int32_t *v = m->triangles + 3 * (int64_t)tri;
    double *b = c->barycentric + 3 * (int64_t)c->count;
    prep_triangle_barycentric(m->vertices + 3 * (int64_t)v[0], m->vertices + 3 * (int64_t)v[1],
                              m->vertices + 3 * (int64_t)v[2], x, b);
    c->organ[c->count] = o;
    c->frame[c->count] = i;
    c->triangle[c->count] = tri;
    c->per_organ[o]++;
    c->count++;
  }
  fascia_ctx_progress(ctx, "coupling", 1, "done");
  *out = c;
  c = NULL;
cleanup:
  fascia_prep_coupling_destroy(&c);
  return status;
}
