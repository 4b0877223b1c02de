// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Internal error helpers: record a status and a readable message on the
// context, check a condition, propagate a failure.
#ifndef FASCIA_SRC_STATUS_H
#define FASCIA_SRC_STATUS_H

#include "fascia/base.h"

#define FASCIA_INTERN __attribute__((visibility("hidden")))

/// Records status and message on ctx, evaluates to status.
#define FASCIA_FAIL(ctx, st, ...) fascia_ctx_fail((ctx), (st), __FILE__, __LINE__, __VA_ARGS__)

/// Returns the recorded status from the enclosing function when cond is false.
#define FASCIA_CHECK(cond, ctx, st, ...)                                                                              \
  do {                                                                                                                \
    if (!(cond)) return FASCIA_FAIL(ctx, st, __VA_ARGS__);                                                           \
  } while (0)

/// Propagates a failing status.
#define FASCIA_TRY(expr)                                                                                              \
  do {                                                                                                                \
    fascia_status fascia_try_st_ = (expr);                                                                            \
    if (fascia_try_st_ != FASCIA_OK) return fascia_try_st_;                                                          \
  } while (0)

/// Inside a function with `fascia_status status` and a `cleanup:` label.
#define FASCIA_TRY_GOTO(expr)                                                                                         \
  do {                                                                                                                \
    status = (expr);                                                                                                  \
    if (status != FASCIA_OK) goto cleanup;                                                                            \
  } while (0)

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
/// once (cpu/system_arrays.h, modes.h, dilatation.h): owner->name gets
/// count * width zeroed elements; ok becomes 0 where it could not.
#define FASCIA_ALLOC_ROW(owner, ok, name, type, count, width)                                                          \
  ok &= ((owner)->name = fascia_calloc((int64_t)(count) * (width), sizeof(type))) != NULL
#define FASCIA_DEF_COOKIE 0x5fa5c1a

#endif
