// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A bonded layer thinner than its sample spacing is held by its faces: two
// boxes with 60 x 60 mm faces 1.5 mm apart, the tissue between them, box B
// slid 0.1 mm along the faces. Small-strain theory gives the force on B:
// shear modulus x face area x slide / gap, G A u / g, plus the rim of
// tissue around the faces' edges (a few per cent here). The force must lie
// within 8 % above and 2 % below G A u / g at frame spacings of 10 and 5 mm,
// and the two must agree within 2 %. With face frames a frame spacing apart
// and free frames on the mid-layer, the free frames sheared the layer at a
// fifth of its energy (0.19 G A u / g), softer still as the spacing shrank.
// prep reports the held volume (--json held_layer_volume, about A g) and
// neither the no-free-frame warning nor the coarse-frames one (its force
// does not depend on the frame spacing) for such a tissue.
// Usage: t586_prep_held_thin_layer PATH/TO/fascia
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <cjson/cJSON.h>
#include <math.h>

#include "check.h"
#include "cli_exec.h"
#include "prep_fixture.h"

#define W 0.03      // half the faces' width, m
#define GAP 0.0015  // m
#define SLIDE 1e-4  // m, along z
#define E 3000.0    // Pa
#define NU 0.3

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.0005, \"seed\": 1, \"gravity\": [0, 0, 0],\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": %g, \"poisson_ratio\": %g}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"prescribed\", \"motion\": {\"pivot\": [0, 0, 0],"
    " \"keys\": [{\"time\": 0}, {\"time\": 1, \"translation\": [0, 0, %g]}]}}],\n"
    " \"tissues\": [{\"name\": \"layer\", \"connects\": [\"A\", \"B\"], \"max_gap\": %g, \"material\": \"soft\",\n"
    "  \"frame_spacing\": %g, \"sample_spacing\": 0.002}]}\n";

// The static force of the layer on B along the slide, N.
static double slide_force(const char *dir, double frame_spacing) {
  char text[2048], path[512];
  snprintf(text, sizeof text, scene_format, E, NU, SLIDE, 1.05 * GAP, frame_spacing);
  CHECK(fixture_write(dir, "scene.json", text));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  double force = NAN;
  CHECK(fixture_prep(ctx, path, &r) == FASCIA_OK);
  if (r.model) {
    fascia_solver_def def = fascia_solver_def_default();
    def.backend = "cpu";
    def.threads = 1;
    fascia_solver *solver = NULL;
    fascia_solve_report report;
    CHECK(fascia_solver_create(ctx, r.model, &def, &solver) == FASCIA_OK);
    CHECK(solver && fascia_solver_set_time(solver, 1) == FASCIA_OK);
    CHECK(solver && fascia_solver_solve_static(solver, &report) == FASCIA_OK);
    fascia_real f[3];
    if (solver && fascia_solver_organ_wrench(solver, fascia_model_find_organ(r.model, "B"), f, NULL, NULL) ==
                      FASCIA_OK)
      force = -f[2];
    fascia_solver_destroy(&solver);
  }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return force;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t586_prep_held_thin_layer PATH/TO/fascia\n");
    return 1;
  }
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  const double a_lo[3] = {-GAP / 2 - 0.01, -W, -W}, a_hi[3] = {-GAP / 2, W, W};
  const double b_lo[3] = {GAP / 2, -W, -W}, b_hi[3] = {GAP / 2 + 0.01, W, W};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && fixture_box(dir, "b.obj", b_lo, b_hi));
  const double theory = E / (2 * (1 + NU)) * (2 * W) * (2 * W) * SLIDE / GAP;
  const double coarse = slide_force(dir, 0.01), fine = slide_force(dir, 0.005);
  fprintf(stderr, "force on B: %.4g N at 10 mm frames, %.4g N at 5 mm; G A u / g = %.4g N\n", coarse, fine, theory);
  CHECK(coarse > 0.98 * theory && coarse < 1.08 * theory);
  CHECK(fine > 0.98 * theory && fine < 1.08 * theory);
  CHECK(fabs(fine - coarse) < 0.02 * coarse);

  // the report: the held volume, and no warning that nothing is simulated
  char args[1024], err[600];
  snprintf(args, sizeof args, "prep '%s/scene.json' -o '%s/m.h5' --json", dir, dir);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  cli_result result;
  CHECK(cli_exec(argv[1], args, err, &result) && result.status == 0);
  cJSON *root = cJSON_Parse(result.out);
  const cJSON *tissue = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "tissues"), 0);
  const double held = cJSON_GetNumberValue(cJSON_GetObjectItem(tissue, "held_layer_volume"));
  const double layer = (2 * W) * (2 * W) * GAP;
  fprintf(stderr, "held layer %.4g cm^3 (faces x gap %.4g cm^3)\n", 1e6 * held, 1e6 * layer);
  CHECK(held > 0.9 * layer && held < 1.2 * layer);
  const cJSON *warning;
  cJSON_ArrayForEach(warning, cJSON_GetObjectItem(root, "warnings")) {
    CHECK(!cJSON_IsString(warning) || !strstr(warning->valuestring, "no free frame"));
    CHECK(!cJSON_IsString(warning) || !strstr(warning->valuestring, "half a layer"));
  }
  CHECK(strstr(result.err, "layers held by frames on both faces") != NULL);
  cJSON_Delete(root);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", "m.h5", "stderr.txt", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
