// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The functions over the rows of the model's table (contract/model_table.h):
// the rows as records, a model's arrays as views, their hashes.
#ifndef FASCIA_SRC_MODEL_ARRAYS_H
#define FASCIA_SRC_MODEL_ARRAYS_H

#include "contract/model_table.h"
#include "fascia/model.h"
#include "util/status.h"

/// One row of the table.
typedef struct fascia_model_array {
  const char *field;   ///< "frame_position"
  fascia_ma_kind kind;
  const char *row;     ///< what a row is, for messages: "frame", "sample", ..
  int32_t plus, width; ///< rows = count + plus; values per row
  const char *path, *unit;
  int32_t fill;
  int32_t flags; ///< FASCIA_MA_*
  int32_t since;
} fascia_model_array;

/// The table, one entry per row of FASCIA_MODEL_ARRAYS, in its order.
FASCIA_INTERN extern const fascia_model_array fascia_model_arrays[FASCIA_MA_COUNT];

/// One array of one model: its row, its data and its number of rows.
typedef struct fascia_model_view {
  const fascia_model_array *array;
  void *data;
  int64_t rows;
} fascia_model_view;

/// The arrays of a model, in the table's order.
FASCIA_INTERN void fascia_model_views(const fascia_model *model, fascia_model_view views[FASCIA_MA_COUNT]);
/// Bytes of one value of a row's kind (a whole structure for MATERIAL, ..).
FASCIA_INTERN size_t fascia_model_array_size(fascia_ma_kind kind);
/// The view's bytes: rows * width values.
FASCIA_INTERN size_t fascia_model_view_bytes(const fascia_model_view *view);
/// 1 where a SPARSE row's array holds an entry other than its fill (always 1
/// for other rows).
FASCIA_INTERN int fascia_model_view_set(const fascia_model_view *view);
/// The model's sizes (fascia_model_alloc's argument).
FASCIA_INTERN fascia_model_sizes fascia_model_shape(const fascia_model *model);

/// FNV-1a over the rows from h: with `file` 0 the fingerprint's (FP rows,
/// SPARSE ones where set, no names), with 1 the model file checksum's (every
/// row but those FASCIA_MA_CHECKSUM_VERSION leaves out, names and key counts
/// included).
FASCIA_INTERN uint64_t fascia_model_hash_rows(uint64_t h, const fascia_model *model, int file);

#endif
