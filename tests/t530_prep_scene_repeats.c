// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Scene files that `fascia prep` (the CLI, argv[1]) must refuse with one line
// naming the file, the key and what is accepted: a key given twice in any
// object, a name given twice in any named table (materials, organs,
// tissues, parts, connects), values out of range (the message names the
// range), empty part names, nesting beyond the JSON reader's limit.
#define _POSIX_C_SOURCE 200809L // mkdtemp, WEXITSTATUS

#include "prep_cli_case.h"

typedef struct scene_case {
  const char *name;
  const char *materials, *organ_a, *tissue, *top; // pieces of prep_case_scene
  const char *expect[4];
} scene_case;

#define SOFT "\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}"

static const scene_case cases[] = {
    // a key twice: in every object, with both places (line, column)
    {"material twice", SOFT ", \"soft\": {\"youngs_modulus\": 1, \"poisson_ratio\": 0.1}", 0, 0, 0,
     {"scene.json", "materials.soft", "given twice", "line 2, column 16 and at line 2, column 72"}},
    {"top-level key twice", 0, 0, 0, ", \"voxel_size\": 0.002",
     {"voxel_size", "given twice", "line 1, column 21 and at line 1, column 42"}},
    {"key twice in an organ", 0, ", \"mesh\": \"b.obj\"", 0, 0, {"organs[0].mesh", "given twice", 0}},
    {"key twice in a material", "\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3, \"poisson_ratio\": 0.1}",
     0, 0, 0, {"materials.soft.poisson_ratio", "given twice", 0}},
    {"key twice deep inside", 0, 0,
     ", \"shape_functions\": {\"kind\": \"mls\", \"neighbours\": 8, \"kind\": \"tet\"}", 0,
     {"tissues[0].shape_functions.kind", "given twice", 0}},
    {"coupling organ twice", 0, 0, ", \"coupling\": {\"organs\": {\"A\": false, \"B\": false, \"A\": true}}", 0,
     {"tissues[0].coupling.organs.A", "given twice", 0}},
    {"key twice in a transform", 0,
     ", \"transform\": {\"scale\": 1, \"translation\": [0, 0, 0], \"scale\": 2}", 0, 0,
     {"organs[0].transform.scale", "given twice", 0}},
    // a name twice in a named table: both places
    {"organ name twice", 0, ", \"name\": \"B\"", 0, 0, {"organs[0].name", "given twice", 0}},
    {"part twice", 0, ", \"parts\": [\"x\", \"y\", \"x\"]", 0, 0,
     {"organs[0].parts[2]", "'x' is given twice", "organs[0].parts[0]"}},
    {"region part twice", 0, 0, ", \"region\": {\"parts\": {\"organ\": \"A\", \"names\": [\"p\", \"p\"]}}", 0,
     {"tissues[0].region.parts.names[1]", "given twice", "names[0]"}},
    {"coupling part twice", 0, 0, ", \"coupling\": {\"organs\": {\"A\": {\"parts\": [\"q\", \"r\", \"q\"]}}}", 0,
     {"tissues[0].coupling.organs.A.parts[2]", "given twice", "parts[0]"}},
    // empty part names say so
    {"empty part name", 0, ", \"parts\": [\"\"]", 0, 0, {"organs[0].parts[0]", "empty string", 0}},
    {"part name not a string", 0, ", \"parts\": [3]", 0, 0, {"organs[0].parts[0]", "(a string), found a number", 0}},
    // ranges: the message names what is accepted
    {"poisson ratio 0.5", "\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.5}", 0, 0, 0,
     {"materials.soft.poisson_ratio", "0.5 is out of range", ">= 0 and < 0.5"}},
    {"poisson ratio negative", "\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": -0.1}", 0, 0, 0,
     {"poisson_ratio", ">= 0 and < 0.5", 0}},
    {"close_holes too large", 0, 0, 0, ", \"close_holes\": 0.2", {"close_holes", "0.2", ">= 0 and < 0.1"}},
    {"youngs modulus zero", "\"soft\": {\"youngs_modulus\": 0, \"poisson_ratio\": 0.3}", 0, 0, 0,
     {"youngs_modulus", "expected > 0", 0}},
    {"version given twice", 0, 0, 0, ", \"fascia_scene\": 2", {"fascia_scene", "given twice", 0}},
    {"neighbours too many", 0, 0, ", \"shape_functions\": {\"neighbours\": 100}", 0,
     {"shape_functions.neighbours", "expected 4 .. 64", 0}},
    {"neighbours not whole", 0, 0, ", \"shape_functions\": {\"neighbours\": 8.5}", 0,
     {"shape_functions.neighbours", "found 8.5", 0}},
    {"translation of two", 0, ", \"transform\": {\"translation\": [1, 2]}", 0, 0,
     {"transform.translation", "array of 3 numbers, found an array of 2", 0}},
    {"rotation not unit", 0, ", \"transform\": {\"rotation\": [3, 0, 0, 0]}", 0, 0,
     {"organs[0].transform", "norm is 3", "expected > 0.5 and < 2"}},
    {"region box inside out", 0, 0, ", \"region\": {\"box\": {\"min\": [0, 0, 0], \"max\": [1, -1, 1]}}", 0,
     {"region.box", "axis 1: min 0, max -1", 0}},
};

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t530_prep_scene_repeats PATH_TO_FASCIA\n");
    return 1;
  }
  const char *cli = argv[1];
  char dir[256], scene[8192], path[512];
  if (!fixture_tmpdir(dir)) return 1;
  const double a_lo[3] = {-0.02, -0.01, -0.01}, a_hi[3] = {-0.003, 0.01, 0.01};
  const double b_lo[3] = {0.003, -0.01, -0.01}, b_hi[3] = {0.02, 0.01, 0.01};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && fixture_box(dir, "b.obj", b_lo, b_hi));
  snprintf(path, sizeof path, "%s/scene.json", dir);

  // the scene itself is accepted: each case below breaks one thing
  prep_case_scene(scene, sizeof scene, 0, 0, 0, 0, 0, 0);
  CHECK(fixture_write(dir, "scene.json", scene));
  CHECK(prep_case_accepted(cli, dir, "the unbroken scene", path));

  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
    const scene_case *c = cases + k;
    prep_case_scene(scene, sizeof scene, 0, 0, c->materials, c->organ_a, c->tissue, c->top);
    CHECK(fixture_write(dir, "scene.json", scene));
    prep_case_refused(cli, dir, c->name, path, c->expect);
  }

  // a tissue name twice (the scene with a second tissue)
  prep_case_scene(scene, sizeof scene, 0, 0, 0, 0, 0, 0);
  char *end = strrchr(scene, ']');
  snprintf(end, sizeof scene - (size_t)(end - scene),
           ", {\"name\": \"gap\", \"connects\": [\"B\", \"A\"], \"max_gap\": 0.008, \"material\": \"soft\", "
           "\"frame_spacing\": 0.006, \"sample_spacing\": 0.004}]}\n");
  CHECK(fixture_write(dir, "scene.json", scene));
  prep_case_refused(cli, dir, "tissue name twice", path,
                    (const char *const[]){"tissues[1].name", "'gap' is given twice", "tissues[0].name", NULL});

  // an organ twice in connects
  prep_case_scene(scene, sizeof scene, 0, 0, 0, 0, 0, 0);
  char *connects = strstr(scene, "[\"A\", \"B\"]");
  memmove(connects + 5, connects, strlen(connects) + 1);
  memcpy(connects, "[\"B\", ", 6);
  CHECK(fixture_write(dir, "scene.json", scene));
  prep_case_refused(cli, dir, "connects an organ twice", path,
                    (const char *const[]){"tissues[0].connects[2]", "'B' is given twice", "connects[0]", NULL});

  // version given once, unsupported: the accepted value is named
  prep_case_scene(scene, sizeof scene, 0, 0, 0, 0, 0, 0);
  memcpy(strstr(scene, "\"fascia_scene\": 1"), "\"fascia_scene\": 2", 17);
  CHECK(fixture_write(dir, "scene.json", scene));
  prep_case_refused(cli, dir, "version 2 alone", path, (const char *const[]){"fascia_scene", "expected 1", NULL});

  // nesting: the reader's limit is 1000 levels; the message says so
  static char deep[8192];
  int n = snprintf(deep, sizeof deep, "{\"description\": ");
  for (int k = 0; k < 1200; ++k) deep[n++] = '[';
  for (int k = 0; k < 1200; ++k) deep[n++] = ']';
  snprintf(deep + n, sizeof deep - (size_t)n, "}\n");
  CHECK(fixture_write(dir, "scene.json", deep));
  prep_case_refused(cli, dir, "nested too deeply", path,
                    (const char *const[]){"scene.json", "nested too deeply", "1000 levels", NULL});

  static const char *const files[] = {"a.obj", "b.obj", "scene.json", "model.h5", "stderr.txt", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
