// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The stored CalculiX reference of the cantilever still follows from the
// deck: the coarse mesh of the reference's refinement, solved again by ccx,
// gives the tip stored for that mesh in the refinement table, and lies
// within the coarse mesh's stated error of the converged reference
// (data/reference/README.md). A change to the deck (geometry, material,
// load, clamp, probe) fails here until the reference is recomputed.
// Skipped without ccx (Debian: calculix-ccx; tools/setup installs it).
// Usage: t360_reference_calculix_deck DATA_REFERENCE_DIR
#include <stdlib.h>
#include <string.h>

#include "beam_calculix.h"
#include "check.h"
#include "fascia/fascia.h"
#include "reference_csv.h"

// One coarse deck per law: the first mesh of the reference ladder.
static int check_case(fascia_ctx *ctx, const char *dir, const char *program, const char *law, double nu) {
  char path[2048];
  snprintf(path, sizeof path, "%s/cantilever-calculix.csv", dir);
  const char *ref_key[] = {"law", law, "E", "40000", "nu", NULL};
  char nu_text[32];
  snprintf(nu_text, sizeof nu_text, "%g", nu);
  ref_key[5] = nu_text;
  double tip_uz = 0, coarse_error = 0;
  CHECK(reference_csv_number(path, ref_key, 3, "tip_uz", &tip_uz));
  CHECK(reference_csv_number(path, ref_key, 3, "coarse_error_uz", &coarse_error));
  snprintf(path, sizeof path, "%s/cantilever-calculix-refinement.csv", dir);
  const char *row_key[] = {"element", "C3D20R", "law", law, "nu", nu_text, "E", "40000", "mesh", "32x2x4",
                           "grading_x", "64", "half", "1"};
  double stored_uz = 0;
  CHECK(reference_csv_number(path, row_key, 7, "tip_uz", &stored_uz));

  fascia_ccx_beam_def def = fascia_ccx_beam_def_default();
  def.beam.law = fascia_law_from_name(law);
  def.beam.poisson_ratio = nu;
  def.cells[0] = 32, def.cells[1] = 2, def.cells[2] = 4;
  def.half = 1;
  def.grading[0] = 64, def.grading[1] = def.grading[2] = 4;
  fascia_ccx_result r;
  CHECK_OK(fascia_ccx_beam_solve(ctx, &def, program, 1, &r), ctx);
  printf("%s nu %g: 32x2x4@64 uz %.6f m (stored %.6f), reference %.6f, stated coarse error %.5f\n", law, nu,
         r.tip[2], stored_uz, tip_uz, coarse_error);
  CHECK_NEAR(r.tip[2], stored_uz, 1e-5, 0);                // the same deck, the same answer
  CHECK(fabs(r.tip[2] - tip_uz) <= coarse_error);         // the converged value is where the table says
  CHECK(coarse_error > 0 && coarse_error < 0.002 * fabs(tip_uz)); // and the coarse deck is already close
  CHECK(fabs(r.tip[1]) < 1e-9);                           // the half beam's symmetry plane holds
  return 0;
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: t360_reference_calculix_deck DATA_REFERENCE_DIR\n");
    return 2;
  }
  const char *program = fascia_ccx_program();
  if (!program) {
    printf("skipped: CalculiX (ccx) is not installed (apt-get install calculix-ccx)\n");
    return TEST_SKIP;
  }
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  if (check_case(ctx, argv[1], program, "stvk", 0.3)) return 1;
  if (check_case(ctx, argv[1], program, "neohookean", 0.49)) return 1;
  // a bad deck is refused before ccx runs, naming the field
  fascia_ccx_beam_def bad = fascia_ccx_beam_def_default();
  bad.cells[2] = 3;
  fascia_ccx_result r;
  CHECK(fascia_ccx_beam_solve(ctx, &bad, program, 1, &r) == FASCIA_ERR_ARGUMENT);
  CHECK(strstr(fascia_ctx_message(ctx), "along z") != NULL);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
