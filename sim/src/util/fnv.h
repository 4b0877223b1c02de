// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// FNV-1a, 64 bits: the fingerprint of a model's contents (model.c) and the
// checksums of checkpoint states (io_checkpoint.c). Every single-byte change
// changes it (each step is a bijection of the running value).
#ifndef FASCIA_SRC_FNV_H
#define FASCIA_SRC_FNV_H

#include <stddef.h>
#include <stdint.h>

#define FASCIA_FNV_START UINT64_C(0xcbf29ce484222325)

static inline uint64_t fascia_fnv(uint64_t h, const void *data, size_t bytes) {
  const unsigned char *p = data;
  for (size_t k = 0; k < bytes; ++k) h = (h ^ p[k]) * UINT64_C(0x100000001b3);
  return h;
}

#endif
