// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Pieces held by nothing: a model whose second lump of tissue shares no frame
// with the clamped first one is refused by validation and by loading, with the
// piece's size and position in the message; allow_floating lets it through and
// survives a save and a load; a rigid organ joins the pieces it touches, and
// a frame that no sample weighs on is no piece.
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "fascia/model.h"

// Frames 0..3 on a line, frame 0 fixed; sample 0 on frames 0 and 1, sample 1
// (1 cm^3) on frames 2 and 3. With `bridge` a third sample joins 1 and 2.
static fascia_model *two_lumps(fascia_ctx *ctx, int bridge) {
  fascia_model_sizes z = {.frames = 5, .samples = 2 + bridge, .pairs = 4 + 2 * bridge, .materials = 1};
  fascia_model *m = NULL;
  if (fascia_model_alloc(ctx, &z, &m) != FASCIA_OK) return NULL;
  for (int i = 0; i < 5; ++i) m->frame_position[3 * i] = 0.01 * i;
  m->frame_kind[0] = FASCIA_FRAME_FIXED; // frame 4 is weighed on by no sample
  const int32_t frames[3][2] = {{0, 1}, {2, 3}, {1, 2}};
  for (int s = 0; s < 2 + bridge; ++s) {
    m->sample_position[3 * s] = 0.01 * (frames[s][0] + 0.5);
    m->sample_volume[s] = 1e-6;
    m->sample_offsets[s + 1] = 2 * (s + 1);
    for (int k = 0; k < 2; ++k) m->pair_frame[2 * s + k] = frames[s][k], m->pair_weight[2 * s + k] = 0.5;
  }
  m->materials[0] = (fascia_material){.name = "soft", .youngs_modulus = 3000, .poisson_ratio = 0.3, .density = 1000};
  m->gravity[2] = -9.81;
  if (fascia_model_build_reverse(ctx, m) != FASCIA_OK) fascia_model_destroy(&m);
  return m;
}

int main(void) {
  fascia_ctx *ctx = NULL;
  fascia_ctx_def def = fascia_ctx_def_default();
  CHECK(fascia_ctx_create(&def, &ctx) == FASCIA_OK);
  fascia_model *m = two_lumps(ctx, 0);
  CHECK(m != NULL);

  fascia_model_piece pieces[5];
  int32_t labels[5], count = -1;
  CHECK_OK(fascia_model_floating_components(ctx, m, labels, pieces, 5, &count), ctx);
  CHECK(count == 1);
  CHECK(pieces[0].frames == 2 && pieces[0].samples == 1 && pieces[0].first_frame == 2);
  CHECK_NEAR(pieces[0].volume, 1e-6, 1e-12, 0);
  CHECK_NEAR(pieces[0].position[0], 0.02, 1e-12, 0);
  CHECK(labels[0] == -1 && labels[1] == -1 && labels[2] == 0 && labels[3] == 0 && labels[4] == -1);

  // validation refuses it, naming the model, the piece and the remedy
  CHECK(fascia_model_validate(ctx, m, "two lumps") == FASCIA_ERR_FORMAT);
  const char *msg = fascia_ctx_message(ctx);
  CHECK(strstr(msg, "model 'two lumps'") && strstr(msg, "2 frames and 1 samples") && strstr(msg, "1 cm^3") &&
        strstr(msg, "frame 2 at (0.02, 0, 0) m") && strstr(msg, "allow_floating") && strstr(msg, "fascia prep"));

  // allowed: validation passes, the flag goes through a file, and a file
  // without it is refused on loading
  char dir[] = "/tmp/t216-XXXXXX", path[64];
  CHECK(mkdtemp(dir) != NULL);
  snprintf(path, sizeof path, "%s/m.h5", dir);
  m->allow_floating = 1;
  CHECK_OK(fascia_model_validate(ctx, m, "two lumps"), ctx);
  CHECK_OK(fascia_model_save(ctx, m, path), ctx);
  fascia_model *back = NULL;
  CHECK_OK(fascia_model_load(ctx, path, &back), ctx);
  CHECK(back->allow_floating == 1);
  fascia_model_destroy(&back);
  m->allow_floating = 0;
  CHECK(fascia_model_save(ctx, m, path) == FASCIA_ERR_FORMAT); // saving validates too
  fascia_model_destroy(&m);

  // joined by a sample: held
  m = two_lumps(ctx, 1);
  CHECK(m != NULL);
  CHECK_OK(fascia_model_floating_components(ctx, m, NULL, NULL, 0, &count), ctx);
  CHECK(count == 0);
  CHECK_OK(fascia_model_validate(ctx, m, "bridged"), ctx);
  fascia_model_destroy(&m);

  // a rigid organ touching both lumps makes them one piece, still unheld
  // when nothing holds the organ... and held when frame 1 (on it) is joined
  // to the clamped lump
  fascia_model_sizes z = {.frames = 5, .samples = 2, .pairs = 4, .materials = 1, .organs = 1, .couplings = 2};
  fascia_model *r = NULL;
  fascia_model *src = two_lumps(ctx, 0);
  CHECK(src != NULL);
  CHECK_OK(fascia_model_alloc(ctx, &z, &r), ctx);
  memcpy(r->frame_position, src->frame_position, 15 * sizeof(fascia_real));
  memcpy(r->frame_kind, src->frame_kind, 5 * sizeof(int32_t));
  memcpy(r->sample_position, src->sample_position, 6 * sizeof(fascia_real));
  memcpy(r->sample_volume, src->sample_volume, 2 * sizeof(fascia_real));
  memcpy(r->sample_offsets, src->sample_offsets, 3 * sizeof(int32_t));
  memcpy(r->pair_frame, src->pair_frame, 4 * sizeof(int32_t));
  memcpy(r->pair_weight, src->pair_weight, 4 * sizeof(fascia_real));
  r->materials[0] = src->materials[0];
  fascia_model_destroy(&src);
  r->organs[0].kind = FASCIA_ORGAN_RIGID;
  r->coupling_organ[0] = r->coupling_organ[1] = 0;
  r->coupling_frame[0] = 1, r->coupling_frame[1] = 3;
  CHECK_OK(fascia_model_build_reverse(ctx, r), ctx);
  CHECK_OK(fascia_model_floating_components(ctx, r, labels, pieces, 5, &count), ctx);
  CHECK(count == 0);
  r->frame_kind[0] = FASCIA_FRAME_FREE; // now nothing holds the organ and its two lumps
  CHECK_OK(fascia_model_floating_components(ctx, r, labels, pieces, 5, &count), ctx);
  CHECK(count == 1 && pieces[0].frames == 4 && pieces[0].samples == 2 && labels[4] == -1);
  fascia_model_destroy(&r);

  unlink(path);
  rmdir(dir);
  fascia_ctx_destroy(&ctx);
  return check_failures_ != 0;
}
