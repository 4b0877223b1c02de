// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Bad input to `fascia prep` (the CLI, argv[1]): each case fails with exit
// status 1, one line on stderr that names the file or the scene key and what
// is wrong, and no model file (an older file at the output path is left as it
// was). Strings the scene gives are whole UTF-8: a \u0000 escape (which
// would cut a mesh path short) and invalid UTF-8 in keys, names and paths
// are refused.
#define _POSIX_C_SOURCE 200809L // mkdtemp, WEXITSTATUS
#include <math.h>

#include "prep_cli_case.h"

static const char *cli;
static char dir[256];

// A two-box scene; each field can be replaced to break it.
typedef struct bad_case {
  const char *name;
  const char *mesh_a, *mesh_b;
  const char *voxel, *gap, *region, *extra;
  const char *raw;          // the whole scene text instead
  const char *expect[3];    // substrings of the message
} bad_case;

static int run_case(const bad_case *c) {
  char scene[4096], path[512];
  if (c->raw)
    snprintf(scene, sizeof scene, "%s", c->raw);
  else
    snprintf(scene, sizeof scene,
             "{\"fascia_scene\": 1, \"voxel_size\": %s,\n"
             " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
             " \"organs\": [{\"name\": \"A\", \"mesh\": \"%s\"}, {\"name\": \"B\", \"mesh\": \"%s\"}],\n"
             " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": %s%s%s,\n"
             "  \"material\": \"soft\", \"frame_spacing\": 0.006, \"sample_spacing\": 0.004}]}\n",
             c->voxel ? c->voxel : "0.001", c->mesh_a ? c->mesh_a : "a.obj", c->mesh_b ? c->mesh_b : "b.obj",
             c->gap ? c->gap : "0.008", c->region ? c->region : "", c->extra ? c->extra : "");
  CHECK(fixture_write(dir, "scene.json", scene));
  snprintf(path, sizeof path, "%s/scene.json", dir);
  const char *expect[4] = {c->expect[0], c->expect[1], c->expect[2], NULL};
  return prep_case_refused(cli, dir, c->name, path, expect);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t503_prep_bad_input PATH_TO_FASCIA\n");
    return 1;
  }
  cli = argv[1];
  if (!fixture_tmpdir(dir)) return 1;
  const double a_lo[3] = {-0.02, -0.01, -0.01}, a_hi[3] = {-0.003, 0.01, 0.01};
  const double b_lo[3] = {0.003, -0.01, -0.01}, b_hi[3] = {0.02, 0.01, 0.01};
  const double f_lo[3] = {0.06, -0.01, -0.01}, f_hi[3] = {0.08, 0.01, 0.01};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi) && fixture_box(dir, "b.obj", b_lo, b_hi) &&
        fixture_box(dir, "far.obj", f_lo, f_hi));
  CHECK(fixture_write(dir, "nan.obj", "v nan 0 0\nv 0.01 0 0\nv 0 0.01 0\nv 0 0 0.01\nf 1 2 3\nf 1 3 4\n"));
  CHECK(fixture_write(dir, "empty.obj", "v 0 0 0\nv 0.01 0 0\nv 0 0.01 0\n"));
  CHECK(fixture_write(dir, "garbage.glb", "this is not a glTF file\n"));
  const bad_case cases[] = {
      {"missing file", "nothere.obj", 0, 0, 0, 0, 0, 0, {"organs[0].mesh", "nothere.obj", "cannot open"}},
      {"unreadable mesh", "garbage.glb", 0, 0, 0, 0, 0, 0, {"organ 'A'", "garbage.glb", "cannot be read"}},
      {"NaN coordinates", 0, "nan.obj", 0, 0, 0, 0, 0, {"organ 'B'", "nan.obj", "non-finite"}},
      {"empty mesh", "empty.obj", 0, 0, 0, 0, 0, 0, {"organ 'A'", "empty.obj", "no triangles"}},
      {"too far apart", 0, "far.obj", 0, 0, 0, 0, 0, {"tissue 'gap'", "too far apart", "max_gap"}},
      {"region selects nothing", 0, 0, 0, 0,
       ", \"region\": {\"box\": {\"min\": [1, 1, 1], \"max\": [1.1, 1.1, 1.1]}}", 0, 0,
       {"tissues[0].region", "selects nothing", 0}},
      {"voxel too large", 0, 0, "0.004", "0.008", 0, 0, 0, {"voxel_size", "too large", "0.00266667"}},
      {"unknown key", 0, 0, 0, 0, 0, ", \"max_gapp\": 1", 0, {"scene.json", "tissues[0].max_gapp", "unknown key"}},
      {"wrong type", 0, 0, 0, "\"8 mm\"", 0, 0, 0, {"scene.json", "tissues[0].max_gap", "expected a number"}},
      {"min_gap not below max_gap", 0, 0, 0, 0, 0, ", \"min_gap\": 0.008", 0,
       {"scene.json", "tissues[0].min_gap", "< 0.008"}},
      {"organs nowhere min_gap apart", 0, 0, 0, 0,
       ", \"region\": {\"box\": {\"min\": [-1, -0.005, -0.005], \"max\": [1, 0.005, 0.005]}}", ", \"min_gap\": 0.007",
       0, {"tissues[0].min_gap", "slide on each other everywhere", "lower min_gap"}},
      {"unknown organ", 0, 0, 0, 0, 0, 0,
       "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"materials\": {\"m\": {\"youngs_modulus\": 1, "
       "\"poisson_ratio\": 0.3}}, \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\"}], \"tissues\": [{\"name\": "
       "\"t\", \"connects\": [\"A\", \"C\"], \"max_gap\": 0.01, \"material\": \"m\", \"frame_spacing\": 0.004, "
       "\"sample_spacing\": 0.002}]}",
       {"tissues[0].connects[1]", "no organ is named 'C'", 0}},
      {"not JSON", 0, 0, 0, 0, 0, 0, "{\"fascia_scene\": 1,\n \"voxel_size\": }", {"scene.json", "not valid JSON", "line 2"}},
      {"NUL escape in a mesh path", 0, "b.obj\\u0000.x", 0, 0, 0, 0, 0, {"scene.json", "\\u0000", "line 3"}},
      {"invalid UTF-8 in a key", 0, 0, 0, 0, 0, ", \"max\xe9gap\": 1", 0, {"scene.json", "tissues[0]", "UTF-8"}},
      {"invalid UTF-8 in a name", 0, 0, 0, 0, 0, 0,
       "{\"fascia_scene\": 1, \"voxel_size\": 0.001, \"materials\": {\"m\": {\"youngs_modulus\": 1, "
       "\"poisson_ratio\": 0.3}}, \"organs\": [{\"name\": \"A\xff\", \"mesh\": \"a.obj\"}], \"tissues\": []}",
       {"scene.json", "organs[0].name", "UTF-8"}},
      {"overlong UTF-8 in a path", 0, "b\xc0\xae.obj", 0, 0, 0, 0, 0, {"scene.json", "organs[1].mesh", "UTF-8"}},
  };
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) run_case(cases + k);
  { // a coupling tolerance of 1 m: OpenVDB's band stays within what the grid can see (in 4 GB, not an abort)
    char scene[4096], path[512], command[2048];
    prep_case_scene(scene, sizeof scene, 0, 0, 0, 0, ", \"coupling\": {\"tolerance\": 1}", 0);
    CHECK(fixture_write(dir, "scene.json", scene));
    snprintf(path, sizeof path, "%s/scene.json", dir);
    snprintf(command, sizeof command,
             "ulimit -v 4000000; FASCIA_PROGRESS=0 timeout 120 '%s' prep '%s' -o '%s/model.h5' > /dev/null 2> "
             "'%s/stderr.txt'",
             cli, path, dir, dir);
    const int status = system(command);
    if (!(status >= 0 && WIFEXITED(status) && WEXITSTATUS(status) == 0)) {
      fprintf(stderr, "case 'coupling tolerance 1 m': exit status %d, it should be accepted\n", status);
      ++check_failures_;
    }
  }
  static const char *const files[] = {"a.obj", "b.obj", "far.obj", "nan.obj", "empty.obj", "garbage.glb",
                                      "scene.json", "model.h5", "stderr.txt", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
