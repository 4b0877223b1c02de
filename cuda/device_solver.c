// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The device backend of the core's Newton loop (sim/contract/backend.h): the
// model's arrays uploaded once, and every operation of the loop run on the
// device through a launcher (launch.h), on a GPU or in the host emulation.
// The loop reads a few scalars per operation (energy, slope, gradient norm);
// conjugate gradients run entirely on the device, their scalar logic in
// kernels (items.h), as recorded launch sequences (CUDA graphs): a fixed
// count in one sequence, a tolerance in chunks whose end the host checks.
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "contract/backend.h"
#include "launch.h"

#define CG_CHUNK 8 // CG iterations per recorded chunk in tolerance mode
#define MAX_BUFFERS 96 // the model, the state and work (about 50), the patches (16)
#define MAX_PINNED 8

enum { SLOT_CG_FIXED = 0, SLOT_CG_CHUNK = 1 };

typedef struct fascia_device {
  fascia_backend base;
  fascia_ctx *ctx;
  int32_t frame_count;
  const fascia_launcher_ops *ops;
  fascia_launcher *L;
  fascia_dev D;                  ///< device pointers, passed to every launch
  fascia_dev_settings set;       ///< host copy of D.set
  fascia_dev_settings *set_dev;
  fascia_dev_scalars sc;         ///< host copy of D.sc after pull_scalars
  fascia_dev_scalars *sc_dev;
  void *buffers[MAX_BUFFERS];
  int buffer_count;
  size_t bytes;                  ///< device memory held
  int recorded[FASCIA_LAUNCH_SLOTS];
  fascia_dev_kernel stiffness;   ///< the stiffness product kernel for this model's terms
  void *pinned[MAX_PINNED];      ///< the host arrays that cross every step, page-locked
  int pinned_count;
  fascia_real *zeros;            ///< host [6N]
  fascia_real *result;           ///< host [19N]: a solve's x, q, d, gradient (device_finish)
  // what crosses at every step's begin: the masks and the frame loads (a
  // caller may fix DOFs, drive an organ or change loads between steps, as
  // on the CPU) and the bodies' per-step values
  const unsigned char *host_mask, *host_full_mask;
  const fascia_real *host_load;
  fascia_real *frame_load;             ///< device copy (D.frame_load)
  const fascia_pt_bodies *host_bodies; ///< NULL: no rigid organs
  unsigned char *mask, *full_mask;     ///< device copies (D.mask, D.full_mask)
  unsigned char *active;
  fascia_real *world_inertia, *target;
  fascia_real *sample_output;          ///< [5S] the outputs' queries (FASCIA_K_SAMPLE_OUTPUT)
  char name[256];
} fascia_device;

static int device_supports(const fascia_backend_setup *setup, char *why, size_t size) {
  const fascia_solver_def *def = setup->def;
  const char *reason = NULL;
  if (def->linear_solver == FASCIA_LINEAR_DIRECT) reason = "the direct linear solver runs on the CPU only";
  else if (def->assembled == 1) reason = "the assembled matrix runs on the CPU only (the device is matrix-free)";
  else if (def->single_precision_matrix == 1) reason = "the float matrix runs on the CPU only";
  if (reason && why) snprintf(why, size, "%s", reason);
  return reason == NULL;
}

// ---------------------------------------------------------------- memory --

static fascia_status make(fascia_device *dev, size_t bytes, void **out) {
  FASCIA_CHECK(dev->buffer_count < MAX_BUFFERS, dev->ctx, FASCIA_ERR_INTERNAL, "device: too many buffers");
  FASCIA_TRY(dev->ops->alloc(dev->L, bytes, out));
  dev->buffers[dev->buffer_count++] = *out;
  dev->bytes += bytes;
  return FASCIA_OK;
}

static fascia_status put(fascia_device *dev, const void *host, size_t bytes, void **out) {
  FASCIA_TRY(make(dev, bytes, out));
  return bytes ? dev->ops->upload(dev->L, *out, host, bytes) : FASCIA_OK;
}

#define MAKE(field, count, type) FASCIA_TRY(make(dev, (size_t)(count) * sizeof(type), (void **)&D->field))
#define PUT(field, host, count, type) FASCIA_TRY(put(dev, (host), (size_t)(count) * sizeof(type), (void **)&D->field))

// The volumetric patches' tables and work (sim/point/patch.h), and the
// samples' pressures the per-sample math reads.
static fascia_status upload_patches(fascia_device *dev, const fascia_pt_patches *h, int64_t E) {
  fascia_dev *D = &dev->D;
  const int64_t P = h->count, N = D->frame_count, S = D->sample_count;
  D->patches.count = h->count;
  PUT(patches.patch_offsets, h->patch_offsets, P + 1, int32_t);
  PUT(patches.patch_samples, h->patch_samples, h->patch_offsets[P], int32_t);
  PUT(patches.support_offsets, h->support_offsets, P + 1, int32_t);
  PUT(patches.entry_frame, h->entry_frame, E, int32_t);
  PUT(patches.entry_patch, h->entry_patch, E, int32_t);
  PUT(patches.pair_entry, h->pair_entry, D->pair_count, int32_t);
  PUT(patches.frame_entry_offsets, h->frame_entry_offsets, N + 1, int32_t);
  PUT(patches.frame_entries, h->frame_entries, E, int32_t);
  PUT(patches.lambda, h->lambda, P, fascia_real);
  PUT(patches.volume, h->volume, P, fascia_real);
  PUT(patches.law, h->law, P, int32_t);
  MAKE(patches.theta, P, fascia_real);
  MAKE(patches.energy, P, fascia_real);
  MAKE(patches.rate, P, fascia_real);
  MAKE(patches.entry_gradient, 6 * E, fascia_real);
  MAKE(patches.sample_pressure, S, fascia_real);
  D->pm.sample_pressure = D->patches.sample_pressure;
  return FASCIA_OK;
}

// The enhanced strain modes on the patches (sim/point/modes.h): their
// tables, and the work the per-patch math writes; the samples' enhanced F
// the per-sample math reads.
static fascia_status upload_modes(fascia_device *dev, const fascia_pt_modes *h, int64_t E) {
  fascia_dev *D = &dev->D;
  const int64_t P = D->patches.count, S = D->sample_count;
  D->modes_count = D->patches.count;
  PUT(modes.active, h->active, P, int32_t);
  PUT(modes.xi_max, h->xi_max, 3 * P, fascia_real);
  PUT(modes.sample_xi, h->sample_xi, 3 * S, fascia_real);
  MAKE(modes.amplitude, 9 * P, fascia_real);
  MAKE(modes.failed, P, int32_t);
  PUT(modes.sample_enhanced, h->sample_enhanced, 9 * S, fascia_real); // zero outside the modes' patches
  MAKE(modes.entry_factor, 54 * E, fascia_real);
  MAKE(modes.reduced, 9 * P, fascia_real);
  D->pm.sample_enhanced = D->modes.sample_enhanced;
  return FASCIA_OK;
}

// Rigid organs: the bodies' table (point/body.h), the full mask and the
// operator's two vectors; the per-step values cross at each begin.
static fascia_status upload_bodies(fascia_device *dev, const fascia_backend_setup *setup) {
  const fascia_pt_bodies *h = setup->bodies;
  fascia_dev *D = &dev->D;
  fascia_pt_bodies *B = &D->bodies;
  const int64_t K = h->count, N = D->frame_count, F = h->frame_offsets[K];
  dev->host_bodies = h;
  dev->host_full_mask = setup->full_mask;
  FASCIA_TRY(put(dev, setup->full_mask, 6 * (size_t)N, (void **)&dev->full_mask));
  D->full_mask = dev->full_mask;
  B->count = h->count;
  PUT(bodies.frame_offsets, h->frame_offsets, K + 1, int32_t);
  PUT(bodies.frames, h->frames, F, int32_t);
  PUT(bodies.frame_body, h->frame_body, N, int32_t);
  PUT(bodies.master, h->master, K, int32_t);
  PUT(bodies.rest_position, h->rest_position, 3 * N, fascia_real);
  B->rest_rotation = D->rest_rotation;
  PUT(bodies.centre, h->centre, 3 * K, fascia_real);
  PUT(bodies.mass, h->mass, K, fascia_real);
  FASCIA_TRY(make(dev, (size_t)K, (void **)&dev->active));
  FASCIA_TRY(make(dev, 9 * (size_t)K * sizeof(fascia_real), (void **)&dev->world_inertia));
  FASCIA_TRY(make(dev, 6 * (size_t)K * sizeof(fascia_real), (void **)&dev->target));
  B->active = dev->active;
  B->world_inertia = dev->world_inertia;
  B->target = dev->target;
  MAKE(bodies.geometric, 9 * K, fascia_real);
  MAKE(prolonged, 6 * N, fascia_real);
  MAKE(product, 6 * N, fascia_real);
  return FASCIA_OK;
}

// The model's and the system's arrays whose device column (the contract's
// model_table.h, system_table.h) names a member of fascia_dev: DEVICE(member)
// uploads the array into D->member, POINT(member) into D->pm.member, HOST
// leaves it on the host.
static fascia_status put_row(fascia_device *dev, const fascia_array_data *row, void **slot) {
  return put(dev, row->data, row->bytes, slot);
}

static fascia_status upload_arrays(fascia_device *dev, const fascia_backend_setup *setup) {
  fascia_dev *D = &dev->D;
  void **slot;
#define HOST NULL
#define DEVICE(member) (void **)&D->member
#define POINT(member) DEVICE(pm.member)
#define MODEL(field, kind, count, plus, width, path, unit, fill, flags, since, device)                                \
  if ((slot = device)) FASCIA_TRY(put_row(dev, setup->model_arrays + FASCIA_MA_ID_##field, slot));
#define SYSTEM(field, type, count, width, device)                                                                     \
  if ((slot = device)) FASCIA_TRY(put_row(dev, setup->system_arrays + FASCIA_SA_ID_##field, slot));
  FASCIA_MODEL_ARRAYS(MODEL)
  FASCIA_SYSTEM_ARRAYS(SYSTEM)
#undef SYSTEM
#undef MODEL
#undef POINT
#undef DEVICE
#undef HOST
  return FASCIA_OK;
}

static fascia_status upload_model(fascia_device *dev, const fascia_backend_setup *setup) {
  const fascia_model *m = setup->model;
  const int64_t N = m->frame_count, Sn = m->sample_count, P = m->pair_count;
  fascia_dev *D = &dev->D;
  D->frame_count = m->frame_count;
  D->sample_count = m->sample_count;
  D->pair_count = P;
  D->max_neighbours = setup->max_neighbours;
  // the leanest stiffness kernel that has every term this model uses
  int coupling = 0, smoothing = 0;
  const fascia_real *sample_coupling = setup->system_arrays[FASCIA_SA_ID_sample_coupling].data;
  const fascia_real *sample_curvature = setup->system_arrays[FASCIA_SA_ID_sample_curvature].data;
  for (int64_t s = 0; s < Sn; ++s) {
    coupling |= sample_coupling[s] > 0;
    smoothing |= sample_curvature[s] > 0;
  }
  dev->stiffness = coupling    ? FASCIA_K_SAMPLE_STIFFNESS
                   : smoothing ? FASCIA_K_SAMPLE_STIFFNESS_SMOOTHING
                               : FASCIA_K_SAMPLE_STIFFNESS_PAPER;
  for (int c = 0; c < 3; ++c) D->gravity[c] = setup->gravity[c];
  FASCIA_TRY(upload_arrays(dev, setup));
  dev->frame_load = (fascia_real *)D->frame_load; // sent again at every step's begin
  FASCIA_TRY(put(dev, setup->mask, 6 * (size_t)N, (void **)&dev->mask));
  D->mask = D->full_mask = dev->mask;
  if (setup->bodies) FASCIA_TRY(upload_bodies(dev, setup));
  if (setup->patches->count > 0) FASCIA_TRY(upload_patches(dev, setup->patches, setup->patch_entries));
  if (setup->modes) FASCIA_TRY(upload_modes(dev, setup->modes, setup->patch_entries));
  // state and work
  MAKE(x_base, 3 * N, fascia_real);
  MAKE(q_base, 4 * N, fascia_real);
  MAKE(x, 3 * N, fascia_real);
  MAKE(q, 4 * N, fascia_real);
  MAKE(A, 9 * N, fascia_real);
  MAKE(A_mass, 9 * N, fascia_real);
  MAKE(d, 6 * N, fascia_real);
  MAKE(d_trial, 6 * N, fascia_real);
  MAKE(saved, 13 * N, fascia_real);
  MAKE(target, 6 * N, fascia_real);
  MAKE(target_M, 6 * N, fascia_real);
  MAKE(g, 6 * N, fascia_real);
  MAKE(g_trial, 6 * N, fascia_real);
  MAKE(p, 6 * N, fascia_real);
  MAKE(r, 6 * N, fascia_real);
  MAKE(z, 6 * N, fascia_real);
  MAKE(dir, 6 * N, fascia_real);
  MAKE(Ad, 6 * N, fascia_real);
  MAKE(mass_blocks, 36 * N, fascia_real);
  MAKE(blocks, 36 * N, fascia_real);
  MAKE(inverse, 36 * N, fascia_real);
  MAKE(damping, 6 * N, fascia_real);
  MAKE(torque, 3 * N, fascia_real);
  MAKE(frame_terms, 4 * N, fascia_real);
  MAKE(pair_buffer, 6 * P, fascia_real);
  MAKE(pair_mass, 6 * P, fascia_real);
  if (setup->def->precond != FASCIA_PRECOND_NONE) MAKE(pair_blocks, 36 * P, fascia_real);
  MAKE(cache, Sn * FASCIA_PT_CACHE_SIZE, fascia_real);
  MAKE(sample_energy, Sn, fascia_real);
  MAKE(sample_flags, Sn, int);
  FASCIA_TRY(make(dev, 5 * (size_t)Sn * sizeof(fascia_real), (void **)&dev->sample_output));
  FASCIA_TRY(make(dev, sizeof(fascia_dev_settings), (void **)&dev->set_dev));
  FASCIA_TRY(make(dev, sizeof(fascia_dev_scalars), (void **)&dev->sc_dev));
  D->set = dev->set_dev;
  D->sc = dev->sc_dev;
  return FASCIA_OK;
}

#undef MAKE
#undef PUT

static void device_destroy(fascia_backend *backend) {
  fascia_device *dev = (fascia_device *)backend;
  if (!dev) return;
  for (int k = 0; k < dev->buffer_count; ++k) dev->ops->release(dev->L, dev->buffers[k]);
  for (int k = 0; k < dev->pinned_count; ++k) dev->ops->unpin(dev->L, dev->pinned[k]);
  if (dev->L) dev->ops->destroy(dev->L);
  free(dev->zeros);
  free(dev->result);
  free(dev);
}

static fascia_status device_create(const fascia_backend_setup *setup, const fascia_backend_ops *backend,
                                   const fascia_launcher_ops *ops, fascia_backend **out) {
  *out = NULL;
  fascia_device *dev = calloc(1, sizeof *dev);
  FASCIA_CHECK(dev, setup->ctx, FASCIA_ERR_MEMORY, "device: out of memory");
  dev->base.ops = backend;
  dev->ctx = setup->ctx;
  dev->frame_count = setup->model->frame_count;
  dev->host_mask = setup->mask;
  dev->host_load = setup->model->frame_load;
  dev->ops = ops;
  dev->zeros = calloc(6 * (size_t)dev->frame_count + 1, sizeof(fascia_real));
  // on pages of its own: page-locking works page by page
  const size_t page = 4096, result_bytes = (19 * (size_t)dev->frame_count + 1) * sizeof(fascia_real);
  dev->result = aligned_alloc(page, (result_bytes + page - 1) / page * page);
  if (dev->result) memset(dev->result, 0, result_bytes);
  fascia_status status =
      dev->zeros && dev->result ? FASCIA_OK : FASCIA_FAIL(setup->ctx, FASCIA_ERR_MEMORY, "device: out of memory");
  if (status == FASCIA_OK) status = ops->create(setup->ctx, setup->threads, &dev->L);
  if (status == FASCIA_OK) status = upload_model(dev, setup);
  if (status == FASCIA_OK) status = ops->finish(dev->L);
  if (status != FASCIA_OK) {
    device_destroy(&dev->base);
    return status;
  }
  // the state crosses every step: page-locked, it copies at the link's rate
  // and without the runtime's staging copy (where locking fails, it still
  // copies, only slower)
  for (int k = 0; k < setup->crossing_count && dev->pinned_count < MAX_PINNED; ++k)
    if (ops->pin(dev->L, setup->crossing[k], setup->crossing_bytes[k])) dev->pinned[dev->pinned_count++] = setup->crossing[k];
  if (dev->pinned_count < MAX_PINNED && ops->pin(dev->L, dev->result, 19 * (size_t)dev->frame_count * sizeof(fascia_real)))
    dev->pinned[dev->pinned_count++] = dev->result;
  const fascia_solver_def *def = setup->def;
  dev->set.cg_limits.max = def->cg_iterations;
  dev->set.cg_limits.fixed = def->cg_fixed;
  dev->set.cg_limits.tolerance = def->cg_tolerance;
  dev->set.consistent_mass = def->mass == FASCIA_MASS_CONSISTENT;
  dev->set.precond = (int32_t)def->precond;
  dev->set.gravity_scale = 1;
  dev->set.project = 1;
  const char *terms = dev->stiffness == FASCIA_K_SAMPLE_STIFFNESS_PAPER       ? "the paper's terms"
                      : dev->stiffness == FASCIA_K_SAMPLE_STIFFNESS_SMOOTHING ? "no rotation coupling"
                                                                              : "all terms";
  snprintf(dev->name, sizeof dev->name, "%s, %.1f MB of device memory for the model, stiffness kernel: %s",
           ops->device_name(dev->L), (double)dev->bytes / (1 << 20), terms);
  *out = &dev->base;
  return FASCIA_OK;
}

static const char *device_describe(const fascia_backend *backend) { return ((const fascia_device *)backend)->name; }

// ------------------------------------------------------------ launches --

static void kernel(fascia_device *dev, fascia_dev_kernel k, int64_t n, const fascia_real *in, fascia_real *out,
                   fascia_real value) {
  dev->ops->kernel(dev->L, &dev->D, k, n, in, out, value);
}

static void reduce(fascia_device *dev, fascia_dev_terms t, int64_t n, const fascia_real *a, const fascia_real *b,
                   fascia_dev_step step) {
  dev->ops->reduce(dev->L, &dev->D, t, n, a, b, step);
}

static fascia_status push_settings(fascia_device *dev) {
  return dev->ops->upload(dev->L, dev->set_dev, &dev->set, sizeof dev->set);
}

static fascia_status pull_scalars(fascia_device *dev) {
  return dev->ops->download(dev->L, &dev->sc, dev->sc_dev, sizeof dev->sc);
}

// The first sample whose flags have bit `flag`, -1 if none (downloads the
// flags: only on the way to a message).
static int32_t first_flagged(fascia_device *dev, int flag) {
  const int32_t S = dev->D.sample_count;
  int *flags = malloc((size_t)S * sizeof *flags + 1);
  int32_t first = -1;
  if (flags && dev->ops->download(dev->L, flags, dev->D.sample_flags, (size_t)S * sizeof *flags) == FASCIA_OK)
    for (int32_t s = 0; s < S && first < 0; ++s)
      if (flags[s] & flag) first = s;
  free(flags);
  return first;
}

// The step objective Phi at d + alpha p (d_trial), its projected gradient
// in g_trial, and |g_trial|^2 (newton.c objective()).
static fascia_status objective(fascia_device *dev, fascia_real alpha, fascia_real *phi, fascia_real *gg) {
  fascia_dev *D = &dev->D;
  const int64_t N = D->frame_count, n = 6 * N, S = D->sample_count;
  kernel(dev, FASCIA_K_TRIAL, n, NULL, NULL, alpha);
  if (D->bodies.count > 0) kernel(dev, FASCIA_K_BODY_EXPAND, N, NULL, NULL, 0); // slaves follow their master
  kernel(dev, FASCIA_K_STATE, N, NULL, NULL, 0);
  if (D->modes_count > 0) kernel(dev, FASCIA_K_MODES_EVALUATE, D->modes_count, NULL, NULL, 0);
  if (D->patches.count > 0) kernel(dev, FASCIA_K_PATCH_EVALUATE, D->patches.count, NULL, NULL, 0);
  kernel(dev, FASCIA_K_SAMPLE_GRADIENT, S, NULL, NULL, 0);
  if (dev->set.consistent_mass && (dev->set.c1 != 0 || dev->set.c2 != 0))
    kernel(dev, FASCIA_K_SAMPLE_MASS, S, D->d_trial, NULL, 0);
  kernel(dev, FASCIA_K_FRAME_GRADIENT, N, NULL, NULL, 0);
  if (D->bodies.count > 0) kernel(dev, FASCIA_K_BODY_GRADIENT, D->bodies.count, NULL, NULL, 0);
  reduce(dev, FASCIA_T_SAMPLES, S, NULL, NULL, FASCIA_S_SAMPLES);
  if (D->patches.count > 0) reduce(dev, FASCIA_T_PATCHES, D->patches.count, NULL, NULL, FASCIA_S_PATCHES);
  reduce(dev, FASCIA_T_FRAMES, N, NULL, NULL, FASCIA_S_OBJECTIVE);
  FASCIA_TRY(pull_scalars(dev));
  *phi = dev->sc.phi;
  *gg = dev->sc.gradient_norm2;
  if (dev->sc.modes_failed > 0)
    return FASCIA_FAIL(dev->ctx, FASCIA_ERR_NUMERIC,
                       "%.0f patches: their enhanced strain modes found no minimum at this state; the step is too "
                       "large or the model is unstable",
                       dev->sc.modes_failed);
  const int32_t s = dev->sc.nonfinite > 0 ? first_flagged(dev, FASCIA_PT_FLAG_NONFINITE) : -1;
  if (s >= 0)
    return FASCIA_FAIL(dev->ctx, FASCIA_ERR_NUMERIC, "sample %d: energy is not finite (deformation gradient blew up)",
                       (int)s);
  if (!isfinite(dev->sc.energy_internal + dev->sc.energy_external))
    return FASCIA_FAIL(dev->ctx, FASCIA_ERR_NUMERIC, "the energy of gravity and the frame loads is not finite at "
                       "this state (a frame's position or a load overflowed)");
  return isfinite(*phi) ? FASCIA_OK : FASCIA_FAIL(dev->ctx, FASCIA_ERR_NUMERIC, "solver: the energy is not finite");
}

// The modes' factors at the state of the last objective (the Hessian's
// condensed terms read them).
static void modes_tangent(fascia_device *dev) {
  if (dev->D.modes_count > 0) kernel(dev, FASCIA_K_MODES_TANGENT, dev->D.modes_count, NULL, NULL, 0);
}

// Diagonal blocks and preconditioner of the Newton operator at the state of
// the last objective (precond.c)
static void build_precond(fascia_device *dev) {
  const fascia_dev *D = &dev->D;
  if (dev->set.precond == FASCIA_PRECOND_NONE) return;
  kernel(dev, FASCIA_K_PAIR_DIAGONAL, D->pair_count, NULL, NULL, 0);
  kernel(dev, FASCIA_K_FRAME_PRECOND, D->frame_count, NULL, NULL, 0);
  if (D->bodies.count > 0) kernel(dev, FASCIA_K_BODY_DIAGONAL, D->bodies.count, NULL, NULL, 0);
}

// The Levenberg weights and the operator's scale from the diagonal blocks
static void build_damping(fascia_device *dev) {
  const int64_t n = 6 * (int64_t)dev->D.frame_count;
  kernel(dev, FASCIA_K_DAMPING, n, NULL, NULL, 0);
  reduce(dev, FASCIA_T_SUM, n, dev->D.damping, NULL, FASCIA_S_SCALE);
  kernel(dev, FASCIA_K_DAMPING_WEIGHT, n, NULL, NULL, 0);
}

typedef struct cg_body_arg {
  fascia_device *dev;
  int iterations;
} cg_body_arg;

// The launches before the operator's reduction: the pair products of z
// (with rigid organs, of P z, then A P z on every frame and its restriction
// to the masters), run only while CG runs.
static void operator_products(fascia_device *dev) {
  const fascia_dev *D = &dev->D;
  const int64_t N = D->frame_count, S = D->sample_count;
  const fascia_real *in = D->z;
  if (D->bodies.count > 0) {
    kernel(dev, FASCIA_K_BODY_PROLONG, N, NULL, NULL, 0);
    in = D->prolonged;
  }
  kernel(dev, dev->stiffness, S, in, NULL, 0);
  if (D->patches.count > 0) kernel(dev, FASCIA_K_PATCH_RATE, D->patches.count, in, NULL, 0);
  if (D->modes_count > 0) kernel(dev, FASCIA_K_MODES_REDUCE, D->modes_count, in, NULL, 0);
  if (dev->set.consistent_mass) kernel(dev, FASCIA_K_CG_SAMPLE_MASS, S, in, NULL, 0); // lumped: per frame
  if (D->bodies.count > 0) {
    kernel(dev, FASCIA_K_FRAME_OPERATOR, N, NULL, NULL, 0);
    kernel(dev, FASCIA_K_BODY_OPERATOR, D->bodies.count, NULL, NULL, 0);
  }
}

// `iterations` CG iterations; each one stops short on the device once CG
// has ended (the kernels test sc->cg.running and sc->cg.action)
static void cg_body(void *argument) {
  const cg_body_arg *arg = argument;
  fascia_device *dev = arg->dev;
  const int64_t N = dev->D.frame_count;
  for (int it = 0; it < arg->iterations; ++it) {
    // the operator's reduction makes dir and A dir of the products
    operator_products(dev);
    reduce(dev, FASCIA_T_OPERATOR, N, NULL, NULL, FASCIA_S_CG_CURVATURE);
    reduce(dev, FASCIA_T_CG_UPDATE, N, NULL, NULL, FASCIA_S_CG_RESIDUAL);
  }
}

// Solves A p = -g on the free DOFs (cg.c); reports iterations and negative
// curvature.
static fascia_status cg_solve(fascia_device *dev, fascia_solve_report *rep) {
  const int fixed = dev->set.cg_limits.fixed, slot = fixed ? SLOT_CG_FIXED : SLOT_CG_CHUNK;
  reduce(dev, FASCIA_T_CG_START, dev->D.frame_count, NULL, NULL, FASCIA_S_CG_START);
  if (!dev->recorded[slot]) {
    cg_body_arg arg = {dev, fixed ? dev->set.cg_limits.max : CG_CHUNK};
    FASCIA_TRY(dev->ops->record(dev->L, slot, cg_body, &arg));
    dev->recorded[slot] = 1;
  }
  if (fixed) {
    dev->ops->replay(dev->L, slot);
    FASCIA_TRY(pull_scalars(dev));
  } else {
    for (int done = 0; done < dev->set.cg_limits.max; done += CG_CHUNK) {
      dev->ops->replay(dev->L, slot);
      FASCIA_TRY(pull_scalars(dev)); // four bytes that matter, every CG_CHUNK iterations
      if (!dev->sc.cg.running) break;
    }
  }
  rep->cg_iterations += dev->sc.cg.iterations;
  rep->negative_curvature += dev->sc.cg.negative_curvature;
  return FASCIA_OK;
}

static fascia_status slope(fascia_device *dev, fascia_real *out) {
  reduce(dev, FASCIA_T_DOT, 6 * (int64_t)dev->D.frame_count, dev->D.p, dev->D.g, FASCIA_S_STORE);
  FASCIA_TRY(pull_scalars(dev));
  *out = dev->sc.sum[0];
  return FASCIA_OK;
}

// ------------------------------------------------------ the Newton loop --

// Anchor, increments and step terms up; the mass at the anchor for a
// dynamic step.
static fascia_status device_begin(fascia_backend *backend, const fascia_step_values *v, fascia_solve_report *rep) {
  fascia_device *dev = (fascia_device *)backend;
  fascia_dev *D = &dev->D;
  const size_t N = (size_t)dev->frame_count, n = 6 * N;
  const fascia_launcher_ops *ops = dev->ops;
  rep->direct = 0;
  // no waits: the host leaves these arrays alone until the step's first
  // evaluation waits for its scalars
  ops->send(dev->L, D->x_base, v->x_base, 3 * N * sizeof(fascia_real));
  ops->send(dev->L, D->q_base, v->q_base, 4 * N * sizeof(fascia_real));
  ops->send(dev->L, D->d, v->d, n * sizeof(fascia_real));
  ops->send(dev->L, dev->mask, dev->host_mask, n);
  ops->send(dev->L, dev->frame_load, dev->host_load, n * sizeof(fascia_real));
  const fascia_pt_bodies *bodies = dev->host_bodies;
  if (bodies) {
    const size_t K = (size_t)bodies->count;
    ops->send(dev->L, dev->full_mask, dev->host_full_mask, n);
    ops->send(dev->L, dev->active, bodies->active, K);
    ops->send(dev->L, dev->world_inertia, bodies->world_inertia, 9 * K * sizeof(fascia_real));
    ops->send(dev->L, dev->target, bodies->target, 6 * K * sizeof(fascia_real));
  }
  dev->set.c1 = v->c1;
  dev->set.c2 = v->c2;
  dev->set.mass_coefficient = v->c1 + v->c2;
  dev->set.shift = 0;
  dev->set.gravity_scale = v->gravity_scale;
  dev->set.jacobian = v->dynamic;
  FASCIA_TRY(push_settings(dev));
  if (!v->dynamic) return FASCIA_OK;
  ops->send(dev->L, D->target, v->inertia_target, n * sizeof(fascia_real));
  kernel(dev, FASCIA_K_MASS_SNAPSHOT, (int64_t)N, NULL, NULL, 0);
  kernel(dev, FASCIA_K_LUMPED_MASS, (int64_t)N, NULL, NULL, 0);
  if (dev->set.consistent_mass) kernel(dev, FASCIA_K_SAMPLE_MASS, D->sample_count, D->target, NULL, 0);
  kernel(dev, FASCIA_K_FRAME_MASS_APPLY, (int64_t)N, D->target, D->target_M, 0);
  reduce(dev, FASCIA_T_DOT, (int64_t)n, D->target, D->target_M, FASCIA_S_TARGET);
  return FASCIA_OK;
}

static fascia_status device_evaluate(fascia_backend *backend, fascia_real alpha, int current,
                                     fascia_trial_values *out) {
  fascia_device *dev = (fascia_device *)backend;
  FASCIA_TRY(objective(dev, current ? 0 : alpha, &out->phi, &out->gradient_norm2));
  out->energy_size = fabs(dev->sc.energy_internal) + fabs(dev->sc.energy_external);
  if (current) kernel(dev, FASCIA_K_COPY_GRADIENT, 6 * (int64_t)dev->frame_count, NULL, NULL, 0);
  return FASCIA_OK;
}

static fascia_status device_prepare(fascia_backend *backend, fascia_solve_report *rep) {
  fascia_device *dev = (fascia_device *)backend;
  const double t = fascia_now_ms();
  modes_tangent(dev);
  build_precond(dev);
  build_damping(dev);
  FASCIA_TRY(dev->ops->finish(dev->L));
  rep->profile.precond_ms += fascia_now_ms() - t;
  return FASCIA_OK;
}

static fascia_status device_direction(fascia_backend *backend, fascia_real *shift, fascia_real *out,
                                      fascia_solve_report *rep) {
  fascia_device *dev = (fascia_device *)backend;
  if (dev->set.shift != *shift) {
    dev->set.shift = *shift;
    FASCIA_TRY(push_settings(dev));
  }
  FASCIA_TRY(cg_solve(dev, rep));
  if (dev->set.jacobian) kernel(dev, FASCIA_K_STEP_ROTATION, dev->frame_count, NULL, NULL, 0);
  FASCIA_TRY(slope(dev, out));
  if (!(*out < 0)) { // not a descent direction: preconditioned gradient
    kernel(dev, FASCIA_K_PRECOND_DESCENT, dev->frame_count, NULL, NULL, 0);
    FASCIA_TRY(slope(dev, out));
  }
  return FASCIA_OK;
}

// static: re-anchor at the accepted state, so d = 0 and the Hessian of the
// next iteration is exact; dynamic: keep the increments
static void device_accept(fascia_backend *backend) {
  fascia_device *dev = (fascia_device *)backend;
  const int64_t N = dev->frame_count;
  if (dev->set.jacobian) kernel(dev, FASCIA_K_ACCEPT_DYNAMIC, 6 * N, NULL, NULL, 0);
  else kernel(dev, FASCIA_K_ACCEPT_STATIC, N, NULL, NULL, 0);
}

static void device_save(fascia_backend *backend) {
  fascia_device *dev = (fascia_device *)backend;
  kernel(dev, FASCIA_K_SAVE, dev->frame_count, NULL, NULL, 0);
}

static void device_restore(fascia_backend *backend) {
  fascia_device *dev = (fascia_device *)backend;
  kernel(dev, FASCIA_K_RESTORE, dev->frame_count, NULL, NULL, 0);
}

// The state of the last evaluation back to the host, into the backend's
// own arrays, with its energies and inversions.
static fascia_status device_finish(fascia_backend *backend, fascia_step_result *result) {
  fascia_device *dev = (fascia_device *)backend;
  const size_t N = (size_t)dev->frame_count;
  const fascia_launcher_ops *ops = dev->ops;
  fascia_real *x = dev->result, *q = x + 3 * N, *d = q + 4 * N, *gradient = d + 6 * N;
  ops->receive(dev->L, x, dev->D.x, 3 * N * sizeof(fascia_real));
  ops->receive(dev->L, q, dev->D.q, 4 * N * sizeof(fascia_real));
  ops->receive(dev->L, d, dev->D.d, 6 * N * sizeof(fascia_real));
  ops->receive(dev->L, gradient, dev->D.g_trial, 6 * N * sizeof(fascia_real));
  FASCIA_TRY(ops->finish(dev->L)); // one wait for the four
  *result = (fascia_step_result){.x = x,
                                 .q = q,
                                 .d = d,
                                 .gradient = gradient,
                                 .energy_internal = dev->sc.energy_internal,
                                 .energy_external = dev->sc.energy_external,
                                 .inverted_count = (int32_t)dev->sc.inverted,
                                 .first_inverted =
                                     dev->sc.inverted > 0 ? first_flagged(dev, FASCIA_PT_FLAG_INVERTED) : -1,
                                 .nonfinite_count = (int32_t)dev->sc.nonfinite,
                                 .first_nonfinite =
                                     dev->sc.nonfinite > 0 ? first_flagged(dev, FASCIA_PT_FLAG_NONFINITE) : -1};
  return FASCIA_OK;
}

// The blow-up rule's strain check, reduced on the device at the state of
// the last evaluation (the one finish gave the host)
static fascia_status device_strain_past(fascia_backend *backend, fascia_real limit, int *past) {
  fascia_device *dev = (fascia_device *)backend;
  if (dev->set.strain_limit != limit) {
    dev->set.strain_limit = limit;
    FASCIA_TRY(push_settings(dev));
  }
  reduce(dev, FASCIA_T_STRAIN, dev->D.sample_count, NULL, NULL, FASCIA_S_STORE);
  FASCIA_TRY(pull_scalars(dev));
  *past = dev->sc.sum[0] > 0;
  return FASCIA_OK;
}

// A query's state between steps: x, q as the anchor with no increment,
// the frames' rotations and the patches' and modes' values there, as an
// evaluation makes them (the next begin sends a step's own anchor).
static fascia_status query_state(fascia_device *dev, const fascia_real *x, const fascia_real *q) {
  fascia_dev *D = &dev->D;
  const size_t N = (size_t)dev->frame_count;
  FASCIA_TRY(dev->ops->upload(dev->L, D->x_base, x, 3 * N * sizeof(fascia_real)));
  FASCIA_TRY(dev->ops->upload(dev->L, D->q_base, q, 4 * N * sizeof(fascia_real)));
  FASCIA_TRY(dev->ops->upload(dev->L, D->d, dev->zeros, 6 * N * sizeof(fascia_real)));
  kernel(dev, FASCIA_K_TRIAL, 6 * (int64_t)N, NULL, NULL, 0);
  kernel(dev, FASCIA_K_STATE, (int64_t)N, NULL, NULL, 0);
  if (D->modes_count > 0) kernel(dev, FASCIA_K_MODES_EVALUATE, D->modes_count, NULL, NULL, 0);
  if (D->patches.count > 0) kernel(dev, FASCIA_K_PATCH_EVALUATE, D->patches.count, NULL, NULL, 0);
  return FASCIA_OK;
}

// The outputs' per-sample values at x, q: the solver's state, which the
// host may have set since the last step; what is asked for comes back.
static fascia_status device_sample_outputs(fascia_backend *backend, const fascia_real *x, const fascia_real *q,
                                           fascia_real *positions, fascia_real *strain, fascia_real *stress) {
  fascia_device *dev = (fascia_device *)backend;
  const size_t S = (size_t)dev->D.sample_count;
  FASCIA_TRY(query_state(dev, x, q));
  kernel(dev, FASCIA_K_SAMPLE_OUTPUT, (int64_t)S, NULL, dev->sample_output, 0);
  if (strain) FASCIA_TRY(dev->ops->download(dev->L, strain, dev->sample_output, S * sizeof(fascia_real)));
  if (stress) FASCIA_TRY(dev->ops->download(dev->L, stress, dev->sample_output + S, S * sizeof(fascia_real)));
  if (positions)
    FASCIA_TRY(dev->ops->download(dev->L, positions, dev->sample_output + 2 * S, 3 * S * sizeof(fascia_real)));
  return FASCIA_OK;
}

// The potential energy's gradient at x, q under the load factor, every
// frame's (the organs' reactions read their fixed and driven frames): the
// evaluation's kernels up to the frames' gradients, unprojected, without
// the bodies' folding. Between steps: the next begin sends a step's own
// loads and settings.
static fascia_status device_energy_gradient(fascia_backend *backend, const fascia_real *x, const fascia_real *q,
                                            fascia_real load_factor, fascia_real *gradient) {
  fascia_device *dev = (fascia_device *)backend;
  fascia_dev *D = &dev->D;
  const size_t N = (size_t)dev->frame_count;
  FASCIA_TRY(dev->ops->upload(dev->L, dev->frame_load, dev->host_load, 6 * N * sizeof(fascia_real)));
  fascia_dev_settings kept = dev->set;
  dev->set.c1 = dev->set.c2 = dev->set.mass_coefficient = dev->set.shift = 0;
  dev->set.jacobian = 0;
  dev->set.gravity_scale = load_factor;
  dev->set.project = 0;
  fascia_status st = push_settings(dev);
  if (st == FASCIA_OK) st = query_state(dev, x, q);
  if (st == FASCIA_OK) {
    kernel(dev, FASCIA_K_SAMPLE_GRADIENT, D->sample_count, NULL, NULL, 0);
    kernel(dev, FASCIA_K_FRAME_GRADIENT, (int64_t)N, NULL, NULL, 0);
    st = dev->ops->download(dev->L, gradient, D->g_trial, 6 * N * sizeof(fascia_real));
  }
  dev->set = kept;
  const fascia_status pushed = push_settings(dev);
  return st != FASCIA_OK ? st : pushed;
}

// ------------------------------------------------------------ operators --

static fascia_status device_gradient(fascia_backend *backend, const fascia_real *x, const fascia_real *q,
                                     fascia_real load_factor, fascia_real *gradient, fascia_real *energy) {
  fascia_device *dev = (fascia_device *)backend;
  const size_t N = (size_t)dev->frame_count;
  FASCIA_TRY(dev->ops->upload(dev->L, dev->D.x_base, x, 3 * N * sizeof(fascia_real)));
  FASCIA_TRY(dev->ops->upload(dev->L, dev->D.q_base, q, 4 * N * sizeof(fascia_real)));
  FASCIA_TRY(dev->ops->upload(dev->L, dev->D.d, dev->zeros, 6 * N * sizeof(fascia_real)));
  dev->set.c1 = dev->set.c2 = dev->set.mass_coefficient = dev->set.shift = 0;
  dev->set.jacobian = 0;
  dev->set.gravity_scale = load_factor;
  FASCIA_TRY(push_settings(dev));
  fascia_real phi, gg;
  FASCIA_TRY(objective(dev, 0, &phi, &gg));
  *energy = phi;
  return dev->ops->download(dev->L, gradient, dev->D.g_trial, 6 * N * sizeof(fascia_real));
}

static fascia_status device_hessian_apply(fascia_backend *backend, const fascia_real *v, fascia_real *out) {
  fascia_device *dev = (fascia_device *)backend;
  const size_t N = (size_t)dev->frame_count;
  fascia_dev_scalars sc = dev->sc;
  sc.cg.running = 1; // the operator kernels run only inside CG
  sc.cg.action = FASCIA_CG_NONE; // as in CG's first iteration: Ad = A z
  FASCIA_TRY(dev->ops->upload(dev->L, dev->sc_dev, &sc, sizeof sc));
  FASCIA_TRY(dev->ops->upload(dev->L, dev->D.z, v, 6 * N * sizeof(fascia_real)));
  modes_tangent(dev);
  operator_products(dev);
  reduce(dev, FASCIA_T_OPERATOR, (int64_t)N, NULL, NULL, FASCIA_S_STORE);
  return dev->ops->download(dev->L, out, dev->D.Ad, 6 * N * sizeof(fascia_real));
}

static fascia_status device_hessian_diagonal(fascia_backend *backend, fascia_real *blocks) {
  fascia_device *dev = (fascia_device *)backend;
  FASCIA_CHECK(dev->set.precond != FASCIA_PRECOND_NONE, dev->ctx, FASCIA_ERR_ARGUMENT,
               "device: no diagonal blocks without a preconditioner");
  modes_tangent(dev);
  build_precond(dev);
  return dev->ops->download(dev->L, blocks, dev->D.blocks, 36 * (size_t)dev->frame_count * sizeof(fascia_real));
}

// ------------------------------------------------------------- backends --

// 1 when the launcher opens a device here, with its name; else why not
static int launcher_available(const fascia_launcher_ops *ops, char *detail, size_t size) {
  fascia_ctx *ctx = NULL;
  fascia_ctx_def def = fascia_ctx_def_default();
  def.threads = 1;
  if (fascia_ctx_create(&def, &ctx) != FASCIA_OK) return 0;
  fascia_launcher *L = NULL;
  const fascia_status st = ops->create(ctx, 1, &L);
  if (detail) snprintf(detail, size, "%s", st == FASCIA_OK ? ops->device_name(L) : fascia_ctx_message(ctx));
  if (L) ops->destroy(L);
  fascia_ctx_destroy(&ctx);
  return st == FASCIA_OK;
}

#define DEVICE_BACKEND_OPS                                                                                            \
  .supports = device_supports, .destroy = device_destroy, .describe = device_describe,                               \
  .begin = device_begin, .evaluate = device_evaluate, .prepare = device_prepare, .direction = device_direction,        \
  .accept = device_accept, .save = device_save, .restore = device_restore, .finish = device_finish,                     \
  .strain_past = device_strain_past, .sample_outputs = device_sample_outputs,                                        \
  .energy_gradient = device_energy_gradient,                                                                          \
  .gradient = device_gradient,                                                                                        \
  .hessian_apply = device_hessian_apply, .hessian_diagonal = device_hessian_diagonal

static int emulated_available(char *detail, size_t size) {
  return launcher_available(&fascia_launcher_emulated, detail, size);
}
static fascia_status emulated_create(const fascia_backend_setup *setup, fascia_backend **out) {
  return device_create(setup, &fascia_backend_emulated, &fascia_launcher_emulated, out);
}
const fascia_backend_ops fascia_backend_emulated = {
    .name = "emulated", .automatic = 0, .available = emulated_available, .create = emulated_create,
    DEVICE_BACKEND_OPS};

#ifdef FASCIA_HAVE_CUDA
static int cuda_available(char *detail, size_t size) { return launcher_available(&fascia_launcher_cuda, detail, size); }
static fascia_status cuda_create(const fascia_backend_setup *setup, fascia_backend **out) {
  return device_create(setup, &fascia_backend_cuda, &fascia_launcher_cuda, out);
}
const fascia_backend_ops fascia_backend_cuda = {
    .name = "cuda", .automatic = 1, .available = cuda_available, .create = cuda_create, DEVICE_BACKEND_OPS};
#else
// A build without the CUDA toolkit: the name is known, and says how to get it.
static int cuda_missing(char *detail, size_t size) {
  if (detail)
    snprintf(detail, size, "this build has no CUDA backend: install the CUDA toolkit (nvcc) and configure with "
                           "-DFASCIA_CUDA=ON");
  return 0;
}
const fascia_backend_ops fascia_backend_cuda = {.name = "cuda", .automatic = 1, .available = cuda_missing};
#endif
