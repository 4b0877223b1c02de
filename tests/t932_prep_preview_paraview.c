// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// prep's preview opens in one go: preview.pvd, opened in ParaView
// (pvbatch, tests/paraview/check_preview.py), shows each organ under its
// name, the region, the frames with what holds each (the kind of the organ
// a frame is shared with: a fixed box A, a prescribed B, a rigid C), the
// samples and the shared frames, as many as prep built. Before, the preview
// was five legacy files with the organs numbered in one of them and no
// frame kind. Skipped, saying so, without pvbatch.
// Usage: t932_prep_preview_paraview TESTS/paraview
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include "check.h"
#include "prep_fixture.h"

static const char scene[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 3,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"box_a\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "   {\"name\": \"box_b\", \"mesh\": \"b.obj\", \"model\": \"prescribed\", \"motion\": {\"pivot\": [0, 0, 0],\n"
    "    \"keys\": [{\"time\": 0}, {\"time\": 1, \"translation\": [0.001, 0, 0]}]}},\n"
    "   {\"name\": \"box_c\", \"mesh\": \"c.obj\", \"model\": \"rigid\"}],\n"
    " \"tissues\": [{\"name\": \"web\", \"connects\": [\"box_a\", \"box_b\", \"box_c\"], \"max_gap\": 0.005,\n"
    "   \"material\": \"soft\", \"frame_spacing\": 0.002, \"sample_spacing\": 0.0015}]}\n";

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t932_prep_preview_paraview TESTS/paraview\n");
    return 1;
  }
  if (system("command -v pvbatch >/dev/null 2>&1") != 0) {
    printf("t932: skipped: pvbatch (Debian's python3-paraview, tools/setup/debian-packages.sh) is not installed\n");
    return TEST_SKIP;
  }
  char dir[256], path[512], preview[512], command[4096];
  CHECK(fixture_tmpdir(dir));
  // A and B side by side 4 mm apart, C above both 3 mm up
  const double lo[3][3] = {{-0.02, -0.01, -0.01}, {0.002, -0.01, -0.01}, {-0.02, 0.013, -0.01}};
  const double hi[3][3] = {{-0.002, 0.01, 0.01}, {0.02, 0.01, 0.01}, {0.02, 0.03, 0.01}};
  const char *names[] = {"a.obj", "b.obj", "c.obj", "scene.json", NULL};
  for (int k = 0; k < 3; ++k) CHECK(fixture_box(dir, names[k], lo[k], hi[k]));
  CHECK(fixture_write(dir, "scene.json", scene));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  snprintf(preview, sizeof preview, "%s/preview", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  if (r.coupling) {
    CHECK_OK(fascia_prep_preview(ctx, preview, r.scene, r.meshes, r.volume, r.points, r.coupling), ctx);
    int64_t voxels = 0;
    const int64_t n = (int64_t)r.volume->dims[0] * r.volume->dims[1] * r.volume->dims[2];
    for (int64_t v = 0; v < n; ++v) voxels += r.volume->region[v] > 0;
    snprintf(command, sizeof command,
             "pvbatch '%s/check_preview.py' '%s/preview.pvd' box_a:1,box_b:2,box_c:3 %d %d %d %lld 2>&1 | "
             "grep -v -i openpmd | tee /dev/stderr | grep -q ', 0 failures'",
             argv[1], preview, (int)r.points->frame_count, (int)r.points->sample_count, (int)r.coupling->count,
             (long long)voxels);
    fflush(stdout);
    CHECK(system(command) == 0);
  }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  snprintf(command, sizeof command, "rm -rf '%s'", dir);
  CHECK(system(command) == 0);
  return CHECK_RESULT();
}
