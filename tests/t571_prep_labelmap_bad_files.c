// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Bad label maps and label tables through `fascia prep`: each refused with
// one line naming the file and the problem, and no output written (the older
// model file is left as it was): not a NIfTI, a truncated gzip, a float
// image, a 4-D image, no affine (sform and qform codes 0), a label the image
// lacks (the message lists those it holds), a name the table lacks, a table
// that does not parse, a NRRD of overlapping layers, an unknown extension.
#define _POSIX_C_SOURCE 200809L // mkdtemp, WEXITSTATUS
#include "labelmap_fixture.h"
#include "prep_cli_case.h"

static uint8_t one_box(const double *x, const void *data) {
  (void)data;
  return (x[0] > -5 && x[0] < 5 && x[1] > -5 && x[1] < 5 && x[2] > -5 && x[2] < 5) ? 1 : 0;
}

static const labelmap_def grid = {{8, 8, 8}, {2, 0, 0, -7, 0, 2, 0, -7, 0, 0, 2, -7}};

static void scene(const char *dir, const char *file, const char *labels, const char *table, char *path) {
  char text[2048];
  snprintf(text, sizeof text,
           "{\"fascia_scene\": 1, \"voxel_size\": 0.001,\n"
           " \"segmentation\": {\"file\": \"%s\", \"labels\": \"%s\"},\n"
           " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
           " \"organs\": [{\"name\": \"A\", \"labels\": %s}, {\"name\": \"B\", \"mesh\": \"b.obj\"}],\n"
           " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008,\n"
           "  \"material\": \"soft\", \"frame_spacing\": 0.006, \"sample_spacing\": 0.004}]}\n",
           file, table, labels);
  fixture_write(dir, "scene.json", text);
  snprintf(path, 512, "%s/scene.json", dir);
}

static void refused(const char *cli, const char *dir, const char *name, const char *file, const char *labels,
                    const char *table, const char *a, const char *b) {
  char path[512];
  scene(dir, file, labels, table, path);
  const char *const expect[] = {a, b, NULL};
  prep_case_refused(cli, dir, name, path, expect);
}

int main(int argc, char **argv) {
  if (argc < 2) return TEST_SKIP;
  const char *cli = argv[1];
  char dir[256], path[512];
  CHECK(fixture_tmpdir(dir));
  const double lo[3] = {0.008, -0.005, -0.005}, hi[3] = {0.02, 0.005, 0.005};
  CHECK(fixture_box(dir, "b.obj", lo, hi));
  CHECK(fixture_write(dir, "labels.tsv", "label\tname\n1\tbox_a\n"));
  CHECK(fixture_write(dir, "bad.tsv", "label\tname\n1 box_a\n"));
  snprintf(path, sizeof path, "%s/good.nii.gz", dir);
  CHECK(labelmap_write_nifti(path, &grid, one_box, NULL, 1, 0, 0, 1));
  // the good file is accepted: the cases below fail for their one fault
  char good[512];
  scene(dir, "good.nii.gz", "\"box_a\"", "labels.tsv", good);
  prep_case_accepted(cli, dir, "good", good);

  CHECK(fixture_write(dir, "text.nii", "this is not an image\n"));
  refused(cli, dir, "not a NIfTI", "text.nii", "1", "labels.tsv", "text.nii", "not a NIfTI");
  { // the gzip cut in half
    FILE *f = fopen(path, "rb");
    char bytes[65536];
    const size_t n = f ? fread(bytes, 1, sizeof bytes, f) : 0;
    if (f) fclose(f);
    char cut[512];
    snprintf(cut, sizeof cut, "%s/cut.nii.gz", dir);
    f = fopen(cut, "wb");
    CHECK(f && fwrite(bytes, 1, n / 2, f) == n / 2);
    if (f) fclose(f);
  }
  refused(cli, dir, "truncated gzip", "cut.nii.gz", "1", "labels.tsv", "cut.nii.gz", "label map");
  snprintf(path, sizeof path, "%s/float.nii", dir);
  CHECK(labelmap_write_nifti(path, &grid, one_box, NULL, 1, 0, 1, 1));
  refused(cli, dir, "float image", "float.nii", "1", "labels.tsv", "float.nii", "not integers");
  snprintf(path, sizeof path, "%s/four.nii", dir);
  CHECK(labelmap_write_nifti(path, &grid, one_box, NULL, 1, 0, 0, 3));
  refused(cli, dir, "4-D image", "four.nii", "1", "labels.tsv", "four.nii", "4-D");
  snprintf(path, sizeof path, "%s/placeless.nii", dir);
  CHECK(labelmap_write_nifti(path, &grid, one_box, NULL, 1, 1, 0, 1));
  refused(cli, dir, "no affine", "placeless.nii", "1", "labels.tsv", "placeless.nii", "no affine");
  refused(cli, dir, "label the image lacks", "good.nii.gz", "7", "labels.tsv", "no voxel labelled 7",
          "holds: 1 (box_a)");
  refused(cli, dir, "name the table lacks", "good.nii.gz", "\"liver\"", "labels.tsv", "labels.tsv", "'liver'");
  refused(cli, dir, "table that does not parse", "good.nii.gz", "1", "bad.tsv", "bad.tsv", "line 2");
  snprintf(path, sizeof path, "%s/layers.seg.nrrd", dir);
  CHECK(labelmap_write_nrrd(path, &grid, one_box, NULL, 1, 2));
  refused(cli, dir, "overlapping layers", "layers.seg.nrrd", "1", "labels.tsv", "layers.seg.nrrd",
          "overlapping layers");
  CHECK(fixture_write(dir, "image.png", "\x89PNG"));
  refused(cli, dir, "unknown extension", "image.png", "1", "labels.tsv", "image.png", "unknown format");
  const char *const names[] = {"b.obj", "labels.tsv", "bad.tsv", "good.nii.gz", "text.nii", "cut.nii.gz",
                               "float.nii", "four.nii", "placeless.nii", "layers.seg.nrrd", "image.png",
                               "scene.json", "model.h5", "stderr.txt", NULL};
  fixture_cleanup(dir, names);
  return CHECK_RESULT();
}
