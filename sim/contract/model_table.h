// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The arrays of the model (fascia_model, fascia/model.h), declared once. Each
// row of FASCIA_MODEL_ARRAYS says what the array is, and every place that
// handles the model's arrays runs over the rows instead of naming them:
// allocation, fill and freeing (model.c), the finite-value check of the
// validation, the fingerprint and the file's checksum, the model file's
// sizes, writing and reading (io_model.c), and the upload to the device
// (cuda/device_solver.c). Adding an array: docs/architecture.md. The table
// is part of the backend contract (contract/backend.h): its last column
// says where a backend puts each array. The functions over the rows:
// sim/src/model/model_arrays.h.
//
// The rows are in hash order: the fingerprint and the checksum hash the
// arrays in this order, and fingerprints stored in checkpoints and results
// and checksums stored in model files depend on it, so rows are never
// reordered; a new row goes where its group is, and is hashed only as the
// flags say. Files hold the datasets in this order too (but for
// FASCIA_MA_EARLY).
//
// The mesh of each organ, the keys of each motion (sized per organ and per
// motion, inside the MATERIAL, MOTION and ORGAN rows), the tissue surface and
// the tetrahedra (drawing only, written after these) are outside the table.
#ifndef FASCIA_CONTRACT_MODEL_TABLE_H
#define FASCIA_CONTRACT_MODEL_TABLE_H

// X(field, kind, count, plus, width, dataset, unit, fill, flags, since, device)
//   field    the member of fascia_model
//   kind     REAL (fascia_real, f64 in files), INT (int32_t), NAME (char[FASCIA_NAME_SIZE]),
//            MATERIAL, MOTION, ORGAN (structures with their own datasets under `dataset`)
//   count    the member of fascia_model_sizes that sizes it: rows = count + plus
//   width    values per row (the file's second dimension; 1: a 1-D dataset)
//   dataset  its HDF5 path in model files (docs/model-format.md); unit: its attribute, or NULL
//   fill     what fascia_model_alloc puts in the first value of each row (the others 0):
//            -1 for "none" indices, 1 for identity quaternions
//   flags    FASCIA_MA_* below
//   since    the file version from which the dataset is present (a file of an older version
//            leaves the fill); 0: optional in any version
//   device   POINT(member): a member of the per-sample math's view (fascia_pt_model, point/sample.h),
//            on the host (fascia_system's pm) and on the device; DEVICE(member): uploaded into that
//            member of the device's arrays (fascia_dev, cuda/items.h); HOST: neither
#define FASCIA_MODEL_ARRAYS(X)                                                                                         \
  X(frame_position, REAL, frames, 0, 3, "/frames/position", "m", 0, FASCIA_MA_FP | FASCIA_MA_SIZES, 1, HOST)           \
  X(frame_rotation, REAL, frames, 0, 4, "/frames/rotation", "1", 1, FASCIA_MA_FP, 1, DEVICE(rest_rotation))            \
  X(frame_kind, INT, frames, 0, 1, "/frames/kind", NULL, 0, FASCIA_MA_FP, 1, HOST)                                     \
  X(frame_motion, INT, frames, 0, 1, "/frames/motion", NULL, -1, FASCIA_MA_FP, 1, HOST)                                \
  X(frame_load, REAL, frames, 0, 6, "/frames/load", "N, N m", 0, FASCIA_MA_FP, 1, DEVICE(frame_load))                  \
  X(frame_organ, INT, frames, 0, 1, "/frames/organ", NULL, -1, FASCIA_MA_FP | FASCIA_MA_EARLY, 0, HOST)                \
  X(frame_offsets, INT, frames, 1, 1, "/frames/offsets", NULL, 0, 0, 1, DEVICE(frame_offsets))                         \
  X(frame_pairs, INT, pairs, 0, 1, "/frames/pairs", NULL, 0, 0, 1, DEVICE(frame_pairs))                                \
  X(sample_position, REAL, samples, 0, 3, "/samples/position", "m", 0, FASCIA_MA_FP | FASCIA_MA_SIZES, 1, HOST)        \
  X(sample_volume, REAL, samples, 0, 1, "/samples/volume", "m^3", 0, FASCIA_MA_FP, 1, POINT(sample_volume))            \
  X(sample_material, INT, samples, 0, 1, "/samples/material", NULL, 0, FASCIA_MA_FP, 1, HOST)                          \
  X(sample_organ, INT, samples, 0, 1, "/samples/organ", NULL, -1, FASCIA_MA_FP, 0, HOST)                               \
  X(sample_patch, INT, samples, 0, 1, "/samples/patch", NULL, -1, FASCIA_MA_FP | FASCIA_MA_SPARSE, 2, HOST)            \
  X(sample_modes, INT, samples, 0, 1, "/samples/modes", NULL, 0, FASCIA_MA_FP | FASCIA_MA_SPARSE, 3, HOST)             \
  X(sample_offsets, INT, samples, 1, 1, "/samples/offsets", NULL, 0, FASCIA_MA_FP, 1, POINT(sample_offsets))           \
  X(pair_frame, INT, pairs, 0, 1, "/pairs/frame", NULL, 0, FASCIA_MA_FP | FASCIA_MA_SIZES, 1, POINT(pair_frame))       \
  X(pair_weight, REAL, pairs, 0, 1, "/pairs/weight", "1", 0, FASCIA_MA_FP, 1, POINT(pair_weight))                      \
  X(pair_gradient, REAL, pairs, 0, 3, "/pairs/gradient", "1/m", 0, FASCIA_MA_FP, 1, POINT(pair_gradient))              \
  X(materials, MATERIAL, materials, 0, 1, "/materials", NULL, 0, FASCIA_MA_FP | FASCIA_MA_SIZES, 1, HOST)              \
  X(motions, MOTION, motions, 0, 1, "/motions", NULL, 0, FASCIA_MA_FP | FASCIA_MA_SIZES, 1, HOST)                      \
  X(probe_name, NAME, probes, 0, 1, "/probes/name", NULL, 0, FASCIA_MA_SIZES, 1, HOST)                                 \
  X(probe_position, REAL, probes, 0, 3, "/probes/position", "m", 0, 0, 1, HOST)                                        \
  X(probe_offsets, INT, probes, 1, 1, "/probes/offsets", NULL, 0, 0, 1, HOST)                                          \
  X(probe_frame, INT, probe_pairs, 0, 1, "/probes/frame", NULL, 0, FASCIA_MA_SIZES, 1, HOST)                           \
  X(probe_weight, REAL, probe_pairs, 0, 1, "/probes/weight", "1", 0, 0, 1, HOST)                                       \
  X(organs, ORGAN, organs, 0, 1, "/organs", NULL, 0, FASCIA_MA_FP | FASCIA_MA_SIZES, 1, HOST)                          \
  X(coupling_organ, INT, couplings, 0, 1, "/coupling/organ", NULL, 0, FASCIA_MA_FP | FASCIA_MA_SIZES, 1, HOST)         \
  X(coupling_frame, INT, couplings, 0, 1, "/coupling/frame", NULL, 0, FASCIA_MA_FP, 1, HOST)                           \
  X(coupling_triangle, INT, couplings, 0, 1, "/coupling/triangle", NULL, 0, FASCIA_MA_FP, 1, HOST)                     \
  X(coupling_barycentric, REAL, couplings, 0, 3, "/coupling/barycentric", "1", 0, FASCIA_MA_FP, 1, HOST)

/// What a row holds.
typedef enum fascia_ma_kind {
  FASCIA_MA_REAL,
  FASCIA_MA_INT,
  FASCIA_MA_NAME,
  FASCIA_MA_MATERIAL,
  FASCIA_MA_MOTION,
  FASCIA_MA_ORGAN,
} fascia_ma_kind;

/// Row flags.
enum {
  /// in the fingerprint (fascia_model_fingerprint): the solver reads it
  FASCIA_MA_FP = 1,
  /// written to files, and fingerprinted, only where an entry differs from
  /// the fill: models without it keep the files and fingerprints they had
  /// before it existed
  FASCIA_MA_SPARSE = 2,
  /// its dataset's rows give the count on reading (one row per count)
  FASCIA_MA_SIZES = 4,
  /// files hold it before the row above (so they always have)
  FASCIA_MA_EARLY = 8,
};

/// The model file version that brought the checksum: it hashes every row of
/// this version or before, and a later SPARSE row only where it is set (where
/// files hold it), so that adding one leaves the checksums of older files.
#define FASCIA_MA_CHECKSUM_VERSION 4

/// Row numbers: FASCIA_MA_ID_frame_position, ...
enum {
#define FASCIA_MA_ID_(field, ...) FASCIA_MA_ID_##field,
  FASCIA_MODEL_ARRAYS(FASCIA_MA_ID_)
#undef FASCIA_MA_ID_
  FASCIA_MA_COUNT
};

#endif
