// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// shell-calculix: fascia's shell organs against CalculiX S8R shells
// (tools/scenes/shell_calculix.h), side by side: CalculiX's mesh ladder
// (how it converges), then fascia at each frame spacing against the
// finest CalculiX mesh. --reference FILE writes the CalculiX rows as the
// CSV that data/reference/shell-calculix.csv holds (tests/t597 compares
// fascia with it).
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "beam_calculix.h"
#include "shell_calculix.h"

#define MAX_ROWS 16

static void usage(FILE *f) {
  fprintf(f,
          "usage: shell-calculix [--case plate|bowl] [--E PA] [--elements N,...] [--spacings M,...]\n"
          "                      [--reference FILE] [--csv FILE] [--no-fascia] [--no-calculix] [--seed N]\n"
          "                      [--split K]\n\n"
          "fascia's shell organ against CalculiX S8R shells (NLGEOM) under their own weight:\n"
          "  plate  the paper's cantilever as a thin shell, 16 x 1 m, 0.1 m thick, E 4 MPa, the edge\n"
          "         x = 0 clamped; probe: the free end's centre\n"
          "  bowl   a hemisphere of radius 50 mm, 1 mm thick, E 100 kPa, hanging from its clamped rim;\n"
          "         probe: its bottom\n"
          "  --E PA          Young's modulus (default: the case's)\n"
          "  --elements LIST CalculiX meshes, finest last (plate: elements along x, 4 x as many\n"
          "                  along x as across ... given as NX; bowl: elements along a quarter rim)\n"
          "  --spacings LIST fascia's frame_spacing values, m of the case\n"
          "  --reference F   write the CalculiX rows (CSV) to F\n"
          "  --csv F         write every row (CSV) to F\n"
          "  --seed N        fascia's scene seed, the draw of the shell's frames (default 1)\n"
          "  --split K       fascia's sample_spacing = frame_spacing / K: each wall triangle split into\n"
          "                  K x K points (default 1: one point per triangle)\n"
          "The ccx program is $FASCIA_CCX or ccx on the PATH (Debian: calculix-ccx).\n");
}

static int parse_list(const char *text, double *v, int max) {
  int n = 0;
  for (const char *p = text; p && *p && n < max;) {
    char *end;
    v[n++] = strtod(p, &end);
    if (end == p) return -1;
    p = *end == ',' ? end + 1 : (*end ? NULL : end);
    if (!p) return -1;
  }
  return n;
}

static void set_elements(fascia_shell_def *d, double n) {
  d->elements[0] = (int32_t)n;
  if (d->kind == FASCIA_SHELL_PLATE) d->elements[1] = 2 * (int32_t)fmax(1, round(n / 32));
}

int main(int argc, char **argv) {
  int kind = FASCIA_SHELL_PLATE, fascia = 1, calculix = 1;
  double E = 0, elements[MAX_ROWS], spacings[MAX_ROWS];
  int seed = 1, split = 1;
  int ne = 0, ns = 0;
  const char *reference = NULL, *csv = NULL;
  for (int k = 1; k < argc; ++k) {
    const char *a = argv[k], *v = k + 1 < argc ? argv[k + 1] : NULL;
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      usage(stdout);
      return 0;
    } else if (!strcmp(a, "--case") && v) {
      if (strcmp(v, "plate") && strcmp(v, "bowl")) {
        fprintf(stderr, "shell-calculix: --case %s: expected plate or bowl\n", v);
        return 2;
      }
      kind = strcmp(v, "plate") ? FASCIA_SHELL_BOWL : FASCIA_SHELL_PLATE, ++k;
    } else if (!strcmp(a, "--E") && v) {
      E = atof(v), ++k;
    } else if (!strcmp(a, "--elements") && v) {
      ne = parse_list(v, elements, MAX_ROWS), ++k;
    } else if (!strcmp(a, "--spacings") && v) {
      ns = parse_list(v, spacings, MAX_ROWS), ++k;
    } else if (!strcmp(a, "--reference") && v) {
      reference = v, ++k;
    } else if (!strcmp(a, "--seed") && v) {
      seed = atoi(v), ++k;
    } else if (!strcmp(a, "--split") && v) {
      split = atoi(v), ++k;
    } else if (!strcmp(a, "--csv") && v) {
      csv = v, ++k;
    } else if (!strcmp(a, "--no-fascia")) {
      fascia = 0;
    } else if (!strcmp(a, "--no-calculix")) {
      calculix = 0;
    } else {
      fprintf(stderr, "shell-calculix: unknown or incomplete option '%s'\n", a);
      usage(stderr);
      return 2;
    }
  }
  if (ne < 0 || ns < 0) {
    fprintf(stderr, "shell-calculix: --elements and --spacings take numbers separated by commas\n");
    return 2;
  }
  fascia_shell_def def = fascia_shell_def_default(kind);
  if (E > 0) def.youngs_modulus = E;
  def.seed = seed;
  def.split = split;
  if (ne == 0) {
    const double plate[] = {32, 64, 128, 256}, bowl[] = {8, 16, 32, 48};
    ne = 4;
    memcpy(elements, kind == FASCIA_SHELL_PLATE ? plate : bowl, sizeof plate);
  }
  if (ns == 0) {
    const double plate[] = {0.5, 0.25, 0.125}, bowl[] = {0.012, 0.006, 0.004};
    ns = 3;
    memcpy(spacings, kind == FASCIA_SHELL_PLATE ? plate : bowl, sizeof plate);
  }
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  const char *program = fascia_ccx_program();
  if (calculix && !program) {
    fprintf(stderr, "shell-calculix: CalculiX (ccx) is not installed (Debian: calculix-ccx, or set FASCIA_CCX)\n");
    return 1;
  }
  const char *name = kind == FASCIA_SHELL_PLATE ? "plate" : "bowl";
  FILE *rows = csv ? fopen(csv, "w") : NULL, *ref = reference ? fopen(reference, "w") : NULL;
  if ((csv && !rows) || (reference && !ref)) {
    fprintf(stderr, "shell-calculix: cannot write %s\n", csv && !rows ? csv : reference);
    return 1;
  }
  if (rows) fprintf(rows, "case,E,code,resolution,nodes,probe_ux,probe_uy,probe_uz,change_or_error,newton,ms\n");
  if (ref) fprintf(ref, "case,E,nu,thickness,elements,nodes,probe_ux,probe_uy,probe_uz,change_uz\n");
  printf("%s, E %g Pa, nu %g, %g m thick; probe displacement (m)\n", name, def.youngs_modulus, def.poisson_ratio,
         def.thickness);
  double best[3] = {0, 0, 0}, last_uz = NAN;
  int failed = 0;
  for (int k = 0; calculix && k < ne; ++k) {
    set_elements(&def, elements[k]);
    fascia_shell_result r;
    if (fascia_shell_calculix(ctx, &def, program, &r) != FASCIA_OK) {
      fprintf(stderr, "shell-calculix: %s\n", fascia_ctx_message(ctx));
      failed = 1;
      continue;
    }
    const double change = isnan(last_uz) ? NAN : r.probe[2] - last_uz;
    printf("  CalculiX S8R %4dx%-3d %6d nodes  u (%+.6f %+.6f %+.6f)  change uz %+.2e (%.3f %%)  %8.0f ms\n",
           (int)def.elements[0], (int)def.elements[1], (int)r.nodes, r.probe[0], r.probe[1], r.probe[2], change,
           100 * fabs(change / r.probe[2]), r.ms);
    if (rows)
      fprintf(rows, "%s,%g,calculix,%dx%d,%d,%.9g,%.9g,%.9g,%.3g,,%.1f\n", name, def.youngs_modulus,
              (int)def.elements[0], (int)def.elements[1], (int)r.nodes, r.probe[0], r.probe[1], r.probe[2], change,
              r.ms);
    if (ref)
      fprintf(ref, "%s,%g,%g,%g,%dx%d,%d,%.9g,%.9g,%.9g,%.3g\n", name, def.youngs_modulus, def.poisson_ratio,
              def.thickness, (int)def.elements[0], (int)def.elements[1], (int)r.nodes, r.probe[0], r.probe[1],
              r.probe[2], change);
    memcpy(best, r.probe, sizeof best);
    last_uz = r.probe[2];
  }
  for (int k = 0; fascia && k < ns; ++k) {
    def.frame_spacing = spacings[k];
    fascia_shell_result r;
    if (fascia_shell_fascia(ctx, &def, &r) != FASCIA_OK) {
      fprintf(stderr, "shell-calculix: fascia, spacing %g m: %s\n", spacings[k], fascia_ctx_message(ctx));
      failed = 1;
      continue;
    }
    double d = 0, n = 0;
    for (int a = 0; a < 3; ++a) d += (r.probe[a] - best[a]) * (r.probe[a] - best[a]), n += best[a] * best[a];
    const double error = n > 0 ? sqrt(d / n) : NAN;
    printf("  fascia spacing %-7g %6d frames  u (%+.6f %+.6f %+.6f)  error %.2f %%  Newton %d  %8.1f ms\n",
           spacings[k], (int)r.nodes, r.probe[0], r.probe[1], r.probe[2], 100 * error, (int)r.newton, r.ms);
    if (rows)
      fprintf(rows, "%s,%g,fascia,%g,%d,%.9g,%.9g,%.9g,%.4g,%d,%.1f\n", name, def.youngs_modulus, spacings[k],
              (int)r.nodes, r.probe[0], r.probe[1], r.probe[2], error, (int)r.newton, r.ms);
  }
  if (rows) fclose(rows);
  if (ref) fclose(ref);
  fascia_ctx_destroy(&ctx);
  return failed;
}
