// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Helpers of the prep bad-input tests that run the CLI (t503, t53x): a scene text
// around two organs with pieces to replace, and one run of `fascia prep`
// that must refuse its input cleanly. Needs _POSIX_C_SOURCE (WEXITSTATUS).
#ifndef FASCIA_TESTS_PREP_CLI_CASE_H
#define FASCIA_TESTS_PREP_CLI_CASE_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "check.h"
#include "prep_fixture.h"

/// Scene text into out[size]: organs A (mesh_a) and B (mesh_b), one tissue;
/// materials replaces the materials object's members, organ_a and tissue
/// are added to organ A's and the tissue's keys, top to the top level
/// (each may be NULL or "", and starts with ", " when given).
static inline void prep_case_scene(char *out, size_t size, const char *mesh_a, const char *mesh_b,
                                   const char *materials, const char *organ_a, const char *tissue, const char *top) {
  snprintf(out, size,
           "{\"fascia_scene\": 1, \"voxel_size\": 0.001%s,\n"
           " \"materials\": {%s},\n"
           " \"organs\": [{\"name\": \"A\", \"mesh\": \"%s\"%s},\n"
           "            {\"name\": \"B\", \"mesh\": \"%s\"}],\n"
           " \"tissues\": [{\"name\": \"gap\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.008,\n"
           "  \"material\": \"soft\", \"frame_spacing\": 0.006, \"sample_spacing\": 0.004%s}]}\n",
           top ? top : "", materials ? materials : "\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}",
           mesh_a ? mesh_a : "a.obj", organ_a ? organ_a : "", mesh_b ? mesh_b : "b.obj", tissue ? tissue : "");
}

/// Runs `fascia prep scene_path -o dir/model.h5` (at most 60 s: a hang
/// fails, it does not stall the test). Passes when it exits with status 1,
/// one line on stderr holding every string of expect (NULL-terminated, up to
/// 4), and dir/model.h5 still holds the older file written before. On
/// failure prints the case name and what happened, and counts a failure.
static inline int prep_case_refused(const char *cli, const char *dir, const char *name, const char *scene_path,
                                    const char *const *expect) {
  char out[512], err[512], command[2048], message[4096] = "", older[64] = "";
  snprintf(out, sizeof out, "%s/model.h5", dir);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  if (!fixture_write(dir, "model.h5", "older file")) return 0;
  snprintf(command, sizeof command, "FASCIA_PROGRESS=0 timeout 60 '%s' prep '%s' -o '%s' > /dev/null 2> '%s'", cli,
           scene_path, out, err);
  const int status = system(command);
  const int code = status >= 0 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  FILE *f = fopen(err, "r");
  const size_t n = f ? fread(message, 1, sizeof message - 1, f) : 0;
  if (f) fclose(f);
  message[n] = 0;
  int lines = 0;
  for (size_t k = 0; k < n; ++k) lines += message[k] == '\n';
  int ok = code == 1 && lines == 1;
  for (int k = 0; k < 4 && expect[k]; ++k) ok = ok && strstr(message, expect[k]) != NULL;
  f = fopen(out, "r");
  const size_t m = f ? fread(older, 1, sizeof older - 1, f) : 0;
  if (f) fclose(f);
  older[m] = 0;
  ok = ok && !strcmp(older, "older file");
  if (!ok) {
    fprintf(stderr, "case '%s': exit %d%s, %d lines, output '%s', message:\n%s\n", name, code,
            code == 124 ? " (it hung)" : "", lines, older, message);
    ++check_failures_;
  }
  return ok;
}

/// Runs `fascia prep scene_path -o dir/model.h5`; 1 when it succeeds.
static inline int prep_case_accepted(const char *cli, const char *dir, const char *name, const char *scene_path) {
  char command[2048], err[512];
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  snprintf(command, sizeof command, "FASCIA_PROGRESS=0 timeout 120 '%s' prep '%s' -o '%s/model.h5' > /dev/null 2> '%s'",
           cli, scene_path, dir, err);
  const int status = system(command);
  const int ok = status >= 0 && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  if (!ok) {
    fprintf(stderr, "case '%s': refused, it should be accepted; stderr in %s\n", name, err);
    ++check_failures_;
  }
  return ok;
}

/// The scene of prep_case_scene with organ B's mesh mesh_b, written as
/// dir/scene.json and run: refused as prep_case_refused checks when expect
/// is given (NULL-terminated), accepted when expect is NULL.
static inline int prep_case_mesh(const char *cli, const char *dir, const char *name, const char *mesh_b,
                                 const char *const *expect) {
  char scene[4096], path[512];
  prep_case_scene(scene, sizeof scene, 0, mesh_b, 0, 0, 0, 0);
  snprintf(path, sizeof path, "%s/scene.json", dir);
  if (!fixture_write(dir, "scene.json", scene)) {
    fprintf(stderr, "case '%s': cannot write %s\n", name, path);
    ++check_failures_;
    return 0;
  }
  return expect ? prep_case_refused(cli, dir, name, path, expect) : prep_case_accepted(cli, dir, name, path);
}

#endif
