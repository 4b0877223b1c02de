// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The demo tissue's tetrahedral CalculiX mesh (fascia_demo_tet_mesh_build,
// CGAL Mesh_3) holds the tissue on the organs' smooth surfaces and folds no
// element: every held corner lies on its organ's surface, the held mid-edge
// nodes were projected onto it (those of a straightened element stay within
// the facet distance), both organs hold nodes, no C3D10 Jacobian is
// non-positive, the mesh fills the region's volume, the bench's volume by
// distance counts every element and sample once, and a bad size is refused
// by name. On 2 mm voxels, tetrahedra of 4 mm circumradius: seconds.
// argv[1]: the demo scene.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "demo_calculix.h"

#define VOXEL 0.002
#define SIZE 0.004
// the corners come from Mesh_3's bisection to 1e-7 of the box's diagonal
// (about 1e-8 m); the mid-edges from three Newton steps on the distance
#define ON_SURFACE (1e-3 * VOXEL)
// where a curved element would fold, its mid-edges stay on its straight
// edges, off the surface by at most the facet distance (a twentieth of a voxel)
#define STRAIGHTENED (0.05 * VOXEL * 1.05)
// of the held mid-edge nodes, at most this share straightened
#define STRAIGHTENED_SHARE 0.02
// the tetrahedra fill the region's voxels, smoothed and cut at the organs' surfaces
#define VOLUME_TOLERANCE 0.1

static double tet_volume(const double *node, const int32_t *e) {
  const double *p0 = node + 3 * e[0], *p1 = node + 3 * e[1], *p2 = node + 3 * e[2], *p3 = node + 3 * e[3];
  const double a[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
  const double b[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
  const double c[3] = {p3[0] - p0[0], p3[1] - p0[1], p3[2] - p0[2]};
  return ((a[1] * b[2] - a[2] * b[1]) * c[0] + (a[2] * b[0] - a[0] * b[2]) * c[1] + (a[0] * b[1] - a[1] * b[0]) * c[2]) /
         6;
}

static void check_mesh(const fascia_prep_stages *s, const fascia_demo_mesh *m) {
  CHECK(m->tetrahedra == 1 && m->element_count > 0 && m->node_count > 0);
  CHECK(m->inverted == 0 && m->min_jacobian_ratio > 0);
  CHECK(m->min_dihedral > 5);
  uint8_t *corner = calloc((size_t)m->node_count, 1);
  CHECK(corner != NULL);
  if (!corner) return;
  double volume = 0;
  for (int64_t e = 0; e < m->element_count; ++e) {
    for (int q = 0; q < 4; ++q) corner[m->element[10 * e + q]] = 1;
    volume += tet_volume(m->node, m->element + 10 * e);
  }
  int64_t held[FASCIA_DEMO_ORGANS_MAX] = {0}, mid = 0, straightened = 0;
  double worst_corner = 0, worst_mid = 0;
  for (int64_t k = 0; k < m->node_count; ++k) {
    const int32_t o = m->node_organ[k];
    if (o < 0) continue;
    ++held[o];
    const double d = fabs(m->node_distance[k]);
    if (corner[k]) {
      worst_corner = fmax(worst_corner, isfinite(d) ? d : INFINITY);
      continue;
    }
    ++mid, worst_mid = fmax(worst_mid, isfinite(d) ? d : INFINITY);
    straightened += !(d <= ON_SURFACE);
  }
  free(corner);
  int64_t voxels = 0;
  const fascia_prep_volume *v = s->volume;
  for (int64_t w = 0; w < (int64_t)v->dims[0] * v->dims[1] * v->dims[2]; ++w) voxels += v->region[w] == 1;
  const double region = (double)voxels * v->voxel_size * v->voxel_size * v->voxel_size;
  if (worst_corner > ON_SURFACE || worst_mid > STRAIGHTENED || straightened > STRAIGHTENED_SHARE * (double)mid ||
      fabs(volume - region) > VOLUME_TOLERANCE * region)
    fprintf(stderr,
            "held corners up to %.2e m off their surface, mid-edges up to %.2e m (%lld of %lld off by more than "
            "%.0e m); volume %.3e m^3 against the region's voxels %.3e m^3\n",
            worst_corner, worst_mid, (long long)straightened, (long long)mid, ON_SURFACE, volume, region);
  CHECK(worst_corner <= ON_SURFACE);
  CHECK(worst_mid <= STRAIGHTENED);
  CHECK(straightened <= STRAIGHTENED_SHARE * (double)mid);
  CHECK(fabs(volume - region) <= VOLUME_TOLERANCE * region);
  for (int32_t o = 0; o < m->organ_count; ++o) CHECK(held[o] >= 100);
  // the bench's volume by distance to the organs: every tetrahedron and
  // every tissue sample counted once, and both have volume in the first voxel
  const double edge[2] = {0, VOXEL};
  double mesh_band[3], sample_band[3];
  fascia_demo_volume_bands(s, m, 3, edge, mesh_band);
  fascia_demo_volume_bands(s, NULL, 3, edge, sample_band);
  const double samples = fascia_model_tissue_volume(s->model);
  CHECK(fabs(mesh_band[0] + mesh_band[1] + mesh_band[2] - volume) <= 1e-9 * volume);
  CHECK(fabs(sample_band[0] + sample_band[1] + sample_band[2] - samples) <= 1e-9 * samples);
  CHECK(mesh_band[1] > 0 && sample_band[1] > 0);
}

int main(int argc, char **argv) {
  CHECK(argc == 2);
  if (argc != 2) return CHECK_RESULT();
  fascia_ctx_def cd = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  CHECK(fascia_ctx_create(&cd, &ctx) == FASCIA_OK);
  fascia_demo_def def = {argv[1], VOXEL, 1, 1, 0, 0, 0, 0};
  fascia_prep_stages s;
  fascia_status st = fascia_demo_prepare(ctx, &def, &s);
  if (st != FASCIA_OK) fprintf(stderr, "prepare: %s\n", fascia_ctx_message(ctx));
  CHECK(st == FASCIA_OK);
  if (st == FASCIA_OK) {
    fascia_demo_mesh m;
    st = fascia_demo_tet_mesh_build(ctx, &s, SIZE, 0, &m);
    if (st != FASCIA_OK) fprintf(stderr, "tetrahedra: %s\n", fascia_ctx_message(ctx));
    CHECK(st == FASCIA_OK);
    if (st == FASCIA_OK) check_mesh(&s, &m);
    fascia_demo_mesh_free(&m);
    // a size that is no size: refused, naming it
    CHECK(fascia_demo_tet_mesh_build(ctx, &s, 0, 0, &m) == FASCIA_ERR_ARGUMENT);
    CHECK(strstr(fascia_ctx_message(ctx), "size") != NULL);
    fascia_demo_mesh_free(&m);
  }
  fascia_prep_stages_free(&s);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
