// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Extra outputs of `fascia run`:
//   --history FILE.csv  one row per step: time, energies, Newton and CG
//                       iterations, ms, largest strain and stress;
//   --paraview DIR      per saved step, the tissue surface, the samples, the
//                       frames and each organ's surface where the
//                       simulation put it (deformable organs carried by
//                       their frames, driven ones by their first coupling
//                       frame), all VTK XML UnstructuredGrid so that meshio
//                       reads every file as ParaView does,
//                       with DIR/run.pvd that opens all of it, named, in one
//                       go, and DIR/organs.pvd of the organs alone (to open
//                       next to the results' XDMF); --organs is its older name;
//   --snapshots DIR     CSV of the tissue samples (position, strain, stress)
//                       and of organ surface points, at rest and at the end,
//                       for the gnuplot scripts in tools/plots/.
#define _POSIX_C_SOURCE 200809L
#include "run_outputs.h"
#include "commands.h"

#include "fascia/files.h"
#include "fascia/vtk_xml.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

const char run_outputs_usage[] =
    "  --history FILE.csv     per-step history: time, energies, iterations, ms, largest strain\n"
    "  --paraview DIR         ParaView files per saved step: open DIR/run.pvd for the samples,\n"
    "                         frames and organ surfaces, named (tissue-<k>.vtu, samples-<k>.vtu,\n"
    "                         frames-<k>.vtu, <organ>-<k>.vtu; DIR/organs.pvd: the organs alone).\n"
    "                         Lengths in m, time in s. --organs DIR:\n"
    "                         the same (its older name)\n"
    "  --snapshots DIR        CSV of tissue samples and organ surface points at rest and at the end\n"
    "                         (DIR/tissue-rest.csv, tissue-final.csv, organs-rest.csv, organs-final.csv)\n";

int run_outputs_take(int *argc, char **argv, run_outputs *out) {
  memset(out, 0, sizeof *out);
  static const char *const names[] = {"--history", "--organs", "--paraview", "--snapshots", NULL};
  int k = 1, kept = 1, taken;
  const char *o, *v;
  while ((taken = cli_take_option(argc, argv, &k, &kept, names, "", &o, &v)) == 1) {
    if (!strcmp(o, "--history")) out->history_path = v;
    else if (!strcmp(o, "--organs") || !strcmp(o, "--paraview")) out->paraview_dir = v;
    else out->snapshots_dir = v;
  }
  return taken ? taken : -1;
}

static fascia_status make_dir(fascia_ctx *ctx, const char *dir) {
  if (mkdir(dir, 0777) == 0 || errno == EEXIST) return FASCIA_OK;
  return fascia_ctx_fail(ctx, FASCIA_ERR_IO, __FILE__, __LINE__, "run: cannot create folder '%s': %s", dir,
                         strerror(errno));
}

// Every text file is written under a temporary name and renamed when
// complete (fascia/files.h): a failure leaves no truncated file behind.
static fascia_file *open_file(fascia_ctx *ctx, const char *what, const char *dir, const char *name,
                              fascia_status *st) {
  char path[4096];
  if (dir) snprintf(path, sizeof path, "%s/%s", dir, name);
  else snprintf(path, sizeof path, "%s", name);
  fascia_file *f = NULL;
  *st = fascia_file_open(ctx, what, path, &f);
  return f;
}

// The organ's surface where the simulation has put it
// (fascia_solver_organ_surface: deformable organs carried by their frames,
// driven ones by their first coupling frame), [3 vertex_count] to free;
// NULL when there is none.
static fascia_real *organ_now(const fascia_model *m, const fascia_solver *solver, int32_t k) {
  fascia_real *p = malloc(3 * sizeof(fascia_real) * ((size_t)m->organs[k].vertex_count + 1));
  if (p && fascia_solver_organ_surface(solver, k, p) != FASCIA_OK) free(p), p = NULL;
  return p;
}

_Static_assert(sizeof(fascia_real) == 8, "the VTK files declare Float64");

// Opens DIR/NAME (--paraview) for an UnstructuredGrid at `time` that shows
// `scalars` coloured and `vectors` for Warp By Vector when opened, and writes
// its points and cells (fascia_vtk_begin_piece); point data follows, then
// end_grid. NULL with *st saying why where it cannot be opened.
static fascia_file *begin_grid(fascia_ctx *ctx, const char *dir, const char *name, fascia_real time,
                               const char *scalars, const char *vectors, const fascia_real *points,
                               int64_t point_count, int nodes, const int32_t *cells, int64_t cell_count,
                               fascia_status *st) {
  fascia_file *file = open_file(ctx, "--paraview", dir, name, st);
  if (!file) return NULL;
  fascia_vtk_piece piece = fascia_vtk_piece_default();
  piece.time = time;
  piece.scalars = scalars;
  piece.vectors = vectors;
  fascia_vtk_begin_piece(fascia_file_stream(file), "UnstructuredGrid", &piece, points, point_count, nodes, cells,
                         cell_count);
  return file;
}

static fascia_status end_grid(fascia_file **file) {
  fascia_vtk_end(fascia_file_stream(*file), "UnstructuredGrid");
  return fascia_file_commit(file);
}

// One organ surface at its current pose: triangles in an UnstructuredGrid.
static fascia_status write_organ(fascia_ctx *ctx, const char *dir, const char *name, const fascia_organ *o,
                                 const fascia_real *positions, fascia_real time) {
  fascia_status st = FASCIA_OK;
  fascia_file *file =
      begin_grid(ctx, dir, name, time, NULL, NULL, positions, o->vertex_count, 3, o->triangles, o->triangle_count, &st);
  return file ? end_grid(&file) : st;
}

// The samples (tissue and deformable organs) at the solver's state as an
// UnstructuredGrid of vertices: displacement, rest position, strain, stress,
// volume, material and organ (-1 tissue), as in the results file.
static fascia_status write_samples(run_outputs *out, fascia_ctx *ctx, const fascia_model *m,
                                   const fascia_solver *solver, const char *name, fascia_real time) {
  const int64_t S = m->sample_count;
  fascia_solver_sample_positions(solver, out->positions);
  fascia_solver_sample_strain(solver, out->strain, out->stress);
  for (int64_t k = 0; k < 3 * S; ++k) out->scratch[k] = out->positions[k] - m->sample_position[k];
  fascia_status st = FASCIA_OK;
  fascia_file *file =
      begin_grid(ctx, out->paraview_dir, name, time, "strain", "displacement", out->positions, S, 1, NULL, S, &st);
  if (!file) return st;
  FILE *f = fascia_file_stream(file);
  fascia_vtk_array(f, "displacement", 3, out->scratch, NULL, S);
  fascia_vtk_array(f, "rest_position", 3, m->sample_position, NULL, S);
  fascia_vtk_array(f, "strain", 1, out->strain, NULL, S);
  fascia_vtk_array(f, "stress", 1, out->stress, NULL, S);
  fascia_vtk_array(f, "volume", 1, m->sample_volume, NULL, S);
  fascia_vtk_array(f, "material", 1, NULL, m->sample_material, S);
  fascia_vtk_array(f, "organ", 1, NULL, m->sample_organ, S);
  return end_grid(&file);
}

// The frames at the solver's state: displacement, rest position, their axes
// (three vectors, for Glyph), kind (0 free, 1 fixed, 2 prescribed), organ
// and the organ it is shared with (its first coupling).
static fascia_status write_frames(run_outputs *out, fascia_ctx *ctx, const fascia_model *m,
                                  const fascia_solver *solver, const char *name, fascia_real time) {
  const int64_t N = m->frame_count;
  const fascia_real *x = fascia_solver_frame_positions(solver);
  fascia_frame_axes(fascia_solver_frame_rotations(solver), N, out->axes);
  fascia_status st = FASCIA_OK;
  fascia_file *file = begin_grid(ctx, out->paraview_dir, name, time, NULL, "displacement", x, N, 1, NULL, N, &st);
  if (!file) return st;
  FILE *f = fascia_file_stream(file);
  for (int64_t k = 0; k < 3 * N; ++k) out->scratch[k] = x[k] - m->frame_position[k];
  fascia_vtk_array(f, "displacement", 3, out->scratch, NULL, N);
  fascia_vtk_array(f, "rest_position", 3, m->frame_position, NULL, N);
  static const char *const axis_names[3] = {"axis_x", "axis_y", "axis_z"};
  for (int c = 0; c < 3; ++c) {
    for (int64_t i = 0; i < N; ++i) memcpy(out->scratch + 3 * i, out->axes + 9 * i + 3 * c, 3 * sizeof(fascia_real));
    fascia_vtk_array(f, axis_names[c], 3, out->scratch, NULL, N);
  }
  fascia_vtk_array(f, "kind", 1, NULL, m->frame_kind, N);
  fascia_vtk_array(f, "organ", 1, NULL, m->frame_organ, N);
  fascia_vtk_array(f, "coupled_organ", 1, NULL, out->coupled_organ, N);
  return end_grid(&file);
}

// The tissue surface (model->tissue_surface) where the frames carry it, with
// its displacement and the strain of the sample nearest each vertex (shown).
static fascia_status write_tissue(run_outputs *out, fascia_ctx *ctx, const fascia_model *m,
                                  const fascia_solver *solver, const char *name, fascia_real time) {
  const fascia_surface *ts = &m->tissue_surface;
  const int64_t V = ts->vertex_count;
  fascia_real *x = malloc(3 * ((size_t)V + 1) * sizeof *x), *u = malloc(3 * ((size_t)V + 1) * sizeof *u);
  fascia_real *strain = malloc(((size_t)V + 1) * sizeof *strain);
  fascia_status st = x && u && strain ? fascia_solver_tissue_surface(solver, x, strain)
                                      : fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__,
                                                        "run: out of memory for the tissue surface");
  fascia_file *file = st == FASCIA_OK ? begin_grid(ctx, out->paraview_dir, name, time, "strain", "displacement", x, V,
                                                   3, ts->triangles, ts->triangle_count, &st)
                                      : NULL;
  if (file) {
    FILE *f = fascia_file_stream(file);
    for (int64_t k = 0; k < 3 * V; ++k) u[k] = x[k] - ts->vertices[k];
    fascia_vtk_array(f, "displacement", 3, u, NULL, V);
    fascia_vtk_array(f, "rest_position", 3, ts->vertices, NULL, V);
    fascia_vtk_array(f, "strain", 1, strain, NULL, V);
    st = end_grid(&file);
  }
  free(x), free(u), free(strain);
  return st;
}

// The tetrahedra of tet tissues (model->tetrahedra) on the frames as they
// are now, with the frames' displacement.
static fascia_status write_tetrahedra(run_outputs *out, fascia_ctx *ctx, const fascia_model *m,
                                      const fascia_solver *solver, const char *name, fascia_real time) {
  const int64_t N = m->frame_count;
  const fascia_real *x = fascia_solver_frame_positions(solver);
  fascia_status st = FASCIA_OK;
  fascia_file *file = begin_grid(ctx, out->paraview_dir, name, time, NULL, "displacement", x, N, 4, m->tetrahedra,
                                 m->tetrahedron_count, &st);
  if (!file) return st;
  for (int64_t k = 0; k < 3 * N; ++k) out->scratch[k] = x[k] - m->frame_position[k];
  fascia_vtk_array(fascia_file_stream(file), "displacement", 3, out->scratch, NULL, N);
  return end_grid(&file);
}

// A collection entry: names and file names are data, escaped.
static void pvd_entry(FILE *pvd, fascia_real time, int part, const char *name, const char *file) {
  fprintf(pvd, "    <DataSet timestep=\"%.17g\" group=\"\" part=\"%d\" name=\"", time, part);
  fascia_xml_text(pvd, name);
  fputs("\" file=\"", pvd);
  fascia_xml_text(pvd, file);
  fputs("\"/>\n", pvd);
}

// One saved step: the tissue surface, the samples, the frames and every
// organ at the solver's state, listed in run.pvd (all of them, named) and
// organs.pvd (the organs); the time as the results' XDMF writes it: one
// time per saved step in ParaView.
static fascia_status write_step(run_outputs *out, fascia_ctx *ctx, const fascia_model *m,
                                const fascia_solver *solver, fascia_real time) {
  FILE *run = fascia_file_stream(out->run_pvd), *organs = fascia_file_stream(out->pvd);
  char name[FASCIA_NAME_SIZE + 32];
  fascia_status st;
  int part = 0;
  if (m->tissue_surface.triangle_count > 0) {
    snprintf(name, sizeof name, "tissue-%04d.vtu", out->organ_steps);
    if ((st = write_tissue(out, ctx, m, solver, name, time)) != FASCIA_OK) return st;
    pvd_entry(run, time, part++, "tissue", name);
  }
  if (m->tetrahedron_count > 0) {
    snprintf(name, sizeof name, "tetrahedra-%04d.vtu", out->organ_steps);
    if ((st = write_tetrahedra(out, ctx, m, solver, name, time)) != FASCIA_OK) return st;
    pvd_entry(run, time, part++, "tetrahedra", name);
  }
  snprintf(name, sizeof name, "samples-%04d.vtu", out->organ_steps);
  if ((st = write_samples(out, ctx, m, solver, name, time)) != FASCIA_OK) return st;
  pvd_entry(run, time, part++, "samples", name);
  snprintf(name, sizeof name, "frames-%04d.vtu", out->organ_steps);
  if ((st = write_frames(out, ctx, m, solver, name, time)) != FASCIA_OK) return st;
  pvd_entry(run, time, part++, "frames", name);
  for (int32_t k = 0; k < m->organ_count; ++k) {
    // a fixed organ never moves: its first file serves every step
    const int fixed = m->organs[k].kind == FASCIA_ORGAN_FIXED;
    snprintf(name, sizeof name, "%s-%04d.vtu", m->organs[k].name, fixed ? 0 : out->organ_steps);
    if (!fixed || out->organ_steps == 0) {
      fascia_real *now = organ_now(m, solver, k);
      if (!now) continue;
      st = write_organ(ctx, out->paraview_dir, name, m->organs + k, now, fixed ? NAN : time); // for all steps: no time
      free(now);
      if (st != FASCIA_OK) return st;
    }
    pvd_entry(organs, time, (int)k, m->organs[k].name, name);
    pvd_entry(run, time, part++, m->organs[k].name, name);
  }
  out->organ_steps++;
  return FASCIA_OK;
}

// tissue-<tag>.csv and organs-<tag>.csv: samples with strain and stress,
// organ surface points (at most about 3000 per organ, evenly picked).
static fascia_status write_snapshot(run_outputs *out, fascia_ctx *ctx, const fascia_model *m,
                                    const fascia_solver *solver, const char *tag) {
  fascia_status st = FASCIA_OK;
  char name[64];
  snprintf(name, sizeof name, "tissue-%s.csv", tag);
  fascia_file *file = open_file(ctx, "--snapshots", out->snapshots_dir, name, &st);
  if (!file) return st;
  FILE *f = fascia_file_stream(file);
  fascia_solver_sample_positions(solver, out->positions);
  fascia_solver_sample_strain(solver, out->strain, out->stress);
  fprintf(f, "x_m,y_m,z_m,strain,stress_pa\n");
  for (int32_t s = 0; s < m->sample_count; ++s)
    fprintf(f, "%.9g,%.9g,%.9g,%.6g,%.6g\n", out->positions[3 * s], out->positions[3 * s + 1],
            out->positions[3 * s + 2], out->strain[s], out->stress[s]);
  if ((st = fascia_file_commit(&file)) != FASCIA_OK) return st;
  snprintf(name, sizeof name, "organs-%s.csv", tag);
  if (!(file = open_file(ctx, "--snapshots", out->snapshots_dir, name, &st))) return st;
  f = fascia_file_stream(file);
  fprintf(f, "organ,x_m,y_m,z_m\n");
  for (int32_t k = 0; k < m->organ_count; ++k) {
    fascia_real *now = organ_now(m, solver, k);
    if (!now) continue;
    const fascia_organ *o = m->organs + k;
    const int32_t stride = o->vertex_count > 3000 ? o->vertex_count / 3000 : 1;
    for (int32_t v = 0; v < o->vertex_count; v += stride) {
      const fascia_real *p = now + 3 * (int64_t)v;
      fprintf(f, "%d,%.9g,%.9g,%.9g\n", (int)k, p[0], p[1], p[2]);
    }
    free(now);
  }
  return fascia_file_commit(&file);
}

static fascia_real largest(const fascia_real *values, int32_t count) {
  fascia_real x = 0;
  for (int32_t s = 0; s < count; ++s)
    if (values[s] > x || values[s] != values[s]) x = values[s];
  return x;
}

static void free_arrays(run_outputs *out) {
  free(out->strain), free(out->stress), free(out->positions), free(out->scratch), free(out->axes),
      free(out->coupled_organ);
  out->coupled_organ = NULL;
  out->strain = out->stress = out->positions = out->scratch = out->axes = NULL;
}

fascia_status run_outputs_begin(run_outputs *out, fascia_ctx *ctx, const fascia_model *m, fascia_solver *solver,
                                fascia_real time) {
  out->ctx = ctx;
  out->model = m;
  if (!out->history_path && !out->paraview_dir && !out->snapshots_dir) return FASCIA_OK;
  const size_t S = (size_t)m->sample_count + 1, N = (size_t)m->frame_count + 1;
  out->strain = malloc(S * sizeof(fascia_real));
  out->stress = malloc(S * sizeof(fascia_real));
  out->positions = malloc(3 * S * sizeof(fascia_real));
  out->scratch = malloc(3 * (S > N ? S : N) * sizeof(fascia_real));
  out->axes = malloc(9 * N * sizeof(fascia_real));
  out->coupled_organ = malloc(N * sizeof(int32_t));
  if (!out->strain || !out->stress || !out->positions || !out->scratch || !out->axes || !out->coupled_organ)
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "run: out of memory for %d samples",
                           (int)m->sample_count);
  for (int32_t i = 0; i < m->frame_count; ++i) out->coupled_organ[i] = -1;
  for (int32_t c = m->coupling_count - 1; c >= 0; --c) out->coupled_organ[m->coupling_frame[c]] = m->coupling_organ[c];
  fascia_status st = FASCIA_OK;
  if (out->history_path) {
    if (!(out->history = open_file(ctx, "--history", NULL, out->history_path, &st))) return st;
    fprintf(fascia_file_stream(out->history), "step,time_s,potential_j,kinetic_j,newton,cg,ms,max_strain,max_stress_pa,converged\n");
  }
  if (out->snapshots_dir) {
    if ((st = make_dir(ctx, out->snapshots_dir)) != FASCIA_OK) return st;
    if ((st = write_snapshot(out, ctx, m, solver, "rest")) != FASCIA_OK) return st;
  }
  if (out->paraview_dir) {
    if ((st = make_dir(ctx, out->paraview_dir)) != FASCIA_OK) return st;
    if (!(out->pvd = open_file(ctx, "--paraview", out->paraview_dir, "organs.pvd", &st))) return st;
    if (!(out->run_pvd = open_file(ctx, "--paraview", out->paraview_dir, "run.pvd", &st))) return st;
    static const char head[] = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
    fputs(head, fascia_file_stream(out->pvd));
    fputs(head, fascia_file_stream(out->run_pvd));
    if ((st = write_step(out, ctx, m, solver, time)) != FASCIA_OK) return st;
  }
  return FASCIA_OK;
}

fascia_status run_outputs_step(run_outputs *out, fascia_solver *solver, int step, const fascia_solve_report *report,
                               double ms, int saved, fascia_real time) {
  fascia_ctx *ctx = out->ctx;
  const fascia_model *m = out->model;
  if (out->history) {
    fascia_real potential = NAN;
    (void)fascia_solver_potential_energy(solver, &potential);
    fascia_solver_sample_strain(solver, out->strain, out->stress);
    FILE *f = fascia_file_stream(out->history);
    fprintf(f, "%d,%.9g,%.9g,%.9g,%d,%d,%.4f,%.6g,%.6g,%d\n", step, fascia_solver_time(solver), potential,
            fascia_solver_kinetic_energy(solver), report->newton_iterations, report->cg_iterations, ms,
            largest(out->strain, m->sample_count), largest(out->stress, m->sample_count), report->converged);
    if (ferror(f)) return fascia_file_commit(&out->history); // a write failed: say why now, not at the end
  }
  if (out->pvd && saved) return write_step(out, ctx, m, solver, time);
  return FASCIA_OK;
}

void run_outputs_discard(run_outputs *out) {
  fascia_file_discard(&out->history);
  fascia_file_discard(&out->pvd);
  fascia_file_discard(&out->run_pvd);
  free_arrays(out);
}

fascia_status run_outputs_end(run_outputs *out, fascia_solver *solver, int ok) {
  fascia_ctx *ctx = out->ctx;
  const fascia_model *m = out->model;
  fascia_status st = FASCIA_OK;
  if (ok && out->snapshots_dir && out->positions) st = write_snapshot(out, ctx, m, solver, "final");
  // history and organs hold the steps done, also after a failed step: kept
  fascia_status hst = fascia_file_commit(&out->history);
  if (out->pvd) fprintf(fascia_file_stream(out->pvd), "  </Collection>\n</VTKFile>\n");
  if (out->run_pvd) fprintf(fascia_file_stream(out->run_pvd), "  </Collection>\n</VTKFile>\n");
  fascia_status pst = fascia_file_commit(&out->pvd), rst = fascia_file_commit(&out->run_pvd);
  if (st == FASCIA_OK) st = hst != FASCIA_OK ? hst : pst != FASCIA_OK ? pst : rst;
  free_arrays(out);
  return st;
}
