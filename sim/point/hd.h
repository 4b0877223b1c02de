// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The only place that tells nvcc from a C compiler: FASCIA_HD marks the
// per-point math as host and device code, so cc and nvcc compile one body.
// FASCIA_STATIC_FORCE_INLINE (in place of static inline) marks a body that
// its callers specialize by constant arguments: each caller gets its own
// copy, with the dead branches gone.
#ifndef FASCIA_POINT_HD_H
#define FASCIA_POINT_HD_H

#include <math.h>
#include <stdint.h>

#if defined(__CUDACC__)
#define FASCIA_HD __host__ __device__
#define FASCIA_RESTRICT __restrict__
#define FASCIA_STATIC_FORCE_INLINE static __forceinline__
#else
#define FASCIA_HD
#define FASCIA_RESTRICT restrict
#define FASCIA_STATIC_FORCE_INLINE static inline __attribute__((always_inline))
#endif

#ifndef FASCIA_REAL_DEFINED
#define FASCIA_REAL_DEFINED
typedef double fascia_real;
#endif

#define FASCIA_R(x) ((fascia_real)(x))

#endif
