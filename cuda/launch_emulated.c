// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The device backend run in host loops: "device memory" is host memory, a
// kernel is a loop over its items (OpenMP where it has threads), a
// reduction sums in item order, a recorded sequence is a list of launches.
// It is slow and exists so that every machine, CI included, tests the device
// solver's code paths against the CPU backend; a GPU adds only the launch
// layer (launch_cuda.cu).
#include <stdlib.h>
#include <string.h>

#include "launch.h"
#include "fascia/base.h"

typedef struct launch_record {
  int reduction; // 0: kernel, 1: reduce
  int id;        // kernel or terms
  int64_t n;
  const fascia_real *in, *a, *b;
  fascia_real *out, value;
  int step;
  fascia_dev D;
} launch_record;

struct fascia_launcher {
  fascia_ctx *ctx;
  int threads;
  int recording; // slot being recorded + 1, 0 when not
  launch_record *slots[FASCIA_LAUNCH_SLOTS];
  int slot_count[FASCIA_LAUNCH_SLOTS], slot_capacity[FASCIA_LAUNCH_SLOTS];
  int failed; // a record ran out of memory
};

static fascia_status emu_create(fascia_ctx *ctx, int threads, fascia_launcher **out) {
  fascia_launcher *L = calloc(1, sizeof *L);
  FASCIA_CHECK(L, ctx, FASCIA_ERR_MEMORY, "emulated device: out of memory");
  L->ctx = ctx;
  L->threads = threads > 0 ? threads : 1;
  *out = L;
  return FASCIA_OK;
}

static void emu_destroy(fascia_launcher *L) {
  if (!L) return;
  for (int s = 0; s < FASCIA_LAUNCH_SLOTS; ++s) free(L->slots[s]);
  free(L);
}

static const char *emu_name(const fascia_launcher *L) {
  (void)L;
  return "host emulation of the device backend";
}

static fascia_status emu_alloc(fascia_launcher *L, size_t bytes, void **out) {
  *out = calloc(1, bytes ? bytes : 1);
  FASCIA_CHECK(*out, L->ctx, FASCIA_ERR_MEMORY, "emulated device: out of memory for %zu bytes", bytes);
  return FASCIA_OK;
}

static void emu_release(fascia_launcher *L, void *p) {
  (void)L;
  free(p);
}

static fascia_status emu_copy_in(fascia_launcher *L, void *dst, const void *src, size_t bytes) {
  (void)L;
  if (bytes) memcpy(dst, src, bytes);
  return FASCIA_OK;
}

static void emu_copy(fascia_launcher *L, void *dst, const void *src, size_t bytes) {
  (void)L;
  if (bytes) memmove(dst, src, bytes);
}

// Host memory is all the emulation has: nothing to lock.
static int emu_pin(fascia_launcher *L, void *host, size_t bytes) {
  (void)L, (void)host, (void)bytes;
  return 0;
}

static void emu_unpin(fascia_launcher *L, void *host) { (void)L, (void)host; }

static void run_kernel(const launch_record *c, int threads) {
  const fascia_dev *D = &c->D;
#pragma omp parallel for num_threads(threads) schedule(static) if (c->n > 256)
  for (int64_t i = 0; i < c->n; ++i) fascia_dev_item(D, c->id, i, c->in, c->out, c->value);
  (void)threads;
}

static void run_reduce(const launch_record *c) {
  fascia_real sum[4] = {0, 0, 0, 0};
  for (int64_t i = 0; i < c->n; ++i) {
    fascia_real t[4] = {0, 0, 0, 0};
    fascia_dev_term(&c->D, c->id, i, c->a, c->b, t);
    for (int k = 0; k < 4; ++k) sum[k] += t[k];
  }
  fascia_dev_scalar_step(&c->D, c->step, sum);
}

static void run_record(fascia_launcher *L, const launch_record *c) {
  if (L->recording) {
    const int s = L->recording - 1;
    if (L->slot_count[s] == L->slot_capacity[s]) {
      const int capacity = L->slot_capacity[s] ? 2 * L->slot_capacity[s] : 64;
      launch_record *grown = realloc(L->slots[s], (size_t)capacity * sizeof *grown);
      if (!grown) {
        L->failed = 1;
        return;
      }
      L->slots[s] = grown;
      L->slot_capacity[s] = capacity;
    }
    L->slots[s][L->slot_count[s]++] = *c;
    return;
  }
  if (c->reduction) run_reduce(c);
  else run_kernel(c, L->threads);
}

static void emu_kernel(fascia_launcher *L, const fascia_dev *D, fascia_dev_kernel kernel, int64_t n,
                       const fascia_real *in, fascia_real *out, fascia_real value) {
  launch_record c;
  memset(&c, 0, sizeof c);
  c.id = kernel, c.n = n, c.in = in, c.out = out, c.value = value, c.D = *D;
  run_record(L, &c);
}

static void emu_reduce(fascia_launcher *L, const fascia_dev *D, fascia_dev_terms terms, int64_t n,
                       const fascia_real *a, const fascia_real *b, fascia_dev_step step) {
  launch_record c;
  memset(&c, 0, sizeof c);
  c.reduction = 1, c.id = terms, c.n = n, c.a = a, c.b = b, c.step = step, c.D = *D;
  run_record(L, &c);
}

static fascia_status emu_record(fascia_launcher *L, int slot, void (*body)(void *), void *arg) {
  FASCIA_CHECK(slot >= 0 && slot < FASCIA_LAUNCH_SLOTS, L->ctx, FASCIA_ERR_ARGUMENT, "launcher: bad slot %d", slot);
  L->slot_count[slot] = 0;
  L->recording = slot + 1;
  body(arg);
  L->recording = 0;
  FASCIA_CHECK(!L->failed, L->ctx, FASCIA_ERR_MEMORY, "emulated device: out of memory recording launches");
  return FASCIA_OK;
}

static void emu_replay(fascia_launcher *L, int slot) {
  for (int k = 0; k < L->slot_count[slot]; ++k) {
    const launch_record *c = &L->slots[slot][k];
    if (c->reduction) run_reduce(c);
    else run_kernel(c, L->threads);
  }
}

static fascia_status emu_finish(fascia_launcher *L) {
  (void)L;
  return FASCIA_OK;
}

// Launches run when they are made, so send and receive are plain copies.
const fascia_launcher_ops fascia_launcher_emulated = {
    .backend = "emulated",
    .create = emu_create,
    .destroy = emu_destroy,
    .device_name = emu_name,
    .alloc = emu_alloc,
    .release = emu_release,
    .upload = emu_copy_in,
    .download = emu_copy_in,
    .copy = emu_copy,
    .pin = emu_pin,
    .unpin = emu_unpin,
    .send = emu_copy,
    .receive = emu_copy,
    .kernel = emu_kernel,
    .reduce = emu_reduce,
    .record = emu_record,
    .replay = emu_replay,
    .finish = emu_finish,
};
