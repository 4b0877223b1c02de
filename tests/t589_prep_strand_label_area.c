// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A strand attached by a label of the segmentation, spread over it (issue
// 43: "a label of the segmentation ... the whole labelled patch"). Box A is
// label box_a; box B is b_upper (y >= 0), b_lower (y < 0) and b_core (one
// voxel deep inside, so with no surface). A strand from A's face at
// (-3, -4, 0) mm to B's label b_lower, spread: a fan of frames on the part
// of b_lower's surface that faces the strand (B's face x = 3 mm, y < 0),
// all coupled to B; by the label's value the same; unspread, the strand
// ends at the label's one point nearest its start. Refused naming the key:
// a label of another organ, a label with no surface (b_core).
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "labelmap_fixture.h"
#include "prep_fixture.h"

// A: x in [-15, -3], B: x in [3, 15]; |y|, |z| <= 6 (mm, RAS); B split at y = 0.
static uint8_t label_of(const double *x, const void *data) {
  (void)data;
  if (fabs(x[1]) > 6 || fabs(x[2]) > 6) return 0;
  if (x[0] >= -15 && x[0] <= -3) return 1;
  if (fabs(x[0] - 9.5) < 0.6 && fabs(x[1] - 3.5) < 0.6 && fabs(x[2] - 0.5) < 0.6) return 4;
  if (x[0] >= 3 && x[0] <= 15) return x[1] >= 0 ? 2 : 3;
  return 0;
}

// 1 mm voxels centred on half millimetres
static const labelmap_def grid = {{40, 24, 24}, {1, 0, 0, -19.5, 0, 1, 0, -11.5, 0, 0, 1, -11.5}};

static const char table[] = "label\tname\n1\tbox_a\n2\tb_upper\n3\tb_lower\n4\tb_core\n";

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.0005, \"seed\": 3,\n"
    " \"segmentation\": {\"file\": \"map.nii\", \"labels\": \"labels.tsv\", \"smoothing\": 0},\n"
    " \"materials\": {\"lig\": {\"youngs_modulus\": 100000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"labels\": \"box_a\", \"model\": \"fixed\"},\n"
    "  {\"name\": \"B\", \"labels\": [\"b_upper\", \"b_lower\", \"b_core\"], \"model\": \"fixed\"}],\n"
    " \"tissues\": [{\"name\": \"lig\", \"form\": \"strand\",\n"
    "  \"from\": {\"organ\": \"A\", \"point\": [-0.003, -0.004, 0]}, \"to\": {\"organ\": \"B\", \"label\": %s},\n"
    "  \"radius\": 0.0005, \"material\": \"lig\", \"frame_spacing\": 0.002}]}\n";

// The frames coupled to B after prep: their count, and how many lie on B's
// face toward A (x within a voxel of 3 mm) at y < 0.5 mm; the status.
static fascia_status fan_on_b(const char *dir, const char *label, int *on_b, int *on_face, char *message,
                              size_t size) {
  char text[2048], path[512];
  snprintf(text, sizeof text, scene_format, label);
  if (!fixture_write(dir, "scene.json", text)) return FASCIA_ERR_IO;
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep(ctx, path, &r);
  snprintf(message, size, "%s", fascia_ctx_message(ctx));
  *on_b = *on_face = 0;
  for (int32_t c = 0; st == FASCIA_OK && c < r.model->coupling_count; ++c)
    if (r.model->coupling_organ[c] == 1) {
      const double *x = r.model->frame_position + 3 * r.model->coupling_frame[c];
      ++*on_b;
      *on_face += fabs(x[0] - 0.003) < 0.001 && x[1] < 0.0005;
    }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return st;
}

int main(void) {
  char dir[256], path[512], message[1024];
  if (!fixture_tmpdir(dir)) return 1;
  CHECK(fixture_write(dir, "labels.tsv", table));
  snprintf(path, sizeof path, "%s/map.nii", dir);
  CHECK(labelmap_write_nifti(path, &grid, label_of, NULL, 1, 0, 0, 1));
  // unspread: one frame, the label's point nearest the strand's start
  {
    int on_b = 0, on_face = 0;
    const fascia_status st = fan_on_b(dir, "\"b_lower\", \"spread\": false", &on_b, &on_face, message, sizeof message);
    if (st != FASCIA_OK) fprintf(stderr, "label b_lower: %s\n", message);
    fprintf(stderr, "label \"b_lower\", unspread: %d frame on B, %d on its face toward A at y < 0\n", on_b, on_face);
    CHECK(st == FASCIA_OK && on_b == 1 && on_face == 1);
  }
  static const char *const labels[2] = {"\"b_lower\", \"spread\": true", "3, \"spread\": true"};
  for (int k = 0; k < 2; ++k) {
    int on_b = 0, on_face = 0;
    const fascia_status st = fan_on_b(dir, labels[k], &on_b, &on_face, message, sizeof message);
    if (st != FASCIA_OK) fprintf(stderr, "label %s: %s\n", labels[k], message);
    fprintf(stderr, "label %s, spread: %d frames on B, %d on its face toward A at y < 0\n", labels[k], on_b, on_face);
    CHECK(st == FASCIA_OK && on_b >= 3 && on_face == on_b);
  }
  int on_b, on_face;
  fascia_status st = fan_on_b(dir, "\"box_a\"", &on_b, &on_face, message, sizeof message);
  fprintf(stderr, "refused: %s\n", message);
  CHECK(st != FASCIA_OK && strstr(message, "tissues[0].to.label") && strstr(message, "no label 'box_a'") &&
        !strchr(message, '\n'));
  st = fan_on_b(dir, "\"b_core\"", &on_b, &on_face, message, sizeof message);
  fprintf(stderr, "refused: %s\n", message);
  CHECK(st != FASCIA_OK && strstr(message, "tissues[0].to.label") && strstr(message, "no surface") &&
        !strchr(message, '\n'));
  static const char *const files[] = {"labels.tsv", "map.nii", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
