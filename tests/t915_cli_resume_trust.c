// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia run --resume` trusts a checkpoint only as far as it should:
// --steps below the checkpoint's step is an error, not a run of nothing
// (equal: the run is complete, and that is said); options that contradict the checkpoint's settings are refused
// naming the option and both values, while options left out take the
// checkpoint's; a checkpoint with a flipped bit is refused naming the dataset.
// Bad model files give fascia's one line and nothing from HDF5 (no "infinite
// loop closing library" at exit); a rigid organ with a fixed coupling frame
// is a model problem (exit 1, the file, organ and frame named), not a usage
// error (exit 2).
// Usage: t915_cli_resume_trust PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <hdf5.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "cli_exec.h"
#include "io_fixture.h"
#include "organ_fixture.h"

static cli_result result;
static const char *fascia_path;
static char err[1100];

// Runs fascia with args; 1 when it exited with `status` and stderr contains
// each of part1, part2 (NULL: anything) and, for a refusal, exactly one line.
static int expect(const char *args, int status, const char *part1, const char *part2) {
  if (!cli_exec(fascia_path, args, err, &result)) return 0;
  int lines = 0;
  for (const char *c = result.err; *c; ++c) lines += *c == '\n';
  const int ok = result.status == status && (!part1 || strstr(result.err, part1)) &&
                 (!part2 || strstr(result.err, part2)) && (status == 0 || lines == 1);
  if (!ok)
    fprintf(stderr, "t915: fascia %s\n  exited %d (wanted %d), stderr (%d lines, wanted '%s', '%s'):\n%s\n", args,
            result.status, status, lines, part1 ? part1 : "", part2 ? part2 : "", result.err);
  return ok;
}

static int flip_byte(const char *path, long at) {
  FILE *f = fopen(path, "r+b");
  if (!f) return 1;
  int failed = fseek(f, at, SEEK_SET) != 0;
  const int c = failed ? EOF : fgetc(f);
  failed = failed || c == EOF || fseek(f, at, SEEK_SET) != 0 || fputc(c ^ 0xff, f) == EOF;
  return fclose(f) != 0 || failed;
}

// Byte offset of the stored data of dataset `name` in an HDF5 file.
static long data_offset(const char *path, const char *name) {
  hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return -1;
  hid_t dset = H5Dopen2(file, name, H5P_DEFAULT);
  const haddr_t offset = dset >= 0 ? H5Dget_offset(dset) : HADDR_UNDEF;
  if (dset >= 0) H5Dclose(dset);
  H5Fclose(file);
  return offset == HADDR_UNDEF ? -1 : (long)offset;
}

static int set_frame_kind(const char *path, int32_t frame, int32_t kind) {
  hid_t file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) return 1;
  hid_t dset = H5Dopen2(file, "/frames/kind", H5P_DEFAULT);
  hid_t space = dset >= 0 ? H5Dget_space(dset) : H5I_INVALID_HID;
  const hsize_t start = (hsize_t)frame, one = 1;
  hid_t memory = H5Screate_simple(1, &one, NULL);
  int failed = space < 0 || H5Sselect_hyperslab(space, H5S_SELECT_SET, &start, NULL, &one, NULL) < 0 ||
               H5Dwrite(dset, H5T_NATIVE_INT32, memory, space, H5P_DEFAULT, &kind) < 0;
  H5Sclose(memory);
  if (space >= 0) H5Sclose(space);
  if (dset >= 0) H5Dclose(dset);
  return H5Fclose(file) < 0 || failed;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: %s PATH/TO/fascia WORK_DIR\n", argv[0]);
    return 2;
  }
  fascia_path = argv[1];
  char dir[1024], model[1100], ck[1100], bad[1100], organs[1100], args[6000];
  snprintf(dir, sizeof dir, "%s/t915-%ld", argv[2], (long)getpid());
  if (mkdir(dir, 0755) != 0) {
    perror(dir);
    return 1;
  }
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  snprintf(model, sizeof model, "%s/beam.h5", dir);
  snprintf(ck, sizeof ck, "%s/beam.ck.h5", dir);
  snprintf(bad, sizeof bad, "%s/bad.h5", dir);
  snprintf(organs, sizeof organs, "%s/organs.h5", dir);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);

  // a checkpoint at step 4 of a run with --damping 0.25
  snprintf(args, sizeof args, "beam --frames 6x3x3 -o '%s'", model);
  CHECK(expect(args, 0, NULL, NULL));
  snprintf(args, sizeof args, "run '%s' --steps 4 --dt 0.005 --damping 0.25 --threads 1 --checkpoint '%s'", model, ck);
  CHECK(expect(args, 0, NULL, NULL));

  // --steps counts from t = 0: at or below the checkpoint's step is an error
  snprintf(args, sizeof args, "run '%s' --steps 2 --resume '%s'", model, ck);
  CHECK(expect(args, 2, "step 4", "--steps 2"));
  snprintf(args, sizeof args, "run '%s' --steps 4 --resume '%s'", model, ck); // complete: said so, nothing run
  CHECK(expect(args, 0, "step 4", "already complete") && result.out[0] == '\0');

  // contradicting settings are refused with both values; left out, they are the checkpoint's
  snprintf(args, sizeof args, "run '%s' --steps 6 --damping 0.5 --resume '%s'", model, ck);
  CHECK(expect(args, 2, "--damping", "0.25"));
  snprintf(args, sizeof args, "run '%s' --steps 6 --dt 0.01 --resume '%s'", model, ck);
  CHECK(expect(args, 2, "--dt", "0.01"));
  snprintf(args, sizeof args, "run '%s' --steps 6 --mass consistent --resume '%s'", model, ck);
  CHECK(expect(args, 2, "--mass", "mass = lumped, the command line asks for consistent"));
  snprintf(args, sizeof args, "run '%s' --steps 6 --preset interactive --resume '%s'", model, ck);
  CHECK(expect(args, 2, "--preset", NULL));
  snprintf(args, sizeof args, "run '%s' --steps 6 --damping 0.25 --json --resume '%s'", model, ck);
  CHECK(expect(args, 0, NULL, NULL));
  CHECK(strstr(result.out, "\"dt\":0.005") != NULL && strstr(result.out, "\"steps\":2") != NULL);

  // a flipped bit in the state
  snprintf(bad, sizeof bad, "%s/flipped.ck.h5", dir);
  CHECK(fixture_copy(ck, bad, -1) == 0);
  const long at = data_offset(bad, "/state/velocity");
  CHECK(at > 0 && flip_byte(bad, at + 3) == 0);
  snprintf(args, sizeof args, "run '%s' --steps 6 --resume '%s'", model, bad);
  CHECK(expect(args, 1, bad, "/state/checksum"));

  // a model damaged in its first object headers (where HDF5 1.10 itself leaks
  // on a failed open): fascia's one line, nothing from HDF5
  snprintf(bad, sizeof bad, "%s/damaged.h5", dir);
  int refused = 0;
  for (long k = 96; k < 160; k += 3) {
    CHECK(fixture_copy(model, bad, -1) == 0 && flip_byte(bad, k) == 0);
    snprintf(args, sizeof args, "inspect '%s'", bad);
    if (!cli_exec(fascia_path, args, err, &result)) continue;
    if (result.status == 0) continue; // a byte HDF5 never reads
    ++refused;
    if (strstr(result.err, "HDF5:") || strstr(result.err, "HDF5-DIAG") || strchr(result.err, '\n') !=
                                                                            result.err + strlen(result.err) - 1) {
      fprintf(stderr, "t915: inspect of a model with byte %ld flipped printed more than fascia's line:\n%s\n", k,
              result.err);
      ++check_failures_;
    }
  }

  CHECK(refused >= 5); // the bytes are HDF5's first headers: most damage there is refused

  // a rigid organ with a fixed coupling frame: the model is wrong, not the command line
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1;
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  organ_fixture_def fd = organ_fixture_def_default(); // A fixed, B rigid
  fascia_model *m = NULL;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  CHECK_OK(fascia_model_save(ctx, m, organs), ctx);
  int32_t frame = -1, organ = 0;
  for (int32_t c = 0; c < m->coupling_count && frame < 0; ++c)
    if (m->organs[m->coupling_organ[c]].kind == FASCIA_ORGAN_RIGID) frame = m->coupling_frame[c], organ = m->coupling_organ[c];
  const char *organ_name = m->organs[organ].name;
  CHECK(frame >= 0 && set_frame_kind(organs, frame, FASCIA_FRAME_FIXED) == 0);
  char frame_text[64];
  snprintf(frame_text, sizeof frame_text, "frame %d", (int)frame);
  snprintf(args, sizeof args, "run '%s' --steps 1", organs);
  CHECK(expect(args, 1, organs, frame_text));
  CHECK(strstr(result.err, organ_name) != NULL && strstr(result.err, "fixed") != NULL);
  CHECK(strstr(result.err, "--help") == NULL);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);

  if (!CHECK_RESULT()) {
    char command[1200];
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    if (system(command) != 0) fprintf(stderr, "could not remove %s\n", dir);
  }
  return CHECK_RESULT();
}
