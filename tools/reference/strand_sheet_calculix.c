// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// strand-sheet-calculix: fascia's strand hanging an organ and sheet under a
// pull against CalculiX on the same geometry (tools/scenes/tissue_calculix.h,
// docs/mechanics.md "Strands and sheets"). Solves each case with fascia at a
// ladder of resolutions and with ccx at a ladder of meshes, and prints the
// values and fascia's errors against ccx's finest mesh; --csv writes them.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "beam_calculix.h"
#include "tissue_calculix.h"

#define MAX_LADDER 16

static const char usage[] =
    "usage: strand-sheet-calculix [--spacings MM,...] [--elements N,...] [--cells NXxNY,...]\n"
    "                             [--shells NXxNY,...] [--pulls NAME,...] [--thickness MM] [--mesh KIND]\n"
    "                             [--no-strand] [--csv FILE]\n"
    "\n"
    "A strand (20 mm, 2 x 2 mm section, E 100 MPa) hanging a rigid 20 mm organ off a fixed one, and\n"
    "a 20 x 16 x 1 mm sheet (E 100 kPa) between them pulled by the second, solved by fascia and by\n"
    "CalculiX (B32 beams, S8R shells, NLGEOM); errors are |fascia - ccx| / |ccx| of vectors, against\n"
    "ccx's last (finest) mesh.\n"
    "  --spacings LIST  fascia's strand frame spacings, mm (default 4,2,1,0.5)\n"
    "  --elements LIST  ccx's B32 elements along the strand (default 10,20,40,80)\n"
    "  --cells LIST     fascia's sheet mesh squares (default 4x4,10x8,20x16,40x32)\n"
    "  --shells LIST    ccx's S8R elements (default 10x8,20x16,40x32)\n"
    "  --pulls LIST     of shear (B moved 1 mm along y), stretch (1 mm along x), bend (0.1 mm\n"
    "                   along z), sag (2 mm along z); default shear,stretch,bend,sag\n"
    "  --thickness MM   the sheet's thickness (default 1): a bent sheet that locks errs as (cell / thickness)^2\n"
    "  --mesh KIND      fascia's sheet triangles: right (squares split by alternating diagonals, the\n"
    "                   default), shifted (rows shifted by half a square: near-equilateral), jittered\n"
    "                   (those with inner vertices moved by up to a fifth of a square); ccx's S8R mesh\n"
    "                   is the same for all\n"
    "  --no-strand      only the sheet\n"
    "  --csv FILE       also write the rows as CSV\n"
    "The ccx program is $FASCIA_CCX or ccx on the PATH (Debian: calculix-ccx).\n";

static int usage_error(const char *what, const char *value) {
  fprintf(stderr, "strand-sheet-calculix: %s %s (see --help)\n", what, value ? value : "");
  return 2;
}

static int parse_numbers(const char *text, double *v, int *count) {
  *count = 0;
  for (const char *p = text; *p;) {
    char *end;
    if (*count == MAX_LADDER) return 0;
    v[*count] = strtod(p, &end);
    if (end == p || !(v[*count] > 0)) return 0;
    ++*count;
    p = *end == ',' ? end + 1 : end;
    if (*end && *end != ',') return 0;
  }
  return *count > 0;
}

static int parse_pairs(const char *text, int32_t (*v)[2], int *count) {
  *count = 0;
  for (const char *p = text; *p;) {
    int a, b, used = 0;
    if (*count == MAX_LADDER || sscanf(p, "%dx%d%n", &a, &b, &used) != 2) return 0;
    v[*count][0] = a, v[*count][1] = b;
    ++*count;
    p += used;
    if (*p == ',') ++p;
    else if (*p) return 0;
  }
  return *count > 0;
}

typedef struct pull_kind {
  const char *name;
  double pull[3];
} pull_kind;

static const pull_kind pulls[] = {
    {"shear", {0, 0.001, 0}}, {"stretch", {0.001, 0, 0}}, {"bend", {0, 0, 0.0001}}, {"sag", {0, 0, 0.002}}};
enum { PULL_KINDS = sizeof pulls / sizeof pulls[0] };

int main(int argc, char **argv) {
  double spacing[MAX_LADDER] = {4, 2, 1, 0.5}, beam_elements[MAX_LADDER] = {10, 20, 40, 80};
  int spacings = 4, beam_count = 4, cell_count = 4, shell_count = 3;
  int32_t cells[MAX_LADDER][2] = {{4, 4}, {10, 8}, {20, 16}, {40, 32}}, shells[MAX_LADDER][2] = {{10, 8}, {20, 16}, {40, 32}};
  int wanted[PULL_KINDS] = {1, 1, 1, 1};
  const char *csv_path = NULL;
  double thickness = 0;
  int32_t mesh = FASCIA_TISSUE_MESH_RIGHT;
  int strand = 1;
  for (int k = 1; k < argc; ++k) {
    const char *a = argv[k], *v = k + 1 < argc ? argv[k + 1] : NULL;
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      fputs(usage, stdout);
      return 0;
    } else if (!strcmp(a, "--no-strand")) {
      strand = 0;
      continue;
    } else if (!v) {
      return usage_error("missing value after", a);
    } else if (!strcmp(a, "--spacings")) {
      if (!parse_numbers(v, spacing, &spacings)) return usage_error("bad --spacings", v);
    } else if (!strcmp(a, "--elements")) {
      if (!parse_numbers(v, beam_elements, &beam_count)) return usage_error("bad --elements", v);
    } else if (!strcmp(a, "--cells")) {
      if (!parse_pairs(v, cells, &cell_count)) return usage_error("bad --cells", v);
    } else if (!strcmp(a, "--shells")) {
      if (!parse_pairs(v, shells, &shell_count)) return usage_error("bad --shells", v);
    } else if (!strcmp(a, "--pulls")) {
      memset(wanted, 0, sizeof wanted);
      char list[256];
      snprintf(list, sizeof list, "%s", v);
      for (char *t = strtok(list, ","); t; t = strtok(NULL, ",")) {
        int found = 0;
        for (int p = 0; p < PULL_KINDS; ++p)
          if (!strcmp(t, pulls[p].name)) wanted[p] = found = 1;
        if (!found) return usage_error("unknown pull", t);
      }
    } else if (!strcmp(a, "--thickness")) {
      char *end;
      thickness = 1e-3 * strtod(v, &end);
      if (end == v || *end || !(thickness > 0)) return usage_error("bad --thickness", v);
    } else if (!strcmp(a, "--mesh")) {
      for (mesh = 0; fascia_tissue_mesh_name(mesh) && strcmp(fascia_tissue_mesh_name(mesh), v); ++mesh) continue;
      if (!fascia_tissue_mesh_name(mesh)) return usage_error("bad --mesh (right, shifted or jittered)", v);
    } else if (!strcmp(a, "--csv")) {
      csv_path = v;
    } else {
      return usage_error("unknown option", a);
    }
    ++k;
  }
  const char *program = fascia_ccx_program();
  if (!program) {
    fprintf(stderr, "strand-sheet-calculix: CalculiX (ccx) is not installed: install calculix-ccx or set FASCIA_CCX\n");
    return 1;
  }
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  FILE *csv = NULL;
  if (csv_path && !(csv = fopen(csv_path, "w"))) {
    fprintf(stderr, "strand-sheet-calculix: cannot write %s\n", csv_path);
    return 1;
  }
  if (csv)
    fprintf(csv, "case,code,resolution,nodes,ms,a_x,a_y,a_z,b_x,b_y,b_z,c_x,c_y,c_z,angle,error_a,error_b,error_c,"
                 "error_angle\n");
  int failed = 0;

  // the hanging organ: a = the organ's centre's displacement (m), b = the
  // strand's end's, c = the strand's force on the fixed organ (N)
  fascia_tissue_hang_result hang[2][MAX_LADDER];
  int hang_ok[2][MAX_LADDER];
  for (int pass = 0; pass < 2 && strand; ++pass)
    for (int k = 0; k < (pass ? spacings : beam_count); ++k) {
      fascia_tissue_hang_def def = fascia_tissue_hang_def_default();
      if (pass) def.frame_spacing = 1e-3 * spacing[k];
      else def.elements = (int32_t)beam_elements[k];
      const fascia_status st = pass ? fascia_tissue_hang_fascia(ctx, &def, &hang[pass][k])
                                    : fascia_tissue_hang_calculix(ctx, &def, program, &hang[pass][k]);
      hang_ok[pass][k] = st == FASCIA_OK;
      if (st != FASCIA_OK) {
        fprintf(stderr, "strand-sheet-calculix: hanging organ, %s at %g: %s\n", pass ? "fascia" : "ccx",
                pass ? spacing[k] : beam_elements[k], fascia_ctx_message(ctx));
        failed = 1;
      }
    }
  const fascia_tissue_hang_result *ref = strand && hang_ok[0][beam_count - 1] ? &hang[0][beam_count - 1] : NULL;
  if (strand) printf("strand hanging an organ: displacements in mm, force in mN, angle in mrad; errors against ccx's last\n");
  if (strand)
    printf("%-8s %-12s %6s %28s %28s %26s %8s | err centre  end  force  angle\n", "code", "resolution", "nodes",
           "organ centre", "strand end", "force on A", "angle");
  for (int pass = 0; pass < 2 && ref; ++pass)
    for (int k = 0; k < (pass ? spacings : beam_count); ++k) {
      if (!hang_ok[pass][k]) continue;
      const fascia_tissue_hang_result *r = &hang[pass][k];
      char resolution[64];
      if (pass) snprintf(resolution, sizeof resolution, "%g mm", spacing[k]);
      else snprintf(resolution, sizeof resolution, "%g B32", beam_elements[k]);
      const double e[4] = {fascia_tissue_error3(r->centre, ref->centre), fascia_tissue_error3(r->end, ref->end),
                           fascia_tissue_error3(r->force, ref->force), fabs(r->angle - ref->angle) / fabs(ref->angle)};
      printf("%-8s %-12s %6d %9.5f %9.5f %9.5f %9.5f %9.5f %9.5f %8.4f %8.4f %8.4f %8.3f | %6.2f%% %5.2f%% %5.2f%% "
             "%5.2f%%\n",
             pass ? "fascia" : "ccx", resolution, (int)r->nodes, 1e3 * r->centre[0], 1e3 * r->centre[1],
             1e3 * r->centre[2], 1e3 * r->end[0], 1e3 * r->end[1], 1e3 * r->end[2], 1e3 * r->force[0],
             1e3 * r->force[1], 1e3 * r->force[2], 1e3 * r->angle, 100 * e[0], 100 * e[1], 100 * e[2], 100 * e[3]);
      if (csv)
        fprintf(csv, "hang,%s,%s,%d,%.4g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.4g,%.4g,%.4g,%.4g\n",
                pass ? "fascia" : "ccx", resolution, (int)r->nodes, r->ms, r->centre[0], r->centre[1], r->centre[2],
                r->end[0], r->end[1], r->end[2], r->force[0], r->force[1], r->force[2], r->angle, e[0], e[1], e[2],
                e[3]);
    }

  // the pulled sheet: a = the sheet's force on B (N), b = the free edge's
  // middle's displacement relative to the centre's, c = the centre's
  for (int p = 0; p < PULL_KINDS; ++p) {
    if (!wanted[p]) continue;
    printf("\nsheet under a pull, %s: B moved by (%g, %g, %g) mm; force in mN, displacements in mm; fascia's mesh %s\n",
           pulls[p].name, 1e3 * pulls[p].pull[0], 1e3 * pulls[p].pull[1], 1e3 * pulls[p].pull[2],
           fascia_tissue_mesh_name(mesh));
    printf("%-8s %-12s %6s %30s %28s %28s | err force  edge  centre newton/indefinite\n", "code", "resolution", "nodes", "force on B",
           "free edge's middle - centre", "centre");
    fascia_tissue_pull_result res[2][MAX_LADDER];
    int ok[2][MAX_LADDER];
    for (int pass = 0; pass < 2; ++pass)
      for (int k = 0; k < (pass ? cell_count : shell_count); ++k) {
        fascia_tissue_pull_def def = fascia_tissue_pull_def_default();
        memcpy(def.pull, pulls[p].pull, sizeof def.pull);
        if (thickness > 0) def.thickness = thickness;
        def.mesh = mesh;
        if (pass) def.cells[0] = cells[k][0], def.cells[1] = cells[k][1];
        else def.elements[0] = shells[k][0], def.elements[1] = shells[k][1];
        const fascia_status st = pass ? fascia_tissue_pull_fascia(ctx, &def, &res[pass][k])
                                      : fascia_tissue_pull_calculix(ctx, &def, program, &res[pass][k]);
        ok[pass][k] = st == FASCIA_OK;
        if (st != FASCIA_OK) {
          fprintf(stderr, "strand-sheet-calculix: %s, %s at %dx%d: %s\n", pulls[p].name, pass ? "fascia" : "ccx",
                  (int)(pass ? cells : shells)[k][0], (int)(pass ? cells : shells)[k][1], fascia_ctx_message(ctx));
          failed = 1;
        }
      }
    const fascia_tissue_pull_result *pref = ok[0][shell_count - 1] ? &res[0][shell_count - 1] : NULL;
    for (int pass = 0; pass < 2 && pref; ++pass)
      for (int k = 0; k < (pass ? cell_count : shell_count); ++k) {
        if (!ok[pass][k]) continue;
        const fascia_tissue_pull_result *r = &res[pass][k];
        char resolution[64];
        snprintf(resolution, sizeof resolution, "%dx%d%s", (int)(pass ? cells : shells)[k][0],
                 (int)(pass ? cells : shells)[k][1], pass ? "" : " S8R");
        const double e[3] = {fascia_tissue_error3(r->force, pref->force), fascia_tissue_error3(r->edge, pref->edge),
                             fascia_tissue_error3(r->centre, pref->centre)};
        printf("%-8s %-12s %6d %10.5f %9.5f %9.5f %9.5f %9.5f %9.5f %9.5f %9.5f %9.5f | %6.2f%% %5.2f%% %5.2f%% %6d/%d\n",
               pass ? "fascia" : "ccx", resolution, (int)r->nodes, 1e3 * r->force[0], 1e3 * r->force[1],
               1e3 * r->force[2], 1e3 * r->edge[0], 1e3 * r->edge[1], 1e3 * r->edge[2], 1e3 * r->centre[0],
               1e3 * r->centre[1], 1e3 * r->centre[2], 100 * e[0], 100 * e[1], 100 * e[2], (int)r->newton_iterations,
               (int)r->negative_curvature);
        if (csv)
          fprintf(csv, "%s,%s,%s,%d,%.4g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,,%.4g,%.4g,%.4g,\n",
                  pulls[p].name, pass ? "fascia" : "ccx", resolution, (int)r->nodes, r->ms, r->force[0], r->force[1],
                  r->force[2], r->edge[0], r->edge[1], r->edge[2], r->centre[0], r->centre[1], r->centre[2], e[0],
                  e[1], e[2]);
      }
  }
  if (csv && fclose(csv) != 0) failed = 1;
  fascia_ctx_destroy(&ctx);
  return failed;
}
