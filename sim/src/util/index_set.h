// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Small sets of indices kept as sorted arrays: the rows of the assembled
// matrix's pattern and the supports of the volumetric patches.
#ifndef FASCIA_SRC_INDEX_SET_H
#define FASCIA_SRC_INDEX_SET_H

#include <stdint.h>
#include <stdlib.h>

static inline int fascia_index_compare(const void *a, const void *b) {
  const int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
  return (x > y) - (x < y);
}

/// Sorts index[0 .. count-1] and drops repeats; returns how many remain.
static inline int32_t fascia_index_set_make(int32_t *index, int32_t count) {
  qsort(index, (size_t)count, sizeof(int32_t), fascia_index_compare);
  int32_t unique = 0;
  for (int32_t k = 0; k < count; ++k)
    if (k == 0 || index[k] != index[k - 1]) index[unique++] = index[k];
  return unique;
}

/// Index sets packed into a larger malloc'ed buffer: gives back its tail past
/// count entries and returns the buffer. Never fails: a shrink that realloc
/// refuses leaves the buffer as it was, large enough.
static inline int32_t *fascia_index_set_trim(int32_t *index, int64_t count) {
  int32_t *trimmed = (int32_t *)realloc(index, (size_t)(count > 0 ? count : 1) * sizeof(int32_t));
  return trimmed ? trimmed : index;
}

/// The position of value in the ascending index[lo .. hi-1] (bisection); the
/// value must be there.
static inline int32_t fascia_index_set_find(const int32_t *index, int32_t lo, int32_t hi, int32_t value) {
  int32_t last = hi - 1;
  while (lo < last) {
    const int32_t mid = (lo + last) / 2;
    if (index[mid] < value) lo = mid + 1;
    else last = mid;
  }
  return lo;
}

#endif
