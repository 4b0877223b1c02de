// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A small random model for derivative tests: frames at random positions,
// samples with random neighbours, positive weights summing to 1 and random
// gradients summing to 0 (what F = I at rest and F = R under rigid motion
// need), random volumes. Not a physical discretization: derivatives must
// match whatever the weights are.
#ifndef FASCIA_TESTS_RANDOM_MODEL_H
#define FASCIA_TESTS_RANDOM_MODEL_H

#include <stdlib.h>

#include "fascia/model.h"

/// xorshift-based uniform in [lo, hi), deterministic for a seed
static inline double rnd_uniform(unsigned long long *state, double lo, double hi) {
  unsigned long long x = *state;
  x ^= x << 13;
  x ^= x >> 7;
  x ^= x << 17;
  *state = x;
  return lo + (hi - lo) * (double)(x >> 11) / 9007199254740992.0;
}

/// Random unit quaternion of a rotation by at most max_angle.
static inline void rnd_rotation(unsigned long long *state, double max_angle, double *q) {
  double axis[3], n = 0;
  do {
    n = 0;
    for (int c = 0; c < 3; ++c) {
      axis[c] = rnd_uniform(state, -1, 1);
      n += axis[c] * axis[c];
    }
  } while (n < 1e-3 || n > 1);
  n = sqrt(n);
  const double angle = rnd_uniform(state, 0, max_angle);
  q[0] = cos(angle / 2);
  for (int c = 0; c < 3; ++c) q[c + 1] = sin(angle / 2) * axis[c] / n;
}

static inline fascia_model *random_model(fascia_ctx *ctx, unsigned long long seed, int frames, int samples, int law,
                                         double coupling, double curvature) {
  if (frames > 64) return NULL; // the frame choice below works in an array of 64
  unsigned long long st = seed;
  int *counts = malloc((size_t)samples * sizeof(int)), pairs = 0;
  for (int s = 0; s < samples; ++s) {
    counts[s] = 1 + (int)rnd_uniform(&st, 0, frames < 6 ? frames : 6);
    if (counts[s] > frames) counts[s] = frames;
    pairs += counts[s];
  }
  fascia_model_sizes z = {frames, samples, pairs, 1, 0, 0, 0, 0, 0};
  fascia_model *m = NULL;
  if (fascia_model_alloc(ctx, &z, &m) != FASCIA_OK) {
    free(counts);
    return NULL;
  }
  m->materials[0].law = law;
  m->materials[0].youngs_modulus = 1000;
  m->materials[0].poisson_ratio = 0.3;
  m->materials[0].density = 1000;
  m->materials[0].rotation_coupling = coupling;
  m->materials[0].rotation_smoothing = curvature;
  m->gravity[0] = 1.0;
  m->gravity[2] = -9.81;
  for (int i = 0; i < frames; ++i) {
    for (int c = 0; c < 3; ++c) m->frame_position[3 * i + c] = rnd_uniform(&st, 0, 1);
    rnd_rotation(&st, 3.0, m->frame_rotation + 4 * i); // rest rotations need not be identity
  }
  int k = 0;
  for (int s = 0; s < samples; ++s) {
    m->sample_offsets[s] = k;
    for (int c = 0; c < 3; ++c) m->sample_position[3 * s + c] = rnd_uniform(&st, 0, 1);
    m->sample_volume[s] = rnd_uniform(&st, 0.01, 0.05);
    // distinct ascending frames: a random start and stride
    const int start = (int)rnd_uniform(&st, 0, frames);
    int chosen[64], n = counts[s];
    for (int j = 0; j < frames; ++j) chosen[j] = 0;
    for (int j = 0; j < n; ++j) chosen[(start + j) % frames] = 1;
    double wsum = 0, gsum[3] = {0, 0, 0};
    int first = k;
    for (int i = 0; i < frames; ++i) {
      if (!chosen[i]) continue;
      m->pair_frame[k] = i;
      m->pair_weight[k] = rnd_uniform(&st, 0.2, 1);
      wsum += m->pair_weight[k];
      for (int c = 0; c < 3; ++c) {
        m->pair_gradient[3 * k + c] = rnd_uniform(&st, -2, 2);
        gsum[c] += m->pair_gradient[3 * k + c];
      }
      ++k;
    }
    for (int j = first; j < k; ++j) {
      m->pair_weight[j] /= wsum;
      for (int c = 0; c < 3; ++c) m->pair_gradient[3 * j + c] -= gsum[c] / n;
    }
  }
  m->sample_offsets[samples] = k;
  free(counts);
  if (fascia_model_build_reverse(ctx, m) != FASCIA_OK) fascia_model_destroy(&m);
  return m;
}

/// Puts the samples of a random model into three volumetric patches of
/// interleaved samples (mean dilatation), with a Poisson ratio that makes the
/// volumetric energy matter.
static inline void random_model_patches(fascia_model *m) {
  m->materials[0].poisson_ratio = 0.45;
  for (int32_t s = 0; s < m->sample_count; ++s) m->sample_patch[s] = (5 * s) % 3;
}

#endif
