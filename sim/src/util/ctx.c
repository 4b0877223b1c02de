// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The context: last error (status, message, source location), thread count,
// progress hook. Libraries never print; the CLI reads the message from here.
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "util/status.h"

struct fascia_ctx {
  fascia_ctx_def def;
  fascia_status status;
  char message[2048];
  char where[256];
};

const char *fascia_version(void) { return "0.1.0"; }

const char *fascia_status_name(fascia_status status) {
  switch (status) {
  case FASCIA_OK: return "FASCIA_OK";
  case FASCIA_ERR_ARGUMENT: return "FASCIA_ERR_ARGUMENT";
  case FASCIA_ERR_MEMORY: return "FASCIA_ERR_MEMORY";
  case FASCIA_ERR_IO: return "FASCIA_ERR_IO";
  case FASCIA_ERR_FORMAT: return "FASCIA_ERR_FORMAT";
  case FASCIA_ERR_UNSUPPORTED: return "FASCIA_ERR_UNSUPPORTED";
  case FASCIA_ERR_DEVICE: return "FASCIA_ERR_DEVICE";
  case FASCIA_ERR_NUMERIC: return "FASCIA_ERR_NUMERIC";
  case FASCIA_ERR_INTERNAL: return "FASCIA_ERR_INTERNAL";
  }
  return "FASCIA_ERR_UNKNOWN";
}

fascia_ctx_def fascia_ctx_def_default(void) {
  fascia_ctx_def def;
  memset(&def, 0, sizeof def);
  def.cookie_ = FASCIA_DEF_COOKIE;
  return def;
}

fascia_status fascia_ctx_create(const fascia_ctx_def *def, fascia_ctx **out) {
  if (!out) return FASCIA_ERR_ARGUMENT;
  *out = NULL;
  if (!def || def->cookie_ != FASCIA_DEF_COOKIE || def->threads < 0) return FASCIA_ERR_ARGUMENT;
  fascia_ctx *ctx = calloc(1, sizeof *ctx);
  if (!ctx) return FASCIA_ERR_MEMORY;
  ctx->def = *def;
  *out = ctx;
  return FASCIA_OK;
}

void fascia_ctx_destroy(fascia_ctx **ctx) {
  if (!ctx || !*ctx) return;
  free(*ctx);
  *ctx = NULL;
}

const char *fascia_ctx_message(const fascia_ctx *ctx) { return ctx ? ctx->message : ""; }
const char *fascia_ctx_where(const fascia_ctx *ctx) { return ctx ? ctx->where : ""; }

void fascia_ctx_clear(fascia_ctx *ctx) {
  if (!ctx) return;
  ctx->status = FASCIA_OK;
  ctx->message[0] = 0;
  ctx->where[0] = 0;
}

int fascia_ctx_threads(const fascia_ctx *ctx) {
  if (ctx && ctx->def.threads > 0) return ctx->def.threads;
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

void fascia_ctx_progress(fascia_ctx *ctx, const char *stage, double fraction, const char *detail) {
  if (ctx && ctx->def.progress) ctx->def.progress(ctx->def.progress_user, stage, fraction, detail);
}

fascia_status fascia_ctx_fail(fascia_ctx *ctx, fascia_status status, const char *file, int line, const char *format,
                              ...) {
  if (!ctx) return status;
  ctx->status = status;
  va_list args;
  va_start(args, format);
  vsnprintf(ctx->message, sizeof ctx->message, format, args);
  va_end(args);
  const char *base = strrchr(file, '/');
  snprintf(ctx->where, sizeof ctx->where, "%s:%d", base ? base + 1 : file, line);
  return status;
}

void *fascia_calloc(int64_t count, size_t size) {
  if (count < 0 || count > FASCIA_MAX_COUNT * 16) return NULL;
  if (count == 0) count = 1; // a valid pointer for empty arrays keeps loops simple
  return calloc((size_t)count, size);
}

#define PAGE_BYTES 4096 // the x86-64 and arm64 base page; larger pages are multiples

void *fascia_calloc_pages(int64_t count, size_t size) {
  if (count < 0 || count > FASCIA_MAX_COUNT * 16 || (size && (size_t)count > (SIZE_MAX - PAGE_BYTES) / size))
    return NULL;
  // at least one page: a valid pointer for empty arrays, as fascia_calloc
  const size_t bytes = ((size_t)count * size / PAGE_BYTES + 1) * PAGE_BYTES;
  void *p = aligned_alloc(PAGE_BYTES, bytes);
  if (p) memset(p, 0, bytes);
  return p;
}
