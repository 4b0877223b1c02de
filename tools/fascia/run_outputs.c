// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Extra outputs of `fascia run`:
//   --history FILE.csv  one row per step: time, energies, Newton and CG
//                       iterations, ms, largest strain and stress;
//   --organs DIR        each organ's surface moved by its pose (fixed,
//                       prescribed, rigid; a driven organ follows its first
//                       coupling frame) as VTK XML PolyData per saved
//                       step, with DIR/organs.pvd that ParaView opens as a
//                       time series next to the results' XDMF;
//   --snapshots DIR     CSV of the tissue samples (position, strain, stress)
//                       and of organ surface points, at rest and at the end,
//                       for the gnuplot scripts in tools/plots/.
#define _POSIX_C_SOURCE 200809L
#include "run_outputs.h"

#include "fascia/files.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

const char run_outputs_usage[] =
    "  --history FILE.csv     per-step history: time, energies, iterations, ms, largest strain\n"
    "  --organs DIR           organ surfaces moved by the simulation, per saved step, as\n"
    "                         DIR/<organ>-<k>.vtp and DIR/organs.pvd (ParaView)\n"
    "  --snapshots DIR        CSV of tissue samples and organ surface points at rest and at the end\n"
    "                         (DIR/tissue-rest.csv, tissue-final.csv, organs-rest.csv, organs-final.csv)\n";

int run_outputs_take(int *argc, char **argv, run_outputs *out) {
  memset(out, 0, sizeof *out);
  int kept = 1;
  for (int k = 1; k < *argc; ++k) {
    const char *o = argv[k];
    if (strcmp(o, "--history") && strcmp(o, "--organs") && strcmp(o, "--snapshots")) {
      argv[kept++] = argv[k];
      continue;
    }
    if (k + 1 >= *argc) {
      fprintf(stderr, "fascia run: option %s needs a value (see fascia run --help)\n", o);
      return 2;
    }
    const char *v = argv[++k];
    if (!strcmp(o, "--history")) out->history_path = v;
    else if (!strcmp(o, "--organs")) out->organs_dir = v;
    else out->snapshots_dir = v;
  }
  *argc = kept;
  return -1;
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

static int little_endian(void) {
  const uint16_t one = 1;
  unsigned char first;
  memcpy(&first, &one, 1);
  return first == 1;
}

// Base64 of a VTK binary block: a UInt32 byte count, then the data.
static void base64_block(FILE *f, const void *data, uint32_t bytes) {
  static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const size_t total = 4 + (size_t)bytes;
  unsigned char *buf = malloc(total);
  if (!buf) return;
  memcpy(buf, &bytes, 4);
  memcpy(buf + 4, data, bytes);
  for (size_t k = 0; k < total; k += 3) {
    const unsigned b0 = buf[k], b1 = k + 1 < total ? buf[k + 1] : 0, b2 = k + 2 < total ? buf[k + 2] : 0;
    fputc(tab[b0 >> 2], f);
    fputc(tab[((b0 & 3) << 4) | (b1 >> 4)], f);
    fputc(k + 1 < total ? tab[((b1 & 15) << 2) | (b2 >> 6)] : '=', f);
    fputc(k + 2 < total ? tab[b2 & 63] : '=', f);
  }
  free(buf);
}

// One organ surface at its current pose as VTK XML PolyData (binary inline).
static fascia_status write_vtp(fascia_ctx *ctx, const char *dir, const char *name, const fascia_organ *o,
                               const fascia_real *positions) {
  fascia_status st = FASCIA_OK;
  fascia_file *file = open_file(ctx, "--organs", dir, name, &st);
  if (!file) return st;
  FILE *f = fascia_file_stream(file);
  float *points = malloc(3 * sizeof(float) * (size_t)(o->vertex_count + 1));
  int32_t *offsets = malloc(sizeof(int32_t) * (size_t)(o->triangle_count + 1));
  if (!points || !offsets) {
    free(points), free(offsets), fascia_file_discard(&file);
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "run: out of memory for organ '%s'", o->name);
  }
  for (int32_t v = 0; v < 3 * o->vertex_count; ++v) points[v] = (float)positions[v];
  for (int32_t k = 0; k < o->triangle_count; ++k) offsets[k] = 3 * (k + 1);
  fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"%s\" "
             "header_type=\"UInt32\">\n<PolyData>\n<Piece NumberOfPoints=\"%d\" NumberOfPolys=\"%d\">\n",
          little_endian() ? "LittleEndian" : "BigEndian",
          (int)o->vertex_count, (int)o->triangle_count);
  fprintf(f, "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"binary\">");
  base64_block(f, points, 3 * sizeof(float) * (uint32_t)o->vertex_count);
  fprintf(f, "</DataArray></Points>\n<Polys><DataArray type=\"Int32\" Name=\"connectivity\" format=\"binary\">");
  base64_block(f, o->triangles, 3 * sizeof(int32_t) * (uint32_t)o->triangle_count);
  fprintf(f, "</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" format=\"binary\">");
  base64_block(f, offsets, sizeof(int32_t) * (uint32_t)o->triangle_count);
  fprintf(f, "</DataArray></Polys>\n</Piece>\n</PolyData>\n</VTKFile>\n");
  free(points), free(offsets);
  return fascia_file_commit(&file);
}

// Every organ at the solver's state, as step k of the PVD collection.
static fascia_status write_organs(run_outputs *out, fascia_ctx *ctx, const fascia_model *m,
                                  const fascia_solver *solver, fascia_real time) {
  for (int32_t k = 0; k < m->organ_count; ++k) {
    char name[FASCIA_NAME_SIZE + 32];
    // a fixed organ never moves: its first file serves every step
    const int fixed = m->organs[k].kind == FASCIA_ORGAN_FIXED;
    snprintf(name, sizeof name, "%s-%04d.vtp", m->organs[k].name, fixed ? 0 : out->organ_steps);
    if (!fixed || out->organ_steps == 0) {
      fascia_real *now = organ_now(m, solver, k);
      if (!now) continue;
      const fascia_status st = write_vtp(ctx, out->organs_dir, name, m->organs + k, now);
      free(now);
      if (st != FASCIA_OK) return st;
    }
    // the time as the results' XDMF writes it: one time per saved step in ParaView
    fprintf(fascia_file_stream(out->pvd), "    <DataSet timestep=\"%.17g\" group=\"\" part=\"%d\" name=\"%s\" file=\"%s\"/>\n",
            time, (int)k, m->organs[k].name, name);
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

fascia_status run_outputs_begin(run_outputs *out, fascia_ctx *ctx, const fascia_model *m, fascia_solver *solver,
                                fascia_real time) {
  out->ctx = ctx;
  out->model = m;
  if (!out->history_path && !out->organs_dir && !out->snapshots_dir) return FASCIA_OK;
  const size_t S = (size_t)m->sample_count + 1;
  out->strain = malloc(S * sizeof(fascia_real));
  out->stress = malloc(S * sizeof(fascia_real));
  out->positions = malloc(3 * S * sizeof(fascia_real));
  if (!out->strain || !out->stress || !out->positions)
    return fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "run: out of memory for %d samples",
                           (int)m->sample_count);
  fascia_status st = FASCIA_OK;
  if (out->history_path) {
    if (!(out->history = open_file(ctx, "--history", NULL, out->history_path, &st))) return st;
    fprintf(fascia_file_stream(out->history), "step,time_s,potential_j,kinetic_j,newton,cg,ms,max_strain,max_stress_pa,converged\n");
  }
  if (out->snapshots_dir) {
    if ((st = make_dir(ctx, out->snapshots_dir)) != FASCIA_OK) return st;
    if ((st = write_snapshot(out, ctx, m, solver, "rest")) != FASCIA_OK) return st;
  }
  if (out->organs_dir) {
    if ((st = make_dir(ctx, out->organs_dir)) != FASCIA_OK) return st;
    if (!(out->pvd = open_file(ctx, "--organs", out->organs_dir, "organs.pvd", &st))) return st;
    fprintf(fascia_file_stream(out->pvd), "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n");
    if ((st = write_organs(out, ctx, m, solver, time)) != FASCIA_OK) return st;
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
  if (out->pvd && saved) return write_organs(out, ctx, m, solver, time);
  return FASCIA_OK;
}

fascia_status run_outputs_end(run_outputs *out, fascia_solver *solver, int ok) {
  fascia_ctx *ctx = out->ctx;
  const fascia_model *m = out->model;
  fascia_status st = FASCIA_OK;
  if (ok && out->snapshots_dir && out->positions) st = write_snapshot(out, ctx, m, solver, "final");
  // history and organs hold the steps done, also after a failed step: kept
  fascia_status hst = fascia_file_commit(&out->history);
  if (out->pvd) fprintf(fascia_file_stream(out->pvd), "  </Collection>\n</VTKFile>\n");
  fascia_status pst = fascia_file_commit(&out->pvd);
  if (st == FASCIA_OK) st = hst != FASCIA_OK ? hst : pst;
  free(out->strain), free(out->stress), free(out->positions);
  out->strain = out->stress = out->positions = NULL;
  return st;
}
