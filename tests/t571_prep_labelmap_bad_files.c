// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Bad label maps and label tables through `fascia prep`: each refused with
// one line naming the file and the problem, and no output written (the older
// model file is left as it was): not a NIfTI, a truncated gzip, a float
// image, a 4-D image, no affine (sform and qform codes 0), a label the image
// lacks (the message lists those it holds), a name the table lacks, a table
// that does not parse, a NRRD of overlapping layers, an unknown extension.
// Damaged files whose damage the NIfTI library reads past: a gzip with a
// flipped bit, cut by 1-8 bytes or followed by other bytes (two gzip members
// are one file, accepted); a .nii cut short, longer than its header says, or
// with vox_offset inside the header; header fields out of their defined set
// (dim[0] 0 or 8, bad magic, sform/qform code 99, pixdim NaN or not
// positive, bitpix against the datatype), each named for its own cause; a
// big-endian file is read. NRRD: gzip and bzip2 data checked whole (a
// flipped length, a cut stream, bytes after it), raw data longer than its
// header says, a detached data file that is a FIFO (refused, not a hang).
#define _POSIX_C_SOURCE 200809L // mkdtemp, mkfifo, WEXITSTATUS
#include <bzlib.h>
#include <math.h>
#include <sys/stat.h>
#include <zlib.h>

#include "labelmap_fixture.h"
#include "prep_cli_case.h"

static size_t slurp(const char *path, unsigned char *buf, size_t cap) {
  FILE *f = fopen(path, "rb");
  const size_t n = f ? fread(buf, 1, cap, f) : 0;
  if (f) fclose(f);
  return n;
}

static int spit(const char *dir, const char *name, const unsigned char *bytes, size_t n) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "wb");
  const int ok = f && fwrite(bytes, 1, n, f) == n;
  return f && fclose(f) == 0 && ok;
}

// bytes as gzip, in two members split at byte cut (0: one member)
static int spit_gz(const char *dir, const char *name, const unsigned char *bytes, size_t n, size_t cut) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  gzFile g = gzopen(path, "wb");
  int ok = g && gzwrite(g, bytes, (unsigned)(cut ? cut : n)) == (int)(cut ? cut : n) && gzclose(g) == Z_OK;
  if (ok && cut) {
    g = gzopen(path, "ab");
    ok = g && gzwrite(g, bytes + cut, (unsigned)(n - cut)) == (int)(n - cut) && gzclose(g) == Z_OK;
  }
  return ok;
}

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
  { // damage the NIfTI library reads past, and header fields out of their set
    static unsigned char nii[8192], gz[8192], b[8192];
    snprintf(path, sizeof path, "%s/raw.nii", dir);
    CHECK(labelmap_write_nifti(path, &grid, one_box, NULL, 1, 0, 0, 1));
    const size_t n = slurp(path, nii, sizeof nii);
    CHECK(n == 352 + 512);
    snprintf(path, sizeof path, "%s/good.nii.gz", dir);
    const size_t m = slurp(path, gz, sizeof gz);
    CHECK(m > 20);
    memcpy(b, gz, m);
    b[m - 6] ^= 0x10; // the CRC32
    CHECK(spit(dir, "x.nii.gz", b, m));
    refused(cli, dir, "gzip CRC flipped", "x.nii.gz", "1", "labels.tsv", "x.nii.gz", "damaged gzip data");
    memcpy(b, gz, m);
    b[m - 3] ^= 0x01; // the length
    CHECK(spit(dir, "x.nii.gz", b, m));
    refused(cli, dir, "gzip length flipped", "x.nii.gz", "1", "labels.tsv", "x.nii.gz", "damaged gzip data");
    for (size_t cut = 1; cut <= 8; ++cut) {
      CHECK(spit(dir, "x.nii.gz", gz, m - cut));
      refused(cli, dir, "gzip cut by a few bytes", "x.nii.gz", "1", "labels.tsv", "x.nii.gz", "damaged gzip data");
    }
    memcpy(b, gz, m);
    memcpy(b + m, "garbage", 7);
    CHECK(spit(dir, "x.nii.gz", b, m + 7));
    refused(cli, dir, "bytes after the gzip", "x.nii.gz", "1", "labels.tsv", "x.nii.gz", "not another gzip member");
    CHECK(spit(dir, "x.nii.gz", nii, n));
    refused(cli, dir, ".nii.gz not compressed", "x.nii.gz", "1", "labels.tsv", "x.nii.gz", "not gzip-compressed");
    CHECK(spit_gz(dir, "two.nii.gz", nii, n, 100));
    scene(dir, "two.nii.gz", "\"box_a\"", "labels.tsv", good);
    prep_case_accepted(cli, dir, "two gzip members", good);
    CHECK(spit_gz(dir, "x.nii.gz", nii, n - 1, 0));
    refused(cli, dir, "gzip of a cut .nii", "x.nii.gz", "1", "labels.tsv", "x.nii.gz", "cut short");
    CHECK(spit(dir, "x.nii", nii, n - 1));
    refused(cli, dir, ".nii cut by a byte", "x.nii", "1", "labels.tsv", "x.nii", "cut short");
    memcpy(b, nii, n);
    b[n] = 0;
    CHECK(spit(dir, "x.nii", b, n + 1));
    refused(cli, dir, ".nii a byte longer", "x.nii", "1", "labels.tsv", "x.nii", "longer than its header says");
    struct {
      const char *name, *expect;
      int field; // which header field is set to value
      double value;
    } const edits[] = {{"vox_offset 0", "vox_offset 0 lies inside the header", 0, 0},
                       {"vox_offset 348", "vox_offset 348", 0, 348},
                       {"dim[0] 0", "dim[0]", 1, 0},
                       {"dim[0] 8", "dim[0]", 1, 8},
                       {"dim[2] 0", "dim[2]", 2, 0},
                       {"bad magic", "bad magic", 3, 0},
                       {"sform_code 99", "sform_code 99", 4, 99},
                       {"qform_code 99", "qform_code 99", 5, 99},
                       {"qform_code -1", "qform_code -1", 5, -1},
                       {"pixdim NaN", "pixdim[1]", 6, NAN},
                       {"pixdim 0", "pixdim[2]", 7, 0},
                       {"pixdim -2", "pixdim[3]", 8, -2},
                       {"bitpix 16 for uint8", "bitpix 16", 9, 16},
                       {"two-file header", "two-file NIfTI", 10, 0}};
    for (size_t e = 0; e < sizeof edits / sizeof edits[0]; ++e) {
      nifti_1_header h;
      memcpy(&h, nii, sizeof h);
      const double v = edits[e].value;
      switch (edits[e].field) {
      case 0: h.vox_offset = (float)v; break;
      case 1: h.dim[0] = (short)v; break;
      case 2: h.dim[2] = (short)v; break;
      case 3: memcpy(h.magic, "n+2", 4); break;
      case 4: h.sform_code = (short)v; break;
      case 5: h.qform_code = (short)v; break;
      case 6: h.pixdim[1] = (float)v; break;
      case 7: h.pixdim[2] = (float)v; break;
      case 8: h.pixdim[3] = (float)v; break;
      case 9: h.bitpix = (short)v; break;
      default: memcpy(h.magic, "ni1", 4); break;
      }
      memcpy(b, &h, sizeof h);
      memcpy(b + sizeof h, nii + sizeof h, n - sizeof h);
      CHECK(spit(dir, "x.nii", b, n));
      refused(cli, dir, edits[e].name, "x.nii", "1", "labels.tsv", "x.nii", edits[e].expect);
      CHECK(spit_gz(dir, "x.nii.gz", b, n, 0));
      refused(cli, dir, edits[e].name, "x.nii.gz", "1", "labels.tsv", "x.nii.gz", edits[e].expect);
    }
    { // in micrometres: the organ is far too small, and its size is the map's, not "units"
      nifti_1_header h;
      memcpy(&h, nii, sizeof h);
      h.xyzt_units = NIFTI_UNITS_MICRON;
      memcpy(b, &h, sizeof h);
      memcpy(b + sizeof h, nii + sizeof h, n - sizeof h);
      CHECK(spit(dir, "x.nii", b, n));
      scene(dir, "x.nii", "1", "labels.tsv", good);
      char command[2048], message[4096] = "";
      snprintf(command, sizeof command, "FASCIA_PROGRESS=0 timeout 60 '%s' prep '%s' -o '%s/model.h5' > /dev/null 2> "
               "'%s/stderr.txt'", cli, good, dir, dir);
      const int status = system(command);
      snprintf(path, sizeof path, "%s/stderr.txt", dir);
      message[slurp(path, (unsigned char *)message, sizeof message - 1)] = 0;
      if (status == 0 || !strstr(message, "segmentation.file 'x.nii'") ||
          !strstr(message, "takes its size from the label map") || strstr(message, "\"units\"")) {
        fprintf(stderr, "case 'label organ in micrometres': status %d, message:\n%s\n", status, message);
        ++check_failures_;
      }
    }
    { // the same file big-endian: read as it is
      nifti_1_header h;
      memcpy(&h, nii, sizeof h);
      swap_nifti_header(&h, 1);
      memcpy(b, &h, sizeof h);
      memcpy(b + sizeof h, nii + sizeof h, n - sizeof h);
      CHECK(spit(dir, "swapped.nii", b, n));
      scene(dir, "swapped.nii", "\"box_a\"", "labels.tsv", good);
      prep_case_accepted(cli, dir, "big-endian", good);
    }
  }
  { // NRRD data: each encoding's stream checked whole
    static unsigned char raw[8192], packed[8192], file[16384];
    snprintf(path, sizeof path, "%s/raw.nrrd", dir);
    CHECK(labelmap_write_nrrd(path, &grid, one_box, NULL, 0, 1));
    const size_t n = slurp(path, raw, sizeof raw);
    const unsigned char *blank = NULL;
    for (size_t k = 0; k + 1 < n && !blank; ++k)
      if (raw[k] == '\n' && raw[k + 1] == '\n') blank = raw + k + 2;
    CHECK(blank && n - (size_t)(blank - raw) == 512);
    const size_t head = blank ? (size_t)(blank - raw) : 0;
    char text[4096];
    memcpy(text, raw, head);
    text[head] = 0;
    char *enc = strstr(text, "encoding: raw\n");
    CHECK(enc);
    for (int e = 0; e < 2 && enc; ++e) { // gzip, bzip2
      char header[4096];
      snprintf(header, sizeof header, "%.*sencoding: %s\n%s", (int)(enc - text), text, e ? "bzip2" : "gzip",
               enc + strlen("encoding: raw\n"));
      size_t m = 0;
      if (e) {
        unsigned int out = sizeof packed;
        CHECK(BZ2_bzBuffToBuffCompress((char *)packed, &out, (char *)(raw + head), 512, 9, 0, 0) == BZ_OK);
        m = out;
      } else {
        CHECK(spit_gz(dir, "x.gz", raw + head, 512, 0));
        snprintf(path, sizeof path, "%s/x.gz", dir);
        m = slurp(path, packed, sizeof packed);
      }
      const size_t h = strlen(header);
      memcpy(file, header, h);
      memcpy(file + h, packed, m);
      CHECK(spit(dir, "x.nrrd", file, h + m));
      scene(dir, "x.nrrd", "\"box_a\"", "labels.tsv", good);
      prep_case_accepted(cli, dir, e ? "bzip2 NRRD" : "gzip NRRD", good);
      for (size_t cut = 1; cut <= 4; ++cut) {
        CHECK(spit(dir, "x.nrrd", file, h + m - cut));
        refused(cli, dir, "compressed NRRD cut", "x.nrrd", "1", "labels.tsv", "x.nrrd", "label map");
      }
      memcpy(file + h + m, "garbage", 7);
      CHECK(spit(dir, "x.nrrd", file, h + m + 7));
      refused(cli, dir, "bytes after the NRRD's stream", "x.nrrd", "1", "labels.tsv", "x.nrrd", "after the end");
      if (!e) {
        file[h + m - 3] ^= 1; // the length
        CHECK(spit(dir, "x.nrrd", file, h + m));
        refused(cli, dir, "gzip NRRD length flipped", "x.nrrd", "1", "labels.tsv", "x.nrrd", "damaged gzip data");
      }
    }
    memcpy(file, raw, n);
    memcpy(file + n, "xx", 2);
    CHECK(spit(dir, "x.nrrd", file, n + 2));
    refused(cli, dir, "raw NRRD longer", "x.nrrd", "1", "labels.tsv", "x.nrrd", "longer than its header says");
    char header[4096];
    text[head - 1] = 0; // no blank line: a detached header
    snprintf(header, sizeof header, "%.3000sdata file: fifo.raw\n", text);
    CHECK(fixture_write(dir, "fifo.nhdr", header));
    snprintf(path, sizeof path, "%s/fifo.raw", dir);
    remove(path);
    CHECK(mkfifo(path, 0600) == 0);
    refused(cli, dir, "NRRD data file a FIFO", "fifo.nhdr", "1", "labels.tsv", "fifo.raw", "FIFO");
  }
  CHECK(fixture_write(dir, "image.png", "\x89PNG"));
  refused(cli, dir, "unknown extension", "image.png", "1", "labels.tsv", "image.png", "unknown format");
  const char *const names[] = {"b.obj", "labels.tsv", "bad.tsv", "good.nii.gz", "text.nii", "cut.nii.gz",
                               "float.nii", "four.nii", "placeless.nii", "layers.seg.nrrd", "image.png", "raw.nii",
                               "x.nii.gz", "x.nii", "two.nii.gz", "swapped.nii", "raw.nrrd", "x.gz", "x.nrrd",
                               "fifo.nhdr", "fifo.raw",
                               "scene.json", "model.h5", "stderr.txt", NULL};
  fixture_cleanup(dir, names);
  return CHECK_RESULT();
}
