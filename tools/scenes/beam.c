// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The paper's cantilever (Bosman et al. 2013 sec. 4.1;
// docs/mechanics.md): a 16 x 1 x 1 m beam along x, clamped at x = 0, 5 kg,
// E = 40000 Pa, nu = 0.3, under its own weight, with frames on a regular grid
// and hexahedral, tetrahedral or meshless shape functions.
//
//   z                       frames (ix, iy, iz), index (ix ny + iy) nz + iz
//   |  y                    +---+---+---  ...  ---+  x = 16: probe "tip"
//   | /                     |   |   |             |  at (16, 0, 0)
//   |/____ x                +---+---+---  ...  ---+
//   x = 0 face: FIXED       each cell: 8 Gauss samples (HEX, MESHLESS)
//                           or 6 Kuhn tetrahedra x 1 or 4 samples (TET)
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_util.h"

// Largest model the generator agrees to build (pairs), far above any use.
#define BEAM_MAX_PAIRS ((int64_t)1 << 28)

// Points across y of a sheet's cell with n along x: one point along the
// axis is free of shear locking; two across leave no mode of zero energy.
static int reduced_across(int n) { return n > 2 ? n : 2; }
// Kernel support of the weights over a sample's own interval or cell, times
// the distance to its farthest frame: a kernel nearly flat over the cell
// gives smooth weights (a support just past the frames makes them peak at
// each frame, and the sheet stiffer in bending).
#define CELL_SUPPORT_FACTOR 2.0

const char *fascia_scene_shape_name(int shape) {
  switch (shape) {
  case FASCIA_SCENE_HEX: return "hex";
  case FASCIA_SCENE_TET: return "tet";
  case FASCIA_SCENE_MESHLESS: return "meshless";
  case FASCIA_SCENE_STRAND: return "strand";
  case FASCIA_SCENE_SHEET: return "sheet";
  default: return "unknown";
  }
}

int fascia_scene_shape_from_name(const char *name) {
  for (int k = 0; name && k < FASCIA_SCENE_SHAPE_COUNT_; ++k)
    if (!strcmp(name, fascia_scene_shape_name(k))) return k;
  return -1;
}

int fascia_scene_shape_dimension(int shape) {
  return shape == FASCIA_SCENE_STRAND ? 1 : shape == FASCIA_SCENE_SHEET ? 2 : 3;
}

int fascia_scene_frames_parse(const char *text, int32_t frames[3]) {
  int n[3] = {1, 1, 1}, used = 0;
  char extra;
  if (!text) return 0;
  if (sscanf(text, "%dx%dx%d%c", &n[0], &n[1], &n[2], &extra) == 3) used = 3;
  else if (sscanf(text, "%dx%d%c", &n[0], &n[1], &extra) == 2) used = 2;
  else if (sscanf(text, "%d%c", &n[0], &extra) == 1) used = 1;
  for (int d = 0; d < used; ++d)
    if (n[d] < 2) return 0;
  if (used)
    for (int d = 0; d < 3; ++d) frames[d] = n[d];
  return used;
}

const char *fascia_scene_patch_name(int patch) {
  switch (patch) {
  case FASCIA_SCENE_PATCH_AUTO: return "auto";
  case FASCIA_SCENE_PATCH_NONE: return "full";
  case FASCIA_SCENE_PATCH_CELL: return "cell";
  case FASCIA_SCENE_PATCH_FRAME: return "frame";
  case FASCIA_SCENE_PATCH_POISSON: return "poisson";
  default: return "unknown";
  }
}

int fascia_scene_patch_from_name(const char *name) {
  for (int k = FASCIA_SCENE_PATCH_AUTO; name && k <= FASCIA_SCENE_PATCH_POISSON; ++k)
    if (!strcmp(name, fascia_scene_patch_name(k))) return k;
  return -2;
}

int32_t fascia_scene_beam_modes_of_shape(int32_t shape) {
  return shape == FASCIA_SCENE_TET ? FASCIA_MODES_NINE : FASCIA_MODES_NORMAL;
}

fascia_scene_beam_def fascia_scene_beam_def_default(void) {
  fascia_scene_beam_def def;
  memset(&def, 0, sizeof def);
  def.length = 16;
  def.width = 1;
  def.height = 1;
  def.frames[0] = 20;
  def.frames[1] = 3;
  def.frames[2] = 3;
  def.shape = FASCIA_SCENE_HEX;
  def.samples_per_cell_dir = 2;
  def.samples_per_tet = 4;
  def.neighbours = 8;
  def.section_points = 2;
  def.law = FASCIA_LAW_STVK;
  def.youngs_modulus = 40000;
  def.poisson_ratio = 0.3;
  def.mass = 5;
  def.density = 0;
  def.rotation_coupling = 0;
  def.rotation_smoothing = FASCIA_SCENE_SMOOTHING_AUTO;
  def.reduced_volumetric = 0;
  def.volumetric_patch = FASCIA_SCENE_PATCH_NONE;
  def.patch_radius = 0.5;
  def.enhanced_modes = 0;
  def.gravity[2] = -9.81;
  def.cookie_ = FASCIA_SCENE_BEAM_COOKIE_;
  return def;
}

fascia_scene_beam_def fascia_scene_beam_def_of_shape(int shape) {
  fascia_scene_beam_def def = fascia_scene_beam_def_default();
  def.shape = shape;
  if (shape == FASCIA_SCENE_STRAND || shape == FASCIA_SCENE_SHEET) {
    if (shape == FASCIA_SCENE_STRAND) def.frames[1] = 1;
    def.frames[2] = 1;
    def.neighbours = 0;           // the frames of the sample's interval or cell
    def.samples_per_cell_dir = 1; // one station per interval: no shear locking
  }
  return def;
}

// Checks the grid and shape fields of a strand or a sheet (see check_beam).
static fascia_status check_reduced(fascia_ctx *ctx, const fascia_scene_beam_def *def, int32_t *samples,
                                   int32_t *per_sample) {
  const char *who = def->shape == FASCIA_SCENE_STRAND ? "beam generator (strand)" : "beam generator (sheet)";
  const int dim = fascia_scene_shape_dimension(def->shape);
  int64_t frames = 1, cells = 1;
  for (int d = 0; d < dim; ++d) {
    SCENE_CHECK(def->frames[d] >= 2 && def->frames[d] <= 100000, ctx, FASCIA_ERR_ARGUMENT,
                "%s: %d frames along %c, expected 2 .. 100000 (frames sit on both ends)", who, (int)def->frames[d],
                "xyz"[d]);
    frames *= def->frames[d];
    cells *= def->frames[d] - 1;
  }
  const int64_t n = def->samples_per_cell_dir, q = def->section_points;
  SCENE_CHECK(n >= 1 && n <= 4, ctx, FASCIA_ERR_ARGUMENT,
              "%s: %d samples per cell direction, expected 1 .. 4 (Gauss-Legendre points)", who, (int)n);
  SCENE_CHECK(q >= 1 && q <= 4, ctx, FASCIA_ERR_ARGUMENT,
              "%s: %d section points, expected 1 .. 4 (Gauss-Legendre points per direction of the section)", who,
              (int)q);
  SCENE_CHECK(def->neighbours == 0 || (def->neighbours >= dim + 1 && def->neighbours <= FASCIA_SHAPE_MAX_NEIGHBOURS),
              ctx, FASCIA_ERR_ARGUMENT, "%s: %d neighbours per sample, expected 0 (the frames of its %s) or %d .. %d",
              who, (int)def->neighbours, dim == 1 ? "interval" : "cell", dim + 1, FASCIA_SHAPE_MAX_NEIGHBOURS);
  SCENE_CHECK(def->reduced_volumetric == 0 && def->volumetric_patch == FASCIA_SCENE_PATCH_NONE, ctx,
              FASCIA_ERR_ARGUMENT,
              "%s: volumetric patches and reduced volumetric integration are cures of volume locking; a %s has "
              "none: choose full (or auto)",
              who, fascia_scene_shape_name(def->shape));
  SCENE_CHECK(def->enhanced_modes <= 0, ctx, FASCIA_ERR_ARGUMENT,
              "%s: enhanced strain modes live on volumetric patches, which a %s has not: choose off (or auto)", who,
              fascia_scene_shape_name(def->shape));
  const int64_t per_cell = dim == 1 ? n * q * q : n * reduced_across((int)n) * q;
  *per_sample = def->neighbours == 0 ? (dim == 1 ? 2 : 4) : def->neighbours < frames ? def->neighbours : (int32_t)frames;
  SCENE_CHECK(frames <= BEAM_MAX_PAIRS && cells * per_cell * *per_sample <= BEAM_MAX_PAIRS, ctx, FASCIA_ERR_MEMORY,
              "%s: %lld frames and %lld sample-frame pairs is too large (at most %lld)", who, (long long)frames,
              (long long)(cells * per_cell * *per_sample), (long long)BEAM_MAX_PAIRS);
  *samples = (int32_t)(cells * per_cell);
  return FASCIA_OK;
}

// Checks the grid and shape fields; on success *samples and *per_sample hold
// the model's sample count and neighbours per sample.
static fascia_status check_beam(fascia_ctx *ctx, const fascia_scene_beam_def *def, int32_t *samples,
                                int32_t *per_sample) {
  const char *who = "beam generator";
  fascia_status st = scene_check_body(ctx, def, who);
  if (st != FASCIA_OK) return st;
  SCENE_CHECK(def->shape >= 0 && def->shape < FASCIA_SCENE_SHAPE_COUNT_, ctx, FASCIA_ERR_ARGUMENT,
              "%s: shape %d, expected 0 (hex), 1 (tet), 2 (meshless), 3 (strand) or 4 (sheet)", who, (int)def->shape);
  if (fascia_scene_shape_dimension(def->shape) < 3) return check_reduced(ctx, def, samples, per_sample);
  int64_t frames = 1, cells = 1;
  for (int d = 0; d < 3; ++d) {
    SCENE_CHECK(def->frames[d] >= 2 && def->frames[d] <= 100000, ctx, FASCIA_ERR_ARGUMENT,
                "%s: %d frames along %c, expected 2 .. 100000 (frames sit on both faces)", who, (int)def->frames[d],
                "xyz"[d]);
    frames *= def->frames[d];
    cells *= def->frames[d] - 1;
  }
  int64_t per_cell;
  if (def->shape == FASCIA_SCENE_TET) {
    SCENE_CHECK(def->samples_per_tet == 1 || def->samples_per_tet == 4, ctx, FASCIA_ERR_ARGUMENT,
                "%s: %d samples per tetrahedron, expected 1 (centroid) or 4 (degree-2 rule)", who,
                (int)def->samples_per_tet);
    per_cell = 6 * (int64_t)def->samples_per_tet;
    *per_sample = 4;
  } else {
    const int64_t n = def->samples_per_cell_dir;
    SCENE_CHECK(n >= 1 && n <= 4, ctx, FASCIA_ERR_ARGUMENT,
                "%s: %d samples per cell direction, expected 1 .. 4 (Gauss-Legendre points)", who, (int)n);
    per_cell = n * n * n;
    *per_sample = 8;
    if (def->shape == FASCIA_SCENE_MESHLESS) {
      SCENE_CHECK(def->neighbours >= 4 && def->neighbours <= FASCIA_SHAPE_MAX_NEIGHBOURS &&
                      def->neighbours <= frames,
                  ctx, FASCIA_ERR_ARGUMENT,
                  "%s: %d neighbours per sample, expected 4 .. %d and at most the frame count (%lld)", who,
                  (int)def->neighbours, FASCIA_SHAPE_MAX_NEIGHBOURS, (long long)frames);
      *per_sample = def->neighbours;
    }
  }
  SCENE_CHECK(frames <= BEAM_MAX_PAIRS && cells * per_cell * *per_sample <= BEAM_MAX_PAIRS, ctx, FASCIA_ERR_MEMORY,
              "%s: %lld frames and %lld sample-frame pairs is too large (at most %lld)", who, (long long)frames,
              (long long)(cells * per_cell * *per_sample), (long long)BEAM_MAX_PAIRS);
  SCENE_CHECK(def->reduced_volumetric == 0 || def->reduced_volumetric == 1, ctx, FASCIA_ERR_ARGUMENT,
              "%s: reduced_volumetric %d, expected 0 or 1", who, (int)def->reduced_volumetric);
  SCENE_CHECK(def->volumetric_patch >= FASCIA_SCENE_PATCH_AUTO && def->volumetric_patch <= FASCIA_SCENE_PATCH_POISSON,
              ctx, FASCIA_ERR_ARGUMENT, "%s: volumetric_patch %d, expected -1 (auto), 0 (none), 1 (cell), 2 (frame) or 3 (poisson)", who,
              (int)def->volumetric_patch);
  SCENE_CHECK(def->enhanced_modes >= -1 && def->enhanced_modes < FASCIA_MODES_COUNT_, ctx, FASCIA_ERR_ARGUMENT,
              "%s: enhanced_modes %d, expected -1 (auto), 0 (off), 1 (nine) or 2 (normal)", who,
              (int)def->enhanced_modes);
  SCENE_CHECK(def->enhanced_modes <= 0 || def->volumetric_patch != FASCIA_SCENE_PATCH_NONE, ctx, FASCIA_ERR_ARGUMENT,
              "%s: enhanced strain modes live on volumetric patches: choose a volumetric_patch", who);
  SCENE_CHECK(!def->reduced_volumetric || def->volumetric_patch == FASCIA_SCENE_PATCH_NONE, ctx,
              FASCIA_ERR_ARGUMENT, "%s: reduced_volumetric and volumetric_patch are two cures of locking: choose one",
              who);
  // reduced volumetric integration: one more sample per cell (per tetrahedron)
  if (def->reduced_volumetric) per_cell += def->shape == FASCIA_SCENE_TET ? 6 : 1;
  *samples = (int32_t)(cells * per_cell);
  return FASCIA_OK;
}

// ------------------------------------------------ strands and sheets --
// A reduced shape's frames span the axis (strand) or the mid-plane (sheet);
// every point p gets the MLS weights of its station, p with the coordinates
// across the span set to 0: the k nearest frames and the kernel radius of
// the station, fascia_shape_mls_adaptive at p (which depends on p only
// through the station).

// Frames per sample: those of the sample's interval (2) or cell (4), or the
// k nearest (at most all).
static int32_t reduced_neighbours(const fascia_scene_beam_def *def, const fascia_frame_grid *grid) {
  if (def->neighbours == 0) return def->shape == FASCIA_SCENE_STRAND ? 2 : 4;
  const int32_t count = fascia_frame_grid_count(grid);
  return def->neighbours < count ? def->neighbours : count;
}

static fascia_status reduced_weights_at(fascia_ctx *ctx, const fascia_scene_beam_def *def, const scene_grid *g,
                                        const fascia_frame_grid *grid, const fascia_real p[3], int32_t *frame,
                                        fascia_real *w, fascia_real *grad) {
  const int dim = fascia_scene_shape_dimension(def->shape);
  const int32_t k = reduced_neighbours(def, grid);
  fascia_real station[3] = {p[0], dim == 2 ? p[1] : 0, 0}, radius, x[3 * FASCIA_SHAPE_MAX_NEIGHBOURS];
  const fascia_real *position = fascia_frame_grid_positions(grid);
  if (def->neighbours == 0) { // the frames of the station's interval or cell
    int32_t cell[3];
    scene_grid_cell_of(g, station, cell);
    const int32_t ny = dim == 2 ? g->n[1] : 1;
    for (int32_t c = 0; c < k; ++c) frame[c] = (cell[0] + (c & 1)) * ny + (dim == 2 ? cell[1] + (c >> 1) : 0);
    fascia_real reach = 0;
    for (int32_t c = 0; c < k; ++c) {
      fascia_real d2 = 0;
      for (int d = 0; d < 2; ++d) d2 += (position[3 * frame[c] + d] - station[d]) * (position[3 * frame[c] + d] - station[d]);
      reach = fmax(reach, sqrt(d2));
    }
    radius = CELL_SUPPORT_FACTOR * reach;
  } else {
    SCENE_TRY(fascia_frame_grid_nearest(ctx, grid, station, k, frame, &radius));
  }
  for (int32_t j = 0; j < k; ++j)
    for (int d = 0; d < 3; ++d) x[3 * j + d] = position[3 * (int64_t)frame[j] + d];
  int32_t found = 0;
  SCENE_TRY(fascia_shape_mls_adaptive(ctx, k, x, p, radius, 0, w, grad, &found));
  SCENE_CHECK(found == dim, ctx, FASCIA_ERR_NUMERIC,
              "beam generator (%s): the %d nearest frames of (%g %g %g) span %d dimension(s), expected %d; use the "
              "frames of the %s (neighbours 0) or more neighbours",
              fascia_scene_shape_name(def->shape), (int)k, p[0], p[1], p[2], (int)found, dim,
              dim == 1 ? "interval" : "cell");
  return FASCIA_OK;
}

// Frame positions of a strand (on the axis) or a sheet (in the mid-plane).
static void reduced_positions(const fascia_scene_beam_def *def, const scene_grid *g, fascia_real *position) {
  const int32_t ny = def->shape == FASCIA_SCENE_SHEET ? g->n[1] : 1;
  for (int32_t ix = 0; ix < g->n[0]; ++ix)
    for (int32_t iy = 0; iy < ny; ++iy) {
      fascia_real *x = position + 3 * ((int64_t)ix * ny + iy);
      x[0] = scene_grid_coord(g, 0, ix);
      x[1] = def->shape == FASCIA_SCENE_SHEET ? scene_grid_coord(g, 1, iy) : 0;
      x[2] = 0;
    }
}

// Samples of a strand (per interval: n stations x q^2 section points) or a
// sheet (per cell: n^2 in-plane points x q through the thickness), from
// sample *first on; volume = Gauss weights x interval (cell) x section.
static fascia_status fill_reduced_samples(fascia_ctx *ctx, const fascia_scene_beam_def *def, const scene_grid *g,
                                          const fascia_frame_grid *grid, fascia_model *m, int32_t *first) {
  fascia_real gp[4], gw[4];
  const int n = def->samples_per_cell_dir, q = def->section_points;
  SCENE_TRY(fascia_shape_gauss_legendre(ctx, n, gp, gw));
  const int strand = def->shape == FASCIA_SCENE_STRAND;
  const int32_t k = reduced_neighbours(def, grid), cy = strand ? 1 : g->n[1] - 1;
  // a sheet's cell: n points along x, reduced_across(n) across y
  const int ny = strand ? 1 : reduced_across(n);
  fascia_real yp[4] = {0.5}, yw[4] = {1};
  if (!strand) SCENE_TRY(fascia_shape_gauss_legendre(ctx, ny, yp, yw));
  // the section, shared with prep's strands and sheets: q x q over width x
  // height (strand), q through the thickness (sheet)
  const fascia_real ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1};
  fascia_real offset[3 * 16], fraction[16];
  const int across = strand ? q * q : q;
  if (strand) SCENE_TRY(fascia_shape_section_points(ctx, 1, q, ey, ez, def->width, def->height, offset, fraction));
  else SCENE_TRY(fascia_shape_section_points(ctx, 2, q, ez, NULL, def->height, 0, offset, fraction));
  const fascia_real section = strand ? def->width * def->height : def->height;
  int32_t frame[FASCIA_SHAPE_MAX_NEIGHBOURS];
  fascia_real w[FASCIA_SHAPE_MAX_NEIGHBOURS], grad[3 * FASCIA_SHAPE_MAX_NEIGHBOURS];
  int32_t s = *first;
  for (int32_t cx = 0; cx < g->n[0] - 1; ++cx)
    for (int32_t j = 0; j < cy; ++j) {
      const fascia_real x0 = scene_grid_coord(g, 0, cx), x1 = scene_grid_coord(g, 0, cx + 1);
      const fascia_real y0 = strand ? 0 : scene_grid_coord(g, 1, j), y1 = strand ? 0 : scene_grid_coord(g, 1, j + 1);
      const fascia_real span = strand ? 1 : y1 - y0;
      for (int a = 0; a < n; ++a)
        for (int b = 0; b < ny; ++b)
          for (int c = 0; c < across; ++c, ++s) {
            fascia_real *p = m->sample_position + 3 * (int64_t)s;
            const fascia_real station[3] = {x0 + (x1 - x0) * gp[a], strand ? 0 : y0 + (y1 - y0) * yp[b], 0};
            for (int r = 0; r < 3; ++r) p[r] = station[r] + offset[3 * c + r];
            m->sample_volume[s] = gw[a] * yw[b] * fraction[c] * (x1 - x0) * span * section;
            m->sample_material[s] = 0;
            SCENE_TRY(reduced_weights_at(ctx, def, g, grid, p, frame, w, grad));
            scene_set_pairs(m, s, k, frame, w, grad);
          }
    }
  *first = s;
  return FASCIA_OK;
}

// Probe "tip" at (length, 0, 0) with the beam's own shape function. MLS
// grows k past the samples' neighbour count if the k nearest frames are
// coplanar (at an end face of a 3 x 3 section the 9 nearest all are).
static fascia_status tip_probe(fascia_ctx *ctx, const fascia_scene_beam_def *def, const scene_grid *g,
                               const fascia_frame_grid *grid, scene_probe *probe) {
  const fascia_real tip[3] = {def->length, 0, 0};
  int32_t frame[SCENE_PROBE_MAX];
  fascia_real w[SCENE_PROBE_MAX], grad[3 * SCENE_PROBE_MAX];
  fascia_status st = FASCIA_OK;
  int32_t n = 0;
  if (def->shape == FASCIA_SCENE_HEX) {
    st = scene_hex_at(ctx, g, tip, frame, w, grad);
    n = 8;
  } else if (def->shape == FASCIA_SCENE_TET) {
    st = scene_tet_at(ctx, g, tip, frame, w, grad);
    n = 4;
  } else if (fascia_scene_shape_dimension(def->shape) < 3) {
    st = reduced_weights_at(ctx, def, g, grid, tip, frame, w, grad);
    n = reduced_neighbours(def, grid);
  } else {
    const int32_t most = fascia_frame_grid_count(grid) < SCENE_PROBE_MAX ? fascia_frame_grid_count(grid)
                                                                         : SCENE_PROBE_MAX;
    for (n = def->neighbours; n <= most; ++n) {
      st = scene_mls_at(ctx, grid, tip, n, frame, w, grad);
      if (st != FASCIA_ERR_NUMERIC) break;
    }
    if (st == FASCIA_OK) fascia_ctx_clear(ctx);
  }
  if (st != FASCIA_OK) return st;
  scene_probe_set(probe, tip, n, frame, w);
  return FASCIA_OK;
}

// Samples on the n^3 Gauss points of every cell, trilinear or MLS weights.
// Samples at the n x n x n Gauss points of every cell, from sample *first on,
// with material `material`; *first moves past them.
static fascia_status fill_gauss_samples(fascia_ctx *ctx, const fascia_scene_beam_def *def, const scene_grid *g,
                                        const fascia_frame_grid *grid, fascia_model *m, int n, int32_t material,
                                        int32_t *first) {
  fascia_real gp[4], gw[4];
  fascia_status st = fascia_shape_gauss_legendre(ctx, n, gp, gw);
  if (st != FASCIA_OK) return st;
  const int32_t k = def->shape == FASCIA_SCENE_MESHLESS ? def->neighbours : 8;
  int32_t frame[FASCIA_SHAPE_MAX_NEIGHBOURS];
  fascia_real w[FASCIA_SHAPE_MAX_NEIGHBOURS], grad[3 * FASCIA_SHAPE_MAX_NEIGHBOURS];
  int32_t s = *first;
  for (int32_t c = 0; c < scene_grid_cell_count(g); ++c) {
    int32_t cell[3], corner[8];
    fascia_real lo[3], hi[3];
    scene_grid_cell_unflatten(g, c, cell);
    scene_grid_cell_corners(g, cell, corner, lo, hi);
    const fascia_real cell_volume = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b)
        for (int q = 0; q < n; ++q, ++s) {
          const int idx[3] = {a, b, q};
          fascia_real *p = m->sample_position + 3 * (int64_t)s;
          for (int d = 0; d < 3; ++d) p[d] = lo[d] + (hi[d] - lo[d]) * gp[idx[d]];
          m->sample_volume[s] = gw[a] * gw[b] * gw[q] * cell_volume;
          m->sample_material[s] = material;
          if (def->shape == FASCIA_SCENE_HEX) {
            st = fascia_shape_hex(ctx, lo, hi, p, w, grad);
            memcpy(frame, corner, sizeof corner);
          } else {
            st = scene_mls_at(ctx, grid, p, k, frame, w, grad);
          }
          if (st != FASCIA_OK) return st;
          scene_set_pairs(m, s, k, frame, w, grad);
        }
  }
  *first = s;
  return FASCIA_OK;
}

// Samples at the quadrature points of the 6 Kuhn tetrahedra of every cell.
// (from sample *first on, with material `material`, rule n; *first moves on)
static fascia_status fill_tet_samples(fascia_ctx *ctx, const scene_grid *g, fascia_model *m, int n, int32_t material,
                                      int32_t *first) {
  fascia_real bary[16], qw[4];
  fascia_status st = fascia_shape_tet_quadrature(ctx, n, bary, qw);
  if (st != FASCIA_OK) return st;
  int32_t s = *first;
  for (int32_t c = 0; c < scene_grid_cell_count(g); ++c) {
    int32_t cell[3], corner[8];
    fascia_real lo[3], hi[3];
    scene_grid_cell_unflatten(g, c, cell);
    scene_grid_cell_corners(g, cell, corner, lo, hi);
    // every Kuhn tetrahedron has a sixth of the cell's volume
    const fascia_real tet_volume = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]) / 6;
    for (int t = 0; t < 6; ++t) {
      int32_t frame[4];
      fascia_real vertex[12];
      scene_cell_tet(g, cell, t, frame, vertex);
      for (int q = 0; q < n; ++q, ++s) {
        fascia_real *p = m->sample_position + 3 * (int64_t)s, w[4], grad[12];
        for (int d = 0; d < 3; ++d)
          p[d] = bary[4 * q] * vertex[d] + bary[4 * q + 1] * vertex[3 + d] + bary[4 * q + 2] * vertex[6 + d] +
                 bary[4 * q + 3] * vertex[9 + d];
        m->sample_volume[s] = qw[q] * tet_volume;
        m->sample_material[s] = material;
        st = fascia_shape_tet(ctx, vertex, p, w, grad);
        if (st != FASCIA_OK) return st;
        scene_set_pairs(m, s, 4, frame, w, grad);
      }
    }
  }
  *first = s;
  return FASCIA_OK;
}

// Volumetric patches: samples are written cell by cell, the same number per
// cell; a frame's patch takes the samples whose nearest frame it is (the
// nearest corner of their cell: the grid is regular).
static void assign_patches(const fascia_scene_beam_def *def, const scene_grid *g, fascia_model *m) {
  const int32_t cells = scene_grid_cell_count(g), per_cell = m->sample_count / cells;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    const int32_t c = s / per_cell;
    if (def->volumetric_patch == FASCIA_SCENE_PATCH_CELL) {
      m->sample_patch[s] = c;
      continue;
    }
    int32_t cell[3], corner[8];
    fascia_real lo[3], hi[3];
    scene_grid_cell_unflatten(g, c, cell);
    scene_grid_cell_corners(g, cell, corner, lo, hi);
    const fascia_real *p = m->sample_position + 3 * (int64_t)s;
    fascia_real best = INFINITY;
    for (int k = 0; k < 8; ++k) {
      const fascia_real *x = m->frame_position + 3 * (int64_t)corner[k];
      const fascia_real d2 = (p[0] - x[0]) * (p[0] - x[0]) + (p[1] - x[1]) * (p[1] - x[1]) + (p[2] - x[2]) * (p[2] - x[2]);
      if (d2 < best || (d2 == best && corner[k] < m->sample_patch[s])) {
        best = d2;
        m->sample_patch[s] = corner[k];
      }
    }
  }
}

static void beam_provenance(char *buf, size_t size, const fascia_scene_beam_def *def, const fascia_model *m) {
  buf[0] = 0;
  scene_append(buf, size,
               "{\"generator\": \"fascia_scene_beam_build\", \"fascia_version\": \"%s\", \"scene\": \"beam\", "
               "\"reference\": \"Bosman et al. 2013 sec. 4.1\", \"frames\": [%d, %d, %d], \"shape\": \"%s\", ",
               fascia_version(), (int)def->frames[0],
               fascia_scene_shape_dimension(def->shape) > 1 ? (int)def->frames[1] : 1,
               fascia_scene_shape_dimension(def->shape) > 2 ? (int)def->frames[2] : 1,
               fascia_scene_shape_name(def->shape));
  if (fascia_scene_shape_dimension(def->shape) < 3) {
    fascia_real E, nu;
    scene_section_moduli(def, &E, &nu);
    scene_append(buf, size,
                 "\"section_points\": %d, \"section\": \"%s\", \"neighbours\": %d, \"kernel\": \"wendland-c2\", "
                 "\"mls_basis\": \"linear in the frames' span\", \"section_youngs_modulus\": %.17g, "
                 "\"section_poisson_ratio\": %.17g, ",
                 (int)def->section_points,
                 def->shape == FASCIA_SCENE_STRAND ? "rigid, uniaxial stress moduli" : "rigid normal, plane stress moduli",
                 (int)def->neighbours, E, nu);
  }
  if (def->shape == FASCIA_SCENE_TET)
    scene_append(buf, size, "\"tet_split\": \"kuhn6\", \"samples_per_tet\": %d, ", (int)def->samples_per_tet);
  else
    scene_append(buf, size, "\"samples_per_cell_dir\": %d, \"sample_rule\": \"gauss-legendre\", ",
                 (int)def->samples_per_cell_dir);
  if (def->shape == FASCIA_SCENE_MESHLESS)
    scene_append(buf, size, "\"neighbours\": %d, \"kernel\": \"wendland-c2\", \"support_margin\": %g, ",
                 (int)def->neighbours, FASCIA_SHAPE_SUPPORT_MARGIN);
  scene_append(buf, size, "\"sample_count\": %d, \"pair_count\": %d, ", (int)m->sample_count, (int)m->pair_count);
  scene_append_body_json(buf, size, def);
  scene_append(buf, size, "}");
}

fascia_status fascia_scene_beam_build(fascia_ctx *ctx, const fascia_scene_beam_def *def, fascia_model **out) {
  SCENE_CHECK(out, ctx, FASCIA_ERR_ARGUMENT, "fascia_scene_beam_build: NULL out");
  *out = NULL;
  // the rule of PATCH_AUTO, once: the def used from here on names its choice
  fascia_scene_beam_def resolved = *def;
  if (resolved.volumetric_patch == FASCIA_SCENE_PATCH_AUTO && fascia_scene_shape_dimension(resolved.shape) < 3)
    resolved.volumetric_patch = FASCIA_SCENE_PATCH_NONE; // a section carried by rotations does not lock
  if (resolved.volumetric_patch == FASCIA_SCENE_PATCH_AUTO)
    resolved.volumetric_patch =
        resolved.poisson_ratio >= FASCIA_PATCH_MIN_POISSON ? FASCIA_SCENE_PATCH_CELL : FASCIA_SCENE_PATCH_NONE;
  if (resolved.enhanced_modes < 0) { // not on meshless beams or the centroid rule: soft enough already
    const int suits = resolved.shape == FASCIA_SCENE_HEX ||
                      (resolved.shape == FASCIA_SCENE_TET && resolved.samples_per_tet == 4);
    resolved.enhanced_modes = suits && resolved.volumetric_patch != FASCIA_SCENE_PATCH_NONE
                                  ? fascia_scene_beam_modes_of_shape(resolved.shape)
                                  : FASCIA_MODES_NONE;
  }
  def = &resolved;
  int32_t samples = 0, per_sample = 0;
  fascia_status status = check_beam(ctx, def, &samples, &per_sample);
  if (status != FASCIA_OK) return status;
  const int reduced = fascia_scene_shape_dimension(def->shape) < 3;
  int32_t grid_frames[3];
  memcpy(grid_frames, def->frames, sizeof grid_frames);
  for (int d = fascia_scene_shape_dimension(def->shape); d < 3; ++d) grid_frames[d] = 2; // not used: no division by 0
  const scene_grid g = scene_grid_of_beam(def, grid_frames);
  const int32_t frames = def->shape == FASCIA_SCENE_STRAND  ? g.n[0]
                         : def->shape == FASCIA_SCENE_SHEET ? g.n[0] * g.n[1]
                                                            : scene_grid_frame_count(&g);
  scene_build b;
  SCENE_TRY(scene_build_begin(ctx, frames, "beam generator", &b));
  scene_probe probe;
  if (reduced) reduced_positions(def, &g, b.position);
  else scene_grid_positions(&g, b.position);
  if (def->shape == FASCIA_SCENE_MESHLESS || reduced) SCENE_TRY_GOTO(fascia_frame_grid_create(ctx, frames, b.position, &b.grid));
  SCENE_TRY_GOTO(tip_probe(ctx, def, &g, b.grid, &probe));
  SCENE_TRY_GOTO(scene_model_alloc(ctx, frames, b.position, samples, samples * per_sample,
                                   def->reduced_volumetric ? 2 : 1, &probe, &b.m));
  // samples are written in order: the (deviatoric) rule, then the volumetric centres
  int32_t next = 0;
  if (reduced) {
    SCENE_TRY_GOTO(fill_reduced_samples(ctx, def, &g, b.grid, b.m, &next));
  } else if (def->shape == FASCIA_SCENE_TET) {
    SCENE_TRY_GOTO(fill_tet_samples(ctx, &g, b.m, def->samples_per_tet, 0, &next));
    if (def->reduced_volumetric) SCENE_TRY_GOTO(fill_tet_samples(ctx, &g, b.m, 1, 1, &next));
  } else {
    SCENE_TRY_GOTO(fill_gauss_samples(ctx, def, &g, b.grid, b.m, def->samples_per_cell_dir, 0, &next));
    if (def->reduced_volumetric) SCENE_TRY_GOTO(fill_gauss_samples(ctx, def, &g, b.grid, b.m, 1, 1, &next));
  }
  if (def->volumetric_patch == FASCIA_SCENE_PATCH_POISSON) SCENE_TRY_GOTO(fascia_model_make_patches(ctx, b.m, &def->patch_radius));
  else if (def->volumetric_patch != FASCIA_SCENE_PATCH_NONE) assign_patches(def, &g, b.m);
  for (int32_t s = 0; s < b.m->sample_count; ++s) b.m->sample_modes[s] = b.m->sample_patch[s] >= 0 ? def->enhanced_modes : FASCIA_MODES_NONE;
  beam_provenance(b.provenance, SCENE_PROVENANCE_SIZE, def, b.m);
  SCENE_TRY_GOTO(scene_finish(ctx, b.m, def, &probe, b.provenance, "beam generator"));
cleanup:
  return scene_build_end(&b, status, out);
}
