// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Gap, contact and overlap reports of `fascia prep` (the CLI, argv[1]) on
// boxes with exact answers, measured on the surfaces so they do not move
// with the voxel size:
//   - four boxes in a row, gaps of 0.5, 1 and 3 voxels, one tissue joining
//     them: the gaps are reported exactly, the two thinner than three voxels
//     warned about (text and --json), the tissue volume matches an
//     independent integration of d_i + d_j <= max_gap over exact box
//     distances within one voxel layer, and every piece touches two boxes;
//   - a 1.75 mm gap at 1 mm voxels and a 0.75 mm gap at 2 mm voxels are gaps
//     (warned about), not contacts; touching boxes are a contact;
//   - boxes overlapping by 4.5 mm report a 4.5 mm depth at 1 and 0.5 mm voxels.
#define _POSIX_C_SOURCE 200809L // mkdtemp, popen
#include <cjson/cJSON.h>
#include <math.h>

#include "check.h"
#include "cli_exec.h"
#include "prep_fixture.h"

static const char *cli;
static char dir[256];
static cli_result result;

// Scene text for organs named A, B, ... (files a.obj, ...), one tissue
// joining all of them.
static int write_scene(int organs, double h, double max_gap) {
  char text[4096];
  int n = snprintf(text, sizeof text,
                   "{\"fascia_scene\": 1, \"voxel_size\": %g, \"seed\": 2,\n"
                   " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
                   " \"organs\": [",
                   h);
  for (int k = 0; k < organs; ++k)
    n += snprintf(text + n, sizeof text - (size_t)n, "%s{\"name\": \"%c\", \"mesh\": \"%c.obj\", \"model\": \"fixed\"}",
                  k ? ", " : "", 'A' + k, 'a' + k);
  n += snprintf(text + n, sizeof text - (size_t)n, "],\n \"tissues\": [{\"name\": \"t\", \"connects\": [");
  for (int k = 0; k < organs; ++k) n += snprintf(text + n, sizeof text - (size_t)n, "%s\"%c\"", k ? ", " : "", 'A' + k);
  snprintf(text + n, sizeof text - (size_t)n,
           "], \"max_gap\": %g, \"material\": \"soft\", \"frame_spacing\": %g, \"sample_spacing\": %g}]}\n", max_gap,
           fmax(0.003, 3 * h), fmax(0.0015, 1.5 * h));
  return fixture_write(dir, "scene.json", text);
}

// Runs fascia prep --json on the scene; the parsed JSON (NULL on failure).
static cJSON *prep(void) {
  char args[1024], err[512];
  snprintf(args, sizeof args, "prep '%s/scene.json' -o '%s/model.h5' --json", dir, dir);
  snprintf(err, sizeof err, "%s/err.txt", dir);
  if (!cli_exec(cli, args, err, &result) || result.status != 0) {
    fprintf(stderr, "fascia %s: status %d\n%s\n", args, result.status, result.err);
    return NULL;
  }
  return cJSON_Parse(result.out);
}

// The gaps entry of organs a and b in the --json output.
static const cJSON *gap_entry(const cJSON *root, const char *a, const char *b) {
  const cJSON *e;
  cJSON_ArrayForEach(e, cJSON_GetObjectItemCaseSensitive(root, "gaps")) {
    const char *ea = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(e, "a"));
    const char *eb = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(e, "b"));
    if (ea && eb && !strcmp(ea, a) && !strcmp(eb, b)) return e;
  }
  return NULL;
}

static int kind_is(const cJSON *root, const char *a, const char *b, const char *kind, double distance) {
  const cJSON *e = gap_entry(root, a, b);
  const char *k = e ? cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(e, "kind")) : NULL;
  const double d = e ? cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(e, "distance")) : NAN;
  if (!k || strcmp(k, kind) || !(fabs(d - distance) <= 1e-8)) {
    fprintf(stderr, "'%s'-'%s': kind %s, distance %.9g m; expected %s, %.9g m\n", a, b, k ? k : "(none)", d, kind,
            distance);
    return 0;
  }
  return 1;
}

// Number of --json warnings naming both organs.
static int warnings_about(const cJSON *root, const char *a, const char *b) {
  char qa[16], qb[16];
  snprintf(qa, sizeof qa, "'%s'", a);
  snprintf(qb, sizeof qb, "'%s'", b);
  int count = 0;
  const cJSON *w;
  cJSON_ArrayForEach(w, cJSON_GetObjectItemCaseSensitive(root, "warnings")) {
    const char *s = cJSON_GetStringValue(w);
    count += s && strstr(s, qa) && strstr(s, qb);
  }
  return count;
}

// Exact distance from p to the box [lo, hi] (0 inside).
static double box_distance(const double *p, const double *lo, const double *hi) {
  double s = 0;
  for (int r = 0; r < 3; ++r) {
    const double e = fmax(fmax(lo[r] - p[r], p[r] - hi[r]), 0);
    s += e * e;
  }
  return sqrt(s);
}

// Four boxes in a row along x, 8 mm long, 12 mm square, gaps 0.5, 1, 3 voxels.
static int row(double h) {
  const double max_gap = 4 * h, shift = 0.3 * h, gaps[3] = {0.5 * h, 1 * h, 3 * h};
  double lo[4][3], hi[4][3], x = 0;
  char name[8];
  for (int k = 0; k < 4; ++k) {
    lo[k][0] = x + shift, hi[k][0] = x + 0.008 + shift;
    for (int r = 1; r < 3; ++r) lo[k][r] = -0.006 + shift, hi[k][r] = 0.006 + shift;
    x += 0.008 + (k < 3 ? gaps[k] : 0);
    snprintf(name, sizeof name, "%c.obj", 'a' + k);
    CHECK(fixture_box(dir, name, lo[k], hi[k]));
  }
  CHECK(write_scene(4, h, max_gap));
  cJSON *root = prep();
  CHECK(root);
  if (!root) return 1;
  CHECK(kind_is(root, "A", "B", "thin", gaps[0]));
  CHECK(kind_is(root, "B", "C", "thin", gaps[1]));
  CHECK(kind_is(root, "C", "D", "gap", gaps[2]));
  CHECK(warnings_about(root, "A", "B") == 1 && warnings_about(root, "B", "C") == 1 &&
        warnings_about(root, "C", "D") == 0);
  CHECK(strstr(result.err, "warning: the gap between 'A' and 'B' (0.5 mm) is thinner than three voxels"));
  // independent volume: midpoint rule at h / 8 over exact box distances
  const double ds = h / 8, grow = max_gap;
  double vol = 0, faces = 0;
  const int64_t nx = (int64_t)ceil((x + 2 * grow) / ds), ny = (int64_t)ceil((0.012 + 2 * grow) / ds);
  uint8_t *prev = calloc((size_t)(nx * ny), 1), *cur = calloc((size_t)(nx * ny), 1);
  for (int64_t k = 0; k < ny; ++k) { // z layers
    for (int64_t j = 0; j < ny; ++j)
      for (int64_t i = 0; i < nx; ++i) {
        const double p[3] = {shift - grow + (i + 0.5) * ds, shift - 0.006 - grow + (j + 0.5) * ds,
                             shift - 0.006 - grow + (k + 0.5) * ds};
        double d[4];
        int in = 0, outside = 1;
        for (int o = 0; o < 4; ++o) outside &= (d[o] = box_distance(p, lo[o], hi[o])) > 0;
        for (int o = 0; o < 4 && outside; ++o)
          for (int q = o + 1; q < 4; ++q) in |= d[o] + d[q] <= max_gap;
        cur[i + nx * j] = (uint8_t)in;
      }
    for (int64_t j = 0; j < ny; ++j)
      for (int64_t i = 0; i < nx; ++i) {
        const int c = cur[i + nx * j];
        vol += c;
        faces += (i + 1 < nx && c != cur[i + 1 + nx * j]) + (j + 1 < ny && c != cur[i + nx * (j + 1)]) +
                 (c != prev[i + nx * j]);
      }
    uint8_t *t = prev;
    prev = cur, cur = t;
  }
  free(prev);
  free(cur);
  vol *= ds * ds * ds;
  const double area = faces * ds * ds; // a staircase area: at most sqrt(3) times the true one
  const cJSON *tissue = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(root, "tissues"), 0);
  const double got = cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(tissue, "volume"));
  fprintf(stderr, "row, voxel %g mm: tissue %.5g cm^3, integrated %.5g cm^3 (%+.2f %%), one voxel layer %.3g cm^3\n",
          1e3 * h, 1e6 * got, 1e6 * vol, 100 * (got / vol - 1), 1e6 * 0.5 * h * area / sqrt(3.0));
  CHECK_NEAR(got, vol, 0, 0.5 * h * area / sqrt(3.0));
  cJSON_Delete(root);
  // the same scene through the API: every piece of tissue bridges two boxes
  char path[512];
  snprintf(path, sizeof path, "%s/scene.json", dir);
  fascia_ctx *ctx = fixture_ctx();
  fixture_run run;
  CHECK_OK(fixture_prep(ctx, path, &run), ctx);
  int pieces = 0;
  CHECK(fixture_pieces_touch(run.volume, 1, 2, &pieces));
  fprintf(stderr, "row: %d pieces of tissue, each touching two boxes\n", pieces);
  fixture_free(&run);
  fascia_ctx_destroy(&ctx);
  return 0;
}

// Two boxes along x, B starting `gap` after A ends (negative: overlap); B
// is narrower (8 mm square against 24 mm) so its corners reach into A.
static cJSON *pair(double h, double gap, double max_gap) {
  const double shift = 0.3 * h;
  const double a_lo[3] = {-0.01 + shift, -0.012 + shift, -0.012 + shift}, a_hi[3] = {shift, 0.012 + shift, 0.012 + shift};
  const double b_lo[3] = {gap + shift, -0.004 + shift, -0.004 + shift},
               b_hi[3] = {gap + 0.01 + shift, 0.004 + shift, 0.004 + shift};
  if (!fixture_box(dir, "a.obj", a_lo, a_hi) || !fixture_box(dir, "b.obj", b_lo, b_hi) ||
      !write_scene(2, h, max_gap))
    return NULL;
  return prep();
}

static double overlap_depth(const cJSON *root) {
  const cJSON *o = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(root, "overlaps"), 0);
  return o ? cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(o, "depth")) : NAN;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t551_prep_gap_reports PATH_TO_FASCIA\n");
    return 1;
  }
  cli = argv[1];
  if (!fixture_tmpdir(dir)) return 1;
  int failed = row(0.001);
  cJSON *r = pair(0.001, 0.00175, 0.006); // thinner than three voxels: a gap, warned about
  CHECK(r && kind_is(r, "A", "B", "thin", 0.00175) && warnings_about(r, "A", "B") == 1);
  CHECK(!strstr(result.err, "none is built") && !strstr(result.err, "contact:"));
  cJSON_Delete(r);
  r = pair(0.002, 0.00075, 0.008); // below half a voxel: still a gap
  CHECK(r && kind_is(r, "A", "B", "thin", 0.00075) && warnings_about(r, "A", "B") == 1);
  cJSON_Delete(r);
  r = pair(0.001, 0, 0.006); // touching
  CHECK(r && kind_is(r, "A", "B", "contact", 0) && warnings_about(r, "A", "B") == 0);
  CHECK(strstr(result.err, "contact: 'A' and 'B' touch"));
  cJSON_Delete(r);
  for (int k = 0; k < 2; ++k) { // overlapping by 4.5 mm: the depth is the penetration, at any voxel size
    const double h = k ? 0.0005 : 0.001;
    r = pair(h, -0.0045, 0.006);
    CHECK(r && kind_is(r, "A", "B", "overlap", 0));
    CHECK(r && fabs(overlap_depth(r) - 0.0045) <= 1e-8);
    if (r) fprintf(stderr, "overlap 4.5 mm at voxel %g mm: depth %.6g mm\n", 1e3 * h, 1e3 * overlap_depth(r));
    cJSON_Delete(r);
  }
  static const char *const files[] = {"a.obj", "b.obj", "c.obj", "d.obj", "scene.json", "model.h5", "err.txt", NULL};
  fixture_cleanup(dir, files);
  return failed || CHECK_RESULT();
}
