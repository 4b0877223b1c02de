// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// cantilever-calculix: the converged 3-D nonlinear finite-element reference
// of fascia's cantilever. Solves the CalculiX deck of
// tools/scenes/beam_calculix.c on a ladder of meshes, finest last, prints
// the refinement table (elements, DOFs, tip displacement, change from the
// previous mesh) and says whether the tip stopped moving; --csv writes the
// table (data/reference/README.md says how the stored reference was made).
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "beam_calculix.h"
#include "fascia/fascia.h"

#define MAX_MESHES 32

static const char usage[] =
    "usage: cantilever-calculix [--element C3D20R|C3D8I] [--law stvk|neohookean] [--E PA] [--nu V]\n"
    "                           [--meshes NXxNYxNZ[@GX],...] [--grading GX,GYZ] [--tolerance REL]\n"
    "                           [--half] [--threads T]"
    " [--csv FILE] [--deck FILE]\n"
    "\n"
    "Solves fascia's cantilever (fascia beam: 16 x 1 x 1 m, clamped at x = 0, 5 kg under gravity)\n"
    "with CalculiX (ccx, NLGEOM) on each mesh in turn and prints the tip displacement at (16, 0, 0).\n"
    "  --element NAME    C3D20R (default) or C3D8I\n"
    "  --law NAME        stvk (default: *ELASTIC, exactly fascia's St. Venant-Kirchhoff) or\n"
    "                    neohookean (*HYPERELASTIC, NEO HOOKE: same small-strain moduli)\n"
    "  --E PA, --nu V    Young's modulus (default 40000) and Poisson ratio (default 0.3)\n"
    "  --meshes LIST     elements along x, y, z (y and z even; y: across the half with --half),\n"
    "                    @GX: that mesh's grading along x (default: the reference's ladder,\n"
    "                    32x2x4@64,64x2x4@256,64x4x8@256 on the half beam, grading 1,4)\n"
    "  --grading GX,GYZ  largest over smallest element, geometric: along x from the clamp, across\n"
    "                    y and z from the surfaces (default 1,1: uniform)\n"
    "  --half            only the half y >= 0, held in y on y = 0 (NY: elements across it)\n"
    "  --tolerance REL   the tip has stopped moving when the last change of uz is under REL |uz|\n"
    "                    (default 1e-4)\n"
    "  --threads T       ccx threads (default 1)\n"
    "  --csv FILE        also write the table as CSV\n"
    "  --deck FILE       write the deck of the first mesh to FILE and stop (ccx not run)\n"
    "The ccx program is $FASCIA_CCX or ccx on the PATH (Debian: calculix-ccx).\n";

static int usage_error(const char *what, const char *value) {
  fprintf(stderr, "cantilever-calculix: %s%s%s (see --help)\n", what, value ? " " : "", value ? value : "");
  return 2;
}

// NXxNYxNZ[@GX],... ; a mesh without @GX gets `grading`.
static int parse_meshes(const char *text, double grading, int32_t (*meshes)[3], double *gx, int *count) {
  *count = 0;
  for (const char *p = text; *p;) {
    int nx, ny, nz, used = 0;
    if (*count == MAX_MESHES || sscanf(p, "%dx%dx%d%n", &nx, &ny, &nz, &used) != 3) return 0;
    meshes[*count][0] = nx, meshes[*count][1] = ny, meshes[*count][2] = nz;
    p += used;
    gx[*count] = grading;
    if (*p == '@' && sscanf(p + 1, "%lf%n", gx + *count, &used) == 1) p += 1 + used;
    ++*count;
    if (*p == ',') ++p;
    else if (*p) return 0;
  }
  return *count > 0;
}

static int parse_real(const char *text, double *out) {
  char *end = NULL;
  errno = 0;
  *out = strtod(text, &end);
  return text[0] && !*end && !errno && isfinite(*out);
}

static int write_deck(fascia_ctx *ctx, const fascia_ccx_beam_def *def, const char *path) {
  fascia_file *file = NULL;
  fascia_status st = fascia_file_open(ctx, "--deck", path, &file);
  if (st == FASCIA_OK) st = fascia_ccx_beam_write(ctx, def, fascia_file_stream(file));
  if (st == FASCIA_OK) st = fascia_file_commit(&file);
  fascia_file_discard(&file);
  if (st == FASCIA_OK) return 0;
  fprintf(stderr, "cantilever-calculix: %s\n", fascia_ctx_message(ctx));
  return 1;
}

static void csv_rows(FILE *f, const fascia_ccx_beam_def *def, const int32_t (*meshes)[3], const double *gx,
                     const fascia_ccx_result *r, int count) {
  fprintf(f, "element,law,E,nu,grading_x,grading_yz,half,mesh,elements,nodes,dofs,tip_ux,tip_uy,tip_uz,change_uz,newton,increments,cpu_s\n");
  for (int k = 0; k < count; ++k) {
    fprintf(f, "%s,%s,%g,%g,%g,%g,%d,%dx%dx%d,%d,%d,%d,%.7f,%.3e,%.7f,", fascia_ccx_element_name(def->element),
            fascia_law_name(def->beam.law), def->beam.youngs_modulus, def->beam.poisson_ratio, gx[k],
            def->grading[1], (int)def->half, (int)meshes[k][0],
            (int)meshes[k][1], (int)meshes[k][2], r[k].elements, r[k].nodes, r[k].dofs, r[k].tip[0], r[k].tip[1],
            r[k].tip[2]);
    if (k > 0) fprintf(f, "%.7f", r[k].tip[2] - r[k - 1].tip[2]);
    fprintf(f, ",%d,%d,%.2f\n", r[k].iterations, r[k].increments, r[k].cpu_ms / 1e3);
  }
}

int main(int argc, char **argv) {
  fascia_ccx_beam_def def = fascia_ccx_beam_def_default();
  int32_t meshes[MAX_MESHES][3];
  int count = 0, threads = 1, grading_given = 0;
  double tolerance = 1e-4;
  const char *csv = NULL, *deck = NULL, *mesh_text = NULL;
  for (int k = 1; k < argc; ++k) {
    const char *opt = argv[k];
    if (!strcmp(opt, "--help") || !strcmp(opt, "-h")) {
      fputs(usage, stdout);
      return 0;
    }
    if (!strcmp(opt, "--half")) {
      def.half = 1;
      continue;
    }
    if (k + 1 >= argc) return usage_error("unknown option or no value:", opt);
    const char *value = argv[++k];
    double real = 0;
    int ok = 1;
    if (!strcmp(opt, "--element")) ok = (def.element = fascia_ccx_element_from_name(value)) >= 0;
    else if (!strcmp(opt, "--law")) ok = (def.beam.law = fascia_law_from_name(value)) >= 0;
    else if (!strcmp(opt, "--E")) ok = parse_real(value, &def.beam.youngs_modulus);
    else if (!strcmp(opt, "--nu")) ok = parse_real(value, &def.beam.poisson_ratio);
    else if (!strcmp(opt, "--meshes")) mesh_text = value;
    else if (!strcmp(opt, "--grading")) {
      ok = grading_given = sscanf(value, "%lf,%lf", def.grading, def.grading + 1) == 2;
      def.grading[2] = def.grading[1];
    } else if (!strcmp(opt, "--tolerance")) ok = parse_real(value, &tolerance) && tolerance > 0;
    else if (!strcmp(opt, "--threads")) ok = parse_real(value, &real) && real >= 1 && real <= 1024 && (threads = (int)real) == real;
    else if (!strcmp(opt, "--csv")) csv = value;
    else if (!strcmp(opt, "--deck")) deck = value;
    else return usage_error("unknown option", opt);
    if (!ok) return usage_error("bad value for", opt);
  }
  // the ladder of data/reference/README.md
  const char *ladder = "32x2x4@64,64x2x4@256,64x4x8@256";
  if (!mesh_text) def.half = 1;
  if (!mesh_text && !grading_given) def.grading[1] = def.grading[2] = 4;
  double gx[MAX_MESHES];
  if (!parse_meshes(mesh_text ? mesh_text : ladder, def.grading[0], meshes, gx, &count))
    return usage_error("bad --meshes, expected NXxNYxNZ,... (at most 32):", mesh_text);
  fascia_ctx_def cdef = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cdef, &ctx) != FASCIA_OK) return 1;
  memcpy(def.cells, meshes[0], sizeof def.cells);
  def.grading[0] = gx[0];
  if (deck) {
    const int rc = write_deck(ctx, &def, deck);
    fascia_ctx_destroy(&ctx);
    return rc;
  }
  const char *program = fascia_ccx_program();
  if (!program) {
    fprintf(stderr, "cantilever-calculix: CalculiX (ccx) is not installed: apt-get install calculix-ccx\n");
    fascia_ctx_destroy(&ctx);
    return 1;
  }
  fascia_ccx_result results[MAX_MESHES];
  printf("cantilever 16 x 1 x 1 m, %s, %s, E = %g Pa, nu = %g, NLGEOM, tight controls, grading across %g%s;\n"
         "tip = the node at (16, 0, 0)\n",
         fascia_ccx_element_name(def.element), fascia_law_name(def.beam.law), def.beam.youngs_modulus,
         def.beam.poisson_ratio, def.grading[1], def.half ? ", half beam" : "");
  printf("%-14s %8s %8s %10s %10s %11s %10s %6s %8s\n", "mesh", "elements", "dofs", "tip_ux_m", "tip_uz_m",
         "change_uz_m", "change_%", "newton", "cpu_s");
  int rc = 0;
  for (int k = 0; k < count; ++k) {
    memcpy(def.cells, meshes[k], sizeof def.cells);
    def.grading[0] = gx[k];
    if (fascia_ccx_beam_solve(ctx, &def, program, threads, results + k) != FASCIA_OK) {
      fprintf(stderr, "cantilever-calculix: %s\n", fascia_ctx_message(ctx));
      rc = 1;
      count = k;
      break;
    }
    const fascia_ccx_result *r = results + k;
    char mesh[48];
    snprintf(mesh, sizeof mesh, "%dx%dx%d@%g", (int)meshes[k][0], (int)meshes[k][1], (int)meshes[k][2], gx[k]);
    printf("%-14s %8d %8d %10.5f %10.5f", mesh, r->elements, r->dofs, r->tip[0], r->tip[2]);
    if (k > 0) {
      const double change = r->tip[2] - results[k - 1].tip[2];
      printf(" %11.5f %10.4f", change, 100 * change / fabs(r->tip[2]));
    } else {
      printf(" %11s %10s", "-", "-");
    }
    printf(" %6d %8.2f\n", r->iterations, r->cpu_ms / 1e3);
    fflush(stdout);
  }
  if (count >= 2) {
    const double change = results[count - 1].tip[2] - results[count - 2].tip[2];
    const int still = fabs(change) < tolerance * fabs(results[count - 1].tip[2]);
    printf("%s: last change %.2e of |uz| (tolerance %.0e)\n", still ? "stopped moving" : "STILL MOVING",
           fabs(change / results[count - 1].tip[2]), tolerance);
  }
  if (csv && count > 0) {
    fascia_file *file = NULL;
    fascia_status st = fascia_file_open(ctx, "--csv", csv, &file);
    if (st == FASCIA_OK) csv_rows(fascia_file_stream(file), &def, (const int32_t(*)[3])meshes, gx, results, count);
    if (st == FASCIA_OK) st = fascia_file_commit(&file);
    fascia_file_discard(&file);
    if (st != FASCIA_OK) {
      fprintf(stderr, "cantilever-calculix: %s\n", fascia_ctx_message(ctx));
      rc = 1;
    }
  }
  fascia_ctx_destroy(&ctx);
  return rc;
}
