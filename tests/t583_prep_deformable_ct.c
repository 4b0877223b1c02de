// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A deformable organ inside a multi-organ tissue from real CT anatomy
// converges: the shipped TotalSegmentator abdomen with its spleen made
// deformable (frames 10 mm, samples 5 mm, E 10 kPa: a soft organ whose
// Newton solves are hard to converge) between three tissues.
// The static solve and five steps of 0.01 s must converge, in a bounded
// number of Newton iterations and with a bounded strain.
// Usage: t583_prep_deformable_ct PATH/TO/data/scenes/abdomen-totalsegmentator.json
#define _XOPEN_SOURCE 700 // mkdtemp, realpath
#include <cjson/cJSON.h>
#include <limits.h>
#include <stdlib.h>

#include "check.h"
#include "prep_fixture.h"

// The shipped scene with the spleen deformable, written into a temporary
// folder; 0 on failure.
static int write_scene(const char *shipped, char *out, size_t size) {
  char text[1 << 16];
  FILE *f = fopen(shipped, "rb");
  if (!f) return 0;
  const size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  text[n] = 0;
  cJSON *scene = cJSON_Parse(text);
  if (!scene) return 0;
  // the label map's path is relative to the shipped scene's folder
  char folder[4096];
  if (!realpath(shipped, folder)) return 0;
  char *slash = strrchr(folder, '/');
  if (slash) *slash = 0;
  cJSON *seg = cJSON_GetObjectItem(scene, "segmentation");
  char file[8192];
  snprintf(file, sizeof file, "%s/%s", slash ? folder : ".", cJSON_GetObjectItem(seg, "file")->valuestring);
  cJSON_ReplaceItemInObject(seg, "file", cJSON_CreateString(file));
  cJSON *spleen_material = cJSON_CreateObject();
  cJSON_AddStringToObject(spleen_material, "law", "neohookean");
  cJSON_AddNumberToObject(spleen_material, "youngs_modulus", 10000);
  cJSON_AddNumberToObject(spleen_material, "poisson_ratio", 0.4);
  cJSON_AddNumberToObject(spleen_material, "density", 1050);
  cJSON_AddItemToObject(cJSON_GetObjectItem(scene, "materials"), "spleen", spleen_material);
  int found = 0;
  cJSON *organ;
  cJSON_ArrayForEach(organ, cJSON_GetObjectItem(scene, "organs")) {
    if (strcmp(cJSON_GetObjectItem(organ, "name")->valuestring, "spleen")) continue;
    cJSON_ReplaceItemInObject(organ, "model", cJSON_CreateString("deformable"));
    cJSON_AddStringToObject(organ, "material", "spleen");
    cJSON_AddNumberToObject(organ, "frame_spacing", 0.010);
    cJSON_AddNumberToObject(organ, "sample_spacing", 0.005);
    found = 1;
  }
  char dir_template[] = "/tmp/t583-XXXXXX";
  const char *dir = mkdtemp(dir_template);
  char *printed = cJSON_Print(scene);
  cJSON_Delete(scene);
  if (!found || !dir || !printed) return free(printed), 0;
  snprintf(out, size, "%s/abdomen-deformable-spleen.json", dir);
  f = fopen(out, "wb");
  const int ok = f && fputs(printed, f) >= 0;
  if (f) fclose(f);
  free(printed);
  return ok;
}

int main(int argc, char **argv) {
  CHECK(argc > 1);
  char path[1024];
  CHECK(write_scene(argv[1], path, sizeof path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  CHECK_OK(fixture_prep(ctx, path, &r), ctx);
  const fascia_model *m = r.model;
  int32_t spleen = -1, free_frames = 0;
  for (int32_t o = 0; o < m->organ_count; ++o)
    if (!strcmp(m->organs[o].name, "spleen")) spleen = o;
  CHECK(spleen >= 0 && m->organs[spleen].kind == FASCIA_ORGAN_DEFORMABLE);
  for (int32_t i = 0; i < m->frame_count; ++i) free_frames += m->frame_kind[i] == FASCIA_FRAME_FREE;
  printf("model: %d frames (%d free), %d samples\n", (int)m->frame_count, (int)free_frames, (int)m->sample_count);
  fascia_solver_def sd = fascia_solver_def_default();
  sd.time_step = 0.01;
  fascia_solver *s = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  fascia_solve_report rep;
  CHECK_OK(fascia_solver_solve_static(s, &rep), ctx);
  printf("static: converged %d in %d Newton iterations\n", rep.converged, rep.newton_iterations);
  CHECK(rep.converged && rep.newton_iterations <= 100);
  fascia_solver_destroy(&s);
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &s), ctx);
  int converged = 0, newton = 0;
  for (int n = 0; n < 5; ++n) {
    CHECK_OK(fascia_solver_step(s, &rep), ctx);
    converged += rep.converged != 0;
    newton += rep.newton_iterations;
  }
  fascia_real *strain = malloc((size_t)m->sample_count * sizeof *strain);
  fascia_solver_sample_strain(s, strain, NULL);
  double largest = 0;
  for (int32_t k = 0; k < m->sample_count; ++k) largest = strain[k] > largest ? strain[k] : largest;
  printf("dynamic, dt 0.01 s: %d of 5 steps converged, %d Newton iterations, largest strain %.3g\n", converged,
         newton, largest);
  CHECK(converged == 5 && newton <= 5 * 10 && largest < 2);
  free(strain);
  fascia_solver_destroy(&s);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
