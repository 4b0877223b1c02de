// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A "parts" name that the mesh file does not have, through `fascia prep`
// (the CLI, argv[1]): a file whose parts have no names (a binary STL, an
// ASCII STL whose solid is unnamed) is refused saying it has no named parts
// (never "its parts are: " with nothing after it); a file with named parts
// (OBJ groups) is refused listing them. Box A of two boxes 6 mm apart.
#define _POSIX_C_SOURCE 200809L // mkdtemp, WEXITSTATUS
#include <stdint.h>

#include "prep_cli_case.h"

static char dir[256];

// The 12 outward triangles of box [lo, hi] (prep_fixture's corner order).
static void box_triangles(const double *lo, const double *hi, float out[12][3][3]) {
  static const int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (int f = 0; f < 6; ++f)
    for (int t = 0; t < 2; ++t) {
      const int corner[3] = {quads[f][0], quads[f][1 + t], quads[f][2 + t]};
      for (int v = 0; v < 3; ++v)
        for (int r = 0; r < 3; ++r) out[2 * f + t][v][r] = (float)((corner[v] >> r) & 1 ? hi[r] : lo[r]);
    }
}

static int write_binary_stl(const char *name, const double *lo, const double *hi) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "wb");
  if (!f) return 0;
  float tri[12][3][3];
  box_triangles(lo, hi, tri);
  const char header[80] = {0};
  const uint32_t count = 12; // little-endian on the machines fascia builds on
  const float normal[3] = {0, 0, 0};
  const uint16_t attributes = 0;
  int ok = fwrite(header, 1, 80, f) == 80 && fwrite(&count, 4, 1, f) == 1;
  for (int t = 0; t < 12; ++t)
    ok = ok && fwrite(normal, 4, 3, f) == 3 && fwrite(tri[t], 4, 9, f) == 9 && fwrite(&attributes, 2, 1, f) == 1;
  return fclose(f) == 0 && ok;
}

static int write_ascii_stl(const char *name, const double *lo, const double *hi) {
  char text[8192];
  float tri[12][3][3];
  box_triangles(lo, hi, tri);
  int n = snprintf(text, sizeof text, "solid\n");
  for (int t = 0; t < 12; ++t) {
    n += snprintf(text + n, sizeof text - (size_t)n, " facet normal 0 0 0\n  outer loop\n");
    for (int v = 0; v < 3; ++v)
      n += snprintf(text + n, sizeof text - (size_t)n, "   vertex %.9g %.9g %.9g\n", tri[t][v][0], tri[t][v][1],
                    tri[t][v][2]);
    n += snprintf(text + n, sizeof text - (size_t)n, "  endloop\n endfacet\n");
  }
  snprintf(text + n, sizeof text - (size_t)n, "endsolid\n");
  return fixture_write(dir, name, text);
}

static void refused(const char *cli, const char *name, const char *mesh_a, const char *e1, const char *e2) {
  char scene[4096], path[512];
  prep_case_scene(scene, sizeof scene, mesh_a, 0, 0, ", \"parts\": [\"lid\"]", 0, 0);
  snprintf(path, sizeof path, "%s/scene.json", dir);
  CHECK(fixture_write(dir, "scene.json", scene));
  prep_case_refused(cli, dir, name, path, (const char *const[]){"organ 'A' (scene '", "organs[0].parts", e1, e2, NULL});
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t582_prep_part_names PATH_TO_FASCIA\n");
    return 1;
  }
  const char *cli = argv[1];
  if (!fixture_tmpdir(dir)) return 1;
  char path[512];
  CHECK(fixture_two_boxes(dir, 0.003, NULL, path));
  const double lo[3] = {-0.02, -0.0102, -0.0102}, hi[3] = {-0.003, 0.0102, 0.0102};
  CHECK(write_binary_stl("binary.stl", lo, hi));
  CHECK(write_ascii_stl("ascii.stl", lo, hi));
  // box A's OBJ in two named groups
  char obj[2048];
  int n = 0;
  for (int c = 0; c < 8; ++c)
    n += snprintf(obj + n, sizeof obj - (size_t)n, "v %.9g %.9g %.9g\n", (c & 1) ? hi[0] : lo[0],
                  (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]);
  snprintf(obj + n, sizeof obj - (size_t)n,
           "g top\nf 1 3 7\nf 1 7 5\nf 2 6 8\nf 2 8 4\nf 1 5 6\nf 1 6 2\n"
           "g bottom\nf 3 4 8\nf 3 8 7\nf 1 2 4\nf 1 4 3\nf 5 7 8\nf 5 8 6\n");
  CHECK(fixture_write(dir, "groups.obj", obj));

  refused(cli, "binary STL", "binary.stl", "binary.stl' has no named parts (1 unnamed), so none named 'lid'",
          "leave \"parts\" out");
  refused(cli, "ASCII STL, unnamed solid", "ascii.stl", "ascii.stl' has no named parts", "leave \"parts\" out");
  refused(cli, "OBJ with groups", "groups.obj", "has no part named 'lid'; its parts are: ", "top, bottom");

  static const char *const files[] = {"a.obj",      "b.obj",    "binary.stl", "ascii.stl", "groups.obj",
                                      "scene.json", "model.h5", "stderr.txt", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
