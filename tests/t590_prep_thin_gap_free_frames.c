// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A tissue across a gap thinner than its frame spacing keeps free frames:
// two 30 x 30 mm faces 2 to 6 mm apart, 1 mm voxels, frames every 10 mm,
// samples every 1 mm (a gap gets mid-layer frames from two sample spacings
// up; a thinner one is held by its faces, tests/t586).
// No voxel of such a gap is farther than the coupling tolerance plus a voxel
// from an organ, so without its mid-layer every frame would lie on a box and
// move with it, and nothing would be simulated. Each gap must have free
// frames between the faces, each on the gap's mid-layer (within a voxel of
// the middle, at least a voxel from both faces), and a static solve with
// box B pulled must iterate and move them. `fascia prep --json` reports the
// tissue's form, its free frames (and how many are mid-layer frames) and
// its shared frames per organ; a third box that the tissue touches but does
// not connect is reported, coupled by default and left free under
// "coupling": {"others": false}. Frames coarser than half the layer warn
// that the forces converge slowly (where ν >= 0.3), in the text and --json.
// Usage: t590_prep_thin_gap_free_frames PATH/TO/fascia
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <cjson/cJSON.h>
#include <math.h>

#include "check.h"
#include "cli_exec.h"
#include "prep_fixture.h"

#define W 0.015 // half the boxes' width, m

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 1,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": %g}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"prescribed\", \"motion\": {\"pivot\": [0, 0, 0], \"keys\": [\n"
    "                {\"time\": 0}, {\"time\": 1, \"translation\": [0, 0.0005, 0]}]}}%s],\n"
    " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008, \"material\": \"soft\",\n"
    "  \"frame_spacing\": %g, \"sample_spacing\": 0.001%s}]}\n";

// The gap's free frames: count, and how many lie off its mid-layer.
static int check_gap(const char *dir, double gap) {
  const double a_lo[3] = {-gap / 2 - 0.01, -W, -W}, a_hi[3] = {-gap / 2, W, W};
  const double b_lo[3] = {gap / 2, -W, -W}, b_hi[3] = {gap / 2 + 0.01, W, W};
  char text[2048], path[512];
  snprintf(text, sizeof text, scene_format, 0.3, "", 0.01, "");
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && fixture_box(dir, "b.obj", b_lo, b_hi));
  CHECK(fixture_write(dir, "scene.json", text));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep(ctx, path, &r);
  CHECK(st == FASCIA_OK);
  int free_frames = 0, off_layer = 0, moved = 0, iterations = 0;
  if (st == FASCIA_OK) {
    const fascia_model *m = r.model;
    for (int32_t i = 0; i < m->frame_count; ++i) { // free frames between the faces (not around their edges)
      const double *x = m->frame_position + 3 * i;
      if (m->frame_kind[i] != FASCIA_FRAME_FREE || fabs(x[1]) >= W || fabs(x[2]) >= W) continue;
      ++free_frames;
      const int off = fabs(x[0]) > 0.001 + 1e-9 || gap / 2 - fabs(x[0]) < 0.001 - 1e-9;
      if (off) fprintf(stderr, "  free frame off the mid-layer at %g %g %g mm\n", 1e3 * x[0], 1e3 * x[1], 1e3 * x[2]);
      off_layer += off;
    }
    fascia_solver_def def = fascia_solver_def_default();
    def.backend = "cpu";
    def.threads = 1;
    def.newton_iterations = 100;
    fascia_solver *solver = NULL;
    CHECK(fascia_solver_create(ctx, m, &def, &solver) == FASCIA_OK);
    fascia_solve_report report;
    CHECK(solver && fascia_solver_set_time(solver, 1) == FASCIA_OK);
    CHECK(solver && fascia_solver_solve_static(solver, &report) == FASCIA_OK);
    iterations = report.newton_iterations;
    const fascia_real *x = solver ? fascia_solver_frame_positions(solver) : NULL;
    for (int32_t i = 0; x && i < m->frame_count; ++i)
      moved += m->frame_kind[i] == FASCIA_FRAME_FREE && fabs(x[3 * i + 1] - m->frame_position[3 * i + 1]) > 1e-6;
    fascia_solver_destroy(&solver);
  }
  if (free_frames == 0 || off_layer || iterations == 0 || moved == 0)
    fprintf(stderr, "gap %g mm: %d free frames, %d off the mid-layer, %d Newton iterations, %d moved\n", 1e3 * gap,
            free_frames, off_layer, iterations, moved);
  CHECK(free_frames > 0 && off_layer == 0 && iterations > 0 && moved > 0);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return free_frames;
}

// The scene `text` written to dir/name, prepared by `fascia prep --json`:
// its report (to cJSON_Delete; NULL when it failed), the run in *result.
static cJSON *prep_json(const char *cli, const char *dir, const char *name, const char *text, cli_result *result) {
  char args[2048], err[600];
  CHECK(fixture_write(dir, name, text));
  snprintf(args, sizeof args, "prep '%s/%s' -o '%s/m3.h5' --json", dir, name, dir);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  const int ran = cli_exec(cli, args, err, result) && result->status == 0;
  CHECK(ran);
  return ran ? cJSON_Parse(result->out) : NULL;
}

// --json of a scene with a third box C against the gap's open side: the
// tissue touches C; "others" (NULL: the default) decides whether it couples.
static void check_report(const char *cli, const char *dir, const char *others) {
  const double c_lo[3] = {-0.005, W + 0.0002, -0.005}, c_hi[3] = {0.005, W + 0.01, 0.005};
  CHECK(fixture_box(dir, "c.obj", c_lo, c_hi));
  char text[2048], extra[256] = "";
  if (others) snprintf(extra, sizeof extra, ", \"coupling\": {\"others\": %s}", others);
  snprintf(text, sizeof text, scene_format, 0.3,
           ",\n              {\"name\": \"C\", \"mesh\": \"c.obj\", \"model\": \"fixed\"}", 0.01, extra);
  cli_result result;
  cJSON *root = prep_json(cli, dir, "scene3.json", text, &result);
  const cJSON *tissue = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "tissues"), 0);
  const cJSON *form = cJSON_GetObjectItem(tissue, "form"), *free_frames = cJSON_GetObjectItem(tissue, "free_frames");
  const cJSON *mid_layer = cJSON_GetObjectItem(tissue, "mid_layer_frames");
  const cJSON *shared = cJSON_GetObjectItem(tissue, "shared_frames");
  const cJSON *touched = cJSON_GetObjectItem(cJSON_GetObjectItem(tissue, "touches_unconnected"), "C");
  const int coupled = !others || !strcmp(others, "true");
  const double c_shared = cJSON_GetNumberValue(cJSON_GetObjectItem(touched, "shared_frames"));
  const double c_free = cJSON_GetNumberValue(cJSON_GetObjectItem(touched, "free_frames"));
  const int ok = cJSON_IsString(form) && !strcmp(form->valuestring, "volume") && cJSON_IsNumber(free_frames) &&
                 free_frames->valueint > 0 && cJSON_IsNumber(mid_layer) && mid_layer->valueint > 0 &&
                 mid_layer->valueint <= free_frames->valueint && strstr(result.err, "on the mid-layers") &&
                 cJSON_GetNumberValue(cJSON_GetObjectItem(shared, "A")) > 0 &&
                 cJSON_GetNumberValue(cJSON_GetObjectItem(shared, "B")) > 0 && cJSON_IsObject(touched) &&
                 (coupled ? c_shared > 0 && c_free == 0 && cJSON_GetNumberValue(cJSON_GetObjectItem(shared, "C")) > 0
                          : c_shared == 0 && c_free > 0 && !cJSON_GetObjectItem(shared, "C")) &&
                 strstr(result.err, "also touches 'C'") != NULL;
  if (!ok) fprintf(stderr, "others %s: %.900s\nstderr: %.600s\n", others ? others : "(default)", result.out, result.err);
  CHECK(ok);
  cJSON_Delete(root);
}

// The 6 mm gap (layers about 6 mm thick, its mean depth a quarter of that
// and more around the boxes' edges) at Poisson ratio nu with frames
// `spacing` apart: prep warns, in its text and its --json, that the frames
// are coarser than half a layer exactly when they are and nu is 0.3 or more.
static void check_coarse_frames(const char *cli, const char *dir, double nu, double spacing, int expected) {
  char text[2048];
  snprintf(text, sizeof text, scene_format, nu, "", spacing, "");
  cli_result result;
  cJSON *root = prep_json(cli, dir, "scene.json", text, &result);
  const cJSON *w;
  int in_json = 0;
  cJSON_ArrayForEach(w, cJSON_GetObjectItem(root, "warnings")) in_json += cJSON_IsString(w) &&
                                                                          strstr(w->valuestring, "half a layer apart");
  const int in_text = strstr(result.err, "warning: tissue 'gap': frames") != NULL;
  if (in_json != expected || in_text != expected)
    fprintf(stderr, "nu %g, frames %g mm: warned %d times in --json, %d in the text (expected %d)\n%.900s\n", nu,
            1e3 * spacing, in_json, in_text, expected, result.err);
  CHECK(in_json == expected && in_text == expected);
  cJSON_Delete(root);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t590_prep_thin_gap_free_frames PATH/TO/fascia\n");
    return 1;
  }
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  static const double gaps[] = {0.002, 0.003, 0.004, 0.006};
  for (size_t k = 0; k < sizeof gaps / sizeof gaps[0]; ++k) check_gap(dir, gaps[k]);
  check_report(argv[1], dir, NULL);
  check_report(argv[1], dir, "false");
  check_coarse_frames(argv[1], dir, 0.3, 0.01, 1);
  check_coarse_frames(argv[1], dir, 0.2, 0.01, 0);
  check_coarse_frames(argv[1], dir, 0.3, 0.0025, 0);
  static const char *const files[] = {"a.obj", "b.obj", "c.obj", "scene.json", "scene3.json", "m3.h5", "stderr.txt",
                                      NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
