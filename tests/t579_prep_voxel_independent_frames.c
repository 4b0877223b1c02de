// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A thin tissue's frames do not follow the voxels, so its answer converges
// as the voxels are refined: two fixed 30 x 30 mm faces 3.8 mm apart, the
// middle of the gap at x = 0.6 mm (off every voxel centre), frames every 10
// mm, samples every 1 mm, prepared at 1, 0.7 and 0.5 mm voxels. Away from
// the faces' edges:
// - every free frame lies on the gap's mid-plane (the midpoint of the two
//   faces' closest points, not a voxel centre);
// - the frames on each face are the same points at every voxel size (their
//   candidates are points of the surface a fixed distance apart, not one
//   per voxel), and so are most mid-layer frames.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "prep_fixture.h"

#define W 0.015     // half the faces' width, m
#define LO -0.0013  // A's face
#define HI 0.0025   // B's face
#define EDGE 0.003  // frames this near the faces' edges are not compared

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": %g, \"seed\": 2,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"fixed\"}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008, \"material\": \"soft\",\n"
    "  \"frame_spacing\": 0.01, \"sample_spacing\": 0.001}]}\n";

typedef struct frames {
  int count;
  double x[400][3];
  int free[400];
} frames;

// The model's frames away from the faces' edges, at this voxel size.
static int prepare(const char *dir, double voxel, frames *out) {
  char text[2048];
  snprintf(text, sizeof text, scene_format, voxel);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep_text(ctx, dir, text, &r);
  CHECK_OK(st, ctx);
  out->count = 0;
  for (int32_t i = 0; st == FASCIA_OK && i < r.model->frame_count && out->count < 400; ++i) {
    const double *x = r.model->frame_position + 3 * i;
    if (fabs(x[1]) > W - EDGE || fabs(x[2]) > W - EDGE) continue;
    for (int c = 0; c < 3; ++c) out->x[out->count][c] = x[c];
    out->free[out->count++] = r.model->frame_kind[i] == FASCIA_FRAME_FREE;
  }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return st == FASCIA_OK;
}

// How many frames of a (free or not, as asked) have a frame of b within 1 um.
static int matched(const frames *a, const frames *b, int free, int *of) {
  int count = 0;
  *of = 0;
  for (int i = 0; i < a->count; ++i) {
    if (a->free[i] != free) continue;
    ++*of;
    for (int j = 0; j < b->count; ++j) {
      const double d = sqrt((a->x[i][0] - b->x[j][0]) * (a->x[i][0] - b->x[j][0]) +
                            (a->x[i][1] - b->x[j][1]) * (a->x[i][1] - b->x[j][1]) +
                            (a->x[i][2] - b->x[j][2]) * (a->x[i][2] - b->x[j][2]));
      if (d < 1e-6) {
        ++count;
        break;
      }
    }
  }
  return count;
}

int main(void) {
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  const double a_lo[3] = {LO - 0.01, -W, -W}, a_hi[3] = {LO, W, W};
  const double b_lo[3] = {HI, -W, -W}, b_hi[3] = {HI + 0.01, W, W};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && fixture_box(dir, "b.obj", b_lo, b_hi));
  static const double voxels[] = {0.001, 0.0007, 0.0005};
  static frames at[3];
  for (int v = 0; v < 3; ++v) {
    CHECK(prepare(dir, voxels[v], at + v));
    int mid = 0, off = 0;
    for (int i = 0; i < at[v].count; ++i) {
      if (!at[v].free[i]) continue;
      ++mid;
      if (fabs(at[v].x[i][0] - 0.5 * (LO + HI)) > 1e-6 && off++ < 3)
        fprintf(stderr, "voxel %g mm: free frame at x %.4f mm, the mid-plane at %.4f mm\n", 1e3 * voxels[v],
                1e3 * at[v].x[i][0], 0.5e3 * (LO + HI));
    }
    printf("voxel %g mm: %d frames away from the edges, %d of them free, %d off the mid-plane\n", 1e3 * voxels[v],
           at[v].count, mid, off);
    CHECK(mid > 0 && off == 0);
  }
  for (int v = 1; v < 3; ++v) {
    int faces, mids;
    const int same_faces = matched(at, at + v, 0, &faces), same_mids = matched(at, at + v, 1, &mids);
    printf("1 mm against %g mm voxels: %d of %d face frames and %d of %d mid-layer frames the same\n",
           1e3 * voxels[v], same_faces, faces, same_mids, mids);
    CHECK(faces > 20 && same_faces >= 0.95 * faces);
    CHECK(same_mids >= 0.6 * mids);
  }
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
