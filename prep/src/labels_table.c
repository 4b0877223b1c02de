// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Label tables of a segmentation: a TSV file (label TAB name, one a line, an
// optional header line "label<TAB>name", '#' comments), or the built-in table
// of TotalSegmentator's task `total` (its v2 class map). Organs name labels by
// value, by name, or by a shell pattern over the names ("vertebrae_*").
#include <ctype.h>
#include <errno.h>
#include <fnmatch.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "labels.h"

#define MAX_TABLE_BYTES ((int64_t)16 << 20)

// TotalSegmentator v2, task total: label k is names[k - 1]
static const char *const totalsegmentator_total[] = {
    "spleen", "kidney_right", "kidney_left", "gallbladder", "liver", "stomach", "pancreas", "adrenal_gland_right",
    "adrenal_gland_left", "lung_upper_lobe_left", "lung_lower_lobe_left", "lung_upper_lobe_right",
    "lung_middle_lobe_right", "lung_lower_lobe_right", "esophagus", "trachea", "thyroid_gland", "small_bowel",
    "duodenum", "colon", "urinary_bladder", "prostate", "kidney_cyst_left", "kidney_cyst_right", "sacrum",
    "vertebrae_S1", "vertebrae_L5", "vertebrae_L4", "vertebrae_L3", "vertebrae_L2", "vertebrae_L1", "vertebrae_T12",
    "vertebrae_T11", "vertebrae_T10", "vertebrae_T9", "vertebrae_T8", "vertebrae_T7", "vertebrae_T6", "vertebrae_T5",
    "vertebrae_T4", "vertebrae_T3", "vertebrae_T2", "vertebrae_T1", "vertebrae_C7", "vertebrae_C6", "vertebrae_C5",
    "vertebrae_C4", "vertebrae_C3", "vertebrae_C2", "vertebrae_C1", "heart", "aorta", "pulmonary_vein",
    "brachiocephalic_trunk", "subclavian_artery_right", "subclavian_artery_left", "common_carotid_artery_right",
    "common_carotid_artery_left", "brachiocephalic_vein_left", "brachiocephalic_vein_right", "atrial_appendage_left",
    "superior_vena_cava", "inferior_vena_cava", "portal_vein_and_splenic_vein", "iliac_artery_left",
    "iliac_artery_right", "iliac_vena_left", "iliac_vena_right", "humerus_left", "humerus_right", "scapula_left",
    "scapula_right", "clavicula_left", "clavicula_right", "femur_left", "femur_right", "hip_left", "hip_right",
    "spinal_cord", "gluteus_maximus_left", "gluteus_maximus_right", "gluteus_medius_left", "gluteus_medius_right",
    "gluteus_minimus_left", "gluteus_minimus_right", "autochthon_left", "autochthon_right", "iliopsoas_left",
    "iliopsoas_right", "brain", "skull", "rib_left_1", "rib_left_2", "rib_left_3", "rib_left_4", "rib_left_5",
    "rib_left_6", "rib_left_7", "rib_left_8", "rib_left_9", "rib_left_10", "rib_left_11", "rib_left_12",
    "rib_right_1", "rib_right_2", "rib_right_3", "rib_right_4", "rib_right_5", "rib_right_6", "rib_right_7",
    "rib_right_8", "rib_right_9", "rib_right_10", "rib_right_11", "rib_right_12", "sternum", "costal_cartilages",
};

void prep_label_table_free(prep_label_table *table) {
  for (int32_t k = 0; table->name && k < table->count; ++k) free(table->name[k]);
  free(table->name);
  free(table->label);
  table->name = NULL;
  table->label = NULL;
  table->count = 0;
}

fascia_status prep_label_table_add(fascia_ctx *ctx, const char *origin, prep_label_table *table, int32_t label,
                                   const char *name) {
  int32_t *labels = realloc(table->label, (size_t)(table->count + 1) * sizeof *labels);
  if (labels) table->label = labels;
  char **names = realloc(table->name, (size_t)(table->count + 1) * sizeof *names);
  if (names) table->name = names;
  char *copy = prep_strdup(name);
  if (!labels || !names || !copy) {
    free(copy);
    return PREP_FAIL(ctx, FASCIA_ERR_MEMORY, "label table '%s': out of memory", origin);
  }
  table->label[table->count] = label;
  table->name[table->count] = copy;
  table->count++;
  return FASCIA_OK;
}

fascia_status prep_label_table_builtin(fascia_ctx *ctx, const char *name, prep_label_table *table) {
  memset(table, 0, sizeof *table);
  if (strcmp(name, PREP_TOTALSEGMENTATOR_TOTAL))
    return PREP_FAIL(ctx, FASCIA_ERR_FORMAT, "no built-in label table is named '%s' (known: %s)", name,
                     PREP_TOTALSEGMENTATOR_TOTAL);
  const int32_t n = (int32_t)(sizeof totalsegmentator_total / sizeof *totalsegmentator_total);
  for (int32_t k = 0; k < n; ++k) {
    const fascia_status status = prep_label_table_add(ctx, name, table, k + 1, totalsegmentator_total[k]);
    if (status != FASCIA_OK) {
      prep_label_table_free(table);
      return status;
    }
  }
  return FASCIA_OK;
}

static char *trim(char *s) {
  while (*s == ' ' || *s == '\t') ++s;
  size_t n = strlen(s);
  while (n && isspace((unsigned char)s[n - 1])) s[--n] = 0;
  return s;
}

fascia_status prep_label_table_load(fascia_ctx *ctx, const char *path, prep_label_table *table) {
  memset(table, 0, sizeof *table);
  char *text = NULL;
  PREP_TRY(prep_read_file(ctx, path, "label table", MAX_TABLE_BYTES, &text, NULL));
  fascia_status status = FASCIA_OK;
  int line = 0;
  for (char *next = text, *row; next && *next; ) {
    row = next;
    next = strchr(row, '\n');
    if (next) *next++ = 0;
    ++line;
    char *tab = strchr(row, '\t');
    char *first = trim(row);
    if (!first[0] || first[0] == '#') continue;
    PREP_CHECK_GOTO(tab, ctx, FASCIA_ERR_FORMAT,
                    "label table '%s' line %d: expected a label, a tab and a name, found '%.40s'", path, line, first);
    *tab = 0;
    char *value = trim(row), *name = trim(tab + 1);
    if (line == 1 && !strcmp(value, "label")) continue; // the header
    char *end;
    errno = 0;
    const long label = strtol(value, &end, 10);
    PREP_CHECK_GOTO(end != value && !*end && !errno && label > 0 && label <= PREP_MAX_LABEL, ctx, FASCIA_ERR_FORMAT,
                    "label table '%s' line %d: '%s' is not a label (expected an integer 1 .. %d)", path, line, value,
                    PREP_MAX_LABEL);
    PREP_CHECK_GOTO(name[0] && !strchr(name, '\t'), ctx, FASCIA_ERR_FORMAT,
                    "label table '%s' line %d: expected one name after the label", path, line);
    for (int32_t k = 0; k < table->count; ++k) {
      PREP_CHECK_GOTO(table->label[k] != label, ctx, FASCIA_ERR_FORMAT,
                      "label table '%s' line %d: label %ld is given twice", path, line, label);
      PREP_CHECK_GOTO(strcmp(table->name[k], name), ctx, FASCIA_ERR_FORMAT,
                      "label table '%s' line %d: name '%s' is given twice", path, line, name);
    }
    PREP_TRY_GOTO(prep_label_table_add(ctx, path, table, (int32_t)label, name));
  }
  PREP_CHECK_GOTO(table->count > 0, ctx, FASCIA_ERR_FORMAT, "label table '%s': no labels in it", path);
cleanup:
  free(text);
  if (status != FASCIA_OK) prep_label_table_free(table);
  return status;
}

const char *prep_label_table_name(const prep_label_table *table, int32_t label) {
  for (int32_t k = 0; k < table->count; ++k)
    if (table->label[k] == label) return table->name[k];
  return NULL;
}

static int has_wildcard(const char *s) { return strpbrk(s, "*?[") != NULL; }

int32_t prep_label_match(const prep_label_table *table, const char *spec, int32_t *out, int32_t capacity) {
  int32_t n = 0;
  for (int32_t k = 0; k < table->count; ++k) {
    const int match = has_wildcard(spec) ? !fnmatch(spec, table->name[k], 0) : !strcmp(spec, table->name[k]);
    if (!match) continue;
    if (n < capacity) out[n] = table->label[k];
    ++n;
  }
  return n;
}

const char *prep_nifti_ending(const char *path) {
  const size_t n = strlen(path);
  if (n > 7 && !strcmp(path + n - 7, ".nii.gz")) return path + n - 7;
  if (n > 4 && !strcmp(path + n - 4, ".nii")) return path + n - 4;
  return NULL;
}

int fascia_prep_labelmap_table_path(const char *path, char *out, size_t size) {
  const char *ending = prep_nifti_ending(path);
  if (!ending) return 0;
  const int n = snprintf(out, size, "%.*s.tsv", (int)(ending - path), path);
  return n > 0 && (size_t)n < size;
}
