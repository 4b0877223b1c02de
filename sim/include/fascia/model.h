// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The model: frames (6 DOF), samples (integration points), the two neighbour
// tables, materials, boundary conditions, probes, organs and coupling. This is
// what the model file holds (schema in docs/model-format.md) and what prep
// builds. docs/mechanics.md gives the notation.
//
// Unlike most fascia objects the model is a plain structure of arrays: prep,
// scene generators and the file reader fill it directly, and every backend
// reads it. fascia_model_alloc sizes every array; fascia_model_validate is the
// one gate every model passes before a solver sees it.
#ifndef FASCIA_MODEL_H
#define FASCIA_MODEL_H

#include "fascia/base.h"

#ifdef __cplusplus
extern "C" {
#endif

#define FASCIA_NAME_SIZE 64

/// Constitutive laws. Values are stored in model files: never renumber.
typedef enum fascia_law {
  FASCIA_LAW_STVK = 0,       ///< Saint-Venant-Kirchhoff (the paper's)
  FASCIA_LAW_NEOHOOKEAN = 1, ///< stable Neo-Hookean, defined under inversion
  FASCIA_LAW_COUNT_
} fascia_law;

/// Which part of a material's energy its samples integrate. Splitting the
/// volumetric (lambda) term onto fewer samples than the deviatoric (mu) term
/// is selective reduced integration, the cure of volumetric locking as nu
/// approaches 1/2 (docs/mechanics.md). Values are stored in model files.
typedef enum fascia_material_part {
  FASCIA_PART_FULL = 0,        ///< the whole energy
  FASCIA_PART_DEVIATORIC = 1,  ///< lambda dropped; the samples carry the mass
  FASCIA_PART_VOLUMETRIC = 2,  ///< mu dropped; no mass, no rotation coupling or smoothing
  FASCIA_PART_COUNT_
} fascia_material_part;

/// Which enhanced strain modes a volumetric patch carries (sample_modes;
/// docs/mechanics.md, "Enhanced strain modes"). Mode j = 3 r + c adds a_j
/// xi_c to entry (r, c) of each sample's F. Values are stored in model
/// files: never renumber.
typedef enum fascia_modes_set {
  FASCIA_MODES_NONE = 0,
  /// all nine, Wilson's incompatible modes: the cure of the tetrahedra's
  /// constant strain in bending
  FASCIA_MODES_NINE = 1,
  /// the three normal ones, F_cc along X_c: the quadratic stretch along an
  /// offset that a frame's rotation (which moves a sample across its offset)
  /// cannot give; for weights that already vary the strain across a cell
  FASCIA_MODES_NORMAL = 2,
  FASCIA_MODES_COUNT_
} fascia_modes_set;

/// Largest Young's modulus (Pa) and density (kg/m^3) a model may hold: past
/// any real solid (diamond: 1.2e12 Pa; osmium: 2.3e4 kg/m^3), and far enough
/// below overflow that energies and forces stay meaningful in double.
#define FASCIA_MAX_MODULUS 1e13
#define FASCIA_MAX_DENSITY 1e6

/// How a frame moves. Values are stored in model files: never renumber.
typedef enum fascia_frame_kind {
  FASCIA_FRAME_FREE = 0,       ///< a degree of freedom of the solver
  FASCIA_FRAME_FIXED = 1,      ///< stays at its rest position and rotation
  FASCIA_FRAME_PRESCRIBED = 2, ///< follows a rigid motion (frame_motion)
  FASCIA_FRAME_KIND_COUNT_
} fascia_frame_kind;

/// How an organ is simulated. Values are stored in model files.
typedef enum fascia_organ_kind {
  FASCIA_ORGAN_FIXED = 0,
  FASCIA_ORGAN_PRESCRIBED = 1,
  FASCIA_ORGAN_RIGID = 2,
  FASCIA_ORGAN_DEFORMABLE = 3,
  FASCIA_ORGAN_KIND_COUNT_
} fascia_organ_kind;

/// A material. The solver derives Lame parameters per sample from it.
typedef struct fascia_material {
  char name[FASCIA_NAME_SIZE];
  int32_t law;                ///< fascia_law
  fascia_real youngs_modulus; ///< E, Pa, > 0
  fascia_real poisson_ratio;  ///< nu, in [0, 0.5)
  fascia_real density;        ///< kg/m^3, > 0
  /// Cosserat coupling modulus as a fraction of mu: ties each frame's rotation
  /// to the material rotation around it (cures the zero-energy rotation modes
  /// of the frame scheme, see docs/mechanics.md). 0 gives the paper's scheme.
  fascia_real rotation_coupling;
  /// Rotation smoothing r (dimensionless): a Cosserat curvature energy
  /// mu (r h)^2 |grad R|^2, h the sample's distance to its frames, that removes
  /// the zero-energy twist modes of the frame scheme while leaving smooth
  /// rotation fields nearly free; its effect on smooth fields vanishes as h^2
  /// under refinement (see docs/mechanics.md). 0 gives the paper's scheme.
  fascia_real rotation_smoothing;
  int32_t part; ///< fascia_material_part
} fascia_material;

/// A rigid motion given by keyframes, linear in translation and spherical
/// linear in rotation, held constant after the last key. A frame following it
/// is at  pivot + T(t) + Q(t) (x_rest - pivot)  with rotation  Q(t) R_rest.
typedef struct fascia_motion {
  char name[FASCIA_NAME_SIZE];
  fascia_real pivot[3];         ///< m, world
  int32_t key_count;            ///< >= 1
  fascia_real *key_time;        ///< [key_count] s, strictly increasing
  fascia_real *key_translation; ///< [3 key_count] m
  fascia_real *key_rotation;    ///< [4 key_count] unit quaternions (w, x, y, z)
} fascia_motion;

/// An organ: its surface (for coupling and pictures) and how it is simulated.
typedef struct fascia_organ {
  char name[FASCIA_NAME_SIZE];
  int32_t kind;           ///< fascia_organ_kind
  int32_t motion;         ///< motion index for PRESCRIBED, else -1
  int32_t vertex_count;   ///< surface vertices
  int32_t triangle_count; ///< surface triangles
  fascia_real *vertices;  ///< [3 vertex_count] m, rest
  int32_t *triangles;     ///< [3 triangle_count] vertex indices
} fascia_organ;

/// A triangle surface at rest: what the tissue looks like (drawing only).
typedef struct fascia_surface {
  int32_t vertex_count;   ///< vertices
  int32_t triangle_count; ///< triangles
  fascia_real *vertices;  ///< [3 vertex_count] m, rest
  int32_t *triangles;     ///< [3 triangle_count] vertex indices, outward
} fascia_surface;

/// Array sizes of a model, for fascia_model_alloc.
typedef struct fascia_model_sizes {
  int32_t frames, samples, pairs, materials, motions, probes, probe_pairs, organs, couplings;
} fascia_model_sizes;

/// The model. Indices are int32_t; every array is allocated by
/// fascia_model_alloc with the sizes given there and owned by the model.
/// N frames, S samples, P sample-frame pairs, Q probes.
typedef struct fascia_model {
  int32_t frame_count, sample_count, pair_count;
  int32_t material_count, motion_count, probe_count, probe_pair_count;
  int32_t organ_count, coupling_count;

  // Frames (rest state).
  fascia_real *frame_position; ///< [3N] x_rest, m, world
  fascia_real *frame_rotation; ///< [4N] R_rest as unit quaternion (w, x, y, z)
  int32_t *frame_kind;         ///< [N] fascia_frame_kind
  int32_t *frame_motion;       ///< [N] motion index for PRESCRIBED frames, else -1
  fascia_real *frame_load;     ///< [6N] constant external force (N) then torque (N m), world
  int32_t *frame_organ;        ///< [N] the deformable organ a frame belongs to, -1 for tissue frames

  // Samples (integration points).
  fascia_real *sample_position; ///< [3S] p_rest, m, world
  fascia_real *sample_volume;   ///< [S] m^3, > 0
  int32_t *sample_material;     ///< [S] material index
  int32_t *sample_organ;        ///< [S] the deformable organ a sample belongs to, -1 for tissue samples
  /// [S] the volumetric patch of a sample, -1 for none. The samples of one
  /// patch (same material) share the volumetric part of their energy: it is
  /// evaluated on the patch's volume-averaged dilatation (mean dilatation),
  /// which cures volumetric locking as nu approaches 1/2 (docs/mechanics.md).
  /// A sample with -1 integrates its whole energy itself.
  int32_t *sample_patch;
  /// [S] the enhanced strain modes of the sample's patch (fascia_modes_set:
  /// 0, the default, none; 1 all nine; 2 the three normal ones), solved
  /// afresh at each evaluation (docs/mechanics.md, "Enhanced strain modes":
  /// the cure of the shape functions' stiffness in bending); every sample
  /// of that patch says the same.
  int32_t *sample_modes;

  // Sample -> frames (CSR): pairs of sample s are sample_offsets[s] ..
  // sample_offsets[s+1]-1, frames ascending within a sample.
  int32_t *sample_offsets;    ///< [S+1]
  int32_t *pair_frame;        ///< [P] frame index
  fascia_real *pair_weight;   ///< [P] w_is, sum over a sample = 1
  fascia_real *pair_gradient; ///< [3P] rest-space gradient of w_is, 1/m; sum = 0

  // Frame -> samples (CSR reverse table): the pairs of frame i, ascending.
  // Every per-frame sum goes through it, in this order (determinism).
  int32_t *frame_offsets; ///< [N+1]
  int32_t *frame_pairs;   ///< [P] pair indices

  fascia_material *materials; ///< [material_count]
  fascia_motion *motions;     ///< [motion_count]; keys via fascia_motion_alloc

  // Probes: named points carried by the frames like samples (no volume).
  char (*probe_name)[FASCIA_NAME_SIZE]; ///< [Q]
  fascia_real *probe_position;          ///< [3Q] rest, m
  int32_t *probe_offsets;               ///< [Q+1] CSR into probe_frame/probe_weight
  int32_t *probe_frame;                 ///< [probe_pair_count]
  fascia_real *probe_weight;            ///< [probe_pair_count], sum over a probe = 1

  // Organs and coupling: coupling frame c is tissue frame coupling_frame[c],
  // shared with organ coupling_organ[c], sitting on its surface triangle
  // coupling_triangle[c] at barycentric coordinates coupling_barycentric[3c..].
  fascia_organ *organs;              ///< [organ_count]; meshes via fascia_organ_alloc
  int32_t *coupling_organ;           ///< [couplings]
  int32_t *coupling_frame;           ///< [couplings]
  int32_t *coupling_triangle;        ///< [couplings]
  fascia_real *coupling_barycentric; ///< [3 couplings]

  fascia_real gravity[3]; ///< m/s^2, world
  /// 1: the model may hold pieces that nothing fixes or prescribes (a body in
  /// free fall, a rigid organ tossed with its tissue); 0, the default: such a
  /// piece is a model error (fascia_model_validate refuses it).
  int32_t allow_floating;
  char *provenance;       ///< JSON text: what made this model, from what (may be NULL)
  /// The boundary of the tissues' regions, smoothed (prep; empty when the
  /// model has none): drawn carried by the frames
  /// (fascia_solver_tissue_surface). No part of the mechanics: the
  /// fingerprint leaves it out.
  fascia_surface tissue_surface;
  /// The tetrahedra of tissues with tetrahedral shape functions (prep; none
  /// otherwise): the frames at their corners, for drawing them. No part of
  /// the mechanics (the samples' weights are), left out of the fingerprint.
  int32_t tetrahedron_count;
  int32_t *tetrahedra; ///< [4 tetrahedron_count] frame indices
} fascia_model;

/// Allocates a model with every array sized and zeroed (frame rotations set to
/// identity, frame_motion, frame_organ and sample_organ to -1,
/// sample_offsets/frame_offsets to 0). On error
/// *out is NULL.
FASCIA_API fascia_status fascia_model_alloc(fascia_ctx *ctx, const fascia_model_sizes *sizes, fascia_model **out);
/// Frees a model and everything it owns; accepts NULL, sets *model to NULL.
FASCIA_API void fascia_model_destroy(fascia_model **model);
/// Allocates the key arrays of a motion (key_count >= 1).
FASCIA_API fascia_status fascia_motion_alloc(fascia_ctx *ctx, fascia_motion *motion, int32_t key_count);
/// Allocates the surface arrays of an organ.
FASCIA_API fascia_status fascia_organ_alloc(fascia_ctx *ctx, fascia_organ *organ, int32_t vertex_count,
                                            int32_t triangle_count);
/// (Re)allocates a surface's arrays, zeroed.
FASCIA_API fascia_status fascia_surface_alloc(fascia_ctx *ctx, fascia_surface *surface, int32_t vertex_count,
                                              int32_t triangle_count);
/// (Re)allocates the model's tetrahedra [4 count], zeroed.
FASCIA_API fascia_status fascia_model_tetrahedra_alloc(fascia_ctx *ctx, fascia_model *model, int32_t count);
/// Sets provenance to a copy of text (JSON).
FASCIA_API fascia_status fascia_model_set_provenance(fascia_ctx *ctx, fascia_model *model, const char *text);

/// Fills frame_offsets/frame_pairs from the sample -> frame table.
FASCIA_API fascia_status fascia_model_build_reverse(fascia_ctx *ctx, fascia_model *model);

/// Checks every size, index and value: indices in range, CSR offsets
/// monotone, finite numbers, positive volumes and densities, weights summing
/// to 1 and gradients to 0, unit quaternions, the reverse table matching the
/// forward one, materials in range. `origin` names the model in messages
/// (file path, or "beam generator"). Nothing is changed.
FASCIA_API fascia_status fascia_model_validate(fascia_ctx *ctx, const fascia_model *model, const char *origin);

/// A connected piece of a model (frames joined by the samples on them and by
/// the rigid organ they follow) that no fixed or prescribed frame holds.
typedef struct fascia_model_piece {
  int32_t frames, samples;
  fascia_real volume;      ///< m^3, its samples'
  int32_t first_frame;     ///< its lowest frame index
  fascia_real position[3]; ///< rest position of that frame, m
} fascia_model_piece;

/// Finds the pieces of the model that nothing holds: a piece is held when one
/// of its frames is fixed or prescribed (the coupling frames of fixed and
/// prescribed organs are), or when no sample weighs on it (a lone frame
/// carries no mass); a deformable organ's frames and the tissue's form
/// one graph through the samples, and a rigid organ's coupling frames are one
/// piece with the body. *count is the number of unheld pieces, numbered by
/// their lowest frame; the first `capacity` are described in `pieces`.
/// frame_piece, if not NULL, receives for each frame its piece number, -1 for
/// held frames. The model must be valid in its indices (fascia_model_validate
/// calls this last).
FASCIA_API fascia_status fascia_model_floating_components(fascia_ctx *ctx, const fascia_model *model,
                                                          int32_t *frame_piece, fascia_model_piece *pieces,
                                                          int32_t capacity, int32_t *count);

/// The Poisson ratio from which fascia's generators (fascia prep, fascia
/// beam) put samples into volumetric patches by default. Below it the
/// patches still gain on the cantilever (hex at nu = 0.2: +3.2 -> +1.8 %),
/// but soft tissue has nu = 0.4-0.49 and a prepared model's patches couple
/// more frames in its matrix; a scene's patch_radius turns them on at any
/// ratio (docs/mechanics.md, "Volumetric locking").
#define FASCIA_PATCH_MIN_POISSON 0.3

/// Groups the samples into volumetric patches (sample_patch) for models
/// without cells: patch centres are a Poisson-disk subset of the samples
/// radius[material] apart (m), chosen in sample order, and each sample joins
/// the nearest centre of its own material and organ; the samples of a
/// material whose radius is <= 0 stay in no patch (-1). A patch then holds
/// the samples of about one ball of that radius (docs/mechanics.md says how
/// the radius is chosen). Materials with a radius must be whole (part
/// FASCIA_PART_FULL). Errors: FASCIA_ERR_ARGUMENT, FASCIA_ERR_MEMORY (the
/// model unchanged).
FASCIA_API fascia_status fascia_model_make_patches(fascia_ctx *ctx, fascia_model *model, const fascia_real *radius);

/// Number of volumetric patches (distinct sample_patch values >= 0) and of
/// the samples in them (*patched, may be NULL).
FASCIA_API int32_t fascia_model_patch_count(const fascia_model *model, int32_t *patched);

/// A fingerprint of the model's contents (FNV-1a, 64 bits) over every array
/// the solver reads: rest state, kinds, motions, loads, samples, patches
/// and their modes, weights, materials, organs and their coupling, gravity. Two models with
/// the same fingerprint simulate alike; names, probes and provenance do not
/// count, so a copy, a rename or a re-save of a model file keeps it.
/// Checkpoints and results record it.
FASCIA_API uint64_t fascia_model_fingerprint(const fascia_model *model);

/// Total sample volume (m^3) and mass (kg).
FASCIA_API fascia_real fascia_model_volume(const fascia_model *model);
/// Volume of the tissue samples alone (sample_organ == -1), m^3.
FASCIA_API fascia_real fascia_model_tissue_volume(const fascia_model *model);
FASCIA_API fascia_real fascia_model_mass(const fascia_model *model);

/// Lame parameters of a material: lambda, mu (Pa).
FASCIA_API void fascia_material_lame(const fascia_material *material, fascia_real *lambda, fascia_real *mu);
/// Young's modulus and Poisson ratio from Lame parameters (lambda >= 0, mu > 0).
FASCIA_API void fascia_lame_to_young(fascia_real lambda, fascia_real mu, fascia_real *youngs_modulus,
                                     fascia_real *poisson_ratio);
/// Law from its name ("stvk", "neohookean"); -1 if unknown.
FASCIA_API int fascia_law_from_name(const char *name);
FASCIA_API const char *fascia_law_name(int law);

/// Reads a model file (docs/model-format.md), validates it. Errors name the
/// file and the dataset: FASCIA_ERR_IO for a missing, unreadable or non-HDF5
/// file, FASCIA_ERR_FORMAT for wrong content. On error *out is NULL.
FASCIA_API fascia_status fascia_model_load(fascia_ctx *ctx, const char *path, fascia_model **out);
/// Writes a model file (validated first; motion and organ names must be
/// unique, non-empty and without '/') under a temporary name next to path
/// (path.tmp-PID-K), then renames it to path. On error no file is left
/// behind and an older file at path is untouched.
FASCIA_API fascia_status fascia_model_save(fascia_ctx *ctx, const fascia_model *model, const char *path);

/// Switches the HDF5 library's own error printing off for the rest of the
/// process. fascia's readers and writers already put every HDF5 failure in
/// their message (fascia_ctx_message) and silence HDF5 while they run, then
/// give the caller its printer back; an application that shows fascia's
/// messages calls this once, at start, so that HDF5 prints nothing besides
/// them. In particular HDF5 1.10 keeps internal state of an H5Fopen that
/// failed on some damaged files (no id of it reaches fascia, so nothing can
/// close it) and, with its printer on, prints "HDF5: infinite loop closing
/// library" and a line of its internal names at exit.
FASCIA_API void fascia_hdf5_quiet(void);

/// Time of the last key of the model's motions (s): from then on every
/// prescribed frame stays where it is. 0 without motions.
FASCIA_API fascia_real fascia_model_motion_end(const fascia_model *model);

/// Probe index by name, -1 if absent.
FASCIA_API int32_t fascia_model_find_probe(const fascia_model *model, const char *name);

#ifdef __cplusplus
}
#endif
#endif
