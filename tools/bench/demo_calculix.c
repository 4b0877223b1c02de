// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// demo-calculix: the demo's tissue against CalculiX, statically
// (tools/scenes/demo_calculix.h). Prints, side by side: CalculiX's force on
// each organ for each mesh asked for, fascia's at the default and at finer
// rungs of frame and sample spacing, the error of each against the
// reference mesh, fascia's displacement error at the reference's nodes
// (50th, 95th percentile and largest, in % of CalculiX's largest
// displacement), the slip of fascia's tissue on the organs (its displacement
// against the organ's at the organ-facing nodes, mm), and each solve's time.
//
//   demo-calculix [SCENE.json] [--ccx LIST] [--fascia LIST] [--reference K]
//                 [--neighbours N] [--threads N] [--csv FILE]
//   --ccx     meshes, comma-separated TYPE:VOXEL_MM:SPLIT[:surface] (TYPE
//             8i = C3D8I, 20r = C3D20R; SPLIT elements along a voxel's edge;
//             surface: the held nodes moved onto the organs' smooth
//             surfaces, where fascia holds the tissue, not left on the voxel
//             faces' staircase); default 8i:1:1,8i:1:2,20r:1:1; or
//             t10:VOXEL_MM:SIZE_MM[:FACET_MM], C3D10 tetrahedra of
//             circumradius at most SIZE_MM that follow the organs' smooth
//             surfaces to FACET_MM (default a twentieth of a voxel)
//   --fascia  rungs, comma-separated VOXEL_MM:SCALE[:SAMPLE_SCALE] (the
//             tissue's frame and sample spacings times SCALE, the sample
//             spacing times SAMPLE_SCALE on top); default 1:1,1:0.7,1:0.5
//   --reference  the CalculiX mesh (from 1) the errors are taken against;
//             default the last; displacements are compared at the nodes of
//             the last mesh of each rung's voxel size
//   TAG       nK: K MLS neighbours; flat: no volumetric patches; frames, e
//             or eX: attachment frames or exact (layer X sample spacings);
//             several joined by +
//   --cache DIR  CalculiX's answers read from DIR when there for the same deck,
//             else solved and kept there with their deck
//   --write-reference FILE  CalculiX's forces per mesh, the reference last
//             (data/reference/demo-calculix.csv, read by tests/t598)
//   --mesh-only  CalculiX's meshes built and described, nothing solved
//   --deck FILE  ... and the (last) mesh's CalculiX deck written to FILE
//   --slip    per rung, the tissue's slip on each organ by distance to the
//             organ's nearest shared frame, where the largest error lies,
//             and the tissue's volume by distance to its nearest organ
//             (CalculiX's tetrahedra against fascia's samples)
//   --linear  CalculiX's linear elasticity (E and nu, no NLGEOM, one solve):
//             the reference for a small motion, where the nonlinear solve
//             of a region of thin layers stalls (tools/bench/ct-vs-calculix.sh)
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "beam_calculix.h"
#include "demo_calculix.h"
#include "point/material.h"
#include "scene_util.h"
#include "tissue_calculix.h"

#define ROWS_MAX 32

typedef struct ccx_row {
  int quadratic;
  int tetrahedra;  ///< C3D10 of fascia_demo_tet_mesh_build, size_mm its tetrahedra's circumradius bound
  double size_mm;
  double facet_mm; ///< tetrahedra: their facets' distance bound on the organs; 0: the mesher's default
  double voxel_mm;
  int32_t split;
  int on_surface; ///< the held nodes on the organs' smooth surfaces, not the voxel faces
  fascia_demo_mesh mesh;
  fascia_demo_result result;
} ccx_row;

typedef struct fascia_row {
  double voxel_mm, scale, sample_scale;
  int32_t neighbours, no_patches, attachment;
  double layer_scale;
} fascia_row;

// A rung's tag: nK (K MLS neighbours), flat (no volumetric patches), frames
// (attachment frames), e or eX (attachment exact, its layer X sample spacings).
static int rung_tag(const char *tag, fascia_row *row) {
  const char *plus = strchr(tag, '+'); // tags joined by +
  if (plus) {
    char first[16];
    snprintf(first, sizeof first, "%.*s", (int)(plus - tag), tag);
    return rung_tag(first, row) && rung_tag(plus + 1, row);
  }
  if (!strcmp(tag, "flat")) return row->no_patches = 1;
  if (!strcmp(tag, "frames")) return row->attachment = 1 + FASCIA_PREP_ATTACH_FRAMES, 1;
  if (!strcmp(tag, "e")) return row->attachment = 1 + FASCIA_PREP_ATTACH_EXACT, 1;
  double x;
  if (sscanf(tag, "e%lf", &x) == 1 && x > 0)
    return row->attachment = 1 + FASCIA_PREP_ATTACH_EXACT, row->layer_scale = x, 1;
  int k;
  if (sscanf(tag, "n%d", &k) == 1 && k >= 4) return row->neighbours = k, 1;
  return 0;
}

// CalculiX's answers kept between runs (--cache DIR): forces and node
// displacements of a mesh, in a file named by its kind, voxel and split,
// beside the deck they answer. The name alone does not say the scene, its
// material or its motion: an answer counts only when its deck is the one
// the run would solve, byte for byte.
static void cache_path(const char *dir, const ccx_row *c, char *path, size_t size) {
  if (c->tetrahedra) {
    char facet[32] = "";
    if (c->facet_mm > 0) snprintf(facet, sizeof facet, "-facet%g", c->facet_mm);
    snprintf(path, size, "%s/ccx-c3d10-%gmm-size%g%s.txt", dir, c->voxel_mm, c->size_mm, facet);
    return;
  }
  snprintf(path, size, "%s/ccx-%s-%gmm-split%d%s.txt", dir, c->quadratic ? "c3d20r" : "c3d8i", c->voxel_mm,
           (int)c->split, c->on_surface ? "-surface" : "");
}

// The mesh's CalculiX deck as text (malloc'd), or NULL.
static char *deck_text(fascia_ctx *ctx, const ccx_row *c, size_t *length) {
  char *text = NULL;
  FILE *f = open_memstream(&text, length);
  if (!f) return NULL;
  const fascia_status st = fascia_demo_write_deck(ctx, &c->mesh, f);
  if (fclose(f) != 0 || st != FASCIA_OK) {
    free(text);
    return NULL;
  }
  return text;
}

// Whether the file holds exactly these bytes.
static int file_equals(const char *path, const char *text, size_t length) {
  FILE *f = fopen(path, "rb");
  if (!f) return 0;
  char buffer[65536];
  size_t at = 0, got;
  int same = 1;
  while (same && (got = fread(buffer, 1, sizeof buffer, f)) > 0) {
    same = at + got <= length && !memcmp(buffer, text + at, got);
    at += got;
  }
  fclose(f);
  return same && at == length;
}

static int cache_load(const char *dir, ccx_row *c, const char *deck, size_t deck_length) {
  char path[1200], deck_path[1300];
  cache_path(dir, c, path, sizeof path);
  snprintf(deck_path, sizeof deck_path, "%s.inp", path);
  if (!deck || !file_equals(deck_path, deck, deck_length)) return 0;
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  fascia_demo_result *r = &c->result;
  memset(r, 0, sizeof *r);
  long long nodes = 0, elements = 0;
  int organs = 0, ok = fscanf(f, "%lld %lld %d %lf", &nodes, &elements, &organs, &r->ms) == 4 &&
                       nodes == c->mesh.node_count && elements == c->mesh.element_count &&
                       organs == c->mesh.organ_count;
  for (int o = 0; ok && o < organs; ++o)
    ok = fscanf(f, "%lf %lf %lf", r->force[o], r->force[o] + 1, r->force[o] + 2) == 3;
  r->u = ok ? malloc((size_t)(3 * nodes) * sizeof *r->u) : NULL;
  for (long long k = 0; r->u && k < 3 * nodes && ok; ++k) ok = fscanf(f, "%lf", r->u + k) == 1;
  fclose(f);
  if (!ok || !r->u) {
    fascia_demo_result_free(r);
    return 0;
  }
  r->nodes = nodes, r->elements = elements, r->organ_count = organs;
  return 1;
}

static void cache_save(const char *dir, const ccx_row *c, const char *deck, size_t deck_length) {
  char path[1200], tmp[1300];
  cache_path(dir, c, path, sizeof path);
  if (!deck) return;
  snprintf(tmp, sizeof tmp, "%s.inp.tmp", path); // the deck first: an answer never sits beside another's deck
  FILE *f = fopen(tmp, "wb");
  if (!f) return;
  const int wrote = fwrite(deck, 1, deck_length, f) == deck_length;
  if (fclose(f) != 0 || !wrote) return;
  char deck_path[1300];
  snprintf(deck_path, sizeof deck_path, "%s.inp", path);
  remove(path);
  if (rename(tmp, deck_path) != 0) return;
  snprintf(tmp, sizeof tmp, "%s.tmp", path);
  f = fopen(tmp, "w");
  if (!f) return;
  const fascia_demo_result *r = &c->result;
  fprintf(f, "%lld %lld %d %.1f\n", (long long)r->nodes, (long long)r->elements, (int)r->organ_count, r->ms);
  for (int o = 0; o < r->organ_count; ++o) fprintf(f, "%.9g %.9g %.9g\n", r->force[o][0], r->force[o][1], r->force[o][2]);
  for (int64_t k = 0; k < r->nodes; ++k)
    fprintf(f, "%.9g %.9g %.9g\n", r->u[3 * k], r->u[3 * k + 1], r->u[3 * k + 2]);
  if (fclose(f) == 0) rename(tmp, path);
  else remove(tmp);
}

static const char usage_text[] =
    "usage: demo-calculix [SCENE.json] [--ccx TYPE:VOXEL_MM:SPLIT[:surface]|t10:VOXEL_MM:SIZE_MM[:FACET_MM],...] "
    "[--fascia VOXEL_MM:SCALE[:SAMPLE_SCALE[:TAG]],...]\n"
    "                     [--reference K] [--neighbours N] [--threads N] [--csv FILE] [--cache DIR] [--slip]\n"
    "                     [--write-reference FILE] [--ccx-solver NAME] [--mesh-only] [--deck FILE] [--linear]\n"
    "  TYPE 8i (C3D8I) or 20r (C3D20R); SPLIT elements along a voxel's edge; surface: held nodes on the organs'\n"
    "  smooth surfaces, not the voxel faces; t10: C3D10 tetrahedra of circumradius SIZE_MM on the organs' smooth\n"
    "  surfaces (CGAL Mesh_3), facets within FACET_MM of them; SCALE times the tissue's frame and\n"
    "  sample spacings, SAMPLE_SCALE times the sample spacing on top; TAG nK (K MLS neighbours) or flat (no\n"
    "  volumetric patches); --reference K: the CalculiX mesh (from 1) errors are taken against, default the last;\n"
    "  --ccx-solver: ccx's linear solver, e.g. \"ITERATIVE CHOLESKY\" (default: ccx's own, SPOOLES);\n"
    "  --linear: CalculiX's linear elasticity, one solve (for a small motion)\n";

static int usage(const char *why) {
  fprintf(stderr, "demo-calculix: %s\n%s", why, usage_text);
  return 2;
}

static const char *mesh_type(const ccx_row *c) { return c->tetrahedra ? "C3D10" : c->quadratic ? "C3D20R" : "C3D8I"; }

static double norm3(const double v[3]) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// The tetrahedra's edge lengths (each element's six, m): 5th, 50th, 95th percentiles.
static void tet_edges(const fascia_demo_mesh *m, double q[3]) {
  double *len = malloc((size_t)(6 * m->element_count + 1) * sizeof *len);
  q[0] = q[1] = q[2] = NAN;
  if (!len) return;
  static const int pair[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (int64_t e = 0; e < m->element_count; ++e)
    for (int k = 0; k < 6; ++k) {
      const double *a = m->node + 3 * m->element[10 * e + pair[k][0]], *b = m->node + 3 * m->element[10 * e + pair[k][1]];
      const double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
      len[6 * e + k] = norm3(d);
    }
  q[0] = fascia_demo_percentile(len, 6 * m->element_count, 0.05);
  q[1] = fascia_demo_percentile(len, 6 * m->element_count, 0.5);
  q[2] = fascia_demo_percentile(len, 6 * m->element_count, 0.95);
  free(len);
}

// The tissue's volume by distance to the nearest organ, CalculiX's mesh against fascia's samples.
static void print_volume_bands(const fascia_prep_stages *s, const fascia_demo_mesh *m) {
  enum { BANDS = 6 };
  static const double edge[BANDS - 1] = {0, 0.25e-3, 0.5e-3, 1e-3, 2e-3};
  static const char *name[BANDS] = {"<0", "0-0.25", "0.25-0.5", "0.5-1", "1-2", ">2"};
  double ref[BANDS], own[BANDS], total[2] = {0, 0};
  fascia_demo_volume_bands(s, m, BANDS, edge, ref);
  fascia_demo_volume_bands(s, NULL, BANDS, edge, own);
  printf("      volume mm3 by distance to the nearest organ (mm), CalculiX's mesh / fascia's samples:");
  for (int k = 0; k < BANDS; ++k) {
    printf(" %s %.1f/%.1f", name[k], 1e9 * ref[k], 1e9 * own[k]);
    total[0] += ref[k], total[1] += own[k];
  }
  printf("; all %.1f/%.1f\n", 1e9 * total[0], 1e9 * total[1]);
}

// The tetrahedra's quality line.
static void print_tet_quality(const fascia_demo_mesh *m) {
  double q[3];
  tet_edges(m, q);
  printf("    tetrahedra: edges p5 %.3f, p50 %.3f, p95 %.3f mm; smallest dihedral angle %.2f degrees; C3D10's "
         "Jacobian at its corners and integration points at least %.3f of the straight element's, %lld inverted\n",
         1e3 * q[0], 1e3 * q[1], 1e3 * q[2], m->min_dihedral, m->min_jacobian_ratio, (long long)m->inverted);
}

// The stable Neo-Hookean's P from fascia's own law against CalculiX's one element.
static int check_one_element(fascia_ctx *ctx, const char *ccx, double E, double nu) {
  const double F[9] = {1.1, 0.05, 0.02, -0.03, 0.95, 0.04, 0.01, 0.06, 1.08};
  double P[9];
  if (fascia_demo_one_element(ctx, ccx, E, nu, 0, F, P) != FASCIA_OK) {
    fprintf(stderr, "demo-calculix: %s\n", fascia_ctx_message(ctx));
    return 0;
  }
  const double mu = E / (2 * (1 + nu)), lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  fascia_real Fr[9], Pr[9], aux[FASCIA_PT_AUX_SIZE];
  for (int k = 0; k < 9; ++k) Fr[k] = F[k];
  fascia_pt_stress(FASCIA_PT_LAW_NEOHOOKEAN, lambda, mu, Fr, Pr, aux);
  double d = 0, n = 0;
  for (int k = 0; k < 9; ++k) d = fmax(d, fabs(P[k] - Pr[k])), n = fmax(n, fabs(Pr[k]));
  printf("one element: CalculiX's *HYPERFOAM against fascia's stable Neo-Hookean under a general F: "
         "largest |P - P_fascia| %.2e of |P|max (ccx prints 7 digits)\n",
         d / n);
  return d / n < 1e-5;
}

// The slip is binned by distance: 1 mm bins, the last one open.
enum { BINS = 6 };
static const double bin_mm = 1;

static int slip_bin(double distance) {
  const int b = (int)(1e3 * distance / bin_mm);
  return b < BINS ? b : BINS - 1;
}

// The mean slip of each bin that holds any, in mm, then the line's end.
static void print_bins(const double sum[BINS], const int64_t count[BINS]) {
  for (int b = 0; b < BINS; ++b)
    if (count[b])
      printf(" %s%g mm %.3f (%lld)", b == BINS - 1 ? ">" : "<", b == BINS - 1 ? bin_mm * b : bin_mm * (b + 1),
             1e3 * sum[b] / (double)count[b], (long long)count[b]);
  printf("\n");
}

// The slip of fascia's tissue on each organ: at the organ-facing nodes of
// CalculiX's mesh (where CalculiX's tissue moves with the organ exactly),
// fascia's displacement less the organ's, by the node's distance to the
// nearest frame the organ shares with the tissue; and where the largest
// displacement error lies.
static void print_slip(const fascia_prep_stages *s, const ccx_row *at, const fascia_demo_result *r) {
  const fascia_demo_mesh *m = &at->mesh;
  const fascia_model *model = s->model;
  for (int32_t o = 0; o < m->organ_count; ++o) {
    const int32_t k = fascia_model_find_organ(model, m->organ_name[o]);
    double sum[BINS] = {0}, motion = 0;
    int64_t count[BINS] = {0}, n = 0;
    double *sl = malloc((size_t)m->node_count * sizeof *sl);
    for (int64_t q = 0; sl && q < m->node_count; ++q) {
      if (m->node_organ[q] != o) continue;
      const double *x = m->node + 3 * q, *uf = r->u + 3 * q, *up = m->node_u + 3 * q;
      double nearest = INFINITY;
      for (int32_t c = 0; c < model->coupling_count; ++c) {
        if (model->coupling_organ[c] != k) continue;
        const fascia_real *y = model->frame_position + 3 * model->coupling_frame[c];
        const double d[3] = {x[0] - y[0], x[1] - y[1], x[2] - y[2]};
        nearest = fmin(nearest, norm3(d));
      }
      const double de[3] = {uf[0] - up[0], uf[1] - up[1], uf[2] - up[2]};
      const double slip = norm3(de);
      const int b = slip_bin(nearest);
      sum[b] += slip, ++count[b], sl[n++] = slip, motion += norm3(up);
    }
    if (sl && n > 0) {
      const double p50 = fascia_demo_percentile(sl, n, 0.5), p95 = fascia_demo_percentile(sl, n, 0.95);
      printf("      slip on %-8s %5lld nodes, organ's motion there %.3f mm on average: p50 %.3f p95 %.3f mm; "
             "mean by distance to its nearest shared frame:",
             m->organ_name[o], (long long)n, 1e3 * motion / (double)n, 1e3 * p50, 1e3 * p95);
      print_bins(sum, count);
    }
    free(sl);
    // at the organ's own surface
    const int64_t ns = r->surface_count[o];
    double ssum[BINS] = {0};
    int64_t scount[BINS] = {0};
    for (int64_t j = 0; j < ns; ++j) {
      const int b = slip_bin(r->surface_distance[o][j]);
      ssum[b] += r->surface_slip[o][j], ++scount[b];
    }
    double *copy = malloc((size_t)(ns + 1) * sizeof *copy);
    if (copy && ns > 0) {
      memcpy(copy, r->surface_slip[o], (size_t)ns * sizeof *copy);
      const double p50 = fascia_demo_percentile(copy, ns, 0.5), p95 = fascia_demo_percentile(copy, ns, 0.95);
      printf("      on %-8s own surface %5lld vertices: p50 %.3f p95 %.3f mm; by distance:", m->organ_name[o],
             (long long)ns, 1e3 * p50, 1e3 * p95);
      print_bins(ssum, scount);
    }
    free(copy);
  }
  // the node of the largest error
  int64_t worst = 0;
  double worst_e = -1;
  for (int64_t q = 0; q < m->node_count; ++q) {
    const double *uc = at->result.u + 3 * q, *uf = r->u + 3 * q;
    const double e[3] = {uf[0] - uc[0], uf[1] - uc[1], uf[2] - uc[2]};
    if (norm3(e) > worst_e) worst_e = norm3(e), worst = q;
  }
  double nearest = INFINITY;
  for (int32_t i = 0; i < model->sample_count; ++i) {
    const double d[3] = {m->node[3 * worst] - model->sample_position[3 * i],
                         m->node[3 * worst + 1] - model->sample_position[3 * i + 1],
                         m->node[3 * worst + 2] - model->sample_position[3 * i + 2]};
    nearest = fmin(nearest, norm3(d));
  }
  printf("      largest error %.3f mm at a %s node (%.4f %.4f %.4f m), %.2f mm from the nearest sample\n", 1e3 * worst_e,
         m->node_organ[worst] >= 0 ? m->organ_name[m->node_organ[worst]] : "free", m->node[3 * worst],
         m->node[3 * worst + 1], m->node[3 * worst + 2], 1e3 * nearest);
}

// Where CalculiX holds the tissue against the organs' surfaces, where
// fascia's shared frames hold it: the held nodes' signed distance to their
// organ (positive into the tissue).
static void print_offsets(const fascia_demo_mesh *m) {
  double *d = malloc((size_t)m->node_count * sizeof *d);
  if (!d) return;
  printf("    held nodes' distance to their organ's surface (mm, + into the tissue):");
  for (int32_t o = 0; o < m->organ_count; ++o) {
    int64_t n = 0;
    double sum = 0;
    for (int64_t k = 0; k < m->node_count; ++k)
      if (m->node_organ[k] == o && isfinite(m->node_distance[k])) d[n++] = m->node_distance[k], sum += m->node_distance[k];
    if (n == 0) continue;
    printf(" %s mean %+.3f, p5 %+.3f, p95 %+.3f;", m->organ_name[o], 1e3 * sum / (double)n,
           1e3 * fascia_demo_percentile(d, n, 0.05), 1e3 * fascia_demo_percentile(d, n, 0.95));
  }
  printf("\n");
  free(d);
}

// CalculiX's forces as the stored reference (data/reference/demo-calculix.csv):
// one row per mesh and organ, the reference mesh last.
static int write_reference(const char *path, const char *scene, const ccx_row *cr, int nc, int reference) {
  char tmp[1100];
  snprintf(tmp, sizeof tmp, "%s.tmp", path);
  FILE *f = fopen(tmp, "w");
  if (!f) {
    fprintf(stderr, "demo-calculix: cannot write %s\n", tmp);
    return 0;
  }
  fprintf(f, "# CalculiX on the first tissue of %s (tools/scenes/demo_calculix.h): C3D8I and C3D20R mesh its\n"
             "# voxels as hexahedra held at their organ-facing nodes (-surface: those nodes moved onto the organs'\n"
             "# surfaces), C3D10 meshes the region as tetrahedra held on the organs' smooth surfaces; the held nodes\n"
             "# moved with the organs at time 1, gravity off, static; the tissue's force on each organ (N), the\n"
             "# reference mesh last (demo-calculix --write-reference)\n"
             "mesh,voxel_mm,nodes,elements,organ,fx,fy,fz\n",
          scene);
  for (int j = 0; j < nc; ++j) {
    const int k = j < reference - 1 ? j : j == nc - 1 ? reference - 1 : j + 1;
    for (int32_t o = 0; o < cr[k].mesh.organ_count; ++o)
      fprintf(f, "%s-split%d%s,%g,%lld,%lld,%s,%.7g,%.7g,%.7g\n", mesh_type(cr + k), (int)cr[k].split,
              cr[k].on_surface ? "-surface" : "",
              cr[k].voxel_mm, (long long)cr[k].result.nodes, (long long)cr[k].result.elements, cr[k].mesh.organ_name[o],
              cr[k].result.force[o][0], cr[k].result.force[o][1], cr[k].result.force[o][2]);
  }
  if (fclose(f) != 0 || rename(tmp, path) != 0) {
    fprintf(stderr, "demo-calculix: cannot write %s\n", path);
    remove(tmp);
    return 0;
  }
  return 1;
}

int main(int argc, char **argv) {
  const char *scene = "data/scenes/pelvis-female-demo.json", *ccx_list = "8i:1:1,8i:1:2,20r:1:1",
             *fascia_list = "1:1,1:0.7,1:0.5", *csv_path = NULL,
             *cache = NULL, *reference_path = NULL, *ccx_solver = NULL, *deck_path = NULL;
  int reference = 0, threads = 1, neighbours = 0, slips = 0, mesh_only = 0, linear = 0;
  for (int i = 1; i < argc; ++i) {
    const char *a = argv[i];
    if (!strcmp(a, "--help")) {
      printf("demo-calculix: the demo's tissue against CalculiX, statically\n%s", usage_text);
      return 0;
    }
    if (!strcmp(a, "--ccx") && i + 1 < argc) ccx_list = argv[++i];
    else if (!strcmp(a, "--fascia") && i + 1 < argc) fascia_list = argv[++i];
    else if (!strcmp(a, "--reference") && i + 1 < argc) reference = atoi(argv[++i]);
    else if (!strcmp(a, "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
    else if (!strcmp(a, "--neighbours") && i + 1 < argc) neighbours = atoi(argv[++i]);
    else if (!strcmp(a, "--csv") && i + 1 < argc) csv_path = argv[++i];
    else if (!strcmp(a, "--cache") && i + 1 < argc) cache = argv[++i];
    else if (!strcmp(a, "--slip")) slips = 1;
    else if (!strcmp(a, "--mesh-only")) mesh_only = 1;
    else if (!strcmp(a, "--linear")) linear = 1;
    else if (!strcmp(a, "--deck") && i + 1 < argc) deck_path = argv[++i], mesh_only = 1;
    else if (!strcmp(a, "--ccx-solver") && i + 1 < argc) ccx_solver = argv[++i];
    else if (!strcmp(a, "--write-reference") && i + 1 < argc) reference_path = argv[++i];
    else if (a[0] != '-') scene = a;
    else return usage("unknown argument");
  }
  ccx_row cr[ROWS_MAX];
  fascia_row fr[ROWS_MAX];
  int nc = 0, nf = 0;
  memset(cr, 0, sizeof cr);
  for (const char *p = ccx_list; p && *p;) {
    if (nc == ROWS_MAX) return usage("--ccx: more meshes than 32");
    char type[8], hold[16] = "";
    double vox, size;
    int split;
    double facet = 0;
    if (sscanf(p, "t10:%lf:%lf:%lf", &vox, &size, &facet) >= 2) {
      if (!(vox > 0 && size > 0 && facet >= 0))
        return usage("--ccx: t10:VOXEL_MM:SIZE_MM[:FACET_MM] expects positive sizes");
      cr[nc].tetrahedra = 1, cr[nc].quadratic = 1, cr[nc].voxel_mm = vox, cr[nc].size_mm = size, cr[nc].facet_mm = facet;
      cr[nc].split = 1, cr[nc].on_surface = 1, ++nc;
      p = strchr(p, ',');
      if (p) ++p;
      continue;
    }
    const int fields = sscanf(p, "%7[^:]:%lf:%d:%15[^,]", type, &vox, &split, hold);
    if (fields < 3 || (strcmp(type, "8i") && strcmp(type, "20r")) || (fields == 4 && strcmp(hold, "surface")))
      return usage("--ccx: expected TYPE:VOXEL_MM:SPLIT[:surface] with TYPE 8i or 20r, or t10:VOXEL_MM:SIZE_MM[:FACET_MM]");
    cr[nc].quadratic = !strcmp(type, "20r"), cr[nc].voxel_mm = vox, cr[nc].split = split;
    cr[nc].on_surface = fields == 4, ++nc;
    p = strchr(p, ',');
    if (p) ++p;
  }
  for (const char *p = fascia_list; p && *p;) {
    if (nf == ROWS_MAX) return usage("--fascia: more rungs than 32");
    memset(fr + nf, 0, sizeof fr[nf]);
    fr[nf].sample_scale = 1;
    char tag[40] = "";
    if (sscanf(p, "%lf:%lf:%lf:%39[^,]", &fr[nf].voxel_mm, &fr[nf].scale, &fr[nf].sample_scale, tag) < 2 ||
        (tag[0] && !rung_tag(tag, fr + nf)))
      return usage("--fascia: expected VOXEL_MM:SCALE[:SAMPLE_SCALE[:TAG]], TAG nK, flat, frames, e or eX");
    ++nf;
    p = strchr(p, ',');
    if (p) ++p;
  }
  if (nc == 0) return usage("--ccx: no mesh");
  if (reference == 0) reference = nc;
  if (reference < 1 || reference > nc) return usage("--reference: expected 1 .. the number of meshes");
  const char *ccx = fascia_ccx_program();
  if (!ccx) {
    fprintf(stderr, "demo-calculix: CalculiX (ccx) not found; install calculix-ccx\n");
    return 1;
  }
  fascia_ctx *ctx = NULL;
  const fascia_ctx_def cd = fascia_ctx_def_default();
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  int rc = 0;
  FILE *csv = NULL;
  char csv_tmp[1100] = "";
  if (csv_path) {
    snprintf(csv_tmp, sizeof csv_tmp, "%s.tmp", csv_path);
    csv = fopen(csv_tmp, "w");
    if (!csv) {
      fprintf(stderr, "demo-calculix: cannot write %s\n", csv_tmp);
      return 1;
    }
    fprintf(csv, "code,mesh,voxel_mm,frame_spacing_mm,sample_spacing_mm,nodes,elements,organ,fx,fy,fz,"
                 "force_error_percent,magnitude_error_percent,u_p50_percent,u_p95_percent,u_max_percent,"
                 "u_free_p95_percent,slip_p50_mm,slip_p95_mm,solve_ms\n");
  }
  printf("demo-calculix: %s, its first tissue against CalculiX, gravity off, static at time 1 (ccx on %d thread%s, "
         "fascia on 1)\n",
         scene, threads, threads == 1 ? "" : "s");
  char organs[FASCIA_DEMO_ORGANS_MAX][FASCIA_NAME_SIZE];
  int32_t organ_count = 0;
  double base_frame = 0, base_sample = 0;
  // CalculiX's meshes
  printf("\nCalculiX                        nodes  elements");
  for (int k = 0; k < nc; ++k) {
    fascia_prep_stages s;
    fascia_demo_def d = {scene, cr[k].voxel_mm * 1e-3, 1, 1, neighbours, 0, 0, 0};
    fascia_status st = fascia_demo_prepare(ctx, &d, &s);
    if (st == FASCIA_OK && cr[k].tetrahedra)
      st = fascia_demo_tet_mesh_build(ctx, &s, cr[k].size_mm * 1e-3, cr[k].facet_mm * 1e-3, &cr[k].mesh);
    else if (st == FASCIA_OK)
      st = fascia_demo_mesh_build(ctx, &s, cr[k].quadratic, cr[k].split, cr[k].on_surface, &cr[k].mesh);
    cr[k].mesh.solver = ccx_solver;
    cr[k].mesh.linear = linear;
    if (st == FASCIA_OK && k == 0) {
      base_frame = s.scene->tissues[0].frame_spacing, base_sample = s.scene->tissues[0].sample_spacing;
      organ_count = cr[k].mesh.organ_count;
      for (int32_t o = 0; o < organ_count; ++o) {
        snprintf(organs[o], FASCIA_NAME_SIZE, "%s", cr[k].mesh.organ_name[o]);
        printf("  %9.9s N (|F|)", organs[o]);
      }
      printf("  time s\n");
      fflush(stdout);
      if (linear)
        printf("CalculiX's linear elasticity (*ELASTIC, no NLGEOM): a reference for a small motion only\n");
      else if (!check_one_element(ctx, ccx, cr[k].mesh.youngs_modulus, cr[k].mesh.poisson_ratio))
        rc = 1;
    }
    fascia_prep_stages_free(&s);
    if (st == FASCIA_OK && mesh_only) {
      printf("  %d %s %g mm: %lld nodes, %lld elements (not solved)\n", k + 1, mesh_type(cr + k), cr[k].voxel_mm,
             (long long)cr[k].mesh.node_count, (long long)cr[k].mesh.element_count);
      print_offsets(&cr[k].mesh);
      if (cr[k].tetrahedra) print_tet_quality(&cr[k].mesh);
      fflush(stdout);
      FILE *deck = deck_path ? fopen(deck_path, "w") : NULL;
      if (deck_path && (!deck || fascia_demo_write_deck(ctx, &cr[k].mesh, deck) != FASCIA_OK || fclose(deck) != 0)) {
        fprintf(stderr, "demo-calculix: cannot write the deck %s\n", deck_path);
        rc = 1;
      }
      continue;
    }
    size_t deck_length = 0;
    char *deck = st == FASCIA_OK && cache ? deck_text(ctx, cr + k, &deck_length) : NULL;
    const int cached = st == FASCIA_OK && cache && cache_load(cache, cr + k, deck, deck_length);
    if (st == FASCIA_OK && !cached) st = fascia_demo_calculix(ctx, &cr[k].mesh, ccx, threads, &cr[k].result);
    if (st == FASCIA_OK && cache && !cached) cache_save(cache, cr + k, deck, deck_length);
    free(deck);
    if (st != FASCIA_OK) {
      fprintf(stderr, "demo-calculix: CalculiX mesh %d: %s\n", k + 1, fascia_ctx_message(ctx));
      rc = 1;
      goto done;
    }
    char name[64];
    snprintf(name, sizeof name, "%d %s %g mm%s", k + 1, mesh_type(cr + k), cr[k].voxel_mm,
             cr[k].split > 1 ? " split" : "");
    if (cr[k].split > 1) snprintf(name + strlen(name), sizeof name - strlen(name), " %d", (int)cr[k].split);
    if (cr[k].tetrahedra) snprintf(name + strlen(name), sizeof name - strlen(name), " size %g", cr[k].size_mm);
    if (cr[k].facet_mm > 0) snprintf(name + strlen(name), sizeof name - strlen(name), " facet %g", cr[k].facet_mm);
    if (cr[k].on_surface && !cr[k].tetrahedra) snprintf(name + strlen(name), sizeof name - strlen(name), " surface");
    printf("  %-26s %8lld %9lld", name, (long long)cr[k].result.nodes, (long long)cr[k].result.elements);
    for (int32_t o = 0; o < organ_count; ++o) printf("  %16.5f", norm3(cr[k].result.force[o]));
    printf("  %6.1f%s\n", 1e-3 * cr[k].result.ms, cached ? " (cached)" : "");
    print_offsets(&cr[k].mesh);
    if (cr[k].tetrahedra) print_tet_quality(&cr[k].mesh);
    fflush(stdout);
  }
  if (mesh_only) goto done;
  const fascia_demo_result *ref = &cr[reference - 1].result;
  if (reference_path && !write_reference(reference_path, scene, cr, nc, reference)) rc = 1;
  printf("reference: mesh %d; the errors below are against it (vector error |F - F_ref| / |F_ref|, then the\n"
         "signed error of |F|), CalculiX's own first\n",
         reference);
  for (int k = 0; k < nc; ++k) {
    printf("  mesh %d:", k + 1);
    for (int32_t o = 0; o < organ_count; ++o)
      printf("  %s %+.2f %% (|F| %+.2f %%)", organs[o], 100 * fascia_tissue_error3(cr[k].result.force[o], ref->force[o]),
             100 * (norm3(cr[k].result.force[o]) - norm3(ref->force[o])) / norm3(ref->force[o]));
    printf("\n");
    if (csv)
      for (int32_t o = 0; o < organ_count; ++o)
        fprintf(csv, "calculix,%s%s%d,%g,,,%lld,%lld,%s,%.6g,%.6g,%.6g,%.4f,%.4f,,,,,,,%.0f\n",
                mesh_type(cr + k), "-split", (int)cr[k].split, cr[k].voxel_mm,
                (long long)cr[k].result.nodes, (long long)cr[k].result.elements, organs[o], cr[k].result.force[o][0],
                cr[k].result.force[o][1], cr[k].result.force[o][2],
                100 * fascia_tissue_error3(cr[k].result.force[o], ref->force[o]),
                100 * (norm3(cr[k].result.force[o]) - norm3(ref->force[o])) / norm3(ref->force[o]), cr[k].result.ms);
  }
  // fascia's rungs
  printf("\nfascia (tag: nK neighbours, flat: no patches; voxel, frame and sample spacing in mm)\ntag   voxel frame  sample  frames samples");
  for (int32_t o = 0; o < organ_count; ++o) printf("  %9.9s N  err %%  |F| %%", organs[o]);
  printf("  u err %% of max: p50   p95   max  free p95  slip mm: p50  p95  solve ms\n");
  for (int k = 0; k < nf; ++k) {
    // displacements at the nodes of the last CalculiX mesh of this voxel size
    const ccx_row *at = NULL;
    for (int c = 0; c < nc; ++c)
      if (fabs(cr[c].voxel_mm - fr[k].voxel_mm) < 1e-9) at = cr + c;
    fascia_prep_stages s;
    fascia_demo_def d = {scene, fr[k].voxel_mm * 1e-3, fr[k].scale, fr[k].sample_scale,
                         fr[k].neighbours ? fr[k].neighbours : neighbours, fr[k].no_patches, fr[k].attachment,
                         fr[k].layer_scale};
    fascia_demo_result r;
    memset(&r, 0, sizeof r);
    fascia_status st = fascia_demo_prepare(ctx, &d, &s);
    if (st == FASCIA_OK) st = fascia_demo_fascia(ctx, &s, at ? &at->mesh : NULL, &r);
    if (st != FASCIA_OK) {
      fprintf(stderr, "demo-calculix: fascia rung %d: %s\n", k + 1, fascia_ctx_message(ctx));
      fascia_prep_stages_free(&s);
      rc = 1;
      continue;
    }
    const double frame = base_frame * fr[k].scale, sample = base_sample * fr[k].scale * fr[k].sample_scale;
    char tag[40] = "";
    if (fr[k].layer_scale > 0) snprintf(tag, sizeof tag, "e%g", fr[k].layer_scale);
    else if (fr[k].attachment) snprintf(tag, sizeof tag, fr[k].attachment == 1 ? "frames" : "e");
    if (fr[k].no_patches) snprintf(tag + strlen(tag), sizeof tag - strlen(tag), "%sflat", tag[0] ? "+" : "");
    if (fr[k].neighbours)
      snprintf(tag + strlen(tag), sizeof tag - strlen(tag), "%sn%d", tag[0] ? "+" : "", (int)fr[k].neighbours);
    printf("%-5s %5.2f %5.2f  %5.3f  %6lld %7lld", tag, fr[k].voxel_mm, 1e3 * frame, 1e3 * sample, (long long)r.nodes,
           (long long)r.elements);
    for (int32_t o = 0; o < organ_count; ++o)
      printf("  %11.5f %+6.2f %+6.2f", norm3(r.force[o]), 100 * fascia_tissue_error3(r.force[o], ref->force[o]),
             100 * (norm3(r.force[o]) - norm3(ref->force[o])) / norm3(ref->force[o]));
    double pct[3] = {NAN, NAN, NAN}, slip[2] = {NAN, NAN}, free95 = NAN, largest = 0;
    if (at) {
      const fascia_demo_mesh *m = &at->mesh;
      double *err = malloc((size_t)m->node_count * sizeof *err), *sl = malloc((size_t)m->node_count * sizeof *sl);
      double *fe = malloc((size_t)m->node_count * sizeof *fe);
      int64_t ns = 0, nfree = 0;
      for (int64_t q = 0; q < m->node_count && err && sl; ++q) {
        const double *uc = at->result.u + 3 * q, *uf = r.u + 3 * q;
        largest = fmax(largest, norm3(uc));
        const double e[3] = {uf[0] - uc[0], uf[1] - uc[1], uf[2] - uc[2]};
        err[q] = norm3(e);
        if (m->node_organ[q] < 0 && fe) fe[nfree++] = err[q];
        if (m->node_organ[q] >= 0) {
          const double *up = m->node_u + 3 * q;
          const double de[3] = {uf[0] - up[0], uf[1] - up[1], uf[2] - up[2]};
          sl[ns++] = norm3(de);
        }
      }
      if (err && sl && largest > 0) {
        pct[0] = 100 * fascia_demo_percentile(err, m->node_count, 0.5) / largest;
        pct[1] = 100 * fascia_demo_percentile(err, m->node_count, 0.95) / largest;
        pct[2] = 100 * fascia_demo_percentile(err, m->node_count, 1.0) / largest;
        slip[0] = 1e3 * fascia_demo_percentile(sl, ns, 0.5), slip[1] = 1e3 * fascia_demo_percentile(sl, ns, 0.95);
        if (fe) free95 = 100 * fascia_demo_percentile(fe, nfree, 0.95) / largest;
      }
      free(err), free(sl), free(fe);
    }
    printf("  %20.1f %5.1f %5.1f %9.1f  %11.3f %4.3f  %8.0f\n", pct[0], pct[1], pct[2], free95, slip[0], slip[1],
           r.ms);
    if (at && slips) {
      print_slip(&s, at, &r);
      if (at->mesh.tetrahedra) print_volume_bands(&s, &at->mesh);
    }
    fascia_prep_stages_free(&s);
    if (at && k == 0) printf("  (displacements at the nodes of CalculiX's last %g mm mesh, its largest %.4f mm)\n", fr[k].voxel_mm, 1e3 * largest);
    fflush(stdout);
    if (csv)
      for (int32_t o = 0; o < organ_count; ++o)
        fprintf(csv, "fascia%s%s,x%g,%g,%.4g,%.4g,%lld,%lld,%s,%.6g,%.6g,%.6g,%.4f,%.4f,%.3f,%.3f,%.3f,%.3f,%.4f,%.4f,%.1f\n",
                tag[0] ? "-" : "", tag, fr[k].scale, fr[k].voxel_mm, 1e3 * frame, 1e3 * sample, (long long)r.nodes, (long long)r.elements,
                organs[o], r.force[o][0], r.force[o][1], r.force[o][2],
                100 * fascia_tissue_error3(r.force[o], ref->force[o]),
                100 * (norm3(r.force[o]) - norm3(ref->force[o])) / norm3(ref->force[o]), pct[0], pct[1], pct[2],
                free95, slip[0], slip[1], r.ms);
    fascia_demo_result_free(&r);
  }
done:
  for (int k = 0; k < nc; ++k) fascia_demo_mesh_free(&cr[k].mesh), fascia_demo_result_free(&cr[k].result);
  if (csv && (fclose(csv) != 0 || rc != 0 || rename(csv_tmp, csv_path) != 0)) {
    if (rc == 0) fprintf(stderr, "demo-calculix: cannot write %s\n", csv_path);
    remove(csv_tmp);
    rc = 1;
  }
  fascia_ctx_destroy(&ctx);
  return rc;
}
