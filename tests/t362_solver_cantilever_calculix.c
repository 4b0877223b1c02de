// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// fascia's cantilever at a fine resolution agrees with the converged 3-D
// CalculiX reference (St. Venant-Kirchhoff, nu = 0.3; data/reference/):
// 40 x 5 x 5 hexahedral frames with the volumetric energy at one sample per
// cell within 0.5 % of the reference tip uz (docs/mechanics.md), closer than
// at 20 x 3 x 3, and the default (full) integration within 2 %, stiff.
#include <string.h>

#include "beam_calculix.h"
#include "beam_tip.h"
#include "check.h"
#include "fascia/solver.h"
#include "scenes.h"

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  const fascia_scene_beam_def beam = fascia_scene_beam_def_default();
  const fascia_ccx_reference *ref = fascia_ccx_reference_find(&beam);
  CHECK(ref != NULL);
  if (!ref) return 1;
  double coarse = 0, fine = 0, full = 0, mass = 0;
  if (beam_tip_uz(ctx, 20, 3, 0.3, 1, &coarse, &mass) || beam_tip_uz(ctx, 40, 5, 0.3, 1, &fine, &mass) ||
      beam_tip_uz(ctx, 40, 5, 0.3, 0, &full, &mass))
    return 1;
  const double e_coarse = (coarse - ref->tip_uz) / fabs(ref->tip_uz), e_fine = (fine - ref->tip_uz) / fabs(ref->tip_uz);
  const double e_full = (full - ref->tip_uz) / fabs(ref->tip_uz);
  printf("reference uz %.5f m; reduced 20x3x3 %.5f (%+.3f %%), 40x5x5 %.5f (%+.3f %%); full 40x5x5 %.5f (%+.3f %%)\n",
         ref->tip_uz, coarse, 100 * e_coarse, fine, 100 * e_fine, full, 100 * e_full);
  CHECK(fabs(e_fine) < 0.005);
  CHECK(fabs(e_fine) < fabs(e_coarse));
  CHECK(e_full > 0 && e_full < 0.02);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
