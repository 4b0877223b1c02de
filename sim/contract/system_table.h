// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The arrays the CPU system owns (fascia_system, sim/src/cpu/system.h), declared once:
// what the model gives the per-sample math after a pass over it (Lame
// parameters, masses, offsets), the frame state and the scratch of an
// evaluation. system.c allocates, checks and frees them from this list and
// sets the per-sample math's view from it, and the device backend uploads
// the rows whose last column names a member of its arrays
// (cuda/device_solver.c) from the data fascia_system_arrays gives it: the
// table is part of the backend contract (backend.h). The model's own
// arrays: model_table.h.
// The smoothing graph (made by the first assembly) is outside the list.
#ifndef FASCIA_CONTRACT_SYSTEM_TABLE_H
#define FASCIA_CONTRACT_SYSTEM_TABLE_H

// X(field, type, count, width, device)
//   field   the member of fascia_system; type: its element type
//   count   the member of fascia_system that sizes it: count * width values
//   device  POINT(member), DEVICE(member) or HOST, as in model_table.h
#define FASCIA_SYSTEM_ARRAYS(X)                                                                                        \
  X(pair_offset, fascia_real, pair_count, 3, POINT(pair_offset))                                                       \
  X(sample_lambda, fascia_real, sample_count, 1, POINT(sample_lambda))                                                 \
  X(sample_mu, fascia_real, sample_count, 1, POINT(sample_mu))                                                         \
  X(sample_coupling, fascia_real, sample_count, 1, POINT(sample_coupling))                                             \
  X(sample_curvature, fascia_real, sample_count, 1, POINT(sample_curvature))                                           \
  X(sample_mass, fascia_real, sample_count, 1, DEVICE(sample_mass))                                                    \
  X(sample_law, int32_t, sample_count, 1, POINT(sample_law))                                                           \
  X(local_slot, int32_t, max_neighbours, 1, HOST)                                                                      \
  X(pair_sample, int32_t, pair_count, 1, DEVICE(pair_sample))                                                          \
  X(pair_lumped_mass, fascia_real, pair_count, 1, HOST)                                                                \
  X(frame_lumped_moments, fascia_real, frame_count, 13, DEVICE(frame_lumped_moments))                                  \
  X(frame_mass, fascia_real, frame_count, 1, DEVICE(frame_mass))                                                       \
  X(frame_moment, fascia_real, frame_count, 3, DEVICE(frame_moment))                                                   \
  X(x, fascia_real, frame_count, 3, HOST)                                                                              \
  X(q, fascia_real, frame_count, 4, HOST)                                                                              \
  X(A, fascia_real, frame_count, 9, HOST)                                                                              \
  X(A_mass, fascia_real, frame_count, 9, HOST)                                                                         \
  X(pair_buffer, fascia_real, pair_count, 6, HOST)                                                                     \
  X(cache, fascia_real, sample_count, FASCIA_PT_CACHE_SIZE, HOST)                                                      \
  X(sample_flags, int, sample_count, 1, HOST)                                                                          \
  X(conservative_torque, fascia_real, frame_count, 3, HOST)                                                            \
  X(gradient_scratch, fascia_real, frame_count, 6, HOST)

/// Row numbers: FASCIA_SA_ID_pair_offset, ...
enum {
#define FASCIA_SA_ID_(field, ...) FASCIA_SA_ID_##field,
  FASCIA_SYSTEM_ARRAYS(FASCIA_SA_ID_)
#undef FASCIA_SA_ID_
  FASCIA_SA_COUNT
};

#endif
