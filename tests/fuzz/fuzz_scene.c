// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Fuzz harness: the scene file parser of prep (cJSON plus fascia's key and
// value checks). The input is the scene text; any refusal must carry a
// message naming the key.
#define _POSIX_C_SOURCE 200809L
#include "fascia/prep.h"
#include "fuzz_common.h"

static fascia_ctx *fuzz_ctx;

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc, (void)argv;
  fascia_ctx_def def = fascia_ctx_def_default();
  def.threads = 1;
  if (fascia_ctx_create(&def, &fuzz_ctx) != FASCIA_OK) abort();
  return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = malloc(size + 1);
  if (!text) return 0;
  memcpy(text, data, size);
  text[size] = 0;
  fascia_ctx_clear(fuzz_ctx);
  fascia_prep_scene *scene = NULL;
  const fascia_status status = fascia_prep_scene_parse(fuzz_ctx, text, "fuzz.json", "/nonexistent", &scene);
  fuzz_check_refusal(fuzz_ctx, status, "fascia_prep_scene_parse");
  if ((status == FASCIA_OK) != (scene != NULL)) abort();
  fascia_prep_scene_destroy(&scene);
  free(text);
  return 0;
}
