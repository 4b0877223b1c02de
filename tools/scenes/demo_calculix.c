// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A prepared scene's volume tissue against CalculiX (demo_calculix.h): the
// scene prepared with gravity off, the region's voxels as hexahedra with
// the organs' faces moved rigidly, the two static solves and fascia's
// displacement at CalculiX's nodes.
#define _POSIX_C_SOURCE 200809L // open_memstream
#include "demo_calculix.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "beam_calculix.h"
#include "fascia/organs.h"
#include "fascia/shape.h"
#include "scene_util.h"
#include "tissue_calculix.h"

// ------------------------------------------------------------ preparing

fascia_status fascia_demo_prepare(fascia_ctx *ctx, const fascia_demo_def *def, fascia_prep_stages *s) {
  memset(s, 0, sizeof *s);
  SCENE_CHECK(def && def->scene, ctx, FASCIA_ERR_ARGUMENT, "demo against CalculiX: no scene file");
  SCENE_TRY(fascia_prep_scene_load(ctx, def->scene, &s->scene));
  fascia_prep_scene *sc = s->scene;
  SCENE_CHECK(sc->tissue_count >= 1 && sc->tissues[0].form == FASCIA_PREP_FORM_VOLUME, ctx, FASCIA_ERR_ARGUMENT,
              "scene '%s': its first tissue is not a volume (the CalculiX comparison meshes a volume tissue)",
              def->scene);
  SCENE_CHECK(sc->organ_count <= FASCIA_DEMO_ORGANS_MAX, ctx, FASCIA_ERR_ARGUMENT,
              "scene '%s': %d organs, at most %d compared", def->scene, (int)sc->organ_count, FASCIA_DEMO_ORGANS_MAX);
  for (int a = 0; a < 3; ++a) sc->gravity[a] = 0;
  if (def->voxel_size > 0) sc->voxel_size = def->voxel_size;
  fascia_prep_tissue_def *td = sc->tissues;
  const double scale = def->spacing_scale > 0 ? def->spacing_scale : 1;
  td->frame_spacing *= scale;
  td->sample_spacing *= scale * (def->sample_scale > 0 ? def->sample_scale : 1);
  if (def->neighbours > 0) td->neighbours = def->neighbours;
  if (def->no_patches) td->patch_radius = 0;
  if (def->attachment > 0) td->attachment = def->attachment - 1;
  if (def->layer_scale > 0) td->attachment_layer = def->layer_scale * td->sample_spacing;
  SCENE_TRY(fascia_prep_import(ctx, sc, &s->meshes));
  SCENE_TRY(fascia_prep_repair(ctx, sc, s->meshes));
  SCENE_TRY(fascia_prep_voxelize(ctx, sc, s->meshes, &s->volume));
  SCENE_TRY(fascia_prep_sample(ctx, sc, s->meshes, s->volume, &s->points));
  SCENE_TRY(fascia_prep_shape_functions(ctx, sc, s->volume, s->points, &s->weights));
  SCENE_TRY(fascia_prep_couple(ctx, sc, s->meshes, s->points, &s->coupling));
  return fascia_prep_package(ctx, sc, s->meshes, s->volume, s->points, s->weights, s->coupling, NULL, &s->model);
}

// ------------------------------------------------------------ the mesh

// Rotation matrix (row-major) of the unit quaternion q (w, x, y, z).
static void quat_matrix(const double q[4], double R[9]) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  R[0] = 1 - 2 * (y * y + z * z), R[1] = 2 * (x * y - w * z), R[2] = 2 * (x * z + w * y);
  R[3] = 2 * (x * y + w * z), R[4] = 1 - 2 * (x * x + z * z), R[5] = 2 * (y * z - w * x);
  R[6] = 2 * (x * z - w * y), R[7] = 2 * (y * z + w * x), R[8] = 1 - 2 * (x * x + y * y);
}

// Each organ's pose at time 1 as p -> R p + t (scene order).
static fascia_status organ_poses(fascia_ctx *ctx, const fascia_prep_stages *s, double (*R)[9], double (*t)[3]) {
  fascia_solver_def def = fascia_solver_def_default();
  def.backend = "cpu";
  def.threads = 1;
  fascia_solver *solver = NULL;
  fascia_status status = FASCIA_OK;
  SCENE_TRY_GOTO(fascia_solver_create(ctx, s->model, &def, &solver));
  SCENE_TRY_GOTO(fascia_solver_set_time(solver, 1));
  for (int32_t o = 0; o < s->scene->organ_count; ++o) {
    const int32_t k = fascia_model_find_organ(s->model, s->scene->organs[o].name);
    SCENE_CHECK_GOTO(k >= 0, ctx, FASCIA_ERR_INTERNAL, "the model lacks organ '%s'", s->scene->organs[o].name);
    fascia_real tr[3], q[4];
    SCENE_TRY_GOTO(fascia_solver_organ_pose(solver, k, tr, q));
    const double qd[4] = {q[0], q[1], q[2], q[3]};
    quat_matrix(qd, R[o]);
    for (int a = 0; a < 3; ++a) t[o][a] = tr[a];
  }
cleanup:
  fascia_solver_destroy(&solver);
  return status;
}

// Local lattice offsets (in element units 0, 1/2, 1) of the nodes of C3D8I
// and C3D20R, ccx's order: corners, then the mid-edges of the bottom, the
// top and the vertical edges.
static const double node_offset[20][3] = {
    {0, 0, 0},   {1, 0, 0},   {1, 1, 0},   {0, 1, 0},   {0, 0, 1},   {1, 0, 1},   {1, 1, 1},
    {0, 1, 1},   {.5, 0, 0},  {1, .5, 0},  {.5, 1, 0},  {0, .5, 0},  {.5, 0, 1},  {1, .5, 1},
    {.5, 1, 1},  {0, .5, 1},  {0, 0, .5},  {1, 0, .5},  {1, 1, .5},  {0, 1, .5}};

void fascia_demo_mesh_free(fascia_demo_mesh *m) {
  if (!m) return;
  free(m->node), free(m->node_organ), free(m->node_u), free(m->node_distance), free(m->element);
  memset(m, 0, sizeof *m);
}

// 1 when voxel w (a grid index, or -1 off the grid) lies inside organ o.
static int inside(const fascia_prep_volume *v, int32_t o, int64_t w) {
  return w >= 0 && v->distance[o] && v->distance[o][w] <= 0;
}

// Organ o's signed distance at x, trilinear between the voxel centres.
static double organ_distance(const fascia_prep_volume *v, int32_t o, const double x[3]) {
  if (!v->distance[o]) return NAN;
  double f[3];
  int32_t c[3];
  for (int a = 0; a < 3; ++a) {
    const double t = (x[a] - v->origin[a]) / v->voxel_size;
    c[a] = (int32_t)floor(t), f[a] = t - c[a];
    if (c[a] < 0 || c[a] + 1 >= v->dims[a]) return NAN;
  }
  double d = 0;
  for (int q = 0; q < 8; ++q) {
    const int32_t i = c[0] + (q & 1), j = c[1] + ((q >> 1) & 1), k = c[2] + ((q >> 2) & 1);
    const double w = ((q & 1) ? f[0] : 1 - f[0]) * (((q >> 1) & 1) ? f[1] : 1 - f[1]) * (((q >> 2) & 1) ? f[2] : 1 - f[2]);
    d += w * v->distance[o][i + (int64_t)v->dims[0] * (j + (int64_t)v->dims[1] * k)];
  }
  return d;
}

// Moves x onto organ o's surface along the distance field's gradient (three
// Newton steps on the signed distance): a held node on the smooth surface
// the organ's mesh has, where fascia's shared frames hold the tissue, not
// on the voxel faces' staircase.
static void onto_surface(const fascia_prep_volume *v, int32_t o, double x[3]) {
  const double step = 0.25 * v->voxel_size;
  for (int it = 0; it < 3; ++it) {
    const double d = organ_distance(v, o, x);
    double g[3], g2 = 0;
    for (int a = 0; a < 3; ++a) {
      double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
      xp[a] += step, xm[a] -= step;
      g[a] = (organ_distance(v, o, xp) - organ_distance(v, o, xm)) / (2 * step);
      g2 += g[a] * g[a];
    }
    if (!(g2 > 0) || !isfinite(d)) return;
    for (int a = 0; a < 3; ++a) x[a] -= d * g[a] / g2;
  }
}

fascia_status fascia_demo_mesh_build(fascia_ctx *ctx, const fascia_prep_stages *s, int quadratic,
                                     int32_t subdivide, int on_surface, fascia_demo_mesh *out) {
  memset(out, 0, sizeof *out);
  SCENE_CHECK(subdivide >= 1 && subdivide <= 4, ctx, FASCIA_ERR_ARGUMENT,
              "demo mesh: %d elements per voxel edge, expected 1 .. 4", (int)subdivide);
  const fascia_prep_scene *sc = s->scene;
  const fascia_prep_volume *v = s->volume;
  const fascia_material *mat = sc->materials + sc->tissues[0].material;
  SCENE_CHECK(mat->law == FASCIA_LAW_NEOHOOKEAN, ctx, FASCIA_ERR_ARGUMENT,
              "demo mesh: tissue '%s' is not of the stable Neo-Hookean law (the *HYPERFOAM card writes that law)",
              sc->tissues[0].name);
  out->quadratic = quadratic, out->subdivide = subdivide;
  out->youngs_modulus = mat->youngs_modulus, out->poisson_ratio = mat->poisson_ratio;
  out->organ_count = sc->organ_count;
  for (int32_t o = 0; o < sc->organ_count; ++o)
    snprintf(out->organ_name[o], FASCIA_NAME_SIZE, "%s", sc->organs[o].name);
  double R[FASCIA_DEMO_ORGANS_MAX][9], T[FASCIA_DEMO_ORGANS_MAX][3];
  SCENE_TRY(organ_poses(ctx, s, R, T));

  // the region's bounds, and a lattice of r points per voxel edge over them
  const int32_t *dims = v->dims;
  int32_t lo[3] = {dims[0], dims[1], dims[2]}, hi[3] = {-1, -1, -1};
  int64_t voxels = 0;
  const int64_t n = (int64_t)dims[0] * dims[1] * dims[2];
  for (int64_t w = 0; w < n; ++w) {
    if (v->region[w] != 1) continue;
    const int32_t c[3] = {(int32_t)(w % dims[0]), (int32_t)((w / dims[0]) % dims[1]),
                          (int32_t)(w / ((int64_t)dims[0] * dims[1]))};
    for (int a = 0; a < 3; ++a) lo[a] = c[a] < lo[a] ? c[a] : lo[a], hi[a] = c[a] > hi[a] ? c[a] : hi[a];
    ++voxels;
  }
  SCENE_CHECK(voxels > 0, ctx, FASCIA_ERR_ARGUMENT, "demo mesh: tissue '%s' has no voxel", sc->tissues[0].name);
  const int32_t r = subdivide * (quadratic ? 2 : 1), per = quadratic ? 20 : 8;
  int64_t ld[3];
  for (int a = 0; a < 3; ++a) ld[a] = (int64_t)r * (hi[a] - lo[a] + 1) + 1;
  const int64_t lattice = ld[0] * ld[1] * ld[2];
  int32_t *id = malloc((size_t)lattice * sizeof *id);
  int32_t *organ = malloc((size_t)lattice * sizeof *organ);
  out->element_count = voxels * subdivide * subdivide * subdivide;
  out->element = malloc((size_t)(out->element_count * per) * sizeof *out->element);
  fascia_status status = FASCIA_OK;
  if (!id || !organ || !out->element) {
    status = SCENE_FAIL(ctx, FASCIA_ERR_MEMORY, "demo mesh: out of memory (%lld lattice points)", (long long)lattice);
    goto cleanup;
  }
  for (int64_t k = 0; k < lattice; ++k) id[k] = -1, organ[k] = -1;
#define LAT(i, j, k) ((int64_t)(i) + ld[0] * ((int64_t)(j) + ld[1] * (int64_t)(k)))
  // elements, their nodes marked (id 0 until numbered), and the organs' faces
  int64_t e = 0;
  for (int64_t w = 0; w < n; ++w) {
    if (v->region[w] != 1) continue;
    const int32_t c[3] = {(int32_t)(w % dims[0]), (int32_t)((w / dims[0]) % dims[1]),
                          (int32_t)(w / ((int64_t)dims[0] * dims[1]))};
    const int64_t base[3] = {(int64_t)r * (c[0] - lo[0]), (int64_t)r * (c[1] - lo[1]), (int64_t)r * (c[2] - lo[2])};
    const int32_t step = quadratic ? 2 : 1;
    for (int32_t sz = 0; sz < subdivide; ++sz)
      for (int32_t sy = 0; sy < subdivide; ++sy)
        for (int32_t sx = 0; sx < subdivide; ++sx, ++e)
          for (int q = 0; q < per; ++q) {
            const int64_t p = LAT(base[0] + step * sx + (int64_t)(step * node_offset[q][0]),
                                  base[1] + step * sy + (int64_t)(step * node_offset[q][1]),
                                  base[2] + step * sz + (int64_t)(step * node_offset[q][2]));
            id[p] = 0;
            out->element[e * per + q] = (int32_t)p; // a lattice index until numbered
          }
    for (int a = 0; a < 3; ++a)
      for (int side = 0; side < 2; ++side) {
        int32_t d[3] = {c[0], c[1], c[2]};
        d[a] += side ? 1 : -1;
        const int64_t nb = d[a] < 0 || d[a] >= dims[a] ? -1 : d[0] + (int64_t)dims[0] * (d[1] + (int64_t)dims[1] * d[2]);
        if (nb >= 0 && v->region[nb] == 1) continue;
        int32_t o = 0;
        while (o < v->organ_count && !inside(v, o, nb)) ++o;
        if (o == v->organ_count) continue; // a free face
        const int b = (a + 1) % 3, cc = (a + 2) % 3;
        for (int32_t i = 0; i <= r; ++i)
          for (int32_t j = 0; j <= r; ++j) {
            int64_t at[3];
            at[a] = base[a] + (side ? r : 0), at[b] = base[b] + i, at[cc] = base[cc] + j;
            const int64_t p = LAT(at[0], at[1], at[2]);
            if (organ[p] < 0) organ[p] = o;
          }
      }
  }
  // number the nodes in lattice order
  int64_t count = 0;
  for (int64_t p = 0; p < lattice; ++p)
    if (id[p] == 0) id[p] = (int32_t)count++;
  out->node_count = count;
  out->node = malloc((size_t)(3 * count) * sizeof *out->node);
  out->node_u = calloc((size_t)(3 * count), sizeof *out->node_u);
  out->node_organ = malloc((size_t)count * sizeof *out->node_organ);
  out->node_distance = malloc((size_t)count * sizeof *out->node_distance);
  if (!out->node || !out->node_u || !out->node_organ || !out->node_distance) {
    status = SCENE_FAIL(ctx, FASCIA_ERR_MEMORY, "demo mesh: out of memory (%lld nodes)", (long long)count);
    goto cleanup;
  }
  const double h = v->voxel_size / r;
  for (int64_t p = 0; p < lattice; ++p) {
    if (id[p] < 0) continue;
    const int64_t k = id[p], ijk[3] = {p % ld[0], (p / ld[0]) % ld[1], p / (ld[0] * ld[1])};
    double *x = out->node + 3 * k;
    for (int a = 0; a < 3; ++a) x[a] = v->origin[a] + v->voxel_size * (lo[a] - 0.5) + h * (double)ijk[a];
    const int32_t o = organ[p];
    out->node_organ[k] = o;
    if (o >= 0 && on_surface) onto_surface(v, o, x);
    out->node_distance[k] = o >= 0 ? organ_distance(v, o, x) : NAN;
    if (o < 0) continue;
    for (int a = 0; a < 3; ++a)
      out->node_u[3 * k + a] = R[o][3 * a] * x[0] + R[o][3 * a + 1] * x[1] + R[o][3 * a + 2] * x[2] + T[o][a] - x[a];
  }
  for (int64_t q = 0; q < out->element_count * per; ++q) out->element[q] = id[out->element[q]];
#undef LAT
cleanup:
  free(id);
  free(organ);
  if (status != FASCIA_OK) fascia_demo_mesh_free(out);
  return status;
}

// ------------------------------------------------------------ CalculiX

// The stable Neo-Hookean, psi = mu/2 (I1 - 3) + l/2 (J - a)^2 - mu^2/(2 l),
// l = lambda + mu, a = 1 + mu/l, as ccx's hyperfoam
// U = sum_i 2 mu_i/alpha_i^2 [sum_k lambda_k^alpha_i - 3 + (J^(-alpha_i beta_i) - 1)/beta_i],
// beta_i = nu_i/(1 - 2 nu_i): term 1 (alpha 2, beta -1) gives mu/2 (I1 - 3)
// - mu/2 (J^2 - 1); terms 2 and 3 (alpha -1, mu_2 = -mu_3, so their stretch
// sums cancel; beta 2 and 1) give (l + mu)/2 J^2 - (l + mu) J and the
// constant, so the sum is psi exactly.
static void write_material(FILE *out, double E, double nu) {
  const double mu = E / (2 * (1 + nu)), lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), l = lambda + mu;
  fprintf(out,
          "** the stable Neo-Hookean (E %.13g Pa, nu %.13g) written exactly as a hyperfoam\n"
          "*MATERIAL, NAME=TISSUE\n*HYPERFOAM, N=3\n%.15g, 2., %.15g, -1., %.15g, -1., 1., 0.4\n%.15g\n",
          E, nu, mu, (l + mu) / 2, -(l + mu) / 2, 1.0 / 3.0);
}

static void write_step(FILE *out, const char *solver) {
  // a quarter of the load first (the whole load at once diverges on the
  // demo); residuals 500 times below ccx's default, for forces to 1e-4
  fprintf(out, "*STEP, NLGEOM, INC=1000\n*STATIC%s%s\n0.25, 1.0, 1e-5, 0.5\n", solver ? ", SOLVER=" : "",
          solver ? solver : "");
  fprintf(out, "*CONTROLS, PARAMETERS=FIELD\n1e-5, 1e-5, 0., -1., 0.02, 1e-5, 1e-3, 1e-8\n");
}

fascia_status fascia_demo_write_deck(fascia_ctx *ctx, const void *arg, FILE *out) {
  const fascia_demo_mesh *m = arg;
  SCENE_CHECK(m && m->node_count > 0 && m->element_count > 0, ctx, FASCIA_ERR_ARGUMENT, "demo deck: an empty mesh");
  const int per = m->quadratic ? 20 : 8;
  fprintf(out,
          "** a scene's tissue region as voxels (tools/scenes/demo_calculix.c): %lld %s elements, %lld nodes;\n"
          "** the nodes on faces bordering an organ moved with its pose at time 1, gravity off, static\n"
          "*HEADING\nfascia demo tissue against CalculiX\n*NODE, NSET=NALL\n",
          (long long)m->element_count, m->quadratic ? "C3D20R" : "C3D8I", (long long)m->node_count);
  for (int64_t k = 0; k < m->node_count; ++k)
    fprintf(out, "%lld, %.15g, %.15g, %.15g\n", (long long)k + 1, m->node[3 * k], m->node[3 * k + 1],
            m->node[3 * k + 2]);
  fprintf(out, "*ELEMENT, TYPE=%s, ELSET=EALL\n", m->quadratic ? "C3D20R" : "C3D8I");
  for (int64_t e = 0; e < m->element_count; ++e) {
    fprintf(out, "%lld", (long long)e + 1);
    for (int q = 0; q < per; ++q) fprintf(out, q == 15 ? ",\n%d" : ", %d", (int)m->element[e * per + q] + 1);
    fputc('\n', out);
  }
  for (int32_t o = 0; o < m->organ_count; ++o) {
    fprintf(out, "** the nodes on organ '%s'\n*NSET, NSET=NORGAN%d\n", m->organ_name[o], (int)o);
    int any = 0;
    for (int64_t k = 0; k < m->node_count; ++k)
      if (m->node_organ[k] == o) fprintf(out, "%lld,\n", (long long)k + 1), any = 1;
    if (!any) fprintf(out, "** none\n");
  }
  write_material(out, m->youngs_modulus, m->poisson_ratio);
  fprintf(out, "*SOLID SECTION, ELSET=EALL, MATERIAL=TISSUE\n");
  write_step(out, m->solver);
  fprintf(out, "*BOUNDARY\n");
  for (int64_t k = 0; k < m->node_count; ++k) {
    if (m->node_organ[k] < 0) continue;
    const double *u = m->node_u + 3 * k;
    if (u[0] == 0 && u[1] == 0 && u[2] == 0) fprintf(out, "%lld, 1, 3\n", (long long)k + 1);
    else
      for (int a = 0; a < 3; ++a) fprintf(out, "%lld, %d, %d, %.15g\n", (long long)k + 1, a + 1, a + 1, u[a]);
  }
  for (int32_t o = 0; o < m->organ_count; ++o)
    fprintf(out, "*NODE PRINT, NSET=NORGAN%d, TOTALS=ONLY\nRF\n", (int)o);
  fprintf(out, "*NODE PRINT, NSET=NALL, FREQUENCY=10000\nU\n*END STEP\n");
  return fascia_ccx_deck_written(ctx, out);
}

// A number of a .dat line at *p, Fortran's way: an exponent of three digits
// comes without its E ("1.234567-100"); *p moves past it. 0 when none.
static int dat_number(const char **p, double *v) {
  char *end;
  *v = strtod(*p, &end);
  if (end == *p) return 0;
  if ((*end == '-' || *end == '+') && end[1] >= '0' && end[1] <= '9') {
    char *e2;
    const long exponent = strtol(end, &e2, 10);
    *v *= pow(10.0, (double)exponent);
    end = e2;
  }
  *p = end;
  return 1;
}

// "node v1 v2 v3" at the start of a .dat line: 4 when read.
static int dat_line(const char *p, long long *node, double v[3]) {
  char *end;
  *node = strtoll(p, &end, 10);
  if (end == p) return 0;
  p = end;
  for (int a = 0; a < 3; ++a)
    if (!dat_number(&p, v + a)) return a + 1;
  return 4;
}

void fascia_demo_result_free(fascia_demo_result *r) {
  if (!r) return;
  free(r->u);
  r->u = NULL;
  for (int o = 0; o < FASCIA_DEMO_ORGANS_MAX; ++o) {
    free(r->surface_slip[o]), free(r->surface_distance[o]);
    r->surface_slip[o] = r->surface_distance[o] = NULL, r->surface_count[o] = 0;
  }
}

fascia_status fascia_demo_calculix(fascia_ctx *ctx, const fascia_demo_mesh *m, const char *program, int threads,
                                   fascia_demo_result *out) {
  memset(out, 0, sizeof *out);
  char *dat = NULL;
  SCENE_TRY(fascia_ccx_run_timed(ctx, "demo tissue", fascia_demo_write_deck, m, program, threads, &dat, &out->ms));
  out->nodes = m->node_count, out->elements = m->element_count, out->organ_count = m->organ_count;
  fascia_status status = FASCIA_OK;
  for (int32_t o = 0; o < m->organ_count; ++o) {
    char header[64];
    snprintf(header, sizeof header, "total force (fx,fy,fz) for set NORGAN%d", (int)o);
    double rf[3] = {0, 0, 0};
    const char *p = fascia_ccx_dat_after(dat, header);
    if (p && !fascia_ccx_dat_triple(p, rf)) p = NULL;
    // ccx prints no reaction of an empty set: the organ bears nothing
    for (int a = 0; a < 3; ++a) out->force[o][a] = -rf[a]; // the support's force on the tissue, reversed
  }
  out->u = malloc((size_t)(3 * m->node_count) * sizeof *out->u);
  const char *p = fascia_ccx_dat_after(dat, "displacements (vx,vy,vz) for set NALL");
  if (!out->u || !p) {
    status = SCENE_FAIL(ctx, out->u ? FASCIA_ERR_FORMAT : FASCIA_ERR_MEMORY,
                        "CalculiX demo tissue: its output lacks the nodes' displacements");
    goto cleanup;
  }
  for (int64_t k = 0; k < 3 * m->node_count; ++k) out->u[k] = NAN;
  while (p && *p) {
    long long node;
    double v[3];
    const int n = dat_line(p, &node, v);
    if (n == 4) {
      if (node >= 1 && node <= m->node_count) memcpy(out->u + 3 * (node - 1), v, sizeof v);
    } else if (p[strspn(p, " \t\r")] != '\n') {
      break;
    }
    p = strchr(p, '\n');
    if (p) ++p;
  }
  int64_t missing = 0;
  for (int64_t k = 0; k < m->node_count; ++k)
    missing += !(isfinite(out->u[3 * k]) && isfinite(out->u[3 * k + 1]) && isfinite(out->u[3 * k + 2]));
  SCENE_CHECK_GOTO(missing == 0, ctx, FASCIA_ERR_FORMAT,
                   "CalculiX demo tissue: %lld of %lld nodes lack a finite displacement in its output",
                   (long long)missing, (long long)m->node_count);
cleanup:
  free(dat);
  if (status != FASCIA_OK) fascia_demo_result_free(out);
  return status;
}

// One cube, every node moved by (F - I) X.
typedef struct one_element {
  double E, nu, F[9];
} one_element;

static fascia_status write_one_element(fascia_ctx *ctx, const void *arg, FILE *out) {
  const one_element *d = arg;
  fprintf(out, "** one C3D8I cube under a homogeneous F (tools/scenes/demo_calculix.c)\n*NODE, NSET=NALL\n");
  for (int q = 0; q < 8; ++q)
    fprintf(out, "%d, %g, %g, %g\n", q + 1, node_offset[q][0], node_offset[q][1], node_offset[q][2]);
  fprintf(out, "*ELEMENT, TYPE=C3D8I, ELSET=EALL\n1, 1, 2, 3, 4, 5, 6, 7, 8\n"
               "*NSET, NSET=NX\n2, 3, 6, 7\n*NSET, NSET=NY\n3, 4, 7, 8\n*NSET, NSET=NZ\n5, 6, 7, 8\n");
  write_material(out, d->E, d->nu);
  fprintf(out, "*SOLID SECTION, ELSET=EALL, MATERIAL=TISSUE\n");
  write_step(out, NULL);
  fprintf(out, "*BOUNDARY\n");
  for (int q = 0; q < 8; ++q)
    for (int a = 0; a < 3; ++a) {
      const double *X = node_offset[q];
      const double u = d->F[3 * a] * X[0] + d->F[3 * a + 1] * X[1] + d->F[3 * a + 2] * X[2] - X[a];
      fprintf(out, "%d, %d, %d, %.15g\n", q + 1, a + 1, a + 1, u);
    }
  fprintf(out, "*NODE PRINT, NSET=NX, TOTALS=ONLY\nRF\n*NODE PRINT, NSET=NY, TOTALS=ONLY\nRF\n"
               "*NODE PRINT, NSET=NZ, TOTALS=ONLY\nRF\n*END STEP\n");
  return fascia_ccx_deck_written(ctx, out);
}

fascia_status fascia_demo_one_element(fascia_ctx *ctx, const char *program, double E, double nu, const double F[9],
                                      double P[9]) {
  one_element d = {E, nu, {0}};
  memcpy(d.F, F, sizeof d.F);
  char *dat = NULL;
  double cpu_ms = 0;
  SCENE_TRY(fascia_ccx_run_deck(ctx, "one element", write_one_element, &d, program, 1, &dat, &cpu_ms));
  int ok = 1;
  for (int c = 0; c < 3 && ok; ++c) {
    char header[64];
    snprintf(header, sizeof header, "total force (fx,fy,fz) for set N%c", "XYZ"[c]);
    double f[3];
    ok = fascia_ccx_dat_triple(fascia_ccx_dat_after(dat, header), f);
    // the reactions on face X_c = 1 of a unit cube sum to P e_c
    for (int r = 0; r < 3 && ok; ++r) P[3 * r + c] = f[r];
  }
  free(dat);
  SCENE_CHECK(ok, ctx, FASCIA_ERR_FORMAT, "CalculiX one element: its output lacks a face's reaction");
  return FASCIA_OK;
}

// ------------------------------------------------------------ fascia

fascia_status fascia_demo_displacement_at(fascia_ctx *ctx, const fascia_model *m, const fascia_solver *solver,
                                          int64_t n, const double *points, double *u) {
  fascia_frame_grid *grid = NULL;
  SCENE_TRY(fascia_frame_grid_create(ctx, m->sample_count, m->sample_position, &grid));
  const fascia_real *x = fascia_solver_frame_positions(solver), *q = fascia_solver_frame_rotations(solver);
  fascia_status status = FASCIA_OK;
  for (int64_t k = 0; k < n; ++k) {
    const fascia_real p[3] = {points[3 * k], points[3 * k + 1], points[3 * k + 2]};
    int32_t s;
    fascia_real radius;
    SCENE_TRY_GOTO(fascia_frame_grid_nearest(ctx, grid, p, 1, &s, &radius));
    const fascia_real *ps = m->sample_position + 3 * s;
    double phi[3] = {0, 0, 0}, F[9] = {0};
    for (int32_t e = m->sample_offsets[s]; e < m->sample_offsets[s + 1]; ++e) {
      const int32_t i = m->pair_frame[e];
      const double w = m->pair_weight[e], *g = NULL;
      double gd[3];
      for (int a = 0; a < 3; ++a) gd[a] = m->pair_gradient[3 * e + a];
      g = gd;
      double qi[4], qr[4], Ri[9], Rr[9], A[9];
      for (int a = 0; a < 4; ++a) qi[a] = q[4 * i + a], qr[a] = m->frame_rotation[4 * i + a];
      quat_matrix(qi, Ri);
      quat_matrix(qr, Rr);
      for (int r = 0; r < 3; ++r) // A = R R_rest^T
        for (int c = 0; c < 3; ++c)
          A[3 * r + c] = Ri[3 * r] * Rr[3 * c] + Ri[3 * r + 1] * Rr[3 * c + 1] + Ri[3 * r + 2] * Rr[3 * c + 2];
      double d[3], y[3];
      for (int a = 0; a < 3; ++a) d[a] = ps[a] - m->frame_position[3 * i + a];
      for (int r = 0; r < 3; ++r) y[r] = x[3 * i + r] + A[3 * r] * d[0] + A[3 * r + 1] * d[1] + A[3 * r + 2] * d[2];
      for (int r = 0; r < 3; ++r) {
        phi[r] += w * y[r];
        for (int c = 0; c < 3; ++c) F[3 * r + c] += y[r] * g[c] + w * A[3 * r + c];
      }
    }
    for (int r = 0; r < 3; ++r)
      u[3 * k + r] = phi[r] + F[3 * r] * (p[0] - ps[0]) + F[3 * r + 1] * (p[1] - ps[1]) +
                     F[3 * r + 2] * (p[2] - ps[2]) - p[r];
  }
cleanup:
  fascia_frame_grid_destroy(&grid);
  return status;
}

// 1 when p's voxel or one of its face neighbours is the first tissue's.
static int beside_region(const fascia_prep_volume *v, const fascia_real p[3]) {
  if (fascia_prep_volume_region_at(v, p) == 1) return 1;
  for (int a = 0; a < 3; ++a)
    for (int side = -1; side <= 1; side += 2) {
      fascia_real q[3] = {p[0], p[1], p[2]};
      q[a] += side * v->voxel_size;
      if (fascia_prep_volume_region_at(v, q) == 1) return 1;
    }
  return 0;
}

// The tissue's slip on organ o (scene order, model organ k) at its surface vertices beside the region.
static fascia_status surface_slip(fascia_ctx *ctx, const fascia_prep_stages *s, const fascia_solver *solver,
                                  int32_t o, int32_t k, fascia_demo_result *out) {
  const fascia_model *m = s->model;
  const fascia_organ *organ = m->organs + k;
  double *points = malloc((size_t)(3 * (int64_t)organ->vertex_count + 3) * sizeof *points);
  double *u = malloc((size_t)(3 * (int64_t)organ->vertex_count + 3) * sizeof *u);
  out->surface_slip[o] = malloc((size_t)(organ->vertex_count + 1) * sizeof(double));
  out->surface_distance[o] = malloc((size_t)(organ->vertex_count + 1) * sizeof(double));
  fascia_status status = FASCIA_OK;
  SCENE_CHECK_GOTO(points && u && out->surface_slip[o] && out->surface_distance[o], ctx, FASCIA_ERR_MEMORY,
                   "demo: out of memory");
  int64_t n = 0;
  for (int32_t i = 0; i < organ->vertex_count; ++i)
    if (beside_region(s->volume, organ->vertices + 3 * i))
      for (int a = 0; a < 3; ++a) points[3 * n + a] = organ->vertices[3 * i + a], n += a == 2;
  SCENE_TRY_GOTO(fascia_demo_displacement_at(ctx, m, solver, n, points, u));
  fascia_real tr[3], q[4];
  SCENE_TRY_GOTO(fascia_solver_organ_pose(solver, k, tr, q));
  const double qd[4] = {q[0], q[1], q[2], q[3]};
  double R[9];
  quat_matrix(qd, R);
  for (int64_t j = 0; j < n; ++j) {
    const double *x = points + 3 * j;
    double d2 = 0, nearest = INFINITY;
    for (int a = 0; a < 3; ++a) {
      const double moved = R[3 * a] * x[0] + R[3 * a + 1] * x[1] + R[3 * a + 2] * x[2] + tr[a] - x[a];
      d2 += (u[3 * j + a] - moved) * (u[3 * j + a] - moved);
    }
    for (int32_t c = 0; c < m->coupling_count; ++c) {
      if (m->coupling_organ[c] != k) continue;
      const fascia_real *y = m->frame_position + 3 * m->coupling_frame[c];
      nearest = fmin(nearest, sqrt((x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) +
                                   (x[2] - y[2]) * (x[2] - y[2])));
    }
    out->surface_slip[o][j] = sqrt(d2), out->surface_distance[o][j] = nearest;
  }
  out->surface_count[o] = n;
cleanup:
  free(points);
  free(u);
  return status;
}

fascia_status fascia_demo_fascia(fascia_ctx *ctx, const fascia_prep_stages *s, const fascia_demo_mesh *at,
                                 fascia_demo_result *out) {
  memset(out, 0, sizeof *out);
  fascia_solver *solver = NULL;
  fascia_solve_report report;
  fascia_status status = FASCIA_OK;
  SCENE_TRY_GOTO(fascia_tissue_solve_static(ctx, s->model, &solver, &report, &out->ms));
  out->nodes = s->model->frame_count, out->elements = s->model->sample_count;
  out->organ_count = s->scene->organ_count;
  for (int32_t o = 0; o < s->scene->organ_count; ++o) {
    const int32_t k = fascia_model_find_organ(s->model, s->scene->organs[o].name);
    SCENE_CHECK_GOTO(k >= 0, ctx, FASCIA_ERR_INTERNAL, "the model lacks organ '%s'", s->scene->organs[o].name);
    fascia_real f[3];
    SCENE_TRY_GOTO(fascia_solver_organ_wrench(solver, k, f, NULL, NULL));
    for (int a = 0; a < 3; ++a) out->force[o][a] = f[a];
  }
  if (at) {
    out->u = malloc((size_t)(3 * at->node_count) * sizeof *out->u);
    SCENE_CHECK_GOTO(out->u, ctx, FASCIA_ERR_MEMORY, "demo: out of memory");
    SCENE_TRY_GOTO(fascia_demo_displacement_at(ctx, s->model, solver, at->node_count, at->node, out->u));
    for (int32_t o = 0; o < s->scene->organ_count; ++o)
      SCENE_TRY_GOTO(surface_slip(ctx, s, solver, o, fascia_model_find_organ(s->model, s->scene->organs[o].name), out));
  }
cleanup:
  fascia_solver_destroy(&solver);
  if (status != FASCIA_OK) fascia_demo_result_free(out);
  return status;
}

static int compare_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

double fascia_demo_percentile(double *values, int64_t n, double q) {
  if (n <= 0) return NAN;
  qsort(values, (size_t)n, sizeof *values, compare_double);
  int64_t k = (int64_t)ceil(q * (double)n) - 1;
  if (k < 0) k = 0;
  if (k >= n) k = n - 1;
  return values[k];
}
