// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// An organ made of several labels has one part per label, named by the
// label table, so a strand can attach to one label of it (issue 43: "a
// label of the segmentation"). Box A is label box_a; box B is two labels,
// b_upper (y >= 0) and b_lower (y < 0). A strand from A's face at
// (-3, -4, 0) mm to B's part b_lower ends on B's facing face near
// (3, -4, 0) mm; to b_upper, on that face at y >= 0, nearest the start
// (the part's edge at y = 0). An organ of one label keeps one part, named
// after the organ; an unknown label part is refused naming the key.
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
  if (x[0] >= 3 && x[0] <= 15) return x[1] >= 0 ? 2 : 3;
  return 0;
}

// 1 mm voxels centred on half millimetres
static const labelmap_def grid = {{40, 24, 24}, {1, 0, 0, -19.5, 0, 1, 0, -11.5, 0, 0, 1, -11.5}};

static const char table[] = "label\tname\n1\tbox_a\n2\tb_upper\n3\tb_lower\n";

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.0005, \"seed\": 3,\n"
    " \"segmentation\": {\"file\": \"map.nii\", \"labels\": \"labels.tsv\", \"smoothing\": 0},\n"
    " \"materials\": {\"lig\": {\"youngs_modulus\": 100000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"labels\": \"box_a\", \"model\": \"fixed\"},\n"
    "  {\"name\": \"B\", \"labels\": [\"b_upper\", \"b_lower\"], \"model\": \"fixed\"}],\n"
    " \"tissues\": [{\"name\": \"lig\", \"form\": \"strand\",\n"
    "  \"from\": {\"organ\": \"A\", \"point\": [-0.003, -0.004, 0]}, \"to\": {\"organ\": \"B\", \"part\": \"%s\"},\n"
    "  \"radius\": 0.0005, \"material\": \"lig\", \"frame_spacing\": 0.002}]}\n";

// The strand's end on B (its frame shared with organ 1) after prep, into end; the status.
static fascia_status strand_end(const char *dir, const char *part, double *end, char *message, size_t size,
                                int *a_parts, int *b_parts) {
  char text[2048], path[512];
  snprintf(text, sizeof text, scene_format, part);
  if (!fixture_write(dir, "scene.json", text)) return FASCIA_ERR_IO;
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep(ctx, path, &r);
  snprintf(message, size, "%s", fascia_ctx_message(ctx));
  if (r.meshes) *a_parts = r.meshes->organs[0].part_count, *b_parts = r.meshes->organs[1].part_count;
  for (int32_t c = 0; st == FASCIA_OK && c < r.model->coupling_count; ++c)
    if (r.model->coupling_organ[c] == 1)
      memcpy(end, r.model->frame_position + 3 * r.model->coupling_frame[c], 3 * sizeof(double));
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
  double end[3] = {NAN, NAN, NAN};
  int a_parts = 0, b_parts = 0;
  fascia_status st = strand_end(dir, "b_lower", end, message, sizeof message, &a_parts, &b_parts);
  if (st != FASCIA_OK) fprintf(stderr, "b_lower: %s\n", message);
  CHECK(st == FASCIA_OK && a_parts == 1 && b_parts == 2);
  // on B's face toward A, at the start's height (the face lies within a voxel of x = 3 mm)
  fprintf(stderr, "b_lower: end at (%.3g, %.3g, %.3g) mm\n", 1e3 * end[0], 1e3 * end[1], 1e3 * end[2]);
  CHECK(fabs(end[0] - 0.003) < 0.001 && fabs(end[1] + 0.004) < 0.0005 && fabs(end[2]) < 0.0005);
  st = strand_end(dir, "b_upper", end, message, sizeof message, &a_parts, &b_parts);
  if (st != FASCIA_OK) fprintf(stderr, "b_upper: %s\n", message);
  CHECK(st == FASCIA_OK);
  fprintf(stderr, "b_upper: end at (%.3g, %.3g, %.3g) mm\n", 1e3 * end[0], 1e3 * end[1], 1e3 * end[2]);
  CHECK(fabs(end[0] - 0.003) < 0.001 && end[1] > -0.001 && end[1] < 0.001 && fabs(end[2]) < 0.0005);
  st = strand_end(dir, "b_middle", end, message, sizeof message, &a_parts, &b_parts);
  CHECK(st != FASCIA_OK && strstr(message, "tissues[0].to.part") && strstr(message, "b_middle"));
  static const char *const files[] = {"labels.tsv", "map.nii", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
