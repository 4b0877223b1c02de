// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Strand and sheet tissues in a scene (data/scenes/README.md, "Strands and
// sheets"). Two 20 mm boxes 20 mm apart, A fixed, B pulled 1 mm along x:
//  - a strand of radius 1 mm from A's face to B's (attachment given 0.5 mm
//    off B, moved onto it), frames every 2 mm: 11 frames, the two ends
//    shared with A and B, 9 free; samples add up to length x area; pulled,
//    its frames move as a uniform stretch (frame i by i/10 mm);
//  - a flat 5 x 5 vertex sheet from A to B, 1 mm thick: 25 frames, 5 shared
//    with each box, 15 free; volume area x thickness; its middle column
//    moves half of B's pull;
//  - every refusal is one line naming the scene key: an attachment on no
//    organ, an unknown organ, a strand through an organ, radius and area
//    both, a closed sheet mesh, a mesh without triangles, a sheet vertex
//    inside an organ, a thickness that reaches into an organ;
//  - the shipped scene (argv[2]) preps through the CLI and --json reports
//    the forms, free frames and shared frames per organ.
// Usage: t591_prep_strand_sheet PATH/TO/fascia PATH/TO/abdomen-ligaments.json
#define _POSIX_C_SOURCE 200809L // mkdtemp
#include <cjson/cJSON.h>
#include <math.h>

#include "check.h"
#include "cli_exec.h"
#include "prep_fixture.h"

#define PI 3.14159265358979323846

static const char scene_format[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"seed\": 5, \"gravity\": [0, 0, 0],\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3},\n"
    "               \"lig\": {\"youngs_modulus\": 100000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"prescribed\",\n"
    "               \"motion\": {\"pivot\": [0, 0, 0], \"keys\": [\n"
    "                {\"time\": 0}, {\"time\": 1, \"translation\": [0.001, 0, 0]}]}}%s],\n"
    " \"tissues\": [%s]}\n";

static const char strand[] =
    "{\"name\": \"lig\", \"form\": \"strand\", \"from\": {\"organ\": \"A\", \"point\": [-0.01, 0, 0]},\n"
    " \"to\": {\"organ\": \"B\", \"point\": [0.0105, 0, 0], \"radius\": 0.001}, \"radius\": 0.001,\n"
    " \"material\": \"lig\", \"frame_spacing\": 0.002}";

static const char sheet[] = "{\"name\": \"mem\", \"form\": \"sheet\", \"mesh\": \"sheet.obj\", \"thickness\": 0.001,\n"
                            " \"connects\": [\"A\", \"B\"], \"material\": \"soft\"}";

// A flat n x n grid from x = -10 to 10 mm, y = -8 to 8 mm, at z (mm).
static int write_sheet(const char *dir, const char *name, double z) {
  char text[8192] = "", line[128];
  const int n = 5;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      snprintf(line, sizeof line, "v %.6f %.6f %.6f\n", -0.01 + 0.02 * i / (n - 1), -0.008 + 0.016 * j / (n - 1),
               1e-3 * z);
      strcat(text, line);
    }
  for (int i = 0; i < n - 1; ++i)
    for (int j = 0; j < n - 1; ++j) {
      const int a = i * n + j + 1, b = (i + 1) * n + j + 1;
      snprintf(line, sizeof line, "f %d %d %d\nf %d %d %d\n", a, b, b + 1, a, b + 1, a + 1);
      strcat(text, line);
    }
  return fixture_write(dir, name, text);
}

static int write_scene(const char *dir, const char *organs, const char *tissues, char *path) {
  char text[8192];
  snprintf(text, sizeof text, scene_format, organs, tissues);
  snprintf(path, 512, "%s/scene.json", dir);
  return fixture_write(dir, "scene.json", text);
}

// Solves the model statically at t = 1 and returns the frames' x
// displacement (m) into u (model frames); 0 on failure.
static int pulled(fascia_ctx *ctx, const fascia_model *m, double *u) {
  fascia_solver_def def = fascia_solver_def_default();
  def.backend = "cpu";
  def.threads = 1;
  def.newton_iterations = 100;
  fascia_solver *solver = NULL;
  fascia_solve_report report;
  int ok = fascia_solver_create(ctx, m, &def, &solver) == FASCIA_OK && fascia_solver_set_time(solver, 1) == FASCIA_OK &&
           fascia_solver_solve_static(solver, &report) == FASCIA_OK && report.newton_iterations > 0;
  const fascia_real *x = ok ? fascia_solver_frame_positions(solver) : NULL;
  for (int32_t i = 0; x && i < m->frame_count; ++i) u[i] = x[3 * i] - m->frame_position[3 * i];
  fascia_solver_destroy(&solver);
  return ok;
}

// Frames of the model coupled to organ o.
static int coupled_to(const fascia_model *m, int32_t o) {
  int n = 0;
  for (int32_t c = 0; c < m->coupling_count; ++c) n += m->coupling_organ[c] == o;
  return n;
}

static void check_strand(const char *dir) {
  char path[512];
  CHECK(write_scene(dir, "", strand, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep(ctx, path, &r);
  if (st != FASCIA_OK) fprintf(stderr, "strand: %s\n", fascia_ctx_message(ctx));
  CHECK(st == FASCIA_OK);
  if (st == FASCIA_OK) {
    const fascia_model *m = r.model;
    double volume = 0;
    for (int32_t s = 0; s < m->sample_count; ++s) volume += m->sample_volume[s];
    const double expected = 0.02 * PI * 1e-6;
    fprintf(stderr, "strand: %d frames, %d samples, volume %.6g (length x area %.6g) m^3\n", (int)m->frame_count,
            (int)m->sample_count, volume, expected);
    CHECK(m->frame_count == 11 && m->sample_count == 40);
    CHECK(fabs(volume - expected) < 1e-6 * expected); // the boxes are read as float32
    CHECK(coupled_to(m, 0) == 1 && coupled_to(m, 1) == 1 && m->coupling_count == 2);
    int free_frames = 0;
    for (int32_t i = 0; i < m->frame_count; ++i) free_frames += m->frame_kind[i] == FASCIA_FRAME_FREE;
    CHECK(free_frames == 9);
    // drawn as a tube: an octagon of its radius around each of its 11 frames
    const fascia_surface *ts = &m->tissue_surface;
    CHECK(ts->vertex_count == 8 * 11 && ts->triangle_count == 16 * 10);
    double off_radius = 0;
    for (int32_t v = 0; v < ts->vertex_count; ++v) {
      const double *p = ts->vertices + 3 * v;
      off_radius = fmax(off_radius, fabs(sqrt(p[1] * p[1] + p[2] * p[2]) - 0.001));
    }
    CHECK(off_radius < 1e-9);
    // the end on B was given 0.5 mm off its face: moved onto it
    double largest_x = -1;
    for (int32_t i = 0; i < m->frame_count; ++i) largest_x = fmax(largest_x, m->frame_position[3 * i]);
    CHECK(fabs(largest_x - 0.01) < 1e-6);
    double u[16], worst = 0;
    CHECK(pulled(ctx, m, u));
    for (int32_t i = 0; i < m->frame_count; ++i) { // uniform stretch: u = (x + 10 mm) / 20 mm x 1 mm
      const double want = 0.001 * (m->frame_position[3 * i] + 0.01) / 0.02;
      worst = fmax(worst, fabs(u[i] - want));
    }
    fprintf(stderr, "strand pulled 1 mm: frames off a uniform stretch by %.3g mm at most\n", 1e3 * worst);
    CHECK(worst < 0.03e-3);
  }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
}

static void check_sheet(const char *dir) {
  char path[512];
  CHECK(write_sheet(dir, "sheet.obj", 5) && write_scene(dir, "", sheet, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep(ctx, path, &r);
  if (st != FASCIA_OK) fprintf(stderr, "sheet: %s\n", fascia_ctx_message(ctx));
  CHECK(st == FASCIA_OK);
  if (st == FASCIA_OK) {
    const fascia_model *m = r.model;
    double volume = 0; // a drilling stabiliser (volumetric part) repeats the volume of the others
    for (int32_t s = 0; s < m->sample_count; ++s)
      if (m->materials[m->sample_material[s]].part != FASCIA_PART_VOLUMETRIC) volume += m->sample_volume[s];
    const double expected = 0.02 * 0.016 * 0.001;
    int free_frames = 0;
    for (int32_t i = 0; i < m->frame_count; ++i) free_frames += m->frame_kind[i] == FASCIA_FRAME_FREE;
    fprintf(stderr, "sheet: %d frames (%d free), %d samples, volume %.6g (area x thickness %.6g) m^3\n",
            (int)m->frame_count, free_frames, (int)m->sample_count, volume, expected);
    CHECK(m->frame_count == 25 && free_frames == 15 && coupled_to(m, 0) == 5 && coupled_to(m, 1) == 5);
    CHECK(fabs(volume - expected) < 1e-6 * expected); // the boxes are read as float32
    // drawn as its mesh over its frames (5 x 5 vertices, 32 triangles)
    CHECK(m->tissue_surface.vertex_count == 25 && m->tissue_surface.triangle_count == 32);
    double u[32], worst = 0;
    CHECK(pulled(ctx, m, u));
    for (int32_t i = 0; i < m->frame_count; ++i)
      if (fabs(m->frame_position[3 * i]) < 1e-9) worst = fmax(worst, fabs(u[i] - 0.0005));
    fprintf(stderr, "sheet pulled 1 mm: middle column off half the pull by %.3g mm at most\n", 1e3 * worst);
    CHECK(worst < 0.05e-3);
  }
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
}

// The scene must be refused with one line holding key and what.
static void refused(const char *dir, const char *organs, const char *tissues, const char *key, const char *what) {
  char path[512];
  CHECK(write_scene(dir, organs, tissues, path));
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  const fascia_status st = fixture_prep(ctx, path, &r);
  const char *message = fascia_ctx_message(ctx);
  const int ok = st != FASCIA_OK && strstr(message, key) && strstr(message, what) && !strchr(message, '\n');
  if (!ok) fprintf(stderr, "expected a refusal naming '%s' ('%s'), got %d: %s\n", key, what, (int)st, message);
  else fprintf(stderr, "refused: %s\n", message);
  CHECK(ok);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
}

// src with its first `old` replaced by `by`, into out[size].
static const char *replaced(const char *src, const char *old, const char *by, char *out, size_t size) {
  const char *at = strstr(src, old);
  CHECK(at != NULL);
  if (!at) return src;
  snprintf(out, size, "%.*s%s%s", (int)(at - src), src, by, at + strlen(old));
  return out;
}

static void check_refusals(const char *dir) {
  char text[2048];
  // the attachment 5 mm off A, its radius the default 2 mm
  refused(dir, "", replaced(strand, "[-0.01, 0, 0]", "[-0.005, 0, 0]", text, sizeof text), "tissues[0].from",
          "lies on no organ");
  refused(dir, "", replaced(strand, "\"organ\": \"B\"", "\"organ\": \"Q\"", text, sizeof text),
          "tissues[0].to.organ", "no organ is named 'Q'");
  // to B's far face: straight through B
  refused(dir, "", replaced(strand, "[0.0105, 0, 0]", "[0.03, 0, 0]", text, sizeof text), "tissues[0]",
          "pass through organ 'B'");
  refused(dir, "", replaced(strand, "\"radius\": 0.001,\n", "\"radius\": 0.001, \"area\": 1e-6,\n", text, sizeof text),
          "tissues[0]", "either \"radius\"");
  refused(dir, "", replaced(sheet, "sheet.obj", "a.obj", text, sizeof text), "tissues[0].mesh", "closed surface");
  CHECK(fixture_write(dir, "lines.obj", "v 0 0 0\nv 0.01 0 0\nv 0.01 0.01 0\nl 1 2\nl 2 3\n"));
  refused(dir, "", replaced(sheet, "sheet.obj", "lines.obj", text, sizeof text), "tissues[0].mesh", "triangle");
  CHECK(fixture_write(dir, "inside.obj", "v -0.02 0 0\nv -0.005 0.005 0.005\nv -0.005 -0.005 0.005\nf 1 2 3\n"));
  refused(dir, "", replaced(sheet, "sheet.obj", "inside.obj", text, sizeof text), "tissues[0].mesh",
          "inside organ 'A'");
  // box C just above the sheet (3 mm over its mid-surface): 1 mm thick fits, 8 mm does not
  const double c_lo[3] = {-0.01, -0.01, 0.008}, c_hi[3] = {0.01, 0.01, 0.02};
  CHECK(fixture_box(dir, "c.obj", c_lo, c_hi) && write_sheet(dir, "sheet.obj", 5));
  refused(dir, ", {\"name\": \"C\", \"mesh\": \"c.obj\", \"model\": \"fixed\"}",
          replaced(sheet, "\"thickness\": 0.001", "\"thickness\": 0.008", text, sizeof text), "tissues[0].thickness",
          "larger than the gap");
}

// One box of an OBJ file as part `name` (o name), its vertices numbered from first + 1.
static void obj_box(char *text, size_t size, const char *name, const double *lo, const double *hi, int first) {
  size_t n = strlen(text);
  n += (size_t)snprintf(text + n, size - n, "o %s\n", name);
  for (int k = 0; k < 8; ++k)
    n += (size_t)snprintf(text + n, size - n, "v %g %g %g\n", (k & 1) ? hi[0] : lo[0], (k & 2) ? hi[1] : lo[1],
                          (k & 4) ? hi[2] : lo[2]);
  static const int faces[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                                   {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  for (int f = 0; f < 12; ++f)
    n += (size_t)snprintf(text + n, size - n, "f %d %d %d\n", first + faces[f][0] + 1, first + faces[f][1] + 1,
                          first + faces[f][2] + 1);
}

// A strand attached to a named part ends at that part's point nearest its
// other end: organ P is two boxes, parts "top" and "bottom", beside B.
static void check_part_attachment(const char *dir) {
  char text[4096] = "";
  const double top_lo[3] = {0.01, -0.005, 0.015}, top_hi[3] = {0.02, 0.005, 0.025};
  const double bottom_lo[3] = {0.01, -0.005, -0.025}, bottom_hi[3] = {0.02, 0.005, -0.015};
  obj_box(text, sizeof text, "top", top_lo, top_hi, 0);
  obj_box(text, sizeof text, "bottom", bottom_lo, bottom_hi, 8);
  CHECK(fixture_write(dir, "p.obj", text));
  static const char organ_p[] = ", {\"name\": \"P\", \"mesh\": \"p.obj\", \"model\": \"fixed\"}";
  static const char *const parts[2] = {"top", "bottom"};
  for (int k = 0; k < 2; ++k) {
    char tissue[1024], path[512];
    snprintf(tissue, sizeof tissue,
             "{\"name\": \"lig\", \"form\": \"strand\", \"from\": {\"organ\": \"A\", \"point\": [-0.01, 0, 0]},\n"
             " \"to\": {\"organ\": \"P\", \"part\": \"%s\"}, \"radius\": 0.001, \"material\": \"lig\",\n"
             " \"frame_spacing\": 0.004}",
             parts[k]);
    CHECK(write_scene(dir, organ_p, tissue, path));
    fascia_ctx *ctx = fixture_ctx();
    fixture_run r;
    const fascia_status st = fixture_prep(ctx, path, &r);
    if (st != FASCIA_OK) fprintf(stderr, "part %s: %s\n", parts[k], fascia_ctx_message(ctx));
    CHECK(st == FASCIA_OK);
    if (st == FASCIA_OK) { // the end on P: the part's edge nearest (-10, 0, 0) mm, coupled to P
      const double want[3] = {0.01, 0, k == 0 ? 0.015 : -0.015};
      double off = INFINITY;
      int on_p = 0;
      for (int32_t c = 0; c < r.model->coupling_count; ++c) {
        if (r.model->coupling_organ[c] != 2) continue;
        const double *x = r.model->frame_position + 3 * r.model->coupling_frame[c];
        off = fmin(off, sqrt((x[0] - want[0]) * (x[0] - want[0]) + (x[1] - want[1]) * (x[1] - want[1]) +
                             (x[2] - want[2]) * (x[2] - want[2])));
        ++on_p;
      }
      if (on_p != 1 || off > 1e-6) fprintf(stderr, "part %s: %d ends on P, %.3g mm off\n", parts[k], on_p, 1e3 * off);
      CHECK(on_p == 1 && off <= 1e-6);
    }
    fixture_free(&r);
    fascia_ctx_destroy(&ctx);
  }
  char text2[2048];
  static const char by_part[] =
      "{\"name\": \"lig\", \"form\": \"strand\", \"from\": {\"organ\": \"A\", \"point\": [-0.01, 0, 0]},\n"
      " \"to\": {\"organ\": \"P\", \"part\": \"top\"}, \"radius\": 0.001, \"material\": \"lig\",\n"
      " \"frame_spacing\": 0.004}";
  refused(dir, organ_p, replaced(by_part, "\"top\"", "\"side\"", text2, sizeof text2), "tissues[0].to.part",
          "no part named 'side'");
  refused(dir, organ_p, replaced(by_part, "\"part\": \"top\"", "\"part\": \"top\", \"point\": [0, 0, 0]", text2,
                                 sizeof text2),
          "tissues[0].to", "not both");
}

static void check_shipped(const char *cli, const char *dir, const char *scene) {
  char args[2048], err[512];
  snprintf(args, sizeof args, "prep '%s' -o '%s/shipped.h5' --json", scene, dir);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  cli_result result;
  CHECK(cli_exec(cli, args, err, &result) && result.status == 0);
  if (result.status != 0) fprintf(stderr, "%s", result.err);
  cJSON *root = cJSON_Parse(result.out);
  CHECK(root != NULL);
  int strands = 0, sheets = 0;
  const cJSON *t;
  cJSON_ArrayForEach(t, cJSON_GetObjectItem(root, "tissues")) {
    const char *form = cJSON_GetStringValue(cJSON_GetObjectItem(t, "form"));
    const double free_frames = cJSON_GetNumberValue(cJSON_GetObjectItem(t, "free_frames"));
    const cJSON *shared = cJSON_GetObjectItem(t, "shared_frames");
    fprintf(stderr, "shipped: tissue '%s' form %s, %g free frames\n",
            cJSON_GetStringValue(cJSON_GetObjectItem(t, "name")), form ? form : "?", free_frames);
    CHECK(form && free_frames > 0);
    if (form && !strcmp(form, "strand")) {
      ++strands;
      // its ends spread over their areas (a fan of frames on each organ)
      CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(shared, "spleen")) >= 3 &&
            cJSON_GetNumberValue(cJSON_GetObjectItem(shared, "kidney")) >= 3);
    }
    if (form && !strcmp(form, "sheet")) {
      ++sheets;
      CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(shared, "liver")) > 0 &&
            cJSON_GetNumberValue(cJSON_GetObjectItem(shared, "colon")) > 0);
    }
  }
  CHECK(strands == 1 && sheets == 1);
  cJSON_Delete(root);
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: t591_prep_strand_sheet PATH/TO/fascia PATH/TO/abdomen-ligaments.json\n");
    return 1;
  }
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  const double a_lo[3] = {-0.03, -0.01, -0.01}, a_hi[3] = {-0.01, 0.01, 0.01};
  const double b_lo[3] = {0.01, -0.01, -0.01}, b_hi[3] = {0.03, 0.01, 0.01};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && fixture_box(dir, "b.obj", b_lo, b_hi));
  check_strand(dir);
  check_sheet(dir);
  check_refusals(dir);
  check_part_attachment(dir);
  check_shipped(argv[1], dir, argv[2]);
  static const char *const files[] = {"a.obj", "b.obj", "c.obj", "p.obj", "sheet.obj", "lines.obj", "inside.obj", "scene.json",
                                      "shipped.h5", "stderr.txt", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
