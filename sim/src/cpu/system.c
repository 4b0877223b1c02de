// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// CPU operators of the frame scheme (paper sec. 2 and 3.2,
// docs/mechanics.md): per-sample work in parallel into a pair buffer, then one
// per-frame gather through the reverse table, as the paper's two GPU kernels
// do. See system.h for the contract.
#define _POSIX_C_SOURCE 200809L // sysconf (strict C11 hides it)
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cpu/system.h"
#include "model/model_arrays.h"
#include "contract/system_table.h"
#include "cpu/wide.h"
#include "cpu/dilatation.h"
#include "cpu/modes.h"
#include "point/frame.h"

#define DOT_BLOCK 2048 // entries per partial sum of fascia_dot (fixed: determinism)

// The lumped mass splits each sample's mass among its frames as point masses
// at the sample, which the frames carry rigidly. The row sum of the
// consistent mass would split it by the weights w_is, but meshless (MLS)
// weights can be negative, and a negative share makes a frame's 6x6 block
// indefinite: the implicit step then has no minimum and blows up at small
// time steps. The shares here are the positive parts of the weights,
// renormalized: never negative, summing to the sample's mass, and equal to
// the row sum wherever no weight is negative (hexahedral, tetrahedral). Each
// frame's block is then positive semi-definite, and positive definite unless
// its samples lie on one line (checked when the solver is made).
static void lumped_mass_shares(fascia_system *sys) {
  const fascia_model *m = sys->model;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    fascia_real positive = 0;
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k)
      positive += m->pair_weight[k] > 0 ? m->pair_weight[k] : 0;
    // the weights sum to one, so the positive ones sum to at least one
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k)
      sys->pair_lumped_mass[k] = m->pair_weight[k] > 0 ? sys->sample_mass[s] * m->pair_weight[k] / positive : 0;
  }
  for (int32_t i = 0; i < m->frame_count; ++i) {
    fascia_real *M = sys->frame_lumped_moments + 13 * (int64_t)i;
    for (int c = 0; c < 13; ++c) M[c] = 0;
    for (int32_t r = m->frame_offsets[i]; r < m->frame_offsets[i + 1]; ++r) {
      const int32_t k = m->frame_pairs[r];
      const fascia_real mk = sys->pair_lumped_mass[k], *d = sys->pair_offset + 3 * (int64_t)k;
      const fascia_real dd = fascia_pt_dot3(d, d);
      M[0] += mk;
      for (int a = 0; a < 3; ++a) {
        M[1 + a] += mk * d[a];
        for (int c = 0; c < 3; ++c) M[4 + 3 * a + c] += mk * ((a == c ? dd : 0) - d[a] * d[c]);
      }
    }
  }
}

fascia_status fascia_system_create(fascia_ctx *ctx, const fascia_model *m, int threads, fascia_system **out) {
  FASCIA_CHECK(m && out, ctx, FASCIA_ERR_ARGUMENT, "system: NULL argument");
  *out = NULL;
  fascia_system *sys = calloc(1, sizeof *sys);
  FASCIA_CHECK(sys, ctx, FASCIA_ERR_MEMORY, "system: out of memory");
  const int64_t S = m->sample_count, P = m->pair_count;
  sys->ctx = ctx;
  sys->model = m;
  sys->frame_count = m->frame_count;
  sys->sample_count = m->sample_count;
  sys->pair_count = m->pair_count;
  sys->threads = sys->threads_max = threads > 0 ? threads : 1;
  sys->gravity_scale = 1;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    const int32_t n = m->sample_offsets[s + 1] - m->sample_offsets[s];
    if (n > sys->max_neighbours) sys->max_neighbours = n;
  }
  int allocated = 1;
#define ALLOC(field, type, count, width, device) FASCIA_ALLOC_ROW(sys, allocated, field, type, sys->count, width);
  FASCIA_SYSTEM_ARRAYS(ALLOC)
#undef ALLOC
  if (!allocated) {
    fascia_system_destroy(&sys);
    return FASCIA_FAIL(ctx, FASCIA_ERR_MEMORY, "system: out of memory for %lld samples, %lld pairs", (long long)S,
                       (long long)P);
  }
  for (int32_t j = 0; j < sys->max_neighbours; ++j) sys->local_slot[j] = j;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    const fascia_material *mat = m->materials + m->sample_material[s];
    fascia_real lambda, mu;
    fascia_material_lame(mat, &lambda, &mu);
    // selective reduced integration: each part keeps its share of the energy
    const int volumetric = mat->part == FASCIA_PART_VOLUMETRIC;
    sys->sample_lambda[s] = mat->part == FASCIA_PART_DEVIATORIC ? 0 : lambda;
    sys->sample_mu[s] = volumetric ? 0 : mu;
    sys->sample_coupling[s] = volumetric ? 0 : mat->rotation_coupling * mu;
    sys->sample_law[s] = mat->law;
    sys->sample_mass[s] = volumetric ? 0 : mat->density * m->sample_volume[s];
    // smoothing length l = r h, h the weighted RMS distance to the frames
    fascia_real h2 = 0;
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k)
      for (int r = 0; r < 3; ++r) {
        const fascia_real d = m->sample_position[3 * s + r] - m->frame_position[3 * m->pair_frame[k] + r];
        sys->pair_offset[3 * k + r] = d;
        h2 += fabs(m->pair_weight[k]) * d * d;
      }
    sys->sample_curvature[s] = volumetric ? 0 : mu * mat->rotation_smoothing * mat->rotation_smoothing * h2;
  }
  for (int32_t s = 0; s < m->sample_count; ++s)
    for (int32_t k = m->sample_offsets[s]; k < m->sample_offsets[s + 1]; ++k) sys->pair_sample[k] = s;
  lumped_mass_shares(sys);
  // gravity moments through the reverse table (fixed order)
  for (int32_t i = 0; i < m->frame_count; ++i)
    for (int32_t r = m->frame_offsets[i]; r < m->frame_offsets[i + 1]; ++r) {
      const int32_t k = m->frame_pairs[r];
      const fascia_real mw = sys->sample_mass[sys->pair_sample[k]] * m->pair_weight[k];
      sys->frame_mass[i] += mw;
      for (int c = 0; c < 3; ++c) sys->frame_moment[3 * i + c] += mw * sys->pair_offset[3 * k + c];
    }
  for (int c = 0; c < 3; ++c) sys->gravity[c] = m->gravity[c];
  // the per-sample math's view: the rows of the two tables marked POINT(member)
  // set sys->pm.member, the others are passed over
#define POINT(member) sys->pm.member =
#define DEVICE(member) (void)
#define HOST (void)
#define MODEL_VIEW(field, kind, count, plus, width, path, unit, fill, flags, since, device) device m->field;
#define SYSTEM_VIEW(field, type, count, width, device) device sys->field;
  FASCIA_MODEL_ARRAYS(MODEL_VIEW)
  FASCIA_SYSTEM_ARRAYS(SYSTEM_VIEW)
#undef SYSTEM_VIEW
#undef MODEL_VIEW
#undef HOST
#undef DEVICE
#undef POINT
  fascia_status status = fascia_dilatation_create(sys, &sys->dilatation);
  if (status == FASCIA_OK) status = fascia_modes_create(sys, &sys->modes);
  if (status != FASCIA_OK) {
    fascia_system_destroy(&sys);
    return status;
  }
  fascia_system_set_rest(sys);
  fascia_system_mass_snapshot(sys);
  *out = sys;
  return FASCIA_OK;
}

int32_t fascia_model_pair_owner(const fascia_model *m, int32_t k) {
  int32_t lo = 0, hi = m->sample_count - 1;
  while (lo < hi) {
    const int32_t mid = (lo + hi + 1) / 2;
    if (m->sample_offsets[mid] <= k) lo = mid;
    else hi = mid - 1;
  }
  return lo;
}

void fascia_system_arrays(const fascia_system *sys, fascia_array_data data[FASCIA_SA_COUNT]) {
#define DATA(field, type, count, width, device)                                                                       \
  data[FASCIA_SA_ID_##field] = (fascia_array_data){sys->field, (size_t)sys->count * (width) * sizeof(type)};
  FASCIA_SYSTEM_ARRAYS(DATA)
#undef DATA
}

void fascia_system_destroy(fascia_system **sys) {
  if (!sys || !*sys) return;
  fascia_system *s = *sys;
  fascia_modes_destroy(&s->modes);
  fascia_dilatation_destroy(&s->dilatation);
#define FREE(field, ...) free(s->field);
  FASCIA_SYSTEM_ARRAYS(FREE)
#undef FREE
  free(s->smoothing_offsets);
  free(s->smoothing_frames);
  free(s->smoothing_weight);
  free(s);
  *sys = NULL;
}

void fascia_system_set_state(fascia_system *sys, const fascia_real *x, const fascia_real *q) {
  const int32_t N = sys->frame_count;
  if (x != sys->x) memcpy(sys->x, x, 3 * (size_t)N * sizeof(fascia_real));
  if (q != sys->q) memcpy(sys->q, q, 4 * (size_t)N * sizeof(fascia_real));
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t i = 0; i < N; ++i)
    fascia_pt_frame_A(sys->q + 4 * (int64_t)i, sys->model->frame_rotation + 4 * (int64_t)i, sys->A + 9 * (int64_t)i);
}

void fascia_system_set_rest(fascia_system *sys) {
  fascia_system_set_state(sys, sys->model->frame_position, sys->model->frame_rotation);
}

// out_i = sum of the pair buffer over the reverse table of frame i
static void gather(const fascia_system *sys, fascia_real *out) {
  const fascia_model *m = sys->model;
  const fascia_real *buffer = sys->pair_buffer;
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t i = 0; i < sys->frame_count; ++i)
    fascia_pt_frame_gather(m->frame_offsets, m->frame_pairs, buffer, i, out + 6 * (int64_t)i);
}

fascia_real fascia_dot(const fascia_real *a, const fascia_real *b, int64_t n, int threads) {
  const int64_t blocks = (n + DOT_BLOCK - 1) / DOT_BLOCK;
  fascia_real partial_stack[64], *partial = blocks <= 64 ? partial_stack : malloc((size_t)blocks * sizeof *partial);
  if (!partial) { // cannot happen in practice; fall back to a serial sum
    fascia_real s = 0;
    for (int64_t k = 0; k < n; ++k) s += a[k] * b[k];
    return s;
  }
#pragma omp parallel for num_threads(threads) schedule(static) if (n > 8 * DOT_BLOCK)
  for (int64_t blk = 0; blk < blocks; ++blk) {
    fascia_real s = 0;
    const int64_t end = (blk + 1) * DOT_BLOCK < n ? (blk + 1) * DOT_BLOCK : n;
    for (int64_t k = blk * DOT_BLOCK; k < end; ++k) s += a[k] * b[k];
    partial[blk] = s;
  }
  fascia_real sum = 0;
  for (int64_t blk = 0; blk < blocks; ++blk) sum += partial[blk];
  if (partial != partial_stack) free(partial);
  return sum;
}

// Samples [begin, end): their energy, summed in order, and their pairs'
// gradients into the pair buffer, with their caches and flags. Compiled
// wide (wide.h).
WIDE_CLONES static fascia_real samples_gradient(fascia_system *sys, const fascia_pt_state *st, int32_t begin,
                                               int32_t end) {
  const int32_t *offsets = sys->model->sample_offsets, *patch = sys->model->sample_patch;
  // the patches' evaluation at this state has the F of their samples
  const fascia_real *known = sys->dilatation ? sys->dilatation->sample_F : NULL;
  fascia_real e = 0;
  for (int32_t s = begin; s < end; ++s) {
    fascia_real own[9];
    const fascia_real *F = known && patch[s] >= 0 ? known + 9 * (int64_t)s : own;
    if (F == own) fascia_pt_sample_F(&sys->pm, st, s, own);
    e += fascia_pt_sample_gradient_at(&sys->pm, st, s, F, sys->pair_buffer + 6 * (int64_t)offsets[s],
                                      sys->cache + (int64_t)s * FASCIA_PT_CACHE_SIZE, sys->sample_flags + s);
  }
  return e;
}

fascia_status fascia_system_evaluate(fascia_system *sys, fascia_real *gradient, fascia_real *energy) {
  const fascia_model *m = sys->model;
  const fascia_pt_state st = {sys->x, sys->A};
  const int32_t S = sys->sample_count;
  // sample energies are summed in fixed blocks of samples (determinism)
  // the modes' enhanced F first, then the patches' pressures: the samples'
  // stresses read both
  const int32_t failed_patch = sys->modes ? fascia_modes_evaluate(sys, sys->modes) : -1;
  fascia_real internal = sys->dilatation ? fascia_dilatation_evaluate(sys, sys->dilatation) : 0;
  if (failed_patch >= 0) internal = NAN; // no minimum in the modes: the step is refused below
  int32_t inverted = 0, first_inverted = -1, nonfinite = 0, first_nonfinite = -1;
  const int64_t blocks = ((int64_t)S + DOT_BLOCK - 1) / DOT_BLOCK;
  fascia_real partial_stack[64], *partial = blocks <= 64 ? partial_stack : malloc((size_t)blocks * sizeof *partial);
  FASCIA_CHECK(partial, sys->ctx, FASCIA_ERR_MEMORY, "system: out of memory");
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int64_t blk = 0; blk < blocks; ++blk) {
    const int32_t end = (int32_t)((blk + 1) * DOT_BLOCK < S ? (blk + 1) * DOT_BLOCK : S);
    partial[blk] = samples_gradient(sys, &st, (int32_t)(blk * DOT_BLOCK), end);
  }
  for (int64_t blk = 0; blk < blocks; ++blk) internal += partial[blk];
  if (partial != partial_stack) free(partial);
  for (int32_t s = 0; s < S; ++s) {
    const int f = sys->sample_flags[s];
    if (f & FASCIA_PT_FLAG_INVERTED) {
      if (first_inverted < 0) first_inverted = s;
      ++inverted;
    }
    if (f & FASCIA_PT_FLAG_NONFINITE) {
      if (first_nonfinite < 0) first_nonfinite = s;
      ++nonfinite;
    }
  }
  sys->inverted_count = inverted;
  sys->first_inverted = first_inverted;
  sys->nonfinite_count = nonfinite;
  sys->first_nonfinite = first_nonfinite;
  sys->energy_internal = internal;
  if (!gradient) gradient = sys->gradient_scratch;
  gather(sys, gradient);
  // gravity and frame loads, scaled by the load factor
  const fascia_real gs = sys->gravity_scale, *g = sys->gravity;
  fascia_real external = 0;
  for (int32_t i = 0; i < sys->frame_count; ++i)
    external += fascia_pt_frame_external(sys->A + 9 * (int64_t)i, sys->frame_moment + 3 * (int64_t)i,
                                         sys->frame_mass[i], g, gs, sys->x + 3 * (int64_t)i,
                                         m->frame_load + 6 * (int64_t)i, gradient + 6 * (int64_t)i,
                                         sys->conservative_torque + 3 * (int64_t)i);
  sys->energy_external = external;
  if (energy) *energy = internal + external;
  if (failed_patch >= 0 && first_nonfinite < 0)
    return FASCIA_FAIL(sys->ctx, FASCIA_ERR_NUMERIC,
                       "patch %d: its enhanced strain modes found no minimum at this state; the step is too large or "
                       "the model is unstable",
                       (int)failed_patch);
  if (first_nonfinite >= 0)
    return FASCIA_FAIL(sys->ctx, FASCIA_ERR_NUMERIC, "sample %d: energy is not finite (deformation gradient blew up)",
                       (int)first_nonfinite);
  if (!isfinite(internal + external))
    return FASCIA_FAIL(sys->ctx, FASCIA_ERR_NUMERIC, "the energy of gravity and the frame loads is not finite at "
                       "this state (a frame's position or a load overflowed)");
  return FASCIA_OK;
}

void fascia_system_gradient_derivative(fascia_system *sys, const fascia_real *v, fascia_real *out) {
  const fascia_model *m = sys->model;
  const fascia_pt_state st = {sys->x, sys->A};
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t s = 0; s < sys->sample_count; ++s) {
    const int32_t begin = m->sample_offsets[s];
    fascia_pt_sample_stiffness(&sys->pm, &st, s, sys->cache + (int64_t)s * FASCIA_PT_CACHE_SIZE, v,
                               m->pair_frame + begin, sys->pair_buffer + 6 * (int64_t)begin);
  }
  gather(sys, out);
  if (sys->dilatation) fascia_dilatation_apply_add(sys, sys->dilatation, v, out);
  if (sys->modes) fascia_modes_apply_add(sys, sys->modes, v, out);
  for (int32_t i = 0; i < sys->frame_count; ++i)
    fascia_pt_frame_gravity_product(sys->A + 9 * (int64_t)i, sys->frame_moment + 3 * (int64_t)i, sys->gravity,
                                    sys->gravity_scale, v + 6 * (int64_t)i, out + 6 * (int64_t)i);
}

void fascia_system_hessian_apply(fascia_system *sys, const fascia_real *v, fascia_real *out) {
  fascia_system_gradient_derivative(sys, v, out);
  for (int32_t i = 0; i < sys->frame_count; ++i)
    fascia_pt_frame_symmetrizing_product(sys->conservative_torque + 3 * (int64_t)i, v + 6 * (int64_t)i,
                                         out + 6 * (int64_t)i);
}

void fascia_system_hessian_diagonal(fascia_system *sys, fascia_real *blocks) {
  const fascia_model *m = sys->model;
  const fascia_pt_state st = {sys->x, sys->A};
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t i = 0; i < sys->frame_count; ++i) {
    fascia_real *B = blocks + 36 * (int64_t)i;
    for (int c = 0; c < 36; ++c) B[c] = 0;
    for (int32_t r = m->frame_offsets[i]; r < m->frame_offsets[i + 1]; ++r) {
      const int32_t k = m->frame_pairs[r], s = sys->pair_sample[k];
      fascia_real P[36];
      fascia_pt_sample_pair_block(&sys->pm, &st, s, sys->cache + (int64_t)s * FASCIA_PT_CACHE_SIZE,
                                  k - m->sample_offsets[s], P);
      for (int c = 0; c < 36; ++c) B[c] += P[c];
    }
    fascia_pt_frame_diagonal_finish(sys->A + 9 * (int64_t)i, sys->frame_moment + 3 * (int64_t)i, sys->gravity,
                                    sys->gravity_scale, sys->conservative_torque + 3 * (int64_t)i, B);
  }
  if (sys->dilatation) fascia_dilatation_diagonal_add(sys, sys->dilatation, blocks);
  if (sys->modes) fascia_modes_diagonal_add(sys, sys->modes, blocks);
}

void fascia_system_mass_snapshot(fascia_system *sys) {
  memcpy(sys->A_mass, sys->A, 9 * (size_t)sys->frame_count * sizeof(fascia_real));
}

void fascia_system_mass_apply(fascia_system *sys, const fascia_real *v, fascia_real *out) {
  const fascia_model *m = sys->model;
  const fascia_pt_state st = {sys->x, sys->A_mass};
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t s = 0; s < sys->sample_count; ++s) {
    const int32_t begin = m->sample_offsets[s];
    fascia_pt_sample_mass(&sys->pm, &st, s, sys->sample_mass[s], v, m->pair_frame + begin,
                          sys->pair_buffer + 6 * (int64_t)begin);
  }
  gather(sys, out);
}

void fascia_system_mass_lumped(fascia_system *sys, fascia_real *blocks) {
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t i = 0; i < sys->frame_count; ++i)
    fascia_pt_frame_lumped_mass(sys->frame_lumped_moments + 13 * (int64_t)i, sys->A_mass + 9 * (int64_t)i,
                                blocks + 36 * (int64_t)i);
}

void fascia_system_sample_positions(const fascia_system *sys, fascia_real *out) {
  const fascia_pt_state st = {sys->x, sys->A};
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t s = 0; s < sys->sample_count; ++s) fascia_pt_sample_position(&sys->pm, &st, s, out + 3 * (int64_t)s);
}

// |E| = |F^T F - I| / 2 of sample s (Frobenius norm), with F for the caller
static fascia_real strain_norm(const fascia_system *sys, const fascia_pt_state *st, int32_t s, fascia_real *F) {
  fascia_pt_sample_F(&sys->pm, st, s, F);
  return fascia_pt_strain_norm(F);
}

fascia_real fascia_system_largest_strain(const fascia_system *sys, int32_t *sample) {
  const fascia_pt_state st = {sys->x, sys->A};
  fascia_real largest = 0;
  int nonfinite = 0;
#pragma omp parallel for num_threads(sys->threads) schedule(static) reduction(max : largest) reduction(| : nonfinite)
  for (int32_t s = 0; s < sys->sample_count; ++s) {
    fascia_real F[9];
    const fascia_real e = strain_norm(sys, &st, s, F);
    if (e > largest) largest = e;
    nonfinite |= !isfinite(e);
  }
  if (nonfinite) largest = INFINITY;
  if (!sample) return largest;
  *sample = -1; // the lowest sample with the largest value (the same for any thread count)
  for (int32_t s = 0; s < sys->sample_count && *sample < 0; ++s) {
    fascia_real F[9];
    const fascia_real e = strain_norm(sys, &st, s, F);
    if (e == largest || (nonfinite && !isfinite(e))) *sample = s;
  }
  return largest;
}

void fascia_system_sample_strain(fascia_system *sys, fascia_real *strain, fascia_real *stress) {
  const fascia_pt_state st = {sys->x, sys->A};
  // the patches' pressures at this state: the last evaluation may have been
  // of a trial, or on a device, which keeps its own
  if (sys->modes) fascia_modes_evaluate(sys, sys->modes); // F has the modes at this state
  if (stress && sys->dilatation) fascia_dilatation_evaluate(sys, sys->dilatation);
#pragma omp parallel for num_threads(sys->threads) schedule(static)
  for (int32_t s = 0; s < sys->sample_count; ++s)
    strain[s] = fascia_pt_sample_output(&sys->pm, &st, s, stress ? stress + s : NULL);
}

int fascia_threads_free(int wanted, int64_t pairs) {
  if (wanted <= 1) return 1;
  if (pairs >= FASCIA_THREADS_LONG_PASS_PAIRS) return wanted;
  FILE *f = fopen("/proc/loadavg", "r");
  if (!f) return wanted;
  double a, b, c;
  long running = 0, total = 0;
  const int read = fscanf(f, "%lf %lf %lf %ld/%ld", &a, &b, &c, &running, &total);
  fclose(f);
  const long cores = sysconf(_SC_NPROCESSORS_ONLN);
  if (read != 5 || cores < 1) return wanted;
  const long free_cores = cores - (running - 1); // this thread is one of the runnable
  return free_cores < 1 ? 1 : free_cores < wanted ? (int)free_cores : wanted;
}
