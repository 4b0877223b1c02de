// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Fuzz harness: the model file loader on raw bytes. The input is written to a
// file and loaded; any refusal must come with a message. Most mutations die
// in HDF5's own header checks, so fuzz_model_struct (which mutates the
// contents of a valid model) is the stronger harness; this one covers damaged
// and truncated files.
#define _POSIX_C_SOURCE 200809L
#include "fuzz_common.h"

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc, (void)argv;
  return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_scratch_path("raw.h5");
  fuzz_write_file(path, data, size);
  fascia_ctx *ctx = NULL;
  fascia_ctx_def def = fascia_ctx_def_default();
  def.threads = 1;
  if (fascia_ctx_create(&def, &ctx) != FASCIA_OK) abort();
  fascia_model *model = NULL;
  const fascia_status status = fascia_model_load(ctx, path, &model);
  fuzz_check_refusal(ctx, status, "fascia_model_load");
  if ((status == FASCIA_OK) != (model != NULL)) abort();
  fascia_model_destroy(&model);
  fascia_ctx_destroy(&ctx);
  return 0;
}
