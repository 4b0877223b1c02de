// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// WIDE_CLONES: a function compiled twice, for AVX2 and for the baseline; the
// loader picks one. Without fused multiply-adds (-ffp-contract=off, and
// "avx2" has none) both give the same bits: the wide loops only do at once
// what the baseline does one by one. The per-point math it calls must be
// inlined into it (FASCIA_STATIC_FORCE_INLINE) to be compiled wide too.
#ifndef FASCIA_SRC_WIDE_H
#define FASCIA_SRC_WIDE_H

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define WIDE_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define WIDE_CLONES
#endif

#endif
