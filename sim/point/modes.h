// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Per-patch work of the enhanced strain modes (sim/src/cpu/modes.h has the
// method and its derivatives), written once for every backend that runs
// them. A patch p holds samples (sim/point/patch.h); mode j = 3 r + c adds
// a_j xi_c to entry (r, c) of each sample's deformation gradient, xi = X_s -
// Xbar_p the sample's rest offset from the patch's centre.
#ifndef FASCIA_POINT_MODES_H
#define FASCIA_POINT_MODES_H

#include "patch.h"

/// The local solve stops when its step changes no mode's strain (a_j |xi_c|)
/// by more than this: near rounding, so that the energy's gradient and
/// Hessian hold to rounding at the amplitudes found.
#define FASCIA_PT_MODES_TOLERANCE FASCIA_R(1e-14)
#define FASCIA_PT_MODES_MAX_ITERATIONS 60

/// The modes' tables (host or device arrays) and what an evaluation leaves.
typedef struct fascia_pt_modes {
  const int32_t *active;       ///< [patches] bit j: mode j acts (its set has it, the patch spans X_{j % 3})
  const fascia_real *xi_max;   ///< [3 patches] the largest |xi_c| of each patch's samples, m
  const fascia_real *sample_xi; ///< [3S] xi_s, m (0 outside patches)
  fascia_real *amplitude;      ///< [9 patches] a_p at the last evaluation, 1/m
  int32_t *failed;             ///< [patches] 1: the last local solve found no minimum
  fascia_real *sample_enhanced; ///< [9S] the enhanced part of F (pm.sample_enhanced)
  /// [54 entries] W_e = K_ue L^-T at the last tangent (6x9, row-major):
  /// K_ue the change of entry e's gradient per active mode, L L^T = K_aa,
  /// so the condensed term is K_ue K_aa^-1 K_uf^T = W_e W_f^T. Its columns
  /// are L's, one per active mode in ascending order, first, then zeros
  /// (fascia_pt_modes_width of them are read)
  fascia_real *entry_factor;
  fascia_real *reduced;        ///< [9 patches] W_p^T v of the last product
} fascia_pt_modes;

static inline FASCIA_HD int fascia_pt_mode_active(const fascia_pt_modes *md, int32_t p, int j) {
  return (md->active[p] >> j) & 1;
}

/// How many columns of patch p's W_e to read: 0 without modes, 3 for at
/// most three active (the normal set), else 9. Constant loop bounds keep the
/// products unrolled; the columns past the active modes are 0.
static inline FASCIA_HD int fascia_pt_modes_width(const fascia_pt_modes *md, int32_t p) {
  int n = 0;
  for (int j = 0; j < 9; ++j) n += fascia_pt_mode_active(md, p, j);
  return n == 0 ? 0 : n <= 3 ? 3 : 9;
}

/// sum_k x[k] y[k] over the first width (3 or 9) entries.
static inline FASCIA_HD fascia_real fascia_pt_modes_dot(const fascia_real *x, const fascia_real *y, int width) {
  fascia_real sum = 0;
  if (width == 3)
    for (int k = 0; k < 3; ++k) sum += x[k] * y[k];
  else
    for (int k = 0; k < 9; ++k) sum += x[k] * y[k];
  return sum;
}

/// The sets of modes (fascia_modes_set's values: sim/src/cpu/modes.c checks).
enum { FASCIA_PT_MODES_NINE = 1, FASCIA_PT_MODES_NORMAL = 2 };

/// 1: mode j is in the set: all nine, or the normal ones j = 0, 4, 8.
static inline FASCIA_HD int fascia_pt_modes_set_has(int32_t set, int j) {
  return set == FASCIA_PT_MODES_NINE || (set == FASCIA_PT_MODES_NORMAL && j % 4 == 0);
}

// The enhanced part of F for amplitudes a at rest offset xi.
static inline FASCIA_HD void fascia_pt_modes_F(const fascia_real *a, const fascia_real *xi, fascia_real *E) {
  for (int j = 0; j < 9; ++j) E[j] = a[j] * xi[j % 3];
}

// Patch p's energy E_p(a) (J: its samples' own energies and its
// mean-dilatation term), its gradient r and Hessian H (81) in the modes at
// amplitudes a, the frames held. m is the model without pressures or modes;
// F_frames [9S]: the frames' part of each sample's F, which the frames
// held do not change. Returns 0 where some sample's energy is not finite.
FASCIA_STATIC_FORCE_INLINE FASCIA_HD int fascia_pt_modes_local(const fascia_pt_model *m, const fascia_pt_state *st,
                                                  const fascia_pt_patches *t, const fascia_pt_modes *md, int32_t p,
                                                  const fascia_real *F_frames, const fascia_real *a,
                                                  fascia_real *energy, fascia_real *r, fascia_real *H) {
  // H NULL: energy and gradient only
  fascia_real g[9] = {0}, D[81] = {0}, sum = 0, e = 0;
  for (int j = 0; j < 9; ++j) r[j] = 0;
  for (int j = 0; j < 81 && H; ++j) H[j] = 0;
  int ok = 1;
  const int law = t->law[p];
  for (int32_t q = t->patch_offsets[p]; q < t->patch_offsets[p + 1]; ++q) {
    const int32_t s = t->patch_samples[q];
    const fascia_real v = m->sample_volume[s], *xi = md->sample_xi + 3 * (int64_t)s;
    fascia_real cache[FASCIA_PT_CACHE_SIZE], E[9], dtheta[9];
    fascia_real *F = cache, *P = cache + 9, *aux = cache + 18;
    fascia_pt_modes_F(a, xi, E);
    for (int j = 0; j < 9; ++j) F[j] = F_frames[9 * (int64_t)s + j] + E[j];
    const fascia_real psi = fascia_pt_sample_law_stress(m, st, s, F, P, aux);
    if (!isfinite(psi)) ok = 0;
    e += v * psi;
    sum += v * fascia_pt_dilatation(law, F, dtheta);
    for (int j = 0; j < 9; ++j) {
      r[j] += v * xi[j % 3] * P[j];
      g[j] += v * xi[j % 3] * dtheta[j];
    }
    // without the rotation coupling a mode's stress response is a column
    // of the law's tangent (m has no pressures), its dilatation's a column
    // of the dilatation's Hessian
    const int closed = H && !(m->sample_coupling[s] > 0);
    fascia_real Dlaw[81], Ddil[81];
    if (closed) {
      fascia_pt_sample_tangent(m, s, cache, Dlaw);
      fascia_pt_dilatation_hessian(law, F, Ddil);
    }
    for (int k = 0; k < 9 && H; ++k) {
      if (!fascia_pt_mode_active(md, p, k)) continue;
      fascia_real dF[9] = {0}, dP[9], dd[9] = {0};
      dF[k] = xi[k % 3];
      if (closed) {
        for (int j = 0; j < 9; ++j) {
          dP[j] = Dlaw[9 * j + k] * dF[k];
          dd[j] = Ddil[9 * j + k] * dF[k];
        }
      } else {
        fascia_pt_sample_F_response(m, st, s, cache, dF, (fascia_real *)0, dP);
        fascia_pt_dilatation_diff_add(law, 1, F, dF, dd);
      }
      for (int j = 0; j <= k; ++j) { // the upper triangle; both are symmetric
        H[9 * j + k] += v * xi[j % 3] * dP[j];
        D[9 * j + k] += v * xi[j % 3] * dd[j];
      }
    }
  }
  for (int k = 0; k < 9 && H; ++k)
    for (int j = 0; j < k; ++j) {
      H[9 * k + j] = H[9 * j + k];
      D[9 * k + j] = D[9 * j + k];
    }
  const fascia_real theta = sum / t->volume[p], pressure = t->lambda[p] * theta, c = t->lambda[p] / t->volume[p];
  e += FASCIA_R(0.5) * t->volume[p] * pressure * theta;
  for (int j = 0; j < 9; ++j) {
    r[j] += pressure * g[j];
    for (int k = 0; k < 9 && H; ++k) H[9 * j + k] += pressure * D[9 * j + k] + c * g[j] * g[k];
  }
  *energy = e;
  return ok && isfinite(e);
}

// The Cholesky factor L (n x n, row-major) of H on patch p's n active
// modes idx, H shifted on its diagonal until positive definite. Returns 0 if
// no shift makes it so.
static inline FASCIA_HD int fascia_pt_modes_factor(const fascia_pt_modes *md, int32_t p, const fascia_real *H,
                                                   int *idx, int *n_out, fascia_real *L) {
  int n = 0;
  for (int j = 0; j < 9; ++j)
    if (fascia_pt_mode_active(md, p, j)) idx[n++] = j;
  *n_out = n;
  fascia_real scale = 0, shift = 0;
  for (int u = 0; u < n; ++u) scale = fmax(scale, fabs(H[10 * idx[u]]));
  for (int attempt = 0; attempt < 40; ++attempt) {
    for (int u = 0; u < n; ++u)
      for (int w = 0; w < n; ++w) L[n * u + w] = H[9 * idx[u] + idx[w]] + (u == w ? shift : 0);
    if (fascia_pt_cholesky(L, n)) return 1;
    shift = shift > 0 ? 4 * shift : FASCIA_R(1e-12) * (scale > 0 ? scale : 1);
  }
  return 0;
}

// The inverse (81, 0 in inactive rows and columns) of H on patch p's
// active modes, shifted as fascia_pt_modes_factor does. Returns 0 on failure.
static inline FASCIA_HD int fascia_pt_modes_inverse(const fascia_pt_modes *md, int32_t p, const fascia_real *H,
                                                    fascia_real *inverse) {
  int idx[9], n;
  fascia_real L[81], inv[81];
  for (int j = 0; j < 81; ++j) inverse[j] = 0;
  if (!fascia_pt_modes_factor(md, p, H, idx, &n, L)) return 0;
  fascia_pt_cholesky_inverse(L, n, inv);
  for (int u = 0; u < n; ++u)
    for (int w = 0; w < n; ++w) inverse[9 * idx[u] + idx[w]] = inv[n * u + w];
  return 1;
}

/// Patch p at the state st: the amplitudes that minimize its energy with the
/// frames held, and its samples' enhanced F. Chord steps from a = 0 with the
/// Hessian of their start (the modes' energy is nearly quadratic: strains
/// are small corrections), the Hessian taken afresh where a step gains
/// energy or converges slowly; the last step, below the tolerance, is taken
/// unevaluated, and steps that stop shrinking far below it end the solve (a
/// minimum to rounding). From 0 each time, so the result depends on the
/// state alone.
/// m is the model without pressures or modes (the patch's pressure follows
/// the amplitudes here). The samples' sample_enhanced hold their frames'
/// part of F during the solve (computed once, not at every trial).
FASCIA_STATIC_FORCE_INLINE FASCIA_HD void fascia_pt_modes_evaluate(const fascia_pt_model *m, const fascia_pt_state *st,
                                                      const fascia_pt_patches *t, const fascia_pt_modes *md, int32_t p) {
  md->failed[p] = 0;
  if (!md->active[p]) return; // a patch without modes keeps its zero enhanced F
  fascia_real a[9] = {0}, trial[9], step[9], r[9], r_trial[9], H[81], inverse[81], e, e_trial;
  fascia_real last_change = 0, shrink = 1;
  int failed = 1, fresh = 1;
  // the rounding error of the patch's energy: a step whose energy rises by
  // less than this is taken, not refused
  fascia_real scale = t->volume[p] * fabs(t->lambda[p]);
  for (int32_t q = t->patch_offsets[p]; q < t->patch_offsets[p + 1]; ++q)
    scale += fascia_pt_sample_energy_scale(m, t->patch_samples[q]);
  const fascia_real roundoff = fascia_pt_energy_roundoff(scale);
  fascia_real *F_frames = md->sample_enhanced;
  for (int32_t q = t->patch_offsets[p]; q < t->patch_offsets[p + 1]; ++q)
    fascia_pt_sample_F_frames(m, st, t->patch_samples[q], F_frames + 9 * (int64_t)t->patch_samples[q]);
  if (fascia_pt_modes_local(m, st, t, md, p, F_frames, a, &e, r, H) && fascia_pt_modes_inverse(md, p, H, inverse)) {
    for (int it = 0; it < FASCIA_PT_MODES_MAX_ITERATIONS; ++it) {
      fascia_real change = 0;
      for (int j = 0; j < 9; ++j) {
        fascia_real sum = 0;
        for (int k = 0; k < 9; ++k) sum -= inverse[9 * j + k] * r[k];
        step[j] = shrink * sum;
        trial[j] = a[j] + step[j];
        change = fmax(change, fabs(step[j]) * md->xi_max[3 * p + j % 3]);
      }
      if (change <= FASCIA_PT_MODES_TOLERANCE) {
        for (int j = 0; j < 9; ++j) a[j] = trial[j];
        failed = 0;
        break;
      }
      const int ok = fascia_pt_modes_local(m, st, t, md, p, F_frames, trial, &e_trial, r_trial, (fascia_real *)0);
      if (!ok || e_trial > e + FASCIA_R(1e-13) * fabs(e) + roundoff) {
        if (fresh) { // a Newton step gains energy: shorten it
          shrink *= FASCIA_R(0.5);
          if (shrink < FASCIA_R(1e-6)) { // no step descends: a is the minimum to rounding
            failed = !ok && it == 0;
            break;
          }
        } else if (!fascia_pt_modes_local(m, st, t, md, p, F_frames, a, &e, r, H) ||
                   !fascia_pt_modes_inverse(md, p, H, inverse))
          break;
        else
          fresh = 1;
        continue;
      }
      const int slow = it > 0 && change > FASCIA_R(0.25) * last_change;
      // steps that stop shrinking far below any strain that matters are
      // rounding noise (on a badly conditioned patch they never reach the
      // tolerance): a is the minimum to rounding
      const int noise = it > 0 && change < FASCIA_R(1e-10) && change > FASCIA_R(0.5) * last_change;
      for (int j = 0; j < 9; ++j) {
        a[j] = trial[j];
        r[j] = r_trial[j];
      }
      e = e_trial;
      if (noise) {
        failed = 0;
        break;
      }
      last_change = change;
      shrink = 1;
      fresh = 0;
      if (slow) { // the chord converges slowly: the Hessian here
        if (!fascia_pt_modes_local(m, st, t, md, p, F_frames, a, &e, r, H) ||
            !fascia_pt_modes_inverse(md, p, H, inverse))
          break;
        fresh = 1;
      }
    }
  }
  md->failed[p] = failed;
  for (int j = 0; j < 9; ++j) md->amplitude[9 * p + j] = a[j];
  for (int32_t q = t->patch_offsets[p]; q < t->patch_offsets[p + 1]; ++q) {
    const int32_t s = t->patch_samples[q];
    fascia_pt_modes_F(a, md->sample_xi + 3 * (int64_t)s, md->sample_enhanced + 9 * (int64_t)s);
  }
}

/// A sample's share of its patch p's K_aa (81) from its v D (Dv), at rest
/// offset xi: v D[j][k] xi_j xi_k in active mode columns k, else 0.
static inline FASCIA_HD void fascia_pt_modes_sample_share(const fascia_pt_modes *md, int32_t p, const fascia_real *xi,
                                                          const fascia_real *Dv, fascia_real *share) {
  fascia_real column[9]; // xi_k in active columns, else 0
  for (int k = 0; k < 9; ++k) column[k] = fascia_pt_mode_active(md, p, k) ? xi[k % 3] : 0;
  for (int j = 0; j < 9; ++j)
    for (int k = 0; k < 9; ++k) share[9 * j + k] = Dv[9 * j + k] * xi[j % 3] * column[k];
}

/// A pair's share of K_ue (6x9) from its B^T v D (BtDv): columns k scaled
/// by xi_k, active mode columns only.
static inline FASCIA_HD void fascia_pt_modes_pair_share(const fascia_pt_modes *md, int32_t p, const fascia_real *xi,
                                                        const fascia_real *BtDv, fascia_real *share) {
  fascia_real column[9];
  for (int k = 0; k < 9; ++k) column[k] = fascia_pt_mode_active(md, p, k) ? xi[k % 3] : 0;
  for (int row = 0; row < 6; ++row)
    for (int k = 0; k < 9; ++k) share[9 * row + k] = BtDv[9 * row + k] * column[k];
}

/// Patch p at the state st (after its evaluation, its samples' cache and
/// the patches' gradients G_e current): K_aa and the coupling K_ue of the
/// modes with each support entry's frame, both including the patch's
/// rank-one term, into the factors W_e. pair_scratch: [6P] rows, each
/// sample's own part written (where the rotation coupling acts).
/// sample_share [81 S] and pair_share [54 P], both or neither, hold the
/// shares of the samples without rotation coupling at this state (the
/// assembly, which has their D and B^T D, leaves them there); else they
/// are computed here, the same way.
FASCIA_STATIC_FORCE_INLINE FASCIA_HD void fascia_pt_modes_tangent(const fascia_pt_model *m, const fascia_pt_state *st,
                                                     const fascia_pt_patches *t, const fascia_pt_modes *md, int32_t p,
                                                     const fascia_real *cache, fascia_real *pair_scratch,
                                                     const fascia_real *sample_share, const fascia_real *pair_share) {
  if (!md->active[p]) return; // its factors stay zero
  fascia_real K[81] = {0}, g[9] = {0};
  for (int64_t q = 54 * (int64_t)t->support_offsets[p]; q < 54 * (int64_t)t->support_offsets[p + 1]; ++q)
    md->entry_factor[q] = 0;
  const int law = t->law[p];
  for (int32_t q = t->patch_offsets[p]; q < t->patch_offsets[p + 1]; ++q) {
    const int32_t s = t->patch_samples[q], begin = m->sample_offsets[s], end = m->sample_offsets[s + 1];
    const fascia_real v = m->sample_volume[s], *xi = md->sample_xi + 3 * (int64_t)s;
    const fascia_real *c = cache + (int64_t)s * FASCIA_PT_CACHE_SIZE;
    fascia_real dtheta[9], *rows = pair_scratch + 6 * (int64_t)begin;
    fascia_pt_dilatation(law, c, dtheta);
    for (int j = 0; j < 9; ++j) g[j] += v * xi[j % 3] * dtheta[j];
    if (!(m->sample_coupling[s] > 0)) { // from v D and B^T v D, as the assembly's local blocks
      fascia_real Dv[81], own[81];
      const fascia_real *share = sample_share ? sample_share + 81 * (int64_t)s : own;
      if (!sample_share) {
        fascia_pt_sample_tangent_volume(m, s, c, Dv);
        fascia_pt_modes_sample_share(md, p, xi, Dv, own);
      }
      for (int u = 0; u < 81; ++u) K[u] += share[u];
      for (int32_t kk = begin; kk < end; ++kk) {
        fascia_real *Ke = md->entry_factor + 54 * (int64_t)t->pair_entry[kk], BtDv[54];
        const fascia_real *pshare = pair_share ? pair_share + 54 * (int64_t)kk : own;
        if (!pair_share) {
          fascia_pt_pair_BtD(m, st, kk, Dv, BtDv);
          fascia_pt_modes_pair_share(md, p, xi, BtDv, own);
        }
        for (int u = 0; u < 54; ++u) Ke[u] += pshare[u];
      }
      continue;
    }
    for (int k = 0; k < 9; ++k) { // the rotation coupling's part too: the full response per mode
      if (!fascia_pt_mode_active(md, p, k)) continue;
      fascia_real dF[9] = {0}, dP[9];
      dF[k] = xi[k % 3];
      fascia_pt_sample_F_response(m, st, s, c, dF, rows, dP);
      for (int j = 0; j < 9; ++j) K[9 * j + k] += v * xi[j % 3] * dP[j];
      for (int32_t kk = begin; kk < end; ++kk) {
        fascia_real *Ke = md->entry_factor + 54 * (int64_t)t->pair_entry[kk];
        for (int row = 0; row < 6; ++row) Ke[9 * row + k] += rows[6 * (kk - begin) + row];
      }
    }
  }
  const fascia_real c = t->lambda[p] / t->volume[p];
  for (int j = 0; j < 9; ++j)
    for (int k = 0; k < 9; ++k) K[9 * j + k] += c * g[j] * g[k];
  for (int32_t e = t->support_offsets[p]; e < t->support_offsets[p + 1]; ++e) {
    const fascia_real *G = t->entry_gradient + 6 * (int64_t)e;
    fascia_real *Ke = md->entry_factor + 54 * (int64_t)e;
    for (int row = 0; row < 6; ++row)
      for (int k = 0; k < 9; ++k)
        if (fascia_pt_mode_active(md, p, k)) Ke[9 * row + k] += c * G[row] * g[k];
  }
  // W_e = K_ue L^-T: row r of W_e solves L w = K_ue[r]
  int idx[9], n;
  fascia_real L[81];
  const int factored = fascia_pt_modes_factor(md, p, K, idx, &n, L);
  for (int32_t e = t->support_offsets[p]; e < t->support_offsets[p + 1]; ++e) {
    fascia_real *W = md->entry_factor + 54 * (int64_t)e;
    for (int row = 0; row < 6; ++row) {
      fascia_real w[9];
      for (int u = 0; u < n; ++u) {
        fascia_real sum = W[9 * row + idx[u]];
        for (int k = 0; k < u; ++k) sum -= L[n * u + k] * w[k];
        w[u] = sum / L[n * u + u];
      }
      for (int j = 0; j < 9; ++j) W[9 * row + j] = 0;
      for (int u = 0; u < n && factored; ++u) W[9 * row + u] = w[u];
    }
  }
}

/// The condensed term's coefficient of patch p for the direction v [6N]:
/// reduced_p = W_p^T v (= L^-1 K_au v).
static inline FASCIA_HD void fascia_pt_modes_reduce(const fascia_pt_patches *t, const fascia_pt_modes *md, int32_t p,
                                                    const fascia_real *v) {
  fascia_real y[9] = {0};
  for (int32_t e = md->active[p] ? t->support_offsets[p] : 0; e < (md->active[p] ? t->support_offsets[p + 1] : 0); ++e) {
    const fascia_real *W = md->entry_factor + 54 * (int64_t)e, *x = v + 6 * (int64_t)t->entry_frame[e];
    for (int row = 0; row < 6; ++row)
      for (int k = 0; k < 9; ++k) y[k] += W[9 * row + k] * x[row];
  }
  for (int j = 0; j < 9; ++j) md->reduced[9 * p + j] = y[j];
}

/// out -= frame i's rows of the condensed terms: sum over its entries of W_e reduced_p.
static inline FASCIA_HD void fascia_pt_modes_frame_add(const fascia_pt_patches *t, const fascia_pt_modes *md,
                                                       int32_t i, fascia_real *out) {
  for (int32_t r = t->frame_entry_offsets[i]; r < t->frame_entry_offsets[i + 1]; ++r) {
    const int32_t e = t->frame_entries[r];
    const int width = fascia_pt_modes_width(md, t->entry_patch[e]);
    if (!width) continue;
    const fascia_real *W = md->entry_factor + 54 * (int64_t)e, *z = md->reduced + 9 * (int64_t)t->entry_patch[e];
    for (int row = 0; row < 6; ++row) {
      const fascia_real sum = fascia_pt_modes_dot(W + 9 * row, z, width);
      out[row] -= sum;
    }
  }
}

/// B -= the condensed term's block between support entries e and f of one
/// patch: W_e W_f^T (6x6, row-major).
static inline FASCIA_HD void fascia_pt_modes_block_add(const fascia_pt_patches *t, const fascia_pt_modes *md,
                                                       int32_t e, int32_t f, fascia_real *B) {
  const int width = fascia_pt_modes_width(md, t->entry_patch[e]);
  if (!width) return;
  const fascia_real *We = md->entry_factor + 54 * (int64_t)e, *Wf = md->entry_factor + 54 * (int64_t)f;
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) B[6 * a + b] -= fascia_pt_modes_dot(We + 9 * a, Wf + 9 * b, width);
}

/// B -= frame i's 6x6 diagonal block of the condensed terms: sum over its
/// entries of W_e W_e^T.
static inline FASCIA_HD void fascia_pt_modes_frame_diagonal_add(const fascia_pt_patches *t, const fascia_pt_modes *md,
                                                                int32_t i, fascia_real *B) {
  for (int32_t r = t->frame_entry_offsets[i]; r < t->frame_entry_offsets[i + 1]; ++r) {
    const int32_t e = t->frame_entries[r];
    fascia_pt_modes_block_add(t, md, e, e, B);
  }
}

/// The model as patch p's local solve reads it: without the patches'
/// pressures (the solve brings its own) and without the modes' enhanced F
/// (it adds the amplitudes it tries).
static inline FASCIA_HD fascia_pt_model fascia_pt_modes_local_model(const fascia_pt_model *m) {
  fascia_pt_model own = *m;
  own.sample_pressure = (const fascia_real *)0;
  own.sample_enhanced = (const fascia_real *)0;
  return own;
}

#endif
