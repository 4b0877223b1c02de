// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Pieces of a model that nothing holds. Frames are the nodes of a graph; a
// sample joins every frame it has a weight on, and the coupling frames of a
// rigid organ are joined through the body they all follow. A connected piece
// is held when one of its frames is fixed or prescribed (the coupling frames
// of fixed and prescribed organs are), or when no sample weighs on its
// frames (they carry no mass). Anything else falls under gravity for
// ever: no static equilibrium, no meaningful dynamic run.
#include <stdlib.h>

#include "fascia/model.h"
#include "util/status.h"

static int32_t find_root(int32_t *parent, int32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]]; // path halving keeps the trees shallow
    i = parent[i];
  }
  return i;
}

static void join(int32_t *parent, int32_t a, int32_t b) {
  a = find_root(parent, a);
  b = find_root(parent, b);
  // the smaller index becomes the root: labels do not depend on visiting order
  if (a < b) parent[b] = a;
  else if (b < a) parent[a] = b;
}

fascia_status fascia_model_floating_components(fascia_ctx *ctx, const fascia_model *m, int32_t *frame_piece,
                                               fascia_model_piece *pieces, int32_t capacity, int32_t *count) {
  FASCIA_CHECK(m && count && capacity >= 0 && (pieces || capacity == 0), ctx, FASCIA_ERR_ARGUMENT,
               "fascia_model_floating_components: NULL argument");
  *count = 0;
  const int32_t N = m->frame_count;
  int32_t *parent = fascia_calloc((int64_t)N + 1, sizeof(int32_t));
  int32_t *label = fascia_calloc((int64_t)N + 1, sizeof(int32_t));
  unsigned char *held = fascia_calloc((int64_t)N + 1, 1);
  int32_t *first_rigid = fascia_calloc((int64_t)m->organ_count + 1, sizeof(int32_t));
  if (!parent || !label || !held || !first_rigid) {
    free(parent), free(label), free(held), free(first_rigid);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "model: out of memory for the connectivity of %d frames", (int)N);
  }
  for (int32_t i = 0; i < N; ++i) parent[i] = i;
  for (int32_t s = 0; s < m->sample_count; ++s)
    for (int32_t p = m->sample_offsets[s] + 1; p < m->sample_offsets[s + 1]; ++p)
      join(parent, m->pair_frame[m->sample_offsets[s]], m->pair_frame[p]);
  for (int32_t k = 0; k < m->organ_count; ++k) first_rigid[k] = -1;
  for (int32_t c = 0; c < m->coupling_count; ++c) {
    const int32_t o = m->coupling_organ[c];
    if (m->organs[o].kind != FASCIA_ORGAN_RIGID) continue;
    if (first_rigid[o] < 0) first_rigid[o] = m->coupling_frame[c];
    else join(parent, first_rigid[o], m->coupling_frame[c]);
  }
  // a frame no sample weighs on carries no mass and no energy: nothing falls
  for (int32_t p = 0; p < m->sample_offsets[m->sample_count]; ++p) label[m->pair_frame[p]] = 1;
  for (int32_t i = 0; i < N; ++i)
    if (m->frame_kind[i] != FASCIA_FRAME_FREE || !label[i]) held[find_root(parent, i)] = 1;
  // number the unheld pieces in order of their lowest frame
  int32_t n = 0;
  for (int32_t i = 0; i < N; ++i) {
    const int32_t r = find_root(parent, i);
    if (held[r]) label[i] = -1;
    else if (r == i) {
      label[i] = n;
      if (n < capacity) {
        fascia_model_piece *q = pieces + n;
        q->frames = q->samples = 0;
        q->volume = 0;
        q->first_frame = i;
        for (int c = 0; c < 3; ++c) q->position[c] = m->frame_position[3 * i + c];
      }
      ++n;
    } else label[i] = label[r];
    if (label[i] >= 0 && label[i] < capacity) pieces[label[i]].frames++;
    if (frame_piece) frame_piece[i] = label[i];
  }
  for (int32_t s = 0; s < m->sample_count; ++s) {
    if (m->sample_offsets[s + 1] <= m->sample_offsets[s]) continue;
    const int32_t l = label[m->pair_frame[m->sample_offsets[s]]];
    if (l < 0 || l >= capacity) continue;
    pieces[l].samples++;
    pieces[l].volume += m->sample_volume[s];
  }
  *count = n;
  free(parent), free(label), free(held), free(first_rigid);
  return FASCIA_OK;
}
