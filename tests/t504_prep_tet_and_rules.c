// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The mesh-based shape functions and the user's rules: with kind "tet" every
// sample has the 4 barycentric weights of its own tetrahedron of frames, all
// in [0, 1] (a partition of unity reproducing linear fields, nothing
// extrapolated), and the sample volumes add up to the tetrahedra's volume,
// which lies within the region's voxel volume (t507 checks each sample in
// detail); a sphere region keeps every
// sample inside it; coupling switched off for organ A shares no frame with A
// (its surface frames stay free), coupling limited to a box for B shares
// only frames inside the box. At nu = 0.3 the tetrahedra's volumetric
// patches carry enhanced strain modes (shape_functions.enhanced_modes,
// default true for tet with 4 samples per tetrahedron; docs/mechanics.md);
// with the key false, or the centroid rule, they carry none, and a key
// that is not a boolean is refused naming it. The patch rule: below a
// Poisson ratio of 0.3 (0.29) no sample is in a patch; an explicit
// patch_radius makes them there, and 0 switches them off at 0.3.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>
#include <string.h>

#include "check.h"
#include "prep_fixture.h"

static const char scene[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.0005, \"seed\": 11,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\"}, {\"name\": \"B\", \"mesh\": \"b.obj\"}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008,\n"
    "  \"region\": {\"sphere\": {\"center\": [0, 0, 0], \"radius\": 0.009}},\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.003, \"sample_spacing\": 0.001,\n"
    "  \"shape_functions\": {\"kind\": \"tet\"},\n"
    "  \"coupling\": {\"organs\": {\"A\": false,\n"
    "     \"B\": {\"region\": {\"box\": {\"min\": [0, -1, -1], \"max\": [1, 1, 0]}}}}}}]}\n";

// |volume| of the tetrahedron on frames f[0..3] at rest
static double tet_volume(const fascia_model *m, const int32_t *f) {
  const double *x[4];
  for (int c = 0; c < 4; ++c) x[c] = m->frame_position + 3 * f[c];
  double e[3][3];
  for (int j = 0; j < 3; ++j)
    for (int a = 0; a < 3; ++a) e[j][a] = x[j + 1][a] - x[0][a];
  return fabs(e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
              e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0])) / 6;
}

int main(void) {
  char dir[256], path[512];
  if (!fixture_tmpdir(dir)) return 1;
  CHECK(fixture_two_boxes(dir, 0.0031, scene, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  const fascia_model *m = r.model;
  double worst = 0, volume = 0, tets = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    const double *p = m->sample_position + 3 * s;
    CHECK(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) <= 0.009 + 0.0005); // in region voxels: within h of the sphere
    CHECK(m->sample_offsets[s + 1] - m->sample_offsets[s] == 4);
    volume += m->sample_volume[s];
    if (s % 4 == 0) tets += tet_volume(m, r.points->sample_tet_frame + 4 * s); // 4 quadrature points per tet, consecutive
    double w = 0, x[3] = {0, 0, 0};
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k) {
      CHECK(m->pair_weight[k] >= -1e-12 && m->pair_weight[k] <= 1 + 1e-12); // round-off only
      CHECK(m->pair_frame[k] == r.points->sample_tet_frame[4 * s + (k - m->sample_offsets[s])]);
      w += m->pair_weight[k];
      for (int a = 0; a < 3; ++a) x[a] += m->pair_weight[k] * m->frame_position[3 * m->pair_frame[k] + a];
    }
    worst = fmax(worst, fabs(w - 1));
    for (int a = 0; a < 3; ++a) worst = fmax(worst, fabs(x[a] - p[a]) / 0.001); // relative to a millimetre
  }
  CHECK(worst < 1e-9);
  CHECK(m->sample_count % 4 == 0);
  CHECK_NEAR(volume, tets, 1e-12, 0);
  // the model keeps each tetrahedron once, for drawing
  double kept = 0;
  for (int32_t k = 0; k < m->tetrahedron_count; ++k) kept += tet_volume(m, m->tetrahedra + 4 * k);
  CHECK(m->tetrahedron_count == m->sample_count / 4);
  CHECK_NEAR(kept, volume, 1e-12, 0);
  CHECK(volume > 0.5 * r.volume->tissues[0].volume && volume < r.volume->tissues[0].volume);
  int32_t on_a_surface = 0, shared_b = 0;
  for (int32_t i = 0; i < r.points->frame_count; ++i)
    if (r.points->frame_organ[i] == 0) {
      ++on_a_surface;
      CHECK(m->frame_kind[i] == FASCIA_FRAME_FREE);
    }
  for (int32_t c = 0; c < m->coupling_count; ++c) {
    CHECK(m->coupling_organ[c] == 1);
    CHECK(m->frame_position[3 * m->coupling_frame[c] + 2] <= 0);
    ++shared_b;
  }
  CHECK(on_a_surface > 0 && shared_b > 0 && r.coupling->per_organ[0] == 0);
  int32_t with_modes = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) with_modes += m->sample_patch[s] >= 0 && m->sample_modes[s] == 1;
  CHECK(with_modes == m->sample_count);
  fixture_free(&r);
  // the key off: patches without modes; not a boolean: refused
  char text[sizeof scene + 64];
  const char *at = strstr(scene, "{\"kind\": \"tet\"}");
  CHECK(at != NULL);
  static const char *const variants[] = {"\"enhanced_modes\": false", "\"samples_per_tet\": 1", "\"enhanced_modes\": 1"};
  for (int k = 0; k < 3 && at; ++k) {
    snprintf(text, sizeof text, "%.*s{\"kind\": \"tet\", %s}%s", (int)(at - scene), scene, variants[k],
             at + strlen("{\"kind\": \"tet\"}"));
    CHECK(fixture_two_boxes(dir, 0.0031, text, path));
    if (k == 2) {
      CHECK(fixture_prep(ctx, path, &r) == FASCIA_ERR_FORMAT);
      CHECK(strstr(fascia_ctx_message(ctx), "shape_functions.enhanced_modes") &&
            strstr(fascia_ctx_message(ctx), "expected true or false"));
      printf("t504: %s\n", fascia_ctx_message(ctx));
      continue;
    }
    CHECK_OK(fixture_prep(ctx, path, &r), ctx);
    int32_t patched = 0, moded = 0;
    for (int32_t s = 0; r.model && s < r.model->sample_count; ++s) {
      patched += r.model->sample_patch[s] >= 0;
      moded += r.model->sample_modes[s];
    }
    CHECK(patched > 0 && moded == 0);
    fixture_free(&r);
  }
  // the patch rule: none below nu = 0.3, unless the scene asks for them; 0 turns them off
  static const struct {
    const char *nu, *radius;
    int patches;
  } rules[] = {{"0.29", "", 0}, {"0.29", "\"patch_radius\": 0.003, ", 1}, {"0.3", "\"patch_radius\": 0, ", 0}};
  const char *nu_at = strstr(scene, "\"poisson_ratio\": 0.3}"), *key_at = strstr(scene, "\"material\": \"soft\"");
  CHECK(nu_at != NULL && key_at != NULL && nu_at < key_at);
  for (int k = 0; k < 3 && nu_at && key_at; ++k) {
    const char *after_nu = nu_at + strlen("\"poisson_ratio\": 0.3");
    snprintf(text, sizeof text, "%.*s\"poisson_ratio\": %s%.*s%s%s", (int)(nu_at - scene), scene, rules[k].nu,
             (int)(key_at - after_nu), after_nu, rules[k].radius, key_at);
    CHECK(fixture_two_boxes(dir, 0.0031, text, path));
    CHECK_OK(fixture_prep(ctx, path, &r), ctx);
    int32_t patched = 0;
    for (int32_t s = 0; r.model && s < r.model->sample_count; ++s) patched += r.model->sample_patch[s] >= 0;
    printf("t504: nu %s, %s%d of %d samples in patches\n", rules[k].nu, rules[k].radius, (int)patched,
           r.model ? (int)r.model->sample_count : 0);
    CHECK(r.model && (rules[k].patches ? patched == r.model->sample_count : patched == 0));
    fixture_free(&r);
  }
  fascia_ctx_destroy(&ctx);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
