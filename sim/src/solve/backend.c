// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The registry of backends (backend.h) and the choice among them. The CUDA
// backend is first: "auto" takes a GPU when there is one and it runs the
// model; the CPU is the reference and always there; the host emulation of
// the device is for tests and is taken only by name. Backends registered
// at run time (fascia_backend_register) follow, in the order registered.
#include <stdio.h>
#include <string.h>

#include "solve/backend.h"
#include "solve/solver_internal.h"

#define BUILT_IN 3

static const fascia_backend_ops *registry[FASCIA_BACKEND_MAX] = {&fascia_backend_cuda, &fascia_backend_cpu,
                                                                 &fascia_backend_emulated};
static int registry_count = BUILT_IN;

const fascia_backend_ops *const *fascia_backends(int *count) {
  *count = registry_count;
  return registry;
}

const fascia_backend_ops *fascia_backend_find(const char *name) {
  for (int k = 0; name && k < registry_count; ++k)
    if (!strcmp(registry[k]->name, name)) return registry[k];
  return NULL;
}

const char *fascia_backend_name(int k) { return k >= 0 && k < registry_count ? registry[k]->name : NULL; }

fascia_status fascia_backend_register(fascia_ctx *ctx, const fascia_backend_ops *ops) {
  FASCIA_CHECK(ops && ops->name && ops->name[0] && strcmp(ops->name, "auto") && ops->available && ops->supports &&
                   ops->create && ops->destroy && ops->describe && ops->begin && ops->evaluate && ops->prepare &&
                   ops->direction && ops->accept && ops->finish,
               ctx, FASCIA_ERR_ARGUMENT,
               "backend registry: a backend needs a name other than 'auto' and every operation of the Newton loop "
               "and of its life (available, supports, create, destroy, describe)");
  FASCIA_CHECK(!fascia_backend_find(ops->name), ctx, FASCIA_ERR_ARGUMENT,
               "backend registry: a backend named '%s' is registered already", ops->name);
  FASCIA_CHECK(registry_count < FASCIA_BACKEND_MAX, ctx, FASCIA_ERR_UNSUPPORTED,
               "backend registry: full (%d backends)", FASCIA_BACKEND_MAX);
  registry[registry_count++] = ops;
  return FASCIA_OK;
}

int fascia_backend_available(const char *name, char *detail, size_t size) {
  if (detail && size) detail[0] = 0;
  const fascia_backend_ops *ops = fascia_backend_find(name);
  if (!ops) {
    if (detail) snprintf(detail, size, "unknown backend");
    return 0;
  }
  return ops->available(detail, size);
}

// Tries one backend: 0 and why when it is not available or does not run the
// setup; its creation's status otherwise.
static fascia_status try_backend(const fascia_backend_ops *ops, const fascia_backend_setup *setup,
                                 fascia_backend **out, char *why, size_t size) {
  if (!ops->available(why, size) || !ops->supports(setup, why, size)) return FASCIA_ERR_UNSUPPORTED;
  return ops->create(setup, out);
}

fascia_status fascia_backend_pick(const fascia_backend_setup *setup, fascia_backend **out, char *describe,
                                  size_t size) {
  *out = NULL;
  const char *name = setup->def->backend ? setup->def->backend : "auto";
  char why[256] = "";
  if (strcmp(name, "auto")) {
    const fascia_backend_ops *ops = fascia_backend_find(name);
    if (!ops) {
      char valid[256] = "auto";
      for (int k = 0; k < registry_count; ++k)
        snprintf(valid + strlen(valid), sizeof valid - strlen(valid), ", %s", registry[k]->name);
      return FASCIA_FAIL(setup->ctx, FASCIA_ERR_ARGUMENT, "unknown backend '%s'; valid: %s", name, valid);
    }
    const int available = ops->available(why, sizeof why);
    if (!available || !ops->supports(setup, why, sizeof why))
      return FASCIA_FAIL(setup->ctx, available ? FASCIA_ERR_ARGUMENT : FASCIA_ERR_UNSUPPORTED,
                         "backend '%s' cannot run this: %s; use --backend cpu (or auto)", name, why);
    FASCIA_TRY(ops->create(setup, out));
    snprintf(describe, size, "%s", ops->describe(*out));
    return FASCIA_OK;
  }
  // auto: the first that runs; why each one before it did not
  char skipped[512] = "";
  for (int k = 0; k < registry_count; ++k) {
    const fascia_backend_ops *ops = registry[k];
    if (!ops->automatic) continue;
    why[0] = 0;
    const fascia_status st = try_backend(ops, setup, out, why, sizeof why);
    if (st == FASCIA_OK) {
      snprintf(describe, size, "%s%s%s%s", ops->describe(*out), skipped[0] ? " (auto: " : "", skipped,
               skipped[0] ? ")" : "");
      return FASCIA_OK;
    }
    if (st != FASCIA_ERR_UNSUPPORTED) { // it could run, and failed: say why, and go on
      snprintf(why, sizeof why, "%s", fascia_ctx_message(setup->ctx));
      fascia_ctx_clear(setup->ctx);
    }
    const size_t used = strlen(skipped);
    snprintf(skipped + used, sizeof skipped - used, "%snot on %s: %s", used ? "; " : "",
             !strcmp(ops->name, "cuda") ? "a GPU" : ops->name, why);
  }
  return FASCIA_FAIL(setup->ctx, FASCIA_ERR_UNSUPPORTED, "no backend runs this model: %s", skipped);
}

fascia_status fascia_solver_backend_gradient(fascia_solver *S, const fascia_real *x, const fascia_real *q,
                                             fascia_real *gradient, fascia_real *energy) {
  return S->backend->ops->gradient(S->backend, x, q, S->load_factor, gradient, energy);
}

fascia_status fascia_solver_backend_hessian_apply(fascia_solver *S, const fascia_real *v, fascia_real *out) {
  return S->backend->ops->hessian_apply(S->backend, v, out);
}

fascia_status fascia_solver_backend_hessian_diagonal(fascia_solver *S, fascia_real *blocks) {
  return S->backend->ops->hessian_diagonal(S->backend, blocks);
}
