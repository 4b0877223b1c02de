// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// One template scene serves segmentations that lack an organ: an organ marked
// "optional" that the label map lacks is left out with the tissues that no
// longer have their organs, and the rest is built as from a scene without
// it; present, it is built as usual; a required organ the map lacks is an
// error naming the organ, its label and the key that would allow it; the key
// on a mesh organ, and a scene left without tissue, are refused.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "labelmap_fixture.h"
#include "prep_fixture.h"

// A: x in [-15, -3], B: x in [3, 15], C: x in [21, 33], |y|, |z| <= 6 (mm, RAS); C only when asked.
static uint8_t label_of(const double *x, const void *data) {
  if (fabs(x[1]) > 6 || fabs(x[2]) > 6) return 0;
  if (x[0] >= -15 && x[0] <= -3) return 1;
  if (x[0] >= 3 && x[0] <= 15) return 2;
  return x[0] >= 21 && x[0] <= 33 && *(const int *)data ? 3 : 0;
}

static const labelmap_def grid = {{36, 12, 12}, {2, 0, 0, -24, 0, 2, 0, -11, 0, 0, 2, -11}};
static const char table[] = "label\tname\n1\tbox_a\n2\tbox_b\n3\tbox_c\n";

// C's extra keys, then the tissues
static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 3,\n"
    " \"segmentation\": {\"file\": \"%s\", \"labels\": \"labels.tsv\", \"smoothing\": 0},\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"labels\": \"box_a\"},\n"
    "  {\"name\": \"B\", \"labels\": \"box_b\", \"model\": \"prescribed\", \"motion\": {\"pivot\": [0, 0, 0],\n"
    "   \"keys\": [{\"time\": 0}, {\"time\": 1, \"translation\": [0.001, 0, 0]}]}},\n"
    "  {\"name\": \"C\", \"labels\": \"box_c\"%s}],\n"
    " \"tissues\": [%s]}\n";
#define TISSUE(name, connects)                                                                                        \
  "{\"name\": \"" name "\", \"connects\": [" connects "], \"max_gap\": 0.008, \"material\": \"soft\", "               \
  "\"frame_spacing\": 0.003, \"sample_spacing\": 0.0015, \"coupling\": {\"organs\": {\"C\": true}}}"

typedef struct outcome {
  fascia_status status;
  int32_t organs, tissues, absent, dropped, frames;
  char absent_name[64], dropped_name[64], message[2048];
} outcome;

static outcome prepare(const char *dir, const char *map, const char *c_keys, const char *tissues) {
  outcome out;
  memset(&out, 0, sizeof out);
  char text[4096], path[512];
  snprintf(text, sizeof text, scene_format, map, c_keys, tissues);
  CHECK(fixture_write(dir, "labels.tsv", table));
  CHECK(fixture_write(dir, "scene.json", text));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  out.status = fixture_prep(ctx, path, &r);
  snprintf(out.message, sizeof out.message, "%s", fascia_ctx_message(ctx));
  if (out.status == FASCIA_OK) {
    out.organs = r.scene->organ_count, out.tissues = r.scene->tissue_count;
    out.absent = r.scene->absent_organ_count, out.dropped = r.scene->dropped_tissue_count;
    if (out.absent) snprintf(out.absent_name, sizeof out.absent_name, "%s", r.scene->absent_organs[0]);
    if (out.dropped) snprintf(out.dropped_name, sizeof out.dropped_name, "%s", r.scene->dropped_tissues[0]);
    out.frames = r.model->frame_count;
  }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return out;
}

int main(void) {
  char dir[256], path[512];
  CHECK(fixture_tmpdir(dir));
  const int with = 1, without = 0;
  snprintf(path, sizeof path, "%s/with.nii.gz", dir);
  CHECK(labelmap_write_nifti(path, &grid, label_of, &with, 1, 0, 0, 1));
  snprintf(path, sizeof path, "%s/without.nii.gz", dir);
  CHECK(labelmap_write_nifti(path, &grid, label_of, &without, 1, 0, 0, 1));
  const char *const two = TISSUE("ab", "\"A\", \"B\"") ", " TISSUE("bc", "\"B\", \"C\"");
  const char *const optional = ", \"optional\": true";

  // present: built as usual, nothing left out
  const outcome present = prepare(dir, "with.nii.gz", optional, two);
  CHECK_OK(present.status, NULL);
  CHECK(present.organs == 3 && present.tissues == 2 && present.absent == 0 && present.dropped == 0);

  // absent: C and the tissue bc left out; ab as from a scene that never had C
  const outcome absent = prepare(dir, "without.nii.gz", optional, two);
  CHECK_OK(absent.status, NULL);
  CHECK(absent.organs == 2 && absent.tissues == 1 && absent.absent == 1 && absent.dropped == 1);
  CHECK(!strcmp(absent.absent_name, "C") && !strcmp(absent.dropped_name, "bc"));
  const outcome alone = prepare(dir, "with.nii.gz", "", TISSUE("ab", "\"A\", \"B\""));
  CHECK_OK(alone.status, NULL);
  CHECK(absent.frames == alone.frames && absent.frames > 0);
  // a tissue that keeps two of its three organs stays, without C
  const outcome kept = prepare(dir, "without.nii.gz", optional, TISSUE("abc", "\"A\", \"B\", \"C\""));
  CHECK_OK(kept.status, NULL);
  CHECK(kept.tissues == 1 && kept.dropped == 0 && kept.frames == alone.frames);

  // required and absent: the organ, its label, the key that would allow it
  const outcome required = prepare(dir, "without.nii.gz", "", two);
  CHECK(required.status == FASCIA_ERR_FORMAT);
  if (!strstr(required.message, "\"optional\"")) fprintf(stderr, "%s\n", required.message);
  CHECK(strstr(required.message, "organ 'C'") && strstr(required.message, "no voxel labelled 3") &&
        strstr(required.message, "\"optional\": true") && !strchr(required.message, '\n'));

  // no tissue left: refused, naming the organ
  const outcome none = prepare(dir, "without.nii.gz", optional, TISSUE("bc", "\"B\", \"C\""));
  CHECK(none.status == FASCIA_ERR_FORMAT);
  CHECK(strstr(none.message, "no tissue is left") && strstr(none.message, "(C)"));
  if (none.status != FASCIA_ERR_FORMAT) fprintf(stderr, "%s\n", none.message);

  // the key applies to label organs only
  snprintf(path, sizeof path, "%s/scene.json", dir);
  CHECK(fixture_write(dir, "scene.json",
                      "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"materials\": {\"soft\": {\"youngs_modulus\": "
                      "3000, \"poisson_ratio\": 0.3}}, \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", "
                      "\"optional\": true}], \"tissues\": []}"));
  fascia_ctx *ctx = fixture_ctx();
  fascia_prep_scene *scene = NULL;
  CHECK(fascia_prep_scene_load(ctx, path, &scene) == FASCIA_ERR_FORMAT);
  CHECK(strstr(fascia_ctx_message(ctx), "organs[0].optional") && strstr(fascia_ctx_message(ctx), "labels"));
  fascia_prep_scene_destroy(&scene);
  fascia_ctx_destroy(&ctx);

  const char *const names[] = {"with.nii.gz", "without.nii.gz", "labels.tsv", "scene.json", NULL};
  fixture_cleanup(dir, names);
  return CHECK_RESULT();
}
