// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The text summary of `fascia prep` (the CLI, argv[1]) for a scene with a
// deformable organ (two boxes 6 mm apart, B deformable): its "tissue volume"
// is the tissue's alone, the volume of the tissue samples in the model file
// (the deformable organ's is given beside it), and a line gives the organ's
// own voxels, frames, shared frames and samples as the model's provenance
// and the organ's samples in the model count them; with B a shell, its line
// gives the wall's thickness and area, not voxels.
#define _POSIX_C_SOURCE 200809L // mkdtemp, popen
#include <cjson/cJSON.h>
#include <math.h>

#include "check.h"
#include "cli_exec.h"
#include "prep_fixture.h"

static const char scene[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 3,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 10000, \"poisson_ratio\": 0.3},\n"
    "               \"organ\": {\"youngs_modulus\": 30000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\"},\n"
    "  {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"deformable\", \"material\": \"organ\",\n"
    "   \"frame_spacing\": 0.006, \"sample_spacing\": 0.003}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008,\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.004, \"sample_spacing\": 0.002}]}\n";

// B a shell instead (a ball of radius 10 mm 3 mm from A): its line gives the
// wall, not voxels
static const char shell_scene[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 3,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 10000, \"poisson_ratio\": 0.3},\n"
    "               \"organ\": {\"youngs_modulus\": 30000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\"},\n"
    "  {\"name\": \"B\", \"mesh\": \"ball.obj\", \"model\": \"shell\", \"material\": \"organ\",\n"
    "   \"thickness\": 0.001, \"frame_spacing\": 0.004}],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008,\n"
    "  \"material\": \"soft\", \"frame_spacing\": 0.004, \"sample_spacing\": 0.002}]}\n";

static cli_result result;

// The shell's line: its wall's thickness and area (its samples' volume over
// the thickness, as in the model file), frames and samples.
static void check_shell_line(const char *fascia, const char *dir) {
  char path[512], args[1200], err[512], model_path[512];
  const double centre[3] = {0.013, 0, 0};
  CHECK(fixture_two_boxes(dir, 0.003, shell_scene, path) && fixture_icosphere(dir, "ball.obj", centre, 0.01, 3, 0));
  snprintf(model_path, sizeof model_path, "%s/model.h5", dir);
  snprintf(args, sizeof args, "prep '%s' -o '%s'", path, model_path);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  cli_result shell;
  CHECK(cli_exec(fascia, args, err, &shell) && shell.status == 0);
  fascia_ctx *ctx = fixture_ctx();
  fascia_model *m = NULL;
  CHECK(ctx && fascia_model_load(ctx, model_path, &m) == FASCIA_OK);
  double wall = 0;
  int32_t samples = 0;
  for (int32_t s = 0; m && s < m->sample_count; ++s)
    if (m->sample_organ[s] == 1) wall += m->sample_volume[s], ++samples;
  const char *at = strstr(shell.err, "\nshell organ 'B': ");
  double thick = -1, area = -1;
  int frames = -1, shared = -1, count = -1;
  CHECK(at && sscanf(at, "\nshell organ 'B': wall %lf mm thick, %lf cm^2; %d frames of its own and %d shared with "
                         "tissues, %d samples", &thick, &area, &frames, &shared, &count) == 5);
  CHECK(!strstr(shell.err, "deformable organ 'B'"));
  CHECK_NEAR(thick, 1, 1e-9, 0);
  CHECK_NEAR(area, 1e4 * wall / 0.001, 1e-3, 0);
  CHECK(frames > 0 && shared > 0 && count == samples);
  if (CHECK_RESULT()) fprintf(stderr, "shell summary:\n%s\n", shell.err);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t581_prep_summary_deformable PATH_TO_FASCIA\n");
    return 1;
  }
  char dir[256], path[512], args[1200], err[512], model_path[512];
  if (!fixture_tmpdir(dir)) return 1;
  CHECK(fixture_two_boxes(dir, 0.003, scene, path));
  snprintf(model_path, sizeof model_path, "%s/model.h5", dir);
  snprintf(args, sizeof args, "prep '%s' -o '%s'", path, model_path);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  CHECK(cli_exec(argv[1], args, err, &result) && result.status == 0);

  fascia_ctx *ctx = fixture_ctx();
  fascia_model *m = NULL;
  CHECK(ctx && fascia_model_load(ctx, model_path, &m) == FASCIA_OK);
  if (!m) return CHECK_RESULT();
  double tissue = 0, organ = 0;
  int32_t organ_samples = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    if (m->sample_organ[s] < 0) tissue += m->sample_volume[s];
    else organ += m->sample_volume[s], ++organ_samples;
  }
  CHECK(organ > 0 && tissue > 0);

  // model: ... tissue volume T m^3 (+ O m^3 of deformable organs), ...
  const char *line = strstr(result.err, "\nmodel: ");
  double t = -1, o = -1;
  const char *at = line ? strstr(line, "tissue volume ") : NULL;
  CHECK(at && sscanf(at, "tissue volume %lf m^3 (+ %lf m^3 of deformable organs)", &t, &o) == 2);
  CHECK(fabs(t - tissue) <= 1e-5 * tissue);
  CHECK(fabs(o - organ) <= 1e-5 * organ);

  // deformable organ 'B': V voxels of 1 mm, ... ; F frames of its own and S shared with tissues, K samples
  cJSON *prov = cJSON_Parse(m->provenance);
  const cJSON *organs = cJSON_GetObjectItem(cJSON_GetObjectItem(prov, "reports"), "organs");
  const cJSON *b = cJSON_GetArrayItem(organs, 1), *d = cJSON_GetObjectItem(b, "deformable");
  CHECK(d != NULL);
  at = strstr(result.err, "\ndeformable organ 'B': ");
  long long voxels = -1;
  int frames = -1, shared = -1, samples = -1;
  CHECK(at && sscanf(at, "\ndeformable organ 'B': %lld voxels", &voxels) == 1);
  at = at ? strstr(at, "dropped); ") : NULL;
  CHECK(at && sscanf(at, "dropped); %d frames of its own and %d shared with tissues, %d samples", &frames, &shared,
                     &samples) == 3);
  CHECK(voxels == (long long)cJSON_GetNumberValue(cJSON_GetObjectItem(d, "voxels")));
  CHECK(frames == (int)cJSON_GetNumberValue(cJSON_GetObjectItem(d, "own_frames")) && frames > 0);
  CHECK(shared == (int)cJSON_GetNumberValue(cJSON_GetObjectItem(b, "shared_frames")) && shared > 0);
  CHECK(samples == organ_samples && samples > 0);
  if (CHECK_RESULT()) fprintf(stderr, "summary:\n%s\n", result.err);
  cJSON_Delete(prov);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  check_shell_line(argv[1], dir);
  static const char *const names[] = {"a.obj", "b.obj", "ball.obj", "scene.json", "model.h5", "stderr.txt", NULL};
  fixture_cleanup(dir, names);
  return CHECK_RESULT();
}
