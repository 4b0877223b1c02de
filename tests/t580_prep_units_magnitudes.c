// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Lengths off anatomy's sizes by a factor of 10 to 1000 through `fascia prep`
// (the CLI, argv[1]): every message says that the units look wrong and names
// the scene file. Two boxes 40 x 30 x 30 mm, 6 mm apart, box B prescribed:
//   refused (one line, no model written): box A's mesh in millimetres with
//   "units" left out (40 m across: "units": "mm" suggested); box A's metre
//   mesh read as millimetres (0.04 mm: "units": "m" suggested); voxel_size 1
//   typed for 1 mm; a motion of 3 m typed for 3 mm;
//   warned about: max_gap 8 typed for 8 mm (before the error about the
//   grid it makes); a motion of 9 cm, 11 times max_gap (the model is built,
//   the warning is in the text and in --json);
//   a sane scene has no warning.
#define _POSIX_C_SOURCE 200809L // mkdtemp, popen, WEXITSTATUS
#include <cjson/cJSON.h>

#include "cli_exec.h"
#include "prep_cli_case.h"

static const char *cli;
static char dir[256], scene_path[512];
static cli_result result;

// The scene: voxel_size, box A's mesh and "units" (NULL: left out), max_gap,
// and box B's motion to (0, lift, 0) in 1 s.
static int write_scene(const char *voxel_size, const char *mesh_a, const char *units_a, const char *max_gap,
                       const char *lift) {
  char text[4096], units[64] = "";
  if (units_a) snprintf(units, sizeof units, ", \"units\": \"%s\"", units_a);
  snprintf(text, sizeof text,
           "{\"fascia_scene\": 1, \"voxel_size\": %s,\n"
           " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
           " \"organs\": [{\"name\": \"A\", \"mesh\": \"%s\"%s},\n"
           "            {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"prescribed\", \"motion\": {\"pivot\": "
           "[0, 0, 0],\n"
           "             \"keys\": [{\"time\": 0}, {\"time\": 1, \"translation\": [0, %s, 0]}]}}],\n"
           " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": %s,\n"
           "  \"material\": \"soft\", \"frame_spacing\": 0.0025, \"sample_spacing\": 0.001}]}\n",
           voxel_size, mesh_a, units, lift, max_gap);
  return fixture_write(dir, "scene.json", text);
}

// Refused in one line naming the scene file, holding e1 and e2.
static void refused(const char *name, const char *e1, const char *e2) {
  prep_case_refused(cli, dir, name, scene_path, (const char *const[]){"scene.json", "units look wrong", e1, e2, NULL});
}

// fascia prep --json; its warnings array (owned by *root), NULL on failure.
static const cJSON *prep_warnings(cJSON **root) {
  char args[1024], err[512];
  snprintf(args, sizeof args, "prep '%s' -o '%s/model.h5' --json", scene_path, dir);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  *root = NULL;
  if (!cli_exec(cli, args, err, &result) || result.status != 0) {
    fprintf(stderr, "fascia %s: status %d\n%s\n", args, result.status, result.err);
    return NULL;
  }
  *root = cJSON_Parse(result.out);
  return cJSON_GetObjectItem(*root, "warnings");
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t580_prep_units_magnitudes PATH_TO_FASCIA\n");
    return 1;
  }
  cli = argv[1];
  if (!fixture_tmpdir(dir)) return 1;
  snprintf(scene_path, sizeof scene_path, "%s/scene.json", dir);
  const double a_lo[3] = {-0.043, -0.015, -0.015}, a_hi[3] = {-0.003, 0.015, 0.015};
  const double b_lo[3] = {0.003, -0.015, -0.015}, b_hi[3] = {0.043, 0.015, 0.015};
  const double a_lo_mm[3] = {-43, -15, -15}, a_hi_mm[3] = {-3, 15, 15};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && fixture_box(dir, "b.obj", b_lo, b_hi));
  CHECK(fixture_box(dir, "a_mm.obj", a_lo_mm, a_hi_mm));

  CHECK(write_scene("0.001", "a_mm.obj", NULL, "0.008", "0.003"));
  refused("millimetre mesh, units left out", "40 x 30 x 30 m, larger than a body (3 m)",
          "organs[0].units left out), and every length of the scene is metres; if the file is in millimetres, set "
          "\"units\": \"mm\" (the organ is then 4 cm across)");
  CHECK(write_scene("0.001", "a.obj", "mm", "0.008", "0.003"));
  refused("metre mesh read as millimetres", "0.04 x 0.03 x 0.03 mm",
          "(organs[0].units \"mm\"), and every length of the scene is metres; if the file is in metres, set "
          "\"units\": \"m\" (the organ is then 4 cm across)");
  CHECK(write_scene("1", "a.obj", NULL, "0.008", "0.003"));
  refused("voxel_size in millimetres", "voxel_size 1 m is coarser than any gap", "a voxel of 1 mm is 0.001");
  CHECK(write_scene("0.001", "a.obj", NULL, "0.008", "3"));
  refused("a motion of 3 m", "organs[1].motion): it moves the organ up to 3 m, more than the whole scene is across",
          "3 mm is 0.003");

  // max_gap 8 m: warned about, then the grid it needs is refused
  CHECK(write_scene("0.001", "a.obj", NULL, "8", "0.003"));
  char args[1024], err[512];
  snprintf(args, sizeof args, "prep '%s' -o '%s/model.h5'", scene_path, dir);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  CHECK(cli_exec(cli, args, err, &result) && result.status == 1);
  CHECK(strstr(result.err, "warning: tissue 'gap' (scene '") && strstr(result.err, "scene.json' tissues[0].max_gap): 8 m"));
  CHECK(strstr(result.err, "units look wrong") && strstr(result.err, "if 8 mm is meant, write 0.008"));
  CHECK(strstr(result.err, "the box is larger than a body"));
  if (CHECK_RESULT()) fprintf(stderr, "max_gap 8 m:\n%s\n", result.err);

  // a motion of 9 cm: built, with a warning
  CHECK(write_scene("0.001", "a.obj", NULL, "0.008", "0.09"));
  cJSON *root;
  const cJSON *warnings = prep_warnings(&root);
  CHECK(cJSON_GetArraySize(warnings) == 1);
  const cJSON *w = cJSON_GetArrayItem(warnings, 0);
  CHECK(cJSON_IsString(w) && strstr(w->valuestring, "organs[1].motion") && strstr(w->valuestring, "up to 90 mm") &&
        strstr(w->valuestring, "units look wrong"));
  CHECK(strstr(result.err, "warning: organ 'B' (scene '"));
  cJSON_Delete(root);

  // a sane scene: no warning
  CHECK(write_scene("0.001", "a.obj", NULL, "0.008", "0.003"));
  warnings = prep_warnings(&root);
  CHECK(cJSON_IsArray(warnings) && cJSON_GetArraySize(warnings) == 0);
  CHECK(!strstr(result.err, "warning"));
  if (strstr(result.err, "warning")) fprintf(stderr, "the sane scene:\n%s\n", result.err);
  cJSON_Delete(root);

  static const char *const files[] = {"a.obj", "b.obj", "a_mm.obj", "scene.json", "model.h5", "stderr.txt", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
