// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The one translation of a CGAL exception into a status and a message, for
// both CGAL adapters (cgal_adapter.cpp, cgal_surface_adapter.cpp).
#ifndef FASCIA_PREP_CGAL_FAIL_HPP
#define FASCIA_PREP_CGAL_FAIL_HPP

#include <exception>
#include <new>

#include "adapters.h"

// The status of the exception being handled: call it only inside a catch
// block. `what` names the input ("surface", an organ), `where` CGAL's step.
inline fascia_status fascia_cgal_fail(fascia_ctx *ctx, const char *what, const char *where) {
  try {
    throw;
  } catch (const std::bad_alloc &) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "%s: out of memory in CGAL %s", what, where);
  } catch (const std::exception &e) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_INTERNAL, __FILE__, __LINE__, "%s: CGAL %s failed: %s", what, where,
                           e.what());
  } catch (...) {
    return fascia_ctx_fail(ctx, FASCIA_ERR_INTERNAL, __FILE__, __LINE__, "%s: CGAL %s: unknown exception", what,
                           where);
  }
}

#endif
