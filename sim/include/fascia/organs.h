// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Organs in the solver (docs/organs.md, paper sec. 4.2): the pose of
// fixed, prescribed and rigid organs, and the C API through which an outside
// simulator drives the coupling frames of an organ and reads back the forces
// the tissue applies on them.
//
// Units are SI throughout (m, s, kg, N, N m); every position, rotation,
// force and torque is in the world frame. Rotations are unit quaternions
// (w, x, y, z).
#ifndef FASCIA_ORGANS_H
#define FASCIA_ORGANS_H

#include "fascia/solver.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Density of rigid organs, kg/m^3: the model stores no density per organ,
/// so the mass and inertia of a rigid organ are those of its closed surface
/// filled at this density (soft tissue is close to water).
#define FASCIA_ORGAN_DENSITY 1000.0

/// Organ index by name, -1 if absent.
FASCIA_API int32_t fascia_model_find_organ(const fascia_model *model, const char *name);

/// Mass (kg), rest centre of mass (m, world) and inertia tensor about that
/// centre at rest (kg m^2, world axes, row-major 3x3) of the organ's closed
/// surface filled at FASCIA_ORGAN_DENSITY. Any pointer may be NULL.
/// FASCIA_ERR_ARGUMENT for a bad index or a surface that encloses no volume.
FASCIA_API fascia_status fascia_solver_organ_mass(const fascia_solver *solver, int32_t organ, fascia_real *mass,
                                                  fascia_real *centre, fascia_real *inertia);

/// Where an organ's surface vertices are now ([3 vertex_count] m, world),
/// for drawing it: fixed, prescribed and rigid organs by their pose; a
/// deformable organ carried by its own frames (and its coupling frames) the
/// way samples are, each vertex by the few frames nearest it at rest with
/// positive kernel weights (exact for any rigid motion); an organ driven by
/// the caller following its first coupling frame rigidly.
FASCIA_API fascia_status fascia_solver_organ_surface(const fascia_solver *solver, int32_t organ,
                                                     fascia_real *positions);
/// Where the tissue surface's vertices are now (model->tissue_surface;
/// [3 vertex_count] m, world), carried by the tissue frames the way samples
/// are (each vertex by the few frames nearest it at rest, positive kernel
/// weights); strain [vertex_count] (may be NULL): the Green-Lagrange strain
/// norm of the tissue sample nearest each vertex at rest. Nothing to do when
/// the model has no tissue surface.
FASCIA_API fascia_status fascia_solver_tissue_surface(const fascia_solver *solver, fascia_real *positions,
                                                      fascia_real *strain);
/// The model's tissue surface at rest (vertex and triangle counts, arrays
/// owned by the model), never NULL: for bindings that keep the model opaque.
FASCIA_API const fascia_surface *fascia_model_tissue_surface(const fascia_model *model);
/// Current pose of an organ as the rigid map from its rest surface to the
/// world: p_world = R p_rest + translation, R the rotation of `rotation`.
/// Fixed organs: identity. Prescribed: their motion at the solver's time.
/// Rigid: the body's pose (part of the solver state). An organ driven by
/// fascia_solver_organ_set_pose: the pose last given. An organ driven
/// frame by frame (fascia_solver_organ_set_frames) has no pose of its own:
/// FASCIA_ERR_UNSUPPORTED, outputs untouched.
FASCIA_API fascia_status fascia_solver_organ_pose(const fascia_solver *solver, int32_t organ,
                                                  fascia_real *translation, fascia_real *rotation);

/// Velocity of a rigid organ: of its centre of mass (m/s) and angular
/// (rad/s), world. Other kinds: zero.
FASCIA_API fascia_status fascia_solver_organ_velocity(const fascia_solver *solver, int32_t organ,
                                                      fascia_real *linear, fascia_real *angular);

/// Number of coupling frames of an organ (frames shared by the tissue and
/// the organ), 0 for a bad index.
FASCIA_API int32_t fascia_solver_organ_frame_count(const fascia_solver *solver, int32_t organ);
/// Frame indices of an organ's coupling frames [fascia_solver_organ_frame_count],
/// in the order of the model's coupling table (each frame once). Every array
/// argument below uses this order.
FASCIA_API fascia_status fascia_solver_organ_frames(const fascia_solver *solver, int32_t organ, int32_t *frames);

/// Outside simulator: sets where the coupling frames of `organ` are at the
/// end of the next step (or in the next static solve): positions [3C] m and
/// rotations [4C] (the frame's full rotation; at rest it is the model's
/// frame_rotation, usually identity), world, C = the organ's frame count.
/// From this call on the organ is driven by the caller whatever its kind in
/// the model: its coupling frames are prescribed (they move linearly in time
/// from where they are to the given pose during the next step, then stay)
/// and a rigid organ's own body is not simulated. Non-finite values or a
/// zero quaternion: FASCIA_ERR_ARGUMENT, nothing changed.
FASCIA_API fascia_status fascia_solver_organ_set_frames(fascia_solver *solver, int32_t organ,
                                                        const fascia_real *positions, const fascia_real *rotations);

/// Outside simulator, the organ as one rigid body: moves the coupling frames
/// of `organ` (fixed, prescribed, rigid or already driven) by the rigid map
/// p_world = R p_rest + translation from their rest poses (R the rotation
/// of the unit quaternion `rotation`, w x y z; normalized here), as
/// fascia_solver_organ_set_frames with those frames: they reach the pose at
/// the end of the next step (or in the next static solve) and stay there,
/// and from this call on the organ is driven by the caller whatever its kind
/// in the model. fascia_solver_organ_pose then returns this pose.
/// Non-finite values or a zero quaternion: FASCIA_ERR_ARGUMENT, nothing
/// changed.
FASCIA_API fascia_status fascia_solver_organ_set_pose(fascia_solver *solver, int32_t organ,
                                                      const fascia_real *translation, const fascia_real *rotation);

/// Hands an organ driven by the caller back to its model kind from the
/// current state (a rigid organ's body takes the pose and velocity of its
/// coupling frames: fixed and prescribed organs jump back to their motion at
/// the next step).
FASCIA_API fascia_status fascia_solver_organ_release(fascia_solver *solver, int32_t organ);

/// The reaction of the tissue on an organ: forces [3C] (N) and torques [3C]
/// (N m, about each frame's own position) that the tissue applies on the
/// organ's coupling frames at the current state, i.e. minus the gradient of
/// the tissue's potential energy with respect to each frame's position and
/// world rotation angle: elastic energy plus the weight of the tissue that
/// the frame scheme carries on that frame (zero without gravity). Loads the
/// model applies directly to the frames (frame_load) are not part of it. At a
/// static equilibrium, reaction + applied loads = 0 on every free frame.
/// torques may be NULL. FASCIA_ERR_NUMERIC when the state is not finite.
FASCIA_API fascia_status fascia_solver_organ_reaction(fascia_solver *solver, int32_t organ, fascia_real *forces,
                                                      fascia_real *torques);

/// The resultant of fascia_solver_organ_reaction on an organ: force [3]
/// (N), the sum over its coupling frames, and torque [3] (N m) about the
/// organ's reference point, the sum of each frame's torque and the moment
/// of its force about that point. The reference point is the centre of the
/// volume the organ's rest surface encloses (fascia_solver_organ_mass's
/// centre; the mean of its rest vertices where the surface encloses no
/// volume) carried by the organ's current pose: fascia_solver_organ_pose,
/// or for an organ driven through fascia_solver_organ_set_frames the rigid
/// motion of its first coupling frame; a deformable organ's stays at rest.
/// point [3] (m, world; may be NULL) gets that point. torque may be NULL.
/// An organ with no coupling frame gets zeros. FASCIA_ERR_NUMERIC when the
/// state is not finite.
FASCIA_API fascia_status fascia_solver_organ_wrench(fascia_solver *solver, int32_t organ, fascia_real *force,
                                                    fascia_real *torque, fascia_real *point);

/// Number of organs of a model, and the name of organ k ("" for a bad
/// index): for bindings that keep the model opaque.
FASCIA_API int32_t fascia_model_organ_count(const fascia_model *model);
FASCIA_API const char *fascia_model_organ_name(const fascia_model *model, int32_t organ);

#ifdef __cplusplus
}
#endif
#endif
