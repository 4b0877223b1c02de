// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The hanging organ and the pulled sheet (tissue_calculix.h): their scenes
// for fascia prep, their CalculiX decks, and reading ccx's answers back.
#define _POSIX_C_SOURCE 200809L
#include "tissue_calculix.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "beam_calculix.h"
#include "fascia/organs.h"
#include "scene_util.h"

#define PATH_SIZE 1024
// The rigid link from the strand's end to the organ's centre in CalculiX: E
// this many times the strand's, on the organ's whole section.
#define LINK_STIFFER 1e3

fascia_tissue_hang_def fascia_tissue_hang_def_default(void) {
  fascia_tissue_hang_def d;
  memset(&d, 0, sizeof d);
  d.gap = 0.02, d.box = 0.02, d.area = 4e-6;
  d.youngs_modulus = 1e8, d.poisson_ratio = 0.3, d.density = 1000, d.gravity = 9.81;
  d.frame_spacing = 0.002;
  d.elements = 40;
  return d;
}

fascia_tissue_pull_def fascia_tissue_pull_def_default(void) {
  fascia_tissue_pull_def d;
  memset(&d, 0, sizeof d);
  d.gap = 0.02, d.width = 0.016, d.box = 0.02, d.thickness = 0.001;
  d.youngs_modulus = 1e5, d.poisson_ratio = 0.3;
  d.pull[1] = 0.001;
  d.cells[0] = 10, d.cells[1] = 8;
  d.elements[0] = 20, d.elements[1] = 16;
  return d;
}

static int positive(double v) { return isfinite(v) && v > 0; }

static fascia_status check_hang(fascia_ctx *ctx, const fascia_tissue_hang_def *d) {
  SCENE_CHECK(d, ctx, FASCIA_ERR_ARGUMENT, "hanging organ: NULL def");
  SCENE_CHECK(positive(d->gap) && positive(d->box), ctx, FASCIA_ERR_ARGUMENT,
              "hanging organ: gap %g m, box %g m, expected both > 0", d->gap, d->box);
  SCENE_CHECK(positive(d->area) && sqrt(d->area) < d->box / 2, ctx, FASCIA_ERR_ARGUMENT,
              "hanging organ: area %g m^2, expected > 0 and a section narrower than half the box", d->area);
  SCENE_CHECK(positive(d->youngs_modulus) && isfinite(d->poisson_ratio) && d->poisson_ratio >= 0 &&
                  d->poisson_ratio < 0.5 && positive(d->density) && positive(d->gravity),
              ctx, FASCIA_ERR_ARGUMENT,
              "hanging organ: E %g Pa, nu %g, density %g, gravity %g: expected E, density, gravity > 0, nu in [0, 0.5)",
              d->youngs_modulus, d->poisson_ratio, d->density, d->gravity);
  SCENE_CHECK(positive(d->frame_spacing) && d->frame_spacing <= d->gap, ctx, FASCIA_ERR_ARGUMENT,
              "hanging organ: frame spacing %g m, expected > 0 and at most the gap %g m", d->frame_spacing, d->gap);
  SCENE_CHECK(d->elements >= 1 && d->elements <= 10000, ctx, FASCIA_ERR_ARGUMENT,
              "hanging organ: %d CalculiX elements, expected 1 .. 10000", (int)d->elements);
  return FASCIA_OK;
}

static fascia_status check_pull(fascia_ctx *ctx, const fascia_tissue_pull_def *d) {
  SCENE_CHECK(d, ctx, FASCIA_ERR_ARGUMENT, "pulled sheet: NULL def");
  SCENE_CHECK(positive(d->gap) && positive(d->box) && positive(d->width) && d->width < d->box, ctx,
              FASCIA_ERR_ARGUMENT, "pulled sheet: gap %g m, width %g m, box %g m, expected > 0 and width < box",
              d->gap, d->width, d->box);
  SCENE_CHECK(positive(d->thickness) && d->thickness < d->box / 2, ctx, FASCIA_ERR_ARGUMENT,
              "pulled sheet: thickness %g m, expected > 0 and under half the box", d->thickness);
  SCENE_CHECK(positive(d->youngs_modulus) && isfinite(d->poisson_ratio) && d->poisson_ratio >= 0 &&
                  d->poisson_ratio < 0.5,
              ctx, FASCIA_ERR_ARGUMENT, "pulled sheet: E %g Pa, nu %g: expected E > 0, nu in [0, 0.5)",
              d->youngs_modulus, d->poisson_ratio);
  const double pull = sqrt(d->pull[0] * d->pull[0] + d->pull[1] * d->pull[1] + d->pull[2] * d->pull[2]);
  SCENE_CHECK(isfinite(pull) && pull > 0 && pull < d->gap, ctx, FASCIA_ERR_ARGUMENT,
              "pulled sheet: pull of %g m, expected > 0 and less than the gap", pull);
  for (int a = 0; a < 2; ++a) {
    SCENE_CHECK(d->cells[a] >= 2 && d->cells[a] <= 400 && d->cells[a] % 2 == 0, ctx, FASCIA_ERR_ARGUMENT,
                "pulled sheet: %d mesh cells along %c, expected an even count 2 .. 400 (a vertex at the middle)",
                (int)d->cells[a], "xy"[a]);
    SCENE_CHECK(d->elements[a] >= 2 && d->elements[a] <= 400 && d->elements[a] % 2 == 0, ctx, FASCIA_ERR_ARGUMENT,
                "pulled sheet: %d CalculiX elements along %c, expected an even count 2 .. 400", (int)d->elements[a],
                "xy"[a]);
  }
  SCENE_CHECK(fascia_tissue_mesh_name(d->mesh), ctx, FASCIA_ERR_ARGUMENT,
              "pulled sheet: mesh %d, expected 0 (right), 1 (shifted) or 2 (jittered)", (int)d->mesh);
  return FASCIA_OK;
}

// ------------------------------------------------------------ scenes

static FILE *open_in(fascia_ctx *ctx, const char *dir, const char *name, char *path) {
  snprintf(path, PATH_SIZE, "%s/%s", dir, name);
  FILE *f = fopen(path, "w");
  if (!f) SCENE_FAIL(ctx, FASCIA_ERR_IO, "cannot write %s (%s)", path, strerror(errno));
  return f;
}

static fascia_status close_file(fascia_ctx *ctx, FILE *f, const char *path) {
  const int bad = ferror(f);
  if (fclose(f) != 0 || bad) return SCENE_FAIL(ctx, FASCIA_ERR_IO, "writing %s failed (%s)", path, strerror(errno));
  return FASCIA_OK;
}

// The box [x0, x0 + edge] x [-edge/2, edge/2]^2 as a closed, outward OBJ.
static fascia_status write_box(fascia_ctx *ctx, const char *dir, const char *name, double x0, double edge) {
  char path[PATH_SIZE];
  FILE *f = open_in(ctx, dir, name, path);
  if (!f) return FASCIA_ERR_IO;
  for (int c = 0; c < 8; ++c)
    fprintf(f, "v %.17g %.17g %.17g\n", (c & 1) ? x0 + edge : x0, (c & 2) ? edge / 2 : -edge / 2,
            (c & 4) ? edge / 2 : -edge / 2);
  static const int quads[6][4] = {{1, 3, 7, 5}, {2, 6, 8, 4}, {1, 5, 6, 2}, {3, 4, 8, 7}, {1, 2, 4, 3}, {5, 7, 8, 6}};
  for (int q = 0; q < 6; ++q)
    fprintf(f, "f %d %d %d\nf %d %d %d\n", quads[q][0], quads[q][1], quads[q][2], quads[q][0], quads[q][2],
            quads[q][3]);
  return close_file(ctx, f, path);
}

static fascia_status write_boxes(fascia_ctx *ctx, const char *dir, double gap, double box) {
  SCENE_TRY(write_box(ctx, dir, FASCIA_TISSUE_BOX_A, -gap / 2 - box, box));
  return write_box(ctx, dir, FASCIA_TISSUE_BOX_B, gap / 2, box);
}

fascia_status fascia_tissue_hang_write_scene(fascia_ctx *ctx, const void *hang_def, const char *dir) {
  const fascia_tissue_hang_def *def = hang_def;
  SCENE_TRY(check_hang(ctx, def));
  SCENE_TRY(write_boxes(ctx, dir, def->gap, def->box));
  char path[PATH_SIZE];
  FILE *f = open_in(ctx, dir, FASCIA_TISSUE_SCENE, path);
  if (!f) return FASCIA_ERR_IO;
  fprintf(f,
          "{\"fascia_scene\": 1, \"name\": \"strand hanging an organ\", \"voxel_size\": %.17g, \"seed\": 1,\n"
          " \"gravity\": [0, 0, %.17g],\n"
          " \"materials\": {\"strand\": {\"law\": \"stvk\", \"youngs_modulus\": %.17g, \"poisson_ratio\": %.17g,"
          " \"density\": %.17g}},\n"
          " \"organs\": [{\"name\": \"A\", \"mesh\": \"" FASCIA_TISSUE_BOX_A "\", \"model\": \"fixed\"},\n"
          "            {\"name\": \"B\", \"mesh\": \"" FASCIA_TISSUE_BOX_B "\", \"model\": \"rigid\"}],\n"
          " \"tissues\": [{\"name\": \"strand\", \"form\": \"strand\", \"from\": {\"organ\": \"A\", \"point\": "
          "[%.17g, 0, 0]},\n"
          "              \"to\": {\"organ\": \"B\", \"point\": [%.17g, 0, 0]}, \"area\": %.17g, \"material\": "
          "\"strand\",\n"
          "              \"frame_spacing\": %.17g}]}\n",
          fmin(def->gap, def->box) / 20, -def->gravity, def->youngs_modulus, def->poisson_ratio, def->density,
          -def->gap / 2, def->gap / 2, def->area, def->frame_spacing);
  return close_file(ctx, f, path);
}

const char *fascia_tissue_mesh_name(int32_t mesh) {
  static const char *const names[] = {"right", "shifted", "jittered"};
  return mesh >= 0 && mesh < 3 ? names[mesh] : NULL;
}

// Row j of the shifted mesh: shifted when it is an inner row an odd number
// of rows from the middle one (the centre and the free edges' middles stay
// on vertices); its vertices' x, from the edge on A to the edge on B.
static int32_t row_x(const fascia_tissue_pull_def *d, int32_t j, double *x) {
  const int32_t nx = d->cells[0], ny = d->cells[1];
  const double h = d->gap / nx;
  const int shifted = j > 0 && j < ny && (j - ny / 2) % 2 != 0;
  int32_t n = 0;
  x[n++] = -d->gap / 2;
  for (int32_t i = 1; i < nx + shifted; ++i) x[n++] = -d->gap / 2 + h * (i - 0.5 * shifted);
  x[n++] = d->gap / 2;
  return n;
}

// The shifted or jittered mesh: rows of vertices, consecutive rows zipped
// into triangles (counter-clockwise seen from +z), each step advancing the
// row whose next vertex lies nearer the edge on A.
static void write_zipped_rows(FILE *f, const fascia_tissue_pull_def *d) {
  const int32_t nx = d->cells[0], ny = d->cells[1];
  const double hx = d->gap / nx, hy = d->width / ny;
  double x[2][402], y[2][402];
  int32_t count[2] = {0, 0}, first[2] = {0, 0}, next = 1;
  uint64_t seed = 0x9e3779b97f4a7c15u;
  for (int32_t j = 0; j <= ny; ++j) {
    const int r = j % 2;
    count[r] = row_x(d, j, x[r]);
    first[r] = next;
    for (int32_t i = 0; i < count[r]; ++i) {
      y[r][i] = -d->width / 2 + d->width * j / ny;
      const int inner = j > 0 && j < ny && i > 0 && i < count[r] - 1 && !(2 * j == ny && fabs(x[r][i]) < hx / 4);
      if (d->mesh == FASCIA_TISSUE_MESH_JITTERED && inner)
        for (int a = 0; a < 2; ++a) { // xorshift: the same mesh on every machine
          seed ^= seed << 13, seed ^= seed >> 7, seed ^= seed << 17;
          const double u = (double)(seed >> 11) / 9007199254740992.0 - 0.5;
          if (a == 0) x[r][i] += 0.4 * u * hx;
          else y[r][i] += 0.4 * u * hy;
        }
      fprintf(f, "v %.17g %.17g 0\n", x[r][i], y[r][i]);
    }
    next += count[r];
    if (j == 0) continue;
    const int lo = 1 - r, up = r;
    int32_t p = 0, q = 0;
    while (p < count[lo] - 1 || q < count[up] - 1) {
      if (q == count[up] - 1 || (p < count[lo] - 1 && x[lo][p + 1] <= x[up][q + 1])) {
        fprintf(f, "f %d %d %d\n", first[lo] + p, first[lo] + p + 1, first[up] + q);
        ++p;
      } else {
        fprintf(f, "f %d %d %d\n", first[lo] + p, first[up] + q + 1, first[up] + q);
        ++q;
      }
    }
  }
}

fascia_status fascia_tissue_pull_write_scene(fascia_ctx *ctx, const void *pull_def, const char *dir) {
  const fascia_tissue_pull_def *def = pull_def;
  SCENE_TRY(check_pull(ctx, def));
  SCENE_TRY(write_boxes(ctx, dir, def->gap, def->box));
  char path[PATH_SIZE];
  FILE *f = open_in(ctx, dir, FASCIA_TISSUE_SHEET, path);
  if (!f) return FASCIA_ERR_IO;
  const int32_t nx = def->cells[0], ny = def->cells[1];
  if (def->mesh == FASCIA_TISSUE_MESH_RIGHT) {
    for (int32_t j = 0; j <= ny; ++j)
      for (int32_t i = 0; i <= nx; ++i)
        fprintf(f, "v %.17g %.17g 0\n", -def->gap / 2 + def->gap * i / nx, -def->width / 2 + def->width * j / ny);
    // diagonals alternating from square to square: no direction of shear preferred
    for (int32_t j = 0; j < ny; ++j)
      for (int32_t i = 0; i < nx; ++i) {
        const int32_t a = 1 + i + (nx + 1) * j, b = a + 1, c = b + nx + 1, d = a + nx + 1;
        if ((i + j) % 2) fprintf(f, "f %d %d %d\nf %d %d %d\n", a, b, d, b, c, d);
        else fprintf(f, "f %d %d %d\nf %d %d %d\n", a, b, c, a, c, d);
      }
  } else {
    write_zipped_rows(f, def);
  }
  SCENE_TRY(close_file(ctx, f, path));
  f = open_in(ctx, dir, FASCIA_TISSUE_SCENE, path);
  if (!f) return FASCIA_ERR_IO;
  const double cell = fmin(def->gap / nx, def->width / ny);
  fprintf(f,
          "{\"fascia_scene\": 1, \"name\": \"sheet under a pull\", \"voxel_size\": %.17g, \"seed\": 1,\n"
          " \"gravity\": [0, 0, 0],\n"
          " \"materials\": {\"sheet\": {\"law\": \"stvk\", \"youngs_modulus\": %.17g, \"poisson_ratio\": %.17g}},\n"
          " \"organs\": [{\"name\": \"A\", \"mesh\": \"" FASCIA_TISSUE_BOX_A "\", \"model\": \"fixed\"},\n"
          "            {\"name\": \"B\", \"mesh\": \"" FASCIA_TISSUE_BOX_B "\", \"model\": \"prescribed\",\n"
          "             \"motion\": {\"pivot\": [0, 0, 0], \"keys\": [{\"time\": 0}, {\"time\": 1, \"translation\": "
          "[%.17g, %.17g, %.17g]}]}}],\n"
          " \"tissues\": [{\"name\": \"sheet\", \"form\": \"sheet\", \"mesh\": \"" FASCIA_TISSUE_SHEET
          "\", \"thickness\": %.17g,\n"
          "              \"connects\": [\"A\", \"B\"], \"material\": \"sheet\", \"coupling\": {\"tolerance\": %.17g}}]}\n",
          fmin(def->gap, def->box) / 20, def->youngs_modulus, def->poisson_ratio, def->pull[0], def->pull[1],
          def->pull[2], def->thickness, cell / 4);
  return close_file(ctx, f, path);
}

// ------------------------------------------------------------ decks

// Increments: a tenth of the load first, ccx growing or cutting them; tight
// Newton controls as the cantilever's reference (beam_calculix.c).
static void write_step_start(FILE *out) {
  fprintf(out, "*STEP, NLGEOM, INC=1000\n*STATIC\n0.1, 1.0, 1e-6, 0.25\n"
               "*CONTROLS, PARAMETERS=FIELD\n1e-7, 1e-7, 0., -1., 0.02, 1e-5, 1e-3, 1e-8\n");
}

fascia_status fascia_tissue_hang_write_deck(fascia_ctx *ctx, const void *hang_def, FILE *out) {
  const fascia_tissue_hang_def *d = hang_def;
  SCENE_TRY(check_hang(ctx, d));
  const int32_t n = d->elements, last = 2 * n + 1, link = last + 1, centre = last + 2;
  const double mass = FASCIA_ORGAN_DENSITY * d->box * d->box * d->box, side = sqrt(d->area);
  fprintf(out,
          "** fascia's strand hanging an organ (tools/scenes/tissue_calculix.c): a strand of %g x %g m section,\n"
          "** %g m long along x, clamped at node 1, its end (node %d) joined rigidly to the organ's centre\n"
          "** (node %d, %g m beyond it), which carries the organ's weight (%.6g kg, a %g m cube at %g kg/m^3);\n"
          "** %d B32 elements, NLGEOM, gravity %g m/s^2 along -z\n*HEADING\nfascia strand hanging an organ\n",
          side, side, d->gap, (int)last, (int)centre, d->box / 2, mass, d->box, FASCIA_ORGAN_DENSITY, (int)n,
          d->gravity);
  fprintf(out, "*NODE, NSET=NALL\n");
  for (int32_t i = 0; i < last; ++i) fprintf(out, "%d, %.13g, 0, 0\n", (int)(i + 1), -d->gap / 2 + d->gap * i / (2 * n));
  fprintf(out, "%d, %.13g, 0, 0\n%d, %.13g, 0, 0\n", (int)link, d->gap / 2 + d->box / 4, (int)centre,
          d->gap / 2 + d->box / 2);
  fprintf(out, "*ELEMENT, TYPE=B32, ELSET=ESTRAND\n");
  for (int32_t e = 0; e < n; ++e) fprintf(out, "%d, %d, %d, %d\n", (int)(e + 1), (int)(2 * e + 1), (int)(2 * e + 2), (int)(2 * e + 3));
  fprintf(out, "*ELEMENT, TYPE=B32, ELSET=ELINK\n%d, %d, %d, %d\n", (int)(n + 1), (int)last, (int)link, (int)centre);
  fprintf(out, "*NSET, NSET=NFIX\n1,\n*NSET, NSET=NORGAN\n%d, %d\n", (int)last, (int)centre);
  fprintf(out, "*MATERIAL, NAME=STRAND\n*ELASTIC\n%.13g, %.13g\n*DENSITY\n%.13g\n", d->youngs_modulus,
          d->poisson_ratio, d->density);
  fprintf(out, "*MATERIAL, NAME=LINK\n*ELASTIC\n%.13g, %.13g\n", LINK_STIFFER * d->youngs_modulus, d->poisson_ratio);
  fprintf(out, "*BEAM SECTION, ELSET=ESTRAND, MATERIAL=STRAND, SECTION=RECT\n%.13g, %.13g\n0., 1., 0.\n", side, side);
  fprintf(out, "*BEAM SECTION, ELSET=ELINK, MATERIAL=LINK, SECTION=RECT\n%.13g, %.13g\n0., 1., 0.\n", d->box, d->box);
  fprintf(out, "*BOUNDARY\nNFIX, 1, 6\n");
  write_step_start(out);
  fprintf(out, "*DLOAD\nESTRAND, GRAV, %.13g, 0., 0., -1.\n*CLOAD\n%d, 3, %.13g\n", d->gravity, (int)centre,
          -mass * d->gravity);
  fprintf(out, "*NODE PRINT, NSET=NORGAN\nU\n*NODE PRINT, NSET=NFIX, TOTALS=ONLY\nRF\n*END STEP\n");
  return fascia_ccx_deck_written(ctx, out);
}

// Node id of point (i, j) of the (2 ex + 1) x (2 ey + 1) grid of an S8R mesh.
int32_t fascia_ccx_s8r_node(int32_t ex, int32_t i, int32_t j) { return 1 + i + (2 * ex + 1) * j; }

void fascia_ccx_s8r_rectangle(FILE *out, int32_t ex, int32_t ey, double x0, double lx, double y0, double ly) {
  const int32_t nx = 2 * ex + 1, ny = 2 * ey + 1;
  fprintf(out, "*NODE, NSET=NALL\n");
  for (int32_t j = 0; j < ny; ++j)
    for (int32_t i = 0; i < nx; ++i)
      if (!(i % 2 && j % 2)) // the serendipity element has no centre node
        fprintf(out, "%d, %.13g, %.13g, 0\n", (int)fascia_ccx_s8r_node(ex, i, j), x0 + lx * i / (nx - 1),
                y0 + ly * j / (ny - 1));
  fprintf(out, "*ELEMENT, TYPE=S8R, ELSET=EALL\n");
  for (int32_t b = 0; b < ey; ++b)
    for (int32_t a = 0; a < ex; ++a) {
      const int32_t i = 2 * a, j = 2 * b;
      const int32_t node[8] = {fascia_ccx_s8r_node(ex, i, j),         fascia_ccx_s8r_node(ex, i + 2, j),
                               fascia_ccx_s8r_node(ex, i + 2, j + 2), fascia_ccx_s8r_node(ex, i, j + 2),
                               fascia_ccx_s8r_node(ex, i + 1, j),     fascia_ccx_s8r_node(ex, i + 2, j + 1),
                               fascia_ccx_s8r_node(ex, i + 1, j + 2), fascia_ccx_s8r_node(ex, i, j + 1)};
      fprintf(out, "%d", (int)(1 + a + ex * b));
      for (int k = 0; k < 8; ++k) fprintf(out, ", %d", (int)node[k]);
      fprintf(out, "\n");
    }
}

static int32_t shell_node(const fascia_tissue_pull_def *d, int32_t i, int32_t j) {
  return fascia_ccx_s8r_node(d->elements[0], i, j);
}

fascia_status fascia_tissue_pull_write_deck(fascia_ctx *ctx, const void *pull_def, FILE *out) {
  const fascia_tissue_pull_def *d = pull_def;
  SCENE_TRY(check_pull(ctx, d));
  const int32_t ex = d->elements[0], ey = d->elements[1], nx = 2 * ex + 1, ny = 2 * ey + 1;
  fprintf(out,
          "** fascia's sheet under a pull (tools/scenes/tissue_calculix.c): %g x %g m in the plane z = 0, %g m\n"
          "** thick, the edge x = %g clamped, the edge x = %g moved by (%g, %g, %g) m without rotating;\n"
          "** %d x %d S8R elements, NLGEOM\n*HEADING\nfascia sheet under a pull\n",
          d->gap, d->width, d->thickness, -d->gap / 2, d->gap / 2, d->pull[0], d->pull[1], d->pull[2], (int)ex,
          (int)ey);
  fascia_ccx_s8r_rectangle(out, ex, ey, -d->gap / 2, d->gap, -d->width / 2, d->width);
  fprintf(out, "*NSET, NSET=NFIX\n");
  for (int32_t j = 0; j < ny; ++j) fprintf(out, "%d,\n", (int)shell_node(d, 0, j));
  fprintf(out, "*NSET, NSET=NPULL\n");
  for (int32_t j = 0; j < ny; ++j) fprintf(out, "%d,\n", (int)shell_node(d, nx - 1, j));
  fprintf(out, "*NSET, NSET=NPROBE\n%d, %d\n", (int)shell_node(d, ex, ny - 1), (int)shell_node(d, ex, ey));
  fprintf(out, "*MATERIAL, NAME=SHEET\n*ELASTIC\n%.13g, %.13g\n*SHELL SECTION, ELSET=EALL, MATERIAL=SHEET\n%.13g\n",
          d->youngs_modulus, d->poisson_ratio, d->thickness);
  fprintf(out, "*BOUNDARY\nNFIX, 1, 6\nNPULL, 4, 6\n");
  write_step_start(out);
  fprintf(out, "*BOUNDARY\nNPULL, 1, 1, %.13g\nNPULL, 2, 2, %.13g\nNPULL, 3, 3, %.13g\n", d->pull[0], d->pull[1],
          d->pull[2]);
  fprintf(out, "*NODE PRINT, NSET=NPROBE\nU\n*NODE PRINT, NSET=NPULL, TOTALS=ONLY\nRF\n*END STEP\n");
  return fascia_ccx_deck_written(ctx, out);
}

// ------------------------------------------------------------ ccx's answers

fascia_status fascia_tissue_hang_calculix(fascia_ctx *ctx, const fascia_tissue_hang_def *def, const char *program,
                                          fascia_tissue_hang_result *out) {
  SCENE_CHECK(out, ctx, FASCIA_ERR_ARGUMENT, "hanging organ: NULL result");
  memset(out, 0, sizeof *out);
  char *dat = NULL;
  SCENE_TRY(fascia_ccx_run_timed(ctx, "hanging organ", fascia_tissue_hang_write_deck, def, program, 1, &dat, &out->ms));
  const int32_t last = 2 * def->elements + 1, centre = last + 2;
  const char *u = fascia_ccx_dat_after(dat, "displacements (vx,vy,vz) for set NORGAN");
  const char *rf = fascia_ccx_dat_after(dat, "total force (fx,fy,fz) for set NFIX");
  double reaction[3];
  const int ok = u && rf && fascia_ccx_dat_node(u, last, out->end) && fascia_ccx_dat_node(u, centre, out->centre) &&
                 fascia_ccx_dat_triple(rf, reaction);
  free(dat);
  SCENE_CHECK(ok, ctx, FASCIA_ERR_FORMAT,
              "CalculiX hanging organ: its output lacks the displacements of nodes %d, %d or the reaction at node 1",
              (int)last, (int)centre);
  for (int a = 0; a < 3; ++a) out->force[a] = -reaction[a]; // the support's force on the strand, reversed
  // the link's direction, along +x at rest
  const double dx = def->box / 2 + out->centre[0] - out->end[0], dz = out->centre[2] - out->end[2];
  out->angle = atan2(-dz, dx);
  out->nodes = last;
  return FASCIA_OK;
}

fascia_status fascia_tissue_pull_calculix(fascia_ctx *ctx, const fascia_tissue_pull_def *def, const char *program,
                                          fascia_tissue_pull_result *out) {
  SCENE_CHECK(out, ctx, FASCIA_ERR_ARGUMENT, "pulled sheet: NULL result");
  memset(out, 0, sizeof *out);
  char *dat = NULL;
  SCENE_TRY(fascia_ccx_run_timed(ctx, "pulled sheet", fascia_tissue_pull_write_deck, def, program, 1, &dat, &out->ms));
  const int32_t ex = def->elements[0], ey = def->elements[1];
  const int32_t edge = shell_node(def, ex, 2 * ey), centre = shell_node(def, ex, ey);
  const char *u = fascia_ccx_dat_after(dat, "displacements (vx,vy,vz) for set NPROBE");
  const char *rf = fascia_ccx_dat_after(dat, "total force (fx,fy,fz) for set NPULL");
  double reaction[3];
  const int ok = u && rf && fascia_ccx_dat_node(u, edge, out->edge) && fascia_ccx_dat_node(u, centre, out->centre) &&
                 fascia_ccx_dat_triple(rf, reaction);
  free(dat);
  SCENE_CHECK(ok, ctx, FASCIA_ERR_FORMAT,
              "CalculiX pulled sheet: its output lacks the displacements of nodes %d, %d or the reaction on the "
              "pulled edge",
              (int)edge, (int)centre);
  for (int a = 0; a < 3; ++a) out->force[a] = -reaction[a], out->edge[a] -= out->centre[a];
  out->nodes = (2 * ex + 1) * (2 * ey + 1) - ex * ey;
  return FASCIA_OK;
}

double fascia_tissue_error3(const double a[3], const double b[3]) {
  double d = 0, n = 0;
  for (int k = 0; k < 3; ++k) d += (a[k] - b[k]) * (a[k] - b[k]), n += b[k] * b[k];
  return n > 0 ? sqrt(d / n) : d > 0 ? INFINITY : 0;
}

// ------------------------------------------------------------ shared with other cases

fascia_status fascia_tissue_write_box(fascia_ctx *ctx, const char *dir, const char *name, double x0, double edge) {
  return write_box(ctx, dir, name, x0, edge);
}

void fascia_tissue_deck_step(FILE *out) { write_step_start(out); }

int fascia_tissue_dat_node(const char *dat, const char *header, long long node, double v[3]) {
  const char *block = fascia_ccx_dat_after(dat, header);
  return block && fascia_ccx_dat_node(block, node, v);
}

FILE *fascia_tissue_open(fascia_ctx *ctx, const char *dir, const char *name, char *path) {
  return open_in(ctx, dir, name, path);
}

fascia_status fascia_tissue_close(fascia_ctx *ctx, FILE *f, const char *path) { return close_file(ctx, f, path); }
