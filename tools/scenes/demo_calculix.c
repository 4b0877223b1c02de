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
#include "cgal_mesh3.h"
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

// What both meshes take from the scene: the tissue's law (the stable
// Neo-Hookean, which the *HYPERFOAM card writes), its E and nu, the organs'
// names and their poses at time 1.
static fascia_status mesh_setup(fascia_ctx *ctx, const fascia_prep_stages *s, fascia_demo_mesh *out,
                                double (*R)[9], double (*T)[3]) {
  const fascia_prep_scene *sc = s->scene;
  const fascia_material *mat = sc->materials + sc->tissues[0].material;
  SCENE_CHECK(mat->law == FASCIA_LAW_NEOHOOKEAN, ctx, FASCIA_ERR_ARGUMENT,
              "demo mesh: tissue '%s' is not of the stable Neo-Hookean law (the *HYPERFOAM card writes that law)",
              sc->tissues[0].name);
  SCENE_CHECK(sc->organ_count <= FASCIA_DEMO_ORGANS_MAX, ctx, FASCIA_ERR_ARGUMENT, "demo mesh: %d organs, at most %d",
              (int)sc->organ_count, FASCIA_DEMO_ORGANS_MAX);
  out->youngs_modulus = mat->youngs_modulus, out->poisson_ratio = mat->poisson_ratio;
  out->organ_count = sc->organ_count;
  for (int32_t o = 0; o < sc->organ_count; ++o)
    snprintf(out->organ_name[o], FASCIA_NAME_SIZE, "%s", sc->organs[o].name);
  return organ_poses(ctx, s, R, T);
}

fascia_status fascia_demo_mesh_build(fascia_ctx *ctx, const fascia_prep_stages *s, int quadratic,
                                     int32_t subdivide, int on_surface, fascia_demo_mesh *out) {
  memset(out, 0, sizeof *out);
  SCENE_CHECK(subdivide >= 1 && subdivide <= 4, ctx, FASCIA_ERR_ARGUMENT,
              "demo mesh: %d elements per voxel edge, expected 1 .. 4", (int)subdivide);
  const fascia_prep_scene *sc = s->scene;
  const fascia_prep_volume *v = s->volume;
  double R[FASCIA_DEMO_ORGANS_MAX][9], T[FASCIA_DEMO_ORGANS_MAX][3];
  SCENE_TRY(mesh_setup(ctx, s, out, R, T));
  out->quadratic = quadratic, out->subdivide = subdivide;

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

// ------------------------------------------------------------ the tetrahedral mesh

// The domain Mesh_3 meshes: the region's voxels, with the organ voxels that
// touch them, as an indicator blurred by [1 2 1] / 4 along each axis and
// cut at 1/2 between the voxel centres (a smooth free boundary through the
// region's outer faces), less every organ's inside (its distance field's
// zero set: the smooth surface, where the tissue is held).
typedef struct tet_domain {
  const fascia_prep_volume *v;
  float *mask;          ///< [voxels] the blurred indicator
  double near;          ///< m: facets this close to an organ's surface are held to near_distance
  double near_distance, far_distance;
} tet_domain;

static double mask_at(const tet_domain *d, const double x[3]) {
  const fascia_prep_volume *v = d->v;
  double f[3];
  int32_t c[3];
  for (int a = 0; a < 3; ++a) {
    const double t = (x[a] - v->origin[a]) / v->voxel_size;
    c[a] = (int32_t)floor(t), f[a] = t - c[a];
    if (c[a] < 0 || c[a] + 1 >= v->dims[a]) return 0;
  }
  double m = 0;
  for (int q = 0; q < 8; ++q) {
    const int32_t i = c[0] + (q & 1), j = c[1] + ((q >> 1) & 1), k = c[2] + ((q >> 2) & 1);
    const double w = ((q & 1) ? f[0] : 1 - f[0]) * (((q >> 1) & 1) ? f[1] : 1 - f[1]) * (((q >> 2) & 1) ? f[2] : 1 - f[2]);
    m += w * d->mask[i + (int64_t)v->dims[0] * (j + (int64_t)v->dims[1] * k)];
  }
  return m;
}

static int tet_label(void *user, const double x[3]) {
  const tet_domain *d = user;
  if (mask_at(d, x) < 0.5) return 0;
  for (int32_t o = 0; o < d->v->organ_count; ++o)
    if (organ_distance(d->v, o, x) <= 0) return 0; // NAN (no field, off the grid) compares false
  return 1;
}

static double tet_facet_distance(void *user, const double x[3]) {
  const tet_domain *d = user;
  for (int32_t o = 0; o < d->v->organ_count; ++o)
    if (fabs(organ_distance(d->v, o, x)) < d->near) return d->near_distance;
  return d->far_distance;
}

// The blurred indicator of the region and the organ voxels among its 26 neighbours.
static float *tet_mask(const fascia_prep_volume *v) {
  const int32_t *n = v->dims;
  const int64_t count = (int64_t)n[0] * n[1] * n[2], stride[3] = {1, n[0], (int64_t)n[0] * n[1]};
  float *m = calloc((size_t)count, sizeof *m), *t = malloc((size_t)count * sizeof *t);
  if (!m || !t) {
    free(m), free(t);
    return NULL;
  }
  for (int64_t w = 0; w < count; ++w) {
    if (v->region[w] != 1) continue;
    const int32_t c[3] = {(int32_t)(w % n[0]), (int32_t)((w / n[0]) % n[1]), (int32_t)(w / stride[2])};
    m[w] = 1;
    for (int q = 0; q < 27; ++q) {
      const int32_t d[3] = {c[0] + q % 3 - 1, c[1] + (q / 3) % 3 - 1, c[2] + q / 9 - 1};
      if (d[0] < 0 || d[1] < 0 || d[2] < 0 || d[0] >= n[0] || d[1] >= n[1] || d[2] >= n[2]) continue;
      const int64_t u = d[0] + stride[1] * d[1] + stride[2] * d[2];
      for (int32_t o = 0; o < v->organ_count; ++o)
        if (inside(v, o, u)) m[u] = 1;
    }
  }
  for (int a = 0; a < 3; ++a) { // [1 2 1] / 4 along axis a, the grid's edge clamped
    for (int64_t w = 0; w < count; ++w) {
      const int32_t c = (int32_t)((w / stride[a]) % n[a]);
      const float lo = c > 0 ? m[w - stride[a]] : m[w], hi = c + 1 < n[a] ? m[w + stride[a]] : m[w];
      t[w] = 0.25f * lo + 0.5f * m[w] + 0.25f * hi;
    }
    float *swap = m;
    m = t, t = swap;
  }
  free(t);
  return m;
}

// Points on the domain's boundary, at most one per cube of edge `spacing`:
// bisected between a region voxel's centre inside and a face neighbour's
// outside. *out malloc'ed [3 count].
static fascia_status tet_seeds(fascia_ctx *ctx, tet_domain *d, const double lo[3], const double hi[3],
                               double spacing, double **out, int64_t *count) {
  const fascia_prep_volume *v = d->v;
  const int32_t *n = v->dims;
  const int64_t voxels = (int64_t)n[0] * n[1] * n[2];
  int64_t cells[3];
  for (int a = 0; a < 3; ++a) cells[a] = (int64_t)ceil((hi[a] - lo[a]) / spacing) + 1;
  uint8_t *taken = calloc((size_t)(cells[0] * cells[1] * cells[2]), 1);
  int64_t capacity = 1024, k = 0;
  double *p = malloc((size_t)(3 * capacity) * sizeof *p);
  *out = NULL, *count = 0;
  if (!taken || !p) {
    free(taken), free(p);
    return SCENE_FAIL(ctx, FASCIA_ERR_MEMORY, "demo tetrahedra: out of memory for the seeds");
  }
  for (int64_t w = 0; w < voxels; ++w) {
    if (v->region[w] != 1) continue;
    const int32_t c[3] = {(int32_t)(w % n[0]), (int32_t)((w / n[0]) % n[1]), (int32_t)(w / ((int64_t)n[0] * n[1]))};
    double a_in[3];
    for (int a = 0; a < 3; ++a) a_in[a] = v->origin[a] + v->voxel_size * c[a];
    if (!tet_label(d, a_in)) continue;
    for (int q = 0; q < 6; ++q) {
      // the ends jittered off the voxel lines: seeds in general position
      // (coplanar seeds leave flat tetrahedra in the Delaunay mesh)
      double in[3], outp[3];
      uint64_t hash = (uint64_t)(6 * w + q) * 0x9E3779B97F4A7C15ull;
      for (int a = 0; a < 3; ++a) {
        hash ^= hash >> 29, hash *= 0xBF58476D1CE4E5B9ull;
        const double jitter = 0.3 * v->voxel_size * ((double)(hash >> 11) / 9007199254740992.0 - 0.5);
        in[a] = a_in[a] + jitter, outp[a] = a_in[a] + jitter;
      }
      outp[q / 2] += (q & 1 ? 1 : -1) * v->voxel_size;
      if (!tet_label(d, in) || tet_label(d, outp)) continue;
      for (int it = 0; it < 50; ++it) {
        double mid[3];
        for (int a = 0; a < 3; ++a) mid[a] = 0.5 * (in[a] + outp[a]);
        memcpy(tet_label(d, mid) ? in : outp, mid, sizeof mid);
      }
      int64_t b[3], key;
      for (int a = 0; a < 3; ++a) b[a] = (int64_t)floor((in[a] - lo[a]) / spacing);
      if (b[0] < 0 || b[1] < 0 || b[2] < 0 || b[0] >= cells[0] || b[1] >= cells[1] || b[2] >= cells[2]) continue;
      key = b[0] + cells[0] * (b[1] + cells[1] * b[2]);
      if (taken[key]) continue;
      taken[key] = 1;
      if (k == capacity) {
        double *grown = realloc(p, (size_t)(6 * capacity) * sizeof *p);
        if (!grown) {
          free(taken), free(p);
          return SCENE_FAIL(ctx, FASCIA_ERR_MEMORY, "demo tetrahedra: out of memory for the seeds");
        }
        p = grown, capacity *= 2;
      }
      memcpy(p + 3 * k++, in, sizeof in);
    }
  }
  free(taken);
  *out = p, *count = k;
  return FASCIA_OK;
}

// A sorted pair or triple of vertex indices with the element it came from.
typedef struct tet_key {
  int32_t v[3];
  int64_t element;
  int32_t local;
} tet_key;

static int compare_key(const void *a, const void *b) {
  const tet_key *x = a, *y = b;
  for (int i = 0; i < 3; ++i)
    if (x->v[i] != y->v[i]) return (x->v[i] > y->v[i]) - (x->v[i] < y->v[i]);
  return 0;
}

static void sort3(int32_t v[3]) {
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2 - i; ++j)
      if (v[j] > v[j + 1]) {
        const int32_t t = v[j];
        v[j] = v[j + 1], v[j + 1] = t;
      }
}

// C3D10's mid-edge nodes 5..10 (from 1) between these corners (from 0).
static const int tet_edge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

// The smallest dihedral angle (degrees) of the straight tetrahedron p.
static double tet_min_dihedral(const double p[4][3]) {
  static const int face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  double nrm[4][3];
  for (int f = 0; f < 4; ++f) {
    const double *o = p[face[f][0]], *b = p[face[f][1]], *c = p[face[f][2]];
    const double u[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]}, w[3] = {c[0] - o[0], c[1] - o[1], c[2] - o[2]};
    double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int a = 0; a < 3; ++a) nrm[f][a] = len > 0 ? n[a] / len : 0;
  }
  double smallest = 180;
  for (int f = 0; f < 4; ++f)
    for (int g = f + 1; g < 4; ++g) {
      const double c = -(nrm[f][0] * nrm[g][0] + nrm[f][1] * nrm[g][1] + nrm[f][2] * nrm[g][2]);
      smallest = fmin(smallest, 180 / acos(-1.0) * acos(fmax(-1, fmin(1, c))));
    }
  return smallest;
}

static double det3(const double J[9]) {
  return J[0] * (J[4] * J[8] - J[5] * J[7]) - J[1] * (J[3] * J[8] - J[5] * J[6]) + J[2] * (J[3] * J[7] - J[4] * J[6]);
}

// The smallest ratio of C3D10's Jacobian determinant at its corners, centre
// and four integration points to the straight element's (x: [10][3], ccx's order).
static double tet_jacobian_ratio(const double x[10][3]) {
  static const double grad_l[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const double a = 0.5854101966249685, b = 0.1381966011250105;
  const double at[9][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}, {.25, .25, .25, .25},
                           {a, b, b, b}, {b, a, b, b}, {b, b, a, b}, {b, b, b, a}};
  double Jl[9];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Jl[3 * r + c] = x[c + 1][r] - x[0][r];
  const double straight = det3(Jl);
  double smallest = INFINITY;
  for (int q = 0; q < 9; ++q) {
    const double *L = at[q];
    double J[9] = {0};
    for (int n = 0; n < 10; ++n) {
      double g[3];
      if (n < 4) {
        for (int c = 0; c < 3; ++c) g[c] = (4 * L[n] - 1) * grad_l[n][c];
      } else {
        const int i = tet_edge[n - 4][0], j = tet_edge[n - 4][1];
        for (int c = 0; c < 3; ++c) g[c] = 4 * (L[j] * grad_l[i][c] + L[i] * grad_l[j][c]);
      }
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) J[3 * r + c] += x[n][r] * g[c];
    }
    smallest = fmin(smallest, det3(J) / straight);
  }
  return smallest;
}

fascia_status fascia_demo_tet_mesh_build(fascia_ctx *ctx, const fascia_prep_stages *s, double size,
                                         double facet_distance, fascia_demo_mesh *out) {
  memset(out, 0, sizeof *out);
  SCENE_CHECK(size > 0 && isfinite(size), ctx, FASCIA_ERR_ARGUMENT, "demo tetrahedra: size %g m, expected > 0", size);
  const fascia_prep_scene *sc = s->scene;
  const fascia_prep_volume *v = s->volume;
  double R[FASCIA_DEMO_ORGANS_MAX][9], T[FASCIA_DEMO_ORGANS_MAX][3];
  SCENE_TRY(mesh_setup(ctx, s, out, R, T));
  out->tetrahedra = 1, out->quadratic = 1, out->subdivide = 1;
  const double h = v->voxel_size;
  SCENE_CHECK(facet_distance >= 0 && facet_distance < h, ctx, FASCIA_ERR_ARGUMENT,
              "demo tetrahedra: facet distance %g m, expected 0 (the default) up to the voxel size %g m", facet_distance,
              h);
  const double near = facet_distance > 0 ? facet_distance : 0.05 * h;
  tet_domain dom = {v, tet_mask(v), 0.25 * h, near, fmax(0.2 * h, near)};
  double *seeds = NULL, *xyz = NULL;
  int32_t *tets = NULL;
  tet_key *keys = NULL;
  int64_t seed_count = 0, nv = 0, nt = 0;
  int32_t *held = NULL, *edge_id = NULL;
  fascia_status status = FASCIA_OK;
  SCENE_CHECK_GOTO(dom.mask, ctx, FASCIA_ERR_MEMORY, "demo tetrahedra: out of memory for the indicator");

  // 1. the box, the seeds, Mesh_3
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  const int64_t voxels = (int64_t)v->dims[0] * v->dims[1] * v->dims[2];
  for (int64_t w = 0; w < voxels; ++w) {
    if (v->region[w] != 1) continue;
    const int64_t c[3] = {w % v->dims[0], (w / v->dims[0]) % v->dims[1], w / ((int64_t)v->dims[0] * v->dims[1])};
    for (int a = 0; a < 3; ++a) {
      const double x = v->origin[a] + h * (double)c[a];
      lo[a] = fmin(lo[a], x - 2 * h), hi[a] = fmax(hi[a], x + 2 * h);
    }
  }
  SCENE_CHECK_GOTO(lo[0] < hi[0], ctx, FASCIA_ERR_ARGUMENT, "demo tetrahedra: tissue '%s' has no voxel",
                   sc->tissues[0].name);
  SCENE_TRY_GOTO(tet_seeds(ctx, &dom, lo, hi, size, &seeds, &seed_count));
  fascia_cgal_tet_def def = {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, tet_label, tet_facet_distance, &dom,
                             size, size, 25, 2, 1e-7, seeds, seed_count};
  SCENE_TRY_GOTO(fascia_cgal_tet_mesh(ctx, "demo tetrahedra", &def, &xyz, &nv, &tets, &nt));

  // 2. the corners an organ holds: those on its surface (to the bisection's error)
  held = malloc((size_t)nv * sizeof *held);
  keys = malloc((size_t)(6 * nt) * sizeof *keys);
  edge_id = malloc((size_t)(6 * nt) * sizeof *edge_id);
  SCENE_CHECK_GOTO(held && keys && edge_id, ctx, FASCIA_ERR_MEMORY, "demo tetrahedra: out of memory (%lld tetrahedra)",
                   (long long)nt);
  const double on = 1e-3 * h;
  for (int64_t k = 0; k < nv; ++k) {
    held[k] = -1;
    double best = on;
    for (int32_t o = 0; o < v->organ_count; ++o) {
      const double d = fabs(organ_distance(v, o, xyz + 3 * k));
      if (d < best) best = d, held[k] = o;
    }
  }
  // 3. the boundary facets (faces of one tetrahedron), then the edges, numbered
  for (int64_t e = 0; e < nt; ++e)
    for (int f = 0; f < 4; ++f) {
      tet_key *k = keys + 4 * e + f;
      for (int i = 0, j = 0; i < 4; ++i)
        if (i != f) k->v[j++] = tets[4 * e + i];
      sort3(k->v), k->element = e, k->local = f;
    }
  qsort(keys, (size_t)(4 * nt), sizeof *keys, compare_key);
  // an organ's facet: a boundary facet whose corners it all holds; its edges are the organ's
  int32_t (*organ_edge)[3] = NULL; // [facets x 3 edges] sorted pairs and organ, gathered below
  organ_edge = malloc((size_t)(3 * 4 * nt + 1) * sizeof *organ_edge);
  SCENE_CHECK_GOTO(organ_edge, ctx, FASCIA_ERR_MEMORY, "demo tetrahedra: out of memory");
  int64_t organ_edges = 0;
  for (int64_t i = 0; i < 4 * nt; ++i) {
    const int twin = (i > 0 && !compare_key(keys + i, keys + i - 1)) || (i + 1 < 4 * nt && !compare_key(keys + i, keys + i + 1));
    if (twin) continue;
    const int32_t *t = keys[i].v, o = held[t[0]];
    if (o < 0 || held[t[1]] != o || held[t[2]] != o) continue;
    const int32_t pair[3][2] = {{t[0], t[1]}, {t[0], t[2]}, {t[1], t[2]}};
    for (int q = 0; q < 3; ++q)
      organ_edge[organ_edges][0] = pair[q][0], organ_edge[organ_edges][1] = pair[q][1], organ_edge[organ_edges++][2] = o;
  }
  for (int64_t e = 0; e < nt; ++e)
    for (int q = 0; q < 6; ++q) {
      tet_key *k = keys + 6 * e + q;
      const int32_t a = tets[4 * e + tet_edge[q][0]], b = tets[4 * e + tet_edge[q][1]];
      k->v[0] = a < b ? a : b, k->v[1] = a < b ? b : a, k->v[2] = 0, k->element = e, k->local = q;
    }
  qsort(keys, (size_t)(6 * nt), sizeof *keys, compare_key);
  int64_t edges = 0;
  for (int64_t i = 0; i < 6 * nt; ++i) {
    if (i > 0 && compare_key(keys + i, keys + i - 1)) ++edges;
    edge_id[6 * keys[i].element + keys[i].local] = (int32_t)(nv + edges);
  }
  ++edges;

  // 4. the nodes: corners, then mid-edges (an organ's edges projected onto its surface)
  out->node_count = nv + edges, out->element_count = nt;
  const int64_t nn = out->node_count;
  out->node = malloc((size_t)(3 * nn) * sizeof *out->node);
  out->node_u = calloc((size_t)(3 * nn), sizeof *out->node_u);
  out->node_organ = malloc((size_t)nn * sizeof *out->node_organ);
  out->node_distance = malloc((size_t)nn * sizeof *out->node_distance);
  out->element = malloc((size_t)(10 * nt) * sizeof *out->element);
  SCENE_CHECK_GOTO(out->node && out->node_u && out->node_organ && out->node_distance && out->element, ctx,
                   FASCIA_ERR_MEMORY, "demo tetrahedra: out of memory (%lld nodes)", (long long)nn);
  memcpy(out->node, xyz, (size_t)(3 * nv) * sizeof *xyz);
  memcpy(out->node_organ, held, (size_t)nv * sizeof *held);
  for (int64_t k = nv; k < nn; ++k) out->node_organ[k] = -1;
  for (int64_t e = 0; e < nt; ++e)
    for (int q = 0; q < 10; ++q) out->element[10 * e + q] = q < 4 ? tets[4 * e + q] : edge_id[6 * e + q - 4];
  for (int64_t i = 0; i < 6 * nt; ++i) { // the mid-edge's position, once per edge
    if (i > 0 && !compare_key(keys + i, keys + i - 1)) continue;
    const int64_t k = edge_id[6 * keys[i].element + keys[i].local];
    for (int a = 0; a < 3; ++a) out->node[3 * k + a] = 0.5 * (xyz[3 * keys[i].v[0] + a] + xyz[3 * keys[i].v[1] + a]);
  }
  for (int64_t j = 0; j < organ_edges; ++j) {
    tet_key probe = {{organ_edge[j][0], organ_edge[j][1], 0}, 0, 0};
    const tet_key *found = bsearch(&probe, keys, (size_t)(6 * nt), sizeof *keys, compare_key);
    if (!found) continue;
    const int64_t k = edge_id[6 * found->element + found->local];
    if (out->node_organ[k] >= 0) continue;
    out->node_organ[k] = organ_edge[j][2];
    onto_surface(v, organ_edge[j][2], out->node + 3 * k);
  }
  free(organ_edge);

  // 5. an element that the projections fold (a flat one whose four corners
  //    lie on the surface) gets its mid-edges back on its straight edges:
  //    held there, off the surface by at most the facet distance
  for (int pass = 0; pass < 100; ++pass) {
    int64_t folded = 0;
    for (int64_t e = 0; e < nt; ++e) {
      double x[10][3];
      for (int q = 0; q < 10; ++q) memcpy(x[q], out->node + 3 * out->element[10 * e + q], sizeof x[q]);
      if (tet_jacobian_ratio((const double(*)[3])x) > 0.1) continue;
      ++folded;
      for (int q = 4; q < 10; ++q)
        for (int a = 0; a < 3; ++a)
          out->node[3 * out->element[10 * e + q] + a] = 0.5 * (x[tet_edge[q - 4][0]][a] + x[tet_edge[q - 4][1]][a]);
    }
    if (!folded) break;
  }
  for (int64_t k = 0; k < nn; ++k) {
    const int32_t o = out->node_organ[k];
    const double *x = out->node + 3 * k;
    out->node_distance[k] = o >= 0 ? organ_distance(v, o, x) : NAN;
    if (o < 0) continue;
    for (int a = 0; a < 3; ++a)
      out->node_u[3 * k + a] = R[o][3 * a] * x[0] + R[o][3 * a + 1] * x[1] + R[o][3 * a + 2] * x[2] + T[o][a] - x[a];
  }

  // 6. quality: the straight tetrahedra's dihedral angles, the curved ones' Jacobians
  out->min_dihedral = 180, out->min_jacobian_ratio = INFINITY, out->inverted = 0;
  for (int64_t e = 0; e < nt; ++e) {
    double x[10][3];
    for (int q = 0; q < 10; ++q) memcpy(x[q], out->node + 3 * out->element[10 * e + q], sizeof x[q]);
    out->min_dihedral = fmin(out->min_dihedral, tet_min_dihedral((const double(*)[3])x));
    const double ratio = tet_jacobian_ratio((const double(*)[3])x);
    out->min_jacobian_ratio = fmin(out->min_jacobian_ratio, ratio);
    out->inverted += !(ratio > 0);
  }
cleanup:
  free(dom.mask), free(seeds), free(xyz), free(tets), free(keys), free(held), free(edge_id);
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
// linear: the small-strain law with the same E and nu instead.
static void write_material(FILE *out, double E, double nu, int linear) {
  if (linear) {
    fprintf(out, "** linear elasticity (E %.13g Pa, nu %.13g): a small motion's reference\n*MATERIAL, NAME=TISSUE\n"
                 "*ELASTIC\n%.15g, %.15g\n",
            E, nu, E, nu);
    return;
  }
  const double mu = E / (2 * (1 + nu)), lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), l = lambda + mu;
  fprintf(out,
          "** the stable Neo-Hookean (E %.13g Pa, nu %.13g) written exactly as a hyperfoam\n"
          "*MATERIAL, NAME=TISSUE\n*HYPERFOAM, N=3\n%.15g, 2., %.15g, -1., %.15g, -1., 1., 0.4\n%.15g\n",
          E, nu, mu, (l + mu) / 2, -(l + mu) / 2, 1.0 / 3.0);
}

static void write_step(FILE *out, const char *solver, double first, double largest, int linear) {
  if (linear) { // one linear solve: nothing to increment or iterate
    fprintf(out, "*STEP\n*STATIC%s%s\n", solver ? ", SOLVER=" : "", solver ? solver : "");
    return;
  }
  // a part of the load first (the whole load at once diverges on the demo;
  // ccx moves only the held nodes in an increment's first iteration, which
  // folds the tetrahedra's thin layers on the organs unless the part is
  // small); residuals 500 times below ccx's default, for forces to 1e-4
  fprintf(out, "*STEP, NLGEOM, INC=1000\n*STATIC%s%s\n%g, 1.0, 1e-5, %g\n", solver ? ", SOLVER=" : "",
          solver ? solver : "", first, largest);
  fprintf(out, "*CONTROLS, PARAMETERS=FIELD\n1e-5, 1e-5, 0., -1., 0.02, 1e-5, 1e-3, 1e-8\n");
}

// Numbers go out with 12 digits: ccx reads a field's first 20 characters,
// and 15 digits with a sign and an exponent take 21 ("-1.23456789012345e-05"
// would be read as -1.23 m).
fascia_status fascia_demo_write_deck(fascia_ctx *ctx, const void *arg, FILE *out) {
  const fascia_demo_mesh *m = arg;
  SCENE_CHECK(m && m->node_count > 0 && m->element_count > 0, ctx, FASCIA_ERR_ARGUMENT, "demo deck: an empty mesh");
  const int per = m->tetrahedra ? 10 : m->quadratic ? 20 : 8;
  const char *type = m->tetrahedra ? "C3D10" : m->quadratic ? "C3D20R" : "C3D8I";
  fprintf(out,
          "** a scene's tissue region (tools/scenes/demo_calculix.c): %lld %s elements, %lld nodes;\n"
          "** the nodes an organ holds moved with its pose at time 1, gravity off, static\n"
          "*HEADING\nfascia demo tissue against CalculiX\n*NODE, NSET=NALL\n",
          (long long)m->element_count, type, (long long)m->node_count);
  for (int64_t k = 0; k < m->node_count; ++k)
    fprintf(out, "%lld, %.12g, %.12g, %.12g\n", (long long)k + 1, m->node[3 * k], m->node[3 * k + 1],
            m->node[3 * k + 2]);
  fprintf(out, "*ELEMENT, TYPE=%s, ELSET=EALL\n", type);
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
  write_material(out, m->youngs_modulus, m->poisson_ratio, m->linear);
  fprintf(out, "*SOLID SECTION, ELSET=EALL, MATERIAL=TISSUE\n");
  write_step(out, m->solver, m->tetrahedra ? 0.0625 : 0.25, m->tetrahedra ? 0.25 : 0.5, m->linear);
  fprintf(out, "*BOUNDARY\n");
  for (int64_t k = 0; k < m->node_count; ++k) {
    if (m->node_organ[k] < 0) continue;
    const double *u = m->node_u + 3 * k;
    if (u[0] == 0 && u[1] == 0 && u[2] == 0) fprintf(out, "%lld, 1, 3\n", (long long)k + 1);
    else
      for (int a = 0; a < 3; ++a) fprintf(out, "%lld, %d, %d, %.12g\n", (long long)k + 1, a + 1, a + 1, u[a]);
  }
  for (int32_t o = 0; o < m->organ_count; ++o)
    fprintf(out, "*NODE PRINT, NSET=NORGAN%d, TOTALS=ONLY\nRF\n", (int)o);
  fprintf(out, "*NODE PRINT, NSET=NALL, FREQUENCY=10000\nU\n*END STEP\n");
  return fascia_ccx_deck_written(ctx, out);
}

// "node v1 v2 v3" at the start of a .dat line (fascia_ccx_dat_numbers reads
// the values as ccx writes them): 4 when read.
static int dat_line(const char *p, long long *node, double v[3]) {
  char *end;
  *node = strtoll(p, &end, 10);
  return end != p && fascia_ccx_dat_numbers(end, v, 3) ? 4 : 0;
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
  int64_t read = 0;
  while (p && *p) {
    long long node;
    double v[3];
    const int n = dat_line(p, &node, v);
    if (n == 4) {
      if (node >= 1 && node <= m->node_count) memcpy(out->u + 3 * (node - 1), v, sizeof v), ++read;
    } else if (p[strspn(p, " \t\r")] != '\n') {
      break;
    }
    p = strchr(p, '\n');
    if (p) ++p;
  }
  int64_t missing = 0;
  for (int64_t k = 0; k < m->node_count; ++k)
    missing += !(isfinite(out->u[3 * k]) && isfinite(out->u[3 * k + 1]) && isfinite(out->u[3 * k + 2]));
  // ccx can call an increment converged whose residual is NaN: say which it was
  SCENE_CHECK_GOTO(missing == 0, ctx, FASCIA_ERR_FORMAT,
                   "CalculiX demo tissue: %lld of %lld nodes lack a finite displacement in its output (%lld read, "
                   "%lld of them not finite%s%.*s)",
                   (long long)missing, (long long)m->node_count, (long long)read,
                   (long long)(missing - (m->node_count - read)), p && *p ? "; it stops at: " : "",
                   p && *p ? (int)fmin(60, (double)strcspn(p, "\r\n")) : 0, p && *p ? p : "");
cleanup:
  free(dat);
  if (status != FASCIA_OK) fascia_demo_result_free(out);
  return status;
}

// One cube, every node moved by (F - I) X.
typedef struct one_element {
  double E, nu, F[9];
  int linear;
} one_element;

static fascia_status write_one_element(fascia_ctx *ctx, const void *arg, FILE *out) {
  const one_element *d = arg;
  fprintf(out, "** one C3D8I cube under a homogeneous F (tools/scenes/demo_calculix.c)\n*NODE, NSET=NALL\n");
  for (int q = 0; q < 8; ++q)
    fprintf(out, "%d, %g, %g, %g\n", q + 1, node_offset[q][0], node_offset[q][1], node_offset[q][2]);
  fprintf(out, "*ELEMENT, TYPE=C3D8I, ELSET=EALL\n1, 1, 2, 3, 4, 5, 6, 7, 8\n"
               "*NSET, NSET=NX\n2, 3, 6, 7\n*NSET, NSET=NY\n3, 4, 7, 8\n*NSET, NSET=NZ\n5, 6, 7, 8\n");
  write_material(out, d->E, d->nu, d->linear);
  fprintf(out, "*SOLID SECTION, ELSET=EALL, MATERIAL=TISSUE\n");
  write_step(out, NULL, 0.25, 0.5, d->linear);
  fprintf(out, "*BOUNDARY\n");
  for (int q = 0; q < 8; ++q)
    for (int a = 0; a < 3; ++a) {
      const double *X = node_offset[q];
      const double u = d->F[3 * a] * X[0] + d->F[3 * a + 1] * X[1] + d->F[3 * a + 2] * X[2] - X[a];
      fprintf(out, "%d, %d, %d, %.12g\n", q + 1, a + 1, a + 1, u);
    }
  fprintf(out, "*NODE PRINT, NSET=NX, TOTALS=ONLY\nRF\n*NODE PRINT, NSET=NY, TOTALS=ONLY\nRF\n"
               "*NODE PRINT, NSET=NZ, TOTALS=ONLY\nRF\n*END STEP\n");
  return fascia_ccx_deck_written(ctx, out);
}

fascia_status fascia_demo_one_element(fascia_ctx *ctx, const char *program, double E, double nu, int linear,
                                      const double F[9], double P[9]) {
  one_element d = {E, nu, {0}, linear};
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

static double nearest_organ(const fascia_prep_volume *v, const double x[3]) {
  double best = INFINITY;
  for (int32_t o = 0; o < v->organ_count; ++o) {
    const double d = organ_distance(v, o, x);
    if (d < best) best = d; // NAN (no field, off the grid) compares false
  }
  return best;
}

static void add_to_band(int bands, const double *edge, double d, double dv, double *volume) {
  int k = 0;
  while (k < bands - 1 && !(d < edge[k])) ++k;
  volume[k] += dv;
}

void fascia_demo_volume_bands(const fascia_prep_stages *s, const fascia_demo_mesh *mesh, int bands, const double *edge,
                              double *volume) {
  for (int k = 0; k < bands; ++k) volume[k] = 0;
  if (mesh) {
    for (int64_t e = 0; e < mesh->element_count && mesh->tetrahedra; ++e) {
      const double *p[4];
      for (int q = 0; q < 4; ++q) p[q] = mesh->node + 3 * mesh->element[10 * e + q];
      double J[9], c[3];
      for (int a = 0; a < 3; ++a) {
        for (int q = 0; q < 3; ++q) J[3 * a + q] = p[q + 1][a] - p[0][a];
        c[a] = 0.25 * (p[0][a] + p[1][a] + p[2][a] + p[3][a]);
      }
      add_to_band(bands, edge, nearest_organ(s->volume, c), fabs(det3(J)) / 6, volume);
    }
    return;
  }
  const fascia_model *m = s->model;
  for (int32_t k = 0; k < m->sample_count; ++k) {
    if (m->sample_organ[k] >= 0) continue;
    const double x[3] = {m->sample_position[3 * k], m->sample_position[3 * k + 1], m->sample_position[3 * k + 2]};
    add_to_band(bands, edge, nearest_organ(s->volume, x), m->sample_volume[k], volume);
  }
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
