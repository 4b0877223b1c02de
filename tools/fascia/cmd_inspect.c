// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia inspect MODEL.h5 [--json]`: loads (and so validates) a model file
// and summarizes it: frames by kind, samples, neighbours, tissue volume and
// mass, materials, motions, probes, organs with their coupling frames, and
// provenance; as text or as one JSON object on stdout.
#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "fascia/fascia.h"

static const char inspect_usage[] = "usage: fascia inspect MODEL.h5 [--json]\n"
                                    "  loads a model file, checks it and prints a summary\n"
                                    "  --json     print one JSON object on stdout instead of text\n"
                                    "  --verbose  on failure, also print where the error was found\n";

static const char *frame_kind_names[FASCIA_FRAME_KIND_COUNT_] = {"free", "fixed", "prescribed"};
static const char *organ_kind_names[FASCIA_ORGAN_KIND_COUNT_] = {"fixed", "prescribed", "rigid", "deformable"};

/// Figures derived from a model for both outputs.
typedef struct summary {
  int32_t frames_by_kind[FASCIA_FRAME_KIND_COUNT_];
  int32_t neighbours_min, neighbours_max;
  double neighbours_mean, volume, tissue_volume, mass;
  int32_t *coupling_frames; ///< [organ_count] distinct frames shared with each organ
} summary;

static int summarize(const fascia_model *m, summary *out) {
  memset(out, 0, sizeof *out);
  for (int32_t i = 0; i < m->frame_count; ++i) out->frames_by_kind[m->frame_kind[i]]++; // validated on load
  out->neighbours_min = m->sample_count ? INT32_MAX : 0;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    const int32_t n = m->sample_offsets[s + 1] - m->sample_offsets[s];
    if (n < out->neighbours_min) out->neighbours_min = n;
    if (n > out->neighbours_max) out->neighbours_max = n;
  }
  out->neighbours_mean = m->sample_count ? (double)m->pair_count / m->sample_count : 0;
  out->volume = fascia_model_volume(m);
  out->tissue_volume = fascia_model_tissue_volume(m);
  out->mass = fascia_model_mass(m);
  // a frame listed twice for one organ counts once: mark frames per organ
  out->coupling_frames = calloc((size_t)m->organ_count + 1, sizeof(int32_t));
  int32_t *mark = calloc((size_t)m->frame_count + 1, sizeof(int32_t));
  if (!out->coupling_frames || !mark) {
    free(out->coupling_frames);
    free(mark);
    return 0;
  }
  for (int32_t o = 0; o < m->organ_count; ++o)
    for (int32_t c = 0; c < m->coupling_count; ++c)
      if (m->coupling_organ[c] == o && mark[m->coupling_frame[c]] != o + 1) {
        mark[m->coupling_frame[c]] = o + 1;
        out->coupling_frames[o]++;
      }
  free(mark);
  return 1;
}

static void print_provenance_text(const char *text) {
  if (!text) {
    printf("provenance  none\n");
    return;
  }
  cJSON *json = cJSON_Parse(text);
  if (!cJSON_IsObject(json)) {
    // not a JSON object: show its start
    printf("provenance  %.*s%s\n", 160, text, strlen(text) > 160 ? "..." : "");
    cJSON_Delete(json);
    return;
  }
  printf("provenance\n");
  for (const cJSON *item = json->child; item; item = item->next) {
    char *value = cJSON_IsObject(item) || cJSON_IsArray(item) ? NULL : cJSON_PrintUnformatted(item);
    const char *shown = value ? value : cJSON_IsObject(item) ? "{...}" : "[...]";
    printf("  %-14s %.*s%s\n", item->string, 100, shown, strlen(shown) > 100 ? "..." : "");
    free(value);
  }
  cJSON_Delete(json);
}

// Samples whose patch carries enhanced strain modes of the set (0: any).
static int32_t samples_with_modes(const fascia_model *m, int32_t set) {
  int32_t count = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) count += set ? m->sample_modes[s] == set : m->sample_modes[s] != 0;
  return count;
}

static void print_text(const char *path, const fascia_model *m, const summary *z) {
  printf("model       %s\n", path);
  printf("frames      %d (free %d, fixed %d, prescribed %d)\n", (int)m->frame_count, (int)z->frames_by_kind[0],
         (int)z->frames_by_kind[1], (int)z->frames_by_kind[2]);
  printf("samples     %d\n", (int)m->sample_count);
  int32_t patched = 0;
  const int32_t patches = fascia_model_patch_count(m, &patched);
  if (patches > 0)
    printf("patches     %d volumetric patches over %d samples (mean dilatation: %.2f samples per patch)\n",
           (int)patches, (int)patched, (double)patched / patches);
  const int32_t nine = samples_with_modes(m, FASCIA_MODES_NINE), normal = samples_with_modes(m, FASCIA_MODES_NORMAL);
  if (nine > 0) printf("modes       9 enhanced strain modes on the patches of %d samples\n", (int)nine);
  if (normal > 0) printf("modes       3 normal enhanced strain modes on the patches of %d samples\n", (int)normal);
  printf("pairs       %d (neighbours per sample: min %d, mean %.2f, max %d)\n", (int)m->pair_count,
         (int)z->neighbours_min, z->neighbours_mean, (int)z->neighbours_max);
  printf("volume      %.6g m^3 (tissue %.6g m^3, deformable organs %.6g m^3), mass %.6g kg\n", z->volume,
         z->tissue_volume, z->volume - z->tissue_volume, z->mass);
  printf("gravity     (%g, %g, %g) m/s^2\n", m->gravity[0], m->gravity[1], m->gravity[2]);
  printf("materials   %d\n", (int)m->material_count);
  for (int32_t k = 0; k < m->material_count; ++k) {
    const fascia_material *mat = m->materials + k;
    printf("  %-14s %s, E %g Pa, nu %g, density %g kg/m^3, rotation coupling %g\n", mat->name,
           fascia_law_name(mat->law), mat->youngs_modulus, mat->poisson_ratio, mat->density, mat->rotation_coupling);
  }
  printf("motions     %d\n", (int)m->motion_count);
  for (int32_t k = 0; k < m->motion_count; ++k) {
    const fascia_motion *mo = m->motions + k;
    printf("  %-14s %d keys, t = %g .. %g s\n", mo->name, (int)mo->key_count, mo->key_time[0],
           mo->key_time[mo->key_count - 1]);
  }
  if (m->tissue_surface.triangle_count > 0)
    printf("surface     the tissue's, %d vertices, %d triangles (drawn by fascia run --paraview)\n",
           (int)m->tissue_surface.vertex_count, (int)m->tissue_surface.triangle_count);
  printf("probes      %d\n", (int)m->probe_count);
  for (int32_t p = 0; p < m->probe_count; ++p)
    printf("  %-14s (%g, %g, %g) m, %d frames\n", m->probe_name[p], m->probe_position[3 * p],
           m->probe_position[3 * p + 1], m->probe_position[3 * p + 2],
           (int)(m->probe_offsets[p + 1] - m->probe_offsets[p]));
  printf("organs      %d\n", (int)m->organ_count);
  for (int32_t o = 0; o < m->organ_count; ++o) {
    const fascia_organ *organ = m->organs + o;
    printf("  %-14s %s, %d vertices, %d triangles, %d coupling frames\n", organ->name,
           organ_kind_names[organ->kind], (int)organ->vertex_count, (int)organ->triangle_count,
           (int)z->coupling_frames[o]);
  }
  print_provenance_text(m->provenance);
}

// One JSON object; NULL when out of memory. cJSON_Add* on a NULL parent
// returns NULL, so one check at the end covers every step.
static cJSON *make_json(const char *path, const fascia_model *m, const summary *z) {
  cJSON *root = cJSON_CreateObject();
  cJSON_AddStringToObject(root, "file", path);
  cJSON_AddNumberToObject(root, "frames", m->frame_count);
  cJSON *kinds = cJSON_AddObjectToObject(root, "frames_by_kind");
  for (int k = 0; k < FASCIA_FRAME_KIND_COUNT_; ++k)
    cJSON_AddNumberToObject(kinds, frame_kind_names[k], z->frames_by_kind[k]);
  cJSON_AddNumberToObject(root, "samples", m->sample_count);
  int32_t patched = 0;
  cJSON_AddNumberToObject(root, "volumetric_patches", fascia_model_patch_count(m, &patched));
  cJSON_AddNumberToObject(root, "patched_samples", patched);
  cJSON_AddNumberToObject(root, "enhanced_mode_samples", samples_with_modes(m, 0));
  cJSON_AddNumberToObject(root, "normal_mode_samples", samples_with_modes(m, FASCIA_MODES_NORMAL));
  cJSON_AddNumberToObject(root, "pairs", m->pair_count);
  cJSON *neighbours = cJSON_AddObjectToObject(root, "neighbours");
  cJSON_AddNumberToObject(neighbours, "min", z->neighbours_min);
  cJSON_AddNumberToObject(neighbours, "mean", z->neighbours_mean);
  cJSON_AddNumberToObject(neighbours, "max", z->neighbours_max);
  cJSON_AddNumberToObject(root, "tissue_volume", z->tissue_volume);
  cJSON_AddNumberToObject(root, "volume", z->volume);
  cJSON_AddNumberToObject(root, "mass", z->mass);
  cJSON_AddItemToObject(root, "gravity", cJSON_CreateDoubleArray(m->gravity, 3));
  cJSON *materials = cJSON_AddArrayToObject(root, "materials");
  for (int32_t k = 0; k < m->material_count; ++k) {
    const fascia_material *mat = m->materials + k;
    cJSON *item = cJSON_CreateObject();
    cJSON_AddItemToArray(materials, item);
    cJSON_AddStringToObject(item, "name", mat->name);
    cJSON_AddStringToObject(item, "law", fascia_law_name(mat->law));
    cJSON_AddNumberToObject(item, "youngs_modulus", mat->youngs_modulus);
    cJSON_AddNumberToObject(item, "poisson_ratio", mat->poisson_ratio);
    cJSON_AddNumberToObject(item, "density", mat->density);
    cJSON_AddNumberToObject(item, "rotation_coupling", mat->rotation_coupling);
    cJSON_AddNumberToObject(item, "rotation_smoothing", mat->rotation_smoothing);
  }
  cJSON *motions = cJSON_AddArrayToObject(root, "motions");
  for (int32_t k = 0; k < m->motion_count; ++k) cJSON_AddItemToArray(motions, cJSON_CreateString(m->motions[k].name));
  cJSON *surface = cJSON_AddObjectToObject(root, "tissue_surface");
  cJSON_AddNumberToObject(surface, "vertices", m->tissue_surface.vertex_count);
  cJSON_AddNumberToObject(surface, "triangles", m->tissue_surface.triangle_count);
  cJSON *probes = cJSON_AddArrayToObject(root, "probes");
  for (int32_t p = 0; p < m->probe_count; ++p) cJSON_AddItemToArray(probes, cJSON_CreateString(m->probe_name[p]));
  cJSON *organs = cJSON_AddArrayToObject(root, "organs");
  cJSON *coupling = cJSON_AddObjectToObject(root, "coupling");
  for (int32_t o = 0; o < m->organ_count; ++o) {
    const fascia_organ *organ = m->organs + o;
    cJSON *item = cJSON_CreateObject();
    cJSON_AddItemToArray(organs, item);
    cJSON_AddStringToObject(item, "name", organ->name);
    cJSON_AddStringToObject(item, "kind", organ_kind_names[organ->kind]);
    cJSON_AddNumberToObject(item, "vertices", organ->vertex_count);
    cJSON_AddNumberToObject(item, "triangles", organ->triangle_count);
    cJSON_AddNumberToObject(item, "coupling_frames", z->coupling_frames[o]);
    cJSON_AddNumberToObject(coupling, organ->name, z->coupling_frames[o]);
  }
  // provenance: the parsed JSON when it parses, else the text (null if none)
  cJSON *provenance = m->provenance ? cJSON_Parse(m->provenance) : NULL;
  if (!provenance) provenance = m->provenance ? cJSON_CreateString(m->provenance) : cJSON_CreateNull();
  cJSON_AddItemToObject(root, "provenance", provenance);
  if (kinds && neighbours && materials && motions && probes && organs && coupling && provenance) return root;
  cJSON_Delete(root);
  return NULL;
}

int cmd_inspect(int argc, char **argv) {
  const char *path = NULL;
  int json = 0;
  for (int k = 1; k < argc; ++k) {
    if (cli_help(argv[k], inspect_usage, NULL)) return 0;
    if (!strcmp(argv[k], "--verbose")) continue; // read by main
    if (!strcmp(argv[k], "--json")) {
      json = 1;
    } else if (argv[k][0] == '-' && argv[k][1]) {
      fprintf(stderr, "fascia inspect: unknown option '%s' (see fascia inspect --help)\n", argv[k]);
      return 2;
    } else if (path) {
      fprintf(stderr, "fascia inspect: one model file at a time ('%s' and '%s')\n", path, argv[k]);
      return 2;
    } else {
      path = argv[k];
    }
  }
  if (!path) {
    fputs(inspect_usage, stderr);
    return 2;
  }
  const cli_path input = {"model", path, CLI_INPUT, NULL, NULL};
  const int paths_rc = cli_check_paths("inspect", &input, 1);
  if (paths_rc >= 0) return paths_rc;
  fascia_ctx *ctx = cli_ctx(0, 0);
  fascia_model *model = NULL;
  const fascia_status status = fascia_model_load(ctx, path, &model);
  if (status != FASCIA_OK) {
    const int code = cli_fail("inspect", ctx, status);
    fascia_ctx_destroy(&ctx);
    return code;
  }
  summary z;
  int code = 0;
  if (!summarize(model, &z)) {
    fprintf(stderr, "fascia inspect: out of memory\n");
    code = 1;
  } else if (json) {
    cJSON *root = make_json(path, model, &z);
    if (root)
      code = cli_json_emit(root, 0);
    else
      fprintf(stderr, "fascia inspect: out of memory\n"), code = 1;
    cJSON_Delete(root);
  } else {
    print_text(path, model, &z);
  }
  free(z.coupling_frames);
  fascia_model_destroy(&model);
  fascia_ctx_destroy(&ctx);
  return code;
}
