// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Stage 7, package: the fascia_model the simulator loads, with the
// provenance of every number in it (input files and their SHA-256, the scene
// text, the version, every parameter used, every report of the stages).
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/shape.h"
#include "prep_util.h"
#include "reduced.h"
#include "shell.h"

#ifndef FASCIA_PREP_VERSION
#define FASCIA_PREP_VERSION "unknown"
#endif

static cJSON *vector(const double *x, int n) {
  cJSON *a = cJSON_CreateArray();
  for (int k = 0; a && k < n; ++k) cJSON_AddItemToArray(a, cJSON_CreateNumber(x[k]));
  return a;
}

static cJSON *parts_json(const fascia_prep_parts *parts) {
  if (parts->count == 0) return cJSON_CreateString("all");
  cJSON *a = cJSON_CreateArray();
  for (int32_t k = 0; a && k < parts->count; ++k) cJSON_AddItemToArray(a, cJSON_CreateString(parts->names[k]));
  return a;
}

static cJSON *region_json(const fascia_prep_region *r) {
  cJSON *o = cJSON_CreateObject();
  if (r->kind == FASCIA_PREP_REGION_BOX) {
    cJSON_AddStringToObject(o, "kind", "box");
    cJSON_AddItemToObject(o, "min", vector(r->min, 3));
    cJSON_AddItemToObject(o, "max", vector(r->max, 3));
  } else if (r->kind == FASCIA_PREP_REGION_SPHERE) {
    cJSON_AddStringToObject(o, "kind", "sphere");
    cJSON_AddItemToObject(o, "center", vector(r->center, 3));
    cJSON_AddNumberToObject(o, "radius", r->radius);
  } else {
    cJSON_AddStringToObject(o, "kind", "none");
  }
  return o;
}

static const char *organ_kind_name(int32_t kind) {
  switch (kind) {
  case FASCIA_ORGAN_FIXED: return "fixed";
  case FASCIA_ORGAN_PRESCRIBED: return "prescribed";
  case FASCIA_ORGAN_RIGID: return "rigid";
  case FASCIA_ORGAN_DEFORMABLE: return "deformable";
  default: return "unknown";
  }
}

// What the samples of one region (tissue t, or deformable organ o) add up
// to: the region's voxel volume (MLS: Voronoi cells of voxels) or the volume
// of the tetrahedra kept inside it (TET: quadrature weights x tet volumes),
// with the tet count. Compare with the region's volume_m3 (voxels).
static void sample_volume_json(cJSON *e, const fascia_prep_points *pts, int32_t t, int32_t o, int32_t kind,
                               int32_t samples_per_tet) {
  double sum = 0;
  int32_t samples = 0;
  for (int32_t s = 0; s < pts->sample_count; ++s)
    if ((t >= 0 ? pts->sample_tissue[s] == t : pts->sample_inside_organ[s] == o) &&
        !(pts->sample_drilling && pts->sample_drilling[s])) // a stabiliser repeats the volume of others
      sum += pts->sample_volume[s], ++samples;
  cJSON_AddNumberToObject(e, "sample_volume_m3", sum);
  const int tet = kind == FASCIA_PREP_SHAPE_TET;
  cJSON_AddStringToObject(e, "sample_volume_of", tet ? "tetrahedra kept inside the region" : "region voxels");
  if (tet) cJSON_AddNumberToObject(e, "tetrahedra", samples_per_tet > 0 ? samples / samples_per_tet : 0);
}

// The volumetric patch rule (docs/mechanics.md, "Volumetric locking"):
// patches from FASCIA_PATCH_MIN_POISSON on, one frame spacing wide where the
// frames are too coarse for the region's layer. The layer locks as
// (lambda/mu) (s/T)^2 for frame spacing s and thickness T, so below
// s = PATCH_FADE_DEPTHS x depth x sqrt(mu/lambda) the patches shrink as that
// square, and under a sample spacing they are left out. depth: the region's
// mean distance to the surfaces that hold it (0: unknown, no fading).
#define PATCH_FADE_DEPTHS 2.5

fascia_real fascia_prep_patch_radius(fascia_real poisson_ratio, fascia_real frame_spacing, fascia_real sample_spacing,
                                     fascia_real depth) {
  if (!(poisson_ratio >= FASCIA_PATCH_MIN_POISSON)) return 0;
  const double lambda_per_mu = poisson_ratio < 0.5 ? 2 * poisson_ratio / (1 - 2 * poisson_ratio) : INFINITY;
  const double fade = depth > 0 ? PATCH_FADE_DEPTHS * depth / sqrt(lambda_per_mu) : 0;
  const double ratio = frame_spacing < fade ? frame_spacing / fade : 1;
  const double radius = frame_spacing * ratio * ratio;
  return radius < sample_spacing ? 0 : radius;
}

// Each volume region's mean depth, m (fascia_prep_patch_radius): its voxels'
// distance to the nearest of its organs (a tissue, [t]) or to its own surface
// (a deformable organ's inside, [tissue_count + o]), each at most the exact
// band of that distance; 0 where there is none.
static double *region_depths(const fascia_prep_scene *scene, const fascia_prep_volume *vol) {
  const int32_t T = scene->tissue_count, O = scene->organ_count;
  double *depth = prep_calloc((size_t)(T + O) + 1, sizeof *depth);
  int64_t *count = prep_calloc((size_t)(T + O) + 1, sizeof *count);
  int32_t *organ_of_label = prep_calloc(256, sizeof *organ_of_label);
  if (!depth || !count || !organ_of_label) {
    free(depth), free(count), free(organ_of_label);
    return NULL;
  }
  for (int l = 0; l < 256; ++l) organ_of_label[l] = -1;
  for (int32_t o = 0; o < O; ++o)
    if (vol->organ_label[o] > 0) organ_of_label[vol->organ_label[o]] = o;
  const int64_t n = (int64_t)vol->dims[0] * vol->dims[1] * vol->dims[2];
  for (int64_t v = 0; v < n; ++v) {
    const int label = vol->region[v];
    if (!label) continue;
    double d = INFINITY;
    int32_t k = -1;
    if (label <= T && scene->tissues[label - 1].form == FASCIA_PREP_FORM_VOLUME) {
      const fascia_prep_tissue_def *td = scene->tissues + label - 1;
      for (int32_t i = 0; i < td->organ_count; ++i) {
        const int32_t o = td->organs[i];
        if (vol->distance[o]) d = fmin(d, fmin(vol->distance[o][v], vol->band[o]));
      }
      k = label - 1;
    } else if (label > T && organ_of_label[label] >= 0) {
      const int32_t o = organ_of_label[label];
      if (vol->distance[o]) d = fmin(-vol->distance[o][v], vol->band[o]);
      k = T + o;
    }
    if (k >= 0 && isfinite(d)) depth[k] += fmax(d, 0), ++count[k];
  }
  for (int32_t k = 0; k < T + O; ++k) depth[k] = count[k] ? depth[k] / (double)count[k] : 0;
  free(count), free(organ_of_label);
  return depth;
}

// The frame spacing below which a volume tissue's frames are half its
// layers apart (a layer between two organs is about four mean depths
// thick), where its material resists a change of volume (a Poisson ratio
// of FASCIA_PATCH_MIN_POISSON or more); 0 where no such bound applies. A
// bonded layer pulled across its thickness contracts sideways over about a
// thickness, which the linear field between coarser frames cannot follow:
// their organ forces come down slowly as the frames are refined
// (docs/mechanics.md, "Thin layers: held by both faces"). A tissue that
// lies all in layers its faces hold (held, m^3, of volume) has no free
// frames there for the spacing to refine: none either.
static double half_layer_spacing(const fascia_prep_scene *scene, int32_t material, double depth, double held,
                                 double volume) {
  const int resists = scene->materials[material].poisson_ratio >= FASCIA_PATCH_MIN_POISSON;
  return resists && depth > 0 && held < FASCIA_PREP_HELD_LAYER_SHARE * volume ? 2 * depth : 0;
}

// A region's patch radius: its own, or the rule's for its material.
static fascia_real region_patch_radius(const fascia_prep_scene *scene, int32_t material, fascia_real radius,
                                       fascia_real frame_spacing, fascia_real sample_spacing, fascia_real depth) {
  return radius == FASCIA_PREP_PATCH_AUTO ? fascia_prep_patch_radius(scene->materials[material].poisson_ratio,
                                                                     frame_spacing, sample_spacing, depth)
                                          : radius;
}

// How a region (a tissue, or a deformable organ's inside) is sampled, in
// its provenance entry: the same keys for both.
static void sampling_json(cJSON *e, const fascia_prep_scene *scene, int32_t material, fascia_real frame_spacing,
                          fascia_real sample_spacing, int32_t shape_kind, int32_t neighbours, int32_t samples_per_tet,
                          int32_t enhanced_modes) {
  cJSON_AddStringToObject(e, "material", scene->materials[material].name);
  cJSON_AddNumberToObject(e, "frame_spacing", frame_spacing);
  cJSON_AddNumberToObject(e, "sample_spacing", sample_spacing);
  cJSON_AddStringToObject(e, "shape_functions", shape_kind == FASCIA_PREP_SHAPE_TET ? "tet" : "mls");
  cJSON_AddNumberToObject(e, "neighbours", neighbours);
  if (shape_kind == FASCIA_PREP_SHAPE_TET) cJSON_AddNumberToObject(e, "samples_per_tet", samples_per_tet);
  cJSON_AddBoolToObject(e, "enhanced_modes", enhanced_modes);
}

// Patches per material: the largest radius among the regions made of it.
static fascia_status make_patches(fascia_ctx *ctx, const fascia_prep_scene *scene, const double *depth,
                                  fascia_model *m) {
  fascia_real *radius = calloc((size_t)m->material_count + 1, sizeof *radius);
  PREP_CHECK(radius, ctx, FASCIA_ERR_MEMORY, "package: out of memory");
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    const fascia_prep_tissue_def *d = scene->tissues + t;
    if (d->form != FASCIA_PREP_FORM_VOLUME) continue; // a section carried by rotations does not lock
    const fascia_real r =
        region_patch_radius(scene, d->material, d->patch_radius, d->frame_spacing, d->sample_spacing, depth[t]);
    if (r > radius[d->material]) radius[d->material] = r;
  }
  for (int32_t o = 0; o < scene->organ_count; ++o) {
    const fascia_prep_organ_def *d = scene->organs + o;
    if (d->kind != FASCIA_ORGAN_DEFORMABLE) continue;
    const fascia_real r = region_patch_radius(scene, d->material, d->patch_radius, d->frame_spacing, d->sample_spacing,
                                              depth[scene->tissue_count + o]);
    if (r > radius[d->material]) radius[d->material] = r;
  }
  const fascia_status status = fascia_model_make_patches(ctx, m, radius);
  free(radius);
  return status;
}

// Enhanced strain modes (docs/mechanics.md) on the patches of the regions
// that ask for them (by default the tetrahedral ones): sample_modes holds 1
// for the samples of such regions until the patches are made; a patch keeps
// its modes where all its samples ask (a patch that also holds samples of a
// meshless region of the same material has none).
static fascia_status modes_on_patches(fascia_ctx *ctx, fascia_model *m) {
  const int32_t S = m->sample_count;
  signed char *all_tet = malloc((size_t)S + 1);
  PREP_CHECK(all_tet, ctx, FASCIA_ERR_MEMORY, "package: out of memory");
  memset(all_tet, -1, (size_t)S + 1);
  for (int32_t s = 0; s < S; ++s) {
    const int32_t p = m->sample_patch[s];
    if (p >= 0) all_tet[p] = (signed char)(all_tet[p] != 0 && m->sample_modes[s]);
  }
  for (int32_t s = 0; s < S; ++s) m->sample_modes[s] = m->sample_patch[s] >= 0 && all_tet[m->sample_patch[s]] == 1;
  free(all_tet);
  return FASCIA_OK;
}

static cJSON *provenance(const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                         const fascia_prep_volume *vol, const fascia_prep_points *pts, const fascia_prep_weights *W,
                         const fascia_prep_coupling *cpl, const double *depth, const fascia_prep_run_info *info) {
  cJSON *root = cJSON_CreateObject();
  cJSON_AddStringToObject(root, "tool", info && info->tool ? info->tool : "fascia_prep");
  cJSON_AddStringToObject(root, "fascia_version", fascia_version());
  cJSON_AddStringToObject(root, "prep_version", FASCIA_PREP_VERSION);
  if (info && info->command_line) cJSON_AddStringToObject(root, "command_line", info->command_line);
  // the scene: path, hash, and its content as parsed JSON
  cJSON *sc = cJSON_AddObjectToObject(root, "scene");
  cJSON_AddStringToObject(sc, "path", scene->path);
  char hex[65];
  prep_sha256_buffer(scene->text, strlen(scene->text), hex);
  cJSON_AddStringToObject(sc, "sha256", hex);
  cJSON *text = cJSON_Parse(scene->text);
  if (text) cJSON_AddItemToObject(sc, "content", text);
  // input meshes
  cJSON *inputs = cJSON_AddArrayToObject(root, "inputs");
  for (int32_t o = 0; o < scene->organ_count; ++o) {
    const fascia_prep_organ_def *d = scene->organs + o;
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "organ", d->name);
    cJSON_AddStringToObject(e, "file", d->mesh_path);
    cJSON_AddStringToObject(e, "sha256", meshes->organs[o].sha256);
    cJSON_AddItemToObject(e, "parts", parts_json(&d->parts));
    cJSON_AddStringToObject(e, "units", d->units);
    cJSON_AddItemToObject(e, "transform_3x4", vector(d->transform, 12));
    cJSON_AddStringToObject(e, "model", organ_kind_name(d->kind));
    if (d->kind == FASCIA_ORGAN_DEFORMABLE) {
      sampling_json(e, scene, d->material, d->frame_spacing, d->sample_spacing, d->shape_kind, d->neighbours,
                    d->samples_per_tet, d->enhanced_modes);
      cJSON_AddNumberToObject(e, "min_component", d->min_component);
      const double at = depth[scene->tissue_count + o];
      cJSON_AddNumberToObject(e, "patch_radius", region_patch_radius(scene, d->material, d->patch_radius,
                                                                     d->frame_spacing, d->sample_spacing, at));
      cJSON_AddNumberToObject(e, "mean_depth", at);
    }
    cJSON_AddItemToArray(inputs, e);
  }
  // every parameter actually used, defaults included
  cJSON *par = cJSON_AddObjectToObject(root, "parameters");
  cJSON_AddNumberToObject(par, "voxel_size", scene->voxel_size);
  cJSON_AddNumberToObject(par, "seed", (double)scene->seed);
  cJSON_AddNumberToObject(par, "close_holes", scene->close_holes);
  cJSON_AddItemToObject(par, "gravity", vector(scene->gravity, 3));
  cJSON_AddNumberToObject(par, "max_hole_edges_filled", 64);
  cJSON_AddNumberToObject(par, "mls_support_margin", FASCIA_SHAPE_SUPPORT_MARGIN);
  cJSON *mats = cJSON_AddArrayToObject(par, "materials");
  for (int32_t k = 0; k < scene->material_count; ++k) {
    const fascia_material *m = scene->materials + k;
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "name", m->name);
    cJSON_AddStringToObject(e, "law", fascia_law_name(m->law));
    cJSON_AddNumberToObject(e, "youngs_modulus", m->youngs_modulus);
    cJSON_AddNumberToObject(e, "poisson_ratio", m->poisson_ratio);
    cJSON_AddNumberToObject(e, "density", m->density);
    cJSON_AddNumberToObject(e, "rotation_coupling", m->rotation_coupling);
    cJSON_AddItemToArray(mats, e);
  }
  cJSON *tis = cJSON_AddArrayToObject(par, "tissues");
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    const fascia_prep_tissue_def *td = scene->tissues + t;
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "name", td->name);
    cJSON_AddStringToObject(e, "form", fascia_prep_form_name(td->form));
    if (td->form != FASCIA_PREP_FORM_VOLUME) {
      cJSON_AddNumberToObject(e, "section_points", td->section_points);
      cJSON_AddStringToObject(e, "section", td->form == FASCIA_PREP_FORM_STRAND
                                                ? "square of the strand's area, carried by the frames' rotations; "
                                                  "uniaxial stress moduli"
                                                : "thickness along the normal, carried by the frames' rotations; "
                                                  "plane stress moduli");
      double E, nu;
      fascia_shape_section_moduli(td->form == FASCIA_PREP_FORM_STRAND ? 1 : 2,
                                  scene->materials[td->material].youngs_modulus,
                                  scene->materials[td->material].poisson_ratio, &E, &nu);
      cJSON_AddNumberToObject(e, "section_youngs_modulus", E);
      cJSON_AddNumberToObject(e, "section_poisson_ratio", nu);
    }
    if (td->form == FASCIA_PREP_FORM_STRAND) {
      const fascia_prep_attachment *ends[2] = {&td->from, &td->to};
      for (int k = 0; k < 2; ++k) {
        cJSON *a = cJSON_AddObjectToObject(e, k ? "to" : "from");
        cJSON_AddStringToObject(a, "organ", scene->organs[ends[k]->organ].name);
        cJSON_AddItemToObject(a, "point", vector(ends[k]->point, 3));
        cJSON_AddNumberToObject(a, "radius", ends[k]->radius);
        if (ends[k]->part[0]) cJSON_AddStringToObject(a, "part", ends[k]->part);
        if (ends[k]->label[0]) cJSON_AddStringToObject(a, "label", ends[k]->label);
        if (ends[k]->region.kind != FASCIA_PREP_REGION_NONE) cJSON_AddItemToObject(a, "region", region_json(&ends[k]->region));
        cJSON_AddBoolToObject(a, "spread", ends[k]->spread);
      }
      cJSON_AddNumberToObject(e, "area", td->area);
      cJSON_AddNumberToObject(e, "radius", td->radius);
      cJSON *through = cJSON_AddArrayToObject(e, "through");
      for (int32_t k = 0; k < td->through_count; ++k) cJSON_AddItemToArray(through, vector(td->through + 3 * k, 3));
      cJSON_AddStringToObject(e, "curve", td->through_count ? "a polyline from its start through the through points "
                                                              "to its end (reduced.c)"
                                                            : "straight between its ends (reduced.c)");
    } else if (td->form == FASCIA_PREP_FORM_SHEET) {
      cJSON_AddStringToObject(e, "mesh", td->mesh_path);
      cJSON_AddStringToObject(e, "mesh_sha256", meshes->sheets[t].sha256);
      cJSON_AddItemToObject(e, "transform_3x4", vector(td->mesh_transform, 12));
      cJSON_AddNumberToObject(e, "mesh_scale", td->mesh_scale);
      cJSON_AddNumberToObject(e, "thickness", td->thickness);
      cJSON_AddStringToObject(e, "frames", "the mesh's vertices");
    }
    cJSON *con = cJSON_AddArrayToObject(e, "connects");
    for (int32_t k = 0; k < td->organ_count; ++k)
      cJSON_AddItemToArray(con, cJSON_CreateString(scene->organs[td->organs[k]].name));
    cJSON_AddNumberToObject(e, "max_gap", td->max_gap);
    if (td->form == FASCIA_PREP_FORM_VOLUME) cJSON_AddNumberToObject(e, "min_gap", td->min_gap);
    cJSON_AddItemToObject(e, "region", region_json(&td->region));
    if (td->region_organ >= 0) {
      cJSON_AddStringToObject(e, "region_parts_organ", scene->organs[td->region_organ].name);
      cJSON_AddItemToObject(e, "region_parts", parts_json(&td->region_parts));
    }
    sampling_json(e, scene, td->material, td->frame_spacing, td->sample_spacing, td->shape_kind, td->neighbours,
                  td->samples_per_tet, td->enhanced_modes);
    cJSON_AddNumberToObject(e, "coupling_tolerance", td->coupling_tolerance);
    cJSON_AddNumberToObject(e, "min_component", td->min_component);
    cJSON_AddNumberToObject(e, "patch_radius", region_patch_radius(scene, td->material, td->patch_radius,
                                                                   td->frame_spacing, td->sample_spacing, depth[t]));
    if (td->form == FASCIA_PREP_FORM_VOLUME) {
      cJSON_AddNumberToObject(e, "mean_depth", depth[t]);
      const double half_layer = half_layer_spacing(scene, td->material, depth[t], pts->tissue_held_layer_volume[t],
                                                   vol->tissues[t].volume);
      if (half_layer > 0) cJSON_AddNumberToObject(e, "half_layer_spacing", half_layer);
    }
    if (td->attachment == FASCIA_PREP_ATTACH_EXACT) { // only when asked: the default's provenance as before
      cJSON_AddStringToObject(e, "attachment", "exact");
      cJSON_AddNumberToObject(e, "attachment_layer", td->attachment_layer > 0 ? td->attachment_layer : td->sample_spacing);
    }
    cJSON *rules = cJSON_AddArrayToObject(e, "coupling_rules");
    for (int32_t k = 0; k < td->coupling_count; ++k) {
      const fascia_prep_coupling_def *c = td->coupling + k;
      cJSON *r = cJSON_CreateObject();
      cJSON_AddStringToObject(r, "organ", scene->organs[c->organ].name);
      cJSON_AddBoolToObject(r, "enabled", c->enabled);
      cJSON_AddItemToObject(r, "region", region_json(&c->region));
      cJSON_AddItemToObject(r, "parts", parts_json(&c->parts));
      cJSON_AddItemToArray(rules, r);
    }
    cJSON_AddItemToArray(tis, e);
  }
  // reports
  cJSON *rep = cJSON_AddObjectToObject(root, "reports");
  cJSON *org = cJSON_AddArrayToObject(rep, "organs");
  for (int32_t o = 0; o < meshes->count; ++o) {
    const fascia_prep_mesh *m = meshes->organs + o;
    const fascia_prep_mesh_report *r = &m->report;
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "name", m->name);
    cJSON_AddNumberToObject(e, "parts", r->parts_used);
    cJSON_AddNumberToObject(e, "vertices", m->vertex_count);
    cJSON_AddNumberToObject(e, "triangles", m->triangle_count);
    cJSON_AddNumberToObject(e, "duplicate_vertices_merged", r->duplicate_vertices_merged);
    cJSON_AddNumberToObject(e, "degenerate_faces_removed", r->degenerate_faces_removed);
    cJSON_AddNumberToObject(e, "duplicate_faces_removed", r->duplicate_faces_removed);
    cJSON_AddNumberToObject(e, "nonmanifold_vertices_split", r->nonmanifold_vertices_split);
    cJSON_AddNumberToObject(e, "components", r->components);
    cJSON_AddNumberToObject(e, "closed_components", r->closed_components);
    cJSON_AddNumberToObject(e, "components_reoriented", r->components_reoriented);
    cJSON_AddNumberToObject(e, "border_edges", r->border_edges);
    cJSON_AddNumberToObject(e, "holes_filled", r->holes_filled);
    cJSON_AddNumberToObject(e, "holes_left", r->holes_left);
    cJSON_AddNumberToObject(e, "self_intersecting_face_pairs", r->self_intersections);
    cJSON_AddNumberToObject(e, "area_m2", r->area);
    cJSON_AddNumberToObject(e, "enclosed_volume_m3", r->enclosed_volume);
    cJSON_AddStringToObject(e, "inside_rule", r->inside_rule[0] ? r->inside_rule : "not voxelized (far from every tissue)");
    cJSON_AddNumberToObject(e, "shared_frames", cpl->per_organ[o]);
    if (scene->organs[o].kind == FASCIA_ORGAN_DEFORMABLE) {
      // the organ's own frames and samples are contiguous ranges (prep.h, fascia_prep_points)
      const fascia_prep_tissue_report *r2 = vol->organ_regions + o;
      int32_t first_frame = -1, frames = 0, first_sample = -1, samples = 0;
      for (int32_t i = 0; i < pts->frame_count; ++i)
        if (pts->frame_inside_organ[i] == o) first_frame = first_frame < 0 ? i : first_frame, ++frames;
      for (int32_t s = 0; s < pts->sample_count; ++s)
        if (pts->sample_inside_organ[s] == o) first_sample = first_sample < 0 ? s : first_sample, ++samples;
      cJSON *d = cJSON_AddObjectToObject(e, "deformable");
      cJSON_AddNumberToObject(d, "voxels", (double)r2->voxels);
      cJSON_AddNumberToObject(d, "volume_m3", r2->volume);
      cJSON_AddNumberToObject(d, "components", r2->components);
      cJSON_AddNumberToObject(d, "dropped_components", r2->dropped_components);
      cJSON_AddNumberToObject(d, "dropped_volume_m3", r2->dropped_volume);
      cJSON_AddNumberToObject(d, "own_frames", frames);
      cJSON_AddNumberToObject(d, "first_frame", first_frame);
      cJSON_AddNumberToObject(d, "samples", samples);
      cJSON_AddNumberToObject(d, "first_sample", first_sample);
      const fascia_prep_organ_def *od = scene->organs + o;
      sample_volume_json(d, pts, -1, o, od->shape_kind, od->samples_per_tet);
    }
    cJSON_AddItemToArray(org, e);
  }
  cJSON *trep = cJSON_AddArrayToObject(rep, "tissues");
  for (int32_t t = 0; t < vol->tissue_count; ++t) {
    const fascia_prep_tissue_report *r = vol->tissues + t;
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "name", scene->tissues[t].name);
    cJSON_AddNumberToObject(e, "voxels", (double)r->voxels);
    cJSON_AddNumberToObject(e, "volume_m3", r->volume);
    cJSON_AddNumberToObject(e, "components", r->components);
    cJSON_AddNumberToObject(e, "dropped_components", r->dropped_components);
    cJSON_AddNumberToObject(e, "dropped_volume_m3", r->dropped_volume);
    cJSON_AddNumberToObject(e, "occupied_volume_m3", r->occupied_volume);
    int32_t frames = 0, samples = 0;
    for (int32_t i = 0; i < pts->frame_count; ++i) frames += pts->frame_tissue[i] == t;
    for (int32_t s = 0; s < pts->sample_count; ++s) samples += pts->sample_tissue[s] == t;
    cJSON_AddNumberToObject(e, "frames", frames);
    cJSON_AddNumberToObject(e, "samples", samples);
    cJSON_AddStringToObject(e, "form", fascia_prep_form_name(scene->tissues[t].form));
    sample_volume_json(e, pts, t, -1, scene->tissues[t].shape_kind, scene->tissues[t].samples_per_tet);
    if (scene->tissues[t].form != FASCIA_PREP_FORM_VOLUME)
      cJSON_ReplaceItemInObject(e, "sample_volume_of",
                                cJSON_CreateString(scene->tissues[t].form == FASCIA_PREP_FORM_STRAND
                                                       ? "length x cross-section area"
                                                       : "mesh area x thickness"));
    cJSON_AddItemToArray(trep, e);
  }
  cJSON *ov = cJSON_AddArrayToObject(rep, "overlaps");
  for (int32_t k = 0; k < vol->overlap_count; ++k) {
    const fascia_prep_overlap *o = vol->overlaps + k;
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "a", meshes->organs[o->a].name);
    cJSON_AddStringToObject(e, "b", meshes->organs[o->b].name);
    cJSON_AddNumberToObject(e, "volume_m3", o->volume);
    cJSON_AddNumberToObject(e, "depth_m", o->depth);
    cJSON_AddStringToObject(e, "rule", "tissue is built outside both organs; organ surfaces kept as given");
    cJSON_AddItemToArray(ov, e);
  }
  cJSON *gaps = cJSON_AddArrayToObject(rep, "closest_distances");
  for (int32_t a = 0; a < vol->organ_count; ++a)
    for (int32_t b = a + 1; b < vol->organ_count; ++b) {
      const double d = vol->closest[a * vol->organ_count + b];
      if (d < 0) continue;
      cJSON *e = cJSON_CreateObject();
      cJSON_AddStringToObject(e, "a", meshes->organs[a].name);
      cJSON_AddStringToObject(e, "b", meshes->organs[b].name);
      cJSON_AddNumberToObject(e, "distance_m", d);
      cJSON_AddItemToArray(gaps, e);
    }
  cJSON_AddNumberToObject(rep, "max_linear_reproduction_error_m", W->max_linear_error);
  cJSON *warnings = cJSON_AddArrayToObject(rep, "warnings");
  for (int32_t k = 0; k < meshes->warning_count; ++k)
    cJSON_AddItemToArray(warnings, cJSON_CreateString(meshes->warnings[k]));
  if (info && info->step_count > 0) {
    cJSON *steps = cJSON_AddArrayToObject(root, "steps");
    for (int32_t k = 0; k < info->step_count; ++k) {
      cJSON *e = cJSON_CreateObject();
      cJSON_AddStringToObject(e, "name", info->step_name[k]);
      cJSON_AddNumberToObject(e, "seconds", info->step_seconds[k]);
      if (info->step_peak_bytes) cJSON_AddNumberToObject(e, "peak_bytes", info->step_peak_bytes[k]);
      cJSON_AddItemToArray(steps, e);
    }
  }
  return root;
}

// Whether sample s weighs on a frame that goes (frame_piece >= 0): an
// unheld piece's samples weigh on its frames only, a hinged piece's also on
// the frames that held it, which stay.
static int sample_dropped(const fascia_model *m, const int32_t *frame_piece, int32_t s) {
  for (int32_t p = m->sample_offsets[s]; p < m->sample_offsets[s + 1]; ++p)
    if (frame_piece[m->pair_frame[p]] >= 0) return 1;
  return 0;
}

// The model without the frames of dropped pieces (frame_piece >= 0), their
// samples and pairs and their coupling entries; organs, motions and materials
// move over from *mp, which is replaced.
static fascia_status compact(fascia_ctx *ctx, fascia_model **mp, const int32_t *frame_piece) {
  fascia_model *m = *mp, *n = NULL;
  const int32_t N = m->frame_count, S = m->sample_count;
  int32_t *map = malloc(((size_t)N + 1) * sizeof *map);
  PREP_CHECK(map, ctx, FASCIA_ERR_MEMORY, "package: out of memory");
  fascia_model_sizes z;
  memset(&z, 0, sizeof z);
  for (int32_t i = 0; i < N; ++i) map[i] = frame_piece[i] < 0 ? z.frames++ : -1;
  for (int32_t s = 0; s < S; ++s)
    if (!sample_dropped(m, frame_piece, s)) ++z.samples, z.pairs += m->sample_offsets[s + 1] - m->sample_offsets[s];
  for (int32_t c = 0; c < m->coupling_count; ++c) z.couplings += map[m->coupling_frame[c]] >= 0;
  z.materials = m->material_count;
  z.motions = m->motion_count;
  z.organs = m->organ_count;
  fascia_status status = fascia_model_alloc(ctx, &z, &n);
  if (status != FASCIA_OK) {
    free(map);
    return status;
  }
  for (int32_t i = 0; i < N; ++i) {
    const int32_t j = map[i];
    if (j < 0) continue;
    memcpy(n->frame_position + 3 * j, m->frame_position + 3 * i, 3 * sizeof(double));
    memcpy(n->frame_rotation + 4 * j, m->frame_rotation + 4 * i, 4 * sizeof(double));
    memcpy(n->frame_load + 6 * j, m->frame_load + 6 * i, 6 * sizeof(double));
    n->frame_kind[j] = m->frame_kind[i];
    n->frame_motion[j] = m->frame_motion[i];
    n->frame_organ[j] = m->frame_organ[i];
  }
  for (int32_t s = 0, t = 0, q = 0; s < S; ++s) {
    if (sample_dropped(m, frame_piece, s)) continue;
    memcpy(n->sample_position + 3 * t, m->sample_position + 3 * s, 3 * sizeof(double));
    n->sample_volume[t] = m->sample_volume[s];
    n->sample_material[t] = m->sample_material[s];
    n->sample_organ[t] = m->sample_organ[s];
    n->sample_patch[t] = m->sample_patch[s];
    n->sample_modes[t] = m->sample_modes[s];
    for (int32_t p = m->sample_offsets[s]; p < m->sample_offsets[s + 1]; ++p, ++q) {
      n->pair_frame[q] = map[m->pair_frame[p]]; // the order of frames is kept: still ascending
      n->pair_weight[q] = m->pair_weight[p];
      memcpy(n->pair_gradient + 3 * q, m->pair_gradient + 3 * p, 3 * sizeof(double));
    }
    n->sample_offsets[++t] = q;
  }
  for (int32_t c = 0, d = 0; c < m->coupling_count; ++c) {
    if (map[m->coupling_frame[c]] < 0) continue;
    n->coupling_organ[d] = m->coupling_organ[c];
    n->coupling_frame[d] = map[m->coupling_frame[c]];
    n->coupling_triangle[d] = m->coupling_triangle[c];
    memcpy(n->coupling_barycentric + 3 * d, m->coupling_barycentric + 3 * c, 3 * sizeof(double));
    ++d;
  }
  int32_t tets = 0; // the tetrahedra whose frames all stay
  for (int32_t k = 0; k < m->tetrahedron_count; ++k) {
    const int32_t *t = m->tetrahedra + 4 * (int64_t)k;
    tets += map[t[0]] >= 0 && map[t[1]] >= 0 && map[t[2]] >= 0 && map[t[3]] >= 0;
  }
  status = fascia_model_tetrahedra_alloc(ctx, n, tets);
  for (int32_t k = 0, j = 0; status == FASCIA_OK && k < m->tetrahedron_count; ++k) {
    const int32_t *t = m->tetrahedra + 4 * (int64_t)k;
    if (map[t[0]] < 0 || map[t[1]] < 0 || map[t[2]] < 0 || map[t[3]] < 0) continue;
    for (int c = 0; c < 4; ++c) n->tetrahedra[4 * (int64_t)j + c] = map[t[c]];
    ++j;
  }
  free(map);
  if (status != FASCIA_OK) {
    fascia_model_destroy(&n);
    return status;
  }
  memcpy(n->gravity, m->gravity, sizeof n->gravity);
  memcpy(n->materials, m->materials, (size_t)m->material_count * sizeof *n->materials);
  // hand the organs' meshes and the motions' keys over instead of copying them
  fascia_organ *organs = n->organs;
  fascia_motion *motions = n->motions;
  n->organs = m->organs, n->motions = m->motions;
  m->organs = organs, m->motions = motions;
  fascia_model_destroy(mp);
  *mp = n;
  return fascia_model_build_reverse(ctx, n);
}

static int compare_tets(const void *a, const void *b) { return memcmp(a, b, 4 * sizeof(int32_t)); }

// The tetrahedra of the TET regions (drawing only): each sample's corner
// frames (ascending), each tetrahedron once.
static fascia_status collect_tetrahedra(fascia_ctx *ctx, const fascia_prep_points *pts, fascia_model *m) {
  const int32_t S = pts->sample_count;
  int32_t *tets = prep_calloc(4 * (int64_t)S + 4, sizeof(int32_t)), count = 0;
  PREP_CHECK(tets, ctx, FASCIA_ERR_MEMORY, "package: out of memory");
  for (int32_t s = 0; s < S; ++s)
    if (pts->sample_tet_frame[4 * (int64_t)s] >= 0)
      memcpy(tets + 4 * (int64_t)count++, pts->sample_tet_frame + 4 * (int64_t)s, 4 * sizeof(int32_t));
  qsort(tets, (size_t)count, 4 * sizeof(int32_t), compare_tets);
  int32_t unique = 0;
  for (int32_t k = 0; k < count; ++k)
    if (unique == 0 || compare_tets(tets + 4 * (int64_t)k, tets + 4 * (int64_t)(unique - 1)))
      memmove(tets + 4 * (int64_t)unique++, tets + 4 * (int64_t)k, 4 * sizeof(int32_t));
  const fascia_status status = fascia_model_tetrahedra_alloc(ctx, m, unique);
  if (status == FASCIA_OK) memcpy(m->tetrahedra, tets, 4 * (size_t)unique * sizeof(int32_t));
  free(tets);
  return status;
}

// A piece of volume tissue held at fewer than three points off one line
// turns about them for free. Its weights reproduce linear fields, so free
// frames moved by d_i = w x (X_i - c), for an axis w through the points that
// hold it (c on it), move every sample by w x (p - c) and give it
// F = I + [w]x, a rotation to first order: no strain, and the energy rises
// only as the fourth power of the angle (a hinge; held at one point, a ball
// joint). Gravity swings such a piece far beyond the tissue's strain and its
// Newton iterations converge slowly, setting the cost of every step of the
// whole model. A piece here: free frames joined through volume samples;
// what holds it: the fixed and prescribed frames and the frames coupled to a
// rigid organ that its samples weigh on. Strand, sheet and shell samples
// carry their section by the frames' rotations, which the held frames lock:
// their pieces are left alone.
#define HINGE_TOLERANCE 1e-2 // held points within this fraction of their span from one line

static int32_t hinge_root(int32_t *parent, int32_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// The largest distance of the points x[3 list[k]] from the line through the
// two farthest apart (the farthest from the first, then the farthest from
// that one), relative to their distance; 0 for fewer than three.
static double off_line(const double *x, const int32_t *list, int32_t count) {
  if (count < 3) return 0;
  int32_t a = list[0], b = list[0];
  double far = 0, worst = 0, e[3];
  for (int32_t k = 0; k < count; ++k)
    if (prep_dist3(x + 3 * (int64_t)list[k], x + 3 * (int64_t)list[0]) > far)
      far = prep_dist3(x + 3 * (int64_t)list[k], x + 3 * (int64_t)list[0]), a = list[k];
  far = 0;
  for (int32_t k = 0; k < count; ++k)
    if (prep_dist3(x + 3 * (int64_t)list[k], x + 3 * (int64_t)a) > far)
      far = prep_dist3(x + 3 * (int64_t)list[k], x + 3 * (int64_t)a), b = list[k];
  if (!(far > 0)) return 0;
  for (int c = 0; c < 3; ++c) e[c] = (x[3 * (int64_t)b + c] - x[3 * (int64_t)a + c]) / far;
  for (int32_t k = 0; k < count; ++k) {
    double v[3], t = 0, o = 0;
    for (int c = 0; c < 3; ++c) v[c] = x[3 * (int64_t)list[k] + c] - x[3 * (int64_t)a + c], t += v[c] * e[c];
    for (int c = 0; c < 3; ++c) o += (v[c] - t * e[c]) * (v[c] - t * e[c]);
    worst = fmax(worst, sqrt(o) / far);
  }
  return worst;
}

// Marks the frames of every hinged piece (above) in frame_piece, numbered
// from *count on, and lists each in `dropped` with the number of frames that
// held it. frame_piece: -1 for a frame kept so far. A hinged piece that
// holds a deformable organ's frames is refused: dropping it would drop the
// organ.
static fascia_status mark_hinged(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_points *pts,
                                 const fascia_model *m, int32_t *frame_piece, int32_t *count, cJSON *dropped) {
  const int32_t N = m->frame_count, S = m->sample_count;
  int32_t *parent = prep_calloc((int64_t)N + 1, sizeof(int32_t)), *stamp = prep_calloc((int64_t)N + 1, sizeof(int32_t));
  int32_t *list = prep_calloc((int64_t)N + 1, sizeof(int32_t)), *root = prep_calloc((int64_t)S + 1, sizeof(int32_t));
  int32_t *start = prep_calloc((int64_t)N + 2, sizeof(int32_t)), *order = prep_calloc((int64_t)S + 1, sizeof(int32_t));
  unsigned char *held = prep_calloc((int64_t)N + 1, 1), *section = prep_calloc((int64_t)N + 1, 1);
  fascia_status status = FASCIA_OK;
  PREP_CHECK_GOTO(parent && stamp && list && root && start && order && held && section, ctx, FASCIA_ERR_MEMORY,
                  "package: out of memory");
  for (int32_t i = 0; i < N; ++i) parent[i] = i, stamp[i] = -1, held[i] = m->frame_kind[i] != FASCIA_FRAME_FREE;
  for (int32_t c = 0; c < m->coupling_count; ++c)
    if (m->organs[m->coupling_organ[c]].kind == FASCIA_ORGAN_RIGID) held[m->coupling_frame[c]] = 1;
  // pieces: the free frames joined through the samples
  for (int32_t s = 0; s < S; ++s) {
    int32_t first = -1;
    for (int32_t p = m->sample_offsets[s]; p < m->sample_offsets[s + 1]; ++p) {
      const int32_t f = m->pair_frame[p];
      if (held[f]) continue;
      section[f] |= pts->sample_voxel[s] < 0;
      if (first < 0) first = f;
      const int32_t a = hinge_root(parent, first), b = hinge_root(parent, f);
      if (a < b) parent[b] = a;
      else if (b < a) parent[a] = b;
    }
  }
  for (int32_t i = 0; i < N; ++i) section[hinge_root(parent, i)] |= section[i];
  // each piece's samples, in one pass (a sample weighing on held frames only has none)
  for (int32_t s = 0; s < S; ++s) {
    root[s] = -1;
    for (int32_t p = m->sample_offsets[s]; p < m->sample_offsets[s + 1] && root[s] < 0; ++p)
      if (!held[m->pair_frame[p]]) root[s] = hinge_root(parent, m->pair_frame[p]);
    if (root[s] >= 0) ++start[root[s] + 1];
  }
  for (int32_t i = 0; i < N; ++i) start[i + 1] += start[i];
  for (int32_t s = 0; s < S; ++s) // stamp counts the samples placed so far per piece
    if (root[s] >= 0) order[start[root[s]] + ++stamp[root[s]]] = s;
  for (int32_t i = 0; i < N; ++i) stamp[i] = -1;
  for (int32_t r = 0; r < N; ++r) {
    if (held[r] || frame_piece[r] >= 0 || section[r] || hinge_root(parent, r) != r || start[r] == start[r + 1])
      continue; // not a piece's first frame, already dropped, a section's, or no sample weighs on it
    int32_t points = 0;
    fascia_model_piece q = {0, 0, 0, r, {m->frame_position[3 * (int64_t)r], m->frame_position[3 * (int64_t)r + 1],
                                         m->frame_position[3 * (int64_t)r + 2]}};
    for (int32_t k = start[r]; k < start[r + 1]; ++k) {
      const int32_t s = order[k];
      ++q.samples;
      if (m->materials[m->sample_material[s]].part != FASCIA_PART_VOLUMETRIC) q.volume += m->sample_volume[s];
      for (int32_t p = m->sample_offsets[s]; p < m->sample_offsets[s + 1]; ++p) {
        const int32_t f = m->pair_frame[p];
        if (held[f] && stamp[f] != r) stamp[f] = r, list[points++] = f;
      }
    }
    if (points == 0 || off_line(m->frame_position, list, points) > HINGE_TOLERANCE) continue; // unheld: drop_unheld's
    for (int32_t i = r; i < N; ++i) {
      if (held[i] || hinge_root(parent, i) != r) continue;
      const int32_t o = m->frame_organ[i];
      PREP_CHECK_GOTO(o < 0, ctx, FASCIA_ERR_ARGUMENT,
                      "scene '%s': deformable organ '%s' and the tissue on it are held at only %d point(s)%s near "
                      "(%.4g, %.4g, %.4g) m: they would turn about %s at no cost; fix or prescribe another organ the "
                      "tissue connects, or lower the tissue's frame_spacing so that more of its frames lie on the "
                      "organs that hold it",
                      scene->path, scene->organs[o].name, (int)points, points > 1 ? " on a line" : "", q.position[0],
                      q.position[1], q.position[2], points > 1 ? "that line" : "it");
      frame_piece[i] = *count;
      ++q.frames;
    }
    const int32_t t = pts->frame_tissue[r];
    cJSON *e = cJSON_CreateObject();
    PREP_CHECK_GOTO(e, ctx, FASCIA_ERR_MEMORY, "package: out of memory");
    cJSON_AddItemToArray(dropped, e);
    if (t >= 0) cJSON_AddStringToObject(e, "tissue", scene->tissues[t].name);
    cJSON_AddNumberToObject(e, "volume_m3", q.volume);
    cJSON_AddNumberToObject(e, "frames", q.frames);
    cJSON_AddNumberToObject(e, "samples", q.samples);
    cJSON_AddItemToObject(e, "position_m", vector(q.position, 3));
    cJSON_AddNumberToObject(e, "held_at", points);
    ++*count;
  }
cleanup:
  free(parent), free(stamp), free(list), free(root), free(start), free(order), free(held), free(section);
  return status;
}

// Tissue that no fixed or prescribed organ holds, directly or through other
// tissue, a deformable or a rigid organ, would fall for ever in the simulation
// (the model loader refuses it). Such pieces, and the hinged ones
// (mark_hinged), are dropped and listed in `dropped` (one object each, with
// held_at the number of frames that held it); a tissue left with nothing is
// refused. A free
// frame that no sample weighs on (a tetrahedral region's frame whose
// tetrahedra all lie outside the region) and that couples to no organ carries
// nothing, and the solver refuses a free frame without mass: those go too,
// counted in *empty.
static fascia_status drop_unheld(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_points *pts,
                                 fascia_model **mp, cJSON *dropped, int32_t *empty) {
  fascia_model *m = *mp;
  const int32_t N = m->frame_count;
  *empty = 0;
  int32_t *frame_piece = malloc(((size_t)N + 1) * sizeof *frame_piece);
  fascia_model_piece *pieces = malloc(((size_t)N + 1) * sizeof *pieces);
  double *kept = calloc((size_t)scene->tissue_count + 1, sizeof *kept);
  double *lost = calloc((size_t)scene->tissue_count + 1, sizeof *lost);
  fascia_status status = FASCIA_OK;
  int32_t count = 0;
  PREP_CHECK_GOTO(frame_piece && pieces && kept && lost, ctx, FASCIA_ERR_MEMORY, "package: out of memory");
  PREP_TRY_GOTO(fascia_model_floating_components(ctx, m, frame_piece, pieces, N, &count));
  {
    unsigned char *used = calloc((size_t)N + 1, 1); // weighed on by a sample, or coupled to an organ
    PREP_CHECK_GOTO(used, ctx, FASCIA_ERR_MEMORY, "package: out of memory");
    for (int32_t k = 0; k < m->pair_count; ++k) used[m->pair_frame[k]] = 1;
    for (int32_t c = 0; c < m->coupling_count; ++c) used[m->coupling_frame[c]] = 1;
    for (int32_t i = 0; i < N; ++i)
      if (m->frame_kind[i] == FASCIA_FRAME_FREE && !used[i] && frame_piece[i] < 0) {
        frame_piece[i] = count; // any piece number drops it (compact keeps -1 only)
        ++*empty;
      }
    free(used);
  }
  int32_t numbered = count + 1; // after the unheld pieces and the frames without samples
  PREP_TRY_GOTO(mark_hinged(ctx, scene, pts, m, frame_piece, &numbered, dropped));
  if (count == 0 && *empty == 0 && numbered == count + 1) goto cleanup;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    const int32_t t = pts->sample_tissue[s];
    if (t < 0) continue;
    if (!sample_dropped(m, frame_piece, s)) kept[t] += m->sample_volume[s];
    else lost[t] += m->sample_volume[s];
  }
  for (int32_t t = 0; t < scene->tissue_count; ++t)
    PREP_CHECK_GOTO(kept[t] > 0 || lost[t] == 0, ctx, FASCIA_ERR_ARGUMENT, // the scene's problem, as voxelize's
                    "scene '%s': no part of tissue '%s' (%.3g cm^3) touches a fixed or prescribed organ, directly or "
                    "through other tissue or organs (at three frames or more off one line): nothing holds it and it "
                    "would fall or turn for ever; make one of the "
                    "organs it touches fixed or prescribed, or widen its region (max_gap) to reach one",
                    scene->path, scene->tissues[t].name, 1e6 * lost[t]);
  for (int32_t k = 0; k < count; ++k) {
    const fascia_model_piece *q = pieces + k;
    const int32_t t = pts->frame_tissue[q->first_frame], o = pts->frame_inside_organ[q->first_frame];
    cJSON *e = cJSON_CreateObject();
    PREP_CHECK_GOTO(e, ctx, FASCIA_ERR_MEMORY, "package: out of memory");
    cJSON_AddItemToArray(dropped, e);
    if (t >= 0) cJSON_AddStringToObject(e, "tissue", scene->tissues[t].name);
    else if (o >= 0) cJSON_AddStringToObject(e, "organ", scene->organs[o].name);
    cJSON_AddNumberToObject(e, "volume_m3", q->volume);
    cJSON_AddNumberToObject(e, "frames", q->frames);
    cJSON_AddNumberToObject(e, "samples", q->samples);
    cJSON_AddItemToObject(e, "position_m", vector(q->position, 3));
    cJSON_AddNumberToObject(e, "held_at", 0);
  }
  PREP_TRY_GOTO(compact(ctx, mp, frame_piece));
cleanup:
  free(frame_piece);
  free(pieces);
  free(kept);
  free(lost);
  return status;
}

fascia_status fascia_prep_package(fascia_ctx *ctx, const fascia_prep_scene *scene, const fascia_prep_meshes *meshes,
                                  const fascia_prep_volume *volume, const fascia_prep_points *points,
                                  const fascia_prep_weights *weights, const fascia_prep_coupling *coupling,
                                  const fascia_prep_run_info *info, fascia_model **out) {
  PREP_CHECK(ctx && scene && meshes && volume && points && weights && coupling && out, ctx, FASCIA_ERR_ARGUMENT,
             "fascia_prep_package: NULL argument");
  *out = NULL;
  fascia_status status = FASCIA_OK;
  fascia_model *m = NULL;
  cJSON *prov = NULL, *dropped = NULL;
  char *prov_text = NULL;
  int32_t empty_frames = 0;
  int32_t motions = 0;
  double *depth = NULL;
  for (int32_t o = 0; o < scene->organ_count; ++o) motions += scene->organs[o].kind == FASCIA_ORGAN_PRESCRIBED;
  fascia_model_sizes z;
  memset(&z, 0, sizeof z);
  z.frames = points->frame_count;
  z.samples = points->sample_count;
  z.pairs = weights->pair_count;
  // a strand's or a sheet's samples get their section's moduli: a material of their own
  int32_t *section_material = prep_calloc(scene->tissue_count, sizeof(int32_t));
  PREP_CHECK(section_material, ctx, FASCIA_ERR_MEMORY, "package: out of memory");
  int32_t sections = 0;
  for (int32_t t = 0; t < scene->tissue_count; ++t) { // a sheet's drilling stabilisers get the next one
    const int form = scene->tissues[t].form;
    section_material[t] = form == FASCIA_PREP_FORM_VOLUME ? -1 : scene->material_count + sections;
    sections += (form != FASCIA_PREP_FORM_VOLUME) + (form == FASCIA_PREP_FORM_SHEET);
  }
  z.materials = scene->material_count + sections;
  z.motions = motions;
  z.organs = scene->organ_count;
  z.couplings = coupling->count;
  PREP_TRY_GOTO(fascia_model_alloc(ctx, &z, &m));
  memcpy(m->gravity, scene->gravity, sizeof m->gravity);
  memcpy(m->materials, scene->materials, (size_t)scene->material_count * sizeof *m->materials);
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    if (section_material[t] < 0) continue;
    const fascia_prep_tissue_def *td = scene->tissues + t;
    fascia_material *mat = m->materials + section_material[t];
    *mat = scene->materials[td->material];
    fascia_shape_section_moduli(td->form == FASCIA_PREP_FORM_STRAND ? 1 : 2, mat->youngs_modulus, mat->poisson_ratio,
                                &mat->youngs_modulus, &mat->poisson_ratio);
    mat->rotation_smoothing = 0; // the rotations carry the section: smoothing would stiffen its bending
    char name[2 * FASCIA_NAME_SIZE + 16];
    snprintf(name, sizeof name, "%s/%s", scene->materials[td->material].name, td->name);
    snprintf(mat->name, sizeof mat->name, "%.*s", (int)sizeof mat->name - 1, name);
    if (td->form == FASCIA_PREP_FORM_SHEET) { // its drilling stabilisers' (reduced.h), the next one
      fascia_material *d = mat + 1;
      const double mu = mat->youngs_modulus / (2 * (1 + mat->poisson_ratio));
      *d = *mat;
      d->part = FASCIA_PART_VOLUMETRIC;
      d->poisson_ratio = 0.25; // lambda = 0.4 E
      d->youngs_modulus = PREP_SHEET_DRILLING_LAMBDA * mu / 0.4;
      snprintf(name, sizeof name, "%s/%s/drilling", scene->materials[td->material].name, td->name);
      snprintf(d->name, sizeof d->name, "%.*s", (int)sizeof d->name - 1, name);
    }
  }
  // organs and their motions
  for (int32_t o = 0, motion = 0; o < scene->organ_count; ++o) {
    const fascia_prep_organ_def *d = scene->organs + o;
    const fascia_prep_mesh *mesh = meshes->organs + o;
    fascia_organ *organ = m->organs + o;
    snprintf(organ->name, sizeof organ->name, "%s", d->name);
    organ->kind = d->kind;
    organ->motion = -1;
    PREP_TRY_GOTO(fascia_organ_alloc(ctx, organ, mesh->vertex_count, mesh->triangle_count));
    memcpy(organ->vertices, mesh->vertices, 3 * (size_t)mesh->vertex_count * sizeof(double));
    memcpy(organ->triangles, mesh->triangles, 3 * (size_t)mesh->triangle_count * sizeof(int32_t));
    if (d->kind == FASCIA_ORGAN_PRESCRIBED) {
      fascia_motion *mo = m->motions + motion;
      snprintf(mo->name, sizeof mo->name, "%s", d->name);
      memcpy(mo->pivot, d->motion.pivot, sizeof mo->pivot);
      PREP_TRY_GOTO(fascia_motion_alloc(ctx, mo, d->motion.key_count));
      memcpy(mo->key_time, d->motion.key_time, (size_t)d->motion.key_count * sizeof(double));
      memcpy(mo->key_translation, d->motion.key_translation, 3 * (size_t)d->motion.key_count * sizeof(double));
      memcpy(mo->key_rotation, d->motion.key_rotation, 4 * (size_t)d->motion.key_count * sizeof(double));
      organ->motion = motion++;
    }
  }
  // frames (rest rotation identity, set by alloc), kinds from the organs they are
  // shared with; frames shared with rigid or deformable organs, and a
  // deformable organ's own frames, stay FREE (alloc's zero)
  memcpy(m->frame_position, points->frame_position, 3 * (size_t)points->frame_count * sizeof(double));
  for (int32_t c = 0; c < coupling->count; ++c) {
    const int32_t i = coupling->frame[c];
    const fascia_organ *organ = m->organs + coupling->organ[c];
    m->coupling_organ[c] = coupling->organ[c];
    m->coupling_frame[c] = i;
    m->coupling_triangle[c] = coupling->triangle[c];
    memcpy(m->coupling_barycentric + 3 * c, coupling->barycentric + 3 * c, 3 * sizeof(double));
    if (organ->kind == FASCIA_ORGAN_FIXED) {
      m->frame_kind[i] = FASCIA_FRAME_FIXED;
      m->frame_motion[i] = -1;
    } else if (organ->kind == FASCIA_ORGAN_PRESCRIBED && m->frame_kind[i] != FASCIA_FRAME_FIXED) {
      m->frame_kind[i] = FASCIA_FRAME_PRESCRIBED;
      m->frame_motion[i] = organ->motion;
    }
  }
  // samples and pairs
  memcpy(m->sample_position, points->sample_position, 3 * (size_t)points->sample_count * sizeof(double));
  memcpy(m->sample_volume, points->sample_volume, (size_t)points->sample_count * sizeof(double));
  for (int32_t s = 0; s < points->sample_count; ++s) {
    const int32_t t = points->sample_tissue[s];
    const int drilling = points->sample_drilling && points->sample_drilling[s];
    m->sample_material[s] = t < 0                      ? scene->organs[points->sample_inside_organ[s]].material
                            : section_material[t] >= 0 ? section_material[t] + drilling
                                                       : scene->tissues[t].material;
    m->sample_organ[s] = points->sample_inside_organ[s]; // model organs are the scene's, in order
    m->sample_modes[s] = t >= 0 // settled on the patches below
                             ? scene->tissues[t].form == FASCIA_PREP_FORM_VOLUME && scene->tissues[t].enhanced_modes
                             : scene->organs[points->sample_inside_organ[s]].enhanced_modes;
  }
  for (int32_t i = 0; i < points->frame_count; ++i) m->frame_organ[i] = points->frame_inside_organ[i];
  // a shell organ's frames in its hold region, its own and those it shares, are fixed (docs/organs.md)
  for (int32_t i = 0, c = 0; i < points->frame_count; ++i) {
    int32_t o = points->frame_inside_organ[i];
    for (; c < coupling->count && coupling->frame[c] < i; ++c) {}
    if (c < coupling->count && coupling->frame[c] == i) o = coupling->organ[c];
    if (o >= 0 && scene->organs[o].shell && scene->organs[o].hold.kind != FASCIA_PREP_REGION_NONE &&
        prep_region_contains(&scene->organs[o].hold, points->frame_position + 3 * (int64_t)i))
      m->frame_kind[i] = FASCIA_FRAME_FIXED, m->frame_motion[i] = -1;
  }
  memcpy(m->sample_offsets, weights->sample_offsets, ((size_t)points->sample_count + 1) * sizeof(int32_t));
  memcpy(m->pair_frame, weights->pair_frame, (size_t)weights->pair_count * sizeof(int32_t));
  memcpy(m->pair_weight, weights->pair_weight, (size_t)weights->pair_count * sizeof(double));
  memcpy(m->pair_gradient, weights->pair_gradient, 3 * (size_t)weights->pair_count * sizeof(double));
  PREP_TRY_GOTO(fascia_model_build_reverse(ctx, m));
  PREP_TRY_GOTO(prep_shell_pressure_loads(ctx, scene, meshes, points, m)); // before the frames are compacted
  PREP_TRY_GOTO(collect_tetrahedra(ctx, points, m));
  dropped = cJSON_CreateArray();
  PREP_CHECK_GOTO(dropped, ctx, FASCIA_ERR_MEMORY, "package: out of memory");
  PREP_TRY_GOTO(drop_unheld(ctx, scene, points, &m, dropped, &empty_frames));
  depth = region_depths(scene, volume);
  PREP_CHECK_GOTO(depth, ctx, FASCIA_ERR_MEMORY, "package: out of memory");
  PREP_TRY_GOTO(make_patches(ctx, scene, depth, m));
  PREP_TRY_GOTO(modes_on_patches(ctx, m));
  PREP_TRY_GOTO(prep_tissue_surface(ctx, scene, meshes, volume, points, &m->tissue_surface));
  // provenance (its counts are those before the unheld pieces were dropped)
  prov = provenance(scene, meshes, volume, points, weights, coupling, depth, info);
  cJSON *reports = prov ? cJSON_GetObjectItem(prov, "reports") : NULL;
  PREP_CHECK_GOTO(reports, ctx, FASCIA_ERR_MEMORY, "package: out of memory for the provenance");
  cJSON_AddItemToObject(reports, "unheld_pieces_dropped", dropped);
  cJSON_AddNumberToObject(reports, "frames_without_samples_dropped", empty_frames);
  dropped = NULL;
  prov_text = prov ? cJSON_PrintUnformatted(prov) : NULL;
  PREP_CHECK_GOTO(prov_text, ctx, FASCIA_ERR_MEMORY, "package: out of memory for the provenance");
  PREP_TRY_GOTO(fascia_model_set_provenance(ctx, m, prov_text));
  PREP_TRY_GOTO(fascia_model_validate(ctx, m, scene->path));
  *out = m;
  m = NULL;
cleanup:
  free(section_material);
  free(depth);
  cJSON_Delete(prov);
  cJSON_Delete(dropped);
  free(prov_text);
  fascia_model_destroy(&m);
  return status;
}
