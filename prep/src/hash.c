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
  FILE *f = fopen(path, "rb");
  PREP_CHECK(f, ctx, FASCIA_ERR_IO, "'%s': cannot open (%s)", path, strerror(errno));
  struct sha256_ctx s;
  sha256_init(&s);
  uint8_t buf[1 << 15];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, f)) > 0) sha256_update(&s, n, buf);
  const int failed = ferror(f);
  fclose(f);
  PREP_CHECK(!failed, ctx, FASCIA_ERR_IO, "'%s': read error", path);
  to_hex(&s, hex);
  return FASCIA_OK;
}

void prep_sha256_buffer(const void *data, size_t size, char hex[65]) {
  struct sha256_ctx s;
  sha256_init(&s);
  sha256_update(&s, size, (const uint8_t *)data);
  to_hex(&s, hex);
}
