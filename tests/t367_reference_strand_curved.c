// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A curved strand against CalculiX on the same curve (issue 43): a strand of
// 2 x 2 mm square section leaves the fixed box A's face at the origin along
// +x and bends down a quarter circle of radius 20 mm (a polyline through
// `segments` + 1 points of the circle) onto the top face of box B, a rigid
// 20 mm cube hanging from it under gravity -z: a hook, bent in its plane.
// fascia: the scene's strand "through" the circle's inner points, its
// default frames (17); CalculiX: B32 beams on the same polyline, clamped at
// A, joined to B's centre by a rigid link that carries B's weight
// (tools/scenes/tissue_calculix.c's hanging organ, on a curve). fascia's
// B centre, strand end, B rotation and force on A within 3 % of the stored
// reference (data/reference/strand-curved-calculix.csv, finest row).
// Usage: t367_reference_strand_curved data/reference/strand-curved-calculix.csv
//        t367_reference_strand_curved --write FILE   (solves with ccx, writes the reference)
#define _POSIX_C_SOURCE 200809L // mkdtemp, open_memstream
#include <math.h>

#include "beam_calculix.h"
#include "check.h"
#include "fascia/organs.h"
#include "prep_fixture.h"
#include "tissue_calculix.h"

#define TOLERANCE 0.03
#define PI 3.14159265358979323846

typedef struct curved_def {
  int segments;         ///< polyline segments along the quarter circle
  double radius, box;   ///< m
  double area;          ///< m^2, a square section
  double youngs_modulus, poisson_ratio, density, gravity;
  double frame_spacing; ///< fascia, m
  int elements;         ///< CalculiX: B32 elements per polyline segment
} curved_def;

static const curved_def def0 = {8, 0.02, 0.02, 4e-6, 1e8, 0.3, 1000, 9.81, 0.002, 8};

typedef struct curved_result {
  double centre[3], end[3], angle, force[3]; // as fascia_tissue_hang_result
} curved_result;

// Point k of the polyline: on the circle of centre (0, 0, -R) in the x-z plane.
static void arc_point(const curved_def *d, int k, double *x) {
  const double a = 0.5 * PI * k / d->segments;
  x[0] = d->radius * sin(a), x[1] = 0, x[2] = -d->radius * (1 - cos(a));
}

static double organ_mass(const curved_def *d) { return FASCIA_ORGAN_DENSITY * d->box * d->box * d->box; }

// ------------------------------------------------------------ CalculiX

static fascia_status write_deck(fascia_ctx *ctx, const void *arg, FILE *out) {
  (void)ctx;
  const curved_def *d = arg;
  const int n = d->segments * d->elements, last = 2 * n + 1, link = last + 1, centre = last + 2;
  const double side = sqrt(d->area), mass = organ_mass(d);
  fprintf(out, "** fascia's curved strand (tests/t367_reference_strand_curved.c): a quarter circle of radius %g m as\n"
               "** %d straight segments of %d B32 elements each, clamped at node 1, its end (node %d) joined rigidly\n"
               "** to the hanging organ's centre (node %d), which carries its weight (%.6g kg); NLGEOM\n"
               "*HEADING\nfascia curved strand\n*NODE, NSET=NALL\n",
          d->radius, d->segments, d->elements, last, centre, mass);
  int node = 1;
  for (int k = 0; k < d->segments; ++k) {
    double p[3], q[3];
    arc_point(d, k, p);
    arc_point(d, k + 1, q);
    for (int j = 0; j < 2 * d->elements; ++j, ++node) {
      const double s = (double)j / (2 * d->elements);
      fprintf(out, "%d, %.13g, %.13g, %.13g\n", node, p[0] + s * (q[0] - p[0]), 0.0, p[2] + s * (q[2] - p[2]));
    }
  }
  double e[3];
  arc_point(d, d->segments, e);
  fprintf(out, "%d, %.13g, 0, %.13g\n%d, %.13g, 0, %.13g\n%d, %.13g, 0, %.13g\n", last, e[0], e[2], link, e[0],
          e[2] - d->box / 4, centre, e[0], e[2] - d->box / 2);
  fprintf(out, "*ELEMENT, TYPE=B32, ELSET=ESTRAND\n");
  for (int k = 0; k < n; ++k) fprintf(out, "%d, %d, %d, %d\n", k + 1, 2 * k + 1, 2 * k + 2, 2 * k + 3);
  fprintf(out, "*ELEMENT, TYPE=B32, ELSET=ELINK\n%d, %d, %d, %d\n", n + 1, last, link, centre);
  fprintf(out, "*NSET, NSET=NFIX\n1,\n*NSET, NSET=NORGAN\n%d, %d\n", last, centre);
  fprintf(out, "*MATERIAL, NAME=STRAND\n*ELASTIC\n%.13g, %.13g\n*DENSITY\n%.13g\n", d->youngs_modulus,
          d->poisson_ratio, d->density);
  fprintf(out, "*MATERIAL, NAME=LINK\n*ELASTIC\n%.13g, %.13g\n", 1e3 * d->youngs_modulus, d->poisson_ratio);
  fprintf(out, "*BEAM SECTION, ELSET=ESTRAND, MATERIAL=STRAND, SECTION=RECT\n%.13g, %.13g\n0., 1., 0.\n", side, side);
  fprintf(out, "*BEAM SECTION, ELSET=ELINK, MATERIAL=LINK, SECTION=RECT\n%.13g, %.13g\n0., 1., 0.\n", d->box, d->box);
  fprintf(out, "*BOUNDARY\nNFIX, 1, 6\n");
  fascia_tissue_deck_step(out);
  fprintf(out, "*DLOAD\nESTRAND, GRAV, %.13g, 0., 0., -1.\n*CLOAD\n%d, 3, %.13g\n", d->gravity, centre,
          -mass * d->gravity);
  fprintf(out, "*NODE PRINT, NSET=NORGAN\nU\n*NODE PRINT, NSET=NFIX, TOTALS=ONLY\nRF\n*END STEP\n");
  return ferror(out) ? FASCIA_ERR_IO : FASCIA_OK;
}

static fascia_status solve_calculix(fascia_ctx *ctx, const curved_def *d, const char *program, curved_result *out) {
  char *dat = NULL;
  double cpu_ms = 0;
  fascia_status st = fascia_ccx_run_deck(ctx, "curved strand", write_deck, d, program, 1, &dat, &cpu_ms);
  if (st != FASCIA_OK) return st;
  const int last = 2 * d->segments * d->elements + 1;
  double reaction[3] = {0, 0, 0};
  const int ok = fascia_tissue_dat_node(dat, "displacements (vx,vy,vz) for set NORGAN", last, out->end) &&
                 fascia_tissue_dat_node(dat, "displacements (vx,vy,vz) for set NORGAN", last + 2, out->centre);
  const char *rf = strstr(dat, "total force (fx,fy,fz) for set NFIX");
  for (const char *p = rf; p; p = strstr(p + 1, "total force (fx,fy,fz) for set NFIX")) rf = p;
  const int ok_rf = rf && sscanf(strchr(rf, '\n'), " %lf %lf %lf", reaction, reaction + 1, reaction + 2) == 3;
  free(dat);
  if (!ok || !ok_rf) return FASCIA_ERR_FORMAT;
  for (int a = 0; a < 3; ++a) out->force[a] = -reaction[a];
  // the link's direction, along -z at rest; a rotation about +y turns it to (-sin, 0, -cos)
  const double dx = out->centre[0] - out->end[0], dz = -d->box / 2 + out->centre[2] - out->end[2];
  out->angle = atan2(-dx, -dz);
  return FASCIA_OK;
}

// ------------------------------------------------------------ fascia

static int write_scene(const char *dir, const curved_def *d, char *path) {
  double e[3];
  arc_point(d, d->segments, e);
  const double a_lo[3] = {-d->box, -d->box / 2, -d->box / 2}, a_hi[3] = {0, d->box / 2, d->box / 2};
  const double b_lo[3] = {e[0] - d->box / 2, -d->box / 2, e[2] - d->box}, b_hi[3] = {e[0] + d->box / 2, d->box / 2, e[2]};
  if (!fixture_box(dir, "a.obj", a_lo, a_hi) || !fixture_box(dir, "b.obj", b_lo, b_hi)) return 0;
  char through[4096] = "", text[8192];
  for (int k = 1; k < d->segments; ++k) {
    double p[3];
    arc_point(d, k, p);
    snprintf(through + strlen(through), sizeof through - strlen(through), "%s[%.17g, 0, %.17g]", k > 1 ? ", " : "",
             p[0], p[2]);
  }
  snprintf(text, sizeof text,
           "{\"fascia_scene\": 1, \"voxel_size\": %.17g, \"seed\": 1, \"gravity\": [0, 0, %.17g],\n"
           " \"materials\": {\"strand\": {\"law\": \"stvk\", \"youngs_modulus\": %.17g, \"poisson_ratio\": %.17g, "
           "\"density\": %.17g}},\n"
           " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
           "              {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"rigid\"}],\n"
           " \"tissues\": [{\"name\": \"strand\", \"form\": \"strand\", \"from\": {\"organ\": \"A\", \"point\": [0, 0, 0]},\n"
           "   \"to\": {\"organ\": \"B\", \"point\": [%.17g, 0, %.17g]}, \"through\": [%s],\n"
           "   \"area\": %.17g, \"material\": \"strand\", \"frame_spacing\": %.17g}]}\n",
           d->box / 40, -d->gravity, d->youngs_modulus, d->poisson_ratio, d->density, e[0], e[2], through, d->area,
           d->frame_spacing);
  snprintf(path, 512, "%s/scene.json", dir);
  return fixture_write(dir, "scene.json", text);
}

// v rotated by the unit quaternion q (w, x, y, z).
static void rotate(const fascia_real q[4], const double v[3], double out[3]) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double t[3] = {2 * (y * v[2] - z * v[1]), 2 * (z * v[0] - x * v[2]), 2 * (x * v[1] - y * v[0])};
  out[0] = v[0] + w * t[0] + (y * t[2] - z * t[1]);
  out[1] = v[1] + w * t[1] + (z * t[0] - x * t[2]);
  out[2] = v[2] + w * t[2] + (x * t[1] - y * t[0]);
}

static int solve_fascia(const curved_def *d, curved_result *out, int *frames) {
  char dir[256], path[512];
  if (!fixture_tmpdir(dir) || !write_scene(dir, d, path)) return 0;
  fascia_ctx *ctx = fixture_ctx();
  fixture_run r;
  fascia_status st = fixture_prep(ctx, path, &r);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  fascia_solver *solver = NULL;
  int ok = st == FASCIA_OK;
  if (!ok) fprintf(stderr, "fascia prep: %s\n", fascia_ctx_message(ctx));
  if (ok) {
    const fascia_model *m = r.model;
    *frames = m->frame_count;
    fascia_solve_report report;
    double ms;
    st = fascia_tissue_solve_static(ctx, m, &solver, &report, &ms);
    const int32_t A = fascia_model_find_organ(m, "A"), B = fascia_model_find_organ(m, "B");
    int32_t end = -1;
    fascia_real t[3], q[4], mass, c[3], torque[3], force[3];
    ok = st == FASCIA_OK && fascia_solver_organ_frame_count(solver, B) == 1 &&
         fascia_solver_organ_frames(solver, B, &end) == FASCIA_OK &&
         fascia_solver_organ_pose(solver, B, t, q) == FASCIA_OK &&
         fascia_solver_organ_mass(solver, B, &mass, c, NULL) == FASCIA_OK &&
         fascia_solver_organ_wrench(solver, A, force, torque, NULL) == FASCIA_OK;
    if (!ok) fprintf(stderr, "fascia solve: %s\n", fascia_ctx_message(ctx));
    if (ok) {
      const double cc[3] = {c[0], c[1], c[2]};
      double moved[3];
      rotate(q, cc, moved);
      const fascia_real *x = fascia_solver_frame_positions(solver);
      for (int a = 0; a < 3; ++a) {
        out->centre[a] = moved[a] + t[a] - cc[a];
        out->end[a] = x[3 * end + a] - m->frame_position[3 * end + a];
        out->force[a] = force[a];
      }
      out->angle = 2 * atan2(q[2], q[0]);
    }
  }
  fascia_solver_destroy(&solver);
  fixture_free(&r);
  fascia_ctx_destroy(&ctx);
  return ok;
}

// ------------------------------------------------------------ the reference file

static const char header[] = "segments,radius_m,box_m,area_m2,youngs_modulus_pa,poisson_ratio,density,gravity,"
                             "elements_per_segment,centre_ux,centre_uy,centre_uz,end_ux,end_uy,end_uz,angle_rad,"
                             "force_x,force_y,force_z";

static int write_reference(const char *file) {
  const char *program = fascia_ccx_program();
  if (!program) {
    fprintf(stderr, "CalculiX (ccx) is not installed (Debian: calculix-ccx, or set FASCIA_CCX)\n");
    return 1;
  }
  char tmp[1024];
  snprintf(tmp, sizeof tmp, "%s.tmp", file);
  FILE *f = fopen(tmp, "w");
  if (!f) return 1;
  fprintf(f, "# CalculiX B32 reference of a quarter-circle strand carrying a rigid organ (tests/t367_reference_strand_"
             "curved.c; regenerate: build/tests/t367_reference_strand_curved --write %s); finest row last\n%s\n",
          "data/reference/strand-curved-calculix.csv", header);
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  int ok = 1;
  static const int ladder[3] = {2, 4, 8};
  for (int k = 0; k < 3 && ok; ++k) {
    curved_def d = def0;
    d.elements = ladder[k];
    curved_result c;
    ok = solve_calculix(ctx, &d, program, &c) == FASCIA_OK;
    if (!ok) fprintf(stderr, "ccx: %s\n", fascia_ctx_message(ctx));
    if (ok)
      fprintf(f, "%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n",
              d.segments, d.radius, d.box, d.area, d.youngs_modulus, d.poisson_ratio, d.density, d.gravity,
              d.elements, c.centre[0], c.centre[1], c.centre[2], c.end[0], c.end[1], c.end[2], c.angle, c.force[0],
              c.force[1], c.force[2]);
  }
  fascia_ctx_destroy(&ctx);
  ok = fclose(f) == 0 && ok;
  if (ok) ok = rename(tmp, file) == 0;
  else remove(tmp);
  return ok ? 0 : 1;
}

// The last row of the reference; 0 if unreadable or not of def0's case.
static int read_reference(const char *file, curved_result *c) {
  FILE *f = fopen(file, "r");
  if (!f) return 0;
  char line[1024];
  int found = 0;
  while (fgets(line, sizeof line, f)) {
    if (line[0] == '#' || !strncmp(line, "segments", 8)) continue;
    curved_def d;
    if (sscanf(line, "%d,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%d,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &d.segments,
               &d.radius, &d.box, &d.area, &d.youngs_modulus, &d.poisson_ratio, &d.density, &d.gravity, &d.elements,
               c->centre, c->centre + 1, c->centre + 2, c->end, c->end + 1, c->end + 2, &c->angle, c->force,
               c->force + 1, c->force + 2) != 19)
      continue;
    found = d.segments == def0.segments && fabs(d.radius - def0.radius) < 1e-12 && fabs(d.box - def0.box) < 1e-12 &&
            fabs(d.area - def0.area) < 1e-15 && fabs(d.youngs_modulus / def0.youngs_modulus - 1) < 1e-9 &&
            fabs(d.gravity - def0.gravity) < 1e-9;
  }
  fclose(f);
  return found;
}

static void check_deck(void) {
  char *text = NULL;
  size_t size = 0;
  FILE *f = open_memstream(&text, &size);
  CHECK(f && write_deck(NULL, &def0, f) == FASCIA_OK);
  if (f) fclose(f);
  CHECK(text && strstr(text, "TYPE=B32, ELSET=ESTRAND") && strstr(text, "*STEP, NLGEOM"));
  // the polyline's last point is the circle's: (R, 0, -R)
  char last[128];
  snprintf(last, sizeof last, "\n%d, %.13g, 0, %.13g\n", 2 * def0.segments * def0.elements + 1, def0.radius,
           -def0.radius);
  CHECK(text && strstr(text, last));
  free(text);
}

int main(int argc, char **argv) {
  if (argc == 3 && !strcmp(argv[1], "--write")) return write_reference(argv[2]);
  if (argc != 2) {
    fprintf(stderr, "usage: t367_reference_strand_curved REFERENCE.csv | --write FILE\n");
    return 1;
  }
  check_deck();
  curved_result cc, fa;
  CHECK(read_reference(argv[1], &cc));
  int frames = 0;
  CHECK(solve_fascia(&def0, &fa, &frames));
  if (check_failures_) return 1;
  const double e[4] = {fascia_tissue_error3(fa.centre, cc.centre), fascia_tissue_error3(fa.end, cc.end),
                       fascia_tissue_error3(fa.force, cc.force), fabs(fa.angle - cc.angle) / fabs(cc.angle)};
  printf("curved strand (%d frames; %d x %d B32): organ centre (%.4f, %.4f) / (%.4f, %.4f) mm (%.2f %%), strand end "
         "(%.4f, %.4f) / (%.4f, %.4f) mm (%.2f %%), force on A z %.4f / %.4f mN (%.2f %%), rotation %.2f / %.2f mrad "
         "(%.2f %%)\n",
         frames, def0.segments, def0.elements, 1e3 * fa.centre[0], 1e3 * fa.centre[2], 1e3 * cc.centre[0],
         1e3 * cc.centre[2], 100 * e[0], 1e3 * fa.end[0], 1e3 * fa.end[2], 1e3 * cc.end[0], 1e3 * cc.end[2],
         100 * e[1], 1e3 * fa.force[2], 1e3 * cc.force[2], 100 * e[2], 1e3 * fa.angle, 1e3 * cc.angle, 100 * e[3]);
  for (int k = 0; k < 4; ++k) CHECK(e[k] < TOLERANCE);
  CHECK(frames == 17);
  CHECK(cc.centre[2] < -0.05 * def0.radius); // a large displacement, not a linear case
  return CHECK_RESULT();
}
