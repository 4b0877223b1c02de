// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Organs from label maps the test writes (docs/labelmaps.md): two boxes of
// labels 12 mm wide across a gap of 3, 1 and 0 voxels of 2 mm, prepared at
// 1 mm voxels. The organs' faces land where the voxels end (within 0.05 mm),
// their volumes match the boxes, the tissue cut to the slab between the
// faces matches the slab's volume, the shared frames sit on the facing
// faces; the same boxes through NIfTI-1, NIfTI-2, NRRD in LPS and an affine
// that rotates and mirrors give the same model, and a mesh of box A placed
// in the world with a label box B gives the same tissue. Touching labels are
// reported, and the interface layer carves a slab of its thickness between them.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <math.h>

#include "check.h"
#include "labelmap_fixture.h"
#include "prep_fixture.h"

typedef struct boxes {
  double half_gap; // mm
} boxes;

// A: x in [-g - 12, -g], B: x in [g, g + 12], both |y|, |z| <= 6 (mm, RAS); 3 is fat (unused by the organs)
static uint8_t box_label(const double *x, const void *data) {
  const double g = ((const boxes *)data)->half_gap;
  if (fabs(x[1]) > 6 || fabs(x[2]) > 6) return x[2] > 9 ? 3 : 0;
  if (x[0] >= -g - 12 && x[0] <= -g) return 1;
  if (x[0] >= g && x[0] <= g + 12) return 2;
  return 0;
}

// Voxel centres 1 mm off every face: odd mm on y and z, and on x odd or even by the gap.
static labelmap_def straight(int gap_voxels) {
  labelmap_def d = {{24, 12, 12}, {2, 0, 0, gap_voxels % 2 ? -24 : -23, 0, 2, 0, -11, 0, 0, 2, -11}};
  return d;
}
// The same lattice of centres, with index axes i -> -y, j -> -x (a mirror and a quarter turn).
static labelmap_def turned(int gap_voxels) {
  labelmap_def d = {{12, 24, 12}, {0, -2, 0, gap_voxels % 2 ? 24 : 23, -2, 0, 0, 11, 0, 0, 2, -11}};
  return d;
}

static const char table[] = "label\tname\n1\tbox_a\n2\tbox_b\n3\tfat\n";

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 3,\n"
    " \"segmentation\": {\"file\": \"%s\", \"labels\": \"labels.tsv\", \"frame\": \"%s\", \"smoothing\": 0,\n"
    "   \"interface_layer\": %g},\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [%s,\n"
    "  {\"name\": \"B\", \"labels\": [\"box_b\"], \"model\": \"prescribed\", \"motion\": {\"pivot\": [0, 0, 0],\n"
    "   \"keys\": [{\"time\": 0}, {\"time\": 1, \"translation\": [0.001, 0, 0]}]}}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": %g,\n"
    "  \"region\": {\"box\": {\"min\": [-0.008, -0.005, -0.005], \"max\": [0.008, 0.005, 0.005]}},\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.003, \"sample_spacing\": 0.0015}]}\n";

typedef struct outcome {
  double tissue, volume_a, volume_b, a_max_x, b_min_x, a_y[2];
  int contacts;
  int64_t faces;
  double contact_area;
} outcome;

// Prepares the scene on file (in frame) with organ A as given; fills *out.
static int prepare(const char *dir, const char *file, const char *frame, const char *organ_a, double half_gap,
                   double layer, outcome *out) {
  char text[4096];
  const double max_gap = 2e-3 * half_gap + (layer > 0 ? layer : 0) + 0.002;
  snprintf(text, sizeof text, scene_format, file, frame, layer, organ_a, max_gap);
  CHECK(fixture_write(dir, "labels.tsv", table));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep_text(ctx, dir, text, &r);
  CHECK_OK(st, ctx);
  memset(out, 0, sizeof *out);
  if (st == FASCIA_OK) {
    out->tissue = r.volume->tissues[0].volume;
    out->volume_a = r.meshes->organs[0].report.enclosed_volume;
    out->volume_b = r.meshes->organs[1].report.enclosed_volume;
    out->a_max_x = r.meshes->organs[0].bounds[3];
    out->b_min_x = r.meshes->organs[1].bounds[0];
    out->a_y[0] = r.meshes->organs[0].bounds[1], out->a_y[1] = r.meshes->organs[0].bounds[4];
    out->contacts = r.meshes->contact_count;
    if (r.meshes->contact_count) out->faces = r.meshes->contacts[0].faces, out->contact_area = r.meshes->contacts[0].area;
    // shared frames on the facing faces: A's at its face, B's at its face
    int wrong = 0;
    double facing[2]; // the bound of each box nearer the other
    for (int o = 0; o < 2; ++o) {
      const double *b = r.meshes->organs[o].bounds;
      facing[o] = fabs(b[0]) < fabs(b[3]) ? b[0] : b[3];
    }
    for (int32_t c = 0; c < r.coupling->count; ++c) {
      const double x = r.points->frame_position[3 * r.coupling->frame[c]];
      const double face = facing[r.coupling->organ[c]];
      if (fabs(x - face) > 0.0011 && wrong++ < 3)
        fprintf(stderr, "%s: frame on organ %d at x %g, its face at %g\n", file, (int)r.coupling->organ[c], x, face);
    }
    CHECK(r.coupling->per_organ[0] > 0 && r.coupling->per_organ[1] > 0);
    CHECK(wrong == 0);
  }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return st == FASCIA_OK;
}

static const char organ_a_labels[] = "{\"name\": \"A\", \"labels\": \"box_a\", \"model\": \"fixed\"}";

static void gap_case(const char *dir, int gap_voxels) {
  const boxes geometry = {gap_voxels}; // half the gap in mm = gap voxels x 2 mm / 2
  const double g = geometry.half_gap;
  char path[512];
  outcome base, other;
  const labelmap_def d = straight(gap_voxels);
  snprintf(path, sizeof path, "%s/boxes.nii.gz", dir);
  CHECK(labelmap_write_nifti(path, &d, box_label, &geometry, 1, 0, 0, 1));
  if (!prepare(dir, "boxes.nii.gz", "RAS", organ_a_labels, g, 0, &base)) return;
  // faces where the voxels end; volumes of the 12 mm boxes less their chamfered edges
  CHECK_NEAR(base.a_max_x, -1e-3 * g, 0, 5e-5);
  CHECK_NEAR(base.b_min_x, 1e-3 * g, 0, 5e-5);
  CHECK_NEAR(base.a_y[0], -0.006, 0, 5e-5);
  CHECK_NEAR(base.a_y[1], 0.006, 0, 5e-5);
  CHECK_NEAR(base.volume_a, 1.728e-6, 0.08, 0);
  CHECK_NEAR(base.volume_b, 1.728e-6, 0.08, 0);
  // the slab |x| < g, |y|, |z| < 5 mm; each of its faces moves by at most h/2
  const double h = 1e-3, exact = 2e-3 * g * 1e-4, area = 2e-4 + 4 * 2e-3 * g * 1e-2;
  CHECK_NEAR(base.tissue, exact, 0, 0.5 * h * area);
  CHECK(base.contacts == 0);
  // the same geometry through the other writers and an affine that turns and mirrors
  snprintf(path, sizeof path, "%s/boxes2.nii", dir);
  CHECK(labelmap_write_nifti(path, &d, box_label, &geometry, 2, 0, 0, 1));
  if (prepare(dir, "boxes2.nii", "RAS", organ_a_labels, g, 0, &other)) CHECK_NEAR(other.tissue, base.tissue, 1e-6, 0);
  snprintf(path, sizeof path, "%s/boxes.nrrd", dir);
  CHECK(labelmap_write_nrrd(path, &d, box_label, &geometry, 1, 1));
  if (prepare(dir, "boxes.nrrd", "RAS", organ_a_labels, g, 0, &other)) {
    CHECK_NEAR(other.tissue, base.tissue, 1e-6, 0);
    CHECK_NEAR(other.a_max_x, base.a_max_x, 0, 1e-9);
  }
  const labelmap_def t = turned(gap_voxels);
  snprintf(path, sizeof path, "%s/turned.nii.gz", dir);
  CHECK(labelmap_write_nifti(path, &t, box_label, &geometry, 1, 0, 0, 1));
  if (prepare(dir, "turned.nii.gz", "RAS", organ_a_labels, g, 0, &other)) {
    CHECK_NEAR(other.tissue, base.tissue, 1e-6, 0);
    CHECK_NEAR(other.a_max_x, base.a_max_x, 0, 1e-9);
    CHECK_NEAR(other.a_y[0], base.a_y[0], 0, 1e-9);
  }
  // LPS: x and y change sign, so A now lies at positive x
  if (prepare(dir, "boxes.nii.gz", "LPS", organ_a_labels, g, 0, &other)) {
    CHECK_NEAR(other.tissue, base.tissue, 1e-6, 0);
    CHECK_NEAR(other.b_min_x, -0.012 - 1e-3 * g, 0, 5e-5); // B's far face, mirrored
  }
  // a mesh of box A in the same world, with label box B: the same tissue
  const double lo[3] = {-0.012 - 1e-3 * g, -0.006, -0.006}, hi[3] = {-1e-3 * g, 0.006, 0.006};
  CHECK(fixture_box(dir, "a.obj", lo, hi));
  if (prepare(dir, "boxes.nii.gz", "RAS", "{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"}", g, 0, &other))
    CHECK_NEAR(other.tissue, base.tissue, 0, 0.5 * h * area);
}

int main(void) {
  char dir[256];
  CHECK(fixture_tmpdir(dir));
  gap_case(dir, 3);
  gap_case(dir, 1);
  // touching labels: reported, and the interface layer carves a 2 mm slab between them
  const boxes touching = {0};
  const labelmap_def d = straight(0);
  char path[512];
  snprintf(path, sizeof path, "%s/touch.nii.gz", dir);
  CHECK(labelmap_write_nifti(path, &d, box_label, &touching, 1, 0, 0, 1));
  outcome o;
  if (prepare(dir, "touch.nii.gz", "RAS", organ_a_labels, 0, 0.002, &o)) {
    CHECK(o.contacts == 1);
    CHECK(o.faces == 36);                       // 6 x 6 voxel faces
    CHECK_NEAR(o.contact_area, 144e-6, 1e-9, 0); // of 2 x 2 mm
    // (the faces' rims recede where the boxes' edges are chamfered: only the middle is checked)
    const double h = 1e-3, exact = 2e-3 * 1e-4, area = 2e-4 + 4 * 2e-3 * 1e-2;
    CHECK_NEAR(o.tissue, exact, 0, 0.5 * h * area);
  }
  const char *const names[] = {"boxes.nii.gz", "boxes2.nii", "boxes.nrrd", "turned.nii.gz", "touch.nii.gz", "a.obj",
                               "labels.tsv",   "scene.json", NULL};
  fixture_cleanup(dir, names);
  return CHECK_RESULT();
}
