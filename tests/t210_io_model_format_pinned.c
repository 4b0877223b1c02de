// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The model's fingerprint, its file's checksum and the datasets a file holds
// stay what they were: fingerprints are stored in checkpoints and results,
// checksums in model files, and the datasets are the file format
// (docs/model-format.md). The values are pinned for the hand-built fixture,
// full, minimal and full with enhanced strain modes (file versions 2, 1 and
// 4): reordering, renaming or reshaping a row of the model's table
// (sim/contract/model_table.h) fails here. --print shows what this build gives.
#define _POSIX_C_SOURCE 200809L
#include <hdf5.h>
#include <inttypes.h>

#include "check.h"
#include "io_fixture.h"

typedef struct pinned {
  uint64_t fingerprint, checksum;
  int32_t version;
  const char *datasets; ///< every dataset, in file order (list_join): "path rank dims class size;"
} pinned;

// The datasets the three variants share: frames, samples, pairs, materials.
#define FRAMES                                                                                                     \
  "/frames/position 2 5 3 f8;/frames/rotation 2 5 4 f8;/frames/kind 1 5 0 i4;/frames/motion 1 5 0 i4;"           \
  "/frames/organ 1 5 0 i4;/frames/load 2 5 6 f8;/frames/offsets 1 6 0 i4;/frames/pairs 1 9 0 i4;"
#define SAMPLES                                                                                                    \
  "/samples/position 2 3 3 f8;/samples/volume 1 3 0 f8;/samples/material 1 3 0 i4;/samples/organ 1 3 0 i4;"
#define PAIRS_MATERIALS                                                                                            \
  "/pairs/frame 1 9 0 i4;/pairs/weight 1 9 0 f8;/pairs/gradient 2 9 3 f8;"                                        \
  "/materials/name 1 2 0 s64;/materials/law 1 2 0 i4;/materials/youngs_modulus 1 2 0 f8;"                          \
  "/materials/poisson_ratio 1 2 0 f8;/materials/density 1 2 0 f8;/materials/rotation_coupling 1 2 0 f8;"          \
  "/materials/rotation_smoothing 1 2 0 f8;/materials/part 1 2 0 i4;"
// The full fixture's motion, probe, organ, coupling, gravity and provenance.
#define FULL_REST                                                                                                  \
  "/motions/breathing/pivot 1 3 0 f8;/motions/breathing/time 1 2 0 f8;/motions/breathing/translation 2 2 3 f8;"   \
  "/motions/breathing/rotation 2 2 4 f8;"                                                                         \
  "/probes/name 1 1 0 s64;/probes/position 2 1 3 f8;/probes/offsets 1 2 0 i4;/probes/frame 1 2 0 i4;"             \
  "/probes/weight 1 2 0 f8;/organs/liver/vertices 2 4 3 f8;/organs/liver/triangles 2 2 3 i4;"                    \
  "/coupling/organ 1 2 0 i4;/coupling/frame 1 2 0 i4;/coupling/triangle 1 2 0 i4;/coupling/barycentric 2 2 3 f8;" \
  "/gravity 1 3 0 f8;/provenance 0 0 0 s48;"

static const pinned expected[3] = {
    {UINT64_C(0xb283c35f47093cab), UINT64_C(0x3b37bf686e3c937b), 2,
     FRAMES SAMPLES "/samples/patch 1 3 0 i4;/samples/offsets 1 4 0 i4;" PAIRS_MATERIALS FULL_REST},
    // empty datasets (no data written) last, in name order
    {UINT64_C(0xabafeb21f575a715), UINT64_C(0x0090b8e158285ce0), 1,
     FRAMES SAMPLES "/samples/offsets 1 4 0 i4;" PAIRS_MATERIALS
     "/probes/offsets 1 1 0 i4;/gravity 1 3 0 f8;/coupling/barycentric 2 0 3 f8;/coupling/frame 1 0 0 i4;"
     "/coupling/organ 1 0 0 i4;/coupling/triangle 1 0 0 i4;/probes/frame 1 0 0 i4;/probes/name 1 0 0 s64;"
     "/probes/position 2 0 3 f8;/probes/weight 1 0 0 f8;"},
    {UINT64_C(0x0abe800e665d684b), UINT64_C(0x162149bc3133c1f1), 4,
     FRAMES SAMPLES "/samples/patch 1 3 0 i4;/samples/modes 1 3 0 i4;/samples/offsets 1 4 0 i4;" PAIRS_MATERIALS
         FULL_REST},
};

// A file's datasets in the order their data was written (their offsets in
// the file), then those without data (empty) in name order.
typedef struct entry {
  haddr_t offset;
  int index;
  char text[96];
} entry;

typedef struct listing {
  entry entries[64];
  int count;
  char text[4096];
} listing;

static herr_t list_dataset(hid_t root, const char *name, const H5O_info_t *info, void *data) {
  listing *l = data;
  if (info->type != H5O_TYPE_DATASET || l->count == 64) return 0;
  entry *e = l->entries + l->count;
  const hid_t dset = H5Dopen2(root, name, H5P_DEFAULT), space = H5Dget_space(dset), type = H5Dget_type(dset);
  hsize_t dims[2] = {0, 0};
  const int rank = H5Sget_simple_extent_type(space) == H5S_SCALAR ? 0 : H5Sget_simple_extent_dims(space, dims, NULL);
  const H5T_class_t cls = H5Tget_class(type);
  const char *kind = cls == H5T_FLOAT ? "f" : cls == H5T_INTEGER ? "i" : cls == H5T_STRING ? "s" : "?";
  snprintf(e->text, sizeof e->text, "/%s %d %llu %llu %s%zu", name, rank, (unsigned long long)dims[0],
           (unsigned long long)dims[1], kind, H5Tget_size(type));
  e->offset = H5Dget_offset(dset);
  e->index = l->count++;
  H5Tclose(type);
  H5Sclose(space);
  H5Dclose(dset);
  return 0;
}

static int by_offset(const void *pa, const void *pb) {
  const entry *a = pa, *b = pb;
  const int a_none = a->offset == HADDR_UNDEF, b_none = b->offset == HADDR_UNDEF;
  if (a_none != b_none) return a_none - b_none;
  if (!a_none && a->offset != b->offset) return a->offset < b->offset ? -1 : 1;
  return a->index - b->index;
}

static void list_join(listing *l) {
  qsort(l->entries, (size_t)l->count, sizeof *l->entries, by_offset);
  size_t used = 0;
  for (int k = 0; k < l->count; ++k) {
    const int n = snprintf(l->text + used, sizeof l->text - used, "%s;", l->entries[k].text);
    if (n > 0 && (size_t)n < sizeof l->text - used) used += (size_t)n;
  }
}

// variant 0: the full fixture, 1: the minimal one, 2: the full one with the
// three normal modes on its patch
static int check_one(fascia_ctx *ctx, const char *dir, int variant, int print) {
  fascia_model *m = NULL, *back = NULL;
  CHECK_OK(fixture_model(ctx, variant == 1, &m), ctx);
  if (variant == 2) m->sample_modes[0] = m->sample_modes[2] = FASCIA_MODES_NORMAL;
  char path[256];
  snprintf(path, sizeof path, "%s/variant-%d.h5", dir, variant);
  CHECK_OK(fascia_model_save(ctx, m, path), ctx);
  CHECK_OK(fascia_model_load(ctx, path, &back), ctx);
  const uint64_t fingerprint = fascia_model_fingerprint(m);
  CHECK(fascia_model_fingerprint(back) == fingerprint);
  pinned found = {fingerprint, 0, 0, NULL};
  static listing l;
  memset(&l, 0, sizeof l);
  const hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t checksum = H5Aopen_by_name(file, "/", "fascia_model_checksum", H5P_DEFAULT, H5P_DEFAULT);
  const hid_t version = H5Aopen_by_name(file, "/", "fascia_model_version", H5P_DEFAULT, H5P_DEFAULT);
  CHECK(file >= 0 && checksum >= 0 && version >= 0);
  CHECK(H5Aread(checksum, H5T_NATIVE_UINT64, &found.checksum) >= 0);
  CHECK(H5Aread(version, H5T_NATIVE_INT32, &found.version) >= 0);
  CHECK(H5Ovisit(file, H5_INDEX_NAME, H5_ITER_INC, list_dataset, &l) >= 0);
  H5Aclose(version);
  H5Aclose(checksum);
  H5Fclose(file);
  list_join(&l);
  found.datasets = l.text;
  const pinned *want = expected + variant;
  if (print) {
    printf("    {UINT64_C(0x%016" PRIx64 "), UINT64_C(0x%016" PRIx64 "), %d,\n", found.fingerprint, found.checksum,
           (int)found.version);
    for (const char *d = found.datasets; *d;) {
      const char *end = strchr(d, ';');
      printf("     \"%.*s;\"\n", (int)(end - d), d);
      d = end + 1;
    }
    printf("    },\n");
  }
  CHECK(found.fingerprint == want->fingerprint);
  CHECK(found.checksum == want->checksum);
  CHECK(found.version == want->version);
  if (strcmp(found.datasets, want->datasets)) {
    fprintf(stderr, "%s: the datasets differ from the pinned ones:\n  found    %s\n  expected %s\n", path,
            found.datasets, want->datasets);
    ++check_failures_;
  }
  fascia_model_destroy(&back);
  fascia_model_destroy(&m);
  return 0;
}

int main(int argc, char **argv) {
  const int print = argc > 1 && !strcmp(argv[1], "--print");
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&def, &ctx) != FASCIA_OK) return 1;
  char dir[] = "t210-XXXXXX";
  CHECK(mkdtemp(dir) != NULL);
  int failed = 0;
  for (int variant = 0; variant < 3; ++variant) failed |= check_one(ctx, dir, variant, print);
  fixture_remove_dir(dir);
  fascia_ctx_destroy(&ctx);
  return failed ? 1 : CHECK_RESULT();
}
