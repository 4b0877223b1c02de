// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Overlapping organs: identical, nested and half-overlapping boxes, with
// faces on voxel centres and off them. The reported overlap volume matches
// the exact volume of the boxes' intersection within one voxel layer over
// its surface and never exceeds the smaller organ's enclosed volume.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include "check.h"
#include "prep_fixture.h"

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": %g,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"P\", \"mesh\": \"p.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"Q\", \"mesh\": \"q.obj\", \"model\": \"fixed\"}],\n"
    " \"tissues\": [{\"name\": \"around\", \"connects\": [\"P\", \"Q\"], \"max_gap\": 0.008, \"material\": \"soft\",\n"
    "  \"frame_spacing\": 0.003, \"sample_spacing\": 0.0015}]}\n";

static int run(const char *dir, const char *what, const double *p_lo, const double *p_hi, const double *q_lo,
               const double *q_hi, double h, double shift) {
  double pl[3], ph[3], ql[3], qh[3], exact = 1, area = 0, side[3];
  for (int r = 0; r < 3; ++r) {
    pl[r] = p_lo[r] + shift, ph[r] = p_hi[r] + shift, ql[r] = q_lo[r] + shift, qh[r] = q_hi[r] + shift;
    side[r] = fmin(ph[r], qh[r]) - fmax(pl[r], ql[r]);
    exact *= side[r];
  }
  for (int r = 0; r < 3; ++r) area += 2 * side[(r + 1) % 3] * side[(r + 2) % 3];
  char text[2048], path[512];
  snprintf(text, sizeof text, scene_format, h);
  CHECK(fixture_box(dir, "p.obj", pl, ph) && fixture_box(dir, "q.obj", ql, qh));
  CHECK(fixture_write(dir, "scene.json", text));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  memset(&r, 0, sizeof r);
  CHECK_OK(fascia_prep_scene_load(ctx, path, &r.scene), ctx);
  CHECK_OK(fascia_prep_import(ctx, r.scene, &r.meshes), ctx);
  CHECK_OK(fascia_prep_repair(ctx, r.scene, r.meshes), ctx);
  CHECK_OK(fascia_prep_voxelize(ctx, r.scene, r.meshes, &r.volume), ctx);
  const fascia_prep_volume *v = r.volume;
  const double smaller =
      fmin(r.meshes->organs[0].report.enclosed_volume, r.meshes->organs[1].report.enclosed_volume);
  int bad = v->overlap_count != 1;
  if (!bad) {
    const double got = v->overlaps[0].volume;
    bad = got > smaller * (1 + 1e-12) || fabs(got - exact) > 0.5 * h * area;
    if (bad)
      fprintf(stderr, "%s, voxel %g mm, shift %g mm: overlap %.6g cm^3, exact %.6g cm^3, smaller organ %.6g cm^3\n",
              what, 1e3 * h, 1e3 * shift, 1e6 * got, 1e6 * exact, 1e6 * smaller);
  } else {
    fprintf(stderr, "%s: %d overlaps reported, expected 1\n", what, (int)v->overlap_count);
  }
  CHECK(!bad);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return bad;
}

int main(void) {
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  // corners on whole millimetres: faces on voxel centres at 1 and 0.5 mm voxels
  static const double box_lo[3] = {-0.006, -0.005, -0.007}, box_hi[3] = {0.004, 0.007, 0.007};
  static const double big_lo[3] = {-0.010, -0.010, -0.010}, big_hi[3] = {0.010, 0.010, 0.010};
  static const double small_lo[3] = {-0.004, -0.003, -0.004}, small_hi[3] = {0.004, 0.005, 0.002};
  static const double half_lo[3] = {-0.001, -0.005, -0.007}, half_hi[3] = {0.009, 0.007, 0.007};
  static const double voxels[] = {0.001, 0.0005};
  static const double shifts[] = {0, 0.3, 0.5}; // fractions of a voxel
  int failed = 0;
  for (int k = 0; k < 2; ++k)
    for (int s = 0; s < 3; ++s) {
      const double h = voxels[k], shift = shifts[s] * h;
      failed |= run(dir, "identical", box_lo, box_hi, box_lo, box_hi, h, shift);
      failed |= run(dir, "nested", big_lo, big_hi, small_lo, small_hi, h, shift);
      failed |= run(dir, "half", box_lo, box_hi, half_lo, half_hi, h, shift);
    }
  static const char *const files[] = {"p.obj", "q.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return failed || CHECK_RESULT();
}
