// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// SHA-256 of input files and of the scene text, for the model's provenance
// (which exact inputs made it). The digest comes from nettle.
#include <errno.h>
#include <nettle/sha2.h>
#include <stdio.h>
#include <string.h>

#include "prep_util.h"

static void to_hex(struct sha256_ctx *s, char hex[65]) {
  uint8_t digest[SHA256_DIGEST_SIZE];
  sha256_digest(s, SHA256_DIGEST_SIZE, digest);
  for (int k = 0; k < SHA256_DIGEST_SIZE; ++k) snprintf(hex + 2 * k, 3, "%02x", digest[k]);
}

fascia_status fascia_prep_file_sha256(fascia_ctx *ctx, const char *path, char hex[65]) {
  FILE *f;
  int64_t size;
  PREP_TRY(prep_open_regular(ctx, path, "file", &f, &size));
  struct sha256_ctx s;
  sha256_init(&s);
  uint8_t buf[1 << 15];
  // the size the file had when opened, and not a byte more: a file that
  // grows without end (or is replaced by one) cannot stall the hash
  int64_t left = size;
  size_t n = 1;
  while (left > 0 && (n = fread(buf, 1, left < (int64_t)sizeof buf ? (size_t)left : sizeof buf, f)) > 0) {
    sha256_update(&s, n, buf);
    left -= (int64_t)n;
  }
  const int failed = ferror(f), err = errno;
  const int longer = left == 0 && fgetc(f) != EOF;
  fclose(f);
  PREP_CHECK(!failed, ctx, FASCIA_ERR_IO, "file '%s': read error (%s)", path, strerror(err));
  PREP_CHECK(left == 0 && !longer, ctx, FASCIA_ERR_IO,
             "file '%s': changed while it was read (%lld bytes expected); read it again once it is complete", path,
             (long long)size);
  to_hex(&s, hex);
  return FASCIA_OK;
}

void prep_sha256_buffer(const void *data, size_t size, char hex[65]) {
  struct sha256_ctx s;
  sha256_init(&s);
  sha256_update(&s, size, (const uint8_t *)data);
  to_hex(&s, hex);
}
