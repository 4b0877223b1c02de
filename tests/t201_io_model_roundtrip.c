// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A model saved and loaded again is identical field by field, bit for bit
// (doubles compared as bytes), both a full model and one with empty arrays
// (no motion, probe, organ, coupling or provenance).
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "io_fixture.h"

#define SAME(a, b, count)                                                                                             \
  do {                                                                                                                \
    const size_t same_bytes_ = (size_t)(count) * sizeof *(a);                                                        \
    if ((count) > 0 && memcmp((a), (b), same_bytes_) != 0) {                                                         \
      fprintf(stderr, "%s:%d: %s differs after the round trip\n", __FILE__, __LINE__, #a);                          \
      ++check_failures_;                                                                                              \
    }                                                                                                                 \
  } while (0)

static void compare(const fascia_model *a, const fascia_model *b) {
  CHECK(a->frame_count == b->frame_count && a->sample_count == b->sample_count && a->pair_count == b->pair_count);
  CHECK(a->material_count == b->material_count && a->motion_count == b->motion_count);
  CHECK(a->probe_count == b->probe_count && a->probe_pair_count == b->probe_pair_count);
  CHECK(a->organ_count == b->organ_count && a->coupling_count == b->coupling_count);
  if (check_failures_) return; // sizes differ: the arrays cannot be compared
  const int64_t N = a->frame_count, S = a->sample_count, P = a->pair_count, Q = a->probe_count,
                R = a->probe_pair_count, C = a->coupling_count;
  SAME(a->frame_position, b->frame_position, 3 * N);
  SAME(a->frame_rotation, b->frame_rotation, 4 * N);
  SAME(a->frame_kind, b->frame_kind, N);
  SAME(a->frame_motion, b->frame_motion, N);
  SAME(a->frame_load, b->frame_load, 6 * N);
  SAME(a->frame_offsets, b->frame_offsets, N + 1);
  SAME(a->frame_pairs, b->frame_pairs, P);
  SAME(a->sample_position, b->sample_position, 3 * S);
  SAME(a->sample_volume, b->sample_volume, S);
  SAME(a->sample_material, b->sample_material, S);
  SAME(a->sample_patch, b->sample_patch, S);
  SAME(a->sample_offsets, b->sample_offsets, S + 1);
  SAME(a->pair_frame, b->pair_frame, P);
  SAME(a->pair_weight, b->pair_weight, P);
  SAME(a->pair_gradient, b->pair_gradient, 3 * P);
  for (int32_t k = 0; k < a->material_count; ++k) {
    const fascia_material *x = a->materials + k, *y = b->materials + k;
    CHECK(!strcmp(x->name, y->name) && x->law == y->law);
    SAME(&x->youngs_modulus, &y->youngs_modulus, 1);
    SAME(&x->poisson_ratio, &y->poisson_ratio, 1);
    SAME(&x->density, &y->density, 1);
    SAME(&x->rotation_coupling, &y->rotation_coupling, 1);
    SAME(&x->rotation_smoothing, &y->rotation_smoothing, 1);
    SAME(&x->part, &y->part, 1);
  }
  for (int32_t k = 0; k < a->motion_count; ++k) {
    const fascia_motion *x = a->motions + k, *y = b->motions + k;
    CHECK(!strcmp(x->name, y->name) && x->key_count == y->key_count);
    if (x->key_count != y->key_count) continue;
    SAME(x->pivot, y->pivot, 3);
    SAME(x->key_time, y->key_time, x->key_count);
    SAME(x->key_translation, y->key_translation, 3 * x->key_count);
    SAME(x->key_rotation, y->key_rotation, 4 * x->key_count);
  }
  for (int32_t p = 0; p < Q; ++p) CHECK(!strcmp(a->probe_name[p], b->probe_name[p]));
  SAME(a->probe_position, b->probe_position, 3 * Q);
  SAME(a->probe_offsets, b->probe_offsets, Q + 1);
  SAME(a->probe_frame, b->probe_frame, R);
  SAME(a->probe_weight, b->probe_weight, R);
  for (int32_t k = 0; k < a->organ_count; ++k) {
    const fascia_organ *x = a->organs + k, *y = b->organs + k;
    CHECK(!strcmp(x->name, y->name) && x->kind == y->kind && x->motion == y->motion);
    CHECK(x->vertex_count == y->vertex_count && x->triangle_count == y->triangle_count);
    if (x->vertex_count != y->vertex_count || x->triangle_count != y->triangle_count) continue;
    SAME(x->vertices, y->vertices, 3 * x->vertex_count);
    SAME(x->triangles, y->triangles, 3 * x->triangle_count);
  }
  SAME(a->coupling_organ, b->coupling_organ, C);
  SAME(a->coupling_frame, b->coupling_frame, C);
  SAME(a->coupling_triangle, b->coupling_triangle, C);
  SAME(a->coupling_barycentric, b->coupling_barycentric, 3 * C);
  SAME(a->gravity, b->gravity, 3);
  CHECK((a->provenance == NULL) == (b->provenance == NULL));
  if (a->provenance && b->provenance) CHECK(!strcmp(a->provenance, b->provenance));
}

static int roundtrip(fascia_ctx *ctx, const char *dir, int minimal) {
  char path[512];
  snprintf(path, sizeof path, "%s/model-%d.h5", dir, minimal);
  fascia_model *a = NULL, *b = NULL, *c = NULL;
  CHECK_OK(fixture_model(ctx, minimal, &a), ctx);
  CHECK_OK(fascia_model_save(ctx, a, path), ctx);
  CHECK_OK(fascia_model_load(ctx, path, &b), ctx);
  compare(a, b);
  // saving over an existing file replaces it and leaves no temporary behind
  CHECK_OK(fascia_model_save(ctx, b, path), ctx);
  CHECK_OK(fascia_model_load(ctx, path, &c), ctx);
  compare(a, c);
  CHECK(fixture_count_files(dir, ".tmp") == 0);
  fascia_model_destroy(&a);
  fascia_model_destroy(&b);
  fascia_model_destroy(&c);
  return 0;
}

int main(void) {
  fascia_ctx_def def = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&def, &ctx) != FASCIA_OK) return 1;
  char dir[] = "t201-XXXXXX";
  CHECK(mkdtemp(dir) != NULL);
  int failed = roundtrip(ctx, dir, 0) || roundtrip(ctx, dir, 1);
  fixture_remove_dir(dir);
  fascia_ctx_destroy(&ctx);
  return failed ? 1 : CHECK_RESULT();
}
