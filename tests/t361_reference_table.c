// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The references compiled into fascia (fascia_ccx_references, used by
// `fascia bench` and `fascia tradeoff`) are the ones stored in
// data/reference/cantilever-calculix.csv, row for row.
// Usage: t361_reference_table DATA_REFERENCE_DIR
#include <string.h>

#include "beam_calculix.h"
#include "check.h"
#include "fascia/fascia.h"
#include "reference_csv.h"

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: t361_reference_table DATA_REFERENCE_DIR\n");
    return 2;
  }
  char path[2048];
  snprintf(path, sizeof path, "%s/cantilever-calculix.csv", argv[1]);
  int count = 0;
  const fascia_ccx_reference *refs = fascia_ccx_references(&count);
  CHECK(count >= 7);
  for (int k = 0; k < count; ++k) {
    char E[32], nu[32];
    snprintf(E, sizeof E, "%g", refs[k].youngs_modulus);
    snprintf(nu, sizeof nu, "%g", refs[k].poisson_ratio);
    const char *key[] = {"law", fascia_law_name(refs[k].law), "E", E, "nu", nu};
    double ux = 0, uz = 0, du = 0;
    CHECK(reference_csv_number(path, key, 3, "tip_ux", &ux));
    CHECK(reference_csv_number(path, key, 3, "tip_uz", &uz));
    CHECK(reference_csv_number(path, key, 3, "uncertainty_uz", &du));
    CHECK_NEAR(refs[k].tip_ux, ux, 0, 1e-12);
    CHECK_NEAR(refs[k].tip_uz, uz, 0, 1e-12);
    CHECK_NEAR(refs[k].uncertainty_uz, du, 0, 1e-12);
    // the lookup by beam finds it
    fascia_scene_beam_def def = fascia_scene_beam_def_default();
    def.law = refs[k].law, def.youngs_modulus = refs[k].youngs_modulus, def.poisson_ratio = refs[k].poisson_ratio;
    CHECK(fascia_ccx_reference_find(&def) == refs + k);
  }
  // no row of the file is missing from the table
  FILE *f = fopen(path, "r");
  int rows = -1; // the header
  char line[REFERENCE_CSV_LINE];
  while (f && fgets(line, sizeof line, f)) rows += line[0] != '\n';
  if (f) fclose(f);
  CHECK(rows == count);
  // a beam the reference does not cover finds none
  fascia_scene_beam_def other = fascia_scene_beam_def_default();
  other.length = 8;
  CHECK(fascia_ccx_reference_find(&other) == NULL);
  return CHECK_RESULT();
}
