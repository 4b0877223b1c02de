// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The plate and the bowl (shell_calculix.h): fascia's scene, the CalculiX
// deck, and ccx's answer. The bowl's meshes, CalculiX's and the organ's,
// come from one lattice: the lower half of a cube's surface projected on
// the sphere (equal angles), so the bottom is a node and no element is
// degenerate.
#define _POSIX_C_SOURCE 200809L
#include "shell_calculix.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "beam_calculix.h"
#include "scene_util.h"
#include "tissue_calculix.h"

#define PATH_SIZE 1024
#define PI 3.14159265358979323846

fascia_shell_def fascia_shell_def_default(int32_t kind) {
  fascia_shell_def d;
  memset(&d, 0, sizeof d);
  d.kind = kind;
  d.poisson_ratio = 0.3, d.gravity = 9.81, d.seed = 1, d.split = 1;
  if (kind == FASCIA_SHELL_BOWL) {
    d.length = 0.05, d.thickness = 0.001;
    d.youngs_modulus = 1e5, d.density = 1000;
    d.frame_spacing = 0.006, d.scale = 1;
    d.elements[0] = 32, d.elements[1] = 0;
  } else {
    d.length = 16, d.width = 1, d.thickness = 0.1;
    d.youngs_modulus = 4e6, d.density = 0.3125;
    d.frame_spacing = 0.25, d.scale = 0.1;
    d.elements[0] = 64, d.elements[1] = 4;
  }
  return d;
}

static int positive(double v) { return isfinite(v) && v > 0; }

static fascia_status check_def(fascia_ctx *ctx, const fascia_shell_def *d) {
  SCENE_CHECK(d && (d->kind == FASCIA_SHELL_PLATE || d->kind == FASCIA_SHELL_BOWL), ctx, FASCIA_ERR_ARGUMENT,
              "shell case: NULL def or kind %d, expected plate (0) or bowl (1)", d ? (int)d->kind : -1);
  const int bowl = d->kind == FASCIA_SHELL_BOWL;
  SCENE_CHECK(positive(d->length) && (bowl || positive(d->width)), ctx, FASCIA_ERR_ARGUMENT,
              "shell case: length %g m, width %g m, expected > 0", d->length, d->width);
  SCENE_CHECK(positive(d->thickness) && d->thickness < d->frame_spacing && positive(d->frame_spacing) &&
                  d->frame_spacing <= (bowl ? d->length : fmin(d->length, d->width)) / 2,
              ctx, FASCIA_ERR_ARGUMENT,
              "shell case: thickness %g m, frame spacing %g m: expected 0 < thickness < spacing <= half the %s",
              d->thickness, d->frame_spacing, bowl ? "radius" : "width");
  SCENE_CHECK(positive(d->youngs_modulus) && isfinite(d->poisson_ratio) && d->poisson_ratio >= 0 &&
                  d->poisson_ratio < 0.5 && positive(d->density) && positive(d->gravity),
              ctx, FASCIA_ERR_ARGUMENT,
              "shell case: E %g Pa, nu %g, density %g, gravity %g: expected E, density, gravity > 0, nu in [0, 0.5)",
              d->youngs_modulus, d->poisson_ratio, d->density, d->gravity);
  SCENE_CHECK(positive(d->scale) && d->scale <= 1, ctx, FASCIA_ERR_ARGUMENT, "shell case: scale %g, expected (0, 1]",
              d->scale);
  if (bowl)
    SCENE_CHECK(d->elements[0] >= 2 && d->elements[0] <= 256 && d->elements[0] % 2 == 0, ctx, FASCIA_ERR_ARGUMENT,
                "bowl: %d S8R elements along a quarter of the rim, expected an even count 2 .. 256",
                (int)d->elements[0]);
  else
    SCENE_CHECK(d->elements[0] >= 1 && d->elements[0] <= 2000 && d->elements[1] >= 2 && d->elements[1] <= 400 &&
                    d->elements[1] % 2 == 0,
                ctx, FASCIA_ERR_ARGUMENT,
                "plate: %d x %d S8R elements, expected 1 .. 2000 along x and an even count 2 .. 400 across",
                (int)d->elements[0], (int)d->elements[1]);
  return FASCIA_OK;
}

// ------------------------------------------------------------ the bowl's lattice

// Half-steps along a cube face's edge: 2 per element; node (I, J, K) of
// the cube's surface, each in [-h, h], K <= 0 (the lower half).
typedef struct lattice {
  int32_t h;
  double radius;
} lattice;

static void lattice_point(const lattice *l, int32_t I, int32_t J, int32_t K, double p[3]) {
  const double c[3] = {tan(0.25 * PI * I / l->h), tan(0.25 * PI * J / l->h), tan(0.25 * PI * K / l->h)};
  const double n = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  for (int a = 0; a < 3; ++a) p[a] = l->radius * c[a] / n;
}

static int64_t lattice_key(const lattice *l, int32_t I, int32_t J, int32_t K) {
  const int64_t w = 2 * (int64_t)l->h + 1;
  return (I + l->h) + w * ((J + l->h) + w * (K + l->h));
}

// The five faces of the lower half: the bottom (K = -h) and the four sides
// down from the rim (K = 0). Face f's point (a, b): a in [-h, h], b in
// [-h, h] (bottom) or [-h, 0] (sides, b = K).
static int32_t face_rows(const lattice *l, int f) { return f == 0 ? 2 * l->h : l->h; }
static void face_node(const lattice *l, int f, int32_t a, int32_t b, int32_t ijk[3]) {
  const int32_t h = l->h;
  switch (f) {
  case 0: ijk[0] = a, ijk[1] = b, ijk[2] = -h; break;
  case 1: ijk[0] = h, ijk[1] = a, ijk[2] = b; break;
  case 2: ijk[0] = -h, ijk[1] = a, ijk[2] = b; break;
  case 3: ijk[0] = a, ijk[1] = h, ijk[2] = b; break;
  default: ijk[0] = a, ijk[1] = -h, ijk[2] = b; break;
  }
}

static int by_key(const void *pa, const void *pb) {
  const int64_t a = *(const int64_t *)pa, b = *(const int64_t *)pb;
  return (a > b) - (a < b);
}

// The lattice's distinct nodes every `step` half-steps (2: corners only, 1:
// with the mid-side nodes), sorted by key; a node's id is its index + 1.
static fascia_status lattice_nodes(fascia_ctx *ctx, const lattice *l, int32_t step, int64_t **keys, int64_t *count) {
  const int64_t w = 2 * (int64_t)l->h + 1;
  int64_t *k = malloc((size_t)(5 * w * w) * sizeof *k), n = 0;
  SCENE_CHECK(k, ctx, FASCIA_ERR_MEMORY, "bowl: out of memory");
  for (int f = 0; f < 5; ++f)
    for (int32_t b = -l->h; b <= -l->h + face_rows(l, f); b += step)
      for (int32_t a = -l->h; a <= l->h; a += step) {
        // the serendipity element has no centre node
        if (step == 1 && (a + l->h) % 2 && (b + l->h) % 2) continue;
        int32_t ijk[3];
        face_node(l, f, a, b, ijk);
        k[n++] = lattice_key(l, ijk[0], ijk[1], ijk[2]);
      }
  qsort(k, (size_t)n, sizeof *k, by_key);
  int64_t u = 0;
  for (int64_t j = 0; j < n; ++j)
    if (u == 0 || k[j] != k[u - 1]) k[u++] = k[j];
  *keys = k, *count = u;
  return FASCIA_OK;
}

static int64_t node_id(const int64_t *keys, int64_t count, const lattice *l, const int32_t ijk[3]) {
  const int64_t key = lattice_key(l, ijk[0], ijk[1], ijk[2]);
  const int64_t *hit = bsearch(&key, keys, (size_t)count, sizeof key, by_key);
  return hit ? hit - keys + 1 : -1;
}

static void key_point(const lattice *l, int64_t key, double p[3]) {
  const int64_t w = 2 * (int64_t)l->h + 1;
  lattice_point(l, (int32_t)(key % w) - l->h, (int32_t)(key / w % w) - l->h, (int32_t)(key / (w * w)) - l->h, p);
}

// Whether the cell (a, b) .. (a + s, b + s) of face f, in that order, turns
// about the outward normal (else its nodes go the other way round).
static int outward(const lattice *l, int f, int32_t a, int32_t b, int32_t s) {
  int32_t q[3][3];
  face_node(l, f, a, b, q[0]);
  face_node(l, f, a + s, b, q[1]);
  face_node(l, f, a, b + s, q[2]);
  double p[3][3];
  for (int k = 0; k < 3; ++k) lattice_point(l, q[k][0], q[k][1], q[k][2], p[k]);
  const double e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
  const double e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
  const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
  return n[0] * p[0][0] + n[1] * p[0][1] + n[2] * p[0][2] > 0;
}

// ------------------------------------------------------------ scene

// The organ's surface, scaled: plate squares split in two about
// frame_spacing / 2 wide; the bowl's lattice at a quarter of the spacing.
static fascia_status write_surface(fascia_ctx *ctx, const fascia_shell_def *d, const char *dir) {
  char path[PATH_SIZE];
  FILE *f = fascia_tissue_open(ctx, dir, FASCIA_TISSUE_SHEET, path);
  if (!f) return FASCIA_ERR_IO;
  const double s = d->scale;
  if (d->kind == FASCIA_SHELL_PLATE) {
    const int32_t nx = (int32_t)fmax(2, ceil(2 * d->length / d->frame_spacing)),
                  ny = (int32_t)fmax(2, ceil(2 * d->width / d->frame_spacing));
    for (int32_t j = 0; j <= ny; ++j)
      for (int32_t i = 0; i <= nx; ++i)
        fprintf(f, "v %.17g %.17g 0\n", s * d->length * i / nx, s * d->width * (-0.5 + (double)j / ny));
    for (int32_t j = 0; j < ny; ++j)
      for (int32_t i = 0; i < nx; ++i) {
        const int32_t a = 1 + i + (nx + 1) * j, b = a + 1, c = b + nx + 1, e = a + nx + 1;
        fprintf(f, "f %d %d %d\nf %d %d %d\n", a, b, c, a, c, e);
      }
    return fascia_tissue_close(ctx, f, path);
  }
  // lattice cells per cube edge (2 h) about a quarter spacing wide, h even
  const int32_t cells = (int32_t)ceil(0.5 * PI * d->length / (0.25 * d->frame_spacing));
  const int32_t half = (cells + 1) / 2;
  const lattice l = {half + half % 2, s * d->length};
  int64_t *keys = NULL, count = 0;
  const int64_t w = 2 * (int64_t)l.h + 1;
  keys = malloc((size_t)(5 * w * w) * sizeof *keys);
  if (!keys) {
    fclose(f);
    return SCENE_FAIL(ctx, FASCIA_ERR_MEMORY, "bowl: out of memory");
  }
  count = 0;
  for (int fc = 0; fc < 5; ++fc)
    for (int32_t b = -l.h; b <= -l.h + face_rows(&l, fc); ++b)
      for (int32_t a = -l.h; a <= l.h; ++a) {
        int32_t ijk[3];
        face_node(&l, fc, a, b, ijk);
        keys[count++] = lattice_key(&l, ijk[0], ijk[1], ijk[2]);
      }
  qsort(keys, (size_t)count, sizeof *keys, by_key);
  int64_t u = 0;
  for (int64_t j = 0; j < count; ++j)
    if (u == 0 || keys[j] != keys[u - 1]) keys[u++] = keys[j];
  count = u;
  for (int64_t j = 0; j < count; ++j) {
    double p[3];
    key_point(&l, keys[j], p);
    fprintf(f, "v %.17g %.17g %.17g\n", p[0], p[1], p[2]);
  }
  for (int fc = 0; fc < 5; ++fc)
    for (int32_t b = -l.h; b < -l.h + face_rows(&l, fc); ++b)
      for (int32_t a = -l.h; a < l.h; ++a) {
        int32_t q[4][3];
        face_node(&l, fc, a, b, q[0]);
        face_node(&l, fc, a + 1, b, q[1]);
        face_node(&l, fc, a + 1, b + 1, q[2]);
        face_node(&l, fc, a, b + 1, q[3]);
        int64_t v[4];
        for (int k = 0; k < 4; ++k) v[k] = node_id(keys, count, &l, q[k]);
        if (!outward(&l, fc, a, b, 1)) {
          const int64_t t = v[1];
          v[1] = v[3], v[3] = t;
        }
        fprintf(f, "f %lld %lld %lld\nf %lld %lld %lld\n", (long long)v[0], (long long)v[1], (long long)v[2],
                (long long)v[0], (long long)v[2], (long long)v[3]);
      }
  free(keys);
  return fascia_tissue_close(ctx, f, path);
}

fascia_status fascia_shell_write_scene(fascia_ctx *ctx, const void *shell_def, const char *dir) {
  const fascia_shell_def *def = shell_def;
  SCENE_TRY(check_def(ctx, def));
  SCENE_TRY(write_surface(ctx, def, dir));
  const double s = def->scale, R = s * def->length, sp = s * def->frame_spacing;
  const int plate = def->kind == FASCIA_SHELL_PLATE;
  // the strand's boxes: beside the clamped edge (plate) or outside the rim (bowl)
  const double e = plate ? s * def->width / 4 : R / 8, x0 = plate ? -4 * e : R + 2 * e;
  SCENE_TRY(fascia_tissue_write_box(ctx, dir, FASCIA_TISSUE_BOX_A, x0, e));
  SCENE_TRY(fascia_tissue_write_box(ctx, dir, FASCIA_TISSUE_BOX_B, x0 + 2 * e, e));
  // the hold: the frames on the clamped edge, none of the wall's others
  const double h = 0.1 * sp, big = plate ? s * def->width : 2 * R + 6 * e;
  const double lo[3] = {plate ? -h : -big, -big, plate ? -big : -h}, hi[3] = {plate ? h : big, big, plate ? big : h};
  char path[PATH_SIZE];
  FILE *f = fascia_tissue_open(ctx, dir, FASCIA_TISSUE_SCENE, path);
  if (!f) return FASCIA_ERR_IO;
  fprintf(f,
          "{\"fascia_scene\": 1, \"name\": \"shell %s against CalculiX\", \"voxel_size\": %.17g, \"seed\": %d,\n"
          " \"gravity\": [0, 0, %.17g],\n"
          " \"materials\": {\"wall\": {\"law\": \"stvk\", \"youngs_modulus\": %.17g, \"poisson_ratio\": %.17g,"
          " \"density\": %.17g},\n"
          "               \"strand\": {\"law\": \"stvk\", \"youngs_modulus\": 1e5, \"poisson_ratio\": 0.3}},\n"
          " \"organs\": [{\"name\": \"shell\", \"mesh\": \"" FASCIA_TISSUE_SHEET "\", \"model\": \"shell\","
          " \"material\": \"wall\",\n"
          "             \"thickness\": %.17g, \"frame_spacing\": %.17g, \"sample_spacing\": %.17g,\n"
          "             \"hold\": {\"box\": {\"min\": [%.17g, %.17g, %.17g], \"max\": [%.17g, %.17g, %.17g]}}},\n"
          "            {\"name\": \"A\", \"mesh\": \"" FASCIA_TISSUE_BOX_A "\", \"model\": \"fixed\"},\n"
          "            {\"name\": \"B\", \"mesh\": \"" FASCIA_TISSUE_BOX_B "\", \"model\": \"fixed\"}],\n"
          " \"tissues\": [{\"name\": \"strand\", \"form\": \"strand\", \"from\": {\"organ\": \"A\", \"point\": "
          "[%.17g, 0, 0]},\n"
          "              \"to\": {\"organ\": \"B\", \"point\": [%.17g, 0, 0]}, \"area\": %.17g, \"material\": "
          "\"strand\",\n"
          "              \"frame_spacing\": %.17g}]}\n",
          plate ? "plate" : "bowl", e / 8, (int)def->seed, -def->gravity, s * def->youngs_modulus, def->poisson_ratio,
          def->density, s * def->thickness, sp, sp / (def->split > 1 ? def->split : 1), lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], x0 + e, x0 + 2 * e,
          e * e / 64, e / 4);
  return fascia_tissue_close(ctx, f, path);
}

// ------------------------------------------------------------ deck

// Node id of point (i, j) of the plate's (2 ex + 1) x (2 ey + 1) grid.
static int32_t plate_node(const fascia_shell_def *d, int32_t i, int32_t j) {
  return fascia_ccx_s8r_node(d->elements[0], i, j);
}

static void write_plate_mesh(const fascia_shell_def *d, FILE *out) {
  const int32_t ex = d->elements[0], ey = d->elements[1], nx = 2 * ex + 1, ny = 2 * ey + 1;
  fascia_ccx_s8r_rectangle(out, ex, ey, 0, d->length, -d->width / 2, d->width);
  fprintf(out, "*NSET, NSET=NFIX\n");
  for (int32_t j = 0; j < ny; ++j) fprintf(out, "%d,\n", (int)plate_node(d, 0, j));
  fprintf(out, "*NSET, NSET=NPROBE\n%d\n", (int)plate_node(d, nx - 1, ey));
}

static fascia_status write_bowl_mesh(fascia_ctx *ctx, const fascia_shell_def *d, FILE *out) {
  const lattice l = {d->elements[0], d->length};
  int64_t *keys = NULL, count = 0;
  SCENE_TRY(lattice_nodes(ctx, &l, 1, &keys, &count));
  const int64_t w = 2 * (int64_t)l.h + 1;
  fprintf(out, "*NODE, NSET=NALL\n");
  for (int64_t j = 0; j < count; ++j) {
    double p[3];
    key_point(&l, keys[j], p);
    fprintf(out, "%lld, %.13g, %.13g, %.13g\n", (long long)(j + 1), p[0], p[1], p[2]);
  }
  fprintf(out, "*ELEMENT, TYPE=S8R, ELSET=EALL\n");
  int64_t element = 0;
  // corners then mid-sides, as (da, db) offsets in half-steps from the cell's corner
  static const int32_t order[8][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 0}, {2, 1}, {1, 2}, {0, 1}};
  static const int reversed[8] = {0, 3, 2, 1, 7, 6, 5, 4};
  for (int f = 0; f < 5; ++f)
    for (int32_t b = -l.h; b < -l.h + face_rows(&l, f); b += 2)
      for (int32_t a = -l.h; a < l.h; a += 2) {
        const int turn = outward(&l, f, a, b, 2);
        fprintf(out, "%lld", (long long)++element);
        for (int k = 0; k < 8; ++k) {
          const int32_t *o = order[turn ? k : reversed[k]];
          int32_t ijk[3];
          face_node(&l, f, a + o[0], b + o[1], ijk);
          fprintf(out, ", %lld", (long long)node_id(keys, count, &l, ijk));
        }
        fprintf(out, "\n");
      }
  fprintf(out, "*NSET, NSET=NFIX\n");
  for (int64_t j = 0; j < count; ++j)
    if (keys[j] / (w * w) == l.h) fprintf(out, "%lld,\n", (long long)(j + 1)); // K = 0: the rim
  const int32_t bottom[3] = {0, 0, -l.h};
  fprintf(out, "*NSET, NSET=NPROBE\n%lld\n", (long long)node_id(keys, count, &l, bottom));
  free(keys);
  return FASCIA_OK;
}

// The probe's node id and the mesh's node count.
static fascia_status probe_node(fascia_ctx *ctx, const fascia_shell_def *d, int64_t *id, int32_t *nodes) {
  if (d->kind == FASCIA_SHELL_PLATE) {
    const int32_t ex = d->elements[0], ey = d->elements[1];
    *id = plate_node(d, 2 * ex, ey);
    *nodes = (2 * ex + 1) * (2 * ey + 1) - ex * ey;
    return FASCIA_OK;
  }
  const lattice l = {d->elements[0], d->length};
  int64_t *keys = NULL, count = 0;
  SCENE_TRY(lattice_nodes(ctx, &l, 1, &keys, &count));
  const int32_t bottom[3] = {0, 0, -l.h};
  *id = node_id(keys, count, &l, bottom);
  *nodes = (int32_t)count;
  free(keys);
  return FASCIA_OK;
}

fascia_status fascia_shell_write_deck(fascia_ctx *ctx, const void *shell_def, FILE *out) {
  const fascia_shell_def *d = shell_def;
  SCENE_TRY(check_def(ctx, d));
  const int plate = d->kind == FASCIA_SHELL_PLATE;
  if (plate)
    fprintf(out,
            "** fascia's shell plate (tools/scenes/shell_calculix.c): %g x %g m in z = 0, %g m thick, the edge\n"
            "** x = 0 clamped, under its own weight; %d x %d S8R elements, NLGEOM\n*HEADING\nfascia shell plate\n",
            d->length, d->width, d->thickness, (int)d->elements[0], (int)d->elements[1]);
  else
    fprintf(out,
            "** fascia's shell bowl (tools/scenes/shell_calculix.c): a hemisphere of radius %g m below z = 0,\n"
            "** %g m thick, its rim clamped, under its own weight; %d S8R elements along a quarter of the rim\n"
            "** (%d in all), NLGEOM\n*HEADING\nfascia shell bowl\n",
            d->length, d->thickness, (int)d->elements[0], (int)(3 * d->elements[0] * d->elements[0]));
  if (plate) write_plate_mesh(d, out);
  else SCENE_TRY(write_bowl_mesh(ctx, d, out));
  fprintf(out, "*MATERIAL, NAME=WALL\n*ELASTIC\n%.13g, %.13g\n*DENSITY\n%.13g\n", d->youngs_modulus, d->poisson_ratio,
          d->density);
  fprintf(out, "*SHELL SECTION, ELSET=EALL, MATERIAL=WALL\n%.13g\n*BOUNDARY\nNFIX, 1, 6\n", d->thickness);
  fascia_tissue_deck_step(out);
  fprintf(out, "*DLOAD\nEALL, GRAV, %.13g, 0., 0., -1.\n*NODE PRINT, NSET=NPROBE\nU\n*END STEP\n", d->gravity);
  return fascia_ccx_deck_written(ctx, out);
}

fascia_status fascia_shell_calculix(fascia_ctx *ctx, const fascia_shell_def *def, const char *program,
                                    fascia_shell_result *out) {
  SCENE_CHECK(out, ctx, FASCIA_ERR_ARGUMENT, "shell case: NULL result");
  memset(out, 0, sizeof *out);
  char *dat = NULL;
  SCENE_TRY(fascia_ccx_run_timed(ctx, def->kind == FASCIA_SHELL_PLATE ? "shell plate" : "shell bowl",
                                 fascia_shell_write_deck, def, program, 1, &dat, &out->ms));
  int64_t probe = -1;
  fascia_status status = probe_node(ctx, def, &probe, &out->nodes);
  const int ok = status == FASCIA_OK &&
                 fascia_tissue_dat_node(dat, "displacements (vx,vy,vz) for set NPROBE", probe, out->probe);
  free(dat);
  SCENE_TRY(status);
  SCENE_CHECK(ok, ctx, FASCIA_ERR_FORMAT, "CalculiX shell case: its output lacks the displacement of node %lld",
              (long long)probe);
  return FASCIA_OK;
}
