// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Two boxes 10 mm wide, 3 to 13 mm apart in 0.5 mm steps, max_gap 8 mm, at
// several voxel sizes and offsets of the boxes against the voxel lattice:
// voxelize either builds the tissue (always when the gap is at most
// max_gap: the tissue bridges it) or refuses with the user's message naming
// the tissue, both organs, the gap between them and the max_gap to use
// (always beyond max_gap); never an internal error. A few runs go through the
// whole pipeline, which must end in a model or a user-level error.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include "check.h"
#include "prep_fixture.h"

#define MAX_GAP 0.008

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": %g, \"seed\": 3,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"fixed\"}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": %g, \"material\": \"soft\",\n"
    "  \"frame_spacing\": %g, \"sample_spacing\": %g}]}\n";

// One layout: box A ends at x = shift - gap / 2, box B starts at shift +
// gap / 2; both are 10 mm on every side, shifted by `shift` on all axes.
static int run(const char *dir, double gap, double h, double shift, int whole) {
  const double a_lo[3] = {shift - gap / 2 - 0.01, shift - 0.005, shift - 0.005};
  const double a_hi[3] = {shift - gap / 2, shift + 0.005, shift + 0.005};
  const double b_lo[3] = {shift + gap / 2, shift - 0.005, shift - 0.005};
  const double b_hi[3] = {shift + gap / 2 + 0.01, shift + 0.005, shift + 0.005};
  char text[2048], path[512];
  const double spacing = h > 0.001 ? h : 0.001;
  snprintf(text, sizeof text, scene_format, h, MAX_GAP, 3 * spacing, 1.5 * spacing);
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && fixture_box(dir, "b.obj", b_lo, b_hi));
  CHECK(fixture_write(dir, "scene.json", text));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  fascia_status st;
  if (whole) {
    st = fixture_prep(ctx, path, &r);
  } else {
    memset(&r, 0, sizeof r);
    st = fascia_prep_scene_load(ctx, path, &r.scene);
    if (!st) st = fascia_prep_import(ctx, r.scene, &r.meshes);
    if (!st) st = fascia_prep_repair(ctx, r.scene, r.meshes);
    if (!st) st = fascia_prep_voxelize(ctx, r.scene, r.meshes, &r.volume);
  }
  const char *message = fascia_ctx_message(ctx);
  int bad = st != FASCIA_OK && st != FASCIA_ERR_ARGUMENT && st != FASCIA_ERR_NUMERIC;
  if (r.volume == NULL && st == FASCIA_ERR_ARGUMENT && strstr(message, "too far apart")) {
    // the user's message: the tissue, both organs, the gap found, max_gap, the remedy
    char found[64];
    snprintf(found, sizeof found, "surfaces are %.3g mm apart", 1e3 * gap);
    bad |= !strstr(message, "tissue 'gap'") || !strstr(message, "'A' and 'B'") || !strstr(message, found) ||
           !strstr(message, "max_gap 0.008 m") || !strstr(message, "raise max_gap to at least");
  }
  // up to max_gap the voxel centres between the faces lie on bridges of
  // length gap (d_A + d_B = gap there): voxelize must build them
  if (gap <= MAX_GAP - 0.01 * h && !r.volume) bad = 1;
  // beyond max_gap no path of at most max_gap joins the boxes: the user's message
  if (gap > MAX_GAP + 1e-9 && (st != FASCIA_ERR_ARGUMENT || !strstr(message, "too far apart"))) bad = 1;
  if (bad)
    fprintf(stderr, "gap %g mm, voxel %g mm, shift %g mm%s: %s: %s\n", 1e3 * gap, 1e3 * h, 1e3 * shift,
            whole ? " (whole pipeline)" : "", fascia_status_name(st), message);
  CHECK(!bad);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return bad;
}

int main(void) {
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  static const double voxels[] = {0.0005, 0.001, 0.002};
  static const double shifts[] = {0, 0.3, 0.5, 0.77}; // fractions of a voxel
  int failed = 0;
  for (int v = 0; v < 3; ++v)
    for (int s = 0; s < 4; ++s)
      for (int k = 0; k <= 20; ++k) {
        if (v == 0 && s % 2) continue; // the finest voxels: two offsets keep the test short
        const double gap = 0.003 + 0.0005 * k, h = voxels[v];
        failed |= run(dir, gap, h, shifts[s] * h, 0);
      }
  // the whole pipeline near the limit
  for (int k = 7; k <= 13; ++k) failed |= run(dir, 0.003 + 0.0005 * k, 0.001, 0.0003, 1);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return failed || CHECK_RESULT();
}
