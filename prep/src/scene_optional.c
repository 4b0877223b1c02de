// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Optional organs: a template scene run over a cohort meets segmentations
// without a gallbladder. The organs it lacks are taken out of the scene's
// JSON, with the tissues that no longer have their organs, and the scene is
// read again, so every later stage sees an ordinary scene.
#include "scene_optional.h"

#include <stdlib.h>
#include <string.h>

#include "labels.h"

static int listed(char (*names)[FASCIA_NAME_SIZE], int32_t count, const char *name) {
  for (int32_t k = 0; k < count; ++k)
    if (!strcmp(names[k], name)) return 1;
  return 0;
}

static const char *string_of(const cJSON *object, const char *key) {
  const cJSON *item = cJSON_GetObjectItemCaseSensitive(object, key);
  return cJSON_IsString(item) ? item->valuestring : NULL;
}

// Removes absent names from the tissue's "connects" and "coupling.organs";
// 1 when the tissue keeps the organs its form needs.
static int tissue_keeps(cJSON *tissue, char (*absent)[FASCIA_NAME_SIZE], int32_t absent_count) {
  const char *form = string_of(tissue, "form");
  if (form && !strcmp(form, "strand")) {
    const char *ends[2] = {"from", "to"};
    for (int e = 0; e < 2; ++e) {
      const char *organ = string_of(cJSON_GetObjectItemCaseSensitive(tissue, ends[e]), "organ");
      if (organ && listed(absent, absent_count, organ)) return 0;
    }
  }
  int left = 0;
  cJSON *connects = cJSON_GetObjectItemCaseSensitive(tissue, "connects");
  for (int k = cJSON_GetArraySize(connects) - 1; k >= 0; --k) {
    const cJSON *name = cJSON_GetArrayItem(connects, k);
    if (cJSON_IsString(name) && listed(absent, absent_count, name->valuestring))
      cJSON_DeleteItemFromArray(connects, k);
    else
      ++left;
  }
  cJSON *rules = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(tissue, "coupling"), "organs");
  for (int32_t k = 0; k < absent_count; ++k) cJSON_DeleteItemFromObjectCaseSensitive(rules, absent[k]);
  const cJSON *parts = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(tissue, "region"), "parts");
  const char *on = string_of(parts, "organ");
  if (on && listed(absent, absent_count, on)) return 0;
  if (form && !strcmp(form, "strand")) return 1;
  return left >= (form && !strcmp(form, "sheet") ? 1 : 2);
}

fascia_status prep_scene_leave_out_absent(fascia_ctx *ctx, fascia_prep_scene *scene, cJSON *root, int *edited) {
  *edited = 0;
  int32_t optional = 0;
  for (int32_t o = 0; o < scene->organ_count; ++o) optional += scene->organs[o].optional;
  if (!optional) return FASCIA_OK;
  prep_labelmap *map = NULL;
  PREP_TRY(prep_labelmap_read(ctx, scene->segmentation.file_path, scene->segmentation.frame, &map));
  uint8_t *present = prep_calloc(PREP_MAX_LABEL + 1, 1);
  scene->absent_organs = prep_calloc(optional, sizeof *scene->absent_organs);
  scene->dropped_tissues = prep_calloc(scene->tissue_count, sizeof *scene->dropped_tissues);
  fascia_status status = FASCIA_OK;
  PREP_CHECK_GOTO(present && scene->absent_organs && scene->dropped_tissues, ctx, FASCIA_ERR_MEMORY,
                  "scene '%s': out of memory", scene->path);
  const int64_t n = (int64_t)map->dims[0] * map->dims[1] * map->dims[2];
  for (int64_t v = 0; v < n; ++v) present[map->labels[v]] = 1;
  for (int32_t o = 0; o < scene->organ_count; ++o) {
    const fascia_prep_organ_def *def = scene->organs + o;
    int any = 0;
    for (int32_t k = 0; k < def->label_count; ++k) any |= present[def->labels[k]];
    if (def->optional && !any) memcpy(scene->absent_organs[scene->absent_organ_count++], def->name, FASCIA_NAME_SIZE);
  }
  if (!scene->absent_organ_count) goto cleanup;
  cJSON *organs = cJSON_GetObjectItemCaseSensitive(root, "organs");
  for (int k = cJSON_GetArraySize(organs) - 1; k >= 0; --k) {
    const char *name = string_of(cJSON_GetArrayItem(organs, k), "name");
    if (name && listed(scene->absent_organs, scene->absent_organ_count, name)) cJSON_DeleteItemFromArray(organs, k);
  }
  cJSON *tissues = cJSON_GetObjectItemCaseSensitive(root, "tissues");
  for (int k = cJSON_GetArraySize(tissues) - 1; k >= 0; --k) {
    cJSON *tissue = cJSON_GetArrayItem(tissues, k);
    if (tissue_keeps(tissue, scene->absent_organs, scene->absent_organ_count)) continue;
    const char *name = string_of(tissue, "name");
    snprintf(scene->dropped_tissues[scene->dropped_tissue_count++], FASCIA_NAME_SIZE, "%s", name ? name : "?");
    cJSON_DeleteItemFromArray(tissues, k);
  }
  for (int32_t a = 0, b = scene->dropped_tissue_count - 1; a < b; ++a, --b) { // in the scene's order
    char name[FASCIA_NAME_SIZE];
    memcpy(name, scene->dropped_tissues[a], sizeof name);
    memcpy(scene->dropped_tissues[a], scene->dropped_tissues[b], sizeof name);
    memcpy(scene->dropped_tissues[b], name, sizeof name);
  }
  *edited = 1;
  PREP_CHECK_GOTO(cJSON_GetArraySize(tissues) > 0, ctx, FASCIA_ERR_FORMAT,
                  "scene '%s': without the optional organs label map '%s' lacks (%s%s), no tissue is left; the "
                  "segmentation lacks too much for this scene",
                  scene->path, scene->segmentation.file_path, scene->absent_organs[0],
                  scene->absent_organ_count > 1 ? ", ..." : "");
cleanup:
  free(present);
  prep_labelmap_destroy(&map);
  return status;
}
