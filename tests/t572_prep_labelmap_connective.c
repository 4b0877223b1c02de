// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Tissue takes the background and the labels the scene declares connective,
// and no other label's voxels (docs/labelmaps.md). Two boxes of labels 12 mm
// wide, 6 mm apart; a third label ("colon") fills part of the space between
// them. Unnamed, it keeps tissue out of its voxels: the tissue loses exactly
// the volume the report says the colon occupies (and
// a few voxels it cuts off), a third of the slab, the
// same through an affine that turns and mirrors. Declared connective (by
// name, by pattern, by value) it gives the tissue back; filling the whole
// gap it is an error that names it; a label both an organ's and connective
// is refused.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "labelmap_fixture.h"
#include "prep_fixture.h"

typedef struct layout {
  double colon_from_y; // mm: label 3 between the boxes where y >= this (INFINITY: none)
} layout;

// A: x in [-15, -3], B: x in [3, 15], |y|, |z| <= 6 (mm, RAS); the colon between them.
static uint8_t label_of(const double *x, const void *data) {
  if (fabs(x[1]) > 6 || fabs(x[2]) > 6) return 0;
  if (x[0] >= -15 && x[0] <= -3) return 1;
  if (x[0] >= 3 && x[0] <= 15) return 2;
  return x[1] >= ((const layout *)data)->colon_from_y ? 3 : 0;
}

// 2 mm voxels centred on even x and odd y, z; and the same centres through a mirror and a quarter turn.
static const labelmap_def straight = {{24, 12, 12}, {2, 0, 0, -24, 0, 2, 0, -11, 0, 0, 2, -11}};
static const labelmap_def turned = {{12, 24, 12}, {0, -2, 0, 24, -2, 0, 0, 11, 0, 0, 2, -11}};

static const char table[] = "label\tname\n1\tbox_a\n2\tbox_b\n3\tcolon\n";

// 0.7 mm voxels: no voxel centre of the scene lies on a face of the image's voxels
static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.0007, \"seed\": 3,\n"
    " \"segmentation\": {\"file\": \"%s\", \"labels\": \"labels.tsv\", \"smoothing\": 0%s},\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"labels\": \"box_a\", \"model\": \"fixed\"},\n"
    "  {\"name\": \"B\", \"labels\": [%s], \"model\": \"prescribed\", \"motion\": {\"pivot\": [0, 0, 0],\n"
    "   \"keys\": [{\"time\": 0}, {\"time\": 1, \"translation\": [0.001, 0, 0]}]}}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008,\n"
    "  \"region\": {\"box\": {\"min\": [-0.008, -0.005, -0.005], \"max\": [0.008, 0.005, 0.005]}},\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.003, \"sample_spacing\": 0.0015}]}\n";

typedef struct outcome {
  fascia_status status;
  double tissue, occupied, dropped;
  int32_t label;
  char text[256], message[1024];
} outcome;

// Prepares the label map file with the segmentation's extra keys and B's labels.
static outcome prepare(const char *dir, const char *file, const char *extra, const char *labels_b) {
  outcome out;
  memset(&out, 0, sizeof out);
  char text[4096], path[512];
  snprintf(text, sizeof text, scene_format, file, extra, labels_b);
  CHECK(fixture_write(dir, "labels.tsv", table));
  CHECK(fixture_write(dir, "scene.json", text));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  out.status = fixture_prep(ctx, path, &r);
  snprintf(out.message, sizeof out.message, "%s", fascia_ctx_message(ctx));
  if (out.status == FASCIA_OK) {
    const fascia_prep_tissue_report *rep = r.volume->tissues;
    out.tissue = rep->volume;
    out.occupied = rep->occupied_volume;
    out.label = rep->occupied_labels[0];
    out.dropped = rep->dropped_volume;
    fascia_prep_occupied_text(r.scene, rep, out.text, sizeof out.text);
    int pieces = 0;
    CHECK(fixture_pieces_touch(r.volume, 1, 2, &pieces));
  }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return out;
}

static void write_map(const char *dir, const char *name, const labelmap_def *d, double colon_from_y) {
  char path[512];
  const layout l = {colon_from_y};
  snprintf(path, sizeof path, "%s/%s", dir, name);
  CHECK(labelmap_write_nifti(path, d, label_of, &l, 1, 0, 0, 1));
}

int main(void) {
  char dir[256];
  CHECK(fixture_tmpdir(dir));
  write_map(dir, "free.nii.gz", &straight, INFINITY);
  write_map(dir, "colon.nii.gz", &straight, 2);
  write_map(dir, "turned.nii.gz", &turned, 2);
  write_map(dir, "full.nii.gz", &straight, -7);

  const outcome free_gap = prepare(dir, "free.nii.gz", "", "\"box_b\"");
  CHECK_OK(free_gap.status, NULL);
  CHECK(free_gap.occupied == 0 && free_gap.label == 0 && !free_gap.text[0]);
  CHECK(free_gap.tissue > 0.9 * 6e-3 * 1e-4); // the 6 x 10 x 10 mm slab, its faces within half a voxel

  // unnamed, the colon keeps tissue out: what the tissue loses is what the report says it occupies
  const outcome colon = prepare(dir, "colon.nii.gz", "", "\"box_b\"");
  CHECK_OK(colon.status, NULL);
  CHECK(free_gap.dropped == 0);
  CHECK_NEAR(colon.tissue + colon.occupied + colon.dropped, free_gap.tissue, 1e-12, 0);
  CHECK(colon.dropped < 0.01 * colon.tissue); // corners the colon cuts off
  CHECK_NEAR(colon.occupied / free_gap.tissue, 1.0 / 3, 0, 0.06); // y from 2 to 5 mm of -5 .. 5, on 0.7 mm voxels
  CHECK(colon.label == 3);
  CHECK(strstr(colon.text, "colon (3) ") == colon.text);
  const outcome turn = prepare(dir, "turned.nii.gz", "", "\"box_b\"");
  CHECK_OK(turn.status, NULL);
  CHECK_NEAR(turn.occupied, colon.occupied, 1e-12, 0);
  CHECK_NEAR(turn.tissue, colon.tissue, 1e-12, 0);

  // declared connective, by name, pattern or value: the tissue takes it back
  const char *const declared[] = {", \"connective\": \"colon\"", ", \"connective\": [\"col*\"]",
                                  ", \"connective\": [3]"};
  for (int k = 0; k < 3; ++k) {
    const outcome c = prepare(dir, "colon.nii.gz", declared[k], "\"box_b\"");
    CHECK_OK(c.status, NULL);
    CHECK(c.occupied == 0);
    CHECK_NEAR(c.tissue, free_gap.tissue, 1e-12, 0);
  }

  // a colon filling the gap: one line that names it and the key
  const outcome full = prepare(dir, "full.nii.gz", "", "\"box_b\"");
  CHECK(full.status == FASCIA_ERR_ARGUMENT);
  if (!strstr(full.message, "colon (3)")) fprintf(stderr, "%s\n", full.message);
  CHECK(strstr(full.message, "colon (3)") && strstr(full.message, "segmentation.connective") &&
        !strchr(full.message, '\n'));
  // a label both an organ's and connective
  const outcome both = prepare(dir, "colon.nii.gz", declared[0], "\"box_b\", \"colon\"");
  CHECK(both.status == FASCIA_ERR_FORMAT);
  CHECK(strstr(both.message, "organs[1].labels") && strstr(both.message, "declared connective"));
  if (both.status != FASCIA_ERR_FORMAT) fprintf(stderr, "%s\n", both.message);

  const char *const names[] = {"free.nii.gz", "colon.nii.gz", "turned.nii.gz", "full.nii.gz",
                               "labels.tsv",  "scene.json",   NULL};
  fixture_cleanup(dir, names);
  return CHECK_RESULT();
}
