// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Every stage of prep in order, for callers that want the whole model of a
// scene file (the tests, the reference cases); `fascia prep` times each
// stage and checks its paths between them, so it calls them itself.
#include <string.h>

#include "prep_util.h"

fascia_status fascia_prep_stages_run(fascia_ctx *ctx, const char *path, const fascia_prep_run_info *info,
                                     fascia_prep_stages *out) {
  memset(out, 0, sizeof *out);
  PREP_TRY(fascia_prep_scene_load(ctx, path, &out->scene));
  PREP_TRY(fascia_prep_import(ctx, out->scene, &out->meshes));
  PREP_TRY(fascia_prep_repair(ctx, out->scene, out->meshes));
  PREP_TRY(fascia_prep_voxelize(ctx, out->scene, out->meshes, &out->volume));
  PREP_TRY(fascia_prep_sample(ctx, out->scene, out->meshes, out->volume, &out->points));
  PREP_TRY(fascia_prep_shape_functions(ctx, out->scene, out->volume, out->points, &out->weights));
  PREP_TRY(fascia_prep_couple(ctx, out->scene, out->meshes, out->points, &out->coupling));
  return fascia_prep_package(ctx, out->scene, out->meshes, out->volume, out->points, out->weights, out->coupling,
                             info, &out->model);
}

void fascia_prep_stages_free(fascia_prep_stages *s) {
  if (!s) return;
  fascia_model_destroy(&s->model);
  fascia_prep_coupling_destroy(&s->coupling);
  fascia_prep_weights_destroy(&s->weights);
  fascia_prep_points_destroy(&s->points);
  fascia_prep_volume_destroy(&s->volume);
  fascia_prep_meshes_destroy(&s->meshes);
  fascia_prep_scene_destroy(&s->scene);
}
