// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Enhanced strain modes over volumetric patches, the cure of the
// tetrahedral shape functions' stiffness in bending (docs/mechanics.md,
// "Enhanced strain modes"). Linear weights give every tetrahedron a nearly
// constant strain, so a bent beam's linear variation of strain across a
// patch costs spurious energy. Each patch p gets nine incompatible modes
// (Wilson's, as in the finite elements' enhanced assumed strain): sample s
// of p gains
//
//   F_s = F_s(frames) + E_s(a_p),   E_s[r][c] = a_p[3 r + c] xi_s[c],
//   xi_s = X_s - Xbar_p,   Xbar_p = sum_{s in p} v_s X_s / V_p
//
// and a_p minimizes the patch's energy with the frames held. Each mode
// averages to zero over its patch, so a uniform deformation leaves a_p = 0
// (the patch test); a rotation leaves it 0 too. The frames keep their six
// unknowns: a_p is solved afresh at each evaluation (a few Newton steps from
// 0, so it depends on the state alone and checkpoints need nothing new), and
// the energy E*(frames) = min_a E is what the solvers see:
//
//   grad E*  = dE/du at a_p                      (a_p is a minimum)
//   hess E*  = K_uu - K_ua K_aa^-1 K_au
//
// K_uu is the Hessian with a_p held (the samples' own, at the enhanced F),
// K_aa (9x9) and K_ua (6 per support frame x 9) the second derivatives in
// the modes, each including the patch's mean-dilatation term. The last term
// is one rank-9 term per patch, applied on its support like the patch's
// rank-one term. A mode column whose samples all lie in one plane
// perpendicular to it (|xi_c| = 0) is left out.
#ifndef FASCIA_SRC_MODES_H
#define FASCIA_SRC_MODES_H

#include "point/modes.h"
#include "cpu/system.h"

struct fascia_dilatation;

/// The modes of a system: the arrays it owns and the view the per-patch
/// math reads (sim/point/modes.h). On the patches of the system's
/// mean-dilatation term.
/// The arrays the per-patch math reads, declared once: member (of the view
/// too), element type, the count that sizes it (P patches, S samples, E
/// support entries), values per row. From the list follow the members,
/// their allocation, check and freeing, and the view (modes.c).
#define FASCIA_MODES_ARRAYS(X)                                                                                         \
  X(active, int32_t, P, 1)                                                                                             \
  X(xi_max, fascia_real, P, 3)                                                                                         \
  X(sample_xi, fascia_real, S, 3)                                                                                      \
  X(amplitude, fascia_real, P, 9)                                                                                      \
  X(sample_enhanced, fascia_real, S, 9)                                                                                \
  X(entry_factor, fascia_real, E, 54)                                                                                  \
  X(reduced, fascia_real, P, 9)                                                                                        \
  X(failed, int32_t, P, 1)

#define FASCIA_MODES_MEMBER(name, type, ...) type *name;
typedef struct fascia_modes {
  FASCIA_MODES_ARRAYS(FASCIA_MODES_MEMBER)
  fascia_pt_modes view;
  int tangent_current; ///< entry_factor is for the last evaluated state
  /// [81 S] and [54 P]: the samples' and pairs' shares of K_aa and K_ue
  /// (fascia_pt_modes_sample_share, _pair_share) that the assembly leaves
  /// from the D and B^T D it computes anyway, so the tangent need not
  /// compute them again (made at the first assembly: the matrix-free path
  /// has no use for them); current: they are for the last evaluated state
  fascia_real *sample_share, *pair_share;
  int shares_current;
} fascia_modes;

/// Makes the modes for sys (NULL in *out when the model asks for none);
/// the model must have patches. sys->pm.sample_enhanced reads them.
FASCIA_INTERN fascia_status fascia_modes_create(fascia_system *sys, fascia_modes **out);
FASCIA_INTERN void fascia_modes_destroy(fascia_modes **modes);

/// At the system's current state: every patch's amplitudes and its samples'
/// enhanced F (before the patches' dilatation and the samples' energies).
/// Returns the lowest patch whose local solve failed, or -1.
FASCIA_INTERN int32_t fascia_modes_evaluate(fascia_system *sys, fascia_modes *md);
/// out -= sum_p K_up K_aa^-1 K_pu v: the condensed terms.
FASCIA_INTERN void fascia_modes_apply_add(const fascia_system *sys, fascia_modes *md, const fascia_real *v,
                                          fascia_real *out);
/// Adds the condensed terms' 6x6 diagonal blocks [36N].
FASCIA_INTERN void fascia_modes_diagonal_add(const fascia_system *sys, fascia_modes *md, fascia_real *blocks);
/// The factors W_e = K_ue L^-T (L L^T = K_aa) at the last evaluated
/// state, unless current (the assembly calls it, then reads md->view);
/// from the assembly's shares where they are current.
FASCIA_INTERN void fascia_modes_tangent(const fascia_system *sys, fascia_modes *md);
/// Makes the shares' arrays where they are not yet; 0 when out of memory
/// (the assembly then leaves no shares, and the tangent computes them).
FASCIA_INTERN int fascia_modes_shares_ready(const fascia_system *sys, fascia_modes *md);
/// The patch of sample s whose modes act, or -1 (no patch, no active
/// mode, or the rotation coupling, whose share the tangent computes).
FASCIA_INTERN int32_t fascia_modes_sample_patch(const fascia_system *sys, const fascia_modes *md, int32_t s);

#endif
