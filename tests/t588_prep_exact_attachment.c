// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A volume tissue with attachment "exact" moves with its organ on the whole
// of the organ's surface, not only at the shared frames: near the surface
// of a fixed box, the weight of the frames that do not move with the organ
// falls to nothing (with attachment "frames" it stays large between the
// shared frames). The weights stay what the mechanics needs: a partition of
// unity whose gradients sum to 0, and, with a free frame moved by its
// distance from one face and the other box moved rigidly, the interpolated
// field and its gradient are that linear field exactly (the organ's node
// value is its motion, so a field that vanishes on a flat face and grows
// linearly away from it is reproduced, and the gradients are the weights'
// derivatives). An unknown attachment, and "exact" on tetrahedra, are
// refused naming the key.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "prep_fixture.h"

#define FACE 0.004 // the boxes' faces at x = -FACE (A) and +FACE (B), m

static const char scene_head[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 3,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 10000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "  {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"fixed\"}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.01,\n"
    "  \"region\": {\"box\": {\"min\": [-0.005, -0.008, -0.008], \"max\": [0.005, 0.008, 0.008]}},\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.004, \"sample_spacing\": 0.0015,\n"
    "  \"attachment\": \"%s\"}]}\n";

// The largest weight of the frames not on an organ over the samples within
// `near` m of A's face (the voxel centres on it); and, on every sample, the field u = x + FACE
// (frames on A: 0, on B: 2 FACE, a free frame its own x + FACE) against its
// interpolation and its gradient against (1, 0, 0).
static int check_weights(const fixture_run *r, double near, double *free_near, double *field, double *slope,
                         double *unity) {
  const fascia_model *m = r->model;
  const fascia_prep_points *pts = r->points;
  *free_near = *field = *slope = *unity = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    if (pts->sample_tissue[s] != 0) continue;
    const double *p = pts->sample_position + 3 * s;
    double w_free = 0, w_sum = 0, u = 0, g_sum[3] = {0, 0, 0}, du[3] = {0, 0, 0}, scale = 0;
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k) {
      const int32_t i = m->pair_frame[k];
      const double w = m->pair_weight[k], *g = m->pair_gradient + 3 * k;
      const int32_t organ = pts->frame_organ[i];
      const double value = organ == 0 ? 0 : organ == 1 ? 2 * FACE : pts->frame_position[3 * i] + FACE;
      if (organ < 0) w_free += w;
      w_sum += w;
      u += w * value;
      for (int a = 0; a < 3; ++a) g_sum[a] += g[a], du[a] += g[a] * value, scale += fabs(g[a]);
    }
    if (p[0] + FACE < near) *free_near = fmax(*free_near, fabs(w_free));
    *unity = fmax(*unity, fabs(w_sum - 1));
    for (int a = 0; a < 3; ++a) *unity = fmax(*unity, fabs(g_sum[a]) / scale);
    *field = fmax(*field, fabs(u - (p[0] + FACE)));
    for (int a = 0; a < 3; ++a) *slope = fmax(*slope, fabs(du[a] - (a == 0)));
  }
  return 0;
}

static int run(const char *dir, const char *attachment, double out[4]) {
  char text[sizeof scene_head + 16], path[512];
  snprintf(text, sizeof text, scene_head, attachment);
  CHECK(fixture_two_boxes(dir, FACE, text, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep(ctx, path, &r);
  if (st != FASCIA_OK) fprintf(stderr, "%s\n", fascia_ctx_message(ctx));
  CHECK(st == FASCIA_OK);
  CHECK(r.scene->tissues[0].attachment == (strcmp(attachment, "exact") ? FASCIA_PREP_ATTACH_FRAMES
                                                                        : FASCIA_PREP_ATTACH_EXACT));
  CHECK(check_weights(&r, 1e-4, out, out + 1, out + 2, out + 3) == 0);
  // the provenance names it when asked for (and the default's stays as it was)
  const char *prov = r.model->provenance;
  CHECK(prov && (strstr(prov, "\"attachment\":\"exact\",\"attachment_layer\":0.0015") != NULL) == !strcmp(attachment, "exact"));
  printf("%-6s free weight on A's face %.3g; u = x + FACE: largest error %.3g m, of its gradient %.3g; "
         "partition of unity %.3g\n",
         attachment, out[0], out[1], out[2], out[3]);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return 0;
}

int main(void) {
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  double frames[4], exact[4];
  CHECK(run(dir, "frames", frames) == 0);
  CHECK(run(dir, "exact", exact) == 0);
  CHECK(frames[0] > 0.02); // between the shared frames the free frames carry the surface, ten times exact's bound
  CHECK(exact[0] < 2e-3);  // the organ does (its kernel floor)
  for (int k = 0; k < 2; ++k) {
    const double *e = k ? exact : frames;
    CHECK(e[1] < 1e-8);    // m, against a field of millimetres: float distances
    CHECK(e[2] < 1e-4);    // central differences of the weights
    CHECK(e[3] < 1e-9);
  }

  // an attachment it does not know is refused, naming the key
  char text[sizeof scene_head + 16], path[512];
  snprintf(text, sizeof text, scene_head, "glue");
  CHECK(fixture_two_boxes(dir, FACE, text, path));
  fascia_ctx *ctx = fixture_ctx();
  fascia_prep_scene *sc = NULL;
  CHECK(fascia_prep_scene_load(ctx, path, &sc) == FASCIA_ERR_FORMAT && !sc);
  CHECK(strstr(fascia_ctx_message(ctx), "tissues[0].attachment") != NULL);
  // and so is exact on tetrahedra, whose weights are their tets'
  char tet[sizeof scene_head + 80];
  snprintf(tet, sizeof tet, scene_head, "exact\", \"shape_functions\": {\"kind\": \"tet\"}, \"description\": \"tet");
  CHECK(fixture_two_boxes(dir, FACE, tet, path));
  CHECK(fascia_prep_scene_load(ctx, path, &sc) == FASCIA_ERR_FORMAT && !sc);
  CHECK(strstr(fascia_ctx_message(ctx), "tissues[0].attachment") && strstr(fascia_ctx_message(ctx), "mls"));
  fascia_ctx_destroy(&ctx);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
