// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The only place that tells nvcc from a C compiler: FASCIA_HD marks the
// per-point math as host and device code, so cc and nvcc compile one body.
#ifndef FASCIA_POINT_HD_H
#define FASCIA_POINT_HD_H

#include <math.h>
#include <stdint.h>

#if defined(__CUDACC__)
#define FASCIA_HD __host__ __device__
#define FASCIA_RESTRICT __restrict__
#else
#define FASCIA_HD
#define FASCIA_RESTRICT restrict
#endif

#ifndef FASCIA_REAL_DEFINED
#define FASCIA_REAL_DEFINED
typedef double fascia_real;
#endif

#define FASCIA_R(x) ((fascia_real)(x))

#endif
