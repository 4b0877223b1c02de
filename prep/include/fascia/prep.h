// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Preprocessing: from organ surface meshes and a scene file to a packaged
// connective-tissue model (README.md). One function
// per stage, each taking the context, the scene (the def), its inputs and its
// outputs:
//
//   scene JSON ─ fascia_prep_scene_load
//        │ fascia_prep_import           assimp: parts, units, transform
//        │ fascia_prep_repair           CGAL: check, repair what is safe, report
//        │ fascia_prep_voxelize         inside/outside per organ, OpenVDB distances,
//        │                              the tissue region (outside every organ,
//        │                              d_A + d_B <= max_gap for two of its organs)
//        │ fascia_prep_sample           Poisson-disk frames (surface + interior)
//        │                              and samples: Voronoi volumes (mls), or
//        │                              tet quadrature points (tet)
//        │ fascia_prep_shape_functions  MLS weights over neighbours found by
//        │                              geodesic distance inside the region, or
//        │                              barycentric weights in the sample's tet
//        │ fascia_prep_couple           surface frames shared with organs
//        ▼ fascia_prep_package          fascia_model + provenance JSON
//
// The intermediate results are plain structures of arrays (like fascia_model)
// so that tests and tools can look inside; each has a _destroy that accepts
// NULL. On error a stage leaves its outputs NULL and its inputs unchanged.
// Lengths are metres, volumes m^3, everything in the scene's world frame.
#ifndef FASCIA_PREP_H
#define FASCIA_PREP_H

#include "fascia/base.h"
#include "fascia/model.h"

#ifdef __cplusplus
extern "C" {
#endif

// ---------------------------------------------------------------- the scene

/// Shape-function kinds of a tissue.
typedef enum fascia_prep_shape_kind {
  FASCIA_PREP_SHAPE_MLS = 0, ///< meshless: moving least squares, linear basis
  FASCIA_PREP_SHAPE_TET = 1  ///< mesh-based: tetrahedra of the frames, samples at their quadrature points
} fascia_prep_shape_kind;

/// How a volume tissue is held by the organs that carry its frames
/// (scene key "attachment"; docs/mechanics.md, "The attachment").
typedef enum fascia_prep_attachment_kind {
  FASCIA_PREP_ATTACH_FRAMES = 0, ///< through its shared frames only, as the weights give them
  FASCIA_PREP_ATTACH_EXACT = 1   ///< weights blended to the organ's motion within a layer of its surface
} fascia_prep_attachment_kind;

/// A box or a sphere that limits a tissue or its coupling.
typedef enum fascia_prep_shape_region {
  FASCIA_PREP_REGION_NONE = 0,
  FASCIA_PREP_REGION_BOX = 1,
  FASCIA_PREP_REGION_SPHERE = 2
} fascia_prep_shape_region;

typedef struct fascia_prep_region {
  int32_t kind;         ///< fascia_prep_shape_region
  fascia_real min[3];   ///< box, m
  fascia_real max[3];   ///< box, m
  fascia_real center[3]; ///< sphere, m
  fascia_real radius;   ///< sphere, m
} fascia_prep_region;

/// A list of part names of one organ (node or mesh names in its file).
typedef struct fascia_prep_parts {
  int32_t count; ///< 0: every part
  char **names;  ///< [count]
} fascia_prep_parts;

/// patch_radius of a tissue or deformable organ left to the rule.
#define FASCIA_PREP_PATCH_AUTO (-1.0)

/// A volume tissue's min_gap by default, m: organs closer than this slide on
/// each other (data/scenes/README.md, "Thin gaps").
#define FASCIA_PREP_MIN_GAP 0.001

/// The volumetric patch radius (m) a region gets by default: 0 (none) below
/// the Poisson ratio where patches pay, else its frame spacing, shrinking
/// once the frames resolve a layer of this mean depth (m, its distance to
/// the surfaces that hold it; 0: not known), and 0 once smaller than the
/// sample spacing (docs/mechanics.md, "Volumetric locking", states the rule
/// and its measurements).
FASCIA_API fascia_real fascia_prep_patch_radius(fascia_real poisson_ratio, fascia_real frame_spacing,
                                                fascia_real sample_spacing, fascia_real depth);

/// One organ of the scene: a surface mesh file, or labels of the scene's
/// segmentation (docs/labelmaps.md).
typedef struct fascia_prep_organ_def {
  char name[FASCIA_NAME_SIZE];
  char *mesh;              ///< path as written in the scene (a label organ: the segmentation's)
  char *mesh_path;         ///< path resolved against the scene's folder
  int32_t label_count;     ///< > 0: the organ is these labels of the segmentation, not a mesh
  int32_t *labels;         ///< [label_count] label values, ascending
  uint8_t *label_named;    ///< [label_count] 1: named by value or name (must be in the image), 0: by a pattern only
  fascia_prep_parts parts; ///< which parts of the file (0: all)
  fascia_real scale;       ///< file units to metres (1, 0.01, 0.001)
  char units[8];           ///< "m", "cm", "mm"
  int32_t units_given;     ///< 1 when the scene gives "units", 0 when it is left out (metres)
  /// affine map applied after scaling: x' = A x + t, row-major 3x4 [A | t]
  fascia_real transform[12];
  int32_t kind;            ///< fascia_organ_kind
  fascia_motion motion;    ///< PRESCRIBED only (keys owned by the scene)
  int32_t material;        ///< DEFORMABLE only: index into materials, else -1
  // DEFORMABLE only: how the organ's inside is sampled (the same keys and
  // meaning as a tissue's; see fascia_prep_tissue_def).
  fascia_real frame_spacing;  ///< Poisson-disk radius of the organ's own frames, m
  fascia_real sample_spacing; ///< Poisson-disk radius of its samples, m
  int32_t shape_kind;         ///< fascia_prep_shape_kind
  int32_t neighbours;         ///< frames per sample (MLS), >= 4
  int32_t samples_per_tet;    ///< TET: quadrature points per tetrahedron, 4 (degree 2) or 1 (centroid)
  int32_t enhanced_modes;     ///< 1: its volumetric patches carry enhanced strain modes (default: TET, 4 per tet)
  fascia_real min_component;  ///< pieces of the inside smaller than this are dropped, m^3
  /// Radius of the volumetric patches (mean dilatation, docs/mechanics.md), m;
  /// 0: none; FASCIA_PREP_PATCH_AUTO: by the rule of fascia_prep_patch_radius.
  fascia_real patch_radius;
  /// 1: an organ of labels the segmentation may lack ("optional": true); when
  /// it does, the scene is read without it (fascia_prep_scene.absent_organs).
  int32_t optional;
  /// 1: a hollow organ ("model": "shell", kind DEFORMABLE): frames on its
  /// surface, its wall thickness wide about the surface (docs/organs.md,
  /// "Shell organs"); material is then the wall's section material.
  int32_t shell;
  fascia_real thickness;     ///< SHELL: wall thickness, m
  int32_t section_points;    ///< SHELL: Gauss points through the wall
  fascia_prep_region hold;   ///< SHELL: its frames in this box or sphere are fixed (NONE: none)
  fascia_real pressure;      ///< SHELL: inside pressure on its wall, Pa (dead load; 0: none)
} fascia_prep_organ_def;

/// Coupling rule of a tissue for one organ.
typedef struct fascia_prep_coupling_def {
  int32_t organ;             ///< organ index
  int32_t enabled;           ///< 0: never share frames with this organ
  fascia_prep_region region; ///< share only inside this region (NONE: anywhere)
  fascia_prep_parts parts;   ///< share only on these parts (0: all)
} fascia_prep_coupling_def;

/// Forms of a tissue (data/scenes/README.md, "Strands and sheets").
typedef enum fascia_prep_tissue_form {
  FASCIA_PREP_FORM_VOLUME = 0, ///< the space between its organs, voxelized
  FASCIA_PREP_FORM_STRAND = 1, ///< a ligament: a curve between two attachments, a cross-section
  FASCIA_PREP_FORM_SHEET = 2   ///< a membrane: a surface mesh given in the scene, a thickness
} fascia_prep_tissue_form;

/// "volume", "strand" or "sheet".
FASCIA_API const char *fascia_prep_form_name(int32_t form);

/// Where a strand ends: a point near an organ's surface (within radius), a
/// named part of the organ's mesh, a label of a label organ or a region of
/// its surface (the strand then ends at the point of that area nearest its
/// next point: a ligament takes the shortest way; or, spread, over all of it).
typedef struct fascia_prep_attachment {
  int32_t organ;        ///< organ index
  fascia_real point[3]; ///< as given, m (unused with a part)
  fascia_real radius;   ///< the point lies within this of the organ's surface, m
  char part[FASCIA_NAME_SIZE]; ///< "" : attached at point; else the part of the organ's mesh
  char label[FASCIA_NAME_SIZE]; ///< "": none; else a label (name or value) of a label organ: its surface
  fascia_prep_region region;    ///< kind NONE: none; else the organ's surface in this box or sphere
  /// 1: the end is coupled over its whole area (point: the surface within
  /// radius; part, label, region: all of it) by a fan of fibres; 0: at the
  /// area's point nearest the strand's next point
  int32_t spread;
} fascia_prep_attachment;

/// One tissue: the connective tissue between two or more organs.
typedef struct fascia_prep_tissue_def {
  int32_t form;              ///< fascia_prep_tissue_form
  /// STRAND: its two ends (organs[0] = from.organ, organs[1] = to.organ).
  fascia_prep_attachment from, to;
  int32_t through_count;     ///< STRAND: points its curve passes through between its ends (0: straight)
  fascia_real *through;      ///< STRAND: [3 through_count] m, in order from `from` to `to`
  /// STRAND: cross-section area, m^2 (a disc of "radius", or "area");
  /// SHEET: thickness, m. Its section is carried by the frames' rotations.
  fascia_real area, thickness;
  fascia_real radius;          ///< STRAND: radius of the disc of that area, m (drawing)
  int32_t section_points;      ///< Gauss points per direction of the section (strand: q x q, sheet: q)
  char *mesh, *mesh_path;      ///< SHEET: its surface as written and resolved
  fascia_real mesh_scale;      ///< SHEET: file units to metres
  fascia_real mesh_transform[12]; ///< SHEET: row-major [A | t] after scaling

  char name[FASCIA_NAME_SIZE];
  int32_t organ_count;
  int32_t *organs;           ///< [organ_count] organs it connects
  fascia_real max_gap;       ///< largest gap it bridges, m
  /// VOLUME: narrowest gap it bonds, m: where its organs are closer than
  /// this they slide on each other and no tissue joins them there
  fascia_real min_gap;
  fascia_prep_region region; ///< optional box or sphere
  int32_t region_organ;      ///< with region_parts: limit to near these parts of this organ (-1: none)
  fascia_prep_parts region_parts;
  int32_t material;          ///< index into materials
  fascia_real frame_spacing; ///< Poisson-disk radius of frames, m
  fascia_real sample_spacing; ///< Poisson-disk radius of samples, m
  int32_t shape_kind;        ///< fascia_prep_shape_kind
  int32_t neighbours;        ///< frames per sample (MLS), >= 4
  int32_t samples_per_tet;   ///< TET: quadrature points per tetrahedron, 4 (degree 2) or 1 (centroid)
  /// 1: its volumetric patches carry nine enhanced strain modes each, the
  /// cure of the tetrahedra's stiffness in bending (docs/mechanics.md);
  /// scene key shape_functions.enhanced_modes, default true for TET with 4
  /// samples per tetrahedron
  int32_t enhanced_modes;
  fascia_real coupling_tolerance; ///< frames this close to an organ surface are shared, m
  int32_t coupling_count;
  fascia_prep_coupling_def *coupling; ///< [coupling_count] per-organ rules (absent organs: share everywhere)
  /// Organs the tissue touches but does not connect, with no rule of their
  /// own: 1 (scene key coupling.others, default true) they share frames
  /// where the tissue lies on them, as connective tissue adheres to what it
  /// touches; 0 the frames there stay free.
  int32_t couple_others;
  fascia_real min_component;  ///< pieces of region smaller than this are dropped, m^3
  fascia_real patch_radius;   ///< as for a deformable organ
  int32_t attachment;         ///< VOLUME: fascia_prep_attachment_kind
  fascia_real attachment_layer; ///< EXACT: thickness of the blended layer, m (0: the sample spacing)
} fascia_prep_tissue_def;

/// 1 when organ (an index into the scene's organs) is one of those tissue td
/// connects (its "connects" list), else 0.
FASCIA_API int fascia_prep_tissue_connects(const fascia_prep_tissue_def *td, int32_t organ);

/// World frames a label map can be placed in (docs/labelmaps.md).
typedef enum fascia_prep_frame {
  FASCIA_PREP_FRAME_RAS = 0, ///< +x toward the patient's right, +y anterior, +z superior (NIfTI)
  FASCIA_PREP_FRAME_LPS = 1  ///< +x left, +y posterior, +z superior (DICOM, ITK)
} fascia_prep_frame;

/// The scene's segmentation: a label map (NIfTI or NRRD) and its label table.
typedef struct fascia_prep_segmentation {
  char *file;                 ///< as written in the scene (NULL: the scene has none)
  char *file_path;            ///< resolved against the scene's folder
  char *table;                ///< the label table as written: a TSV path or "totalsegmentator:total", or the
                              ///< segmentation file itself when a .seg.nrrd names its segments (NULL: none)
  int32_t table_count;        ///< entries of the table
  int32_t *table_label;       ///< [table_count]
  char **table_name;          ///< [table_count]
  int32_t frame;              ///< fascia_prep_frame the image is placed in
  int32_t smoothing;          ///< smoothing passes of each label's indicator before its surface is taken
  fascia_real interface_layer; ///< organs closer than this (touching included) each give up half of it at their interface, m
  /// Labels whose voxels the tissue may take besides the background (fat,
  /// for instance). A label neither an organ's nor connective keeps tissue
  /// out of its voxels (docs/labelmaps.md).
  int32_t connective_count;
  int32_t *connective;        ///< [connective_count] label values, ascending
} fascia_prep_segmentation;

/// A parsed scene file (the def of every stage). Built by
/// fascia_prep_scene_load or _parse; owned, freed by _destroy.
typedef struct fascia_prep_scene {
  char *path;                 ///< scene file ("(memory)" when parsed from text)
  char *text;                 ///< its text, kept for provenance
  char *output;               ///< "output" key as given (relative to the working folder), or NULL
  fascia_real voxel_size;     ///< m
  uint64_t seed;              ///< random seed of the Poisson sampling
  fascia_real gravity[3];     ///< m/s^2
  fascia_real close_holes;    ///< open meshes: holes up to about this wide are closed, m
  int32_t material_count;
  fascia_material *materials; ///< [material_count]
  int32_t organ_count;
  fascia_prep_organ_def *organs; ///< [organ_count]
  int32_t tissue_count;
  fascia_prep_tissue_def *tissues; ///< [tissue_count]
  fascia_prep_segmentation segmentation; ///< file NULL when no organ comes from labels
  /// Optional organs the segmentation lacks, left out of organs, and the
  /// tissues left out with them (too few of their organs left).
  int32_t absent_organ_count;
  char (*absent_organs)[FASCIA_NAME_SIZE];   ///< [absent_organ_count]
  int32_t dropped_tissue_count;
  char (*dropped_tissues)[FASCIA_NAME_SIZE]; ///< [dropped_tissue_count]
} fascia_prep_scene;

/// Reads and checks a scene file. Unknown keys, wrong types, missing
/// required keys and impossible values are errors naming the file and the key
/// ("scene 'a.json' tissues[0].max_gap: expected a number > 0, found "x"").
/// Mesh paths are resolved against the scene file's folder. On error *out is NULL.
FASCIA_API fascia_status fascia_prep_scene_load(fascia_ctx *ctx, const char *path, fascia_prep_scene **out);
/// The same from text; base_dir resolves relative mesh paths (NULL: ".").
FASCIA_API fascia_status fascia_prep_scene_parse(fascia_ctx *ctx, const char *text, const char *origin,
                                                 const char *base_dir, fascia_prep_scene **out);
FASCIA_API void fascia_prep_scene_destroy(fascia_prep_scene **scene);

// ---------------------------------------------------------------- import, repair

/// What the check found and what the repair did, per organ.
typedef struct fascia_prep_mesh_report {
  int32_t parts_used;
  int32_t duplicate_vertices_merged;
  int32_t degenerate_faces_removed;
  int32_t duplicate_faces_removed;
  int32_t nonmanifold_vertices_split;
  int32_t components;
  int32_t closed_components;
  int32_t border_edges;       ///< after repair
  int32_t holes_filled;
  int32_t holes_left;
  int32_t components_reoriented;
  int32_t self_intersections; ///< intersecting face pairs (counted up to a limit)
  fascia_real area;           ///< m^2
  fascia_real enclosed_volume; ///< m^3, from the inside/outside voxels (after voxelize)
  char inside_rule[160];      ///< how inside/outside was decided (set by voxelize)
} fascia_prep_mesh_report;

/// The surface of one organ: triangles of the chosen parts, in metres, world.
typedef struct fascia_prep_mesh {
  char name[FASCIA_NAME_SIZE];
  int32_t vertex_count, triangle_count;
  fascia_real *vertices;  ///< [3 vertex_count]
  int32_t *triangles;     ///< [3 triangle_count]
  int32_t *triangle_part; ///< [triangle_count] index into part_names
  int32_t part_count;
  char **part_names;      ///< [part_count] node or mesh names
  char sha256[65];        ///< of the mesh file
  fascia_real bounds[6];  ///< min xyz, max xyz
  fascia_prep_mesh_report report;
} fascia_prep_mesh;

/// Two organs built from labels that meet in the label map.
typedef struct fascia_prep_label_contact {
  int32_t a, b;           ///< organ indices, a < b
  int64_t faces;          ///< voxel faces where a label of a meets one of b
  fascia_real area;       ///< m^2 of those faces
  fascia_real layer;      ///< thickness carved at their interface (the segmentation's interface_layer), m
} fascia_prep_label_contact;

typedef struct fascia_prep_meshes {
  int32_t count; ///< = scene organ_count, same order
  fascia_prep_mesh *organs;
  int32_t warning_count;
  char **warnings; ///< [warning_count] one line each: sizes that look like a units mistake (set by import)
  /// [count tissues of the scene] a SHEET tissue's surface (vertices merged,
  /// in metres, world); vertex_count 0 for other forms
  fascia_prep_mesh *sheets;
  int32_t sheet_slots;                 ///< entries of sheets (the scene's tissue_count)
  int32_t contact_count;               ///< pairs of label organs that touch in the label map
  fascia_prep_label_contact *contacts; ///< [contact_count]
  /// The segmentation's voxels that keep tissue out: those of labels that
  /// are neither an organ's nor connective (docs/labelmaps.md). NULL: none.
  uint16_t *occupied;          ///< [nx ny nz] such a voxel's label, else 0 (index i + nx (j + ny k))
  int32_t occupied_dims[3];
  double occupied_from_world[12]; ///< row-major [A | t]: a world point (m) to its voxel's (i, j, k) (the centre's)
} fascia_prep_meshes;

/// Reads every organ's mesh file with assimp, keeps the named parts (error
/// lists the parts the file has, or says it has no named parts), applies
/// units and transform, refuses NaN coordinates and empty meshes. Organs
/// made of labels get their surface from the segmentation instead: the
/// labels' smoothed indicator, meshed (OpenVDB), placed in the world by the
/// image's affine, carved at touching interfaces by the interface layer
/// (docs/labelmaps.md). Then judges the scene's sizes against anatomy's
/// (data/scenes/README.md, "Units and sizes"): refuses what cannot be
/// simulated (an organ larger than a body, a motion larger than the whole
/// scene) and lists in warnings what looks like a units mistake but may be
/// meant. On error *out is NULL.
FASCIA_API fascia_status fascia_prep_import(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                            fascia_prep_meshes **out);
/// Checks and repairs every mesh in place with CGAL, part by part: merges
/// duplicate vertices, removes degenerate and duplicate faces, splits
/// non-manifold vertices, orients each component consistently (closed ones
/// outward), fills small holes, counts self-intersections; fills the report.
/// On error the meshes may be partly repaired: destroy them.
FASCIA_API fascia_status fascia_prep_repair(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                            fascia_prep_meshes *meshes);
FASCIA_API void fascia_prep_meshes_destroy(fascia_prep_meshes **meshes);

// ---------------------------------------------------------------- voxelize

/// Two organs that overlap (both claim the same voxels).
typedef struct fascia_prep_overlap {
  int32_t a, b;          ///< organ indices, a < b
  fascia_real volume;    ///< m^3, voxels inside both on the organs' own grids (at most the smaller enclosed_volume)
  fascia_real depth;     ///< largest penetration of one surface into the other (vertices inside the other organ), m
} fascia_prep_overlap;

/// Per-tissue figures of the region.
typedef struct fascia_prep_tissue_report {
  int64_t voxels;           ///< region voxels kept
  fascia_real volume;       ///< m^3, kept
  int32_t components;       ///< pieces kept
  int32_t dropped_components;
  fascia_real dropped_volume; ///< m^3 in pieces smaller than min_component
  fascia_real slide_volume;   ///< m^3 between its organs closer than min_gap, left out: they slide there
  /// Kept voxels with a face neighbour inside an organ: one voxel layer on
  /// the tissue's faces against the organs (the scale of its volume's error).
  int64_t organ_face_voxels;
  /// Its kept volume split by the pair of organs whose bridge through each
  /// voxel is shortest: [K (K - 1) / 2] m^3 for its K organs (the tissue
  /// def's list), pairs in the order (0, 1), (0, 2) .. (0, K-1), (1, 2) ..
  fascia_real *pair_volume;
  /// Space between its organs (within max_gap and its region) left out
  /// because labels the scene does not model occupy it (meshes->occupied).
  fascia_real occupied_volume; ///< m^3
  int32_t occupied_labels[4];  ///< the labels that occupy most of it, largest first (0: none)
  fascia_real occupied_label_volume[4]; ///< m^3 each
} fascia_prep_tissue_report;

/// The name of a label in the segmentation's table, NULL if it has none.
FASCIA_API const char *fascia_prep_label_name(const fascia_prep_segmentation *seg, int32_t label);
/// "colon (20) 8.1 cm^3, aorta (52) 1.2 cm^3, ..." of the labels the report
/// says occupy space between a tissue's organs (names from the scene's
/// label table); "" when none.
FASCIA_API void fascia_prep_occupied_text(const fascia_prep_scene *scene, const fascia_prep_tissue_report *report,
                                          char *out, size_t size);

/// The scene's voxel grid: voxel (i, j, k) is centred at
/// origin + h (i, j, k), index i + nx (j + ny k). It covers every tissue's
/// candidate space and every deformable organ; organs have signed distances
/// on it (negative inside).
///
/// Regions are the pieces of space that get frames and samples: the tissues
/// (labels 1 .. tissue_count) and the insides of the deformable organs
/// (label organ_label[o] > tissue_count). They never share a voxel.
typedef struct fascia_prep_volume {
  fascia_real voxel_size;   ///< h, m
  fascia_real origin[3];    ///< centre of voxel (0,0,0), m
  int32_t dims[3];          ///< nx, ny, nz
  int32_t lattice[3];       ///< global lattice index of voxel (0,0,0): origin = h lattice
  uint8_t *region;          ///< [voxels] 0: none; t + 1: tissue t; organ_label[o]: inside deformable organ o
  int32_t organ_count;
  float **distance;         ///< [organ_count][voxels] signed distance, m (NULL: organ not near)
  float *band;              ///< [organ_count] distances are exact up to this, m
  int32_t tissue_count;
  fascia_prep_tissue_report *tissues; ///< [tissue_count]
  int32_t overlap_count;
  fascia_prep_overlap *overlaps;      ///< [overlap_count]
  fascia_real *closest;     ///< [organ_count^2] closest surface distance between organs near a tissue, measured on the surfaces (0: overlap), m (-1: not measured)
  int32_t *organ_label;     ///< [organ_count] region label of a deformable organ's inside, 0 for other organs
  fascia_prep_tissue_report *organ_regions; ///< [organ_count] figures of each deformable organ's inside (zeros for others)
} fascia_prep_volume;

/// Decides inside/outside for every organ (edge-crossing flood fill from
/// outside: the outer surface counts, so thin double shells and cavities are
/// inside; open meshes whose holes leak get a morphological closing), measures
/// overlaps, and builds each tissue's region, then each deformable organ's
/// (its inside voxels that no earlier region holds; pieces smaller than its
/// min_component dropped; of a closed surface of nested shells, a hollow
/// organ, only the wall between them, by ray parity: the tissues still see
/// the cavity as inside). Every organ a tissue connects gets a distance
/// field wherever the tissue can lie. Errors: voxel size too large for a
/// gap, organs too far apart for max_gap (the message names the two, their
/// distance and the max_gap that bridges them), a region that selects
/// nothing, a deformable organ with no inside left, a deformable organ whose
/// closed shells cross around a large even-parity volume.
FASCIA_API fascia_status fascia_prep_voxelize(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                              fascia_prep_meshes *meshes, fascia_prep_volume **out);
FASCIA_API void fascia_prep_volume_destroy(fascia_prep_volume **volume);
/// Region label of the voxel holding point (m): tissue index + 1, a deformable
/// organ's organ_label, 0 if none or off the grid.
FASCIA_API int fascia_prep_volume_region_at(const fascia_prep_volume *volume, const fascia_real *point);

// ---------------------------------------------------------------- sample

/// Frames and samples of every region. Frame i sits on an organ surface when
/// frame_organ[i] >= 0 (then frame_triangle[i] is the closest triangle).
/// Tissue frames and samples come first, tissue by tissue; then those of each
/// deformable organ's inside, organ by organ (contiguous ranges).
///
/// A tissue frame on the surface of a deformable organ that the tissue's
/// coupling rules allow is *shared*: frame_organ_voxel[i] names a voxel of the
/// organ's inside it is reached from, so the organ's samples take it as a
/// neighbour just as the tissue's samples do (one frame, two regions).
typedef struct fascia_prep_points {
  int32_t frame_count, sample_count;
  fascia_real *frame_position;  ///< [3N] m
  int32_t *frame_tissue;        ///< [N] tissue it was placed in, -1 for a deformable organ's own frame
  int32_t *frame_inside_organ;  ///< [N] deformable organ whose inside holds it, -1 for a tissue frame
  int32_t *frame_organ;         ///< [N] organ whose surface it lies on, or -1
  int32_t *frame_triangle;      ///< [N] triangle of that organ, or -1
  int64_t *frame_voxel;         ///< [N] region voxel it is attached to
  int64_t *frame_organ_voxel;   ///< [N] shared with a deformable organ: voxel of its inside; else -1
  fascia_real *sample_position; ///< [3S] m
  fascia_real *sample_volume;   ///< [S] m^3; sum over a region = its voxel volume (MLS) or its kept tets' volume (TET)
  int32_t *sample_tissue;       ///< [S] tissue, -1 for a sample inside a deformable organ
  int32_t *sample_inside_organ; ///< [S] deformable organ whose inside holds it, -1 for a tissue sample
  int64_t *sample_voxel;        ///< [S] voxel holding the sample (a region voxel)
  /// [4S] TET regions: the frames at the vertices of the tetrahedron whose
  /// quadrature point the sample is, ascending; -1 (all four) for MLS samples
  int32_t *sample_tet_frame;
  /// [3S] STRAND and SHEET samples: the frames of its interval (two, then
  /// -1) or triangle (three), whose weights it takes; -1 (all three) for
  /// volume samples. Such samples and frames have no voxel (sample_voxel,
  /// frame_voxel -1).
  int32_t *sample_cell_frame;
  /// [S] 1 for a sheet triangle's drilling stabiliser (docs/mechanics.md,
  /// "Against CalculiX"), 0 for every other sample; NULL: none
  uint8_t *sample_drilling;
  /// [tissue_count] of each tissue's frames, those on the mid-layers of its
  /// gaps thinner than its frame spacing (free frames no interior frame
  /// could give there; 0 for strands and sheets)
  int32_t *tissue_mid_layer_frames;
  /// [tissue_count] m^3 of each tissue in gaps thinner than two sample
  /// spacings: layers held by the frames on both their faces, with no free
  /// frame of their own (0 for strands and sheets)
  double *tissue_held_layer_volume;
} fascia_prep_points;

/// The share of a volume tissue in held layers (tissue_held_layer_volume)
/// from which it counts as lying all in them: it has no free frames for a
/// finer spacing to refine, so neither prep's missing-free-frames error nor
/// its coarse-frames warning applies to it.
#define FASCIA_PREP_HELD_LAYER_SHARE 0.99

/// Poisson-disk sampling in each tissue region (fixed seed: same input, same
/// points): surface frames first (on the organ surfaces the region touches),
/// then interior frames, then samples. MLS regions: Poisson-disk samples;
/// each region voxel goes to the sample nearest inside the region, so sample
/// volumes add up to the region's voxel volume. TET regions: the frames are
/// tetrahedralised (CGAL Delaunay), the tetrahedra whose centroid, edge
/// midpoints and quadrature points lie in the region are kept, and the
/// samples are their quadrature points (samples_per_tet per tet, volume =
/// quadrature weight x tet volume), so sample volumes add up to the kept
/// tets' volume (sample_spacing is not used). Then each deformable organ's
/// inside the same way, its surface frames being the shared tissue frames on
/// it (the organ's interior frames keep the organ's frame_spacing from them).
/// Errors: a TET region with fewer than 4 frames or no kept tetrahedron.
FASCIA_API fascia_status fascia_prep_sample(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                            const fascia_prep_meshes *meshes, const fascia_prep_volume *volume,
                                            fascia_prep_points **out);
FASCIA_API void fascia_prep_points_destroy(fascia_prep_points **points);

// ---------------------------------------------------------------- shape functions

/// Sample -> frame weights in CSR form (the model's layout).
typedef struct fascia_prep_weights {
  int32_t sample_count, pair_count;
  int32_t *sample_offsets;    ///< [S+1]
  int32_t *pair_frame;        ///< [P] ascending within a sample
  fascia_real *pair_weight;   ///< [P] sum 1 per sample
  fascia_real *pair_gradient; ///< [3P] 1/m, sum 0 per sample
  fascia_real max_linear_error; ///< largest |sum w_i x_i - p_s| over samples, m
} fascia_prep_weights;

/// Weights of every sample, region by region (tissues and deformable organs
/// alike). MLS: the `neighbours` frames nearest by geodesic distance through
/// the sample's region voxels (so never across an organ or a void), more
/// when the moment matrix is ill-conditioned; cubic kernel; reproduces
/// constant and linear fields exactly. TET: the barycentric weights of the
/// sample in its own tetrahedron (points->sample_tet_frame), all in [0, 1]
/// since every sample is a quadrature point inside its tet: nothing is
/// extrapolated. A shared frame belongs to both regions it touches. The MLS
/// neighbours are found locally (cost with the samples and their
/// neighbourhoods, not the voxels between) and the progress hook hears of
/// every percent of the samples.
FASCIA_API fascia_status fascia_prep_shape_functions(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                                     const fascia_prep_volume *volume,
                                                     const fascia_prep_points *points, fascia_prep_weights **out);
FASCIA_API void fascia_prep_weights_destroy(fascia_prep_weights **weights);

// ---------------------------------------------------------------- coupling

/// Frames shared with organs: entry c says frame[c] sits on organ[c]'s
/// triangle[c] at barycentric[3c..3c+2].
typedef struct fascia_prep_coupling {
  int32_t count;
  int32_t *organ, *frame, *triangle; ///< [count]
  fascia_real *barycentric;          ///< [3 count]
  int32_t *per_organ;                ///< [organ_count] shared frames per organ
  int32_t organ_count;
} fascia_prep_coupling;

/// Chooses the shared frames: surface frames (and any frame within the
/// tissue's coupling tolerance of an organ it may couple to), filtered by the
/// tissue's per-organ rules (off, region, parts). For a deformable organ,
/// exactly the frames the sampling shared with its inside (frame_organ_voxel).
FASCIA_API fascia_status fascia_prep_couple(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                            const fascia_prep_meshes *meshes, const fascia_prep_points *points,
                                            fascia_prep_coupling **out);
FASCIA_API void fascia_prep_coupling_destroy(fascia_prep_coupling **coupling);

// ---------------------------------------------------------------- package

/// Figures of a run for provenance (all optional).
typedef struct fascia_prep_run_info {
  const char *tool;          ///< "fascia prep 0.1.0"
  const char *command_line;  ///< as typed
  int32_t step_count;
  const char *const *step_name;   ///< [step_count]
  const double *step_seconds;     ///< [step_count]
  const double *step_peak_bytes;  ///< [step_count]
} fascia_prep_run_info;

/// Builds the model: organs (repaired surfaces, kinds, motions), materials,
/// frames (coupling frames of FIXED organs are FASCIA_FRAME_FIXED, of
/// PRESCRIBED organs FASCIA_FRAME_PRESCRIBED with the organ's motion; those
/// of RIGID and DEFORMABLE organs and a deformable organ's own frames are
/// FASCIA_FRAME_FREE), samples (a deformable organ's with its material),
/// samples, pairs, the reverse table, coupling, gravity and the provenance
/// JSON (input files and hashes, the scene, the version, every parameter and
/// every report). The model is validated before it is returned.
FASCIA_API fascia_status fascia_prep_package(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                             const fascia_prep_meshes *meshes, const fascia_prep_volume *volume,
                                             const fascia_prep_points *points, const fascia_prep_weights *weights,
                                             const fascia_prep_coupling *coupling, const fascia_prep_run_info *info,
                                             fascia_model **out);

/// What every stage built for one scene, in the order they run; freed by
/// fascia_prep_stages_free (NULL members are skipped).
typedef struct fascia_prep_stages {
  fascia_prep_scene *scene;
  fascia_prep_meshes *meshes;
  fascia_prep_volume *volume;
  fascia_prep_points *points;
  fascia_prep_weights *weights;
  fascia_prep_coupling *coupling;
  fascia_model *model;
} fascia_prep_stages;

/// Runs every stage on the scene file at path, as `fascia prep` does, and
/// stops at the first error (its status; what was built stays in *out, to
/// free). info goes to fascia_prep_package (NULL: none).
FASCIA_API fascia_status fascia_prep_stages_run(fascia_ctx *ctx, const char *path, const fascia_prep_run_info *info,
                                                fascia_prep_stages *out);
/// Frees every member and zeroes them; accepts a zeroed struct.
FASCIA_API void fascia_prep_stages_free(fascia_prep_stages *stages);

/// Writes a ParaView preview into folder dir (created if absent), VTK XML:
/// ORGAN.vtp per organ (its surface), region.vti (the voxel grid: region,
/// distance to the nearest organ), frames.vtu (kind: 0 free, 1 on a fixed
/// organ, 2 prescribed, 3 rigid, 4 a deformable organ's; tissue, organs),
/// samples.vtu (tissue, organ, volume), coupling.vtu (shared frames), and
/// preview.pvd, which opens them all as blocks named after the organs and
/// the parts (docs/results-format.md). Files are written to temporary
/// names and renamed.
FASCIA_API fascia_status fascia_prep_preview(fascia_ctx *ctx, const char *dir, const fascia_prep_scene *scene,
                                             const fascia_prep_meshes *meshes, const fascia_prep_volume *volume,
                                             const fascia_prep_points *points, const fascia_prep_coupling *coupling);

/// Writes the organs as a label map (NIfTI-1, `.nii` or `.nii.gz`): organ k
/// is label k + 1 (uint8, uint16 beyond 254 organs), 0 elsewhere, at the
/// scene's voxel size on a grid covering every organ, by voxelize's inside
/// rule; sform in RAS mm (a scene whose segmentation frame is LPS is
/// turned). Beside it, the label table `PATH-without-.nii[.gz].tsv`, whose
/// path goes to table_path. Both written under temporary names and renamed.
/// A build without label-map support answers FASCIA_ERR_UNSUPPORTED.
FASCIA_API fascia_status fascia_prep_labelmap_write(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                                    fascia_prep_meshes *meshes, const char *path, char *table_path,
                                                    size_t table_size);

/// The label table beside the label map at path (MAP.nii[.gz] -> MAP.tsv)
/// into out; 0 when path does not end in .nii or .nii.gz (or out is too short).
FASCIA_API int fascia_prep_labelmap_table_path(const char *path, char *out, size_t size);

/// Hex SHA-256 of a file into hex[65].
FASCIA_API fascia_status fascia_prep_file_sha256(fascia_ctx *ctx, const char *path, char hex[65]);

// ---------------------------------------------------------------- estimate

/// What preparing a scene will take, known before it runs (a scheduler sizes
/// a job by it): the voxel grid over the organs, their surfaces' triangles,
/// and the peak resident memory they imply (docs/cohort.md).
typedef struct fascia_prep_estimate_report {
  double grid_voxels;  ///< voxels of the tissues' grid: their organs' overlapping bounds grown by max_gap
  double organ_voxels; ///< voxels of the largest organ's own grid (its bounds)
  double triangles;    ///< the organs' surface triangles (label organs: two per boundary voxel face)
  double input_bytes;  ///< bytes of the mesh files read (0 for a label map)
  double input_voxels; ///< voxels of the label map (0 for meshes)
  double peak_bytes;   ///< expected peak resident memory of `fascia prep`, bytes
  double bounds[6];    ///< the organs' bounds, m, world: min xyz, max xyz
} fascia_prep_estimate_report;

/// Reads the scene's label map, or its meshes (assimp only), and fills out;
/// nothing is meshed, voxelized or written. Errors as import's.
FASCIA_API fascia_status fascia_prep_estimate(fascia_ctx *ctx, const fascia_prep_scene *scene,
                                              fascia_prep_estimate_report *out);

#ifdef __cplusplus
}
#endif
#endif
