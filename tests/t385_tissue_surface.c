// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The tissue as a body (fascia_solver_tissue_surface): the model's tissue
// surface is carried by the tissue frames. Under a rigid motion of every
// frame each vertex moves with it exactly (R p + t); under a random
// deformation each vertex shows the strain of the tissue sample nearest it
// at rest (found here by brute force); at rest it is the rest surface. The
// model file keeps the surface (save and load), refuses a triangle naming a
// vertex it lacks, and the fingerprint leaves the surface out (drawing only).
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <unistd.h>

#include "check.h"
#include "fascia/organs.h"
#include "organ_fixture.h"
#include "random_model.h"

int main(void) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1;
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  organ_fixture_def fd = organ_fixture_def_default();
  fascia_model *m = NULL;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  if (!m) return 1;
  const uint64_t bare = fascia_model_fingerprint(m);
  CHECK_OK(organ_fixture_add_surface(ctx, m), ctx);
  CHECK(fascia_model_fingerprint(m) == bare);
  const fascia_surface *ts = &m->tissue_surface;
  const int32_t V = ts->vertex_count, N = m->frame_count, S = m->sample_count;
  fascia_solver_def sd = fascia_solver_def_default();
  fascia_solver *solver = NULL;
  CHECK_OK(fascia_solver_create(ctx, m, &sd, &solver), ctx);
  fascia_real *p = calloc(3 * (size_t)V, sizeof *p), *strain = calloc((size_t)V, sizeof *strain);
  fascia_real *x = calloc(3 * (size_t)N, sizeof *x), *q = calloc(4 * (size_t)N, sizeof *q);
  fascia_real *sample_strain = calloc((size_t)S, sizeof *sample_strain);

  // at rest: the rest surface
  CHECK_OK(fascia_solver_tissue_surface(solver, p, NULL), ctx);
  double worst = 0;
  for (int64_t k = 0; k < 3 * (int64_t)V; ++k) worst = fmax(worst, fabs(p[k] - ts->vertices[k]));
  CHECK(worst < 1e-15);

  // every frame moved rigidly: R about (1, 2, 3)/|.| by 0.7 rad, then t
  const double axis[3] = {1 / sqrt(14.0), 2 / sqrt(14.0), 3 / sqrt(14.0)}, half = 0.35, t[3] = {0.01, -0.02, 0.005};
  const fascia_real rot[4] = {cos(half), sin(half) * axis[0], sin(half) * axis[1], sin(half) * axis[2]};
  fascia_real R[9];
  fascia_frame_axes(rot, 1, R); // columns: R[3c + r] = R_rc
  for (int32_t i = 0; i < N; ++i) {
    const fascia_real *a = m->frame_position + 3 * (int64_t)i, *b = m->frame_rotation + 4 * (int64_t)i;
    for (int r = 0; r < 3; ++r) x[3 * i + r] = R[r] * a[0] + R[3 + r] * a[1] + R[6 + r] * a[2] + t[r];
    // q = rot * b
    q[4 * i] = rot[0] * b[0] - rot[1] * b[1] - rot[2] * b[2] - rot[3] * b[3];
    q[4 * i + 1] = rot[0] * b[1] + rot[1] * b[0] + rot[2] * b[3] - rot[3] * b[2];
    q[4 * i + 2] = rot[0] * b[2] - rot[1] * b[3] + rot[2] * b[0] + rot[3] * b[1];
    q[4 * i + 3] = rot[0] * b[3] + rot[1] * b[2] - rot[2] * b[1] + rot[3] * b[0];
  }
  CHECK_OK(fascia_solver_set_state(solver, x, q, NULL), ctx);
  CHECK_OK(fascia_solver_tissue_surface(solver, p, NULL), ctx);
  worst = 0;
  for (int32_t v = 0; v < V; ++v) {
    const fascia_real *a = ts->vertices + 3 * (int64_t)v;
    for (int r = 0; r < 3; ++r)
      worst = fmax(worst, fabs(p[3 * v + r] - (R[r] * a[0] + R[3 + r] * a[1] + R[6 + r] * a[2] + t[r])));
  }
  printf("rigid motion: the surface is off R p + t by %.3g m\n", worst);
  CHECK(worst < 1e-14);

  // a random deformation: each vertex shows its nearest tissue sample's strain
  unsigned long long seed = 12345;
  for (int32_t i = 0; i < N; ++i) {
    for (int r = 0; r < 3; ++r) x[3 * i + r] = m->frame_position[3 * i + r] + rnd_uniform(&seed, -1e-3, 1e-3);
    memcpy(q + 4 * i, m->frame_rotation + 4 * i, 4 * sizeof *q);
  }
  CHECK_OK(fascia_solver_set_state(solver, x, q, NULL), ctx);
  CHECK_OK(fascia_solver_tissue_surface(solver, p, strain), ctx);
  fascia_solver_sample_strain(solver, sample_strain, NULL);
  int wrong = 0;
  double largest = 0;
  for (int32_t v = 0; v < V; ++v) {
    int32_t nearest = -1;
    double best = INFINITY;
    for (int32_t s = 0; s < S; ++s) {
      const fascia_real *a = ts->vertices + 3 * (int64_t)v, *b = m->sample_position + 3 * (int64_t)s;
      const double d = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
      if (m->sample_organ[s] < 0 && d < best) best = d, nearest = s;
    }
    wrong += nearest < 0 || strain[v] != sample_strain[nearest];
    largest = fmax(largest, strain[v]);
  }
  CHECK(wrong == 0 && largest > 0);

  // the model file keeps it; a bad triangle is refused, naming the dataset
  char dir[] = "/tmp/fascia-t385-XXXXXX", path[256];
  CHECK(mkdtemp(dir) != NULL);
  snprintf(path, sizeof path, "%s/m.h5", dir);
  CHECK_OK(fascia_model_save(ctx, m, path), ctx);
  fascia_model *back = NULL;
  CHECK_OK(fascia_model_load(ctx, path, &back), ctx);
  CHECK(back && back->tissue_surface.vertex_count == V && back->tissue_surface.triangle_count == ts->triangle_count &&
        !memcmp(back->tissue_surface.vertices, ts->vertices, 3 * sizeof(double) * (size_t)V) &&
        !memcmp(back->tissue_surface.triangles, ts->triangles, 3 * sizeof(int32_t) * (size_t)ts->triangle_count));
  fascia_model_destroy(&back);
  m->tissue_surface.triangles[4] = V;
  CHECK(fascia_model_validate(ctx, m, "fixture") == FASCIA_ERR_FORMAT &&
        strstr(fascia_ctx_message(ctx), "/tissue_surface/triangles: triangle 1 names vertex"));
  unlink(path);
  rmdir(dir);

  free(p), free(strain), free(x), free(q), free(sample_strain);
  fascia_solver_destroy(&solver);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
