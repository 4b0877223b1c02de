// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Organ surfaces that enclose nothing must be refused by `fascia prep` (the
// CLI, argv[1]), naming the organ, the file and the measured enclosed volume
// and area, instead of becoming a slab by hole closing: one triangle, a flat
// square, a box of zero height, a small flat triangle whose border the repair
// fills (a closed sheet of two faces). An organ that encloses a volume but
// smaller than a voxel is refused with its size and the voxel size. An open
// box (one face missing, the hole closed by the repair) is accepted.
#define _POSIX_C_SOURCE 200809L // mkdtemp, WEXITSTATUS

#include "prep_cli_case.h"

static char dir[256];

static void check_refused(const char *cli, const char *name, const char *mesh_b, const char *e1, const char *e2,
                          const char *e3) {
  prep_case_mesh(cli, dir, name, mesh_b, (const char *const[]){"organ 'B'", e1, e2, e3, NULL});
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t532_prep_encloses_nothing PATH_TO_FASCIA\n");
    return 1;
  }
  const char *cli = argv[1];
  if (!fixture_tmpdir(dir)) return 1;
  const double a_lo[3] = {-0.02, -0.01, -0.01}, a_hi[3] = {-0.003, 0.01, 0.01};
  CHECK(fixture_box(dir, "a.obj", a_lo, a_hi));
  CHECK(fixture_write(dir, "triangle.obj", "v 0.003 -0.01 -0.01\nv 0.003 0.01 -0.01\nv 0.003 0 0.01\nf 1 2 3\n"));
  CHECK(fixture_write(dir, "square.obj",
                      "v 0.005 -0.01 -0.01\nv 0.005 0.01 -0.01\nv 0.015 0.01 0.01\nv 0.015 -0.01 0.01\n"
                      "f 1 2 3\nf 1 3 4\n"));
  const double flat_lo[3] = {0.003, -0.01, 0}, flat_hi[3] = {0.02, 0.01, 0};
  CHECK(fixture_box(dir, "flatbox.obj", flat_lo, flat_hi));
  // 2 x 2 mm: within close_holes, so the repair closes it with a second face
  CHECK(fixture_write(dir, "small.obj", "v 0.004 0 0\nv 0.004 0.002 0\nv 0.004 0.001 0.002\nf 1 2 3\n"));
  const double tiny_lo[3] = {0.004, 0, 0}, tiny_hi[3] = {0.0043, 0.0003, 0.0003};
  CHECK(fixture_box(dir, "tiny.obj", tiny_lo, tiny_hi));
  // a box 7 x 6 x 20 mm without its +z face: an open mesh whose hole (9 mm across) the repair closes
  CHECK(fixture_write(dir, "openbox.obj",
                      "v 0.003 -0.003 -0.01\nv 0.01 -0.003 -0.01\nv 0.003 0.003 -0.01\nv 0.01 0.003 -0.01\n"
                      "v 0.003 -0.003 0.01\nv 0.01 -0.003 0.01\nv 0.003 0.003 0.01\nv 0.01 0.003 0.01\n"
                      "f 1 3 7\nf 1 7 5\nf 2 6 8\nf 2 8 4\nf 1 5 6\nf 1 6 2\nf 3 4 8\nf 3 8 7\nf 1 2 4\nf 1 4 3\n"));

  check_refused(cli, "one triangle", "triangle.obj", "triangle.obj", "encloses no volume", "2 cm^2 of surface");
  check_refused(cli, "flat square", "square.obj", "square.obj", "encloses no volume", "0 m^3 inside");
  check_refused(cli, "box of zero height", "flatbox.obj", "flatbox.obj", "encloses no volume", 0);
  check_refused(cli, "small triangle, closed by the repair", "small.obj", "small.obj", "encloses no volume",
                "0 border edges");
  check_refused(cli, "smaller than a voxel", "tiny.obj", "0.3 x 0.3 x 0.3 mm", "smaller or thinner than a voxel",
                "voxel_size 1 mm");

  CHECK(prep_case_mesh(cli, dir, "open box", "openbox.obj", NULL));

  static const char *const files[] = {"a.obj",    "triangle.obj", "square.obj", "flatbox.obj", "small.obj",
                                      "tiny.obj", "openbox.obj",  "scene.json", "model.h5",    "stderr.txt",
                                      NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
