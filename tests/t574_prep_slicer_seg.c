// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A 3D Slicer segmentation (.seg.nrrd, written here as Slicer 4.11+ writes
// one: a 3-D label volume in LPS with Segment<k>_Name, _LabelValue, _Layer
// in its header) names its organs without a label table: organs by Slicer's
// segment names ("box a", "box b") or by value give the same tissue, and the
// unmodelled segment between them is reported by its name ("colon (9)").
// Refused in one line naming the file and the key: segments in two layers
// (also in a 4-D file of two layers), a segment without a label value, two
// segments of one value, a name no segment has.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "labelmap_fixture.h"
#include "prep_fixture.h"

// A (5): x in [-15, -3], B (7): x in [3, 15], |y|, |z| <= 6 (mm, RAS); the colon (9) between them where y >= 0.
static uint8_t label_of(const double *x, const void *data) {
  (void)data;
  if (fabs(x[1]) > 6 || fabs(x[2]) > 6) return 0;
  if (x[0] >= -15 && x[0] <= -3) return 5;
  if (x[0] >= 3 && x[0] <= 15) return 7;
  return x[1] >= 0 ? 9 : 0;
}

// 2 mm voxels centred on even x and odd y, z (RAS mm).
static const labelmap_def grid = {{24, 12, 12}, {2, 0, 0, -24, 0, 2, 0, -11, 0, 0, 2, -11}};

// The segments as Slicer's header lists them (one key a line), before the blank line.
static const char segments[] = "Segment0_Color:=0.9 0.5 0.5\n"
                               "Segment0_ID:=Segment_1\n"
                               "Segment0_LabelValue:=5\n"
                               "Segment0_Layer:=0\n"
                               "Segment0_Name:=box a\n"
                               "Segment1_ID:=Segment_2\n"
                               "Segment1_LabelValue:=7\n"
                               "Segment1_Layer:=0\n"
                               "Segment1_Name:=box b\n"
                               "Segment2_ID:=Segment_3\n"
                               "Segment2_LabelValue:=9\n"
                               "Segment2_Layer:=0\n"
                               "Segment2_Name:=colon\n"
                               "Segmentation_MasterRepresentation:=Binary labelmap\n";

// dir/name: the label volume in LPS (Slicer's space) with header lines keys;
// layers 2 writes a 4-D file of two layers, the second empty.
static int write_seg(const char *dir, const char *name, const char *keys, int layers) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  uint8_t *labels = labelmap_fill(&grid, label_of, NULL);
  FILE *f = labels ? fopen(path, "wb") : NULL;
  if (!f) {
    free(labels);
    return 0;
  }
  const double *a = grid.affine; // RAS -> LPS: x and y change sign
  fprintf(f, "NRRD0004\ntype: unsigned char\ndimension: %d\nspace: left-posterior-superior\n", layers > 1 ? 4 : 3);
  if (layers > 1) fprintf(f, "sizes: %d %d %d %d\nspace directions: none", layers, grid.dims[0], grid.dims[1], grid.dims[2]);
  else fprintf(f, "sizes: %d %d %d\nspace directions:", grid.dims[0], grid.dims[1], grid.dims[2]);
  for (int c = 0; c < 3; ++c) fprintf(f, " (%.17g,%.17g,%.17g)", -a[c], -a[4 + c], a[8 + c]);
  fprintf(f, "\nkinds: %sdomain domain domain\nendian: little\nencoding: raw\nspace origin: (%.17g,%.17g,%.17g)\n%s\n",
          layers > 1 ? "list " : "", -a[3], -a[7], a[11], keys);
  const size_t n = (size_t)grid.dims[0] * grid.dims[1] * grid.dims[2];
  int ok = 1;
  for (size_t k = 0; k < n; ++k)
    for (int l = 0; l < layers; ++l) ok = ok && fputc(l == 0 ? labels[k] : 0, f) != EOF;
  free(labels);
  return fclose(f) == 0 && ok;
}

// 0.7 mm voxels: no voxel centre of the scene lies on a face of the image's voxels
static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.0007, \"seed\": 3,\n"
    " \"segmentation\": {\"file\": \"%s\", \"frame\": \"LPS\", \"smoothing\": 0},\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"labels\": %s, \"model\": \"fixed\"},\n"
    "  {\"name\": \"B\", \"labels\": %s, \"model\": \"fixed\"}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008,\n"
    "  \"region\": {\"box\": {\"min\": [-0.008, -0.005, -0.005], \"max\": [0.008, 0.005, 0.005]}},\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.003, \"sample_spacing\": 0.0015}]}\n";

typedef struct outcome {
  fascia_status status;
  double tissue;
  char occupied[256], message[1024];
} outcome;

static outcome prepare(const char *dir, const char *file, const char *labels_a, const char *labels_b) {
  outcome out;
  memset(&out, 0, sizeof out);
  char text[4096], path[512];
  snprintf(text, sizeof text, scene_format, file, labels_a, labels_b);
  CHECK(fixture_write(dir, "scene.json", text));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  out.status = fixture_prep(ctx, path, &r);
  snprintf(out.message, sizeof out.message, "%s", fascia_ctx_message(ctx));
  if (out.status == FASCIA_OK) {
    out.tissue = r.volume->tissues->volume;
    fascia_prep_occupied_text(r.scene, r.volume->tissues, out.occupied, sizeof out.occupied);
  }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return out;
}

// Refused: FORMAT or UNSUPPORTED, one line holding a and b.
static void refused(const char *dir, const char *name, const char *keys, int layers, const char *labels_a,
                    const char *a, const char *b) {
  CHECK(write_seg(dir, "bad.seg.nrrd", keys, layers));
  const outcome o = prepare(dir, "bad.seg.nrrd", labels_a, "\"box b\"");
  const int ok = o.status != FASCIA_OK && !strchr(o.message, '\n') && strstr(o.message, a) && strstr(o.message, b);
  if (!ok) fprintf(stderr, "case '%s': status %d, message: %s\n", name, (int)o.status, o.message);
  CHECK(ok);
}

int main(void) {
  char dir[256];
  CHECK(fixture_tmpdir(dir));
  CHECK(write_seg(dir, "pelvis.seg.nrrd", segments, 1));

  // by Slicer's names, and by value: one tissue, the colon named
  const outcome named = prepare(dir, "pelvis.seg.nrrd", "\"box a\"", "\"box b\"");
  CHECK(named.status == FASCIA_OK);
  if (named.status != FASCIA_OK) fprintf(stderr, "by name: %s\n", named.message);
  const outcome valued = prepare(dir, "pelvis.seg.nrrd", "5", "[7]");
  CHECK(valued.status == FASCIA_OK);
  CHECK(named.tissue > 0 && named.tissue == valued.tissue); // the same labels: the same model, bit for bit
  CHECK(strstr(named.occupied, "colon (9)") != NULL);
  if (!strstr(named.occupied, "colon (9)")) fprintf(stderr, "occupied by: '%s'\n", named.occupied);
  const outcome pattern = prepare(dir, "pelvis.seg.nrrd", "\"box a\"", "[\"box ?\"]"); // box a is A's already
  CHECK(pattern.status != FASCIA_OK && strstr(pattern.message, "label 5 is already organ 'A'"));

  // refused, naming the file and the key
  char keys[2048];
  snprintf(keys, sizeof keys, "%s", segments);
  *strstr(keys, "Segment2_Layer:=0") = 0; // the colon in layer 1
  strcat(keys, "Segment2_Layer:=1\nSegment2_Name:=colon\n");
  refused(dir, "two layers", keys, 1, "\"box a\"", "bad.seg.nrrd", "Segment2_Layer");
  refused(dir, "a 4-D file of two layers", keys, 2, "\"box a\"", "bad.seg.nrrd", "layer 1");
  snprintf(keys, sizeof keys, "%s", segments);
  memcpy(strstr(keys, "Segment0_LabelValue"), "Segment0_LabelVaMue", 19);
  refused(dir, "no label value", keys, 1, "\"box a\"", "bad.seg.nrrd", "Segment0_LabelValue: absent");
  snprintf(keys, sizeof keys, "%s", segments);
  memcpy(strstr(keys, "Segment1_LabelValue:=7"), "Segment1_LabelValue:=5", 22);
  refused(dir, "two segments of one value", keys, 1, "\"box a\"", "bad.seg.nrrd", "Segment1_LabelValue: 5");
  refused(dir, "a name no segment has", segments, 1, "\"liver\"", "bad.seg.nrrd", "'liver'");

  const char *const names[] = {"pelvis.seg.nrrd", "bad.seg.nrrd", "scene.json", NULL};
  fixture_cleanup(dir, names);
  return CHECK_RESULT();
}
