// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Mesh-based shape functions ("tet") are a real tetrahedral discretization: every
// sample is a quadrature point inside its own tetrahedron of frames (4 points
// of degree 2, or the centroid with samples_per_tet 1), its weights are its
// barycentric coordinates there (in [0, 1], a partition of unity reproducing
// linear fields), and the sample volumes add up to the volume of the kept
// tetrahedra, which lie inside the region (between 60 % and 100 % of its voxel
// volume here); the same for a deformable organ's inside; a rule other than 1
// or 4 is refused naming the key.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "prep_fixture.h"

// Box A x in [-20, -3.1] mm (fixed), box B x in [3.1, 20] mm (deformable,
// "tet" with the centroid rule), both y, z in [-10.2, 10.2] mm; the tissue
// ("tet", default 4 points) is the slab between them, cut to |y|, |z| < 8 mm.
static const char scene[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 5,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 10000, \"poisson_ratio\": 0.3},\n"
    "               \"organ\": {\"youngs_modulus\": 30000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "  {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"deformable\", \"material\": \"organ\",\n"
    "   \"frame_spacing\": 0.005, \"sample_spacing\": 0.0025,\n"
    "   \"shape_functions\": {\"kind\": \"tet\", \"samples_per_tet\": 1}}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008,\n"
    "  \"region\": {\"box\": {\"min\": [-0.005, -0.008, -0.008], \"max\": [0.005, 0.008, 0.008]}},\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.0025, \"sample_spacing\": 0.00125,\n"
    "  \"shape_functions\": {\"kind\": \"tet\"}}]}\n";

// 6 x signed volume of (a, b, c, d).
static double det6(const double *a, const double *b, const double *c, const double *d) {
  const double e[3][3] = {{b[0] - a[0], b[1] - a[1], b[2] - a[2]},
                          {c[0] - a[0], c[1] - a[1], c[2] - a[2]},
                          {d[0] - a[0], d[1] - a[1], d[2] - a[2]}};
  return e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
         e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
}

// One sample of a tet region: its pairs are its tet's frames; its weights are
// in [0, 1] and equal its barycentric coordinates computed independently
// (ratios of sub-tet volumes), which are those of a point of the rule; the
// partition of unity and linear reproduction hold with their gradients.
static int check_sample(const fascia_prep_points *pts, const fascia_model *m, int32_t s, int rule) {
  const int32_t *v = pts->sample_tet_frame + 4 * s;
  const double *p = pts->sample_position + 3 * s, *x[4];
  for (int r = 0; r < 4; ++r) x[r] = pts->frame_position + 3 * v[r];
  CHECK(m->sample_offsets[s + 1] - m->sample_offsets[s] == 4);
  const double whole = det6(x[0], x[1], x[2], x[3]);
  CHECK(fabs(whole) > 0);
  const double a = (5 + 3 * sqrt(5.0)) / 20, b = (5 - sqrt(5.0)) / 20; // the degree-2 rule's coordinates
  int at_a = 0;
  double w_sum = 0, g_sum[3] = {0, 0, 0}, lin[3] = {0, 0, 0}, G[9] = {0};
  for (int r = 0; r < 4; ++r) {
    const int32_t k = m->sample_offsets[s] + r;
    CHECK(m->pair_frame[k] == v[r]);
    const double *y[4] = {x[0], x[1], x[2], x[3]};
    y[r] = p;
    const double bary = det6(y[0], y[1], y[2], y[3]) / whole;
    // 1e-12: round-off of 3x3 determinants of millimetre edges, relative to 1
    CHECK(m->pair_weight[k] >= -1e-12 && m->pair_weight[k] <= 1 + 1e-12);
    CHECK(bary >= -1e-12); // inside its tet
    CHECK_NEAR(m->pair_weight[k], bary, 0, 1e-10);
    if (rule == 1) CHECK_NEAR(bary, 0.25, 0, 1e-10);
    if (rule == 4) {
      CHECK(fabs(bary - a) < 1e-10 || fabs(bary - b) < 1e-10);
      at_a += fabs(bary - a) < 1e-10;
    }
    const double *dw = m->pair_gradient + 3 * k;
    w_sum += m->pair_weight[k];
    for (int i = 0; i < 3; ++i) {
      g_sum[i] += dw[i];
      lin[i] += m->pair_weight[k] * x[r][i];
      for (int j = 0; j < 3; ++j) G[3 * i + j] += x[r][i] * dw[j];
    }
  }
  if (rule == 4) CHECK(at_a == 1);
  CHECK_NEAR(w_sum, 1, 0, 1e-12);
  for (int i = 0; i < 3; ++i) {
    CHECK_NEAR(lin[i], p[i], 0, 1e-14);                       // metres: 1e-11 of a millimetre
    CHECK_NEAR(g_sum[i] * 1e-3, 0, 0, 1e-10);                 // gradients ~ 1/spacing: compare at mm scale
    for (int j = 0; j < 3; ++j) CHECK_NEAR(G[3 * i + j], i == j, 0, 1e-10);
  }
  return 0;
}

// The samples of one region (tissue t, or deformable organ o): each checked,
// in the region's voxels, `rule` consecutive samples per tet whose volumes
// are the rule's weights times the tet's volume; their sum (the kept tets'
// volume) between 60 % and 100 % of the region's voxel volume: the tets stay
// inside the region, and on these boxes lose at most the layers next to the
// organs and the cut faces that the frames' hull misses.
static int check_region(const fixture_run *r, int32_t t, int32_t o, int rule, double voxel_volume) {
  const fascia_prep_points *pts = r->points;
  const int label = t >= 0 ? t + 1 : r->volume->organ_label[o];
  double sum = 0, tets = 0;
  int32_t count = 0;
  for (int32_t s = 0; s < pts->sample_count; ++s) {
    if (t >= 0 ? pts->sample_tissue[s] != t : pts->sample_inside_organ[s] != o) continue;
    CHECK(check_sample(pts, r->model, s, rule) == 0);
    CHECK(fascia_prep_volume_region_at(r->volume, pts->sample_position + 3 * s) == label);
    CHECK(r->model->sample_volume[s] == pts->sample_volume[s]);
    if (count % rule == 0) { // first sample of a tet: the next rule - 1 share it
      const int32_t *v = pts->sample_tet_frame + 4 * s;
      const double *x = pts->frame_position;
      const double volume = fabs(det6(x + 3 * v[0], x + 3 * v[1], x + 3 * v[2], x + 3 * v[3])) / 6;
      for (int j = 0; j < rule; ++j) {
        CHECK(s + j < pts->sample_count && memcmp(pts->sample_tet_frame + 4 * (s + j), v, 4 * sizeof(int32_t)) == 0);
        CHECK_NEAR(pts->sample_volume[s + j], volume / rule, 1e-12, 0);
      }
      tets += volume;
    }
    sum += pts->sample_volume[s];
    ++count;
  }
  CHECK(count > 0 && count % rule == 0);
  CHECK_NEAR(sum, tets, 1e-12, 0);
  CHECK(sum > 0.6 * voxel_volume && sum < voxel_volume);
  return 0;
}

int main(void) {
  char dir[256], path[512];
  if (!fixture_tmpdir(dir)) return 1;
  CHECK(fixture_two_boxes(dir, 0.0031, scene, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  CHECK(r.scene->tissues[0].samples_per_tet == 4 && r.scene->organs[1].samples_per_tet == 1);
  CHECK(check_region(&r, 0, -1, 4, r.volume->tissues[0].volume) == 0);
  CHECK(check_region(&r, -1, 1, 1, r.volume->organ_regions[1].volume) == 0);
  CHECK(r.weights->max_linear_error < 1e-14);
  // the provenance says what the samples add up to
  const char *prov = r.model->provenance;
  CHECK(prov && strstr(prov, "sample_volume_of") && strstr(prov, "tetrahedra kept inside the region"));
  fixture_free(&r);

  // only the two rules of fascia_shape_tet_quadrature
  char *bad = malloc(sizeof scene + 8);
  CHECK(bad);
  strcpy(bad, scene);
  char *rule = strstr(bad, "\"samples_per_tet\": 1");
  CHECK(rule);
  rule[strlen("\"samples_per_tet\": ")] = '3';
  fascia_prep_scene *sc = NULL;
  CHECK(fascia_prep_scene_parse(ctx, bad, "bad.json", dir, &sc) == FASCIA_ERR_FORMAT && !sc);
  CHECK(strstr(fascia_ctx_message(ctx), "samples_per_tet") != NULL);
  free(bad);

  fascia_ctx_destroy(&ctx);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
