// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The scene's sizes against anatomy's. Every length of a scene is metres; a
// mesh in millimetres read without its "units", or a motion of 3 mm typed as
// 3, is off from any organ by a factor of 10 to 1000, and would otherwise end
// in a message about voxel counts or memory. What cannot be simulated (an
// organ larger than a body, a motion larger than the whole scene) is refused;
// what may be meant is warned about. Each message says that the units look
// wrong and how the scene's lengths are read (data/scenes/README.md, "Units
// and sizes").
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "prep_util.h"

// anatomy's sizes, m
#define BODY_SIZE 3.0      // no organ, nor the space between organs, is larger
#define ORGAN_SMALLEST 1e-3 // no organ is smaller
#define TYPICAL_ORGAN 0.1  // the size the suggested units aim at
#define VOXEL_COARSEST 0.05 // coarser voxels resolve no gap between organs
// the largest strain a run accepts by default (fascia run --blow-up-strain)
#define RUN_STRAIN_LIMIT 10.0

static const struct {
  const char *name, *word;
  double metres;
} units_known[] = {{"m", "metres", 1}, {"cm", "centimetres", 0.01}, {"mm", "millimetres", 0.001}};
enum { UNITS_KNOWN = sizeof units_known / sizeof units_known[0] };

static const char *units_word(const char *name) {
  for (int u = 0; u < UNITS_KNOWN; ++u)
    if (!strcmp(units_known[u].name, name)) return units_known[u].word;
  return name;
}

double prep_mesh_extent(const fascia_prep_mesh *mesh) {
  const double *b = mesh->bounds;
  return fmax(fmax(b[3] - b[0], b[4] - b[1]), b[5] - b[2]);
}

void prep_units_hint_organ(const fascia_prep_scene *scene, int32_t k, double extent, char *out, size_t size) {
  const fascia_prep_organ_def *d = scene->organs + k;
  out[0] = 0;
  if (extent >= ORGAN_SMALLEST && extent <= BODY_SIZE) return;
  if (d->label_count) { // its size comes from the label map's affine and units, not from "units"
    snprintf(out, size,
             "; the size looks wrong: an organ of labels takes its size from the label map (its affine and its "
             "units field); check the map's header or voxel_size");
    return;
  }
  // the other units that bring the organ closest to a typical organ's size
  int better = -1;
  double miss = INFINITY, fixed = 0;
  for (int u = 0; u < UNITS_KNOWN; ++u) {
    const double e = extent * units_known[u].metres / d->scale;
    if (!strcmp(units_known[u].name, d->units) || e < ORGAN_SMALLEST || e > BODY_SIZE) continue;
    if (fabs(log(e / TYPICAL_ORGAN)) < miss) miss = fabs(log(e / TYPICAL_ORGAN)), better = u, fixed = e;
  }
  char given[32] = "left out";
  if (d->units_given) snprintf(given, sizeof given, "\"%s\"", d->units);
  int n = snprintf(out, size,
                   "; the units look wrong: the file's coordinates are read as %s (organs[%d].units %s), and every "
                   "length of the scene is metres",
                   units_word(d->units), (int)k, given);
  if (better >= 0 && n > 0 && (size_t)n < size)
    snprintf(out + n, size - (size_t)n, "; if the file is in %s, set \"units\": \"%s\" (the organ is then %.3g cm across)",
             units_known[better].word, units_known[better].name, 100 * fixed);
}

void prep_units_hint_voxel(const fascia_prep_scene *scene, char *out, size_t size) {
  out[0] = 0;
  if (scene->voxel_size >= VOXEL_COARSEST)
    snprintf(out, size,
             "; the units look wrong: voxel_size %g m is coarser than any gap between organs, and every length of the "
             "scene is metres (a voxel of 1 mm is 0.001)",
             scene->voxel_size);
}

void prep_units_hint_box(double extent, char *out, size_t size) {
  out[0] = 0;
  if (extent > BODY_SIZE)
    snprintf(out, size,
             "; the box is larger than a body (%g m): check the units, every length of the scene is metres "
             "(voxel_size, max_gap, spacings, motions; the meshes by their \"units\")",
             BODY_SIZE);
}

static fascia_status warn(fascia_ctx *ctx, fascia_prep_meshes *meshes, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static fascia_status warn(fascia_ctx *ctx, fascia_prep_meshes *meshes, const char *format, ...) {
  char text[1024];
  va_list args;
  va_start(args, format);
  vsnprintf(text, sizeof text, format, args);
  va_end(args);
  char **grown = realloc(meshes->warnings, ((size_t)meshes->warning_count + 1) * sizeof *grown);
  PREP_CHECK(grown, ctx, FASCIA_ERR_MEMORY, "import: out of memory");
  meshes->warnings = grown;
  grown[meshes->warning_count] = prep_strdup(text);
  PREP_CHECK(grown[meshes->warning_count], ctx, FASCIA_ERR_MEMORY, "import: out of memory");
  meshes->warning_count++;
  return FASCIA_OK;
}

// How far the motion carries any point of the box (min xyz, max xyz) at its
// keys: the displacement is affine in the point, so a corner is the farthest.
static double motion_reach(const fascia_motion *mo, const double *bounds) {
  double reach = 0;
  for (int32_t k = 0; k < mo->key_count; ++k) {
    double R[9];
    prep_quat_matrix(mo->key_rotation + 4 * k, R);
    for (int c = 0; c < 8; ++c) {
      double x[3], d2 = 0;
      for (int r = 0; r < 3; ++r) x[r] = ((c >> r) & 1 ? bounds[3 + r] : bounds[r]) - mo->pivot[r];
      for (int r = 0; r < 3; ++r) {
        const double d = mo->key_translation[3 * k + r] + R[3 * r] * x[0] + R[3 * r + 1] * x[1] +
                         R[3 * r + 2] * x[2] - x[r];
        d2 += d * d;
      }
      reach = fmax(reach, sqrt(d2));
    }
  }
  return reach;
}

// The gap tissue t bridges: its max_gap, a strand's span between its
// points, at most a sheet's size.
static double tissue_span(const fascia_prep_scene *scene, const fascia_prep_meshes *meshes, int32_t t) {
  const fascia_prep_tissue_def *td = scene->tissues + t;
  if (td->form != FASCIA_PREP_FORM_SHEET || !meshes->sheets) return td->max_gap;
  const double *b = meshes->sheets[t].bounds;
  double d2 = 0;
  for (int r = 0; r < 3; ++r) d2 += (b[3 + r] - b[r]) * (b[3 + r] - b[r]);
  return sqrt(d2);
}

// A Poisson-disk spacing or max_gap larger than every organ it concerns.
static fascia_status length_warning(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_meshes *meshes,
                                    const char *owner, const char *key, double value, int32_t organ) {
  const double extent = prep_mesh_extent(meshes->organs + organ);
  if (value <= extent) return FASCIA_OK;
  return warn(ctx, meshes,
              "%s (scene '%s' %s): %g m is larger than the organs it concerns (the largest, '%s', is %.3g m across): "
              "the units look wrong; every length of the scene is metres (if %g mm is meant, write %g)",
              owner, scene->path, key, value, scene->organs[organ].name, extent, value, 1e-3 * value);
}

fascia_status prep_check_magnitudes(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_meshes *meshes) {
  char hint[512], owner[FASCIA_NAME_SIZE + 32], key[64];
  double all[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY}, smallest = INFINITY;
  for (int32_t k = 0; k < meshes->count; ++k) {
    const fascia_prep_mesh *m = meshes->organs + k;
    const double *b = m->bounds, extent = prep_mesh_extent(m);
    for (int r = 0; r < 3; ++r) all[r] = fmin(all[r], b[r]), all[3 + r] = fmax(all[3 + r], b[3 + r]);
    smallest = fmin(smallest, extent);
    // an organ of labels comes from segmentation.file, not from a mesh key
    const char *source_key = scene->organs[k].label_count ? "segmentation.file" : "mesh";
    if (extent > BODY_SIZE) {
      prep_units_hint_organ(scene, k, extent, hint, sizeof hint);
      return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                       "organ '%s' (scene '%s' organs[%d] %s '%s'): it is %.3g x %.3g x %.3g m, larger than a body "
                       "(%g m)%s",
                       m->name, scene->path, (int)k, source_key, scene->organs[k].mesh, b[3] - b[0], b[4] - b[1],
                       b[5] - b[2], BODY_SIZE, hint);
    }
    if (extent < ORGAN_SMALLEST) {
      prep_units_hint_organ(scene, k, extent, hint, sizeof hint);
      PREP_TRY(warn(ctx, meshes,
                    "organ '%s' (scene '%s' organs[%d] %s '%s'): it is %.3g x %.3g x %.3g mm, smaller than any "
                    "organ (%g mm)%s",
                    m->name, scene->path, (int)k, source_key, scene->organs[k].mesh, 1e3 * (b[3] - b[0]), 1e3 * (b[4] - b[1]),
                    1e3 * (b[5] - b[2]), 1e3 * ORGAN_SMALLEST, hint));
    }
  }
  // a strand's unspread end on a deformable organ loads one of its frames (reduced.c)
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    const fascia_prep_tissue_def *td = scene->tissues + t;
    for (int e = 0; td->form == FASCIA_PREP_FORM_STRAND && e < 2; ++e) {
      const fascia_prep_attachment *a = e ? &td->to : &td->from;
      const fascia_prep_organ_def *od = scene->organs + a->organ;
      if (a->spread || od->kind != FASCIA_ORGAN_DEFORMABLE || od->shell) continue;
      PREP_TRY(warn(ctx, meshes,
                    "tissue '%s' (scene '%s' tissues[%d].%s): its end on deformable organ '%s' loads one frame of "
                    "the organ, where the organ's strain peaks and which it nearly turns about; spread the end over "
                    "its insertion (\"spread\": true, or a \"region\")",
                    td->name, scene->path, (int)t, e ? "to" : "from", od->name));
    }
  }
  if (scene->voxel_size >= VOXEL_COARSEST) {
    prep_units_hint_voxel(scene, hint, sizeof hint);
    PREP_TRY(warn(ctx, meshes, "scene '%s' voxel_size:%s", scene->path, hint + 1));
  }
  // with organs smaller than any (warned about above) the other lengths may be the ones that are right
  if (smallest < ORGAN_SMALLEST) return FASCIA_OK;
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    const fascia_prep_tissue_def *td = scene->tissues + t;
    int32_t largest = td->organs[0];
    for (int32_t k = 1; k < td->organ_count; ++k)
      if (prep_mesh_extent(meshes->organs + td->organs[k]) > prep_mesh_extent(meshes->organs + largest))
        largest = td->organs[k];
    snprintf(owner, sizeof owner, "tissue '%s'", td->name);
    if (td->form == FASCIA_PREP_FORM_VOLUME) {
      snprintf(key, sizeof key, "tissues[%d].max_gap", (int)t);
      PREP_TRY(length_warning(ctx, scene, meshes, owner, key, td->max_gap, largest));
    }
    if (td->form != FASCIA_PREP_FORM_SHEET) { // a sheet's frames are its mesh's vertices
      snprintf(key, sizeof key, "tissues[%d].frame_spacing", (int)t);
      PREP_TRY(length_warning(ctx, scene, meshes, owner, key, td->frame_spacing, largest));
    }
  }
  double scene_size = 0;
  for (int r = 0; r < 3; ++r) scene_size += (all[3 + r] - all[r]) * (all[3 + r] - all[r]);
  scene_size = sqrt(scene_size);
  for (int32_t k = 0; k < scene->organ_count; ++k) {
    const fascia_prep_organ_def *d = scene->organs + k;
    if (d->kind == FASCIA_ORGAN_DEFORMABLE) {
      snprintf(owner, sizeof owner, "deformable organ '%s'", d->name);
      snprintf(key, sizeof key, "organs[%d].frame_spacing", (int)k);
      PREP_TRY(length_warning(ctx, scene, meshes, owner, key, d->frame_spacing, k));
    }
    if (d->kind != FASCIA_ORGAN_PRESCRIBED) continue;
    const double reach = motion_reach(&d->motion, meshes->organs[k].bounds);
    PREP_CHECK(reach <= scene_size, ctx, FASCIA_ERR_FORMAT,
               "organ '%s' (scene '%s' organs[%d].motion): it moves the organ up to %.3g m, more than the whole scene "
               "is across (%.3g m), tearing every tissue it holds: the units look wrong; the motion's translations "
               "and pivot are metres (3 mm is 0.003)",
               d->name, scene->path, (int)k, reach, scene_size);
    // the widest tissue the organ pulls, whose stretch is the least
    int32_t widest = -1;
    double widest_gap = 0;
    for (int32_t t = 0; t < scene->tissue_count; ++t)
      for (int32_t j = 0; j < scene->tissues[t].organ_count; ++j) {
        const double gap = tissue_span(scene, meshes, t);
        if (scene->tissues[t].organs[j] == k && (widest < 0 || gap > widest_gap)) widest = t, widest_gap = gap;
      }
    if (widest >= 0 && reach > RUN_STRAIN_LIMIT * widest_gap)
      PREP_TRY(warn(ctx, meshes,
                    "organ '%s' (scene '%s' organs[%d].motion): it moves the organ up to %.3g mm, %.0f times the "
                    "max_gap of the widest tissue it pulls ('%s', %.3g mm): the tissue would stretch past a strain of "
                    "%g, where a run stops as diverged; the units look wrong? the motion's translations and pivot are "
                    "metres (3 mm is 0.003)",
                    d->name, scene->path, (int)k, 1e3 * reach, reach / widest_gap, scene->tissues[widest].name,
                    1e3 * widest_gap, RUN_STRAIN_LIMIT));
  }
  return FASCIA_OK;
}
