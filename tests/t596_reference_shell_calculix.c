// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Shell organs against CalculiX S8R shells (tools/scenes/shell_calculix.h),
// the stored references (data/reference/shell-calculix.csv, the finest mesh
// of each ladder; tools/bench/shell-vs-calculix.sh makes them):
//  - plate: the paper's cantilever as a thin shell (16 x 1 m, 0.1 m thick,
//    E 4 MPa, its edge clamped by the shell's hold) at fascia's default
//    frame spacing, the free end's displacement within 2 %; a wall whose
//    triangles shear when bent (linear gradients) is 40 % too stiff here;
//  - bowl: a hemisphere hanging from its clamped rim (a curved wall that
//    carries its weight by stretching), the bottom's sag within 2 % at the
//    default spacing, and its sideways drift (the random frames are not
//    symmetric; CalculiX's mesh is) within 3 % of the sag; a least-squares
//    fit's gradients alone leave the wall's hourglass and drilling modes
//    nearly free: 7 % too soft here;
//  - the decks: S8R, the clamp, gravity; bad definitions refused by name;
//    fascia's scene carries the definition's seed (the draw of the frames).
// argv[1]: the reference CSV.
#define _POSIX_C_SOURCE 200809L // open_memstream
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "shell_calculix.h"
#include "tissue_calculix.h"

#define TOLERANCE 0.02
#define SIDEWAYS 0.03

// The last row of the case in the CSV: its probe displacement.
static int reference(const char *path, const char *name, double u[3]) {
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  char line[512];
  int found = 0;
  while (fgets(line, sizeof line, f)) {
    char kind[32];
    double E, nu, t, ux, uy, uz;
    char mesh[32];
    int nodes;
    if (sscanf(line, "%31[^,],%lf,%lf,%lf,%31[^,],%d,%lf,%lf,%lf", kind, &E, &nu, &t, mesh, &nodes, &ux, &uy, &uz) ==
            9 &&
        !strcmp(kind, name))
      u[0] = ux, u[1] = uy, u[2] = uz, found = 1;
  }
  fclose(f);
  return found;
}

static void check_decks(fascia_ctx *ctx) {
  for (int kind = 0; kind < 2; ++kind) {
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    fascia_shell_def def = fascia_shell_def_default(kind);
    CHECK(f && fascia_shell_write_deck(ctx, &def, f) == FASCIA_OK);
    if (f) fclose(f);
    CHECK(text && strstr(text, "TYPE=S8R") && strstr(text, "*SHELL SECTION") && strstr(text, "NFIX, 1, 6") &&
          strstr(text, "GRAV, 9.81") && strstr(text, "*STEP, NLGEOM"));
    free(text);
  }
  fascia_shell_def bad = fascia_shell_def_default(FASCIA_SHELL_BOWL);
  bad.elements[0] = 7;
  FILE *f = fopen("/dev/null", "w");
  CHECK(f && fascia_shell_write_deck(ctx, &bad, f) == FASCIA_ERR_ARGUMENT);
  CHECK(strstr(fascia_ctx_message(ctx), "7 S8R elements") != NULL);
  bad = fascia_shell_def_default(FASCIA_SHELL_PLATE);
  bad.frame_spacing = 0.05; // thinner than the wall
  CHECK(f && fascia_shell_write_deck(ctx, &bad, f) == FASCIA_ERR_ARGUMENT);
  CHECK(strstr(fascia_ctx_message(ctx), "frame spacing 0.05 m") != NULL);
  if (f) fclose(f);
  char dir[] = "/tmp/t596-XXXXXX", path[64], text[256] = {0};
  CHECK(mkdtemp(dir) != NULL);
  fascia_shell_def seeded = fascia_shell_def_default(FASCIA_SHELL_BOWL);
  seeded.seed = 7;
  CHECK(fascia_shell_write_scene(ctx, &seeded, dir) == FASCIA_OK);
  snprintf(path, sizeof path, "%s/%s", dir, FASCIA_TISSUE_SCENE);
  FILE *scene = fopen(path, "r");
  CHECK(scene && fread(text, 1, sizeof text - 1, scene) > 0);
  CHECK(strstr(text, "\"seed\": 7,") != NULL);
  if (scene) fclose(scene);
  const char *const files[] = {FASCIA_TISSUE_SCENE, FASCIA_TISSUE_SHEET, FASCIA_TISSUE_BOX_A, FASCIA_TISSUE_BOX_B};
  for (int k = 0; k < 4; ++k) snprintf(path, sizeof path, "%s/%s", dir, files[k]), remove(path);
  rmdir(dir);
}

// tolerance bounds the error of the displacement; with sideways > 0 it
// bounds the error of its z component, and sideways its x and y.
static void check_case(fascia_ctx *ctx, const char *csv, int kind, const char *name, double tolerance,
                       double sideways) {
  double ref[3];
  CHECK(reference(csv, name, ref));
  const fascia_shell_def def = fascia_shell_def_default(kind);
  fascia_shell_result r;
  const fascia_status st = fascia_shell_fascia(ctx, &def, &r);
  if (st != FASCIA_OK) fprintf(stderr, "%s, fascia: %s\n", name, fascia_ctx_message(ctx));
  CHECK(st == FASCIA_OK);
  if (st != FASCIA_OK) return;
  double d = 0, n = 0;
  for (int a = 0; a < 3; ++a) d += (r.probe[a] - ref[a]) * (r.probe[a] - ref[a]), n += ref[a] * ref[a];
  const double error = sqrt(d / n), sag = fabs(r.probe[2] - ref[2]) / sqrt(n),
               drift = sqrt((r.probe[0] - ref[0]) * (r.probe[0] - ref[0]) + (r.probe[1] - ref[1]) * (r.probe[1] - ref[1])) /
                       sqrt(n);
  printf("%s (%d frames, spacing %g m): probe u (%.6f %.6f %.6f) m, CalculiX (%.6f %.6f %.6f) m: %.2f %% (z %.2f %%, "
         "x and y %.2f %%); static solve %.1f ms, %d Newton iterations\n",
         name, (int)r.nodes, def.frame_spacing, r.probe[0], r.probe[1], r.probe[2], ref[0], ref[1], ref[2],
         100 * error, 100 * sag, 100 * drift, r.ms, (int)r.newton);
  if (sideways > 0) {
    CHECK(sag < tolerance);
    CHECK(drift < sideways);
  } else {
    CHECK(error < tolerance);
  }
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t596 data/reference/shell-calculix.csv\n");
    return 1;
  }
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  check_decks(ctx);
  check_case(ctx, argv[1], FASCIA_SHELL_PLATE, "plate", TOLERANCE, 0);
  check_case(ctx, argv[1], FASCIA_SHELL_BOWL, "bowl", TOLERANCE, SIDEWAYS);
  fascia_ctx_destroy(&ctx);
  return check_failures_ != 0;
}
