// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Base types of the public API: real type, status codes and the context that
// carries the last error message, thread count and progress hook.
#ifndef FASCIA_BASE_H
#define FASCIA_BASE_H

#include <stddef.h>
#include <stdint.h>

#if defined(_WIN32)
#define FASCIA_API __declspec(dllexport)
#else
#define FASCIA_API __attribute__((visibility("default")))
#endif

#ifdef __cplusplus
extern "C" {
#endif

/// Floating point type of every physical quantity (SI units throughout).
#ifndef FASCIA_REAL_DEFINED
#define FASCIA_REAL_DEFINED
typedef double fascia_real;
#endif

/// Result of every function that can fail. The readable message is kept in
/// the context (fascia_ctx_message).
typedef enum fascia_status {
  FASCIA_OK = 0,
  FASCIA_ERR_ARGUMENT,    ///< impossible setting or misuse; nothing changed
  FASCIA_ERR_MEMORY,      ///< allocation failed or a size is absurd
  FASCIA_ERR_IO,          ///< a file could not be opened, read or written
  FASCIA_ERR_FORMAT,      ///< a readable file with wrong content
  FASCIA_ERR_UNSUPPORTED, ///< a part that was not built, or is absent
  FASCIA_ERR_DEVICE,      ///< GPU failure: destroy and recreate the object
  FASCIA_ERR_NUMERIC,     ///< NaN, inversion, no convergence
  FASCIA_ERR_INTERNAL     ///< a bug: destroy and recreate the object
} fascia_status;

/// Name of a status value ("FASCIA_ERR_FORMAT"), never NULL.
FASCIA_API const char *fascia_status_name(fascia_status status);

/// Progress hook: stage is a short name ("static solve"), fraction in [0, 1]
/// or negative when unknown, detail a short human line (may be NULL).
typedef void (*fascia_progress_fn)(void *user, const char *stage, double fraction, const char *detail);

typedef struct fascia_ctx fascia_ctx;

/// Options of a context; start from fascia_ctx_def_default().
typedef struct fascia_ctx_def {
  int threads;                 ///< worker threads (0: OpenMP's default)
  fascia_progress_fn progress; ///< may be NULL
  void *progress_user;
  int cookie_; ///< private: set by fascia_ctx_def_default
} fascia_ctx_def;

FASCIA_API fascia_ctx_def fascia_ctx_def_default(void);
/// Creates a context. On error *out is NULL.
FASCIA_API fascia_status fascia_ctx_create(const fascia_ctx_def *def, fascia_ctx **out);
/// Destroys a context; accepts NULL and sets *ctx to NULL.
FASCIA_API void fascia_ctx_destroy(fascia_ctx **ctx);
/// The last error message recorded on this context ("" if none).
FASCIA_API const char *fascia_ctx_message(const fascia_ctx *ctx);
/// Source file:line where the last error was recorded ("" if none).
FASCIA_API const char *fascia_ctx_where(const fascia_ctx *ctx);
/// Forgets the last error.
FASCIA_API void fascia_ctx_clear(fascia_ctx *ctx);
/// Thread count the context asks for (>= 1).
FASCIA_API int fascia_ctx_threads(const fascia_ctx *ctx);
/// Reports progress through the hook, if any.
FASCIA_API void fascia_ctx_progress(fascia_ctx *ctx, const char *stage, double fraction, const char *detail);
/// Records an error on the context (used by libraries built on fascia, such
/// as prep) and returns status.
FASCIA_API fascia_status fascia_ctx_fail(fascia_ctx *ctx, fascia_status status, const char *file, int line,
                                         const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

// Error propagation for code built on fascia (the library, prep, the scenes):
// record a status and message on ctx, check a condition, propagate a failure.
/// Records status and message on ctx, evaluates to status.
#define FASCIA_FAIL(ctx, st, ...) fascia_ctx_fail((ctx), (st), __FILE__, __LINE__, __VA_ARGS__)
/// Returns the recorded status from the enclosing function when cond is false.
#define FASCIA_CHECK(cond, ctx, st, ...)                                                                              \
  do {                                                                                                                \
    if (!(cond)) return FASCIA_FAIL(ctx, st, __VA_ARGS__);                                                           \
  } while (0)
/// Propagates a failing status.
#define FASCIA_TRY(expr)                                                                                              \
  do {                                                                                                                \
    fascia_status fascia_try_st_ = (expr);                                                                            \
    if (fascia_try_st_ != FASCIA_OK) return fascia_try_st_;                                                          \
  } while (0)
/// Inside a function with `fascia_status status` and a `cleanup:` label.
#define FASCIA_TRY_GOTO(expr)                                                                                         \
  do {                                                                                                                \
    status = (expr);                                                                                                  \
    if (status != FASCIA_OK) goto cleanup;                                                                            \
  } while (0)
/// The same for a check: records the failure in `status`, then goes to cleanup.
#define FASCIA_CHECK_GOTO(cond, ctx, st, ...)                                                                         \
  do {                                                                                                                \
    if (!(cond)) {                                                                                                    \
      status = FASCIA_FAIL(ctx, st, __VA_ARGS__);                                                                     \
      goto cleanup;                                                                                                   \
    }                                                                                                                 \
  } while (0)

/// Version of the library, "MAJOR.MINOR.PATCH".
FASCIA_API const char *fascia_version(void);

#ifdef __cplusplus
}
#endif
#endif
