// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Organ models inside the solver (organs.c): rigid organs as one 6-DOF body
// whose coupling frames move rigidly with it, eliminated from the Newton
// systems by a prolongation P; organs driven by an outside simulator. See
// the design note at the top of organs.c.
#ifndef FASCIA_SRC_ORGANS_H
#define FASCIA_SRC_ORGANS_H

#include "point/body.h"
#include "cpu/assemble.h"
#include "cpu/system.h"
#include "solve/motion.h"

typedef struct fascia_organs fascia_organs;

/// The run's state arrays the organs read and write (the solver's): frame
/// positions [3N], rotations [4N], velocities [6N], a step's increments [6N]
/// and its anchor [3N], [4N].
typedef struct fascia_organs_state {
  fascia_real *x, *q, *u, *d;
  const fascia_real *x_base, *q_base;
} fascia_organs_state;

/// Builds the organ state of a solver: mass properties of rigid organs, the
/// master and slave frames, the masks. Checks that every coupling frame of a
/// rigid organ is a free frame of one rigid organ only. *out is NULL when
/// the model has no organ.
FASCIA_INTERN fascia_status fascia_organs_create(fascia_ctx *ctx, const fascia_model *model, fascia_organs **out);
FASCIA_INTERN void fascia_organs_destroy(fascia_organs **organs);

/// Fills the solver's mask, its only writer (free DOFs of the reduced
/// coordinates: free tissue frames and the master frame of each simulated
/// rigid organ), and the organs' own full mask (every frame the tissue may
/// move). O NULL (a model without organs): the free frames.
FASCIA_INTERN void fascia_organs_masks(const fascia_model *m, fascia_organs *O, unsigned char *mask);

/// Static solve: puts frames driven by the caller at their targets.
FASCIA_INTERN void fascia_organs_place(const fascia_organs *O, fascia_real *x, fascia_real *q);
/// Dynamic step of length h: anchors the bodies at the step's start
/// (st->x_base, q_base), sets their inertia targets and world inertia,
/// the increments st->d of frames driven by the caller, and expands d.
FASCIA_INTERN void fascia_organs_step_begin(fascia_organs *O, const fascia_organs_state *st, fascia_real h);
/// After a successful step of length h (its state st): the bodies'
/// velocities, and free flight under gravity of rigid organs without
/// coupling frames.
FASCIA_INTERN void fascia_organs_step_end(fascia_organs *O, const fascia_organs_state *st, const fascia_real *gravity,
                                          fascia_real h);

/// The bodies' table that every backend's body math reads (point/body.h);
/// NULL when the model has no rigid organ with coupling frames. Its active
/// flags say which bodies move now (fascia_organs_body_count of them).
FASCIA_INTERN const fascia_pt_bodies *fascia_organs_bodies(const fascia_organs *O);
/// [6N] every frame the tissue may move (the bodies' slaves included; the
/// solver's mask has only their masters); NULL without organs.
FASCIA_INTERN const unsigned char *fascia_organs_full_mask(const fascia_organs *O);

/// Prolongation of increments: overwrites the increments [6N] of each body's
/// slave frames from its master's (exactly rigid, nonlinear in the rotation).
FASCIA_INTERN void fascia_organs_expand(const fascia_organs *O, const fascia_real *x_base, const fascia_real *q_base,
                                        fascia_real *d);
/// At state x, q (increments d from x_base, q_base; gradient the full one
/// of Phi, may be NULL): the bodies' energy, their gradient folded into the
/// masters (fascia_pt_body_gradient).
FASCIA_INTERN fascia_real fascia_organs_reduce(const fascia_organs *O, const fascia_pt_body_step *step,
                                               const fascia_real *x, const fascia_real *q, const fascia_real *x_base,
                                               const fascia_real *q_base, const fascia_real *d, fascia_real *gradient);
/// The pattern of the reduced matrix P^T K P for the direct solver: K's
/// block pattern with every frame of a simulated rigid organ mapped to its
/// body's master frame; every row keeps its diagonal. R's values allocated.
FASCIA_INTERN fascia_status fascia_organs_reduced_pattern(fascia_ctx *ctx, const fascia_organs *O,
                                                          const fascia_bsr *K, fascia_bsr *R);
/// R = P^T K P at the state of sys, plus each body's mass and inertia
/// (mass_coefficient, as the operator's restriction) and the geometric
/// term of the last fascia_organs_reduce: the assembled form of that
/// operator on the reduced coordinates. Blocks of frames not in moves
/// (fascia_system_hessian_assemble; NULL: all) are not read.
FASCIA_INTERN void fascia_organs_reduce_matrix(const fascia_organs *O, const fascia_system *sys,
                                               const unsigned char *moves, fascia_real mass_coefficient,
                                               const fascia_bsr *K, fascia_bsr *R);
/// Squared norm of the loads on the bodies (gravity of the body, loads and
/// tissue weight on the slave frames) at load factor gs, for the Newton
/// tolerance.
FASCIA_INTERN fascia_real fascia_organs_load_norm2(const fascia_organs *O, const fascia_system *sys, fascia_real gs);

/// Body state that a failed step must restore: size in reals, save, restore.
FASCIA_INTERN size_t fascia_organs_state_size(const fascia_organs *O);
FASCIA_INTERN void fascia_organs_save(const fascia_organs *O, fascia_real *buffer);
FASCIA_INTERN void fascia_organs_restore(fascia_organs *O, const fascia_real *buffer);
/// After fascia_solver_set_state: bodies take the pose and velocity of
/// their master frame; slave frames are put rigidly on it (st->x, q, u).
FASCIA_INTERN void fascia_organs_sync(fascia_organs *O, const fascia_organs_state *st);

/// Kinetic energy of the bodies at rotations q [4N], and their gravity
/// energy at positions x, rotations q, J.
FASCIA_INTERN fascia_real fascia_organs_kinetic_energy(const fascia_organs *O, const fascia_real *q);
FASCIA_INTERN fascia_real fascia_organs_potential_energy(const fascia_organs *O, const fascia_real *x,
                                                         const fascia_real *q, const fascia_real *gravity);

/// The rigid organ whose body carries frame i (its master or a slave), -1
/// for none (O may be NULL).
FASCIA_INTERN int32_t fascia_organs_frame_body(const fascia_organs *O, int32_t i);

/// 1 when the caller drives some organ now (its work on the tissue is not
/// known to the solver); O may be NULL.
FASCIA_INTERN int fascia_organs_any_driven(const fascia_organs *O);
/// 1 when the caller drives organ's coupling frames.
FASCIA_INTERN int fascia_organs_driven(const fascia_organs *O, int32_t organ);

/// Number of rigid organs simulated as bodies with coupling frames (0: the
/// reduced and full coordinates coincide).
FASCIA_INTERN int32_t fascia_organs_body_count(const fascia_organs *O);

// The parts of the organ API (solve/organ_api.c); organ is a valid index.
/// Mass, centre and inertia of the organ's closed surface at
/// FASCIA_ORGAN_DENSITY; 0 where it encloses no volume.
FASCIA_INTERN int fascia_organs_mass_properties(const fascia_organ *o, fascia_real *mass, fascia_real *centre,
                                                fascia_real *inertia);
/// The organ's coupling frames: their count, and *frames (O's own array).
FASCIA_INTERN int32_t fascia_organs_frames(const fascia_organs *O, int32_t organ, const int32_t **frames);
/// The organ's pose now (translation [3], rotation [4] w x y z) at time
/// and state x, q: a posed organ's own, a prescribed organ's motion, a
/// rigid body's, identity for a deformable one. 0 (nothing written) for an
/// organ the caller drives frame by frame, which has no pose of its own.
FASCIA_INTERN int fascia_organs_pose(const fascia_organs *O, int32_t organ, fascia_real time, const fascia_real *x,
                                     const fascia_real *q, fascia_real *translation, fascia_real *rotation);
/// A rigid body's velocity, zero for any other organ (linear or angular may be NULL).
FASCIA_INTERN void fascia_organs_velocity(const fascia_organs *O, int32_t organ, fascia_real *linear,
                                          fascia_real *angular);
/// The caller drives the organ's coupling frames to positions [3 count]
/// and nonzero rotations [4 count] (normalized here); pose [7]
/// (translation, unit rotation) where they come from one, else NULL. The
/// solver's mask follows.
FASCIA_INTERN void fascia_organs_drive(fascia_organs *O, int32_t organ, const fascia_real *positions,
                                       const fascia_real *rotations, const fascia_real *pose, unsigned char *mask);
/// Hands a driven organ back to its model (a rigid body takes its slaves
/// again, st); 1 when it was driven, 0 (nothing changed) otherwise.
FASCIA_INTERN int fascia_organs_release(fascia_organs *O, int32_t organ, const fascia_organs_state *st,
                                        unsigned char *mask);
/// The tissue's force and torque on each coupling frame of the organ
/// (torques may be NULL) from the gradient g [6N] of the potential energy
/// at full load (the frames' loads taken out).
FASCIA_INTERN void fascia_organs_reaction(const fascia_organs *O, int32_t organ, const fascia_real *g,
                                          fascia_real *forces, fascia_real *torques);
/// The organ's reference point where the organ is now (at time, state x, q).
FASCIA_INTERN void fascia_organs_reference_point(const fascia_organs *O, int32_t organ, fascia_real time,
                                                 const fascia_real *x, const fascia_real *q, fascia_real *point);

#endif
