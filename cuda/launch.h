// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A launcher runs the items of items.h somewhere: on an NVIDIA GPU
// (launch_cuda.cu) or, for tests on machines without one, in host loops
// (launch_emulated.c). The device solver (device_solver.c) talks to it only
// through this table, so both run the same solver code.
//
// Launches are asynchronous and in order; download() and finish() wait.
// A launch that fails is remembered and reported by the next download() or
// finish(), with the GPU's own words.
#ifndef FASCIA_CUDA_LAUNCH_H
#define FASCIA_CUDA_LAUNCH_H

#include <stddef.h>

#include "fascia/base.h"
#include "items.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct fascia_launcher fascia_launcher;

/// Sequences of launches recorded once and replayed (CUDA graphs).
enum { FASCIA_LAUNCH_SLOTS = 4 };

typedef struct fascia_launcher_ops {
  const char *backend; ///< "cuda" or "emulated"
  /// Opens the device; fails with a message saying why there is none.
  /// threads: host threads of the emulation (ignored by CUDA).
  fascia_status (*create)(fascia_ctx *ctx, int threads, fascia_launcher **out);
  void (*destroy)(fascia_launcher *L);
  /// The device in words, e.g. "NVIDIA H100 80GB HBM3 (sm_90, 79 GiB)".
  const char *(*device_name)(const fascia_launcher *L);
  /// Device memory, zero-filled; FASCIA_ERR_MEMORY with the sizes on failure.
  fascia_status (*alloc)(fascia_launcher *L, size_t bytes, void **out);
  void (*release)(fascia_launcher *L, void *p);
  fascia_status (*upload)(fascia_launcher *L, void *device_dst, const void *host_src, size_t bytes);
  /// Waits for the launches before it, then copies.
  fascia_status (*download)(fascia_launcher *L, void *host_dst, const void *device_src, size_t bytes);
  /// Device-to-device copy, in order with the launches.
  void (*copy)(fascia_launcher *L, void *device_dst, const void *device_src, size_t bytes);
  /// Page-locks host memory, so that copies from and to it run at the full
  /// rate of the link and without a staging copy: 1 if it did (unpin before
  /// the memory is freed), 0 if not (copies work all the same).
  int (*pin)(fascia_launcher *L, void *host, size_t bytes);
  void (*unpin)(fascia_launcher *L, void *host);
  /// Copies that do not wait, in order with the launches: host_src must stay
  /// as it is, and host_dst is filled, only once the next download() or
  /// finish() returns. A failure is reported there.
  void (*send)(fascia_launcher *L, void *device_dst, const void *host_src, size_t bytes);
  void (*receive)(fascia_launcher *L, void *host_dst, const void *device_src, size_t bytes);
  /// fascia_dev_item(D, kernel, i, in, out, value) for i in [0, n).
  void (*kernel)(fascia_launcher *L, const fascia_dev *D, fascia_dev_kernel kernel, int64_t n,
                 const fascia_real *in, fascia_real *out, fascia_real value);
  /// Sums fascia_dev_term(D, terms, i, a, b) over i in [0, n) in a fixed
  /// order, then runs fascia_dev_scalar_step(D, step, sums) once.
  void (*reduce)(fascia_launcher *L, const fascia_dev *D, fascia_dev_terms terms, int64_t n, const fascia_real *a,
                 const fascia_real *b, fascia_dev_step step);
  /// Records the launches body(arg) makes as the sequence of slot (they
  /// are not run); replay() runs it. Arguments are captured by value.
  fascia_status (*record)(fascia_launcher *L, int slot, void (*body)(void *arg), void *arg);
  void (*replay)(fascia_launcher *L, int slot);
  /// Waits for everything launched; reports a failed launch.
  fascia_status (*finish)(fascia_launcher *L);
} fascia_launcher_ops;

/// The host emulation: every build has it.
extern const fascia_launcher_ops fascia_launcher_emulated;
#ifdef FASCIA_HAVE_CUDA
/// NVIDIA GPUs: builds with the CUDA toolkit have it.
extern const fascia_launcher_ops fascia_launcher_cuda;
#endif

#ifdef __cplusplus
}
#endif
#endif
