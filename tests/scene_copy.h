// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A shipped scene copied into a test's folder: its organs' meshes named by
// absolute path (the copy prepares from anywhere), changed by the test
// through cJSON on the way. Link cjson.
#ifndef FASCIA_TESTS_SCENE_COPY_H
#define FASCIA_TESTS_SCENE_COPY_H

#include "cli_exec.h"

#include <cjson/cJSON.h>
#include <libgen.h>

/// The scene at `from` written to `to`, its meshes' paths made absolute,
/// after edit(scene, arg) changed it (edit may be NULL). 1 on success.
static inline int scene_copy(const char *from, const char *to, void (*edit)(cJSON *scene, void *arg), void *arg) {
  static char text[1 << 16];
  if (cli_read_file(from, text, sizeof text) <= 0) return 0;
  cJSON *scene = cJSON_Parse(text);
  if (!scene) return 0;
  char folder[1024], path[2048];
  snprintf(folder, sizeof folder, "%s", from);
  const char *dir = dirname(folder);
  cJSON *item;
  cJSON_ArrayForEach(item, cJSON_GetObjectItemCaseSensitive(scene, "organs")) {
    const char *mesh = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(item, "mesh"));
    if (!mesh || mesh[0] == '/') continue;
    snprintf(path, sizeof path, "%s/%s", dir, mesh);
    cJSON_ReplaceItemInObjectCaseSensitive(item, "mesh", cJSON_CreateString(path));
  }
  if (edit) edit(scene, arg);
  char *out = cJSON_Print(scene);
  FILE *f = out ? fopen(to, "wb") : NULL;
  int ok = f && fputs(out, f) >= 0;
  if (f) ok &= fclose(f) == 0;
  cJSON_free(out), cJSON_Delete(scene);
  return ok;
}

#endif
