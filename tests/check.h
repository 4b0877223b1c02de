// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Test macros: silent on success; on failure print the expression, the values
// and file:line, and make the test return 1. Exit 77 means skipped.
#ifndef FASCIA_TESTS_CHECK_H
#define FASCIA_TESTS_CHECK_H

#include <math.h>
#include <stdio.h>

#include "fascia/base.h"

#define TEST_SKIP 77

static int check_failures_ = 0;

#define CHECK(cond)                                                                                                   \
  do {                                                                                                                \
    if (!(cond)) {                                                                                                    \
      fprintf(stderr, "%s:%d: CHECK(%s) failed\n", __FILE__, __LINE__, #cond);                                        \
      ++check_failures_;                                                                                              \
    }                                                                                                                 \
  } while (0)

/// |a - b| <= atol + rtol |b|
#define CHECK_NEAR(a, b, rtol, atol)                                                                                  \
  do {                                                                                                                \
    const double check_a_ = (double)(a), check_b_ = (double)(b);                                                      \
    if (!(fabs(check_a_ - check_b_) <= (atol) + (rtol)*fabs(check_b_))) {                                            \
      fprintf(stderr, "%s:%d: CHECK_NEAR(%s, %s) failed: %.17g vs %.17g (diff %.3g, rtol %g, atol %g)\n", __FILE__,  \
              __LINE__, #a, #b, check_a_, check_b_, fabs(check_a_ - check_b_), (double)(rtol), (double)(atol));       \
      ++check_failures_;                                                                                              \
    }                                                                                                                 \
  } while (0)

/// Fails (and returns 1 from the enclosing function) when st is not FASCIA_OK.
#define CHECK_OK(st, ctx)                                                                                             \
  do {                                                                                                                \
    fascia_status check_st_ = (st);                                                                                   \
    if (check_st_ != FASCIA_OK) {                                                                                     \
      fprintf(stderr, "%s:%d: %s returned %s: %s\n", __FILE__, __LINE__, #st, fascia_status_name(check_st_),         \
              fascia_ctx_message(ctx));                                                                               \
      return 1;                                                                                                       \
    }                                                                                                                 \
  } while (0)

#define CHECK_RESULT() (check_failures_ ? 1 : 0)

#endif
