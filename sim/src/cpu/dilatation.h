// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Mean dilatation over volumetric patches, the cure of volumetric locking
// (docs/mechanics.md, "Volumetric locking"). The volumetric part of the
// energy, lambda/2 theta^2 (theta = tr E for StVK, J - 1 for the stable
// Neo-Hookean; each law is affine in lambda), is split: each sample keeps
// lambda_s = lambda mu / (lambda + mu) of it on its own theta_s (at most mu:
// no locking; the variation of theta across a patch is then as stiff as
// uniaxial stress), and the rest, lambda_p = lambda - lambda_s, is evaluated
// once per patch, on the volume average of theta over its samples:
//
//   E_vol = sum_s v_s lambda_s/2 theta_s^2 + sum_p V_p lambda_p/2 thetabar_p^2,
//   thetabar_p = sum_{s in p} v_s theta_s / V_p
//
// The samples' share is part of their law (fascia_pt_stress at lambda_s);
// what follows is the patch's share:
//   grad  = sum_p lambda_p thetabar_p G_p,      G_p = sum_{s in p} v_s grad theta_s
//   H     = sum_p lambda_p / V_p G_p G_p^T  +  lambda_p thetabar_p sum_{s in p} v_s hess theta_s
//
// The second Hessian term is per sample: each sample of p carries the
// pressure lambda_p thetabar_p (fascia_pt_model.sample_pressure), which the
// per-sample math adds to its stress and stress derivative, geometric part
// included. The first is one rank-one term per patch, applied here on the
// patch's support (the distinct frames its samples hang on). One constraint
// per patch instead of one per sample is what frees the locked modes.
#ifndef FASCIA_SRC_DILATATION_H
#define FASCIA_SRC_DILATATION_H

#include "point/patch.h"
#include "cpu/system.h"

/// The patches of a model as tables: which samples each holds, and the
/// distinct frames its samples hang on (its support); a support entry is one
/// (patch, frame) pair. Patches are numbered by ascending model patch number,
/// empty ones left out. Built from the model alone (the assembled matrix's
/// pattern needs it too).
/// Its arrays, declared once (members of the view, fascia_pt_patches, of the
/// same names): the members, their freeing and the view follow.
#define FASCIA_PATCH_TABLE_ARRAYS(X)                                                                                   \
  X(patch_offsets)       /* [patches+1] CSR into patch_samples */                                                      \
  X(patch_samples)       /* samples of each patch, ascending */                                                        \
  X(support_offsets)     /* [patches+1] CSR into entry_frame */                                                        \
  X(entry_frame)         /* [entries] frames of each patch's support, ascending */                                     \
  X(entry_patch)         /* [entries] */                                                                               \
  X(pair_entry)          /* [P] the support entry of pair k's frame, -1 for samples in no patch */                     \
  X(frame_entry_offsets) /* [N+1] CSR into frame_entries */                                                            \
  X(frame_entries)       /* the entries of each frame, ascending */

#define FASCIA_PATCH_TABLE_MEMBER(name) int32_t *name;
typedef struct fascia_patch_table {
  int32_t patch_count, entry_count;
  FASCIA_PATCH_TABLE_ARRAYS(FASCIA_PATCH_TABLE_MEMBER)
} fascia_patch_table;

/// Builds the tables; a model without patches gives patch_count 0 and no
/// arrays. On error the table is empty.
FASCIA_INTERN fascia_status fascia_patch_table_build(fascia_ctx *ctx, const fascia_model *model,
                                                     fascia_patch_table *table);
FASCIA_INTERN void fascia_patch_table_free(fascia_patch_table *table);

/// The arrays the mean-dilatation term owns, declared once: member, element
/// type, the count that sizes it (P patches, E support entries, S samples),
/// values per row, the view's member. The members, their allocation, check
/// and freeing and the view follow (dilatation.c).
#define FASCIA_DILATATION_ARRAYS(X)                                                                                    \
  X(patch_lambda, fascia_real, P, 1, lambda)                   /* Pa */                                                \
  X(patch_volume, fascia_real, P, 1, volume)                   /* V_p, m^3 */                                          \
  X(patch_law, int32_t, P, 1, law)                             /* FASCIA_PT_LAW_* */                                   \
  X(patch_theta, fascia_real, P, 1, theta)                     /* thetabar_p at the last evaluation */                 \
  X(patch_energy, fascia_real, P, 1, energy)                   /* J */                                                 \
  X(patch_rate, fascia_real, P, 1, rate)                       /* scratch of the Hessian product */                    \
  X(entry_gradient, fascia_real, E, 6, entry_gradient)         /* G_p on the entry's frame (x then theta) */           \
  X(sample_pressure, fascia_real, S, 1, sample_pressure)       /* lambda_p thetabar_p on p's samples, 0 elsewhere */   \
  X(sample_F, fascia_real, S, 9, sample_F) /* F of the samples in patches at the last evaluation (the patches and  */  \
                                           /* the samples' gradient read it) */

#define FASCIA_DILATATION_MEMBER(name, type, ...) type *name;

/// The mean-dilatation term of a system: its tables, the arrays it owns,
/// and the view of both the per-patch math reads (sim/point/patch.h).
typedef struct fascia_dilatation {
  fascia_patch_table table;
  FASCIA_DILATATION_ARRAYS(FASCIA_DILATATION_MEMBER)
  fascia_pt_patches view;       ///< all of the above, as the per-patch math reads them
  int gradients_current;        ///< entry_gradient is for the last evaluated state
} fascia_dilatation;

/// Makes the term for sys (NULL in *out when the model has no patch): the
/// samples in patches lose their own lambda, and sys->pm reads the pressures.
FASCIA_INTERN fascia_status fascia_dilatation_create(fascia_system *sys, fascia_dilatation **out);
FASCIA_INTERN void fascia_dilatation_destroy(fascia_dilatation **dilatation);

/// At the system's current state: every patch's mean dilatation and
/// pressure; returns E_vol (J), not finite when a patch's is not. The
/// gradients G_p wait for the first Hessian use (fascia_dilatation_gradients):
/// line-search trials and chord steps never need them.
FASCIA_INTERN fascia_real fascia_dilatation_evaluate(fascia_system *sys, fascia_dilatation *d);
/// The gradients G_p at the last evaluated state, unless they are there
/// already; the Hessian's users below call it, and so does the assembly.
FASCIA_INTERN void fascia_dilatation_gradients(const fascia_system *sys, fascia_dilatation *d);
/// out += sum_p lambda_p / V_p G_p (G_p . v): the rank-one terms.
FASCIA_INTERN void fascia_dilatation_apply_add(const fascia_system *sys, fascia_dilatation *d, const fascia_real *v,
                                               fascia_real *out);
/// Adds the rank-one terms' 6x6 diagonal blocks [36N].
FASCIA_INTERN void fascia_dilatation_diagonal_add(const fascia_system *sys, fascia_dilatation *d,
                                                  fascia_real *blocks);

#endif
