// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A strand hanging an organ and a sheet under a pull, fascia against
// CalculiX on the same geometry (tools/scenes/tissue_calculix.h), within 3 %:
//  - hang: the default strand (11 frames) carrying a rigid 20 mm organ as a
//    cantilever: the organ's centre, the strand's end, the organ's rotation
//    and the strand's force on the fixed organ against 40 B32 beams;
//  - pull: the default 10 x 8 sheet sheared (B moved 1 mm along y) and
//    stretched (1 mm along x), the sheet's force on B and the free edge's
//    middle against 20 x 16 S8R shells; pulled 2 mm across its plane (bent
//    and stretched) and bent (B moved 0.1 mm across), the default sheet
//    too, its force across also checked on its own (bent, the force along,
//    from the sheet's stretch, is as large and hides it): with the linear
//    triangle's gradients it locked, +8 % sagged and +29 % bent
//    (docs/mechanics.md, "Against CalculiX"). Each pull on three meshes of
//    the sheet: right triangles, near-equilateral ones and jittered ones.
// Without ccx only the decks and the definitions' checks are tested, and
// the test says it skipped the rest (exit 77).
#define _POSIX_C_SOURCE 200809L // open_memstream
#include <stdlib.h>
#include <string.h>

#include "beam_calculix.h"
#include "check.h"
#include "fascia/organs.h"
#include "tissue_calculix.h"

#define TOLERANCE 0.03

static void check_decks(fascia_ctx *ctx) {
  char *text = NULL;
  size_t size = 0;
  FILE *f = open_memstream(&text, &size);
  fascia_tissue_hang_def hang = fascia_tissue_hang_def_default();
  CHECK(f && fascia_tissue_hang_write_deck(ctx, &hang, f) == FASCIA_OK);
  if (f) fclose(f);
  CHECK(text && strstr(text, "TYPE=B32, ELSET=ESTRAND") && strstr(text, "SECTION=RECT") &&
        strstr(text, "*STEP, NLGEOM"));
  free(text);
  f = open_memstream(&text, &size);
  fascia_tissue_pull_def pull = fascia_tissue_pull_def_default();
  CHECK(f && fascia_tissue_pull_write_deck(ctx, &pull, f) == FASCIA_OK);
  if (f) fclose(f);
  CHECK(text && strstr(text, "TYPE=S8R") && strstr(text, "*SHELL SECTION") && strstr(text, "NPULL, 2, 2, 0.001"));
  free(text);
  // bad definitions are refused naming what is wrong
  pull.mesh = 3;
  f = fopen("/dev/null", "w");
  CHECK(f && fascia_tissue_pull_write_deck(ctx, &pull, f) == FASCIA_ERR_ARGUMENT);
  CHECK(strstr(fascia_ctx_message(ctx), "mesh 3, expected") != NULL);
  pull.mesh = FASCIA_TISSUE_MESH_RIGHT;
  pull.cells[0] = 5;
  CHECK(f && fascia_tissue_pull_write_deck(ctx, &pull, f) == FASCIA_ERR_ARGUMENT);
  CHECK(strstr(fascia_ctx_message(ctx), "5 mesh cells along x") != NULL);
  hang.area = 1; // wider than the organ
  CHECK(f && fascia_tissue_hang_write_deck(ctx, &hang, f) == FASCIA_ERR_ARGUMENT);
  CHECK(strstr(fascia_ctx_message(ctx), "area 1 m^2") != NULL);
  if (f) fclose(f);
}

static void check_hang(fascia_ctx *ctx, const char *program) {
  const fascia_tissue_hang_def def = fascia_tissue_hang_def_default();
  fascia_tissue_hang_result fa, cc;
  const fascia_status sf = fascia_tissue_hang_fascia(ctx, &def, &fa);
  if (sf != FASCIA_OK) fprintf(stderr, "hang, fascia: %s\n", fascia_ctx_message(ctx));
  const fascia_status sc = fascia_tissue_hang_calculix(ctx, &def, program, &cc);
  if (sc != FASCIA_OK) fprintf(stderr, "hang, ccx: %s\n", fascia_ctx_message(ctx));
  CHECK(sf == FASCIA_OK && sc == FASCIA_OK);
  if (sf != FASCIA_OK || sc != FASCIA_OK) return;
  const double e[4] = {fascia_tissue_error3(fa.centre, cc.centre), fascia_tissue_error3(fa.end, cc.end),
                       fascia_tissue_error3(fa.force, cc.force), fabs(fa.angle - cc.angle) / fabs(cc.angle)};
  printf("hang (%d frames, %d B32 nodes): organ centre uz %.4f / %.4f mm (%.2f %%), strand end uz %.4f / %.4f mm "
         "(%.2f %%), force on A %.3f / %.3f mN (%.2f %%), rotation %.2f / %.2f mrad (%.2f %%)\n",
         (int)fa.nodes, (int)cc.nodes, 1e3 * fa.centre[2], 1e3 * cc.centre[2], 100 * e[0], 1e3 * fa.end[2],
         1e3 * cc.end[2], 100 * e[1], 1e3 * fa.force[2], 1e3 * cc.force[2], 100 * e[2], 1e3 * fa.angle,
         1e3 * cc.angle, 100 * e[3]);
  for (int k = 0; k < 4; ++k) CHECK(e[k] < TOLERANCE);
  // the organ sags by a quarter of the strand's length: not a small-displacement case
  CHECK(cc.centre[2] < -0.2 * def.gap);
  // both carry the weights of the organ and the strand
  const double weight = (FASCIA_ORGAN_DENSITY * def.box * def.box * def.box + def.density * def.area * def.gap) *
                        def.gravity;
  CHECK_NEAR(-fa.force[2], weight, 1e-6, 0);
  CHECK_NEAR(-cc.force[2], weight, 1e-4, 0);
}

// fascia's sheet on mesh kind `mesh` against ccx's answer cc; `edge`: check
// the free edge's middle too. Not on the irregular meshes pulled across:
// bent, it moves by 4e-5 mm, and sagged, their 10 x 8 meshes lift it by
// 2.5e-3 mm out of the plane (a quarter of a percent of the sag, a fifth of
// its 0.014 mm in the plane; 1-3 % at 20 x 16, docs/measured.md).
static void check_mesh(fascia_ctx *ctx, const char *name, fascia_tissue_pull_def def, int32_t mesh,
                       const fascia_tissue_pull_result *cc, int edge) {
  def.mesh = mesh;
  fascia_tissue_pull_result fa;
  const fascia_status sf = fascia_tissue_pull_fascia(ctx, &def, &fa);
  if (sf != FASCIA_OK) fprintf(stderr, "%s, fascia on the %s mesh: %s\n", name, fascia_tissue_mesh_name(mesh),
                               fascia_ctx_message(ctx));
  CHECK(sf == FASCIA_OK);
  if (sf != FASCIA_OK) return;
  const double e[3] = {fascia_tissue_error3(fa.force, cc->force), fascia_tissue_error3(fa.edge, cc->edge),
                       fascia_tissue_error3(fa.centre, cc->centre)};
  printf("%s (%dx%d %s mesh, %dx%d S8R): force on B (%.4f %.4f %.4f) / (%.4f %.4f %.4f) mN (%.2f %%), free edge's "
         "middle less the centre (%.4f %.4f %.4f) / (%.4f %.4f %.4f) mm (%.2f %%), centre %.2f %%, %d Newton "
         "iterations\n",
         name, (int)def.cells[0], (int)def.cells[1], fascia_tissue_mesh_name(mesh), (int)def.elements[0],
         (int)def.elements[1], 1e3 * fa.force[0], 1e3 * fa.force[1], 1e3 * fa.force[2], 1e3 * cc->force[0],
         1e3 * cc->force[1], 1e3 * cc->force[2], 100 * e[0], 1e3 * fa.edge[0], 1e3 * fa.edge[1], 1e3 * fa.edge[2],
         1e3 * cc->edge[0], 1e3 * cc->edge[1], 1e3 * cc->edge[2], 100 * e[1], 100 * e[2], (int)fa.newton_iterations);
  CHECK(e[0] < TOLERANCE);
  CHECK(!edge || e[1] < TOLERANCE);
  CHECK(e[2] < TOLERANCE);
  if (def.pull[2] != 0) {
    const double ez = fabs(fa.force[2] - cc->force[2]) / fabs(cc->force[2]);
    printf("%s, %s mesh: force on B across %.2f %%\n", name, fascia_tissue_mesh_name(mesh), 100 * ez);
    CHECK(ez < TOLERANCE);
  }
}

// The pull on the right-triangle mesh, then on the near-equilateral
// (shifted) and irregular (jittered) ones, where a stabiliser that felt the
// change of area alone left a drilling field free: +6 % and +9.5 % at the
// free edge sheared and stretched, 2-3 % soft in force jittered, and a
// 40 x 32 sag that found another equilibrium.
static void check_pull(fascia_ctx *ctx, const char *program, const char *name, double x, double y, double z,
                       int cells_x, int cells_y) {
  fascia_tissue_pull_def def = fascia_tissue_pull_def_default();
  def.pull[0] = x, def.pull[1] = y, def.pull[2] = z;
  def.cells[0] = cells_x, def.cells[1] = cells_y;
  fascia_tissue_pull_result cc;
  const fascia_status sc = fascia_tissue_pull_calculix(ctx, &def, program, &cc);
  if (sc != FASCIA_OK) fprintf(stderr, "%s, ccx: %s\n", name, fascia_ctx_message(ctx));
  CHECK(sc == FASCIA_OK);
  if (sc != FASCIA_OK) return;
  check_mesh(ctx, name, def, FASCIA_TISSUE_MESH_RIGHT, &cc, 1);
  check_mesh(ctx, name, def, FASCIA_TISSUE_MESH_SHIFTED, &cc, z == 0);
  check_mesh(ctx, name, def, FASCIA_TISSUE_MESH_JITTERED, &cc, z == 0);
}

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  check_decks(ctx);
  const char *program = fascia_ccx_program();
  if (!program) {
    printf("skipped: CalculiX (ccx) is not installed (Debian: calculix-ccx, or set FASCIA_CCX); the decks were "
           "checked, not solved\n");
    fascia_ctx_destroy(&ctx);
    return check_failures_ ? 1 : TEST_SKIP;
  }
  check_hang(ctx, program);
  check_pull(ctx, program, "shear", 0, 0.001, 0, 10, 8);
  check_pull(ctx, program, "stretch", 0.001, 0, 0, 10, 8);
  check_pull(ctx, program, "sag", 0, 0, 0.002, 10, 8);
  check_pull(ctx, program, "bend", 0, 0, 0.0001, 10, 8);
  fascia_ctx_destroy(&ctx);
  return check_failures_ != 0;
}
