// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The scene file: a strict JSON reader. Every key is known (unknown keys and
// duplicates are errors, so a typo never silently falls back to a default),
// every value is type- and range-checked, and every message names the file
// and the key path ("scene 'a.json' tissues[0].max_gap: ..."). The format is
// documented with examples in data/scenes/README.md.
#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fascia/shape.h"
#include "labels.h"
#include "prep_util.h"
#include "scene_optional.h"
#include "shell.h"

typedef struct reader {
  fascia_ctx *ctx;
  const char *file;
} reader;

#define PATH_SIZE 256
// a scene is a few kB; anything this large is not one
#define MAX_SCENE_BYTES ((int64_t)64 << 20)

static fascia_status key_fail(const reader *rd, const char *path, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static fascia_status key_fail(const reader *rd, const char *path, const char *format, ...) {
  char text[1024];
  va_list args;
  va_start(args, format);
  vsnprintf(text, sizeof text, format, args);
  va_end(args);
  return PREP_FAIL(rd->ctx, FASCIA_ERR_FORMAT, "scene '%s' %s: %s", rd->file, path[0] ? path : "(top level)", text);
}

// out = path.key or path[index], truncated to PATH_SIZE - 1 characters.
static void append(char *out, size_t *n, const char *text) {
  size_t m = strlen(text);
  if (m > PATH_SIZE - 1 - *n) m = PATH_SIZE - 1 - *n;
  memcpy(out + *n, text, m);
  *n += m;
  out[*n] = 0;
}
static void sub_key(char *out, const char *path, const char *key) {
  size_t n = 0;
  out[0] = 0;
  append(out, &n, path);
  if (path[0]) append(out, &n, ".");
  append(out, &n, key);
}
static void sub_index(char *out, const char *path, int index) {
  char text[16];
  snprintf(text, sizeof text, "[%d]", index);
  size_t n = 0;
  out[0] = 0;
  append(out, &n, path);
  append(out, &n, text);
}

static const char *type_name(const cJSON *item) {
  if (!item) return "nothing";
  if (cJSON_IsNumber(item)) return "a number";
  if (cJSON_IsString(item)) return "a string";
  if (cJSON_IsBool(item)) return "a boolean";
  if (cJSON_IsNull(item)) return "null";
  if (cJSON_IsArray(item)) return "an array";
  if (cJSON_IsObject(item)) return "an object";
  return "an invalid value";
}

// Repeated names in a list, in n log n (a hostile file may list many).
typedef struct named {
  const char *name;
  int index;
} named;

static int compare_named(const void *a, const void *b) {
  const named *x = a, *y = b;
  const int c = strcmp(x->name, y->name);
  return c ? c : (x->index > y->index) - (x->index < y->index);
}

// Of n names (file order), the repeated pair *first < *second whose second
// comes earliest: 1 found, 0 none, -1 out of memory.
static int find_repeat(const char *const *names, int n, int *first, int *second) {
  if (n < 2) return 0;
  named *sorted = malloc((size_t)n * sizeof *sorted);
  if (!sorted) return -1;
  for (int k = 0; k < n; ++k) sorted[k].name = names[k], sorted[k].index = k;
  qsort(sorted, (size_t)n, sizeof *sorted, compare_named);
  int found = 0;
  for (int k = 1; k < n; ++k)
    if (!strcmp(sorted[k].name, sorted[k - 1].name) && (k < 2 || strcmp(sorted[k - 2].name, sorted[k].name)) &&
        (!found || sorted[k].index < *second)) {
      *first = sorted[k - 1].index; // the run's first two, in file order
      *second = sorted[k].index;
      found = 1;
    }
  free(sorted);
  return found;
}

// A table whose entries are named (organs, tissues, parts, ...): each name
// once; a repeat names both places, at(k) being entry k's key path.
static fascia_status check_unique(const reader *rd, const char *table, const char *const *names, int n,
                                  void (*at)(char *out, const char *table, int k)) {
  int first, second;
  const int r = find_repeat(names, n, &first, &second);
  PREP_CHECK(r >= 0, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  if (!r) return FASCIA_OK;
  char a[PATH_SIZE], b[PATH_SIZE];
  at(a, table, first);
  at(b, table, second);
  return key_fail(rd, b, "'%s' is given twice (first as %s); each name must be unique here", names[second], a);
}

static void at_index(char *out, const char *table, int k) { sub_index(out, table, k); }
static void at_name(char *out, const char *table, int k) {
  char item[PATH_SIZE];
  sub_index(item, table, k);
  sub_key(out, item, "name");
}

// Every key of obj must be in known (NULL-terminated); that none appears
// twice was checked for every object of the file (check_repeated_keys).
static fascia_status check_keys(const reader *rd, const cJSON *obj, const char *path, const char *const *known) {
  if (!cJSON_IsObject(obj)) return key_fail(rd, path, "expected an object, found %s", type_name(obj));
  const cJSON *item;
  cJSON_ArrayForEach(item, obj) {
    int found = 0;
    for (int k = 0; known[k]; ++k)
      if (!strcmp(item->string, known[k])) found = 1;
    if (!found) {
      char list[512] = "";
      for (int k = 0; known[k]; ++k) {
        strncat(list, known[k], sizeof list - strlen(list) - 1);
        if (known[k + 1]) strncat(list, ", ", sizeof list - strlen(list) - 1);
      }
      char at[PATH_SIZE];
      sub_key(at, path, item->string);
      return key_fail(rd, at, "unknown key (known keys here: %s)", list);
    }
  }
  return FASCIA_OK;
}

// A number > lo (or >= lo when inclusive), < hi; default when absent and not required.
static fascia_status get_number(const reader *rd, const cJSON *obj, const char *path, const char *key, int required,
                                double fallback, double lo, int inclusive, double hi, double *out) {
  char at[PATH_SIZE];
  sub_key(at, path, key);
  const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!item) {
    if (required) return key_fail(rd, at, "missing (a number is required)");
    *out = fallback;
    return FASCIA_OK;
  }
  if (!cJSON_IsNumber(item)) return key_fail(rd, at, "expected a number, found %s", type_name(item));
  const double v = item->valuedouble;
  if (!isfinite(v) || (inclusive ? v < lo : v <= lo) || v >= hi) {
    char upper[48] = "";
    if (isfinite(hi)) snprintf(upper, sizeof upper, " and < %g", hi);
    return key_fail(rd, at, "%g is out of range (expected %s %g%s)", v, inclusive ? ">=" : ">", lo, upper);
  }
  *out = v;
  return FASCIA_OK;
}

static fascia_status get_int(const reader *rd, const cJSON *obj, const char *path, const char *key, int required,
                             int fallback, int lo, int hi, int *out) {
  char at[PATH_SIZE];
  sub_key(at, path, key);
  const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!item) {
    if (required) return key_fail(rd, at, "missing (an integer is required)");
    *out = fallback;
    return FASCIA_OK;
  }
  if (!cJSON_IsNumber(item)) return key_fail(rd, at, "expected an integer, found %s", type_name(item));
  if (item->valuedouble != floor(item->valuedouble))
    return key_fail(rd, at, "expected an integer, found %g", item->valuedouble);
  if (item->valuedouble < lo || item->valuedouble > hi) {
    if (lo == hi) return key_fail(rd, at, "%g is not supported (expected %d)", item->valuedouble, lo);
    return key_fail(rd, at, "%g is out of range (expected %d .. %d)", item->valuedouble, lo, hi);
  }
  *out = (int)item->valuedouble;
  return FASCIA_OK;
}

// A boolean (true or false), fallback when absent.
static fascia_status get_bool(const reader *rd, const cJSON *obj, const char *path, const char *key, int fallback,
                              int *out) {
  char at[PATH_SIZE];
  sub_key(at, path, key);
  const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!item) {
    *out = fallback;
    return FASCIA_OK;
  }
  if (!cJSON_IsBool(item)) return key_fail(rd, at, "expected true or false, found %s", type_name(item));
  *out = cJSON_IsTrue(item);
  return FASCIA_OK;
}

// A string; *out points into the JSON tree (NULL when absent and optional).
static fascia_status get_string(const reader *rd, const cJSON *obj, const char *path, const char *key, int required,
                                const char **out) {
  char at[PATH_SIZE];
  sub_key(at, path, key);
  const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
  *out = NULL;
  if (!item) {
    if (required) return key_fail(rd, at, "missing (a string is required)");
    return FASCIA_OK;
  }
  if (!cJSON_IsString(item) || !item->valuestring)
    return key_fail(rd, at, "expected a string, found %s", type_name(item));
  if (!item->valuestring[0]) return key_fail(rd, at, "is empty");
  *out = item->valuestring;
  return FASCIA_OK;
}

static fascia_status get_name(const reader *rd, const cJSON *obj, const char *path, const char *key, char *out) {
  const char *s;
  PREP_TRY(get_string(rd, obj, path, key, 1, &s));
  char at[PATH_SIZE];
  sub_key(at, path, key);
  if (strlen(s) >= FASCIA_NAME_SIZE)
    return key_fail(rd, at, "'%s' is longer than %d characters", s, FASCIA_NAME_SIZE - 1);
  strcpy(out, s);
  return FASCIA_OK;
}

// An array of n finite numbers.
static fascia_status get_vector(const reader *rd, const cJSON *obj, const char *path, const char *key, int required,
                                int n, double *out) {
  char at[PATH_SIZE];
  sub_key(at, path, key);
  const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
  if (!item) {
    if (required) return key_fail(rd, at, "missing (an array of %d numbers is required)", n);
    return FASCIA_OK;
  }
  if (!cJSON_IsArray(item)) return key_fail(rd, at, "expected an array of %d numbers, found %s", n, type_name(item));
  if (cJSON_GetArraySize(item) != n)
    return key_fail(rd, at, "expected an array of %d numbers, found an array of %d", n, cJSON_GetArraySize(item));
  int k = 0;
  const cJSON *e;
  cJSON_ArrayForEach(e, item) {
    if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble)) {
      char ek[PATH_SIZE];
      sub_index(ek, at, k);
      return key_fail(rd, ek, "expected a finite number, found %s", type_name(e));
    }
    out[k++] = e->valuedouble;
  }
  return FASCIA_OK;
}

// "all" or an array of non-empty strings.
static fascia_status get_parts(const reader *rd, const cJSON *obj, const char *path, const char *key,
                               fascia_prep_parts *out) {
  char at[PATH_SIZE];
  sub_key(at, path, key);
  const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
  out->count = 0;
  out->names = NULL;
  if (!item || (cJSON_IsString(item) && !strcmp(item->valuestring, "all"))) return FASCIA_OK;
  if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) == 0)
    return key_fail(rd, at, "expected \"all\" or a non-empty array of part names, found %s", type_name(item));
  const int n = cJSON_GetArraySize(item);
  out->names = prep_calloc(n, sizeof(char *));
  PREP_CHECK(out->names, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  const cJSON *e;
  cJSON_ArrayForEach(e, item) {
    char ek[PATH_SIZE];
    sub_index(ek, at, out->count);
    if (!cJSON_IsString(e)) return key_fail(rd, ek, "expected a part name (a string), found %s", type_name(e));
    if (!e->valuestring[0]) return key_fail(rd, ek, "is an empty string; give a node or mesh name of the file");
    out->names[out->count] = prep_strdup(e->valuestring);
    PREP_CHECK(out->names[out->count], rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
    out->count++;
  }
  return check_unique(rd, at, (const char *const *)out->names, out->count, at_index);
}

static int organ_index(const fascia_prep_scene *scene, const char *name) {
  for (int32_t k = 0; k < scene->organ_count; ++k)
    if (!strcmp(scene->organs[k].name, name)) return k;
  return -1;
}

static int material_index(const fascia_prep_scene *scene, const char *name) {
  for (int32_t k = 0; k < scene->material_count; ++k)
    if (!strcmp(scene->materials[k].name, name)) return k;
  return -1;
}

static fascia_status need_organ(const reader *rd, const fascia_prep_scene *scene, const char *at, const char *name,
                                int32_t *out) {
  *out = organ_index(scene, name);
  if (*out >= 0) return FASCIA_OK;
  char list[512] = "";
  for (int32_t k = 0; k < scene->organ_count; ++k) {
    strncat(list, scene->organs[k].name, sizeof list - strlen(list) - 1);
    if (k + 1 < scene->organ_count) strncat(list, ", ", sizeof list - strlen(list) - 1);
  }
  return key_fail(rd, at, "no organ is named '%s' (organs: %s)", name, list);
}

// {"box": {"min": [..], "max": [..]}} or {"sphere": {"center": [..], "radius": r}}
static fascia_status get_shape_region(const reader *rd, const cJSON *item, const char *path,
                                      fascia_prep_region *out) {
  memset(out, 0, sizeof *out);
  const cJSON *box = cJSON_GetObjectItemCaseSensitive(item, "box");
  const cJSON *sphere = cJSON_GetObjectItemCaseSensitive(item, "sphere");
  char at[PATH_SIZE];
  if (box && sphere) return key_fail(rd, path, "give either \"box\" or \"sphere\", not both");
  if (box) {
    sub_key(at, path, "box");
    static const char *const known[] = {"min", "max", NULL};
    PREP_TRY(check_keys(rd, box, at, known));
    out->kind = FASCIA_PREP_REGION_BOX;
    PREP_TRY(get_vector(rd, box, at, "min", 1, 3, out->min));
    PREP_TRY(get_vector(rd, box, at, "max", 1, 3, out->max));
    for (int r = 0; r < 3; ++r)
      if (!(out->max[r] > out->min[r]))
        return key_fail(rd, at, "max must exceed min on every axis (axis %d: min %g, max %g)", r, out->min[r],
                        out->max[r]);
  } else if (sphere) {
    sub_key(at, path, "sphere");
    static const char *const known[] = {"center", "radius", NULL};
    PREP_TRY(check_keys(rd, sphere, at, known));
    out->kind = FASCIA_PREP_REGION_SPHERE;
    PREP_TRY(get_vector(rd, sphere, at, "center", 1, 3, out->center));
    PREP_TRY(get_number(rd, sphere, at, "radius", 1, 0, 0, 0, INFINITY, &out->radius));
  }
  return FASCIA_OK;
}

static fascia_status parse_material(const reader *rd, const cJSON *item, const char *path, fascia_material *m) {
  static const char *const known[] = {"law", "youngs_modulus", "poisson_ratio", "density", "rotation_coupling",
                                      "description", NULL};
  PREP_TRY(check_keys(rd, item, path, known));
  if (strlen(item->string) >= FASCIA_NAME_SIZE)
    return key_fail(rd, path, "the material name is longer than %d characters", FASCIA_NAME_SIZE - 1);
  strcpy(m->name, item->string);
  const char *law = NULL, *description = NULL;
  PREP_TRY(get_string(rd, item, path, "description", 0, &description));
  PREP_TRY(get_string(rd, item, path, "law", 0, &law));
  m->law = law ? fascia_law_from_name(law) : FASCIA_LAW_NEOHOOKEAN;
  if (m->law < 0) {
    char at[PATH_SIZE];
    sub_key(at, path, "law");
    return key_fail(rd, at, "unknown law '%s' (known: stvk, neohookean)", law);
  }
  PREP_TRY(get_number(rd, item, path, "youngs_modulus", 1, 0, 0, 0, INFINITY, &m->youngs_modulus));
  PREP_TRY(get_number(rd, item, path, "poisson_ratio", 1, 0, 0, 1, 0.5, &m->poisson_ratio));
  PREP_TRY(get_number(rd, item, path, "density", 0, 1000, 0, 0, INFINITY, &m->density));
  PREP_TRY(get_number(rd, item, path, "rotation_coupling", 0, 0, 0, 1, INFINITY, &m->rotation_coupling));
  return FASCIA_OK;
}

static fascia_status parse_motion(const reader *rd, const cJSON *organ, const char *path, fascia_motion *motion,
                                  const char *organ_name) {
  char at[PATH_SIZE];
  sub_key(at, path, "motion");
  const cJSON *item = cJSON_GetObjectItemCaseSensitive(organ, "motion");
  if (!item) return key_fail(rd, at, "missing: a prescribed organ needs a motion {\"pivot\", \"keys\"}");
  static const char *const known[] = {"pivot", "keys", NULL};
  PREP_TRY(check_keys(rd, item, at, known));
  PREP_TRY(get_vector(rd, item, at, "pivot", 1, 3, motion->pivot));
  char kat[PATH_SIZE];
  sub_key(kat, at, "keys");
  const cJSON *keys = cJSON_GetObjectItemCaseSensitive(item, "keys");
  if (!cJSON_IsArray(keys) || cJSON_GetArraySize(keys) < 1)
    return key_fail(rd, kat, "expected a non-empty array of keys {\"time\", \"translation\", \"rotation\"}, found %s",
                    type_name(keys));
  snprintf(motion->name, FASCIA_NAME_SIZE, "%s", organ_name);
  PREP_TRY(fascia_motion_alloc(rd->ctx, motion, cJSON_GetArraySize(keys)));
  int k = 0;
  const cJSON *key;
  cJSON_ArrayForEach(key, keys) {
    char ek[PATH_SIZE];
    sub_index(ek, kat, k);
    static const char *const known_key[] = {"time", "translation", "rotation", NULL};
    PREP_TRY(check_keys(rd, key, ek, known_key));
    PREP_TRY(get_number(rd, key, ek, "time", 1, 0, 0, 1, INFINITY, &motion->key_time[k]));
    if (k > 0 && !(motion->key_time[k] > motion->key_time[k - 1]))
      return key_fail(rd, ek, "time %g is not after the previous key's %g; key times must increase strictly",
                      motion->key_time[k], motion->key_time[k - 1]);
    PREP_TRY(get_vector(rd, key, ek, "translation", 0, 3, motion->key_translation + 3 * k));
    double *q = motion->key_rotation + 4 * k;
    PREP_TRY(get_vector(rd, key, ek, "rotation", 0, 4, q));
    const double norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(norm > 0.5 && norm < 2))
      return key_fail(rd, ek, "rotation must be a unit quaternion (w, x, y, z); its norm is %g (expected > 0.5 and < "
                      "2; it is then normalised)", norm);
    for (int r = 0; r < 4; ++r) q[r] /= norm;
    ++k;
  }
  return FASCIA_OK;
}

// The sampling keys a tissue and a deformable organ share: frame_spacing,
// sample_spacing, shape_functions {kind, neighbours, samples_per_tet,
// enhanced_modes (default: true for tet with 4 samples per tetrahedron)},
// min_component (default frame_spacing^3).
static fascia_status parse_sampling(const reader *rd, const fascia_prep_scene *scene, const cJSON *item,
                                    const char *path, double *frame_spacing, double *sample_spacing,
                                    int32_t *shape_kind, int32_t *neighbours, int32_t *samples_per_tet,
                                    int32_t *enhanced_modes, double *min_component, double *patch_radius) {
  char at[PATH_SIZE];
  PREP_TRY(get_number(rd, item, path, "frame_spacing", 1, 0, 0, 0, INFINITY, frame_spacing));
  PREP_TRY(get_number(rd, item, path, "sample_spacing", 1, 0, 0, 0, INFINITY, sample_spacing));
  if (*sample_spacing > *frame_spacing) {
    sub_key(at, path, "sample_spacing");
    return key_fail(rd, at, "%g m is coarser than frame_spacing %g m; samples must be at least as fine as frames",
                    *sample_spacing, *frame_spacing);
  }
  // samples finer than the voxels split them (sample.c), down to an eighth of a voxel
  if (*sample_spacing < scene->voxel_size / 8) {
    char hint[512];
    prep_units_hint_voxel(scene, hint, sizeof hint);
    sub_key(at, path, "sample_spacing");
    return key_fail(rd, at, "%g m is finer than an eighth of the voxel size %g m; raise it or lower voxel_size%s",
                    *sample_spacing, scene->voxel_size, hint);
  }
  *shape_kind = FASCIA_PREP_SHAPE_MLS;
  *neighbours = 8;
  *samples_per_tet = 4;
  *enhanced_modes = 0;
  const cJSON *shape = cJSON_GetObjectItemCaseSensitive(item, "shape_functions");
  if (shape) {
    sub_key(at, path, "shape_functions");
    static const char *const known_s[] = {"kind", "neighbours", "samples_per_tet", "enhanced_modes", NULL};
    PREP_TRY(check_keys(rd, shape, at, known_s));
    const char *kind;
    PREP_TRY(get_string(rd, shape, at, "kind", 0, &kind));
    if (kind && !strcmp(kind, "tet"))
      *shape_kind = FASCIA_PREP_SHAPE_TET;
    else if (kind && strcmp(kind, "mls")) {
      char kk[PATH_SIZE];
      sub_key(kk, at, "kind");
      return key_fail(rd, kk, "unknown kind '%s' (known: mls, tet)", kind);
    }
    int count;
    PREP_TRY(get_int(rd, shape, at, "neighbours", 0, 8, 4, 64, &count));
    *neighbours = count;
    PREP_TRY(get_int(rd, shape, at, "samples_per_tet", 0, 4, 1, 4, &count));
    if (count != 1 && count != 4) {
      char kk[PATH_SIZE];
      sub_key(kk, at, "samples_per_tet");
      return key_fail(rd, kk, "%d is not a tetrahedron rule (expected 4: degree 2, or 1: the centroid)", count);
    }
    *samples_per_tet = count;
    int modes = 0;
    // by default on the tetrahedra's degree-2 rule (the centroid rule is soft already)
    PREP_TRY(get_bool(rd, shape, at, "enhanced_modes", *shape_kind == FASCIA_PREP_SHAPE_TET && count == 4, &modes));
    *enhanced_modes = modes;
  }
  const double fs = *frame_spacing;
  PREP_TRY(get_number(rd, item, path, "min_component", 0, fs * fs * fs, 0, 1, INFINITY, min_component));
  PREP_TRY(get_number(rd, item, path, "patch_radius", 0, FASCIA_PREP_PATCH_AUTO, 0, 1, INFINITY, patch_radius));
  if (*patch_radius > 0 && *patch_radius < *sample_spacing) {
    sub_key(at, path, "patch_radius");
    return key_fail(rd, at, "%g m is finer than sample_spacing %g m: a patch of one sample locks like no patch; "
                    "use 0 (no patches) or a radius of about the frame spacing", *patch_radius, *sample_spacing);
  }
  return FASCIA_OK;
}

// name resolved against the scene's folder (an absolute name as it is), malloc'ed.
static char *resolve_path(const char *base_dir, const char *name) {
  const size_t n = strlen(base_dir) + strlen(name) + 2;
  char *out = malloc(n);
  if (!out) return NULL;
  if (name[0] == '/' || !base_dir[0])
    snprintf(out, n, "%s", name);
  else
    snprintf(out, n, "%s/%s", base_dir, name);
  return out;
}

// Adds the labels spec names to *list (sorted, each once): a label value, a
// name of the table, or a pattern over its names ("vertebrae_*").
static fascia_status add_labels(const reader *rd, const fascia_prep_segmentation *seg, const prep_label_table *table,
                                const cJSON *spec, const char *at, int32_t **list, uint8_t **by_name, int32_t *count) {
  int32_t found[4096];
  int32_t n = 0;
  if (cJSON_IsNumber(spec)) {
    const double v = spec->valuedouble;
    if (v != floor(v) || v < 1 || v > PREP_MAX_LABEL)
      return key_fail(rd, at, "%g is not a label (expected an integer 1 .. %d)", v, PREP_MAX_LABEL);
    found[n++] = (int32_t)v;
  } else if (cJSON_IsString(spec) && spec->valuestring[0]) {
    if (!seg->table)
      return key_fail(rd, at, "'%s' is a label name, but the segmentation has no label table (give "
                      "segmentation.labels, or label values)", spec->valuestring);
    n = prep_label_match(table, spec->valuestring, found, (int32_t)(sizeof found / sizeof *found));
    if (n > (int32_t)(sizeof found / sizeof *found)) return key_fail(rd, at, "'%s' matches too many labels", spec->valuestring);
    if (n == 0)
      return key_fail(rd, at, "no label of table '%s' is named '%s'%s", seg->table, spec->valuestring,
                      strpbrk(spec->valuestring, "*?[") ? " (the pattern matches nothing)" : "");
  } else {
    return key_fail(rd, at, "expected a label value, a label name or a pattern, found %s", type_name(spec));
  }
  const uint8_t is_named = !cJSON_IsString(spec) || !strpbrk(spec->valuestring, "*?[");
  int32_t *grown = realloc(*list, (size_t)(*count + n) * sizeof *grown);
  if (grown) *list = grown;
  uint8_t *grown_named = realloc(*by_name, (size_t)(*count + n));
  if (grown_named) *by_name = grown_named;
  PREP_CHECK(grown && grown_named, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  for (int32_t k = 0; k < n; ++k) {
    int32_t at_k = 0;
    while (at_k < *count && grown[at_k] < found[k]) ++at_k;
    if (at_k < *count && grown[at_k] == found[k]) {
      grown_named[at_k] |= is_named;
      continue;
    }
    memmove(grown + at_k + 1, grown + at_k, (size_t)(*count - at_k) * sizeof *grown);
    memmove(grown_named + at_k + 1, grown_named + at_k, (size_t)(*count - at_k));
    grown[at_k] = found[k];
    grown_named[at_k] = is_named;
    ++*count;
  }
  return FASCIA_OK;
}

// One spec or an array of them.
static fascia_status get_labels(const reader *rd, const fascia_prep_segmentation *seg, const prep_label_table *table,
                                const cJSON *item, const char *at, int32_t **list, uint8_t **by_name, int32_t *count) {
  if (!cJSON_IsArray(item)) return add_labels(rd, seg, table, item, at, list, by_name, count);
  if (cJSON_GetArraySize(item) == 0) return key_fail(rd, at, "is empty; name at least one label");
  int k = 0;
  const cJSON *e;
  cJSON_ArrayForEach(e, item) {
    char ek[PATH_SIZE];
    sub_index(ek, at, k++);
    PREP_TRY(add_labels(rd, seg, table, e, ek, list, by_name, count));
  }
  return FASCIA_OK;
}

static void scene_table(const fascia_prep_segmentation *seg, prep_label_table *table) {
  table->count = seg->table_count;
  table->label = seg->table_label;
  table->name = seg->table_name;
}

static fascia_status parse_organ_labels(const reader *rd, fascia_prep_scene *scene, const cJSON *labels,
                                        const char *path, fascia_prep_organ_def *o) {
  char at[PATH_SIZE];
  sub_key(at, path, "labels");
  if (!scene->segmentation.file)
    return key_fail(rd, at, "the organ is made of labels, but the scene has no \"segmentation\"");
  prep_label_table table;
  scene_table(&scene->segmentation, &table);
  PREP_TRY(get_labels(rd, &scene->segmentation, &table, labels, at, &o->labels, &o->label_named, &o->label_count));
  for (int32_t k = 0; k < scene->organ_count - 1; ++k) // the organs parsed before this one
    for (int32_t a = 0; a < scene->organs[k].label_count; ++a)
      for (int32_t b = 0; b < o->label_count; ++b)
        if (scene->organs[k].labels[a] == o->labels[b])
          return key_fail(rd, at, "label %d is already organ '%s''s; a label belongs to one organ", (int)o->labels[b],
                          scene->organs[k].name);
  const fascia_prep_segmentation *seg = &scene->segmentation;
  for (int32_t a = 0; a < seg->connective_count; ++a)
    for (int32_t b = 0; b < o->label_count; ++b)
      if (seg->connective[a] == o->labels[b])
        return key_fail(rd, at, "label %d is declared connective (segmentation.connective); a label is either an "
                        "organ's or space the tissue may take", (int)o->labels[b]);
  return FASCIA_OK;
}

// "segmentation": {"file", "labels", "frame", "smoothing", "interface_layer", "connective"}
static fascia_status parse_segmentation(const reader *rd, fascia_prep_scene *scene, const cJSON *item,
                                        const char *base_dir) {
  static const char *const known[] = {"file",       "labels",      "frame", "smoothing", "interface_layer",
                                      "connective", "description", NULL};
  const char *path = "segmentation";
  PREP_TRY(check_keys(rd, item, path, known));
  fascia_prep_segmentation *seg = &scene->segmentation;
  const char *file, *labels, *frame, *description;
  PREP_TRY(get_string(rd, item, path, "description", 0, &description));
  PREP_TRY(get_string(rd, item, path, "file", 1, &file));
  seg->file = prep_strdup(file);
  seg->file_path = resolve_path(base_dir, file);
  PREP_CHECK(seg->file && seg->file_path, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  char at[PATH_SIZE];
  PREP_TRY(get_string(rd, item, path, "labels", 0, &labels));
  if (labels) {
    seg->table = prep_strdup(labels);
    PREP_CHECK(seg->table, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
    prep_label_table table;
    fascia_status status;
    sub_key(at, path, "labels");
    if (!strncmp(labels, "totalsegmentator:", 17)) {
      status = prep_label_table_builtin(rd->ctx, labels, &table);
    } else {
      char *table_path = resolve_path(base_dir, labels);
      PREP_CHECK(table_path, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
      status = prep_label_table_load(rd->ctx, table_path, &table);
      free(table_path);
    }
    if (status != FASCIA_OK) {
      char reason[768];
      snprintf(reason, sizeof reason, "%s", fascia_ctx_message(rd->ctx));
      return key_fail(rd, at, "%s", reason);
    }
    seg->table_count = table.count;
    seg->table_label = table.label;
    seg->table_name = table.name;
  } else { // a 3D Slicer .seg.nrrd names its segments in its header: that is its table
    prep_label_table table;
    PREP_TRY(prep_segmentation_table(rd->ctx, seg->file_path, &table));
    if (table.count > 0) {
      seg->table = prep_strdup(file);
      seg->table_count = table.count;
      seg->table_label = table.label;
      seg->table_name = table.name;
      PREP_CHECK(seg->table, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
    }
  }
  PREP_TRY(get_string(rd, item, path, "frame", 0, &frame));
  seg->frame = FASCIA_PREP_FRAME_RAS;
  if (frame && !strcmp(frame, "LPS"))
    seg->frame = FASCIA_PREP_FRAME_LPS;
  else if (frame && strcmp(frame, "RAS")) {
    sub_key(at, path, "frame");
    return key_fail(rd, at, "unknown frame '%s' (known: RAS, LPS)", frame);
  }
  int smoothing;
  PREP_TRY(get_int(rd, item, path, "smoothing", 0, 1, 0, 10, &smoothing));
  seg->smoothing = smoothing;
  PREP_TRY(get_number(rd, item, path, "interface_layer", 0, 0, 0, 1, 0.1, &seg->interface_layer));
  const cJSON *connective = cJSON_GetObjectItemCaseSensitive(item, "connective");
  if (connective) {
    prep_label_table table;
    scene_table(seg, &table);
    sub_key(at, path, "connective");
    uint8_t *by_name = NULL; // a connective label the image lacks is no error: a scene may serve many images
    const fascia_status status =
        get_labels(rd, seg, &table, connective, at, &seg->connective, &by_name, &seg->connective_count);
    free(by_name);
    PREP_TRY(status);
  }
  return FASCIA_OK;
}

// "units" and "transform" of a mesh (an organ's or a sheet's): file units
// to metres, then x' = translation + rotation (scale x).
static fascia_status parse_placement(const reader *rd, const cJSON *item, const char *path, double *scale,
                                     char *units_out, size_t units_size, int32_t *units_given, double *transform) {
  const char *units;
  char at[PATH_SIZE];
  PREP_TRY(get_string(rd, item, path, "units", 0, &units));
  snprintf(units_out, units_size, "%s", units ? units : "m");
  *units_given = units != NULL;
  if (!units || !strcmp(units, "m"))
    *scale = 1;
  else if (!strcmp(units, "cm"))
    *scale = 0.01;
  else if (!strcmp(units, "mm"))
    *scale = 0.001;
  else {
    sub_key(at, path, "units");
    return key_fail(rd, at, "unknown units '%s' (known: m, cm, mm)", units);
  }
  for (int r = 0; r < 12; ++r) transform[r] = (r % 4 == r / 4) ? 1 : 0;
  const cJSON *tr = cJSON_GetObjectItemCaseSensitive(item, "transform");
  if (tr) {
    sub_key(at, path, "transform");
    static const char *const known_tr[] = {"translation", "rotation", "scale", NULL};
    PREP_TRY(check_keys(rd, tr, at, known_tr));
    double t[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0}, sc = 1;
    PREP_TRY(get_vector(rd, tr, at, "translation", 0, 3, t));
    PREP_TRY(get_vector(rd, tr, at, "rotation", 0, 4, q));
    PREP_TRY(get_number(rd, tr, at, "scale", 0, 1, 0, 0, INFINITY, &sc));
    const double norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(norm > 0.5 && norm < 2))
      return key_fail(rd, at, "rotation must be a unit quaternion (w, x, y, z); its norm is %g (expected > 0.5 and < "
                      "2; it is then normalised)", norm);
    for (int r = 0; r < 4; ++r) q[r] /= norm;
    double R[9];
    prep_quat_matrix(q, R);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) transform[4 * r + c] = sc * R[3 * r + c];
      transform[4 * r + 3] = t[r];
    }
  }
  return FASCIA_OK;
}

// A shell organ (docs/organs.md, "Shell organs"): its wall's thickness,
// material and frame spacing; the wall gets a material of its own with the
// section's moduli (plane stress, as a sheet's: fascia_shape_section_moduli),
// appended to the scene's materials as "MATERIAL/ORGAN".
static fascia_status parse_shell(const reader *rd, fascia_prep_scene *scene, const cJSON *item, const char *path,
                                 fascia_prep_organ_def *o) {
  char at[PATH_SIZE];
  const char *material;
  PREP_TRY(get_string(rd, item, path, "material", 0, &material));
  sub_key(at, path, "material");
  if (!material) return key_fail(rd, at, "missing: a shell organ needs the material of its wall");
  const int base = material_index(scene, material);
  if (base < 0) return key_fail(rd, at, "no material is named '%s' in \"materials\"", material);
  PREP_TRY(get_number(rd, item, path, "thickness", 1, 0, 0, 0, INFINITY, &o->thickness));
  PREP_TRY(get_number(rd, item, path, "frame_spacing", 1, 0, 0, 0, INFINITY, &o->frame_spacing));
  if (o->thickness >= o->frame_spacing) {
    sub_key(at, path, "thickness");
    return key_fail(rd, at, "%g m is not thinner than frame_spacing %g m: a wall that thick is a volume; make the "
                    "organ \"deformable\", or space its frames wider", o->thickness, o->frame_spacing);
  }
  static const char *const volume_keys[] = {"shape_functions", "min_component", "patch_radius", NULL};
  for (int k = 0; volume_keys[k]; ++k)
    if (cJSON_GetObjectItemCaseSensitive(item, volume_keys[k])) {
      sub_key(at, path, volume_keys[k]);
      return key_fail(rd, at, "a shell's points lie on the triangles of its frames (their weights linear, their "
                      "gradients a quadratic fit over the wall, docs/organs.md); leave %s out", volume_keys[k]);
    }
  // the wall's triangles split into round(frame_spacing / sample_spacing)^2
  PREP_TRY(get_number(rd, item, path, "sample_spacing", 0, o->frame_spacing, 0, 0, INFINITY, &o->sample_spacing));
  if (o->sample_spacing > o->frame_spacing || o->sample_spacing * PREP_SHELL_SPLIT_MAX < o->frame_spacing * (1 - 1e-9)) {
    sub_key(at, path, "sample_spacing");
    return key_fail(rd, at, "%g m is outside [frame_spacing / %d, frame_spacing] = [%g, %g] m", o->sample_spacing,
                    PREP_SHELL_SPLIT_MAX, o->frame_spacing / PREP_SHELL_SPLIT_MAX, o->frame_spacing);
  }
  int q;
  PREP_TRY(get_int(rd, item, path, "section_points", 0, 2, 1, 4, &q));
  o->section_points = q;
  PREP_TRY(get_number(rd, item, path, "pressure", 0, 0, -INFINITY, 0, INFINITY, &o->pressure));
  const cJSON *hold = cJSON_GetObjectItemCaseSensitive(item, "hold");
  if (hold) {
    sub_key(at, path, "hold");
    static const char *const known_h[] = {"box", "sphere", NULL};
    PREP_TRY(check_keys(rd, hold, at, known_h));
    PREP_TRY(get_shape_region(rd, hold, at, &o->hold));
    if (o->hold.kind == FASCIA_PREP_REGION_NONE) return key_fail(rd, at, "give a \"box\" or a \"sphere\"");
  }
  o->shape_kind = FASCIA_PREP_SHAPE_MLS;
  o->neighbours = 3;
  o->patch_radius = 0; // the section is carried by the rotations: nothing locks volumetrically
  fascia_material *wall = scene->materials + scene->material_count;
  *wall = scene->materials[base];
  fascia_shape_section_moduli(2, wall->youngs_modulus, wall->poisson_ratio, &wall->youngs_modulus,
                              &wall->poisson_ratio);
  wall->rotation_smoothing = 0;
  char name[2 * FASCIA_NAME_SIZE + 8];
  snprintf(name, sizeof name, "%s/%s", scene->materials[base].name, o->name);
  snprintf(wall->name, sizeof wall->name, "%.*s", (int)sizeof wall->name - 1, name);
  o->material = scene->material_count++;
  return FASCIA_OK;
}

static fascia_status parse_organ(const reader *rd, fascia_prep_scene *scene, const cJSON *item, const char *path,
                                 const char *base_dir, fascia_prep_organ_def *o) {
  static const char *const known[] = {"name",          "mesh",           "labels",          "parts",
                                      "units",         "transform",      "model",           "motion",
                                      "material",      "frame_spacing",  "sample_spacing",  "shape_functions",
                                      "min_component", "patch_radius",   "description",    "optional",
                                      "thickness",     "section_points", "hold",           "pressure",
                                      NULL};
  PREP_TRY(check_keys(rd, item, path, known));
  PREP_TRY(get_name(rd, item, path, "name", o->name));
  int optional = 0;
  PREP_TRY(get_bool(rd, item, path, "optional", 0, &optional));
  o->optional = optional;
  if (optional && !cJSON_GetObjectItemCaseSensitive(item, "labels")) {
    char ok[PATH_SIZE];
    sub_key(ok, path, "optional");
    return key_fail(rd, ok, "applies to an organ made of labels (a segmentation may lack them); a mesh is given or "
                    "not");
  }
  const char *mesh, *model, *description;
  PREP_TRY(get_string(rd, item, path, "description", 0, &description));
  const cJSON *labels = cJSON_GetObjectItemCaseSensitive(item, "labels");
  PREP_TRY(get_string(rd, item, path, "mesh", !labels, &mesh));
  if (labels) {
    if (mesh) return key_fail(rd, path, "give either \"mesh\" or \"labels\", not both");
    static const char *const mesh_only[] = {"parts", "units", "transform", NULL};
    for (int k = 0; mesh_only[k]; ++k)
      if (cJSON_GetObjectItemCaseSensitive(item, mesh_only[k])) {
        char mk[PATH_SIZE];
        sub_key(mk, path, mesh_only[k]);
        return key_fail(rd, mk, "applies to a mesh; an organ made of labels is placed by the segmentation's affine");
      }
    PREP_TRY(parse_organ_labels(rd, scene, labels, path, o));
    mesh = scene->segmentation.file;
  }
  o->mesh = prep_strdup(mesh);
  o->mesh_path = labels ? prep_strdup(scene->segmentation.file_path) : resolve_path(base_dir, mesh);
  PREP_CHECK(o->mesh && o->mesh_path, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  PREP_TRY(get_parts(rd, item, path, "parts", &o->parts));
  char at[PATH_SIZE];
  PREP_TRY(parse_placement(rd, item, path, &o->scale, o->units, sizeof o->units, &o->units_given, o->transform));
  PREP_TRY(get_string(rd, item, path, "model", 0, &model));
  o->material = -1;
  o->motion.key_count = 0;
  sub_key(at, path, "model");
  if (!model || !strcmp(model, "fixed"))
    o->kind = FASCIA_ORGAN_FIXED;
  else if (!strcmp(model, "prescribed"))
    o->kind = FASCIA_ORGAN_PRESCRIBED;
  else if (!strcmp(model, "rigid"))
    o->kind = FASCIA_ORGAN_RIGID;
  else if (!strcmp(model, "deformable") || !strcmp(model, "shell"))
    o->kind = FASCIA_ORGAN_DEFORMABLE, o->shell = !strcmp(model, "shell");
  else
    return key_fail(rd, at, "unknown model '%s' (known: fixed, prescribed, rigid, deformable, shell)", model);
  if (o->shell) return parse_shell(rd, scene, item, path, o);
  static const char *const shell_keys[] = {"thickness", "section_points", "hold", "pressure", NULL};
  for (int k = 0; shell_keys[k]; ++k)
    if (cJSON_GetObjectItemCaseSensitive(item, shell_keys[k])) {
      sub_key(at, path, shell_keys[k]);
      return key_fail(rd, at, "only a \"shell\" organ (a hollow organ's wall) takes it (this organ's model is \"%s\")",
                      model ? model : "fixed");
    }
  if (o->kind == FASCIA_ORGAN_PRESCRIBED) {
    PREP_TRY(parse_motion(rd, item, path, &o->motion, o->name));
  } else if (cJSON_GetObjectItemCaseSensitive(item, "motion")) {
    sub_key(at, path, "motion");
    return key_fail(rd, at, "only a \"prescribed\" organ takes a motion");
  }
  const char *material;
  PREP_TRY(get_string(rd, item, path, "material", 0, &material));
  sub_key(at, path, "material");
  if (o->kind == FASCIA_ORGAN_DEFORMABLE) {
    if (!material) return key_fail(rd, at, "missing: a deformable organ needs a material");
    o->material = material_index(scene, material);
    if (o->material < 0) return key_fail(rd, at, "no material is named '%s' in \"materials\"", material);
    return parse_sampling(rd, scene, item, path, &o->frame_spacing, &o->sample_spacing, &o->shape_kind,
                          &o->neighbours, &o->samples_per_tet, &o->enhanced_modes, &o->min_component, &o->patch_radius);
  }
  if (material) return key_fail(rd, at, "only a \"deformable\" organ takes a material");
  static const char *const sampling_keys[] = {"frame_spacing", "sample_spacing", "shape_functions", "min_component",
                                              "patch_radius",  NULL};
  for (int k = 0; sampling_keys[k]; ++k)
    if (cJSON_GetObjectItemCaseSensitive(item, sampling_keys[k])) {
      sub_key(at, path, sampling_keys[k]);
      return key_fail(rd, at, "only a \"deformable\" organ is sampled (this organ's model is \"%s\")",
                      model ? model : "fixed");
    }
  return FASCIA_OK;
}

static fascia_status parse_coupling(const reader *rd, const fascia_prep_scene *scene, const cJSON *item,
                                    const char *path, fascia_prep_tissue_def *t) {
  static const char *const known[] = {"tolerance", "organs", "others", NULL};
  PREP_TRY(check_keys(rd, item, path, known));
  PREP_TRY(get_number(rd, item, path, "tolerance", 0, scene->voxel_size, 0, 1, INFINITY, &t->coupling_tolerance));
  int others = 1;
  PREP_TRY(get_bool(rd, item, path, "others", 1, &others));
  t->couple_others = others;
  const cJSON *organs = cJSON_GetObjectItemCaseSensitive(item, "organs");
  if (!organs) return FASCIA_OK;
  char at[PATH_SIZE];
  sub_key(at, path, "organs");
  if (!cJSON_IsObject(organs))
    return key_fail(rd, at, "expected an object {organ name: false or {\"region\", \"parts\"}}, found %s",
                    type_name(organs));
  const int n = cJSON_GetArraySize(organs);
  t->coupling = prep_calloc(n, sizeof *t->coupling);
  PREP_CHECK(t->coupling, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  const cJSON *e;
  cJSON_ArrayForEach(e, organs) {
    char ek[PATH_SIZE];
    sub_key(ek, at, e->string);
    fascia_prep_coupling_def *c = t->coupling + t->coupling_count++;
    PREP_TRY(need_organ(rd, scene, ek, e->string, &c->organ));
    for (int32_t k = 0; k + 1 < t->coupling_count; ++k)
      if (t->coupling[k].organ == c->organ) return key_fail(rd, ek, "the organ appears twice");
    if (cJSON_IsBool(e)) {
      c->enabled = cJSON_IsTrue(e);
      continue;
    }
    static const char *const known_c[] = {"region", "parts", NULL};
    PREP_TRY(check_keys(rd, e, ek, known_c));
    c->enabled = 1;
    const cJSON *region = cJSON_GetObjectItemCaseSensitive(e, "region");
    if (region) {
      char rk[PATH_SIZE];
      sub_key(rk, ek, "region");
      static const char *const known_r[] = {"box", "sphere", NULL};
      PREP_TRY(check_keys(rd, region, rk, known_r));
      PREP_TRY(get_shape_region(rd, region, rk, &c->region));
    }
    PREP_TRY(get_parts(rd, e, ek, "parts", &c->parts));
  }
  return FASCIA_OK;
}

#define SCENE_PI 3.14159265358979323846

// A strand's end: {"organ"} and one of "point" (with "radius"), "part",
// "label" (a label organ's) or "region" (a box or a sphere); "spread".
static fascia_status parse_attachment(const reader *rd, const fascia_prep_scene *scene, const cJSON *item,
                                      const char *path, const char *key, fascia_prep_attachment *a) {
  char at[PATH_SIZE], ok[PATH_SIZE];
  sub_key(at, path, key);
  const cJSON *e = cJSON_GetObjectItemCaseSensitive(item, key);
  if (!cJSON_IsObject(e))
    return key_fail(rd, at,
                    "expected an attachment {\"organ\": name, \"point\": [x, y, z], \"radius\": r} or {\"organ\": "
                    "name, \"part\" | \"label\" | \"region\": ...}, found %s",
                    type_name(e));
  static const char *const known[] = {"organ", "point", "radius", "part", "label", "region", "spread", NULL};
  PREP_TRY(check_keys(rd, e, at, known));
  const char *organ;
  PREP_TRY(get_string(rd, e, at, "organ", 1, &organ));
  sub_key(ok, at, "organ");
  PREP_TRY(need_organ(rd, scene, ok, organ, &a->organ));
  static const char *const kinds[] = {"point", "part", "label", "region"};
  int given = 0;
  for (int k = 0; k < 4; ++k) given += cJSON_GetObjectItemCaseSensitive(e, kinds[k]) != NULL;
  if (given != 1)
    return key_fail(rd, at, "give one of \"point\" (with \"radius\"), \"part\", \"label\" or \"region\"%s",
                    given ? ", not both" : "");
  if (cJSON_GetObjectItemCaseSensitive(e, "radius") && !cJSON_GetObjectItemCaseSensitive(e, "point"))
    return key_fail(rd, at, "\"radius\" goes with \"point\"; give either \"point\" (with \"radius\") or a part, "
                    "label or region, not both");
  const cJSON *region = cJSON_GetObjectItemCaseSensitive(e, "region");
  PREP_TRY(get_bool(rd, e, at, "spread", region != NULL, &a->spread));
  static const char *const names[2] = {"part", "label"};
  for (int k = 0; k < 2; ++k) {
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(e, names[k]);
    if (!name) continue;
    char nk[PATH_SIZE], value[FASCIA_NAME_SIZE];
    sub_key(nk, at, names[k]);
    if (k == 1 && cJSON_IsNumber(name) && name->valuedouble == floor(name->valuedouble) && name->valuedouble >= 0 &&
        name->valuedouble < 1e9)
      snprintf(value, sizeof value, "%d", (int)name->valuedouble);
    else if (cJSON_IsString(name) && name->valuestring[0] && strlen(name->valuestring) < sizeof value)
      snprintf(value, sizeof value, "%s", name->valuestring);
    else
      return key_fail(rd, nk, "expected the name of a %s of organ '%s' (up to %d characters)%s, found %s", names[k],
                      organ, (int)sizeof value - 1, k ? " or its value" : "", type_name(name));
    if (k == 1 && scene->organs[a->organ].label_count == 0)
      return key_fail(rd, nk, "organ '%s' is a mesh, not labels of the segmentation; name a \"part\" of its mesh "
                      "or give a \"region\"", organ);
    snprintf(k ? a->label : a->part, sizeof a->part, "%s", value);
    return FASCIA_OK;
  }
  if (region) {
    char rk[PATH_SIZE];
    sub_key(rk, at, "region");
    static const char *const known_r[] = {"box", "sphere", NULL};
    PREP_TRY(check_keys(rd, region, rk, known_r));
    PREP_TRY(get_shape_region(rd, region, rk, &a->region));
    if (a->region.kind == FASCIA_PREP_REGION_NONE) return key_fail(rd, rk, "give a \"box\" or a \"sphere\"");
    return FASCIA_OK;
  }
  PREP_TRY(get_vector(rd, e, at, "point", 1, 3, a->point));
  PREP_TRY(get_number(rd, e, at, "radius", 0, 2 * scene->voxel_size, 0, 0, INFINITY, &a->radius));
  return FASCIA_OK;
}

// Where an attachment is known before the meshes are read: its point or
// its region's centre; 0 for a part or a label.
static int attachment_centre(const fascia_prep_attachment *a, double *x) {
  if (a->part[0] || a->label[0]) return 0;
  for (int r = 0; r < 3; ++r)
    x[r] = a->region.kind == FASCIA_PREP_REGION_BOX      ? 0.5 * (a->region.min[r] + a->region.max[r])
           : a->region.kind == FASCIA_PREP_REGION_SPHERE ? a->region.center[r]
                                                          : a->point[r];
  return 1;
}

// A strand's "through": the points its curve passes through, in order.
static fascia_status parse_through(const reader *rd, const cJSON *item, const char *path,
                                   fascia_prep_tissue_def *t) {
  const cJSON *through = cJSON_GetObjectItemCaseSensitive(item, "through");
  if (!through) return FASCIA_OK;
  char at[PATH_SIZE];
  sub_key(at, path, "through");
  if (!cJSON_IsArray(through) || cJSON_GetArraySize(through) < 1 || cJSON_GetArraySize(through) > 10000)
    return key_fail(rd, at, "expected an array of 1 to 10000 points [x, y, z] (m) the strand passes through, found %s",
                    type_name(through));
  const int n = cJSON_GetArraySize(through);
  t->through = prep_calloc(3 * (int64_t)n, sizeof(fascia_real));
  PREP_CHECK(t->through, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  const cJSON *e;
  cJSON_ArrayForEach(e, through) {
    char ek[PATH_SIZE];
    sub_index(ek, at, t->through_count);
    int k = 0;
    const cJSON *c;
    if (cJSON_IsArray(e) && cJSON_GetArraySize(e) == 3) {
      cJSON_ArrayForEach(c, e) {
        if (cJSON_IsNumber(c) && isfinite(c->valuedouble)) t->through[3 * t->through_count + k++] = c->valuedouble;
      }
    }
    if (k != 3) return key_fail(rd, ek, "expected a point [x, y, z] of three finite numbers (m), found %s", type_name(e));
    if (t->through_count > 0) {
      const fascia_real *p = t->through + 3 * t->through_count;
      double d2 = 0;
      for (int r = 0; r < 3; ++r) d2 += (p[r] - p[r - 3]) * (p[r] - p[r - 3]);
      if (!(d2 > 0)) return key_fail(rd, ek, "the same point as the one before; give each point once");
    }
    t->through_count++;
  }
  return FASCIA_OK;
}

// A tissue's "connects": at least `minimum` organ names, each once, into
// t->organs (the sheet's organs, a volume tissue's two or more).
static fascia_status get_connects(const reader *rd, const fascia_prep_scene *scene, const cJSON *item,
                                  const char *path, int minimum, fascia_prep_tissue_def *t) {
  char at[PATH_SIZE];
  sub_key(at, path, "connects");
  const cJSON *connects = cJSON_GetObjectItemCaseSensitive(item, "connects");
  if (!cJSON_IsArray(connects) || cJSON_GetArraySize(connects) < minimum)
    return key_fail(rd, at, "expected an array of %s organ names, found %s%s",
                    minimum == 1 ? "one or more" : "two or more", type_name(connects),
                    cJSON_IsArray(connects) ? " with fewer" : "");
  t->organs = prep_calloc(cJSON_GetArraySize(connects), sizeof(int32_t));
  PREP_CHECK(t->organs, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  const cJSON *e;
  cJSON_ArrayForEach(e, connects) {
    char ek[PATH_SIZE];
    sub_index(ek, at, t->organ_count);
    if (!cJSON_IsString(e)) return key_fail(rd, ek, "expected an organ name, found %s", type_name(e));
    PREP_TRY(need_organ(rd, scene, ek, e->valuestring, &t->organs[t->organ_count]));
    for (int32_t k = 0; k < t->organ_count; ++k)
      if (t->organs[k] == t->organs[t->organ_count]) {
        char first[PATH_SIZE];
        sub_index(first, at, k);
        return key_fail(rd, ek, "organ '%s' is given twice (first as %s); each organ once", e->valuestring, first);
      }
    t->organ_count++;
  }
  return FASCIA_OK;
}

// A strand or a sheet (the keys of parse_tissue that apply, and their own).
static fascia_status parse_reduced_tissue(const reader *rd, const fascia_prep_scene *scene, const cJSON *item,
                                          const char *path, const char *base_dir, fascia_prep_tissue_def *t) {
  static const char *const known_strand[] = {"name", "form", "from", "to", "through", "radius", "area", "material",
                                             "frame_spacing", "section_points", "description", NULL};
  static const char *const known_sheet[] = {"name", "form", "mesh", "units", "transform", "thickness", "connects",
                                            "material", "section_points", "coupling", "description", NULL};
  const int strand = t->form == FASCIA_PREP_FORM_STRAND;
  PREP_TRY(check_keys(rd, item, path, strand ? known_strand : known_sheet));
  char at[PATH_SIZE];
  const char *material;
  PREP_TRY(get_string(rd, item, path, "material", 1, &material));
  t->material = material_index(scene, material);
  sub_key(at, path, "material");
  if (t->material < 0) return key_fail(rd, at, "no material is named '%s' in \"materials\"", material);
  int q;
  PREP_TRY(get_int(rd, item, path, "section_points", 0, 2, 1, 4, &q));
  t->section_points = q;
  t->shape_kind = FASCIA_PREP_SHAPE_MLS;
  t->neighbours = strand ? 2 : 3;
  t->region_organ = -1;
  t->coupling_tolerance = scene->voxel_size;
  t->couple_others = 1;
  if (strand) {
    t->organs = prep_calloc(2, sizeof(int32_t));
    PREP_CHECK(t->organs, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
    PREP_TRY(parse_attachment(rd, scene, item, path, "from", &t->from));
    PREP_TRY(parse_attachment(rd, scene, item, path, "to", &t->to));
    t->organs[0] = t->from.organ;
    t->organs[1] = t->to.organ;
    t->organ_count = t->from.organ == t->to.organ ? 1 : 2;
    const cJSON *radius = cJSON_GetObjectItemCaseSensitive(item, "radius"), *area = cJSON_GetObjectItemCaseSensitive(item, "area");
    if (!!radius == !!area)
      return key_fail(rd, path, "give the cross-section as either \"radius\" (m) or \"area\" (m^2)%s",
                      radius ? ", not both" : "");
    if (radius) {
      PREP_TRY(get_number(rd, item, path, "radius", 1, 0, 0, 0, INFINITY, &t->radius));
      t->area = SCENE_PI * t->radius * t->radius;
    } else {
      PREP_TRY(get_number(rd, item, path, "area", 1, 0, 0, 0, INFINITY, &t->area));
      t->radius = sqrt(t->area / SCENE_PI);
    }
    PREP_TRY(get_number(rd, item, path, "frame_spacing", 1, 0, 0, 0, INFINITY, &t->frame_spacing));
    t->sample_spacing = t->frame_spacing;
    PREP_TRY(parse_through(rd, item, path, t));
    // the gap it bridges (what a motion's stretch is judged by): along the
    // points known now, its ends' points or regions' centres and "through"
    double prev[3], x[3], span = 0;
    int have = attachment_centre(&t->from, prev);
    for (int32_t k = 0; k <= t->through_count; ++k) {
      const int known = k < t->through_count ? (memcpy(x, t->through + 3 * k, sizeof x), 1)
                                             : attachment_centre(&t->to, x);
      if (known && have) span += sqrt((x[0] - prev[0]) * (x[0] - prev[0]) + (x[1] - prev[1]) * (x[1] - prev[1]) +
                                      (x[2] - prev[2]) * (x[2] - prev[2]));
      if (known) memcpy(prev, x, sizeof x), have = 1;
    }
    t->max_gap = span;
    const int points = !t->from.part[0] && !t->from.label[0] && t->from.region.kind == FASCIA_PREP_REGION_NONE &&
                       !t->to.part[0] && !t->to.label[0] && t->to.region.kind == FASCIA_PREP_REGION_NONE;
    double d2 = 0;
    for (int r = 0; r < 3; ++r) d2 += (t->to.point[r] - t->from.point[r]) * (t->to.point[r] - t->from.point[r]);
    if (points && t->through_count == 0 && !(sqrt(d2) > t->from.radius + t->to.radius)) {
      sub_key(at, path, "to");
      return key_fail(rd, at, "the strand's ends are %g m apart, within their attachment radii (%g + %g m); give "
                      "points farther apart or smaller radii", sqrt(d2), t->from.radius, t->to.radius);
    }
    return FASCIA_OK;
  }
  const char *mesh;
  PREP_TRY(get_string(rd, item, path, "mesh", 1, &mesh));
  t->mesh = prep_strdup(mesh);
  t->mesh_path = resolve_path(base_dir, mesh);
  PREP_CHECK(t->mesh && t->mesh_path, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  char units[8];
  int32_t units_given;
  PREP_TRY(parse_placement(rd, item, path, &t->mesh_scale, units, sizeof units, &units_given, t->mesh_transform));
  PREP_TRY(get_number(rd, item, path, "thickness", 1, 0, 0, 0, INFINITY, &t->thickness));
  t->area = t->thickness;
  PREP_TRY(get_connects(rd, scene, item, path, 1, t));
  const cJSON *coupling = cJSON_GetObjectItemCaseSensitive(item, "coupling");
  if (coupling) {
    sub_key(at, path, "coupling");
    PREP_TRY(parse_coupling(rd, scene, coupling, at, t));
  }
  return FASCIA_OK;
}

static fascia_status parse_tissue(const reader *rd, const fascia_prep_scene *scene, const cJSON *item,
                                  const char *path, const char *base_dir, fascia_prep_tissue_def *t) {
  PREP_TRY(get_name(rd, item, path, "name", t->name));
  const char *form;
  PREP_TRY(get_string(rd, item, path, "form", 0, &form));
  t->form = FASCIA_PREP_FORM_VOLUME;
  if (form && !strcmp(form, "strand"))
    t->form = FASCIA_PREP_FORM_STRAND;
  else if (form && !strcmp(form, "sheet"))
    t->form = FASCIA_PREP_FORM_SHEET;
  else if (form && strcmp(form, "volume")) {
    char at[PATH_SIZE];
    sub_key(at, path, "form");
    return key_fail(rd, at, "unknown form '%s' (known: volume, strand, sheet)", form);
  }
  if (t->form != FASCIA_PREP_FORM_VOLUME) return parse_reduced_tissue(rd, scene, item, path, base_dir, t);
  static const char *const known[] = {"name",           "form",          "connects",       "max_gap",
                                      "min_gap",        "region",        "material",       "frame_spacing",
                                      "sample_spacing", "shape_functions", "coupling",     "min_component",
                                      "patch_radius",   "description",   "attachment",   "attachment_layer",
                                      NULL};
  PREP_TRY(check_keys(rd, item, path, known));
  PREP_TRY(get_name(rd, item, path, "name", t->name));
  const char *description;
  PREP_TRY(get_string(rd, item, path, "description", 0, &description));
  PREP_TRY(get_connects(rd, scene, item, path, 2, t));
  char at[PATH_SIZE];
  PREP_TRY(get_number(rd, item, path, "max_gap", 1, 0, 0, 0, INFINITY, &t->max_gap));
  PREP_TRY(get_number(rd, item, path, "min_gap", 0, FASCIA_PREP_MIN_GAP, 0, 1, t->max_gap, &t->min_gap));
  t->region_organ = -1;
  const cJSON *region = cJSON_GetObjectItemCaseSensitive(item, "region");
  if (region) {
    sub_key(at, path, "region");
    static const char *const known_r[] = {"box", "sphere", "parts", NULL};
    PREP_TRY(check_keys(rd, region, at, known_r));
    PREP_TRY(get_shape_region(rd, region, at, &t->region));
    const cJSON *parts = cJSON_GetObjectItemCaseSensitive(region, "parts");
    if (parts) {
      char pk[PATH_SIZE];
      sub_key(pk, at, "parts");
      static const char *const known_p[] = {"organ", "names", NULL};
      PREP_TRY(check_keys(rd, parts, pk, known_p));
      const char *organ;
      PREP_TRY(get_string(rd, parts, pk, "organ", 1, &organ));
      char ok[PATH_SIZE];
      sub_key(ok, pk, "organ");
      PREP_TRY(need_organ(rd, scene, ok, organ, &t->region_organ));
      int connected = 0;
      for (int32_t k = 0; k < t->organ_count; ++k) connected |= t->organs[k] == t->region_organ;
      if (!connected) return key_fail(rd, ok, "organ '%s' is not one the tissue connects", organ);
      PREP_TRY(get_parts(rd, parts, pk, "names", &t->region_parts));
      if (t->region_parts.count == 0) return key_fail(rd, pk, "\"names\" must list at least one part");
    }
  }
  const char *material;
  PREP_TRY(get_string(rd, item, path, "material", 1, &material));
  t->material = material_index(scene, material);
  sub_key(at, path, "material");
  if (t->material < 0) return key_fail(rd, at, "no material is named '%s' in \"materials\"", material);
  PREP_TRY(parse_sampling(rd, scene, item, path, &t->frame_spacing, &t->sample_spacing, &t->shape_kind,
                          &t->neighbours, &t->samples_per_tet, &t->enhanced_modes, &t->min_component, &t->patch_radius));
  const char *attachment;
  PREP_TRY(get_string(rd, item, path, "attachment", 0, &attachment));
  t->attachment = attachment && !strcmp(attachment, "exact") ? FASCIA_PREP_ATTACH_EXACT : FASCIA_PREP_ATTACH_FRAMES;
  if (attachment && strcmp(attachment, "exact") && strcmp(attachment, "frames")) {
    sub_key(at, path, "attachment");
    return key_fail(rd, at, "unknown attachment '%s' (known: frames, exact)", attachment);
  }
  if (t->attachment == FASCIA_PREP_ATTACH_EXACT && t->shape_kind != FASCIA_PREP_SHAPE_MLS) {
    sub_key(at, path, "attachment");
    return key_fail(rd, at, "\"exact\" needs mls shape functions (tet weights are their tetrahedra's); use "
                            "\"frames\" or shape_functions.kind \"mls\"");
  }
  PREP_TRY(get_number(rd, item, path, "attachment_layer", 0, 0, 0, 0, INFINITY, &t->attachment_layer));
  t->coupling_tolerance = scene->voxel_size;
  t->couple_others = 1;
  const cJSON *coupling = cJSON_GetObjectItemCaseSensitive(item, "coupling");
  if (coupling) {
    sub_key(at, path, "coupling");
    PREP_TRY(parse_coupling(rd, scene, coupling, at, t));
  }
  return FASCIA_OK;
}

// The name fields of n structs stride bytes apart, first at name: unique.
static fascia_status unique_names(const reader *rd, const char *table, int32_t n, const char *name, size_t stride) {
  const char **names = prep_calloc(n, sizeof *names);
  PREP_CHECK(names, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  for (int32_t k = 0; k < n; ++k) names[k] = name + (size_t)k * stride;
  const fascia_status status = check_unique(rd, table, names, n, at_name);
  free(names);
  return status;
}

static fascia_status parse_root(const reader *rd, const cJSON *root, const char *base_dir, fascia_prep_scene *s) {
  static const char *const known[] = {"fascia_scene", "name",      "description", "voxel_size", "seed",
                                      "gravity",      "output",    "close_holes", "materials",  "organs",
                                      "tissues",      "segmentation", NULL};
  PREP_TRY(check_keys(rd, root, "", known));
  int version;
  PREP_TRY(get_int(rd, root, "", "fascia_scene", 1, 1, 1, 1, &version));
  const char *name, *description, *output;
  PREP_TRY(get_string(rd, root, "", "name", 0, &name));
  PREP_TRY(get_string(rd, root, "", "description", 0, &description));
  PREP_TRY(get_number(rd, root, "", "voxel_size", 1, 0, 0, 0, INFINITY, &s->voxel_size));
  int seed;
  PREP_TRY(get_int(rd, root, "", "seed", 0, 1, 0, 2147483647, &seed));
  s->seed = (uint64_t)seed;
  s->gravity[0] = 0, s->gravity[1] = -9.81, s->gravity[2] = 0;
  PREP_TRY(get_vector(rd, root, "", "gravity", 0, 3, s->gravity));
  PREP_TRY(get_number(rd, root, "", "close_holes", 0, 0.01, 0, 1, 0.1, &s->close_holes));
  PREP_TRY(get_string(rd, root, "", "output", 0, &output));
  if (output) { // as given: relative to the working folder, like -o
    s->output = prep_strdup(output);
    PREP_CHECK(s->output, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  }

  const cJSON *materials = cJSON_GetObjectItemCaseSensitive(root, "materials");
  if (!cJSON_IsObject(materials) || cJSON_GetArraySize(materials) < 1)
    return key_fail(rd, "materials", "expected an object {name: {\"youngs_modulus\", ...}}, found %s",
                    type_name(materials));
  // room for the wall material each shell organ derives (parse_shell)
  s->materials = prep_calloc(cJSON_GetArraySize(materials) +
                                 cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(root, "organs")),
                             sizeof *s->materials);
  PREP_CHECK(s->materials, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  const cJSON *e;
  cJSON_ArrayForEach(e, materials) {
    char at[PATH_SIZE];
    sub_key(at, "materials", e->string);
    PREP_TRY(parse_material(rd, e, at, s->materials + s->material_count));
    s->material_count++;
  }

  const cJSON *segmentation = cJSON_GetObjectItemCaseSensitive(root, "segmentation");
  if (segmentation) PREP_TRY(parse_segmentation(rd, s, segmentation, base_dir));

  const cJSON *organs = cJSON_GetObjectItemCaseSensitive(root, "organs");
  if (!cJSON_IsArray(organs) || cJSON_GetArraySize(organs) < 1)
    return key_fail(rd, "organs", "expected a non-empty array of organs, found %s", type_name(organs));
  s->organs = prep_calloc(cJSON_GetArraySize(organs), sizeof *s->organs);
  PREP_CHECK(s->organs, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  cJSON_ArrayForEach(e, organs) {
    char at[PATH_SIZE];
    sub_index(at, "organs", s->organ_count);
    fascia_prep_organ_def *o = s->organs + s->organ_count;
    s->organ_count++; // counted first so that destroy frees what was parsed
    PREP_TRY(parse_organ(rd, s, e, at, base_dir, o));
  }
  PREP_TRY(unique_names(rd, "organs", s->organ_count, s->organs[0].name, sizeof *s->organs));

  const cJSON *tissues = cJSON_GetObjectItemCaseSensitive(root, "tissues");
  if (!cJSON_IsArray(tissues) || cJSON_GetArraySize(tissues) < 1)
    return key_fail(rd, "tissues", "expected a non-empty array of tissues, found %s", type_name(tissues));
  if (cJSON_GetArraySize(tissues) > 250)
    return key_fail(rd, "tissues", "%d tissues, more than the 250 a model can label", cJSON_GetArraySize(tissues));
  s->tissues = prep_calloc(cJSON_GetArraySize(tissues), sizeof *s->tissues);
  PREP_CHECK(s->tissues, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
  cJSON_ArrayForEach(e, tissues) {
    char at[PATH_SIZE];
    sub_index(at, "tissues", s->tissue_count);
    fascia_prep_tissue_def *t = s->tissues + s->tissue_count;
    s->tissue_count++;
    PREP_TRY(parse_tissue(rd, s, e, at, base_dir, t));
  }
  PREP_TRY(unique_names(rd, "tissues", s->tissue_count, s->tissues[0].name, sizeof *s->tissues));
  return FASCIA_OK;
}

// ------------------------------------------------ repeated keys, with places
// cJSON keeps every member of an object, repeats included, and its lookups
// return the first: a key given twice would silently take the first value.
// So every object of the file is checked, walking the text beside the tree
// (cJSON has validated it) to know where each key stands.

static const char *skip_space(const char *p) {
  while (*p && (unsigned char)*p <= 32) ++p; // what cJSON skips
  return p;
}

static const char *skip_string(const char *p) { // p at the opening quote
  for (++p; *p && *p != '"'; ++p)
    if (*p == '\\' && p[1]) ++p;
  return *p ? p + 1 : p;
}

static void line_column(const char *text, const char *at, int *line, int *column) {
  *line = 1, *column = 1;
  for (const char *c = text; c < at && *c; ++c) {
    if (*c == '\n')
      ++*line, *column = 1;
    else
      ++*column;
  }
}

// Checks item (whose text starts at or after *p) and everything in it;
// *p is left after its text.
static fascia_status check_repeated_keys(const reader *rd, const char *text, const cJSON *item, const char *path,
                                         const char **p) {
  const char *c = skip_space(*p);
  if (cJSON_IsString(item)) {
    *p = skip_string(c);
    return FASCIA_OK;
  }
  if (!cJSON_IsObject(item) && !cJSON_IsArray(item)) { // number, true, false, null
    while (*c && (unsigned char)*c > 32 && *c != ',' && *c != ']' && *c != '}') ++c;
    *p = c;
    return FASCIA_OK;
  }
  const int object = cJSON_IsObject(item), n = cJSON_GetArraySize(item);
  const char **keys = NULL, **places = NULL;
  if (object && n > 1) {
    keys = prep_calloc(n, sizeof *keys);
    places = prep_calloc(n, sizeof *places);
    if (!keys || !places) {
      free(keys);
      free(places);
      return PREP_FAIL(rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
    }
  }
  fascia_status status = FASCIA_OK;
  ++c; // '{' or '['
  int k = 0;
  const cJSON *e;
  cJSON_ArrayForEach(e, item) {
    char at[PATH_SIZE];
    c = skip_space(c);
    if (object) {
      if (keys) keys[k] = e->string, places[k] = c;
      c = skip_space(skip_string(c)) + 1; // the key and its ':'
      sub_key(at, path, e->string);
    } else {
      sub_index(at, path, k);
    }
    PREP_TRY_GOTO(check_repeated_keys(rd, text, e, at, &c));
    c = skip_space(c);
    if (*c == ',') ++c;
    ++k;
  }
  c = skip_space(c);
  if (*c) ++c; // '}' or ']'
  *p = c;
  if (keys) {
    int first, second;
    const int r = find_repeat(keys, n, &first, &second);
    PREP_CHECK_GOTO(r >= 0, rd->ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", rd->file);
    if (r) {
      int l1, c1, l2, c2;
      line_column(text, places[first], &l1, &c1);
      line_column(text, places[second], &l2, &c2);
      char at[PATH_SIZE];
      sub_key(at, path, keys[second]);
      status = key_fail(rd, at, "the key is given twice, at line %d, column %d and at line %d, column %d; keep one",
                        l1, c1, l2, c2);
    }
  }
cleanup:
  free(keys);
  free(places);
  return status;
}

// Why text failed to parse at end: its nesting beyond cJSON's limit, or
// other damage.
static fascia_status json_error(fascia_ctx *ctx, const char *origin, const char *text, const char *end) {
  int depth = 0; // of the arrays and objects open before end
  for (const char *c = text; end && c < end && *c; ++c) {
    if (*c == '"')
      c = skip_string(c) - 1;
    else if (*c == '[' || *c == '{')
      ++depth;
    else if (*c == ']' || *c == '}')
      --depth;
  }
  int line, column;
  line_column(text, end ? end : text, &line, &column);
  if (end && (*end == '[' || *end == '{') && depth >= CJSON_NESTING_LIMIT)
    return PREP_FAIL(ctx, FASCIA_ERR_FORMAT,
                     "scene '%s': arrays and objects are nested too deeply at line %d, column %d (more than %d "
                     "levels, the reader's limit; a scene needs fewer than 10)",
                     origin, line, column, CJSON_NESTING_LIMIT);
  return PREP_FAIL(ctx, FASCIA_ERR_FORMAT, "scene '%s': not valid JSON near line %d, column %d", origin, line, column);
}

// 1 when s is valid UTF-8 (no overlong forms, surrogates or code points
// past U+10FFFF): names and paths go into files and JSON output as they are.
static int valid_utf8(const unsigned char *s) {
  while (*s) {
    const unsigned c = *s;
    int n;
    unsigned min;
    if (c < 0x80) {
      ++s;
      continue;
    } else if ((c & 0xE0) == 0xC0) n = 1, min = 0x80;
    else if ((c & 0xF0) == 0xE0) n = 2, min = 0x800;
    else if ((c & 0xF8) == 0xF0) n = 3, min = 0x10000;
    else return 0;
    unsigned v = c & (0x3Fu >> n);
    for (int k = 1; k <= n; ++k) {
      if ((s[k] & 0xC0) != 0x80) return 0;
      v = v << 6 | (s[k] & 0x3Fu);
    }
    if (v < min || v > 0x10FFFF || (v >= 0xD800 && v <= 0xDFFF)) return 0;
    s += n + 1;
  }
  return 1;
}

// Every key and string of the scene valid UTF-8, named by its path.
static fascia_status check_strings(const reader *rd, const cJSON *item, const char *path) {
  int index = 0;
  for (const cJSON *c = item->child; c; c = c->next, ++index) {
    char at[PATH_SIZE];
    if (cJSON_IsObject(item)) {
      if (c->string && !valid_utf8((const unsigned char *)c->string))
        return key_fail(rd, path, "a key is not valid UTF-8; write names and paths in UTF-8");
      sub_key(at, path, c->string ? c->string : "");
    } else {
      sub_index(at, path, index);
    }
    if (cJSON_IsString(c) && c->valuestring && !valid_utf8((const unsigned char *)c->valuestring))
      return key_fail(rd, at, "not valid UTF-8; write names and paths in UTF-8");
    PREP_TRY(check_strings(rd, c, at));
  }
  return FASCIA_OK;
}

// A string escape \u0000 becomes a NUL that ends the C string early (a mesh
// path would read a shorter name): refused where it stands.
static fascia_status check_nul_escapes(const reader *rd, const char *text) {
  int in_string = 0, line = 1, column = 1;
  for (const char *c = text; *c; ++c, ++column) {
    if (*c == '\n') line++, column = 0;
    if (!in_string) {
      in_string = *c == '"';
      continue;
    }
    if (*c == '"') in_string = 0;
    else if (*c == '\\' && c[1]) {
      if (c[1] == 'u' && c[2] == '0' && c[3] == '0' && c[4] == '0' && c[5] == '0')
        return PREP_FAIL(rd->ctx, FASCIA_ERR_FORMAT,
                         "scene '%s' line %d, column %d: a string holds \\u0000 (a NUL character), which would cut it "
                         "short; remove it",
                         rd->file, line, column);
      ++c, ++column;
    }
  }
  return FASCIA_OK;
}

fascia_status fascia_prep_scene_parse(fascia_ctx *ctx, const char *text, const char *origin, const char *base_dir,
                                      fascia_prep_scene **out) {
  PREP_CHECK(out && text, ctx, FASCIA_ERR_ARGUMENT, "fascia_prep_scene_parse: NULL argument");
  *out = NULL;
  if (!origin) origin = "(memory)";
  if (!base_dir) base_dir = ".";
  const reader rd = {ctx, origin};
  const char *end = NULL;
  cJSON *root = cJSON_ParseWithOpts(text, &end, 1);
  if (!root) return json_error(ctx, origin, text, end);
  if (check_nul_escapes(&rd, text) != FASCIA_OK || check_strings(&rd, root, "") != FASCIA_OK) {
    cJSON_Delete(root);
    return FASCIA_ERR_FORMAT;
  }
  fascia_prep_scene *s = calloc(1, sizeof *s);
  fascia_status status = FASCIA_OK;
  PREP_CHECK_GOTO(s, ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", origin);
  s->path = prep_strdup(origin);
  s->text = prep_strdup(text);
  PREP_CHECK_GOTO(s->path && s->text, ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", origin);
  const char *cursor = text;
  if (!strncmp(cursor, "\xEF\xBB\xBF", 3)) cursor += 3; // a UTF-8 byte order mark, which cJSON skips
  PREP_TRY_GOTO(check_repeated_keys(&rd, text, root, "", &cursor));
  PREP_TRY_GOTO(parse_root(&rd, root, base_dir, s));
  int edited = 0;
  PREP_TRY_GOTO(prep_scene_leave_out_absent(ctx, s, root, &edited));
  if (edited) { // read again without the absent optional organs
    fascia_prep_scene *again = calloc(1, sizeof *again);
    PREP_CHECK_GOTO(again, ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", origin);
    again->path = s->path, again->text = s->text, s->path = s->text = NULL;
    again->absent_organ_count = s->absent_organ_count, again->absent_organs = s->absent_organs;
    again->dropped_tissue_count = s->dropped_tissue_count, again->dropped_tissues = s->dropped_tissues;
    s->absent_organs = s->dropped_tissues = NULL;
    fascia_prep_scene_destroy(&s);
    s = again;
    PREP_TRY_GOTO(parse_root(&rd, root, base_dir, s));
  }
  *out = s;
  s = NULL;
cleanup:
  fascia_prep_scene_destroy(&s);
  cJSON_Delete(root);
  return status;
}

fascia_status fascia_prep_scene_load(fascia_ctx *ctx, const char *path, fascia_prep_scene **out) {
  PREP_CHECK(out && path, ctx, FASCIA_ERR_ARGUMENT, "fascia_prep_scene_load: NULL argument");
  *out = NULL;
  char *text = NULL;
  size_t size = 0;
  PREP_TRY(prep_read_file(ctx, path, "scene", MAX_SCENE_BYTES, &text, &size));
  const char *nul = memchr(text, 0, size);
  if (nul) {
    int line = 1;
    for (const char *c = text; c < nul; ++c) line += *c == '\n';
    free(text);
    return PREP_FAIL(ctx, FASCIA_ERR_FORMAT, "scene '%s' line %d: a NUL byte, which JSON text never holds; the file is "
                     "damaged or not a scene", path, line);
  }
  char *dir = prep_strdup(path);
  if (!dir) {
    free(text);
    return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "scene '%s': out of memory", path);
  }
  char *slash = strrchr(dir, '/');
  if (slash)
    *slash = 0;
  else
    strcpy(dir, ".");
  const fascia_status status = fascia_prep_scene_parse(ctx, text, path, dir, out);
  free(dir);
  free(text);
  return status;
}

static void free_parts(fascia_prep_parts *parts) {
  for (int32_t k = 0; parts->names && k < parts->count; ++k) free(parts->names[k]);
  free(parts->names);
  parts->names = NULL;
  parts->count = 0;
}

void fascia_prep_scene_destroy(fascia_prep_scene **scene) {
  if (!scene || !*scene) return;
  fascia_prep_scene *s = *scene;
  for (int32_t k = 0; s->organs && k < s->organ_count; ++k) {
    fascia_prep_organ_def *o = s->organs + k;
    free(o->mesh);
    free(o->mesh_path);
    free_parts(&o->parts);
    free(o->labels);
    free(o->label_named);
    free(o->motion.key_time);
    free(o->motion.key_translation);
    free(o->motion.key_rotation);
  }
  for (int32_t k = 0; s->tissues && k < s->tissue_count; ++k) {
    fascia_prep_tissue_def *t = s->tissues + k;
    free(t->organs);
    free_parts(&t->region_parts);
    for (int32_t c = 0; t->coupling && c < t->coupling_count; ++c) free_parts(&t->coupling[c].parts);
    free(t->coupling);
    free(t->mesh);
    free(t->mesh_path);
    free(t->through);
  }
  fascia_prep_segmentation *seg = &s->segmentation;
  prep_label_table table;
  scene_table(seg, &table);
  prep_label_table_free(&table);
  free(seg->file);
  free(seg->file_path);
  free(seg->table);
  free(seg->connective);
  free(s->organs);
  free(s->tissues);
  free(s->materials);
  free(s->path);
  free(s->text);
  free(s->output);
  free(s->absent_organs);
  free(s->dropped_tissues);
  free(s);
  *scene = NULL;
}

const char *fascia_prep_form_name(int32_t form) {
  switch (form) {
  case FASCIA_PREP_FORM_VOLUME: return "volume";
  case FASCIA_PREP_FORM_STRAND: return "strand";
  case FASCIA_PREP_FORM_SHEET: return "sheet";
  default: return "unknown";
  }
}
