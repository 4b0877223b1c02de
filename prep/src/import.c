// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Stage 1, import: read each organ's file with assimp, keep the parts the
// scene names, apply units and transform, refuse NaN coordinates and empty
// meshes. The file's SHA-256 is kept for provenance.
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "labels.h"
#include "prep_util.h"
#include "reduced.h"

void fascia_prep_meshes_destroy(fascia_prep_meshes **meshes) {
  if (!meshes || !*meshes) return;
  fascia_prep_meshes *m = *meshes;
  for (int32_t k = 0; m->organs && k < m->count; ++k) {
    fascia_prep_mesh *o = m->organs + k;
    free(o->vertices);
    free(o->triangles);
    free(o->triangle_part);
    for (int32_t p = 0; o->part_names && p < o->part_count; ++p) free(o->part_names[p]);
    free(o->part_names);
  }
  free(m->organs);
  for (int32_t k = 0; m->sheets && k < m->sheet_slots; ++k) {
    free(m->sheets[k].vertices);
    free(m->sheets[k].triangles);
    free(m->sheets[k].triangle_part);
    for (int32_t p = 0; m->sheets[k].part_names && p < m->sheets[k].part_count; ++p) free(m->sheets[k].part_names[p]);
    free(m->sheets[k].part_names);
  }
  free(m->sheets);
  for (int32_t k = 0; m->warnings && k < m->warning_count; ++k) free(m->warnings[k]);
  free(m->warnings);
  free(m->contacts);
  free(m->occupied);
  free(m);
  *meshes = NULL;
}

// The file's part names into out ("a, b, c", unnamed parts counted); 0 when
// no part has a name (an STL, an OBJ without groups).
static int list_parts(const fascia_assimp_file *f, char *out, size_t size) {
  out[0] = 0;
  int named = 0, unnamed = 0;
  for (int32_t p = 0; p < f->part_count; ++p) {
    const char *name = f->node_names[p][0] ? f->node_names[p] : f->mesh_names[p];
    if (!name[0]) {
      ++unnamed;
      continue;
    }
    if (strlen(out) + strlen(name) + 8 >= size) {
      strncat(out, ", ...", size - strlen(out) - 1);
      return 1;
    }
    if (named++) strcat(out, ", ");
    strcat(out, name);
  }
  if (named && unnamed) snprintf(out + strlen(out), size - strlen(out), " (and %d unnamed)", unnamed);
  return named > 0;
}

// Picks parts from the file into o; each requested name must match a node or mesh name.
static fascia_status pick_parts(fascia_ctx *ctx, const char *scene_path, const fascia_prep_organ_def *def,
                                const fascia_assimp_file *f, int32_t organ_index, fascia_prep_mesh *o) {
  const int32_t P = f->part_count;
  int32_t *use = prep_calloc(P, sizeof(int32_t)); // part index in o + 1, 0: unused
  PREP_CHECK(use, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", def->name);
  fascia_status status = FASCIA_OK;
  const int32_t names = def->parts.count ? def->parts.count : P;
  o->part_names = prep_calloc(names, sizeof(char *));
  PREP_CHECK_GOTO(o->part_names, ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", def->name);
  if (def->parts.count == 0) {
    for (int32_t p = 0; p < P; ++p) {
      use[p] = p + 1;
      o->part_names[p] = prep_strdup(f->node_names[p][0] ? f->node_names[p] : f->mesh_names[p]);
      PREP_CHECK_GOTO(o->part_names[p], ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", def->name);
      o->part_count++;
    }
  } else {
    for (int32_t n = 0; n < def->parts.count; ++n) {
      int found = 0;
      for (int32_t p = 0; p < P; ++p)
        if (!strcmp(f->node_names[p], def->parts.names[n]) || !strcmp(f->mesh_names[p], def->parts.names[n])) {
          if (!use[p]) use[p] = n + 1;
          found = 1;
        }
      if (!found) {
        char list[1024];
        if (list_parts(f, list, sizeof list))
          PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_FORMAT,
                          "organ '%s' (scene '%s' organs[%d].parts): mesh '%s' has no part named '%s'; its parts are: %s",
                          def->name, scene_path, (int)organ_index, def->mesh_path, def->parts.names[n], list);
        PREP_CHECK_GOTO(0, ctx, FASCIA_ERR_FORMAT,
                        "organ '%s' (scene '%s' organs[%d].parts): mesh '%s' has no named parts (%d unnamed), so "
                        "none named '%s'; leave \"parts\" out to take the whole file, or export it with named "
                        "parts (glTF nodes, OBJ groups)",
                        def->name, scene_path, (int)organ_index, def->mesh_path, (int)f->part_count, def->parts.names[n]);
      }
      o->part_names[n] = prep_strdup(def->parts.names[n]);
      PREP_CHECK_GOTO(o->part_names[n], ctx, FASCIA_ERR_MEMORY, "organ '%s': out of memory", def->name);
      o->part_count++;
    }
  }
  int64_t nv = 0, nt = 0;
  for (int32_t p = 0; p < P; ++p)
    if (use[p]) {
      nv += f->vertex_offset[p + 1] - f->vertex_offset[p];
      nt += f->triangle_offset[p + 1] - f->triangle_offset[p];
    }
  PREP_CHECK_GOTO(nt > 0, ctx, FASCIA_ERR_FORMAT,
                  "organ '%s': mesh '%s' has no triangles%s (%d parts, %d points or lines skipped); give a file with "
                  "a surface mesh",
                  def->name, def->mesh_path, def->parts.count ? " in the chosen parts" : "", (int)P,
                  (int)f->skipped_primitives);
  PREP_CHECK_GOTO(nv < INT32_MAX && nt < INT32_MAX, ctx, FASCIA_ERR_MEMORY, "organ '%s': mesh '%s' is too large",
                  def->name, def->mesh_path);
  o->vertices = prep_calloc(3 * nv, sizeof(double));
  o->triangles = prep_calloc(3 * nt, sizeof(int32_t));
  o->triangle_part = prep_calloc(nt, sizeof(int32_t));
  PREP_CHECK_GOTO(o->vertices && o->triangles && o->triangle_part, ctx, FASCIA_ERR_MEMORY,
                  "organ '%s': out of memory for %lld triangles", def->name, (long long)nt);
  for (int32_t p = 0; p < P; ++p) {
    if (!use[p]) continue;
    const int32_t v0 = f->vertex_offset[p], v1 = f->vertex_offset[p + 1];
    const int32_t base = o->vertex_count;
    for (int32_t v = v0; v < v1; ++v) {
      const double *x = f->vertices + 3 * (int64_t)v;
      double *y = o->vertices + 3 * (int64_t)o->vertex_count;
      for (int r = 0; r < 3; ++r) {
        PREP_CHECK_GOTO(isfinite(x[r]), ctx, FASCIA_ERR_FORMAT,
                        "organ '%s': mesh '%s' part '%s' vertex %d has a non-finite coordinate (%g); repair the file",
                        def->name, def->mesh_path, f->node_names[p], (int)(v - v0), x[r]);
      }
      for (int r = 0; r < 3; ++r) {
        const double *row = def->transform + 4 * r;
        y[r] = row[0] * def->scale * x[0] + row[1] * def->scale * x[1] + row[2] * def->scale * x[2] + row[3];
      }
      o->vertex_count++;
    }
    for (int32_t t = f->triangle_offset[p]; t < f->triangle_offset[p + 1]; ++t) {
      for (int r = 0; r < 3; ++r)
        o->triangles[3 * (int64_t)o->triangle_count + r] = base + (f->triangles[3 * (int64_t)t + r] - v0);
      o->triangle_part[o->triangle_count++] = use[p] - 1;
    }
  }
cleanup:
  free(use);
  return status;
}

// The mesh file: a regular file (a directory, FIFO or device is refused
// before any read), complete where its format can tell, hashed, then read.
static fascia_status check_and_read(fascia_ctx *ctx, const char *path, char sha256[65], fascia_assimp_file **file) {
  FILE *f;
  int64_t size;
  PREP_TRY(prep_open_regular(ctx, path, "mesh", &f, &size));
  const fascia_status status = prep_mesh_precheck(ctx, path, f, size);
  fclose(f);
  PREP_TRY(status);
  PREP_TRY(fascia_prep_file_sha256(ctx, path, sha256));
  return fascia_assimp_read(ctx, path, file);
}

fascia_status fascia_prep_import(fascia_ctx *ctx, const fascia_prep_scene *scene, fascia_prep_meshes **out) {
  PREP_CHECK(ctx && scene && out, ctx, FASCIA_ERR_ARGUMENT, "fascia_prep_import: NULL argument");
  *out = NULL;
  fascia_status status = FASCIA_OK;
  fascia_assimp_file *file = NULL;
  fascia_prep_meshes *m = calloc(1, sizeof *m);
  PREP_CHECK(m, ctx, FASCIA_ERR_MEMORY, "import: out of memory");
  m->organs = prep_calloc(scene->organ_count, sizeof *m->organs);
  PREP_CHECK_GOTO(m->organs, ctx, FASCIA_ERR_MEMORY, "import: out of memory");
  m->count = scene->organ_count;
  for (int32_t k = 0; k < scene->organ_count; ++k) {
    const fascia_prep_organ_def *def = scene->organs + k;
    fascia_prep_mesh *o = m->organs + k;
    snprintf(o->name, sizeof o->name, "%s", def->name);
    if (def->label_count) continue; // made of labels: below, all from one read of the label map
    char detail[160];
    snprintf(detail, sizeof detail, "%s (%s)", def->name, def->mesh);
    fascia_ctx_progress(ctx, "import", (double)k / scene->organ_count, detail);
    status = check_and_read(ctx, def->mesh_path, o->sha256, &file);
    if (status != FASCIA_OK) {
      char reason[1024];
      snprintf(reason, sizeof reason, "%s", fascia_ctx_message(ctx));
      PREP_FAIL(ctx, status, "organ '%s' (scene '%s' organs[%d].mesh): %s", def->name, scene->path, (int)k, reason);
      goto cleanup;
    }
    PREP_TRY_GOTO(pick_parts(ctx, scene->path, def, file, k, o));
    fascia_assimp_free(&file);
    prep_mesh_bounds(o);
    o->report.parts_used = o->part_count;
  }
  // the sheets' surfaces, read and placed as an organ's
  m->sheets = prep_calloc(scene->tissue_count, sizeof *m->sheets);
  PREP_CHECK_GOTO(m->sheets, ctx, FASCIA_ERR_MEMORY, "import: out of memory");
  m->sheet_slots = scene->tissue_count;
  for (int32_t t = 0; t < scene->tissue_count; ++t) {
    const fascia_prep_tissue_def *td = scene->tissues + t;
    if (td->form != FASCIA_PREP_FORM_SHEET) continue;
    fascia_prep_mesh *o = m->sheets + t;
    snprintf(o->name, sizeof o->name, "%s", td->name);
    fascia_ctx_progress(ctx, "import", 1, td->name);
    status = check_and_read(ctx, td->mesh_path, o->sha256, &file);
    if (status != FASCIA_OK) {
      char reason[1024];
      snprintf(reason, sizeof reason, "%s", fascia_ctx_message(ctx));
      PREP_FAIL(ctx, status, "scene '%s' tissues[%d].mesh: %s", scene->path, (int)t, reason);
      goto cleanup;
    }
    PREP_CHECK_GOTO(file->part_count > 0 && file->triangle_offset[file->part_count] > 0, ctx, FASCIA_ERR_FORMAT,
                    "scene '%s' tissues[%d].mesh: '%s' has no triangles (%d points or lines skipped); a sheet needs "
                    "a triangulated surface",
                    scene->path, (int)t, td->mesh_path, (int)file->skipped_primitives);
    fascia_prep_organ_def def;
    memset(&def, 0, sizeof def);
    snprintf(def.name, sizeof def.name, "%s", td->name);
    def.mesh_path = td->mesh_path;
    def.scale = td->mesh_scale;
    memcpy(def.transform, td->mesh_transform, sizeof def.transform);
    PREP_TRY_GOTO(pick_parts(ctx, scene->path, &def, file, t, o));
    fascia_assimp_free(&file);
    PREP_TRY_GOTO(prep_sheet_prepare(ctx, scene, t, o));
  }
  PREP_TRY_GOTO(prep_label_organs(ctx, scene, m));
  PREP_TRY_GOTO(prep_check_magnitudes(ctx, scene, m));
  fascia_ctx_progress(ctx, "import", 1, "done");
  *out = m;
  m = NULL;
cleanup:
  fascia_assimp_free(&file);
  fascia_prep_meshes_destroy(&m);
  return status;
}
