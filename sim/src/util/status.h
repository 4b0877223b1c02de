// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Internal helpers of the library: hidden visibility, size limits, a clock,
// allocation; the error macros are in fascia/base.h.
#ifndef FASCIA_SRC_STATUS_H
#define FASCIA_SRC_STATUS_H

#include "fascia/base.h"

#define FASCIA_INTERN __attribute__((visibility("hidden")))

// FASCIA_FAIL, _CHECK, _TRY, _TRY_GOTO, _CHECK_GOTO: fascia/base.h.

/// Largest element count fascia allocates for one array: refuses absurd sizes
/// up front with a message instead of failing deep inside.
#define FASCIA_MAX_COUNT ((int64_t)1 << 30)

/// A monotonic clock in milliseconds, for the solvers' profiles (newton.c).
FASCIA_INTERN double fascia_now_ms(void);
/// calloc of count elements of size bytes, NULL on overflow or failure.
FASCIA_INTERN void *fascia_calloc(int64_t count, size_t size);
/// The same on pages of its own (aligned, the size rounded up to whole
/// pages), for arrays that a GPU backend page-locks: locking works page by
/// page and fails where two arrays share one. Freed with free().
FASCIA_INTERN void *fascia_calloc_pages(int64_t count, size_t size);
/// One row X(name, type, count, width, ...) of a list of arrays declared
/// once (contract/system_table.h, modes.h, dilatation.h): owner->name gets
/// count * width zeroed elements; ok becomes 0 where it could not.
#define FASCIA_ALLOC_ROW(owner, ok, name, type, count, width)                                                          \
  ok &= ((owner)->name = fascia_calloc((int64_t)(count) * (width), sizeof(type))) != NULL
#define FASCIA_DEF_COOKIE 0x5fa5c1a

#endif
