// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A sample spacing below the voxel size is kept: the voxels are split so
// that samples finer than them still each get a cell. The same scene
// (samples every 0.75 mm) prepared at 1 mm voxels (split) and at 0.5 mm
// (not) has about the same number of samples, every one with a volume, the
// same volume and the same static answer. When a voxel could go to one
// sample only (and the scene refused samples finer than its voxels), the
// 1 mm voxels kept at most one sample each, and the finer rungs of a
// spacing ladder at a fixed voxel size stopped refining (docs/measured.md,
// the demo against CalculiX).
// The scene: t594's 12 mm gap between two boxes, B pulled 1 mm along it.
#define _POSIX_C_SOURCE 200809L // mkdtemp in prep_fixture.h
#include <math.h>

#include "check.h"
#include "prep_fixture.h"

#define GAP 0.012
#define W 0.02 // half the boxes' width, m

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": %g, \"seed\": 3,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n \"gravity\": [0, 0, 0],\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"prescribed\", \"motion\": {\"pivot\": [0, 0, 0], "
    "\"keys\": [\n"
    "                {\"time\": 0}, {\"time\": 1, \"translation\": [0, 0.001, 0]}]}}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.015, \"material\": \"soft\",\n"
    "  \"frame_spacing\": 0.006, \"sample_spacing\": 0.00075}]}\n";

typedef struct answer {
  fixture_run run;
  double force;  // |force on A|, N
  double volume; // sum of the sample volumes, m^3
  double least;  // smallest sample volume, m^3
} answer;

static int prepare(const char *dir, double voxel, answer *out) {
  char text[2048], name[64], path[512];
  snprintf(text, sizeof text, scene_format, voxel);
  snprintf(name, sizeof name, "scene-%g.json", voxel);
  snprintf(path, sizeof path, "%s/%s", dir, name);
  double force[3];
  if (!fixture_write(dir, name, text) || !fixture_prep_static(path, 0, &out->run, force)) return 0;
  out->force = sqrt(force[0] * force[0] + force[1] * force[1] + force[2] * force[2]);
  out->volume = 0, out->least = INFINITY;
  for (int32_t s = 0; s < out->run.model->sample_count; ++s) {
    out->volume += out->run.model->sample_volume[s];
    out->least = fmin(out->least, out->run.model->sample_volume[s]);
  }
  return 1;
}

int main(void) {
  char dir[256];
  CHECK(fixture_tmpdir(dir));
  const double a_lo[3] = {-GAP / 2 - 0.01, -W, -W}, a_hi[3] = {-GAP / 2, W, W};
  const double b_lo[3] = {GAP / 2, -W, -W}, b_hi[3] = {GAP / 2 + 0.01, W, W};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && fixture_box(dir, "b.obj", b_lo, b_hi));
  answer coarse, fine;
  CHECK(prepare(dir, 0.001, &coarse) && prepare(dir, 0.0005, &fine));
  const fascia_model *c = coarse.run.model, *f = fine.run.model;
  const double change = fine.force / coarse.force - 1;
  printf("t587: samples every 0.75 mm; 1 mm voxels: %d samples, volume %.4g cm^3 (smallest %.3g mm^3), force %.5g N; "
         "0.5 mm voxels: %d samples, volume %.4g cm^3, force %.5g N (%+.2f %%)\n",
         (int)c->sample_count, 1e6 * coarse.volume, 1e9 * coarse.least, coarse.force, (int)f->sample_count,
         1e6 * fine.volume, fine.force, 100 * change);
  CHECK(fabs((double)c->sample_count / f->sample_count - 1) < 0.1);
  CHECK(coarse.least > 0 && fine.least > 0);
  CHECK(fabs(coarse.volume / fine.volume - 1) < 0.05);
  CHECK(coarse.force > 0 && fabs(change) < 0.05);
  fixture_free(&coarse.run);
  fixture_free(&fine.run);
  const char *names[] = {"a.obj", "b.obj", "scene-0.001.json", "scene-0.0005.json", NULL};
  fixture_cleanup(dir, names);
  return CHECK_RESULT();
}
