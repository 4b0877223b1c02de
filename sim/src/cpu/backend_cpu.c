// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The CPU backend of the Newton loop (backend.h): the step objective on the
// host system (system.c), the tangent as products or an assembled block
// matrix, directions by its linear solver (linear_solver.c: CG or sparse
// Cholesky), and rigid organs as bodies whose frames follow them (organs.c).
// Like the device, it keeps a step's state in arrays of its own: begin
// copies the step's values in, finish hands the iterate back to be copied.
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "contract/backend.h"
#include "cpu/linear_solver.h"
#include "organs/organs.h"
#include "point/block6.h"
#include "point/frame.h"

// The backend's own arrays, declared once: member, element type, values per
// frame. The members, their allocation, check and freeing follow.
#define CPU_ARRAYS(X)                                                                                                  \
  X(x_base, fascia_real, 3)            /* the anchor: positions */                                                     \
  X(q_base, fascia_real, 4)            /* and rotations */                                                             \
  X(d, fascia_real, 6)                 /* the iterate: increments from the anchor */                                   \
  X(gradient, fascia_real, 6)          /* its gradient */                                                              \
  X(x, fascia_real, 3)                 /* the state of the last evaluation: positions */                               \
  X(q, fascia_real, 4)                 /* and rotations */                                                             \
  X(target_M, fascia_real, 6)          /* M (h u) */                                                                   \
  X(d_trial, fascia_real, 6)           /* the trial d + alpha p */                                                     \
  X(gradient_trial, fascia_real, 6)    /* its gradient */                                                              \
  X(direction, fascia_real, 6)         /* p */                                                                         \
  X(rhs, fascia_real, 6)               /* -gradient, the linear solve's */                                             \
  X(mass_blocks, fascia_real, 36)      /* the lumped mass's 6x6 blocks */                                              \
  X(scratch, fascia_real, 12)          /* M d, then the operator's scratch */                                          \
  X(saved, fascia_real, 13)            /* the watched iterate (cpu_save): anchor x, q and increments */                \
  X(prolonged, fascia_real, 6)         /* the operator's P v for rigid organs */                                       \
  X(frame_moves, unsigned char, 1)     /* a frame with a free unknown, a body's slave included (assembly) */

#define CPU_MEMBER(name, type, width) type *name;
typedef struct cpu_backend {
  fascia_backend base;
  fascia_ctx *ctx;
  fascia_organs *organs;
  const uint64_t *linear_epoch; ///< the solver's: a kept factorization is used while it stays
  fascia_system *sys;
  const fascia_model *model;
  const fascia_solver_def *def;
  const unsigned char *mask;
  int32_t frame_count;
  // the step
  fascia_step_values values;
  fascia_real target_norm;          ///< (h u).M(h u)
  CPU_ARRAYS(CPU_MEMBER)
  const fascia_pt_bodies *bodies; ///< rigid organs (point/body.h), NULL for none
  const unsigned char *full_mask; ///< [6N] every frame the tissue moves (the bodies' slaves too)
  fascia_linear *linear;          ///< the Newton systems' solver: CG or direct, the factorization kept
  fascia_real gradient_norm2, trial_norm2; ///< of the current and the trial gradient (cpu_evaluate)
  fascia_real torque_work;                 ///< the loads' torques' work at the last evaluation (objective)
  char text[96];
} cpu_backend;

static int cpu_available(char *detail, size_t size) {
  if (detail) snprintf(detail, size, "the CPU reference backend");
  return 1;
}

static int cpu_supports(const fascia_backend_setup *setup, char *why, size_t size) {
  (void)setup, (void)why, (void)size;
  return 1;
}

static void cpu_destroy(fascia_backend *backend) {
  cpu_backend *B = (cpu_backend *)backend;
  if (!B) return;
  fascia_linear_destroy(&B->linear);
#define FREE_ARRAY(name, ...) free(B->name);
  CPU_ARRAYS(FREE_ARRAY)
#undef FREE_ARRAY
  free(B);
}

static fascia_status cpu_create(const fascia_backend_setup *setup, fascia_backend **out) {
  *out = NULL;
  cpu_backend *B = calloc(1, sizeof *B);
  FASCIA_CHECK(B, setup->ctx, FASCIA_ERR_MEMORY, "solver: out of memory");
  B->base.ops = &fascia_backend_cpu;
  B->ctx = setup->ctx;
  B->organs = setup->organs;
  B->linear_epoch = setup->linear_epoch;
  B->sys = setup->sys;
  B->model = setup->model;
  B->def = setup->def;
  B->mask = setup->mask;
  B->bodies = setup->bodies;
  B->full_mask = setup->full_mask;
  B->frame_count = setup->model->frame_count;
  const int64_t N = B->frame_count;
  int allocated = 1;
#define ALLOC_ARRAY(name, type, width) FASCIA_ALLOC_ROW(B, allocated, name, type, N, width);
  CPU_ARRAYS(ALLOC_ARRAY)
#undef ALLOC_ARRAY
  if (!allocated) {
    cpu_destroy(&B->base);
    return FASCIA_FAIL(setup->ctx, FASCIA_ERR_MEMORY, "solver: out of memory for %lld frames", (long long)N);
  }
  const fascia_status st =
      fascia_linear_create(setup->ctx, setup->model, setup->def, setup->mask, setup->organs, &B->linear);
  if (st != FASCIA_OK) {
    cpu_destroy(&B->base);
    return st;
  }
  const int threads = B->sys->threads_max;
  snprintf(B->text, sizeof B->text, "cpu, %d thread%s", threads, threads == 1 ? "" : "s");
  *out = &B->base;
  return FASCIA_OK;
}

static const char *cpu_describe(const fascia_backend *backend) { return ((const cpu_backend *)backend)->text; }

static void mass_apply(cpu_backend *B, const fascia_real *v, fascia_real *out) {
  if (B->def->mass == FASCIA_MASS_LUMPED) {
    for (int32_t i = 0; i < B->frame_count; ++i)
      fascia_pt_block6_mul(B->mass_blocks + 36 * (int64_t)i, v + 6 * (int64_t)i, out + 6 * (int64_t)i);
  } else {
    fascia_system_mass_apply(B->sys, v, out);
  }
}

// Anchor and first iterate into the backend's arrays; the mass at the
// anchor for a dynamic step.
static fascia_status cpu_begin(fascia_backend *backend, const fascia_step_values *v, fascia_solve_report *report) {
  cpu_backend *B = (cpu_backend *)backend;
  B->values = *v;
  const int64_t N = B->frame_count, n = 6 * N;
  memcpy(B->x_base, v->x_base, 3 * (size_t)N * sizeof(fascia_real));
  memcpy(B->q_base, v->q_base, 4 * (size_t)N * sizeof(fascia_real));
  memcpy(B->d, v->d, (size_t)n * sizeof(fascia_real));
  B->values.x_base = B->x_base, B->values.q_base = B->q_base, B->values.d = B->d;
  B->sys->gravity_scale = v->gravity_scale;
  B->target_norm = 0;
  if (v->dynamic) {
    fascia_system_set_state(B->sys, B->x_base, B->q_base);
    fascia_system_mass_snapshot(B->sys);
    fascia_system_mass_lumped(B->sys, B->mass_blocks);
    mass_apply(B, v->inertia_target, B->target_M);
    B->target_norm = fascia_dot(v->inertia_target, B->target_M, n, B->sys->threads);
  }
  // the masks may change between steps: the frames that move, from them
  for (int32_t i = 0; i < B->frame_count; ++i) {
    unsigned char moves = 0;
    for (int c = 0; c < 6; ++c)
      moves |= B->mask[6 * (int64_t)i + c] | (B->full_mask ? B->full_mask[6 * (int64_t)i + c] : 0);
    B->frame_moves[i] = moves != 0;
  }
  const fascia_real c = v->c1 + v->c2;
  fascia_operator op = {.sys = B->sys,
                        .mass_coefficient = c,
                        .mass = B->def->mass,
                        .mass_blocks = B->mass_blocks,
                        .frame_moves = B->frame_moves,
                        .mask = B->mask,
                        .scratch = B->scratch + n};
  // rigid organs: the table says which bodies move in this step (the caller may drive one)
  op.bodies = fascia_organs_body_count(B->organs) > 0 ? B->bodies : NULL;
  op.full_mask = B->full_mask;
  op.prolonged = B->prolonged;
  fascia_linear_begin(B->linear, &op, v->dynamic, *B->linear_epoch, report);
  return FASCIA_OK;
}

// Phi and its projected gradient at increments d (newton.c's header has the
// objective).
static fascia_status objective(cpu_backend *B, const fascia_real *d, fascia_real *phi, fascia_real *gradient) {
  const fascia_step_values *v = &B->values;
  const int32_t N = B->frame_count;
  const int64_t n = 6 * (int64_t)N;
  for (int32_t i = 0; i < N; ++i) {
    for (int c = 0; c < 3; ++c) B->x[3 * i + c] = B->x_base[3 * i + c] + d[6 * i + c];
    memcpy(B->q + 4 * i, B->q_base + 4 * i, 4 * sizeof(fascia_real));
    fascia_pt_quat_rotate_by(d + 6 * i + 3, B->q + 4 * i);
  }
  fascia_system_set_state(B->sys, B->x, B->q);
  fascia_real energy;
  FASCIA_TRY(fascia_system_evaluate(B->sys, gradient, &energy));
  // the loads' torques' work along the step, external energy here as on the device
  const fascia_real *load = B->model->frame_load;
  fascia_real torque_work = 0;
  for (int32_t i = 0; i < N; ++i)
    torque_work += fascia_pt_frame_step_rotation(load + 6 * i, v->gravity_scale, d + 6 * i, v->dynamic, gradient + 6 * i);
  energy += torque_work;
  B->torque_work = torque_work;
  if (v->c1 != 0 || v->c2 != 0) {
    // c1/2 (d - hu).M(d - hu) + c2/2 d.M d with M(hu) precomputed
    mass_apply(B, d, B->scratch);
    const int threads = B->sys->threads;
    const fascia_real dMd = fascia_dot(d, B->scratch, n, threads), dz = fascia_dot(d, B->target_M, n, threads);
    energy += FASCIA_R(0.5) * v->c1 * (dMd - 2 * dz + B->target_norm) + FASCIA_R(0.5) * v->c2 * dMd;
    for (int64_t k = 0; k < n; ++k) gradient[k] += (v->c1 + v->c2) * B->scratch[k] - v->c1 * B->target_M[k];
  }
  // rigid organs: the bodies' own terms, gradient restricted to their masters
  const fascia_pt_body_step body_step = {v->c1, v->c2, v->gravity_scale, v->dynamic,
                                         {B->sys->gravity[0], B->sys->gravity[1], B->sys->gravity[2]}};
  energy += fascia_organs_reduce(B->organs, &body_step, B->x, B->q, B->x_base, B->q_base, d, gradient);
  for (int64_t k = 0; k < n; ++k)
    if (!B->mask[k]) gradient[k] = 0;
  *phi = energy;
  return isfinite(energy) ? FASCIA_OK
                          : FASCIA_FAIL(B->ctx, FASCIA_ERR_NUMERIC, "solver: the energy is not finite");
}

static fascia_status cpu_evaluate(fascia_backend *backend, fascia_real alpha, int current, fascia_trial_values *out) {
  cpu_backend *B = (cpu_backend *)backend;
  const int64_t n = 6 * (int64_t)B->frame_count;
  const fascia_real *d = B->d;
  fascia_real *g = current ? B->gradient : B->gradient_trial;
  if (!current) {
    for (int64_t k = 0; k < n; ++k) B->d_trial[k] = B->d[k] + alpha * B->direction[k];
    fascia_organs_expand(B->organs, B->x_base, B->q_base, B->d_trial); // slaves of rigid organs follow their master
    d = B->d_trial;
  }
  FASCIA_TRY(objective(B, d, &out->phi, g));
  out->gradient_norm2 = fascia_dot(g, g, n, B->sys->threads);
  *(current ? &B->gradient_norm2 : &B->trial_norm2) = out->gradient_norm2;
  out->energy_size = fabs(B->sys->energy_internal) + fabs(B->sys->energy_external + B->torque_work);
  return FASCIA_OK;
}

// A new tangent, or the kept factorization (linear_solver.c)
static fascia_status cpu_prepare(fascia_backend *backend, fascia_solve_report *report) {
  cpu_backend *B = (cpu_backend *)backend;
  return fascia_linear_prepare(B->linear, B->gradient_norm2, report);
}

static fascia_status cpu_direction(fascia_backend *backend, fascia_real *shift, fascia_real *slope,
                                   fascia_solve_report *report) {
  cpu_backend *B = (cpu_backend *)backend;
  const int64_t n = 6 * (int64_t)B->frame_count;
  fascia_real *p = B->direction, *g = B->gradient;
  for (int64_t k = 0; k < n; ++k) B->rhs[k] = -g[k];
  // dynamic: the tangent is the energy's at the iterate, for world-space
  // rotation increments there; the Newton step is taken in those
  // coordinates and mapped back to increments of the step's rotation
  // vectors d (without it, a step that turns frames by tenths of a radian
  // converges only linearly)
  if (B->values.dynamic)
    for (int64_t i = 0; i < B->frame_count; ++i) fascia_pt_step_rotation_map(B->d + 6 * i, B->mask + 6 * i, 0, B->rhs + 6 * i);
  FASCIA_TRY(fascia_linear_solve(B->linear, B->rhs, p, shift, report));
  if (B->values.dynamic)
    for (int64_t i = 0; i < B->frame_count; ++i) fascia_pt_step_rotation_map(B->d + 6 * i, B->mask + 6 * i, 1, p + 6 * i);
  *slope = fascia_dot(p, g, n, B->sys->threads);
  if (!(*slope < 0)) { // not a descent direction: preconditioned gradient
    fascia_linear_precondition(B->linear, g, p);
    for (int64_t k = 0; k < n; ++k) p[k] = -p[k];
    *slope = fascia_dot(p, g, n, B->sys->threads);
  }
  return FASCIA_OK;
}

static void cpu_accept(fascia_backend *backend) {
  cpu_backend *B = (cpu_backend *)backend;
  const int32_t N = B->frame_count;
  const size_t n = 6 * (size_t)N;
  memcpy(B->gradient, B->gradient_trial, n * sizeof(fascia_real));
  B->gradient_norm2 = B->trial_norm2;
  if (B->values.dynamic) {
    memcpy(B->d, B->d_trial, n * sizeof(fascia_real));
  } else {
    // static: re-anchor at the accepted state, so d = 0 and the Hessian
    // of the next iteration is exact (no Jacobian of the rotation map)
    memcpy(B->x_base, B->x, 3 * (size_t)N * sizeof(fascia_real));
    memcpy(B->q_base, B->q, 4 * (size_t)N * sizeof(fascia_real));
    memset(B->d, 0, n * sizeof(fascia_real));
  }
}

// The iterate is the anchor and the increments (rigid organs follow them)
static void cpu_save(fascia_backend *backend) {
  cpu_backend *B = (cpu_backend *)backend;
  const size_t N = (size_t)B->frame_count;
  memcpy(B->saved, B->x_base, 3 * N * sizeof(fascia_real));
  memcpy(B->saved + 3 * N, B->q_base, 4 * N * sizeof(fascia_real));
  memcpy(B->saved + 7 * N, B->d, 6 * N * sizeof(fascia_real));
}

static void cpu_restore(fascia_backend *backend) {
  cpu_backend *B = (cpu_backend *)backend;
  const size_t N = (size_t)B->frame_count;
  memcpy(B->x_base, B->saved, 3 * N * sizeof(fascia_real));
  memcpy(B->q_base, B->saved + 3 * N, 4 * N * sizeof(fascia_real));
  memcpy(B->d, B->saved + 7 * N, 6 * N * sizeof(fascia_real));
}

// The state of the last evaluation (the iterate), its increments and
// gradient, from the backend's own arrays, and the system's energies there.
static fascia_status cpu_finish(fascia_backend *backend, fascia_step_result *result) {
  cpu_backend *B = (cpu_backend *)backend;
  const fascia_system *sys = B->sys;
  *result = (fascia_step_result){.x = B->x,
                                 .q = B->q,
                                 .d = B->d,
                                 .gradient = B->gradient,
                                 .energy_internal = sys->energy_internal,
                                 .energy_external = sys->energy_external + B->torque_work,
                                 .inverted_count = sys->inverted_count,
                                 .first_inverted = sys->inverted_count > 0 ? sys->first_inverted : -1,
                                 .nonfinite_count = sys->nonfinite_count,
                                 .first_nonfinite = sys->first_nonfinite};
  return FASCIA_OK;
}

static fascia_status cpu_gradient(fascia_backend *backend, const fascia_real *x, const fascia_real *q,
                                  fascia_real load_factor, fascia_real *gradient, fascia_real *energy) {
  cpu_backend *B = (cpu_backend *)backend;
  fascia_system_set_state(B->sys, x, q);
  B->sys->gravity_scale = load_factor;
  FASCIA_TRY(fascia_system_evaluate(B->sys, gradient, energy));
  for (int64_t k = 0; k < 6 * (int64_t)B->frame_count; ++k)
    if (!B->mask[k]) gradient[k] = 0;
  return FASCIA_OK;
}

static fascia_status cpu_hessian_apply(fascia_backend *backend, const fascia_real *v, fascia_real *out) {
  cpu_backend *B = (cpu_backend *)backend;
  fascia_system_hessian_apply(B->sys, v, out);
  for (int64_t k = 0; k < 6 * (int64_t)B->frame_count; ++k)
    if (!B->mask[k]) out[k] = 0;
  return FASCIA_OK;
}

static fascia_status cpu_hessian_diagonal(fascia_backend *backend, fascia_real *blocks) {
  fascia_system_hessian_diagonal(((cpu_backend *)backend)->sys, blocks);
  return FASCIA_OK;
}

// The kept factorization, for checkpoints (linear_solver.h)
static int64_t cpu_linear_state_size(fascia_backend *backend) {
  cpu_backend *B = (cpu_backend *)backend;
  return fascia_linear_state_size(B->linear, *B->linear_epoch);
}

static void cpu_linear_state_save(fascia_backend *backend, fascia_real *out) {
  fascia_linear_state_save(((cpu_backend *)backend)->linear, out);
}

static int cpu_linear_state_load(fascia_backend *backend, const fascia_real *in, int64_t count) {
  cpu_backend *B = (cpu_backend *)backend;
  return fascia_linear_state_load(B->linear, in, count, *B->linear_epoch);
}

const fascia_backend_ops fascia_backend_cpu = {
    .name = "cpu",
    .automatic = 1,
    .available = cpu_available,
    .supports = cpu_supports,
    .create = cpu_create,
    .destroy = cpu_destroy,
    .describe = cpu_describe,
    .begin = cpu_begin,
    .evaluate = cpu_evaluate,
    .prepare = cpu_prepare,
    .direction = cpu_direction,
    .accept = cpu_accept,
    .save = cpu_save,
    .restore = cpu_restore,
    .finish = cpu_finish,
    .linear_state_size = cpu_linear_state_size,
    .linear_state_save = cpu_linear_state_save,
    .linear_state_load = cpu_linear_state_load,
    .gradient = cpu_gradient,
    .hessian_apply = cpu_hessian_apply,
    .hessian_diagonal = cpu_hessian_diagonal,
};
