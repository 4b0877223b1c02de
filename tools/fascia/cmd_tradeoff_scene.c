// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia tradeoff SCENE.json`: speed against accuracy on the user's own
// scene. The scene is prepared at a ladder of resolutions (every tissue's
// frame and sample spacing scaled by a factor, the shape-function kind, the
// voxel size where a finer sample spacing needs it) through the prep stage's
// module, each model is run through the scene's own motion with each solver
// preset, and every row is measured against the finest: each organ's force
// and torque at the end of the run, the tissue's displacement at fixed
// points (carried by each model's own frames and weights), strain
// percentiles, ms per step and memory. Then the Pareto front, a
// recommendation for --budget MS or --error PERCENT, and per tissue what it
// carries: each organ's force split by the tissue whose frames hold it, and
// the change of every organ force when that tissue alone is one rung
// coarser (docs/cli.md, "tradeoff on a scene").
#define _GNU_SOURCE // malloc_trim
#include <cjson/cJSON.h>
#include <dlfcn.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "commands.h"
#include "fascia/fascia.h"
#include "fascia/files.h"
#include "fascia/prep.h"
#include "presets.h"
#include "tradeoff_scene.h"

static const char scene_usage[] =
    "usage: fascia tradeoff SCENE.json [--budget MS | --error PERCENT] [-o MODEL.h5] [--out DIR] [--quick]\n"
    "                       [--ladder F1,F2,..] [--kinds scene,mls,tet] [--presets P1,P2,..] [--steps N]\n"
    "                       [--dt S] [--threads T] [--repeats R] [--no-tissues] [--json] [--no-plot]\n"
    "\n"
    "Prepares the scene at a ladder of resolutions, runs its own motion with each solver preset and\n"
    "measures every row against the finest: each organ's force and torque at the end of the run, the\n"
    "tissue's displacement at fixed points, strain percentiles, ms per step and memory. Prints the\n"
    "rows, the Pareto front (error against ms), a recommendation and what each tissue carries; writes\n"
    "DIR/tradeoff-scene.csv, tradeoff-scene.json, pareto-scene.gp and, with gnuplot, pareto-scene.png.\n"
    "  --budget MS      recommend the most accurate row at most MS ms per step\n"
    "  --error PERCENT  recommend the fastest row whose largest organ-force error is at most PERCENT\n"
    "                   (neither: --error 5); exit 1 when no row meets the target\n"
    "  -o MODEL.h5      write the recommended row's model\n"
    "  --out DIR        output folder (default .; created if absent)\n"
    "  --quick          the ladder 1.4,1, the scene's shape functions, presets default,interactive\n"
    "  --ladder LIST    spacing factors, coarse to fine (default 1.4,1,0.7): every tissue's frame and\n"
    "                   sample spacing times each; the voxel size follows a sample spacing below it\n"
    "  --kinds LIST     shape functions per rung: scene (as the scene says), mls, tet (default: scene\n"
    "                   and the other kind)\n"
    "  --presets LIST   solver settings: default, interactive, balanced, accurate (default: all four)\n"
    "  --steps N --dt S the run: N steps of S s (default dt 0.05 s, steps to 1.5 times the motion's end,\n"
    "                   at least 10)\n"
    "  --threads T      worker threads, 1 to 1024 (default: OpenMP's)\n"
    "  --repeats R      runs per row for its time, the least is kept (default 2)\n"
    "  --no-tissues     leave out the rows that coarsen one tissue at a time, and the row that draws\n"
    "                   the base again with seed + 1 (the discretization's noise)\n"
    "  --backend NAME   cpu (default), cuda, auto or emulated\n"
    "  --json           print the rows as one JSON array on stdout\n"
    "  --no-plot        write the gnuplot script but do not run gnuplot\n";

#define MAX_LADDER 8
#define MAX_PRESETS 4
#define MAX_KINDS 3
#define MAX_PROBES 400
#define COARSEN 1.4         // one rung coarser, for the tissue rows
#define FORCE_FLOOR 0.01    // an organ force is compared against at least this fraction of the largest
#define DEFAULT_ERROR 5.0   // the target when neither --budget nor --error is given
#define LONG_ROW_MS 2000.0  // rows slower than this are not repeated

enum { KIND_SCENE = -1 };

// ------------------------------------------------------------ prep API --
// The prep stage lives in the module fascia-prep.so (prep_module.c): its
// functions are reached through dlsym, so the program starts without it.

typedef struct prep_api {
  fascia_status (*scene_parse)(fascia_ctx *, const char *, const char *, const char *, fascia_prep_scene **);
  void (*scene_destroy)(fascia_prep_scene **);
  fascia_status (*import)(fascia_ctx *, const fascia_prep_scene *, fascia_prep_meshes **);
  fascia_status (*repair)(fascia_ctx *, const fascia_prep_scene *, fascia_prep_meshes *);
  fascia_status (*voxelize)(fascia_ctx *, const fascia_prep_scene *, fascia_prep_meshes *, fascia_prep_volume **);
  fascia_status (*sample)(fascia_ctx *, const fascia_prep_scene *, const fascia_prep_meshes *,
                          const fascia_prep_volume *, fascia_prep_points **);
  fascia_status (*shape_functions)(fascia_ctx *, const fascia_prep_scene *, const fascia_prep_volume *,
                                   const fascia_prep_points *, fascia_prep_weights **);
  fascia_status (*couple)(fascia_ctx *, const fascia_prep_scene *, const fascia_prep_meshes *,
                          const fascia_prep_points *, fascia_prep_coupling **);
  fascia_status (*package)(fascia_ctx *, const fascia_prep_scene *, const fascia_prep_meshes *,
                           const fascia_prep_volume *, const fascia_prep_points *, const fascia_prep_weights *,
                           const fascia_prep_coupling *, const fascia_prep_run_info *, fascia_model **);
  void (*stages_free)(fascia_prep_stages *);
} prep_api;

static int prep_api_load(prep_api *api) {
  void *module = cli_prep_module_open("tradeoff");
  if (!module) return 0;
  static const char *const names[] = {"fascia_prep_scene_parse", "fascia_prep_scene_destroy", "fascia_prep_import",
                                      "fascia_prep_repair",      "fascia_prep_voxelize",      "fascia_prep_sample",
                                      "fascia_prep_shape_functions", "fascia_prep_couple", "fascia_prep_package",
                                      "fascia_prep_stages_free"};
  void **slots[] = {(void **)&api->scene_parse, (void **)&api->scene_destroy, (void **)&api->import,
                    (void **)&api->repair,      (void **)&api->voxelize,      (void **)&api->sample,
                    (void **)&api->shape_functions, (void **)&api->couple, (void **)&api->package,
                    (void **)&api->stages_free};
  for (size_t k = 0; k < sizeof names / sizeof names[0]; ++k)
    if (!(*slots[k] = dlsym(module, names[k]))) {
      fprintf(stderr, "fascia tradeoff: the prep module has no %s: a module of another build; install fascia again\n",
              names[k]);
      return 0;
    }
  return 1;
}

// ------------------------------------------------------------- options --

typedef struct scene_options {
  const char *scene, *out, *model_out, *backend;
  double ladder[MAX_LADDER];
  int ladder_count;
  int kinds[MAX_KINDS], kind_count; ///< KIND_SCENE or FASCIA_PREP_SHAPE_*
  const char *presets[MAX_PRESETS];
  int preset_count;
  double budget, error, dt;
  int steps, threads, repeats, tissues, json, plot, quick;
  int other_kind; ///< kinds left to the default: the second is the kind the scene does not use
} scene_options;

// The positional argument, skipping the values of options that take one.
int cli_tradeoff_scene_wanted(int argc, char **argv) {
  static const char *const valued[] = {"--out", "--repeats", "--threads", "--time", "--backend", "--budget",
                                       "--error", "-o", "--output", "--ladder", "--kinds", "--presets", "--steps",
                                       "--dt", NULL};
  for (int k = 1; k < argc; ++k) {
    if (argv[k][0] != '-' || !argv[k][1]) return 1;
    for (int v = 0; valued[v]; ++v)
      if (!strcmp(argv[k], valued[v])) {
        ++k;
        break;
      }
  }
  return 0;
}

// The items of a comma-separated list, each named once: their count, or -1
// for an empty, too long or repeated item, or more than most items.
static int parse_list(const char *text, char items[][24], int most) {
  int n = 0;
  const char *p = text;
  while (*p) {
    const char *e = strchr(p, ',');
    const size_t len = e ? (size_t)(e - p) : strlen(p);
    if (n == most || len == 0 || len >= 24) return -1;
    memcpy(items[n], p, len);
    items[n][len] = 0;
    for (int j = 0; j < n; ++j)
      if (!strcmp(items[j], items[n])) return -1;
    ++n;
    p += len + (e ? 1 : 0);
    if (e && !*p) return -1;
  }
  return n;
}

static int bad_value(const char *option, const char *value, const char *expected) {
  fprintf(stderr, "fascia tradeoff: bad value '%s' for %s: expected %s (see fascia tradeoff SCENE.json --help)\n",
          value, option, expected);
  return 2;
}

static int parse_ladder(const char *v, scene_options *o) {
  char items[MAX_LADDER][24];
  const int n = parse_list(v, items, MAX_LADDER);
  if (n < 1) return 0;
  for (int k = 0; k < n; ++k) {
    fascia_real f = 0;
    if (!cli_parse_real(items[k], &f) || !(f >= 0.25 && f <= 4) || (k > 0 && !(f < o->ladder[k - 1]))) return 0;
    o->ladder[k] = f;
  }
  o->ladder_count = n;
  return 1;
}

static int parse_kinds(const char *v, scene_options *o) {
  char items[MAX_KINDS][24];
  const int n = parse_list(v, items, MAX_KINDS);
  if (n < 1) return 0;
  for (int k = 0; k < n; ++k) {
    o->kinds[k] = !strcmp(items[k], "scene") ? KIND_SCENE
                  : !strcmp(items[k], "mls") ? FASCIA_PREP_SHAPE_MLS
                  : !strcmp(items[k], "tet") ? FASCIA_PREP_SHAPE_TET
                                             : -2;
    if (o->kinds[k] == -2) return 0;
  }
  o->kind_count = n;
  return 1;
}

static int parse_presets(const char *v, scene_options *o) {
  static char items[MAX_PRESETS][24]; // the names outlive the parse
  const int n = parse_list(v, items, MAX_PRESETS);
  if (n < 1) return 0;
  for (int k = 0; k < n; ++k) {
    fascia_solver_def d = fascia_solver_def_default();
    if (strcmp(items[k], "default") && !cli_preset_apply(items[k], &d)) return 0;
    o->presets[k] = items[k];
  }
  o->preset_count = n;
  return 1;
}

// Returns -1 to go on, else the exit status (reported).
static int parse_scene_options(int argc, char **argv, scene_options *o) {
  memset(o, 0, sizeof *o);
  o->out = ".", o->backend = "cpu", o->repeats = 2, o->tissues = 1, o->plot = 1, o->dt = 0.05;
  int ladder_given = 0, kinds_given = 0, presets_given = 0;
  for (int k = 1; k < argc; ++k) {
    const char *a = argv[k];
    if (cli_help(a, scene_usage, NULL)) return 0;
    if (a[0] != '-' || !a[1]) {
      if (o->scene) return cli_usage_error("tradeoff", "one scene file only, found a second: '%s'", a);
      o->scene = a;
      continue;
    }
    if (!strcmp(a, "--verbose")) continue;
    if (!strcmp(a, "--quick")) o->quick = 1;
    else if (!strcmp(a, "--json")) o->json = 1;
    else if (!strcmp(a, "--no-plot")) o->plot = 0;
    else if (!strcmp(a, "--no-tissues")) o->tissues = 0;
    else {
      static const char *const valued[] = {"--out", "--repeats", "--threads", "--backend", "--budget", "--error", "-o",
                                           "--output", "--ladder", "--kinds", "--presets", "--steps", "--dt", NULL};
      int known = 0;
      for (int j = 0; valued[j]; ++j) known |= !strcmp(a, valued[j]);
      if (!known) return cli_usage_error("tradeoff", "unknown option '%s' for a scene", a);
      if (k + 1 >= argc) return cli_usage_error("tradeoff", "option %s needs a value", a);
      const char *v = argv[++k];
      fascia_real x = 0;
      if (!strcmp(a, "--out")) o->out = v;
      else if (!strcmp(a, "-o") || !strcmp(a, "--output")) o->model_out = v;
      else if (!strcmp(a, "--backend")) {
        if (!cli_parse_backend(v, &o->backend)) return bad_value(a, v, "cpu, cuda, auto or emulated");
      } else if (!strcmp(a, "--budget")) {
        if (!cli_parse_real(v, &x) || !(x > 0)) return bad_value(a, v, "milliseconds per step, a number > 0");
        o->budget = x;
      } else if (!strcmp(a, "--error")) {
        if (!cli_parse_real(v, &x) || !(x > 0)) return bad_value(a, v, "a percentage > 0");
        o->error = x;
      } else if (!strcmp(a, "--dt")) {
        if (!cli_parse_real(v, &x) || !(x > 0 && x <= 10)) return bad_value(a, v, "a time step in s, > 0 and <= 10");
        o->dt = x;
      } else if (!strcmp(a, "--steps")) {
        if (!cli_parse_count(v, &o->steps, 1) || o->steps > 100000) return bad_value(a, v, "a whole number 1 to 100000");
      } else if (!strcmp(a, "--repeats")) {
        if (!cli_parse_count(v, &o->repeats, 1) || o->repeats > 100) return bad_value(a, v, "a whole number 1 to 100");
      } else if (!strcmp(a, "--threads")) {
        if (!cli_parse_threads(v, &o->threads)) return bad_value(a, v, "a whole number from 1 to " CLI_MAX_THREADS_TEXT);
      } else if (!strcmp(a, "--ladder")) {
        if (!parse_ladder(v, o)) return bad_value(a, v, "factors 0.25 to 4 separated by commas, coarse to fine");
        ladder_given = 1;
      } else if (!strcmp(a, "--kinds")) {
        if (!parse_kinds(v, o)) return bad_value(a, v, "scene, mls or tet separated by commas, each once");
        kinds_given = 1;
      } else if (!parse_presets(v, o)) { // --presets
        return bad_value(a, v, "default, interactive, balanced or accurate separated by commas, each once");
      } else {
        presets_given = 1;
      }
    }
  }
  if (!o->scene) return cli_usage_error("tradeoff", "%s", "missing SCENE.json, the scene to measure");
  if (o->budget > 0 && o->error > 0)
    return cli_usage_error("tradeoff", "%s", "--budget and --error exclude each other: give one target");
  if (!ladder_given) {
    static const double full[] = {1.4, 1, 0.7}, quick[] = {1.4, 1};
    o->ladder_count = o->quick ? 2 : 3;
    memcpy(o->ladder, o->quick ? quick : full, (size_t)o->ladder_count * sizeof(double));
  }
  if (!kinds_given) o->kinds[0] = KIND_SCENE, o->kind_count = o->quick ? 1 : 2, o->other_kind = !o->quick;
  if (!presets_given) {
    static const char *const full[] = {"default", "interactive", "balanced", "accurate"};
    o->preset_count = o->quick ? 2 : 4;
    for (int k = 0; k < o->preset_count; ++k) o->presets[k] = full[k];
  }
  return -1;
}

// ---------------------------------------------------------------- rungs --

/// One prepared model: the ladder's factor and kind, or the base with one
/// tissue coarsened.
typedef struct rung {
  double factor;
  int kind;            ///< KIND_SCENE or FASCIA_PREP_SHAPE_*
  int coarse_tissue;   ///< -1, else the tissue one rung coarser than factor
  int seed_offset;     ///< 1: the base with the scene's seed + 1, the draw's noise
  double voxel;        ///< m
  double tissue_volume; ///< m^3, the tissue samples' (a kind that loses tissue shows here)
  fascia_model *model; ///< NULL when it failed
  int32_t *frame_tissue; ///< [frames] the tissue each frame lies in (-1 none)
  int32_t *probe_sample; ///< [probes] the tissue sample nearest each probe, -1 when none is near
  double prep_s;
  char error[768];
} rung;

/// One run of one rung with one solver setting, and what it measured.
typedef struct scene_row {
  int rung;
  const char *preset;
  char label[96];
  // results
  int failed, steps, converged_steps, newton, pareto, recommended, reference;
  char error[768];
  double ms, memory_mb, peak_mb;
  double *force, *torque;        ///< [3 organs] N, N m, end of the run
  double *force_error, *torque_error, *change; ///< [organs] %: against the reference; change: against the base
  double force_error_max, torque_error_max, change_max, extrapolated_error;
  int force_error_organ;
  double *share;                 ///< [organs x tissues] part of each organ's force its tissue holds, % (floored)
  double *displacement;          ///< [3 probes] m, NAN where the model has no tissue there
  double disp[3];                ///< median, 95th percentile, largest error, % of the largest displacement
  int probes_compared;
  double strain[3];              ///< p50, p95, max (volume-weighted, tissue samples)
} scene_row;

typedef struct study {
  scene_options *opt;
  fascia_ctx *ctx;
  prep_api prep;
  cJSON *scene_json;
  char folder[4096];
  const fascia_prep_scene *base; ///< the scene as written
  int organ_count, tissue_count;
  char (*organ_names)[FASCIA_NAME_SIZE];
  char (*tissue_names)[FASCIA_NAME_SIZE];
  rung *rungs;
  int rung_count;
  scene_row *rows;
  int row_count;
  double *probe;   ///< [3 probes] rest points, m
  int probe_count;
  /// Imported and repaired organs per voxel size: the only stages a rung's
  /// spacings and kind leave unchanged (voxelize writes their reports only).
  struct {
    double voxel;
    fascia_prep_stages stages; ///< scene and meshes
  } meshes[MAX_LADDER + 1];
  int mesh_count;
  double started_ms, prep_ms_sum, row_ms_sum;
  int preps_done, rows_done;
} study;

static double now_s(const study *s) { return (cli_now_ms() - s->started_ms) / 1e3; }

// Progress: one line per step of the study, with the time left estimated from
// the mean prep and row times so far.
static void progress(const study *s, const char *what) {
  const int preps_left = s->rung_count - s->preps_done, rows_left = s->row_count - s->rows_done;
  const double prep_mean = s->preps_done ? s->prep_ms_sum / s->preps_done : 0;
  const double row_mean = s->rows_done ? s->row_ms_sum / s->rows_done : 0;
  const long left = lround((preps_left * prep_mean + rows_left * row_mean) / 1e3);
  if (!s->preps_done) fprintf(stderr, "tradeoff %5.1f s: %s; time left: known after the first prep\n", now_s(s), what);
  else fprintf(stderr, "tradeoff %5.1f s: %s; time left ~%ld:%02ld\n", now_s(s), what, left / 60, left % 60);
}

static const char *kind_name(int kind) {
  return kind == KIND_SCENE ? "scene" : kind == FASCIA_PREP_SHAPE_TET ? "tet" : "mls";
}

static void rung_label(const study *s, const rung *r, char *out, size_t size) {
  if (r->seed_offset) snprintf(out, size, "x%g %s, seed+%d", r->factor, kind_name(r->kind), r->seed_offset);
  else if (r->coarse_tissue >= 0)
    snprintf(out, size, "x%g %s, %s x%g", r->factor, kind_name(r->kind), s->tissue_names[r->coarse_tissue],
             r->factor * COARSEN);
  else snprintf(out, size, "x%g %s", r->factor, kind_name(r->kind));
}

static const fascia_prep_tissue_def *base_tissue(const study *s, const char *name) {
  for (int32_t t = 0; t < s->base->tissue_count; ++t)
    if (!strcmp(s->base->tissues[t].name, name)) return s->base->tissues + t;
  return NULL;
}

static void scale_number(cJSON *item, const char *key, double factor) {
  cJSON *v = cJSON_GetObjectItemCaseSensitive(item, key);
  if (cJSON_IsNumber(v)) cJSON_SetNumberValue(v, v->valuedouble * factor);
}

// The scene text of a rung: spacings scaled, kind set, voxel size lowered to
// the finest sample spacing where that falls below it (the scene's rule:
// samples at least a voxel apart). NULL when out of memory.
static char *rung_text(study *s, rung *r) {
  cJSON *root = cJSON_Duplicate(s->scene_json, 1);
  if (!root) return NULL;
  double finest = INFINITY;
  cJSON *tissues = cJSON_GetObjectItemCaseSensitive(root, "tissues"), *t;
  int index = 0;
  cJSON_ArrayForEach(t, tissues) {
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(t, "name");
    const fascia_prep_tissue_def *td = cJSON_IsString(name) ? base_tissue(s, name->valuestring) : NULL;
    int tissue = -1;
    for (int k = 0; td && k < s->tissue_count; ++k)
      if (!strcmp(s->tissue_names[k], td->name)) tissue = k;
    ++index;
    if (!td || td->form == FASCIA_PREP_FORM_SHEET) continue;
    const double f = r->factor * (tissue == r->coarse_tissue ? COARSEN : 1);
    scale_number(t, "frame_spacing", f);
    if (td->form != FASCIA_PREP_FORM_VOLUME) continue;
    scale_number(t, "sample_spacing", f);
    finest = fmin(finest, td->sample_spacing * f);
    if (r->kind == KIND_SCENE) continue;
    cJSON *shape = cJSON_GetObjectItemCaseSensitive(t, "shape_functions");
    if (!shape) shape = cJSON_AddObjectToObject(t, "shape_functions");
    cJSON_DeleteItemFromObjectCaseSensitive(shape, "kind");
    cJSON_AddStringToObject(shape, "kind", kind_name(r->kind));
    if (r->kind == FASCIA_PREP_SHAPE_TET) { // a tetrahedron's weights are its corners': no exact attachment
      cJSON_DeleteItemFromObjectCaseSensitive(shape, "neighbours");
      cJSON_DeleteItemFromObjectCaseSensitive(t, "attachment");
      cJSON_DeleteItemFromObjectCaseSensitive(t, "attachment_layer");
    } else cJSON_DeleteItemFromObjectCaseSensitive(shape, "samples_per_tet");
  }
  cJSON *organs = cJSON_GetObjectItemCaseSensitive(root, "organs"), *o;
  index = 0;
  cJSON_ArrayForEach(o, organs) { // deformable organs' own sampling (absent on the others)
    scale_number(o, "frame_spacing", r->factor);
    const cJSON *sample = cJSON_GetObjectItemCaseSensitive(o, "sample_spacing");
    if (cJSON_IsNumber(sample)) {
      scale_number(o, "sample_spacing", r->factor);
      finest = fmin(finest, sample->valuedouble);
    }
    ++index;
  }
  r->voxel = fmin(s->base->voxel_size, finest);
  if (r->seed_offset) {
    cJSON_DeleteItemFromObjectCaseSensitive(root, "seed");
    cJSON_AddNumberToObject(root, "seed", (double)(s->base->seed + (uint64_t)r->seed_offset));
  }
  cJSON *voxel = cJSON_GetObjectItemCaseSensitive(root, "voxel_size");
  if (cJSON_IsNumber(voxel)) cJSON_SetNumberValue(voxel, r->voxel);
  char *text = cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  return text;
}

// Prepares a rung: every stage of `fascia prep` on its scene text. A failure
// is the rung's (its error kept), not the study's.
static void prepare_rung(study *s, rung *r) {
  const double t0 = cli_now_ms();
  char *text = rung_text(s, r);
  fascia_prep_stages st;
  memset(&st, 0, sizeof st);
  fascia_status status = text ? FASCIA_OK : FASCIA_ERR_MEMORY;
  char tool[64];
  snprintf(tool, sizeof tool, "fascia tradeoff %s", fascia_version());
  char command[256];
  rung_label(s, r, command, sizeof command);
  const fascia_prep_run_info info = {tool, command, 0, NULL, NULL, NULL};
  const prep_api *p = &s->prep;
  if (status == FASCIA_OK) status = p->scene_parse(s->ctx, text, s->opt->scene, s->folder, &st.scene);
  int cached = -1;
  for (int k = 0; status == FASCIA_OK && k < s->mesh_count; ++k)
    if (s->meshes[k].voxel == r->voxel) cached = k;
  if (cached >= 0) {
    st.meshes = s->meshes[cached].stages.meshes;
  } else {
    if (status == FASCIA_OK) status = p->import(s->ctx, st.scene, &st.meshes);
    if (status == FASCIA_OK) status = p->repair(s->ctx, st.scene, st.meshes);
    if (status == FASCIA_OK && s->mesh_count <= MAX_LADDER) { // kept with the scene that made them
      cached = s->mesh_count++;
      s->meshes[cached].voxel = r->voxel;
      s->meshes[cached].stages.meshes = st.meshes;
      status = p->scene_parse(s->ctx, text, s->opt->scene, s->folder, &s->meshes[cached].stages.scene);
    }
  }
  if (status == FASCIA_OK) status = p->voxelize(s->ctx, st.scene, st.meshes, &st.volume);
  if (status == FASCIA_OK) status = p->sample(s->ctx, st.scene, st.meshes, st.volume, &st.points);
  if (status == FASCIA_OK) status = p->shape_functions(s->ctx, st.scene, st.volume, st.points, &st.weights);
  if (status == FASCIA_OK) status = p->couple(s->ctx, st.scene, st.meshes, st.points, &st.coupling);
  if (status == FASCIA_OK)
    status = p->package(s->ctx, st.scene, st.meshes, st.volume, st.points, st.weights, st.coupling, &info, &st.model);
  if (status == FASCIA_OK && (st.model->organ_count != s->organ_count))
    status = fascia_ctx_fail(s->ctx, FASCIA_ERR_INTERNAL, __FILE__, __LINE__, "%d organs, the scene has %d",
                             (int)st.model->organ_count, s->organ_count);
  if (status == FASCIA_OK) {
    const int32_t n = st.model->frame_count;
    r->frame_tissue = malloc(((size_t)n + 1) * sizeof *r->frame_tissue);
    if (!r->frame_tissue) status = FASCIA_ERR_MEMORY;
    for (int32_t i = 0; r->frame_tissue && i < n; ++i)
      r->frame_tissue[i] = i < st.points->frame_count ? st.points->frame_tissue[i] : -1;
  }
  if (status == FASCIA_OK) {
    r->model = st.model, st.model = NULL;
    for (int32_t k = 0; k < r->model->sample_count; ++k) // a volumetric part repeats the volume of others
      if (r->model->sample_organ[k] < 0 &&
          r->model->materials[r->model->sample_material[k]].part != FASCIA_PART_VOLUMETRIC)
        r->tissue_volume += r->model->sample_volume[k];
  }
  else
    snprintf(r->error, sizeof r->error, "%s",
             status == FASCIA_ERR_MEMORY ? "out of memory" : fascia_ctx_message(s->ctx));
  for (char *c = r->error; *c; ++c)
    if (*c == '\n' || *c == '\r') *c = ' ';
  fascia_ctx_clear(s->ctx);
  if (cached >= 0) st.meshes = NULL; // the cache's
  p->stages_free(&st);
  free(text);
  r->prep_s = (cli_now_ms() - t0) / 1e3;
}

// -------------------------------------------------------------- probes --

// The fixed points displacements are compared at: tissue samples of the
// first model prepared, at most MAX_PROBES of them, evenly through its list.
static int choose_probes(study *s, const fascia_model *m) {
  int32_t tissue_samples = 0;
  for (int32_t k = 0; k < m->sample_count; ++k) tissue_samples += m->sample_organ[k] < 0;
  const int32_t stride = tissue_samples > MAX_PROBES ? (tissue_samples + MAX_PROBES - 1) / MAX_PROBES : 1;
  s->probe = malloc(3 * (size_t)MAX_PROBES * sizeof *s->probe);
  if (!s->probe) return 0;
  int32_t seen = 0;
  for (int32_t k = 0; k < m->sample_count && s->probe_count < MAX_PROBES; ++k) {
    if (m->sample_organ[k] >= 0) continue;
    if (seen++ % stride) continue;
    memcpy(s->probe + 3 * s->probe_count++, m->sample_position + 3 * k, 3 * sizeof(double));
  }
  return 1;
}

// Each probe's nearest tissue sample of r's model; none beyond two voxels
// (the probe lies outside this model's tissue).
static int map_probes(const study *s, rung *r) {
  const fascia_model *m = r->model;
  r->probe_sample = malloc(((size_t)s->probe_count + 1) * sizeof *r->probe_sample);
  if (!r->probe_sample) return 0;
  const double reach = 2 * r->voxel;
  for (int p = 0; p < s->probe_count; ++p) {
    double best = reach * reach;
    r->probe_sample[p] = -1;
    for (int32_t k = 0; k < m->sample_count; ++k) {
      if (m->sample_organ[k] >= 0) continue;
      double d = 0;
      for (int c = 0; c < 3; ++c) d += pow(m->sample_position[3 * k + c] - s->probe[3 * p + c], 2);
      if (d <= best) best = d, r->probe_sample[p] = k;
    }
  }
  return 1;
}

static double norm3(const double *v) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// The largest norm of the organs' vectors (forces or torques), of those with
// ok[o] where ok is not NULL.
static double largest_norm(const double *v, int organs, const int *ok) {
  double largest = 0;
  for (int o = 0; o < organs; ++o)
    if (!ok || ok[o]) largest = fmax(largest, norm3(v + 3 * o));
  return largest;
}

// What an organ's force (or torque) of this norm is compared against: itself,
// or FORCE_FLOOR of the largest where it is smaller (an organ the tissue
// barely holds would otherwise turn round-off into %).
static double floored(double norm, double largest) { return fmax(norm, fmax(FORCE_FLOOR * largest, 1e-300)); }

static void quat_matrix(const double *q, double R[9]) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  R[0] = 1 - 2 * (y * y + z * z), R[1] = 2 * (x * y - w * z), R[2] = 2 * (x * z + w * y);
  R[3] = 2 * (x * y + w * z), R[4] = 1 - 2 * (x * x + z * z), R[5] = 2 * (y * z - w * x);
  R[6] = 2 * (x * z - w * y), R[7] = 2 * (y * z + w * x), R[8] = 1 - 2 * (x * x + y * y);
}

// A probe's displacement as the model carries it: the weights of its nearest
// sample, moved to the probe by their gradients (first order), and the frame
// scheme's map x = sum_i w_i (x_i + R_i R0_i^T (p - X_i)).
static void probe_displacement(const fascia_model *m, const fascia_solver *solver, int32_t sample, const double *p,
                               double *u) {
  const double *x = fascia_solver_frame_positions(solver), *q = fascia_solver_frame_rotations(solver);
  const double *ps = m->sample_position + 3 * sample;
  double out[3] = {0, 0, 0};
  for (int32_t k = m->sample_offsets[sample]; k < m->sample_offsets[sample + 1]; ++k) {
    const int32_t i = m->pair_frame[k];
    double w = m->pair_weight[k];
    for (int c = 0; c < 3; ++c) w += m->pair_gradient[3 * k + c] * (p[c] - ps[c]);
    double R[9], R0[9], d[3], rest[3];
    quat_matrix(q + 4 * i, R);
    quat_matrix(m->frame_rotation + 4 * i, R0);
    for (int c = 0; c < 3; ++c) d[c] = p[c] - m->frame_position[3 * i + c];
    for (int a = 0; a < 3; ++a) rest[a] = R0[a] * d[0] + R0[3 + a] * d[1] + R0[6 + a] * d[2]; // R0^T d
    for (int a = 0; a < 3; ++a)
      out[a] += w * (x[3 * i + a] + R[3 * a] * rest[0] + R[3 * a + 1] * rest[1] + R[3 * a + 2] * rest[2]);
  }
  for (int c = 0; c < 3; ++c) u[c] = out[c] - p[c];
}

// ----------------------------------------------------------------- rows --

static int compare_pairs(const void *a, const void *b) {
  const double x = ((const double *)a)[0], y = ((const double *)b)[0];
  return (x > y) - (x < y);
}

// Volume-weighted 50th and 95th percentiles and the largest strain of the tissue samples.
static int strain_percentiles(const fascia_model *m, const fascia_solver *solver, double out[3]) {
  double *strain = malloc(((size_t)m->sample_count + 1) * sizeof *strain);
  double *pairs = malloc(2 * ((size_t)m->sample_count + 1) * sizeof *pairs);
  if (!strain || !pairs) {
    free(strain), free(pairs);
    return 0;
  }
  fascia_solver_sample_strain(solver, strain, NULL);
  int32_t n = 0;
  double volume = 0;
  for (int32_t k = 0; k < m->sample_count; ++k)
    if (m->sample_organ[k] < 0 && m->materials[m->sample_material[k]].part != FASCIA_PART_VOLUMETRIC)
      pairs[2 * n] = strain[k], pairs[2 * n + 1] = m->sample_volume[k], volume += pairs[2 * n++ + 1];
  qsort(pairs, (size_t)n, 2 * sizeof *pairs, compare_pairs);
  out[0] = out[1] = out[2] = n ? pairs[2 * (n - 1)] : 0;
  double sum = 0;
  int have50 = 0;
  for (int32_t k = 0; k < n; ++k) {
    sum += pairs[2 * k + 1];
    if (!have50 && sum >= 0.5 * volume) out[0] = pairs[2 * k], have50 = 1;
    if (sum >= 0.95 * volume) {
      out[1] = pairs[2 * k];
      break;
    }
  }
  free(strain), free(pairs);
  return 1;
}

// The organs' wrenches, and each organ's force split by the tissue of the
// coupling frames that carry it.
static fascia_status measure_forces(study *s, const rung *r, fascia_solver *solver, scene_row *row) {
  fascia_status st = FASCIA_OK;
  for (int o = 0; o < s->organ_count && st == FASCIA_OK; ++o) {
    st = fascia_solver_organ_wrench(solver, o, row->force + 3 * o, row->torque + 3 * o, NULL);
    const int32_t count = fascia_solver_organ_frame_count(solver, o);
    if (st != FASCIA_OK || count == 0) continue;
    int32_t *frames = malloc((size_t)count * sizeof *frames);
    double *forces = malloc(3 * (size_t)count * sizeof *forces);
    double *part = calloc(3 * ((size_t)s->tissue_count + 1), sizeof *part);
    if (!frames || !forces || !part) st = FASCIA_ERR_MEMORY;
    if (st == FASCIA_OK) st = fascia_solver_organ_frames(solver, o, frames);
    if (st == FASCIA_OK) st = fascia_solver_organ_reaction(solver, o, forces, NULL);
    for (int32_t c = 0; st == FASCIA_OK && c < count; ++c) {
      const int32_t t = r->frame_tissue[frames[c]];
      for (int a = 0; t >= 0 && t < s->tissue_count && a < 3; ++a) part[3 * t + a] += forces[3 * c + a];
    }
    const double *F = row->force + 3 * o, Fn = norm3(F);
    for (int t = 0; st == FASCIA_OK && t < s->tissue_count; ++t)
      row->share[o * s->tissue_count + t] =
          Fn > 0 ? (part[3 * t] * F[0] + part[3 * t + 1] * F[1] + part[3 * t + 2] * F[2]) / Fn : 0;
    free(frames), free(forces), free(part);
  }
  // The parts along each organ's force in % of it, floored as the errors
  // are: a net force near zero (a free rigid organ at rest) would otherwise
  // blow its parts up to 1e12 %.
  const double largest = largest_norm(row->force, s->organ_count, NULL);
  for (int o = 0; st == FASCIA_OK && o < s->organ_count; ++o) {
    const double scale = floored(norm3(row->force + 3 * o), largest);
    for (int t = 0; t < s->tissue_count; ++t) row->share[o * s->tissue_count + t] *= 100 / scale;
  }
  return st;
}

// Runs a row: `repeats` runs of the scene's motion (the least time kept), then
// the measures of the last one's end state. A failed step is the row's error.
static void run_row(study *s, scene_row *row) {
  const scene_options *opt = s->opt;
  const rung *r = s->rungs + row->rung;
  fascia_solver_def def = fascia_solver_def_default();
  if (strcmp(row->preset, "default")) cli_preset_apply(row->preset, &def);
  def.time_step = opt->dt, def.threads = opt->threads, def.backend = opt->backend;
  fascia_solver *solver = NULL;
  fascia_status st = FASCIA_OK;
  row->ms = INFINITY;
  for (int rep = 0; rep < opt->repeats && st == FASCIA_OK; ++rep) {
    fascia_solver_destroy(&solver);
#ifdef __GLIBC__
    if (rep == 0) malloc_trim(0); // freed pages back, so that this row's memory shows as its own
#endif
    const double base_mb = cli_resident_mb();
    st = fascia_solver_create(s->ctx, r->model, &def, &solver);
    if (st == FASCIA_ERR_ARGUMENT && strcmp(def.backend, "cpu")) { // settings the GPU solver refuses
      fascia_ctx_clear(s->ctx);
      def.backend = "cpu";
      st = fascia_solver_create(s->ctx, r->model, &def, &solver);
    }
    double solve_ms = 0;
    int steps = 0, converged = 0, newton = 0;
    for (; st == FASCIA_OK && steps < opt->steps; ++steps) {
      fascia_solve_report rep_;
      const double t0 = cli_now_ms();
      st = fascia_solver_step(solver, &rep_);
      solve_ms += cli_now_ms() - t0;
      if (st == FASCIA_OK) converged += rep_.converged != 0, newton += rep_.newton_iterations;
    }
    if (st != FASCIA_OK) break;
    row->ms = fmin(row->ms, solve_ms / steps);
    row->steps = steps, row->converged_steps = converged, row->newton = newton;
    if (rep == 0) row->memory_mb = cli_resident_mb() - base_mb, row->peak_mb = cli_peak_mb();
    if (solve_ms > LONG_ROW_MS) break;
  }
  if (st == FASCIA_OK) st = measure_forces(s, r, solver, row);
  if (st == FASCIA_OK && !strain_percentiles(r->model, solver, row->strain)) st = FASCIA_ERR_MEMORY;
  for (int p = 0; st == FASCIA_OK && p < s->probe_count; ++p) {
    double *u = row->displacement + 3 * p;
    if (r->probe_sample && r->probe_sample[p] >= 0)
      probe_displacement(r->model, solver, r->probe_sample[p], s->probe + 3 * p, u);
    else u[0] = u[1] = u[2] = NAN;
  }
  if (st != FASCIA_OK) {
    row->failed = 1;
    snprintf(row->error, sizeof row->error, "%s", st == FASCIA_ERR_MEMORY ? "out of memory" : fascia_ctx_message(s->ctx));
    for (char *c = row->error; *c; ++c)
      if (*c == '\n' || *c == '\r') *c = ' ';
    fascia_ctx_clear(s->ctx);
  }
  fascia_solver_destroy(&solver);
}

// ------------------------------------------------------------ measures --

static double dist3(const double *a, const double *b) {
  const double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  return norm3(d);
}

// Each organ's force (or torque) difference from ref's, in % of ref's,
// floored (floored).
static double wrench_errors(const double *v, const double *ref, int organs, double *out, int *worst) {
  const double largest = largest_norm(ref, organs, NULL);
  double top = 0;
  if (worst) *worst = -1;
  for (int o = 0; o < organs; ++o) {
    out[o] = 100 * dist3(v + 3 * o, ref + 3 * o) / floored(norm3(ref + 3 * o), largest);
    if (worst && (*worst < 0 || out[o] > top)) *worst = o;
    top = fmax(top, out[o]);
  }
  return top;
}

// Displacement errors at the probes both models cover: median, 95th
// percentile and largest, in % of the reference's largest displacement there.
static void displacement_errors(const study *s, scene_row *row, const scene_row *ref) {
  double *e = malloc(((size_t)s->probe_count + 1) * sizeof *e), largest = 0;
  int n = 0;
  for (int p = 0; e && p < s->probe_count; ++p) {
    const double *u = row->displacement + 3 * p, *v = ref->displacement + 3 * p;
    if (!isfinite(u[0]) || !isfinite(v[0])) continue;
    largest = fmax(largest, norm3(v));
    e[n++] = dist3(u, v);
  }
  row->probes_compared = n;
  row->disp[0] = row->disp[1] = row->disp[2] = NAN;
  if (n && largest > 0) {
    qsort(e, (size_t)n, sizeof *e, compare_pairs);
    row->disp[0] = 100 * e[(n - 1) / 2] / largest;
    row->disp[1] = 100 * e[(int)ceil(0.95 * n) - 1] / largest;
    row->disp[2] = 100 * e[n - 1] / largest;
  }
  free(e);
}

void cli_pareto_mark(int count, const double *ms, const double *error, const int *skip, int *pareto) {
  for (int k = 0; k < count; ++k) {
    pareto[k] = !skip[k];
    for (int j = 0; j < count && pareto[k]; ++j)
      if (j != k && !skip[j] && error[j] <= error[k] && ms[j] <= ms[k] && (error[j] < error[k] || ms[j] < ms[k]))
        pareto[k] = 0;
  }
}

static int find_row(const study *s, double factor, int kind, int coarse, const char *preset) {
  for (int k = 0; k < s->row_count; ++k) {
    const rung *r = s->rungs + s->rows[k].rung;
    if (r->factor == factor && r->kind == kind && r->coarse_tissue == coarse && !r->seed_offset &&
        !strcmp(s->rows[k].preset, preset))
      return k;
  }
  return -1;
}

// The row `back` rungs coarser on the ladder than row ref's, of its kind and
// preset, or -1 where there is none or it failed.
static int row_before(const study *s, int ref, int back) {
  const scene_options *o = s->opt;
  if (ref < 0) return -1;
  const rung *rr = s->rungs + s->rows[ref].rung;
  int f = o->ladder_count - 1;
  while (f >= back && o->ladder[f] != rr->factor) --f;
  if (f < back) return -1;
  const int k = find_row(s, o->ladder[f - back], rr->kind, -1, s->rows[ref].preset);
  return k >= 0 && !s->rows[k].failed ? k : -1;
}

// The reference: the finest rung of the first kind with the most accurate
// preset asked for; the next finest when that failed.
static int reference_row(const study *s) {
  const char *order[] = {"accurate", "balanced", "default", "interactive"};
  const char *preset = s->opt->presets[0];
  for (int p = 3; p >= 0; --p)
    for (int k = 0; k < s->opt->preset_count; ++k)
      if (!strcmp(s->opt->presets[k], order[p])) preset = order[p];
  for (int f = s->opt->ladder_count - 1; f >= 0; --f) {
    const int k = find_row(s, s->opt->ladder[f], s->opt->kinds[0], -1, preset);
    if (k >= 0 && !s->rows[k].failed) return k;
  }
  for (int k = 0; k < s->row_count; ++k)
    if (!s->rows[k].failed && s->rungs[s->rows[k].rung].coarse_tissue < 0 && !s->rungs[s->rows[k].rung].seed_offset)
      return k;
  return -1;
}

// The base the tissue rows are compared with: the rung at factor 1 (else the
// ladder's middle) of the first kind, with the first preset.
static double base_factor(const scene_options *opt) {
  for (int f = 0; f < opt->ladder_count; ++f)
    if (opt->ladder[f] == 1) return 1;
  return opt->ladder[opt->ladder_count / 2];
}

/// Richardson extrapolation of each organ's force from the three finest rungs
/// of the reference's kind and preset (ratios r1, r2; order from the
/// differences' ratio). ok[o] is 0 where the differences do not shrink at an
/// order between 0.5 and 6: those organs are not in the asymptotic range.
typedef struct extrapolation {
  int available; ///< three rungs ran
  double *force; ///< [3 organs]
  double *order; ///< [organs]
  int *ok;       ///< [organs]
} extrapolation;

static void extrapolate(const study *s, int ref, extrapolation *x) {
  x->available = 0;
  const int a = row_before(s, ref, 2), b = row_before(s, ref, 1);
  if (a < 0 || b < 0) return;
  const double ratio = sqrt(s->rungs[s->rows[a].rung].factor / s->rungs[s->rows[ref].rung].factor);
  x->available = 1;
  for (int g = 0; g < s->organ_count; ++g) {
    const double *F1 = s->rows[a].force + 3 * g, *F2 = s->rows[b].force + 3 * g, *F3 = s->rows[ref].force + 3 * g;
    const double d1 = dist3(F1, F2), d2 = dist3(F2, F3);
    x->order[g] = d2 > 0 && d1 > 0 ? log(d1 / d2) / log(ratio) : NAN;
    x->ok[g] = x->order[g] >= 0.5 && x->order[g] <= 6;
    for (int c = 0; c < 3; ++c)
      x->force[3 * g + c] = x->ok[g] ? F3[c] + (F3[c] - F2[c]) / (pow(ratio, x->order[g]) - 1) : NAN;
  }
}

static void compute_errors(study *s, int ref, int base, const extrapolation *x) {
  const int organs = s->organ_count;
  for (int k = 0; k < s->row_count; ++k) {
    scene_row *row = s->rows + k;
    row->reference = k == ref;
    if (row->failed || ref < 0) continue;
    const scene_row *R = s->rows + ref;
    row->force_error_max = wrench_errors(row->force, R->force, organs, row->force_error, &row->force_error_organ);
    row->torque_error_max = wrench_errors(row->torque, R->torque, organs, row->torque_error, NULL);
    displacement_errors(s, row, R);
    row->change_max = base >= 0 && !s->rows[base].failed
                          ? wrench_errors(row->force, s->rows[base].force, organs, row->change, NULL)
                          : NAN;
    row->extrapolated_error = NAN;
    if (x->available) { // against the extrapolation, the organs it holds for
      const double largest = largest_norm(x->force, organs, x->ok);
      double top = 0;
      for (int o = 0; o < organs; ++o)
        if (x->ok[o])
          top = fmax(top,
                     100 * dist3(row->force + 3 * o, x->force + 3 * o) / floored(norm3(x->force + 3 * o), largest));
      row->extrapolated_error = largest > 0 ? top : NAN;
    }
  }
}

// The row for the target: --budget: the least error within it; --error (or
// the default): the fastest within it. -1 when none meets it.
static int recommend(const study *s) {
  const double target = s->opt->error > 0 ? s->opt->error : DEFAULT_ERROR;
  int best = -1;
  for (int k = 0; k < s->row_count; ++k) {
    const scene_row *r = s->rows + k;
    if (r->failed || s->rungs[r->rung].seed_offset) continue; // the noise row is the base's model drawn again
    if (s->opt->budget > 0) {
      if (r->ms <= s->opt->budget &&
          (best < 0 || r->force_error_max < s->rows[best].force_error_max ||
           (r->force_error_max == s->rows[best].force_error_max && r->ms < s->rows[best].ms)))
        best = k;
    } else if (r->force_error_max <= target && (best < 0 || r->ms < s->rows[best].ms)) {
      best = k;
    }
  }
  return best;
}

// --------------------------------------------------------------- output --

static void row_label(const study *s, scene_row *row) {
  char r[80];
  rung_label(s, s->rungs + row->rung, r, sizeof r);
  snprintf(row->label, sizeof row->label, "%s, %s", r, row->preset);
}

static cJSON *json_numbers(const double *v, int n) {
  cJSON *a = cJSON_CreateArray();
  for (int k = 0; a && k < n; ++k) cJSON_AddItemToArray(a, cJSON_CreateNumber(v[k]));
  return a;
}

static cJSON *json_row(const study *s, const scene_row *row) {
  const rung *r = s->rungs + row->rung;
  cJSON *o = cJSON_CreateObject();
  cJSON_AddStringToObject(o, "scene", s->opt->scene);
  cJSON_AddStringToObject(o, "label", row->label);
  cJSON_AddStringToObject(o, "group", r->seed_offset ? "seed" : r->coarse_tissue >= 0 ? "tissue" : "ladder");
  cJSON_AddNumberToObject(o, "factor", r->factor);
  cJSON_AddStringToObject(o, "shape_functions", kind_name(r->kind));
  if (r->coarse_tissue >= 0) cJSON_AddStringToObject(o, "coarsened_tissue", s->tissue_names[r->coarse_tissue]);
  else cJSON_AddNullToObject(o, "coarsened_tissue");
  cJSON_AddStringToObject(o, "preset", row->preset);
  cJSON_AddNumberToObject(o, "voxel_size", r->voxel);
  cJSON_AddNumberToObject(o, "frames", r->model ? r->model->frame_count : 0);
  cJSON_AddNumberToObject(o, "samples", r->model ? r->model->sample_count : 0);
  cJSON_AddNumberToObject(o, "tissue_volume", r->tissue_volume);
  cJSON_AddNumberToObject(o, "prep_seconds", r->prep_s);
  cJSON_AddNumberToObject(o, "steps", s->opt->steps);
  cJSON_AddNumberToObject(o, "dt", s->opt->dt);
  if (row->failed) cJSON_AddStringToObject(o, "error", row->error);
  else cJSON_AddNullToObject(o, "error");
  cJSON_AddNumberToObject(o, "converged_steps", row->converged_steps);
  cJSON_AddNumberToObject(o, "newton_total", row->newton);
  cJSON_AddNumberToObject(o, "ms_per_step", row->failed ? NAN : row->ms);
  cJSON_AddNumberToObject(o, "memory_mb", row->memory_mb);
  cJSON_AddNumberToObject(o, "peak_memory_mb", row->peak_mb);
  cJSON_AddBoolToObject(o, "reference", row->reference);
  cJSON_AddNumberToObject(o, "force_error_percent", row->failed ? NAN : row->force_error_max);
  cJSON_AddStringToObject(o, "force_error_organ",
                          !row->failed && row->force_error_organ >= 0 ? s->organ_names[row->force_error_organ] : "");
  cJSON_AddNumberToObject(o, "torque_error_percent", row->failed ? NAN : row->torque_error_max);
  cJSON_AddNumberToObject(o, "force_error_vs_extrapolated_percent", row->extrapolated_error);
  cJSON_AddNumberToObject(o, "force_change_vs_base_percent", row->failed ? NAN : row->change_max);
  cJSON *d = cJSON_AddObjectToObject(o, "displacement_error_percent");
  cJSON_AddNumberToObject(d, "median", row->disp[0]);
  cJSON_AddNumberToObject(d, "p95", row->disp[1]);
  cJSON_AddNumberToObject(d, "max", row->disp[2]);
  cJSON_AddNumberToObject(d, "probes", row->probes_compared);
  cJSON *st = cJSON_AddObjectToObject(o, "strain");
  cJSON_AddNumberToObject(st, "p50", row->strain[0]);
  cJSON_AddNumberToObject(st, "p95", row->strain[1]);
  cJSON_AddNumberToObject(st, "max", row->strain[2]);
  cJSON *organs = cJSON_AddArrayToObject(o, "organs");
  for (int g = 0; !row->failed && g < s->organ_count; ++g) {
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "name", s->organ_names[g]);
    cJSON_AddItemToObject(e, "force", json_numbers(row->force + 3 * g, 3));
    cJSON_AddItemToObject(e, "torque", json_numbers(row->torque + 3 * g, 3));
    cJSON_AddNumberToObject(e, "force_error_percent", row->force_error[g]);
    cJSON_AddNumberToObject(e, "torque_error_percent", row->torque_error[g]);
    cJSON_AddNumberToObject(e, "force_change_vs_base_percent", row->change[g]);
    cJSON *share = cJSON_AddObjectToObject(e, "held_by_tissue_percent");
    for (int t = 0; t < s->tissue_count; ++t)
      cJSON_AddNumberToObject(share, s->tissue_names[t], row->share[g * s->tissue_count + t]);
    cJSON_AddItemToArray(organs, e);
  }
  cJSON_AddBoolToObject(o, "pareto", row->pareto);
  cJSON_AddBoolToObject(o, "recommended", row->recommended);
  return o;
}

static fascia_file *open_out(const study *s, const char *name) { return cli_tradeoff_open(s->ctx, s->opt->out, name); }

static int close_out(const study *s, fascia_file *f) { return cli_tradeoff_commit(s->ctx, f); }

static int write_csv(const study *s) {
  fascia_file *file = open_out(s, "tradeoff-scene.csv");
  if (!file) return 1;
  FILE *f = fascia_file_stream(file);
  fprintf(f, "label,group,factor,shape_functions,coarsened_tissue,preset,voxel_size,frames,samples,tissue_volume,prep_seconds,steps,"
             "converged_steps,ms_per_step,memory_mb,peak_memory_mb,force_error_percent,force_error_organ,"
             "torque_error_percent,force_error_vs_extrapolated_percent,force_change_vs_base_percent,"
             "displacement_median_percent,displacement_p95_percent,displacement_max_percent,strain_p50,strain_p95,"
             "strain_max,pareto,recommended,reference");
  for (int g = 0; g < s->organ_count; ++g) fprintf(f, ",force_%s_N,force_error_%s_percent", s->organ_names[g], s->organ_names[g]);
  fprintf(f, ",error\n");
  for (int k = 0; k < s->row_count; ++k) {
    const scene_row *row = s->rows + k;
    const rung *r = s->rungs + row->rung;
    cli_csv_text(f, row->label);
    fprintf(f, ",%s,%g,%s,%s,%s,%g,%d,%d,%.6g,%.2f,%d,%d,%.4f,%.1f,%.1f,%.4f,%s,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.5g,%.5g,%.5g,%d,%d,%d",
            r->seed_offset ? "seed" : r->coarse_tissue >= 0 ? "tissue" : "ladder", r->factor, kind_name(r->kind),
            r->coarse_tissue >= 0 ? s->tissue_names[r->coarse_tissue] : "", row->preset, r->voxel,
            r->model ? (int)r->model->frame_count : 0, r->model ? (int)r->model->sample_count : 0, r->tissue_volume,
            r->prep_s,
            s->opt->steps, row->converged_steps, row->failed ? NAN : row->ms, row->memory_mb, row->peak_mb,
            row->failed ? NAN : row->force_error_max,
            !row->failed && row->force_error_organ >= 0 ? s->organ_names[row->force_error_organ] : "",
            row->failed ? NAN : row->torque_error_max, row->extrapolated_error, row->failed ? NAN : row->change_max,
            row->disp[0], row->disp[1], row->disp[2], row->strain[0], row->strain[1], row->strain[2], row->pareto,
            row->recommended, row->reference);
    for (int g = 0; g < s->organ_count; ++g)
      fprintf(f, ",%.6g,%.4f", row->failed ? NAN : norm3(row->force + 3 * g), row->failed ? NAN : row->force_error[g]);
    fputc(',', f);
    cli_csv_text(f, row->failed ? row->error : "");
    fputc('\n', f);
  }
  return close_out(s, file);
}

// Points, front and the gnuplot script of error against ms.
static int write_plot(const study *s) {
  cli_tradeoff_point *points = malloc((size_t)(s->row_count > 0 ? s->row_count : 1) * sizeof *points);
  if (!points) {
    fprintf(stderr, "fascia tradeoff: out of memory for %d rows\n", (int)s->row_count);
    return 1;
  }
  int n = 0;
  for (int k = 0; k < s->row_count; ++k) {
    const scene_row *r = s->rows + k;
    if (!r->failed) points[n++] = (cli_tradeoff_point){r->ms, fmax(r->force_error_max, 1e-3), r->label, r->pareto};
  }
  const int rc = cli_tradeoff_write_points(s->ctx, s->opt->out, "points-scene.dat", "front-scene.dat",
                                           "ms_per_step largest_organ_force_error_percent label", points, n);
  free(points);
  fascia_file *gf = rc ? NULL : open_out(s, "pareto-scene.gp");
  if (!gf) return 1;
  FILE *g = fascia_file_stream(gf);
  fprintf(g,
          "# fascia tradeoff %s: largest organ-force error against ms per step (gnuplot pareto-scene.gp)\n"
          "set terminal pngcairo size 1100,700 font ',10'\nset output 'pareto-scene.png'\n"
          "set logscale xy\nset grid\nset key top right\n"
          "set title 'the scene''s own motion, %d steps of %g s; error against the finest row (errors of 0 drawn at "
          "0.001 %%)'\n"
          "set xlabel 'ms per step'\nset ylabel 'largest organ-force error, %% of the finest'\n",
          s->opt->scene, s->opt->steps, s->opt->dt);
  if (s->opt->budget > 0)
    fprintf(g, "set arrow from %g, graph 0 to %g, graph 1 nohead dt 2 lc 'black'\nset label 'budget %g ms' at %g, graph "
               "0.97 offset 0.5,0 font ',8'\n", s->opt->budget, s->opt->budget, s->opt->budget, s->opt->budget);
  const double target = s->opt->error > 0 ? s->opt->error : DEFAULT_ERROR;
  if (!(s->opt->budget > 0))
    fprintf(g, "set arrow from graph 0, first %g to graph 1, first %g nohead dt 3 lc 'black'\n"
             "set label 'error target %g %%' at graph 0.01, first %g offset 0,0.6 font ',8'\n", target, target, target,
          target);
  fprintf(g, "plot 'points-scene.dat' u 1:2 w p pt 7 ps 0.9 t 'rows', \\\n"
             "     'front-scene.dat' u 1:2 w l lw 2 t 'Pareto front', \\\n"
             "     'front-scene.dat' u 1:2:3 w labels left offset 0.5,0.3 font ',7' notitle\n");
  return close_out(s, gf);
}

static void print_rows(const study *s, FILE *out) {
  fprintf(out, "%-44s %6s %6s %8s %8s %7s %8s %-14s %8s %17s %8s %s\n", "row", "frames", "samp", "cm3", "ms/step",
          "mem MB", "F err%", "(organ)", "T err%", "disp med/p95/max%", "strain95", "");
  for (int k = 0; k < s->row_count; ++k) {
    const scene_row *r = s->rows + k;
    const rung *g = s->rungs + r->rung;
    if (r->failed) {
      fprintf(out, "%-44s failed: %s\n", r->label, r->error);
      continue;
    }
    char disp[48];
    snprintf(disp, sizeof disp, "%.1f/%.1f/%.1f", r->disp[0], r->disp[1], r->disp[2]);
    fprintf(out, "%-44s %6d %6d %8.4g %8.2f %7.1f %8.2f %-14s %8.2f %17s %8.3f %s%s%s\n", r->label,
            (int)g->model->frame_count, (int)g->model->sample_count, 1e6 * g->tissue_volume, r->ms, r->memory_mb,
            r->force_error_max,
            r->force_error_organ >= 0 ? s->organ_names[r->force_error_organ] : "", r->torque_error_max, disp,
            r->strain[1], r->reference ? "reference " : "", r->pareto ? "pareto " : "",
            r->recommended ? "RECOMMENDED" : "");
  }
}

// The Pareto front, fastest first.
static void print_front(const study *s, FILE *out) {
  fprintf(out, "\nPareto front (no other row both faster and closer to the finest), fastest first:\n");
  double last = -1;
  for (;;) { // the next fastest front row after `last` ms
    int next = -1;
    for (int k = 0; k < s->row_count; ++k)
      if (s->rows[k].pareto && s->rows[k].ms > last && (next < 0 || s->rows[k].ms < s->rows[next].ms)) next = k;
    if (next < 0) break;
    fprintf(out, "  %8.2f ms/step  %8.2f %%  %s\n", s->rows[next].ms, s->rows[next].force_error_max, s->rows[next].label);
    last = s->rows[next].ms;
  }
}

// What each tissue carries: each organ's force split by tissue (base row),
// and the change of every organ force with that tissue one rung coarser.
static void print_tissues(const study *s, int base, FILE *out) {
  const double target = s->opt->error > 0 ? s->opt->error : DEFAULT_ERROR;
  if (base >= 0 && !s->rows[base].failed) {
    fprintf(out,
            "\neach organ's force held by each tissue (%% of the organ's force, or of 1 %% of the largest where "
            "an organ's is smaller; row %s):\n",
            s->rows[base].label);
    for (int g = 0; g < s->organ_count; ++g) {
      fprintf(out, "  %-16s %8.4g N:", s->organ_names[g], norm3(s->rows[base].force + 3 * g));
      for (int t = 0; t < s->tissue_count; ++t)
        fprintf(out, " %s %.1f%%", s->tissue_names[t], s->rows[base].share[g * s->tissue_count + t]);
      fputc('\n', out);
    }
  }
  double noise = NAN;
  for (int k = 0; k < s->row_count; ++k)
    if (s->rungs[s->rows[k].rung].seed_offset && !s->rows[k].failed) {
      noise = s->rows[k].change_max;
      fprintf(out, "the base drawn again (seed + 1): organ forces change by up to %.2f %% (", noise);
      for (int o = 0; o < s->organ_count; ++o)
        fprintf(out, "%s%s %.2f", o ? ", " : "", s->organ_names[o], s->rows[k].change[o]);
      fprintf(out, "): the discretization's noise at this resolution\n");
    }
  for (int k = 0; k < s->row_count; ++k) {
    const scene_row *r = s->rows + k;
    const rung *g = s->rungs + r->rung;
    if (g->coarse_tissue < 0) continue;
    if (r->failed || base < 0 || s->rows[base].failed) {
      fprintf(out, "tissue %s one rung coarser: %s\n", s->tissue_names[g->coarse_tissue],
              r->failed ? r->error : "no base row to compare with");
      continue;
    }
    fprintf(out, "tissue %s one rung coarser (x%g): organ forces change by at most %.2f %% (", s->tissue_names[g->coarse_tissue],
            g->factor * COARSEN, r->change_max);
    for (int o = 0; o < s->organ_count; ++o) fprintf(out, "%s%s %.2f", o ? ", " : "", s->organ_names[o], r->change[o]);
    fprintf(out, "): %s\n", r->change_max <= target ? "it could be coarser (within the error target)"
                            : r->change_max <= noise
                                ? "beyond the error target but within the draw's noise: this ladder cannot tell"
                                : "it needs its resolution");
  }
}

// ----------------------------------------------------------------- main --

static const char *const out_names[] = {"tradeoff-scene.csv", "tradeoff-scene.json", "pareto-scene.gp",
                                        "pareto-scene.png", "points-scene.dat", "front-scene.dat", NULL};

// The scene text, parsed as JSON and as a scene (its own checks and messages).
static int load_scene(study *s, fascia_prep_scene **scene) {
  FILE *f = NULL;
  fascia_status st = fascia_file_open_input(s->ctx, "scene", s->opt->scene, &f);
  if (st != FASCIA_OK) return cli_fail("tradeoff", s->ctx, st);
  char *text = NULL;
  size_t size = 0, used = 0;
  for (;;) {
    if (used + 4096 > size) {
      char *grown = realloc(text, size = 2 * size + 8192);
      if (!grown) break;
      text = grown;
    }
    const size_t n = fread(text + used, 1, size - used - 1, f);
    used += n;
    if (n == 0) break;
  }
  fclose(f);
  if (!text) {
    fprintf(stderr, "fascia tradeoff: out of memory reading the scene '%s'\n", s->opt->scene);
    return 1;
  }
  text[used] = 0;
  fascia_path_folder(s->opt->scene, s->folder, sizeof s->folder);
  st = s->prep.scene_parse(s->ctx, text, s->opt->scene, s->folder, scene);
  if (st == FASCIA_OK) s->scene_json = cJSON_Parse(text);
  free(text);
  if (st != FASCIA_OK) return cli_fail("tradeoff", s->ctx, st);
  if (!s->scene_json) {
    fprintf(stderr, "fascia tradeoff: out of memory for the scene '%s'\n", s->opt->scene);
    return 1;
  }
  return -1;
}

// Organs and tissues by name, the second shape kind, the run's steps.
static int learn_scene(study *s, const fascia_prep_scene *sc) {
  scene_options *o = s->opt;
  s->base = sc;
  s->organ_count = sc->organ_count, s->tissue_count = sc->tissue_count;
  s->organ_names = calloc((size_t)sc->organ_count + 1, sizeof *s->organ_names);
  s->tissue_names = calloc((size_t)sc->tissue_count + 1, sizeof *s->tissue_names);
  if (!s->organ_names || !s->tissue_names) return 0;
  for (int k = 0; k < sc->organ_count; ++k) memcpy(s->organ_names[k], sc->organs[k].name, FASCIA_NAME_SIZE);
  for (int k = 0; k < sc->tissue_count; ++k) memcpy(s->tissue_names[k], sc->tissues[k].name, FASCIA_NAME_SIZE);
  if (o->other_kind) {
    int kind = FASCIA_PREP_SHAPE_MLS;
    for (int t = sc->tissue_count - 1; t >= 0; --t)
      if (sc->tissues[t].form == FASCIA_PREP_FORM_VOLUME) kind = sc->tissues[t].shape_kind;
    o->kinds[1] = kind == FASCIA_PREP_SHAPE_TET ? FASCIA_PREP_SHAPE_MLS : FASCIA_PREP_SHAPE_TET;
  }
  if (!o->steps) {
    double end = 0;
    for (int k = 0; k < sc->organ_count; ++k)
      if (sc->organs[k].kind == FASCIA_ORGAN_PRESCRIBED && sc->organs[k].motion.key_count > 0)
        end = fmax(end, sc->organs[k].motion.key_time[sc->organs[k].motion.key_count - 1]);
    o->steps = (int)fmax(10, ceil(1.5 * end / o->dt - 1e-9));
  }
  return 1;
}

// The rungs in the order they are prepared (the base first: its tissue gives
// the probes) and their rows.
static int plan(study *s) {
  const scene_options *o = s->opt;
  const int most = o->ladder_count * o->kind_count + s->tissue_count + 2;
  s->rungs = calloc((size_t)most, sizeof *s->rungs);
  s->rows = calloc((size_t)most * o->preset_count, sizeof *s->rows);
  if (!s->rungs || !s->rows) return 0;
  const double base = base_factor(o);
  s->rungs[s->rung_count++] = (rung){.factor = base, .kind = o->kinds[0], .coarse_tissue = -1};
  for (int f = 0; f < o->ladder_count; ++f)
    for (int k = 0; k < o->kind_count; ++k)
      if (o->ladder[f] != base || k != 0)
        s->rungs[s->rung_count++] = (rung){.factor = o->ladder[f], .kind = o->kinds[k], .coarse_tissue = -1};
  for (int t = 0; o->tissues && t < s->tissue_count; ++t)
    if (s->base->tissues[t].form != FASCIA_PREP_FORM_SHEET)
      s->rungs[s->rung_count++] = (rung){.factor = base, .kind = o->kinds[0], .coarse_tissue = t};
  if (o->tissues) s->rungs[s->rung_count++] = (rung){.factor = base, .kind = o->kinds[0], .coarse_tissue = -1, .seed_offset = 1};
  const size_t per_row = 3 * (size_t)s->organ_count * 2 + 3 * (size_t)s->organ_count +
                         (size_t)s->organ_count * s->tissue_count + 3 * MAX_PROBES + 1;
  for (int r = 0; r < s->rung_count; ++r)
    for (int p = 0; p < (s->rungs[r].coarse_tissue >= 0 || s->rungs[r].seed_offset ? 1 : o->preset_count); ++p) {
      scene_row *row = s->rows + s->row_count++;
      row->rung = r, row->preset = o->presets[p];
      double *block = calloc(per_row, sizeof *block);
      if (!block) return 0;
      row->force = block, row->torque = block + 3 * s->organ_count;
      row->force_error = block + 6 * s->organ_count, row->torque_error = row->force_error + s->organ_count;
      row->change = row->torque_error + s->organ_count, row->share = row->change + s->organ_count;
      row->displacement = row->share + s->organ_count * s->tissue_count;
      row_label(s, row);
    }
  return 1;
}

// Prepares every rung and runs its rows, with progress.
static void measure(study *s) {
  char line[1024];
  int next_row = 0;
  for (int r = 0; r < s->rung_count; ++r) {
    rung *g = s->rungs + r;
    char label[96];
    rung_label(s, g, label, sizeof label);
    snprintf(line, sizeof line, "preparing %d/%d: %s", r + 1, s->rung_count, label);
    progress(s, line);
    prepare_rung(s, g);
    s->preps_done++, s->prep_ms_sum += 1e3 * g->prep_s;
    if (g->model && !s->probe && !choose_probes(s, g->model)) snprintf(g->error, sizeof g->error, "out of memory");
    if (g->model && s->probe && !map_probes(s, g)) snprintf(g->error, sizeof g->error, "out of memory");
    if (g->model)
      snprintf(line, sizeof line, "prepared %s: %d frames, %d samples, voxel %.3g mm, %.1f s", label,
               (int)g->model->frame_count, (int)g->model->sample_count, 1e3 * g->voxel, g->prep_s);
    else snprintf(line, sizeof line, "%s failed to prepare: %s", label, g->error);
    progress(s, line);
    for (; next_row < s->row_count && s->rows[next_row].rung == r; ++next_row) {
      scene_row *row = s->rows + next_row;
      const double t0 = cli_now_ms();
      if (!g->model) {
        row->failed = 1;
        snprintf(row->error, sizeof row->error, "prep: %.700s", g->error[0] ? g->error : "failed");
      } else {
        run_row(s, row);
      }
      s->rows_done++, s->row_ms_sum += cli_now_ms() - t0;
      if (row->failed) snprintf(line, sizeof line, "row %d/%d %s: failed: %.600s", next_row + 1, s->row_count, row->label, row->error);
      else
        snprintf(line, sizeof line, "row %d/%d %s: %.3g ms/step, %d/%d steps converged", next_row + 1, s->row_count,
                 row->label, row->ms, row->converged_steps, row->steps);
      if (g->model) progress(s, line);
    }
  }
}

// The rows in the order the tables show them: the ladder coarse to fine, by
// kind and preset as asked, then the tissue rows.
static void sort_rows(study *s) {
  const scene_options *o = s->opt;
  int *key = malloc(((size_t)s->row_count + 1) * sizeof *key);
  if (!key) return; // the order prepared in, then
  for (int k = 0; k < s->row_count; ++k) {
    const rung *r = s->rungs + s->rows[k].rung;
    int f = 0, kind = 0, preset = 0;
    while (f < o->ladder_count - 1 && o->ladder[f] != r->factor) ++f;
    while (kind < o->kind_count - 1 && o->kinds[kind] != r->kind) ++kind;
    while (preset < o->preset_count - 1 && strcmp(o->presets[preset], s->rows[k].preset)) ++preset;
    key[k] = r->seed_offset      ? 2000000
             : r->coarse_tissue >= 0 ? 1000000 + r->coarse_tissue
                                     : (f * MAX_KINDS + kind) * MAX_PRESETS + preset;
  }
  for (int a = 1; a < s->row_count; ++a)
    for (int b = a; b > 0 && key[b] < key[b - 1]; --b) {
      const scene_row t = s->rows[b];
      const int kt = key[b];
      s->rows[b] = s->rows[b - 1], key[b] = key[b - 1];
      s->rows[b - 1] = t, key[b - 1] = kt;
    }
  free(key);
}

static void study_free(study *s) {
  for (int r = 0; s->rungs && r < s->rung_count; ++r) {
    fascia_model_destroy(&s->rungs[r].model);
    free(s->rungs[r].frame_tissue), free(s->rungs[r].probe_sample);
  }
  for (int k = 0; s->rows && k < s->row_count; ++k) free(s->rows[k].force);
  free(s->rungs), free(s->rows), free(s->probe), free(s->organ_names), free(s->tissue_names);
  cJSON_Delete(s->scene_json);
  for (int k = 0; k < s->mesh_count; ++k) s->prep.stages_free(&s->meshes[k].stages);
}

// Where the finest rung's frames are farther apart than half its tissues'
// layers (their provenance's half_layer_spacing, prep's package.c), its
// organ forces come down slowly with the frames and can look settled before
// they are: which tissues, and the factor that reaches half a layer in all.
static void print_half_layers(const study *s, int ref, FILE *out) {
  const rung *r = s->rungs + s->rows[ref].rung;
  cJSON *prov = r->model && r->model->provenance ? cJSON_Parse(r->model->provenance) : NULL;
  const cJSON *e;
  double reach = INFINITY;
  int printed = 0;
  cJSON_ArrayForEach(e, cJSON_GetObjectItem(cJSON_GetObjectItem(prov, "parameters"), "tissues")) {
    const double half = cJSON_GetNumberValue(cJSON_GetObjectItem(e, "half_layer_spacing"));
    const double spacing = cJSON_GetNumberValue(cJSON_GetObjectItem(e, "frame_spacing"));
    if (!(half > 0 && spacing > half)) continue;
    fprintf(out, "%s%s (frames %.3g mm apart, half a layer %.3g mm)",
            printed++ ? ", " : "\nthe finest rung's frames are farther apart than half the layers of its tissue ",
            cJSON_GetStringValue(cJSON_GetObjectItem(e, "name")), 1e3 * spacing, 1e3 * half);
    reach = fmin(reach, half / spacing);
  }
  if (printed)
    fprintf(out, ": their organ forces come down slowly as the frames are refined and may move beyond the target at "
                 "finer rungs (docs/mechanics.md, \"Thin layers: held by both faces\"); a rung at x%.2f reaches half "
                 "a layer in every tissue\n",
            floor(100 * r->factor * reach) / 100);
  cJSON_Delete(prov);
}


// The report after the rows: reference, extrapolation, rows, tissues, target.
static int report(study *s, int ref, int base, const extrapolation *x, int best, FILE *out) {
  const scene_options *o = s->opt;
  if (ref < 0) {
    fprintf(stderr, "fascia tradeoff: no row of '%s' ran: every rung failed (see the rows)\n", o->scene);
    print_rows(s, out);
    return 1;
  }
  fprintf(out, "scene %s: %d steps of %g s (its own motion), %d probe points, backend %s\n", o->scene, o->steps, o->dt,
          s->probe_count, o->backend);
  fprintf(out, "errors against the finest row, %s (largest organ-force error: %% of each organ's force, or of %g %% of "
               "the largest where an organ's is smaller)\n",
          s->rows[ref].label, 100 * FORCE_FLOOR);
  if (x->available) {
    fprintf(out, "Richardson extrapolation of the three finest rungs (the finest row's error against it):\n");
    const double largest = largest_norm(x->force, s->organ_count, x->ok);
    for (int g = 0; g < s->organ_count; ++g) {
      if (!x->ok[g]) {
        fprintf(out, "  %-16s not in the asymptotic range (order %.2g): the finest row is the reference\n",
                s->organ_names[g], x->order[g]);
        continue;
      }
      const double *F = x->force + 3 * g, *R = s->rows[ref].force + 3 * g;
      fprintf(out, "  %-16s %.4g N extrapolated (order %.2f), the finest %.4g N: %.2f %%\n", s->organ_names[g],
              norm3(F), x->order[g], norm3(R), 100 * dist3(F, R) / floored(norm3(F), largest));
    }
  } else {
    fprintf(out, "no Richardson extrapolation: it needs three rungs of the reference's kind and preset\n");
  }
  print_rows(s, out);
  print_front(s, out);
  print_tissues(s, base, out);
  const double target = o->error > 0 ? o->error : DEFAULT_ERROR;
  // the rung before the finest: its error against it is how far the finest
  // still moved, below which no row's error can be trusted
  const int coarser = row_before(s, ref, 1);
  if (coarser >= 0 && s->rows[coarser].force_error_max > target) {
    const scene_row *c = s->rows + coarser;
    fprintf(out, "\nthe finest rung has not settled: the rung before it (%s) is %.2f %% from it (%s), more than the "
                 "%g %% target, so every error against it may understate the row's own; add a finer rung "
                 "(--ladder ...,%g) where the time allows\n",
            c->label, c->force_error_max, c->force_error_organ >= 0 ? s->organ_names[c->force_error_organ] : "", target,
            0.7 * s->rungs[s->rows[ref].rung].factor);
  }
  print_half_layers(s, ref, out);
  if (best < 0) {
    if (o->budget > 0) fprintf(stderr, "fascia tradeoff: no row of '%s' runs within --budget %g ms per step\n", o->scene, o->budget);
    else fprintf(stderr, "fascia tradeoff: no row of '%s' is within %g %% of the finest in every organ force\n", o->scene, target);
    return 1;
  }
  const scene_row *b = s->rows + best;
  fprintf(out, "\nrecommended for %s%g%s: %s: %.3g ms/step, largest organ-force error %.2f %% (%s)%s\n",
          o->budget > 0 ? "--budget " : "--error ", o->budget > 0 ? o->budget : target, o->budget > 0 ? " ms" : " %",
          b->label, b->ms, b->force_error_max, b->force_error_organ >= 0 ? s->organ_names[b->force_error_organ] : "",
          b->force_error_max <= 5 ? "" : "; more than 5 % from the finest");
  fprintf(out, "  run it with: fascia run MODEL.h5 --steps %d --dt %g%s%s\n", o->steps, o->dt,
          strcmp(b->preset, "default") ? " --preset " : "", strcmp(b->preset, "default") ? b->preset : "");
  return 0;
}

static int write_outputs(study *s) {
  if (write_csv(s)) return 1;
  cJSON *array = cJSON_CreateArray();
  for (int k = 0; array && k < s->row_count; ++k) cJSON_AddItemToArray(array, json_row(s, s->rows + k));
  char *text = array ? cJSON_Print(array) : NULL;
  fascia_file *file = text ? open_out(s, "tradeoff-scene.json") : NULL;
  int rc = !file;
  if (file) {
    fprintf(fascia_file_stream(file), "%s\n", text);
    rc = close_out(s, file);
  }
  if (!rc && s->opt->json) (void)cli_json_emit(array, 0);
  cJSON_free(text);
  cJSON_Delete(array);
  if (rc) return 1;
  if (write_plot(s)) return 1;
  static const char *const scripts[] = {"pareto-scene.gp", NULL};
  return s->opt->plot ? cli_tradeoff_gnuplot(s->opt->out, scripts) : 0;
}

// The model -o writes must not replace one of the scene's inputs (its
// meshes, its label map). Returns -1 to go on, else the exit status.
static int check_scene_inputs(const scene_options *opt, const fascia_prep_scene *scene) {
  const fascia_prep_segmentation *seg = &scene->segmentation;
  const cli_path paths[3] = {{"segmentation.file", seg->file ? seg->file_path : NULL, CLI_INPUT, NULL, NULL},
                             {"-o", opt->model_out, CLI_OUTPUT_FILE, NULL, NULL},
                             {"scene", opt->scene, CLI_INPUT, NULL, NULL}};
  int rc = cli_check_paths("tradeoff", paths, 3);
  for (int32_t k = 0; rc < 0 && opt->model_out && k < scene->organ_count; ++k) {
    const cli_path mesh[2] = {{"organs[].mesh", scene->organs[k].label_count ? NULL : scene->organs[k].mesh_path,
                               CLI_INPUT, NULL, NULL},
                              {"-o", opt->model_out, CLI_OUTPUT_FILE, NULL, NULL}};
    rc = cli_check_paths("tradeoff", mesh, 2);
  }
  return rc;
}

// The Pareto front over the rows that ran (the seed row left out: it is the
// base's model drawn again).
static void mark_front(study *s) {
  const size_t n = (size_t)s->row_count + 1;
  double *ms = calloc(n, sizeof *ms), *err = calloc(n, sizeof *err);
  int *skip = calloc(n, sizeof *skip), *front = calloc(n, sizeof *front);
  for (int k = 0; ms && err && skip && front && k < s->row_count; ++k)
    ms[k] = s->rows[k].ms, err[k] = s->rows[k].force_error_max,
    skip[k] = s->rows[k].failed || s->rungs[s->rows[k].rung].seed_offset;
  if (ms && err && skip && front) cli_pareto_mark(s->row_count, ms, err, skip, front);
  for (int k = 0; front && k < s->row_count; ++k) s->rows[k].pareto = front[k];
  free(ms), free(err), free(skip), free(front);
}

int cmd_tradeoff_scene(int argc, char **argv) {
  scene_options opt;
  int rc = parse_scene_options(argc, argv, &opt);
  if (rc >= 0) return rc;
  study s;
  memset(&s, 0, sizeof s);
  s.opt = &opt;
  s.started_ms = cli_now_ms();
  const cli_path early[] = {{"scene", opt.scene, CLI_INPUT, NULL, NULL},
                            {"--out", opt.out, CLI_OUTPUT_DIR, out_names, NULL},
                            {"-o", opt.model_out, CLI_OUTPUT_FILE, NULL, NULL}};
  if ((rc = cli_check_paths("tradeoff", early, 3)) >= 0) return rc;
  if (!prep_api_load(&s.prep)) return 1;
  s.ctx = cli_ctx(opt.threads, 0);
  fascia_prep_scene *scene = NULL;
  if ((rc = load_scene(&s, &scene)) >= 0) goto done;
  if ((rc = check_scene_inputs(&opt, scene)) >= 0) goto done;
  rc = 1;
  if (mkdir(opt.out, 0777) != 0 && errno != EEXIST) {
    fprintf(stderr, "fascia tradeoff: cannot create folder '%s': %s\n", opt.out, strerror(errno));
    goto done;
  }
  if (!learn_scene(&s, scene) || !plan(&s)) {
    fprintf(stderr, "fascia tradeoff: out of memory\n");
    goto done;
  }
  measure(&s);
  sort_rows(&s);
  const int ref = reference_row(&s);
  const int base = find_row(&s, base_factor(&opt), opt.kinds[0], -1, opt.presets[0]);
  extrapolation x = {0, calloc(3 * (size_t)s.organ_count + 1, sizeof(double)),
                     calloc((size_t)s.organ_count + 1, sizeof(double)), calloc((size_t)s.organ_count + 1, sizeof(int))};
  if (!x.force || !x.order || !x.ok) {
    fprintf(stderr, "fascia tradeoff: out of memory\n");
    free(x.force), free(x.order), free(x.ok);
    goto done;
  }
  extrapolate(&s, ref, &x);
  compute_errors(&s, ref, base, &x);
  if (ref >= 0) mark_front(&s);
  const int best = ref >= 0 ? recommend(&s) : -1;
  if (best >= 0) s.rows[best].recommended = 1;
  rc = report(&s, ref, base, &x, best, opt.json ? stderr : stdout);
  free(x.force), free(x.order), free(x.ok);
  if (write_outputs(&s)) rc = 1;
  if (best >= 0 && opt.model_out) {
    const fascia_status st = fascia_model_save(s.ctx, s.rungs[s.rows[best].rung].model, opt.model_out);
    if (st != FASCIA_OK) rc = cli_fail("tradeoff", s.ctx, st);
    else fprintf(opt.json ? stderr : stdout, "model of the recommended row: %s\n", opt.model_out);
  }
  fprintf(stderr, "tradeoff: %d rows of %d rungs in %.1f s\n", s.row_count, s.rung_count, now_s(&s));
done:
  if (scene) s.prep.scene_destroy(&scene);
  study_free(&s);
  fascia_ctx_destroy(&s.ctx);
  return rc;
}
