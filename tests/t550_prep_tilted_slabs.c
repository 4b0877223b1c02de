// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Tissue between two slabs tilted against each other, their gap growing from
// 0 (they touch along an edge) to three times max_gap: the tissue is the set
// of points on a bridge of length at most max_gap between them
// (d_A + d_B <= max_gap), whose cross-section is known in closed form. Its
// voxel volume matches it within one voxel layer over its boundary, and every
// piece of it touches both slabs. Two parallel boxes farther apart than
// max_gap (but within twice it) get no tissue: no sheet floats in the middle.
// With min_gap m the slabs slide where they are closer than m: the tissue
// loses the part of that cross-section with d_A + d_B < m (the same shape,
// scaled by m / max_gap), reported as slide_volume.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "prep_fixture.h"

#define MAX_GAP 0.006
#define SLOPE (1.0 / 3.0) // B's lower face z = SLOPE x: the gap reaches 3 max_gap at x = LENGTH
#define LENGTH (3 * MAX_GAP / SLOPE)
#define HALF_WIDTH 0.008 // the region box keeps |y| below this, inside both slabs

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": %g, \"seed\": 5,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"fixed\"}],\n"
    " \"tissues\": [{\"name\": \"t\", \"connects\": [\"A\", \"B\"], \"max_gap\": %g,%s\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.003, \"sample_spacing\": 0.0015}]}\n";

// A hexahedron from its 8 corners (bit 0: x, bit 1: y, bit 2: z side), as
// the boxes of fixture_box.
static int write_hex(const char *dir, const char *name, double c[8][3]) {
  char text[2048];
  int n = 0;
  for (int k = 0; k < 8; ++k) n += snprintf(text + n, sizeof text - (size_t)n, "v %.9g %.9g %.9g\n", c[k][0], c[k][1], c[k][2]);
  static const int quads[6][4] = {{1, 3, 7, 5}, {2, 6, 8, 4}, {1, 5, 6, 2}, {3, 4, 8, 7}, {1, 2, 4, 3}, {5, 7, 8, 6}};
  for (int f = 0; f < 6; ++f)
    n += snprintf(text + n, sizeof text - (size_t)n, "f %d %d %d\nf %d %d %d\n", quads[f][0], quads[f][1],
                  quads[f][2], quads[f][0], quads[f][2], quads[f][3]);
  return fixture_write(dir, name, text);
}

static fascia_status voxelize(const char *path, fascia_ctx *ctx, fixture_run *r) {
  memset(r, 0, sizeof *r);
  fascia_status st = fascia_prep_scene_load(ctx, path, &r->scene);
  if (!st) st = fascia_prep_import(ctx, r->scene, &r->meshes);
  if (!st) st = fascia_prep_repair(ctx, r->scene, r->meshes);
  if (!st) st = fascia_prep_voxelize(ctx, r->scene, r->meshes, &r->volume);
  return st;
}

// The tilted slabs at voxel size h, shifted by `shift` (m) on every axis,
// the tissue's min_gap m.
static int tilted(const char *dir, double h, double shift, double m) {
  const double G = MAX_GAP, s = SLOPE, c = sqrt(1 + s * s), W = 2 * HALF_WIDTH;
  double a[8][3], b[8][3];
  for (int k = 0; k < 8; ++k) {
    const double x = (k & 1) ? LENGTH : 0, y = (k & 2) ? 0.014 : -0.014;
    a[k][0] = ((k & 1) ? LENGTH : -0.012) + shift, a[k][1] = y + shift, a[k][2] = ((k & 4) ? 0 : -0.008) + shift;
    b[k][0] = x + shift, b[k][1] = y + shift, b[k][2] = s * x + ((k & 4) ? 0.008 : 0) + shift;
  }
  CHECK(write_hex(dir, "a.obj", a) && write_hex(dir, "b.obj", b));
  char text[2048], region[256], path[512];
  snprintf(region, sizeof region,
           " \"min_gap\": %g, \"region\": {\"box\": {\"min\": [-1, %.9g, -1], \"max\": [1, %.9g, 1]}},", m,
           -HALF_WIDTH + shift, HALF_WIDTH + shift);
  snprintf(text, sizeof text, scene_format, h, G, region);
  CHECK(fixture_write(dir, "scene.json", text));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  CHECK_OK(voxelize(path, ctx, &r), ctx);
  if (r.volume) {
    // cross-section (x, z) of the set d_A + d_B <= G outside both slabs:
    // over B's lower face (0 <= z <= s x, d_A = z, d_B = (s x - z) / c) the
    // triangle (0, 0), (G c / s, 0), (G / s, G); beyond B's end face
    // (x < 0, d_B = -x) the triangle (-G, 0), (0, 0), (0, G)
    const double area = G * G * c / (2 * s) + G * G / 2, slid = area * (m / G) * (m / G);
    const double exact = (area - slid) * W;
    const double perimeter = 2 * G + G * sqrt(2.0) + 2 * G * c / s + hypot(G * (c - 1) / s, G);
    const double layer = 0.5 * h * (perimeter * W + 2 * area); // one voxel layer straddling the boundary
    const double got = r.volume->tissues[0].volume;
    fprintf(stderr, "tilted slabs, voxel %g mm, shift %g mm, min_gap %g mm: tissue %.5g cm^3, exact %.5g cm^3 "
                    "(%+.2f %%), one voxel layer %.3g cm^3; slid %.4g cm^3, exact %.4g\n",
            1e3 * h, 1e3 * shift, 1e3 * m, 1e6 * got, 1e6 * exact, 100 * (got / exact - 1), 1e6 * layer,
            1e6 * r.volume->tissues[0].slide_volume, 1e6 * slid * W);
    CHECK_NEAR(got, exact, 0, layer);
    CHECK_NEAR(r.volume->tissues[0].slide_volume, slid * W, 0, layer);
    int pieces = 0;
    CHECK(fixture_pieces_touch(r.volume, 1, 2, &pieces));
    CHECK(pieces >= 1);
    // the slabs touch along x = 0: a contact, reported as a zero gap
    CHECK_NEAR(r.volume->closest[1], 0, 0, 1e-9);
  }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return 0;
}

// Two parallel boxes `gap` apart: built and touching both up to max_gap,
// refused beyond it (old rule: a sheet in the middle touching neither).
static int parallel(const char *dir, double h, double gap) {
  const double a_lo[3] = {-0.02, -0.01, -0.01}, a_hi[3] = {-gap / 2, 0.01, 0.01};
  const double b_lo[3] = {gap / 2, -0.01, -0.01}, b_hi[3] = {0.02, 0.01, 0.01};
  double shifted[4][3];
  for (int r = 0; r < 3; ++r) {
    const double shift = 0.3 * h;
    shifted[0][r] = a_lo[r] + shift, shifted[1][r] = a_hi[r] + shift;
    shifted[2][r] = b_lo[r] + shift, shifted[3][r] = b_hi[r] + shift;
  }
  CHECK(fixture_box(dir, "a.obj", shifted[0], shifted[1]) && fixture_box(dir, "b.obj", shifted[2], shifted[3]));
  char text[2048], path[512];
  snprintf(text, sizeof text, scene_format, h, MAX_GAP, "");
  CHECK(fixture_write(dir, "scene.json", text));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = voxelize(path, ctx, &r);
  if (gap <= MAX_GAP && st != FASCIA_OK) CHECK_OK(st, ctx);
  if (st == FASCIA_OK) {
    int pieces = 0;
    CHECK(fixture_pieces_touch(r.volume, 1, 2, &pieces));
    CHECK_NEAR(r.volume->closest[1], gap, 0, 1e-9);
  } else {
    CHECK(st == FASCIA_ERR_ARGUMENT && strstr(fascia_ctx_message(ctx), "too far apart"));
  }
  if (gap > MAX_GAP) CHECK(st != FASCIA_OK);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return 0;
}

int main(void) {
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  int failed = tilted(dir, 0.001, 0.0003, 0);
  failed |= tilted(dir, 0.0005, 0.00017, 0);
  failed |= tilted(dir, 0.001, 0.0003, 0.003);
  failed |= tilted(dir, 0.0005, 0.00017, 0.003);
  failed |= parallel(dir, 0.001, 0.9 * MAX_GAP);
  failed |= parallel(dir, 0.001, 1.5 * MAX_GAP);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return failed || CHECK_RESULT();
}
