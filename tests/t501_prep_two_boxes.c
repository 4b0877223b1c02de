// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Two boxes facing each other across a known gap, the tissue cut to the slab
// between their faces: the region volume matches the analytic one within half
// a voxel per boundary face (a bound that tightens with the voxel size), every
// sample lies in the region, sample volumes add up to it, the weights are a
// partition of unity that reproduces linear fields, shared frames sit on the
// face of the right box with kinds from the organ model, the tissue
// surface wraps the slab, and the model survives a save and a load.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "prep_fixture.h"

// Box A spans x in [-20, -3.1] mm, box B x in [3.1, 20] mm, both y, z in
// [-10.2, 10.2] mm. The region box keeps |y|, |z| < 8.05 mm, inside the
// boxes' cross-section, so the region is the slab |x| < 3.1 mm exactly and
// every point of it is within 6.2 mm < max_gap of both boxes.
#define FACE 0.0031
#define HALF_REGION 0.00805

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": %g, \"seed\": 7,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3, \"density\": 1000}},\n"
    " \"organs\": [\n"
    "  {\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "  {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"prescribed\", \"motion\": {\"pivot\": [0, 0, 0],\n"
    "   \"keys\": [{\"time\": 0}, {\"time\": 1, \"translation\": [0.001, 0, 0]}]}}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008,\n"
    "  \"region\": {\"box\": {\"min\": [-0.005, -%g, -%g], \"max\": [0.005, %g, %g]}},\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.003, \"sample_spacing\": %g,\n"
    "  \"shape_functions\": {\"kind\": \"mls\", \"neighbours\": 8}}]}\n";

static int run(const char *dir, double h, double sample_spacing) {
  char text[4096], path[512];
  snprintf(text, sizeof text, scene_format, h, HALF_REGION, HALF_REGION, HALF_REGION, HALF_REGION, sample_spacing);
  CHECK(fixture_write(dir, "scene.json", text));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);

  // region volume against the analytic slab; each of the 6 boundary faces
  // moves by at most h/2 when voxel centres decide membership
  const double side = 2 * HALF_REGION, width = 2 * FACE;
  const double exact = width * side * side;
  const double area = 2 * side * side + 4 * width * side;
  const double region = r.volume->tissues[0].volume;
  CHECK_NEAR(region, exact, 0, 0.5 * h * area);
  CHECK(r.volume->tissues[0].components == 1);

  // samples: inside the region, volumes summing to it (round-off only)
  double sum = 0;
  for (int32_t s = 0; s < r.points->sample_count; ++s) {
    CHECK(fascia_prep_volume_region_at(r.volume, r.points->sample_position + 3 * s) == 1);
    sum += r.points->sample_volume[s];
  }
  CHECK_NEAR(sum, region, 1e-12, 0);
  CHECK_NEAR(fascia_model_volume(r.model), region, 1e-12, 0);

  // weights: sum w = 1, sum grad w = 0, sum w x_i = p, sum x_i (x) grad w = I
  // (1e-9 relative: MLS solves a 4x4 system in double per sample)
  const fascia_model *m = r.model;
  double worst[3];
  fixture_weight_errors(m, worst);
  CHECK(worst[0] < 1e-9);
  CHECK(worst[1] < 1e-12); // metres: 1e-9 of a millimetre
  CHECK(worst[2] < 1e-8);

  // coupling: frames shared with A lie on its face x = -FACE, with B on x = +FACE,
  // the barycentric point on the triangle is the frame, kinds follow the organs
  // (1e-9 m: assimp reads coordinates as float, 0.0031 becomes 0.00310000009)
  int32_t on_a = 0, on_b = 0;
  for (int32_t c = 0; c < m->coupling_count; ++c) {
    const int32_t o = m->coupling_organ[c], i = m->coupling_frame[c];
    const double *x = m->frame_position + 3 * i;
    CHECK_NEAR(x[0], o == 0 ? -FACE : FACE, 0, 1e-9);
    CHECK(fabs(x[1]) <= HALF_REGION + h && fabs(x[2]) <= HALF_REGION + h);
    const fascia_organ *organ = m->organs + o;
    const int32_t *t = organ->triangles + 3 * m->coupling_triangle[c];
    for (int a = 0; a < 3; ++a) {
      double y = 0;
      for (int v = 0; v < 3; ++v) y += m->coupling_barycentric[3 * c + v] * organ->vertices[3 * t[v] + a];
      CHECK_NEAR(y, x[a], 0, 1e-12);
    }
    CHECK(m->frame_kind[i] == (o == 0 ? FASCIA_FRAME_FIXED : FASCIA_FRAME_PRESCRIBED));
    CHECK(o == 0 || m->frame_motion[i] == m->organs[1].motion);
    on_a += o == 0;
    on_b += o == 1;
  }
  CHECK(on_a >= 4 && on_b >= 4);
  CHECK(r.coupling->per_organ[0] == on_a && r.coupling->per_organ[1] == on_b);
  // free frames are the others, all strictly between the faces
  for (int32_t i = 0; i < m->frame_count; ++i)
    if (m->frame_kind[i] == FASCIA_FRAME_FREE) CHECK(fabs(m->frame_position[3 * i]) < FACE);
  CHECK(m->provenance && strstr(m->provenance, "\"voxel_size\""));
  // the tissue surface wraps the slab: its box is the slab's within a voxel
  const fascia_surface *ts = &m->tissue_surface;
  double lo[3] = {1e30, 1e30, 1e30}, hi[3] = {-1e30, -1e30, -1e30};
  for (int32_t v = 0; v < ts->vertex_count; ++v)
    for (int c = 0; c < 3; ++c)
      lo[c] = fmin(lo[c], ts->vertices[3 * v + c]), hi[c] = fmax(hi[c], ts->vertices[3 * v + c]);
  CHECK(ts->triangle_count > 0);
  CHECK_NEAR(lo[0], -FACE, 0, h);
  CHECK_NEAR(hi[0], FACE, 0, h);
  for (int c = 1; c < 3; ++c) {
    CHECK_NEAR(lo[c], -HALF_REGION, 0, h);
    CHECK_NEAR(hi[c], HALF_REGION, 0, h);
  }

  // the model file: written, read back with the same counts
  snprintf(path, sizeof path, "%s/model.h5", dir);
  CHECK_OK(fascia_model_save(ctx, m, path), ctx);
  fascia_model *back = NULL;
  CHECK_OK(fascia_model_load(ctx, path, &back), ctx);
  CHECK(back->frame_count == m->frame_count && back->sample_count == m->sample_count &&
        back->coupling_count == m->coupling_count && back->organ_count == 2);
  fascia_model_destroy(&back);
  remove(path);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return 0;
}

int main(void) {
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  CHECK(fixture_two_boxes(dir, FACE, NULL, NULL));
  int failed = run(dir, 0.001, 0.0015);
  failed |= run(dir, 0.0005, 0.001);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return failed || CHECK_RESULT();
}
