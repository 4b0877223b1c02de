// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// An organ face that lies on voxel centres keeps its surface frames: the
// region voxels next to it are exactly a voxel away, which the float
// distance field stores a rounding above the voxel size, and the surface
// frames' candidates (the region voxels within a voxel of the organ) left
// that whole layer out. Box A's face at x = -33 mm, on the 0.5 mm voxel
// centres, then kept half its shared frames (117 of 234; a sphere beside
// it 27 of 146, and a tenth of its force). The same scene moved 0.13 mm
// off the centres is the reference: A's shared frames and the tissue's
// force on A agree within 10 %.
#define _POSIX_C_SOURCE 200809L // mkdtemp in prep_fixture.h
#include <math.h>

#include "check.h"
#include "prep_fixture.h"

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.0005, \"seed\": 1, \"gravity\": [0, 0, 0],\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 5000, \"poisson_ratio\": 0.4}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a-%s.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"b-%s.obj\", \"model\": \"prescribed\", \"motion\": {\"pivot\": [0, 0, 0], "
    "\"keys\": [{\"time\": 0}, {\"time\": 1, \"translation\": [0.001, 0, 0]}]}}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.009, \"material\": \"soft\",\n"
    "  \"frame_spacing\": 0.0025, \"sample_spacing\": 0.00125}]}\n";

typedef struct answer {
  int32_t shared_a; // frames shared with A
  double force;     // the tissue's force on A along x, N
} answer;

static int prepare(const char *dir, const char *tag, double shift, answer *out) {
  const double h = 0.018;
  const double a_lo[3] = {-0.045 + shift, -h, -h}, a_hi[3] = {-0.033 + shift, h, h};
  const double b_lo[3] = {-0.030 + shift, -h, -h}, b_hi[3] = {shift, h, h};
  char a[64], b[64], text[2048], name[64], path[512];
  snprintf(a, sizeof a, "a-%s.obj", tag);
  snprintf(b, sizeof b, "b-%s.obj", tag);
  snprintf(text, sizeof text, scene_format, tag, tag);
  snprintf(name, sizeof name, "scene-%s.json", tag);
  snprintf(path, sizeof path, "%s/%s", dir, name);
  if (!fixture_box(dir, a, a_lo, a_hi) || !fixture_box(dir, b, b_lo, b_hi) || !fixture_write(dir, name, text)) return 0;
  fixture_run run = {0};
  double force[3];
  const int ok = fixture_prep_static(path, 0, &run, force);
  out->shared_a = ok ? run.coupling->per_organ[0] : 0;
  out->force = force[0];
  fixture_free(&run);
  return ok;
}

int main(void) {
  char dir[256];
  CHECK(fixture_tmpdir(dir));
  answer on, off;
  CHECK(prepare(dir, "on", 0, &on) && prepare(dir, "off", 0.00013, &off));
  printf("t548: A's face on the voxel centres: %d shared frames, force %.5g N; moved off them: %d, %.5g N\n",
         (int)on.shared_a, on.force, (int)off.shared_a, off.force);
  CHECK(off.shared_a > 0 && fabs((double)on.shared_a / off.shared_a - 1) < 0.1);
  CHECK(off.force != 0 && fabs(on.force / off.force - 1) < 0.1);
  const char *names[] = {"a-on.obj", "b-on.obj", "scene-on.json", "a-off.obj", "b-off.obj", "scene-off.json", NULL};
  fixture_cleanup(dir, names);
  return CHECK_RESULT();
}
