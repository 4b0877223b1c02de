// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia tradeoff`: speed against accuracy, measured (tools/bench/README.md). Three groups of rows, each error against
// milliseconds and memory:
//   discretization  static tip deflection of the paper's cantilever (sec. 4.1)
//                   over shape kinds, frame grids, samples and neighbours, for
//                   three problems: the cantilever (E = 40 kPa, nu = 0.3), the
//                   same beam stiff (E = 4 MPa) and near-incompressible
//                   (nu = 0.49), each against its converged CalculiX reference
//                   (data/reference/); the Richardson extrapolation of
//                   fascia's own hexahedral refinement 10x2x2 -> 20x3x3 ->
//                   40x5x5 is printed beside it.
//   solver / timestep / preset
//                   implicit Euler on the 20x3x3 hexahedral cantilever from
//                   rest to t = T: tip uz(T) against the time-converged value
//                   (accurate Newton, dt 0.005 and 0.0025 extrapolated to
//                   dt -> 0: backward Euler is first order), over Newton
//                   iterations, linear solver, CG tolerance or fixed count,
//                   preconditioner, assembled or matrix-free, time step, and the
//                   presets of `fascia run --preset`.
// Every row runs on the CPU unless --backend says otherwise (its times are
// CPU figures); the backend and device of each row are in the CSV and JSON.
// Writes tradeoff.csv/.json, convergence.csv (paper Figure 3, with the
// CalculiX C3D8 figures), gnuplot scripts and, when gnuplot is on
// the PATH, pareto.png and convergence.png into --out DIR.
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "beam_calculix.h"
#include "commands.h"
#include "fascia/fascia.h"
#include "fascia/files.h"
#include "presets.h"
#include "scenes.h"
#include "tradeoff_scene.h"

static const char tradeoff_usage[] =
    "usage: fascia tradeoff [--out DIR] [--quick] [--repeats R] [--threads T] [--time T] [--json] [--no-plot]\n"
    "                       [--backend cpu|cuda|auto|emulated]\n"
    "       fascia tradeoff SCENE.json [...]   the trade on your own scene (fascia tradeoff SCENE.json --help)\n"
    "\n"
    "Sweeps the knobs that trade time for accuracy on the paper's cantilever and writes\n"
    "DIR/tradeoff.csv, tradeoff.json, convergence.csv, pareto.gp, convergence.gp and, with\n"
    "gnuplot on the PATH, pareto.png and convergence.png (error against ms, log-log, Pareto\n"
    "fronts; tip deflection against DOFs beside hexahedral FEM).\n"
    "  --out DIR      output folder (default .; created if absent)\n"
    "  --quick        fewer rows, no 40x5x5 grids (about a minute; the full sweep: about 5 minutes)\n"
    "  --repeats R    timing repeats, the minimum is reported (default 2; rows over 2 s run once)\n"
    "  --threads T    worker threads, 1 to 1024 (default 1)\n"
    "  --time T       dynamic rows: simulated time, s (default 0.3)\n"
    "  --json         also print the rows as one JSON array on stdout\n"
    "  --no-plot      write the gnuplot scripts but do not run gnuplot\n"
    "  --backend NAME cpu (default: the published tables are CPU figures), cuda, auto or emulated\n"
    "                 (the GPU solver in host loops: slow); rows the GPU solver cannot run (direct\n"
    "                 linear solver, assembled matrix) run on the CPU: the backend column says where\n";

#define MAX_ROWS 160
#define LONG_ROW_MS 2000.0 // rows slower than this are not repeated

enum { PROBLEM_CANTILEVER, PROBLEM_STIFF, PROBLEM_INCOMPRESSIBLE, PROBLEM_COUNT };
static const char *const problem_names[PROBLEM_COUNT] = {"cantilever", "stiff", "incompressible"};

/// One row: what was run and what it gave.
typedef struct row {
  const char *group, *preset; ///< preset NULL unless group "preset"
  int problem, dynamic, shape, spc, neighbours, reduced; ///< reduced: selective reduced integration
  int patch; ///< volumetric patches (FASCIA_SCENE_PATCH_*): mean dilatation per cell
  int32_t grid[3];
  fascia_solver_def solver;
  // results
  int frames, samples, newton, cg, converged, steps, pareto;
  double uz, reference, error_percent, ms, memory_mb, peak_mb;
  char backend[16], device[256]; ///< where it ran: fascia_solver_backend, fascia_solver_device
} row;

typedef struct tradeoff_options {
  const char *out, *backend;
  int quick, repeats, threads, json, plot;
  double time;
  fascia_ctx *ctx; ///< for the output files' messages
} tradeoff_options;

static const char *linear_name(const fascia_solver_def *d) {
  return d->linear_solver == FASCIA_LINEAR_CG ? "cg" : d->linear_solver == FASCIA_LINEAR_DIRECT ? "direct" : "auto";
}

static const char *precond_name(fascia_precond p) {
  return p == FASCIA_PRECOND_NONE ? "none" : p == FASCIA_PRECOND_JACOBI ? "jacobi" : "block";
}

static fascia_scene_beam_def beam_def(const row *r) {
  fascia_scene_beam_def b = fascia_scene_beam_def_of_shape(r->shape); // strands and sheets: their own frames
  memcpy(b.frames, r->grid, sizeof b.frames);
  if (r->shape == FASCIA_SCENE_TET) b.samples_per_tet = r->spc;
  else b.samples_per_cell_dir = r->spc;
  if (r->shape == FASCIA_SCENE_MESHLESS) b.neighbours = r->neighbours;
  if (r->problem == PROBLEM_STIFF) b.youngs_modulus = 4e6;
  if (r->problem == PROBLEM_INCOMPRESSIBLE) b.poisson_ratio = 0.49;
  b.reduced_volumetric = r->reduced;
  b.volumetric_patch = r->patch;
  b.enhanced_modes = -1; // fascia beam's rule: hex and tet patches carry their modes
  return b;
}

// Runs one row `repeats` times (once when slow), keeping the least time.
// Static rows: time per solve; dynamic rows: time per step over `time` s.
static fascia_status run_row(fascia_ctx *ctx, const tradeoff_options *opt, row *r) {
  const double base_mb = cli_resident_mb();
  fascia_scene_beam_def bdef = beam_def(r);
  fascia_model *model = NULL;
  fascia_solver *solver = NULL;
  fascia_status st = fascia_scene_beam_build(ctx, &bdef, &model);
  if (st != FASCIA_OK) return st;
  r->frames = model->frame_count;
  r->samples = model->sample_count;
  r->ms = INFINITY;
  const int32_t tip = fascia_model_find_probe(model, "tip");
  for (int k = 0; k < opt->repeats; ++k) {
    fascia_solver_destroy(&solver);
    st = fascia_solver_create(ctx, model, &r->solver, &solver);
    if (st == FASCIA_ERR_ARGUMENT && strcmp(r->solver.backend, "cpu")) { // settings the GPU solver refuses
      fascia_ctx_clear(ctx);
      r->solver.backend = "cpu";
      st = fascia_solver_create(ctx, model, &r->solver, &solver);
    }
    if (st != FASCIA_OK) goto cleanup;
    snprintf(r->backend, sizeof r->backend, "%s", fascia_solver_backend(solver));
    snprintf(r->device, sizeof r->device, "%s", fascia_solver_device(solver));
    fascia_solve_report rep;
    int newton = 0, cg = 0, converged = 1, steps = 0;
    const double t0 = cli_now_ms();
    if (!r->dynamic) {
      st = fascia_solver_solve_static(solver, &rep);
      if (st == FASCIA_ERR_NUMERIC && rep.newton_iterations > 0) st = FASCIA_OK; // unconverged: reported
      newton = rep.newton_iterations, cg = rep.cg_iterations, converged = rep.converged, steps = 1;
    } else {
      const int count = (int)lround(opt->time / r->solver.time_step);
      for (; steps < count && st == FASCIA_OK; ++steps) {
        st = fascia_solver_step(solver, &rep);
        newton += rep.newton_iterations, cg += rep.cg_iterations, converged &= rep.converged != 0;
      }
    }
    const double ms = (cli_now_ms() - t0) / (steps > 0 ? steps : 1);
    if (st != FASCIA_OK) goto cleanup;
    if (ms < r->ms) r->ms = ms;
    r->newton = newton, r->cg = cg, r->converged = converged, r->steps = steps;
    if (ms * steps > LONG_ROW_MS) break;
  }
  fascia_real p[3] = {NAN, NAN, NAN};
  if (tip >= 0) fascia_solver_probe_position(solver, tip, p);
  r->uz = tip >= 0 ? p[2] - model->probe_position[3 * tip + 2] : NAN;
  r->memory_mb = cli_resident_mb() - base_mb;
  r->peak_mb = cli_peak_mb();
cleanup:
  fascia_solver_destroy(&solver);
  fascia_model_destroy(&model);
  return st;
}

// ------------------------------------------------------------- the rows --

static row *add_row(row *rows, int *count, const char *group, int problem, int dynamic, int shape, const char *grid,
                    int spc, int neighbours) {
  if (*count == MAX_ROWS) return NULL;
  row *r = rows + (*count)++;
  memset(r, 0, sizeof *r);
  r->group = group, r->problem = problem, r->dynamic = dynamic, r->shape = shape, r->spc = spc;
  r->neighbours = shape == FASCIA_SCENE_MESHLESS ? neighbours : 0;
  fascia_scene_frames_parse(grid, r->grid); // "NX" strand, "NXxNY" sheet, "NXxNYxNZ"
  r->solver = fascia_solver_def_default();
  if (!dynamic) r->solver.newton_iterations = 100; // the static solve's limit (solver.h)
  return r;
}

// Static rows of one problem. The first three are the hexahedral refinement
// the Richardson references come from.
static void discretization_rows(row *rows, int *count, int problem, int quick) {
  static const char *const full[] = {"10x2x2", "20x3x3", "30x4x4", "40x5x5"};
  static const char *const small[] = {"10x2x2", "20x3x3"};
  const char *const *grids = quick ? small : full;
  const int n = quick ? 2 : 4;
  const int main_problem = problem == PROBLEM_CANTILEVER;
  for (int g = 0; g < n; ++g) {
    if (!main_problem && !strcmp(grids[g], "30x4x4")) continue; // only the convergence plot needs it
    if (problem == PROBLEM_INCOMPRESSIBLE && !strcmp(grids[g], "40x5x5")) continue; // hex: 166 s, unconverged
    add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_HEX, grids[g], 2, 0);
    add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_TET, grids[g], 4, 0);
    add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_MESHLESS, grids[g], 2, 8);
  }
  add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_MESHLESS, "10x2x2", 2, 16);
  add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_MESHLESS, "20x3x3", 2, 16);
  // selective reduced integration (after the full rows: the references are those)
  add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_HEX, "10x2x2", 2, 0)->reduced = 1;
  add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_HEX, "20x3x3", 2, 0)->reduced = 1;
  if (!quick && main_problem) add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_HEX, "40x5x5", 2, 0)->reduced = 1;
  // volumetric patches, the default of fascia beam (mean dilatation per cell)
  for (int g = 0; g < n; ++g) {
    if (!strcmp(grids[g], "30x4x4") || (problem == PROBLEM_INCOMPRESSIBLE && !strcmp(grids[g], "40x5x5"))) continue;
    add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_HEX, grids[g], 2, 0)->patch = FASCIA_SCENE_PATCH_CELL;
    add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_TET, grids[g], 4, 0)->patch = FASCIA_SCENE_PATCH_CELL;
    add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_MESHLESS, grids[g], 2, 8)->patch = FASCIA_SCENE_PATCH_CELL;
  }
  add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_MESHLESS, "20x3x3", 2, 16)->patch = FASCIA_SCENE_PATCH_CELL;
  // lower dimensions: the strand (1-D) and the sheet (2-D), one station per interval
  static const char *const strands[] = {"10", "20", "40"}, *const sheets[] = {"10x2", "20x3", "40x5"};
  for (int g = quick ? 1 : 0; g < 3; ++g) {
    add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_STRAND, strands[g], 1, 0);
    add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_SHEET, sheets[g], 1, 0);
  }
  if (!main_problem) return;
  add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_HEX, "20x3x3", 1, 0);
  add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_HEX, "20x3x3", 3, 0);
  add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_TET, "20x3x3", 1, 0);
  add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_MESHLESS, "20x3x3", 3, 16);
  add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_MESHLESS, "20x3x3", 2, 12);
  if (!quick) add_row(rows, count, "discretization", problem, 0, FASCIA_SCENE_MESHLESS, "40x5x5", 2, 16);
}

static row *dyn(row *rows, int *count, const char *group) {
  return add_row(rows, count, group, PROBLEM_CANTILEVER, 1, FASCIA_SCENE_HEX, "20x3x3", 2, 0);
}

// Dynamic rows on the 20x3x3 hexahedral cantilever, dt = 0.01 s unless set.
static void dynamic_rows(row *rows, int *count, int quick) {
  row *r;
  // the time-converged reference: accurate Newton at dt 0.005 and 0.0025
  for (int k = 0; k < 2; ++k) {
    r = dyn(rows, count, "reference");
    r->solver.time_step = k == 0 ? 0.005 : 0.0025;
    r->solver.newton_tolerance = 1e-10;
    r->solver.linear_solver = FASCIA_LINEAR_DIRECT;
  }
  static const double dts[] = {0.1, 0.05, 0.02, 0.01, 0.005};
  for (int k = quick ? 1 : 0; k < 5; ++k) dyn(rows, count, "timestep")->solver.time_step = dts[k];
  for (int newton = 1; newton <= 3; ++newton) { // capped Newton: unconverged steps are the trade
    r = dyn(rows, count, "solver");
    r->solver.newton_iterations = newton;
    r->solver.require_convergence = 0;
  }
  static const double tolerances[] = {1e-1, 1e-2, 1e-3, 1e-5};
  for (int k = 0; k < 4; ++k) {
    if (quick && k != 2) continue;
    r = dyn(rows, count, "solver");
    r->solver.linear_solver = FASCIA_LINEAR_CG;
    r->solver.cg_tolerance = tolerances[k];
  }
  r = dyn(rows, count, "solver");
  r->solver.linear_solver = FASCIA_LINEAR_CG, r->solver.assembled = 1, r->solver.single_precision_matrix = 0;
  r = dyn(rows, count, "solver"); // float or double: the assembled matrix in float
  r->solver.linear_solver = FASCIA_LINEAR_CG, r->solver.assembled = 1, r->solver.single_precision_matrix = 1;
  for (int p = FASCIA_PRECOND_NONE; p <= FASCIA_PRECOND_JACOBI && !quick; ++p) {
    r = dyn(rows, count, "solver");
    r->solver.linear_solver = FASCIA_LINEAR_CG, r->solver.precond = (fascia_precond)p;
  }
  static const int fixed[] = {5, 20, 60};
  for (int k = 0; k < 3; ++k) { // the paper's mode and cheaper
    r = dyn(rows, count, "solver");
    r->solver.linear_solver = FASCIA_LINEAR_CG, r->solver.cg_fixed = 1, r->solver.cg_iterations = fixed[k];
    r->solver.newton_iterations = 1;
    r->solver.require_convergence = 0;
  }
  int preset_count = 0;
  const fascia_preset *presets = cli_presets(&preset_count);
  for (int k = 0; k < preset_count; ++k) {
    r = dyn(rows, count, "preset");
    r->preset = presets[k].name;
    cli_preset_apply(presets[k].name, &r->solver);
  }
}

// Richardson extrapolation of three values on grids refined by about 2:
// observed order p from the differences, limit u3 + (u3 - u2) / (2^p - 1).
// Falls back to the finest value when the differences do not shrink.
static double richardson(double u1, double u2, double u3, double *order) {
  const double d1 = u2 - u1, d2 = u3 - u2;
  *order = NAN;
  if (d1 == 0 || d2 == 0 || d1 * d2 < 0 || fabs(d2) >= fabs(d1)) return u3;
  *order = log2(d1 / d2);
  return u3 + d2 / (pow(2, *order) - 1);
}

static const row *find_row(const row *rows, int count, int problem, int shape, const char *grid) {
  char text[32];
  for (int k = 0; k < count; ++k) {
    snprintf(text, sizeof text, "%dx%dx%d", (int)rows[k].grid[0], (int)rows[k].grid[1], (int)rows[k].grid[2]);
    if (!rows[k].dynamic && rows[k].problem == problem && rows[k].shape == shape && !strcmp(text, grid) &&
        rows[k].spc == (shape == FASCIA_SCENE_TET ? 4 : 2) && (shape != FASCIA_SCENE_MESHLESS || rows[k].neighbours == 8))
      return rows + k;
  }
  return NULL;
}

// The converged CalculiX tip uz of a problem's beam (data/reference/), NAN if none.
static double calculix_uz(int problem) {
  row r;
  memset(&r, 0, sizeof r);
  r.problem = problem;
  const fascia_scene_beam_def b = beam_def(&r);
  const fascia_ccx_reference *ref = fascia_ccx_reference_find(&b);
  return ref ? ref->tip_uz : NAN;
}

// References: the CalculiX values, Richardson of the hexahedral refinement
// where there is none; the dynamic reference dt -> 0 from its two rows.
static void set_references(row *rows, int count, int quick, double references[PROBLEM_COUNT],
                           double extrapolated[PROBLEM_COUNT], double orders[PROBLEM_COUNT], double *dynamic_ref) {
  for (int p = 0; p < PROBLEM_COUNT; ++p) {
    orders[p] = NAN;
    const row *a = find_row(rows, count, p, FASCIA_SCENE_HEX, "10x2x2"), *b = find_row(rows, count, p, FASCIA_SCENE_HEX, "20x3x3"),
              *c = find_row(rows, count, p, FASCIA_SCENE_HEX, quick ? "20x3x3" : "40x5x5");
    extrapolated[p] = a && b && c ? richardson(a->uz, b->uz, c->uz, orders + p) : NAN;
    references[p] = isfinite(calculix_uz(p)) ? calculix_uz(p) : extrapolated[p];
  }
  double coarse = NAN, fine = NAN;
  for (int k = 0; k < count; ++k)
    if (!strcmp(rows[k].group, "reference")) *(rows[k].solver.time_step > 0.004 ? &coarse : &fine) = rows[k].uz;
  *dynamic_ref = 2 * fine - coarse; // backward Euler: first order in dt
  for (int k = 0; k < count; ++k) {
    row *r = rows + k;
    r->reference = r->dynamic ? *dynamic_ref : references[r->problem];
    r->error_percent = 100 * fabs(r->uz - r->reference) / fabs(r->reference);
  }
}

// Marks the rows no other row of the same set (static: problem; dynamic)
// beats in both error and time.
static void mark_pareto(row *rows, int count) {
  for (int k = 0; k < count; ++k) {
    row *r = rows + k;
    r->pareto = strcmp(r->group, "reference") != 0;
    for (int j = 0; j < count && r->pareto; ++j) {
      const row *o = rows + j;
      if (j == k || o->dynamic != r->dynamic || o->problem != r->problem || !strcmp(o->group, "reference")) continue;
      if (o->error_percent <= r->error_percent && o->ms <= r->ms &&
          (o->error_percent < r->error_percent || o->ms < r->ms))
        r->pareto = 0;
    }
  }
}

// ---------------------------------------------------------------- output --

static void row_label(const row *r, char *out, size_t size) {
  char grid[32];
  snprintf(grid, sizeof grid, "%dx%dx%d", (int)r->grid[0], (int)r->grid[1], (int)r->grid[2]);
  if (!r->dynamic) {
    const char *volumetric = r->reduced ? " sri" : r->patch ? " patches" : "";
    if (r->shape == FASCIA_SCENE_MESHLESS)
      snprintf(out, size, "meshless %s k%d s%d%s", grid, r->neighbours, r->spc, volumetric);
    else snprintf(out, size, "%s %s s%d%s", fascia_scene_shape_name(r->shape), grid, r->spc, volumetric);
  } else if (r->preset) {
    snprintf(out, size, "preset %s", r->preset);
  } else {
    const fascia_solver_def *d = &r->solver;
    if (d->linear_solver == FASCIA_LINEAR_CG && d->cg_fixed)
      snprintf(out, size, "dt %g newton %d cg %d fixed", d->time_step, d->newton_iterations, d->cg_iterations);
    else if (d->linear_solver == FASCIA_LINEAR_CG)
      snprintf(out, size, "dt %g newton %d cg %s tol %g%s", d->time_step, d->newton_iterations,
               precond_name(d->precond), d->cg_tolerance,
               d->single_precision_matrix == 1 ? " assembled float" : d->assembled == 1 ? " assembled" : "");
    else snprintf(out, size, "dt %g newton %d %s", d->time_step, d->newton_iterations, linear_name(d));
  }
}

static const char csv_header[] =
    "group,problem,mode,label,shape,grid,frames,dofs,samples,samples_per_cell,neighbours,dt,newton_iterations,"
    "newton_tolerance,linear_solver,assembled,precond,cg_iterations,cg_fixed,cg_tolerance,tip_uz,reference_uz,"
    "error_percent,ms,ms_unit,newton_total,cg_total,converged,memory_mb,peak_memory_mb,pareto,volumetric,backend,"
    "device\n";

static void csv_row(FILE *f, const row *r) {
  char label[96], grid[32];
  row_label(r, label, sizeof label);
  snprintf(grid, sizeof grid, "%dx%dx%d", (int)r->grid[0], (int)r->grid[1], (int)r->grid[2]);
  const fascia_solver_def *d = &r->solver;
  fprintf(f, "%s,%s,%s,%s,%s,%s,%d,%d,%d,%d,%d,%g,%d,%g,%s,%d,%s,%d,%d,%g,%.6f,%.6f,%.4f,%.3f,%s,%d,%d,%d,%.2f,%.1f,%d",
          r->group, problem_names[r->problem], r->dynamic ? "dynamic" : "static", label,
          fascia_scene_shape_name(r->shape), grid, r->frames, 6 * r->frames, r->samples, r->spc, r->neighbours,
          r->dynamic ? d->time_step : 0.0, d->newton_iterations, d->newton_tolerance, linear_name(d), d->assembled,
          precond_name(d->precond), d->cg_iterations, d->cg_fixed, d->cg_tolerance, r->uz, r->reference,
          r->error_percent, r->ms, r->dynamic ? "per_step" : "per_solve", r->newton, r->cg, r->converged,
          r->memory_mb, r->peak_mb, r->pareto);
  fprintf(f, ",%s,%s,", r->reduced ? "reduced" : fascia_scene_patch_name(r->patch), r->backend);
  cli_csv_text(f, r->device);
  fputc('\n', f);
}

static cJSON *json_row(const row *r) {
  char label[96], grid[32];
  row_label(r, label, sizeof label);
  snprintf(grid, sizeof grid, "%dx%dx%d", (int)r->grid[0], (int)r->grid[1], (int)r->grid[2]);
  const fascia_solver_def *d = &r->solver;
  cJSON *o = cJSON_CreateObject();
  cJSON_AddStringToObject(o, "group", r->group);
  cJSON_AddStringToObject(o, "problem", problem_names[r->problem]);
  cJSON_AddStringToObject(o, "mode", r->dynamic ? "dynamic" : "static");
  cJSON_AddStringToObject(o, "label", label);
  if (r->preset) cJSON_AddStringToObject(o, "preset", r->preset);
  cJSON_AddStringToObject(o, "shape", fascia_scene_shape_name(r->shape));
  cJSON_AddStringToObject(o, "grid", grid);
  cJSON_AddNumberToObject(o, "frames", r->frames);
  cJSON_AddNumberToObject(o, "dofs", 6 * r->frames);
  cJSON_AddNumberToObject(o, "samples", r->samples);
  cJSON_AddNumberToObject(o, "samples_per_cell", r->spc);
  cJSON_AddNumberToObject(o, "neighbours", r->neighbours);
  if (r->dynamic) cJSON_AddNumberToObject(o, "dt", d->time_step);
  cJSON_AddNumberToObject(o, "newton_iterations", d->newton_iterations);
  cJSON_AddNumberToObject(o, "newton_tolerance", d->newton_tolerance);
  cJSON_AddStringToObject(o, "linear_solver", linear_name(d));
  cJSON_AddBoolToObject(o, "assembled", d->assembled);
  cJSON_AddStringToObject(o, "precond", precond_name(d->precond));
  cJSON_AddNumberToObject(o, "cg_iterations", d->cg_iterations);
  cJSON_AddBoolToObject(o, "cg_fixed", d->cg_fixed);
  cJSON_AddNumberToObject(o, "cg_tolerance", d->cg_tolerance);
  cJSON_AddNumberToObject(o, "tip_uz", r->uz);
  cJSON_AddNumberToObject(o, "reference_uz", r->reference);
  cJSON_AddNumberToObject(o, "error_percent", r->error_percent);
  cJSON_AddNumberToObject(o, r->dynamic ? "ms_per_step" : "ms_per_solve", r->ms);
  cJSON_AddNumberToObject(o, "newton_total", r->newton);
  cJSON_AddNumberToObject(o, "cg_total", r->cg);
  cJSON_AddBoolToObject(o, "converged", r->converged);
  cJSON_AddNumberToObject(o, "memory_mb", r->memory_mb);
  cJSON_AddNumberToObject(o, "peak_memory_mb", r->peak_mb);
  cJSON_AddBoolToObject(o, "pareto", r->pareto);
  cJSON_AddStringToObject(o, "backend", r->backend);
  cJSON_AddStringToObject(o, "device", r->device);
  return o;
}

// The files of --out DIR, each written under a temporary name and renamed
// when complete (fascia/files.h); a failure is reported, and nothing left.
static const char *const out_names[] = {"tradeoff.csv", "tradeoff.json", "convergence.csv", "pareto.gp",
                                        "convergence.gp", "pareto.png", "convergence.png",
                                        "points_static_cantilever.dat", "front_static_cantilever.dat",
                                        "points_static_stiff.dat", "front_static_stiff.dat",
                                        "points_static_incompressible.dat", "front_static_incompressible.dat",
                                        "points_dynamic_cantilever.dat", "front_dynamic_cantilever.dat", NULL};

fascia_file *cli_tradeoff_open(fascia_ctx *ctx, const char *dir, const char *name) {
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  fascia_file *f = NULL;
  const fascia_status st = fascia_file_open(ctx, "--out", path, &f);
  if (st != FASCIA_OK) cli_fail("tradeoff", ctx, st);
  return f;
}

int cli_tradeoff_commit(fascia_ctx *ctx, fascia_file *f) {
  const fascia_status st = fascia_file_commit(&f);
  return st == FASCIA_OK ? 0 : cli_fail("tradeoff", ctx, st);
}

static fascia_file *open_out(const tradeoff_options *opt, const char *name) {
  return cli_tradeoff_open(opt->ctx, opt->out, name);
}

// Finishes f: 0, else 1 after the message (nothing left under its name).
static int close_out(const tradeoff_options *opt, fascia_file *f) { return cli_tradeoff_commit(opt->ctx, f); }

int cli_tradeoff_write_points(fascia_ctx *ctx, const char *dir, const char *points_name, const char *front_name,
                              const char *columns, const cli_tradeoff_point *points, int count) {
  int *order = malloc((size_t)(count > 0 ? count : 1) * sizeof *order);
  if (!order) {
    fprintf(stderr, "fascia tradeoff: out of memory for %d points\n", count);
    return 1;
  }
  fascia_file *pf = cli_tradeoff_open(ctx, dir, points_name);
  fascia_file *ff = pf ? cli_tradeoff_open(ctx, dir, front_name) : NULL;
  if (!ff) {
    fascia_file_discard(&pf);
    free(order);
    return 1;
  }
  FILE *p = fascia_file_stream(pf), *f = fascia_file_stream(ff);
  fprintf(p, "# %s\n", columns);
  fprintf(f, "# %s (Pareto front, by time)\n", columns);
  int n = 0;
  for (int k = 0; k < count; ++k) {
    fprintf(p, "%.4f %.6g \"%s\"\n", points[k].ms, points[k].error, points[k].label);
    if (points[k].pareto) order[n++] = k;
  }
  for (int a = 1; a < n; ++a) // insertion sort by time, ties in their order
    for (int b = a; b > 0 && points[order[b]].ms < points[order[b - 1]].ms; --b) {
      const int t = order[b];
      order[b] = order[b - 1], order[b - 1] = t;
    }
  for (int k = 0; k < n; ++k)
    fprintf(f, "%.4f %.6g \"%s\"\n", points[order[k]].ms, points[order[k]].error, points[order[k]].label);
  free(order);
  const int rc = cli_tradeoff_commit(ctx, pf);
  return cli_tradeoff_commit(ctx, ff) | rc;
}

// Point files for gnuplot: all rows of a set, and its front sorted by time.
static int write_points(const tradeoff_options *opt, const row *rows, int count, int dynamic, int problem) {
  char labels[MAX_ROWS][96];
  cli_tradeoff_point points[MAX_ROWS];
  int n = 0;
  for (int k = 0; k < count; ++k)
    if (rows[k].dynamic == dynamic && rows[k].problem == problem && strcmp(rows[k].group, "reference")) {
      row_label(rows + k, labels[n], sizeof labels[n]);
      points[n] = (cli_tradeoff_point){rows[k].ms, fmax(rows[k].error_percent, 1e-6), labels[n], rows[k].pareto};
      ++n;
    }
  char points_name[96], front_name[96];
  const char *mode = dynamic ? "dynamic" : "static";
  snprintf(points_name, sizeof points_name, "points_%s_%s.dat", mode, problem_names[problem]);
  snprintf(front_name, sizeof front_name, "front_%s_%s.dat", mode, problem_names[problem]);
  return cli_tradeoff_write_points(opt->ctx, opt->out, points_name, front_name, "ms error_percent label", points, n);
}

// Hexahedral FEM on the same problem (CalculiX C3D8, nonlinear).
static const struct {
  const char *grid;
  int dofs;
  double error_percent;
} c3d8[] = {{"16x1x1", 192, -29.96}, {"32x2x2", 864, -9.79}, {"64x4x4", 4800, -2.73},
            {"96x6x6", 14112, -1.27}, {"128x8x8", 31104, -0.74}};
#define C3D8_REFERENCE (-6.5106)

static int write_convergence(const tradeoff_options *opt, const row *rows, int count) {
  fascia_file *file = open_out(opt, "convergence.csv");
  if (!file) return 1;
  FILE *f = fascia_file_stream(file);
  fprintf(f, "method,grid,dofs,tip_uz,error_percent\n");
  for (int s = 0; s < FASCIA_SCENE_SHAPE_COUNT_; ++s)
    for (int k = 0; k < count; ++k) {
      const row *r = rows + k;
      if (r->dynamic || r->problem != PROBLEM_CANTILEVER || r->shape != s || r->reduced ||
          r->spc != (s == FASCIA_SCENE_TET ? 4 : fascia_scene_shape_dimension(s) < 3 ? 1 : 2) ||
          (s == FASCIA_SCENE_MESHLESS && r->neighbours != 8))
        continue;
      fprintf(f, "fascia-%s%s,%dx%dx%d,%d,%.6f,%.4f\n", fascia_scene_shape_name(s), r->patch ? "-patches" : "",
              (int)r->grid[0], (int)r->grid[1],
              (int)r->grid[2], 6 * r->frames, r->uz,
              100 * (r->uz - calculix_uz(PROBLEM_CANTILEVER)) / fabs(calculix_uz(PROBLEM_CANTILEVER)));
    }
  for (size_t k = 0; k < sizeof c3d8 / sizeof c3d8[0]; ++k) // error < 0: too stiff, as the tables sign it
    fprintf(f, "calculix-c3d8,%s,%d,%.6f,%.4f\n", c3d8[k].grid, c3d8[k].dofs,
            C3D8_REFERENCE * (1 + c3d8[k].error_percent / 100), -c3d8[k].error_percent);
  return close_out(opt, file);
}

static int write_plot_scripts(const tradeoff_options *opt) {
  fascia_file *file = open_out(opt, "pareto.gp");
  if (!file) return 1;
  FILE *f = fascia_file_stream(file);
  fputs("# fascia tradeoff: error against time, log-log, with Pareto fronts (gnuplot pareto.gp)\n"
        "set terminal pngcairo size 1400,600 font ',10'\nset output 'pareto.png'\n"
        "set datafile separator whitespace\nset logscale xy\nset grid\nset key outside bottom center horizontal\n"
        "set multiplot layout 1,2\n"
        "set title 'static tip deflection (discretization)'\nset xlabel 'ms per static solve'\n"
        "set ylabel 'tip uz error, % of the reference'\n"
        "plot for [p in 'cantilever stiff incompressible'] 'points_static_'.p.'.dat' u 1:2 w p pt 7 ps 0.8 t p, \\\n"
        "     for [p in 'cantilever stiff incompressible'] 'front_static_'.p.'.dat' u 1:2 w l lw 2 t p.' front', \\\n"
        "     'front_static_cantilever.dat' u 1:2:3 w labels left offset 0.5,0.3 font ',7' notitle\n"
        "set title 'implicit Euler, 20x3x3 hex cantilever (solver, time step, presets)'\n"
        "set xlabel 'ms per step'\nset ylabel 'tip uz(T) error, % of the dt -> 0 value'\n"
        "plot 'points_dynamic_cantilever.dat' u 1:2 w p pt 7 ps 0.8 t 'rows', \\\n"
        "     'front_dynamic_cantilever.dat' u 1:2 w l lw 2 t 'front', \\\n"
        "     'front_dynamic_cantilever.dat' u 1:2:3 w labels left offset 0.5,0.3 font ',7' notitle\n"
        "unset multiplot\n",
        f);
  if (close_out(opt, file) || !(file = open_out(opt, "convergence.gp"))) return 1;
  f = fascia_file_stream(file);
  fputs("# tip deflection against DOFs, like Figure 3 of Bosman et al. 2013 (gnuplot convergence.gp)\n"
        "set terminal pngcairo size 900,600 font ',10'\nset output 'convergence.png'\n"
        "set datafile separator ','\nset logscale x\nset grid\nset key bottom right\n"
        "set xlabel 'degrees of freedom (fascia: 6 x frames; FEM: 3 x nodes)'\nset ylabel 'tip uz (m)'\n",
        f);
  fprintf(f,
          "set title 'cantilever 16 x 1 x 1 m, static, StVK: reference uz = %.4f m'\n"
          "plot %.5f w l dt 2 lc 'black' t 'converged FE reference (CalculiX)', \\\n"
          "  for [m in 'fascia-hex fascia-tet fascia-meshless fascia-hex-patches fascia-tet-patches "
          "fascia-meshless-patches calculix-c3d8'] 'convergence.csv' "
          "u (strcol(1) eq m ? $3 : NaN):4 w lp pt 7 lw 2 t m\n",
          calculix_uz(PROBLEM_CANTILEVER), calculix_uz(PROBLEM_CANTILEVER));
  return close_out(opt, file);
}

int cli_tradeoff_gnuplot(const char *dir, const char *const *scripts) {
  if (system("command -v gnuplot > /dev/null 2>&1") != 0) {
    fprintf(stderr, "fascia tradeoff: gnuplot not found; the scripts are in %s (gnuplot %s)\n", dir, scripts[0]);
    return 0;
  }
  char command[8192];
  int n = snprintf(command, sizeof command, "cd '%s'", dir);
  for (int k = 0; scripts[k] && n > 0 && n < (int)sizeof command; ++k)
    n += snprintf(command + n, sizeof command - (size_t)n, " && gnuplot %s", scripts[k]);
  if (system(command) != 0) {
    fprintf(stderr, "fascia tradeoff: gnuplot failed in %s\n", dir);
    return 1;
  }
  return 0;
}

static int run_gnuplot(const tradeoff_options *opt) {
  static const char *const scripts[] = {"pareto.gp", "convergence.gp", NULL};
  return cli_tradeoff_gnuplot(opt->out, scripts);
}

// ------------------------------------------------------------------ main --

static int parse_options(int argc, char **argv, tradeoff_options *opt) {
  memset(opt, 0, sizeof *opt);
  opt->out = ".", opt->repeats = 2, opt->threads = 1, opt->plot = 1, opt->time = 0.3;
  opt->backend = "cpu"; // the published tables are CPU figures
  for (int k = 1; k < argc; ++k) {
    const char *o = argv[k];
    if (cli_help(o, tradeoff_usage, NULL)) return 0;
    if (!strcmp(o, "--verbose")) continue;
    if (!strcmp(o, "--quick")) opt->quick = 1;
    else if (!strcmp(o, "--json")) opt->json = 1;
    else if (!strcmp(o, "--no-plot")) opt->plot = 0;
    else if (!strcmp(o, "--out") || !strcmp(o, "--repeats") || !strcmp(o, "--threads") || !strcmp(o, "--time") ||
             !strcmp(o, "--backend")) {
      if (k + 1 >= argc) {
        fprintf(stderr, "fascia tradeoff: option %s needs a value (see fascia tradeoff --help)\n", o);
        return 2;
      }
      const char *v = argv[++k];
      char *end = NULL;
      int ok = 1;
      if (!strcmp(o, "--out")) opt->out = v;
      else if (!strcmp(o, "--backend")) ok = cli_parse_backend(v, &opt->backend);
      else if (!strcmp(o, "--time")) opt->time = strtod(v, &end), ok = *end == 0 && opt->time >= 0.01 && opt->time <= 100;
      else if (!strcmp(o, "--threads")) ok = cli_parse_threads(v, &opt->threads);
      else {
        const long x = strtol(v, &end, 10);
        ok = *v && *end == 0 && x >= 1 && x <= 1000;
        opt->repeats = (int)x;
      }
      if (!ok) {
        fprintf(stderr, "fascia tradeoff: bad value '%s' for %s%s (see fascia tradeoff --help)\n", v, o,
                !strcmp(o, "--threads") ? ": expected a whole number from 1 to " CLI_MAX_THREADS_TEXT : "");
        return 2;
      }
    } else {
      fprintf(stderr, "fascia tradeoff: unknown option '%s' (see fascia tradeoff --help)\n", o);
      return 2;
    }
  }
  return -1;
}

static void print_row(const row *r) {
  char label[96];
  row_label(r, label, sizeof label);
  printf("%-14s %-14s %-7s %-40s %6d %10.5f %10.5f %9.3f %10.2f %s\n", r->group, problem_names[r->problem],
         r->dynamic ? "dynamic" : "static", label, 6 * r->frames, r->uz, r->reference, r->error_percent, r->ms,
         r->pareto ? "*" : "");
}

// Where the rows ran: the first row's backend and device, and how many rows
// ran elsewhere (on the CPU where the GPU solver refuses their settings).
static void print_backends(const row *rows, int count) {
  int elsewhere = 0;
  for (int k = 1; k < count; ++k) elsewhere += strcmp(rows[k].backend, rows[0].backend) != 0;
  printf("backend: %s; device: %s\n", rows[0].backend, rows[0].device);
  if (elsewhere) printf("         %d rows ran on another backend (see the backend column of tradeoff.csv)\n", elsewhere);
}

int cmd_tradeoff(int argc, char **argv) {
  if (cli_tradeoff_scene_wanted(argc, argv)) return cmd_tradeoff_scene(argc, argv); // fascia tradeoff SCENE.json
  tradeoff_options opt;
  int rc = parse_options(argc, argv, &opt);
  if (rc >= 0) return rc;
  const cli_path out = {"--out", opt.out, CLI_OUTPUT_DIR, out_names, NULL};
  if ((rc = cli_check_paths("tradeoff", &out, 1)) >= 0) return rc; // before minutes of rows
  if (mkdir(opt.out, 0777) != 0 && errno != EEXIST) {
    fprintf(stderr, "fascia tradeoff: cannot create folder '%s': %s\n", opt.out, strerror(errno));
    return 1;
  }
  row *rows = calloc(MAX_ROWS, sizeof *rows);
  if (!rows) {
    fprintf(stderr, "fascia tradeoff: out of memory\n");
    return 1;
  }
  int count = 0;
  for (int p = 0; p < PROBLEM_COUNT; ++p) discretization_rows(rows, &count, p, opt.quick);
  dynamic_rows(rows, &count, opt.quick);
  fascia_ctx *ctx = cli_ctx(opt.threads, 0);
  opt.ctx = ctx;
  for (int k = 0; k < count; ++k) {
    rows[k].solver.threads = opt.threads;
    rows[k].solver.backend = opt.backend;
    char label[96];
    row_label(rows + k, label, sizeof label);
    fprintf(stderr, "\rtradeoff %d/%d: %s %s\033[K", k + 1, count, problem_names[rows[k].problem], label);
    const fascia_status st = run_row(ctx, &opt, rows + k);
    if (st != FASCIA_OK) {
      fprintf(stderr, "\n");
      rc = cli_solver_fail("tradeoff", rows[k].solver.backend, ctx, st);
      goto done;
    }
  }
  fprintf(stderr, "\r\033[K");
  double references[PROBLEM_COUNT], extrapolated[PROBLEM_COUNT], orders[PROBLEM_COUNT], dynamic_ref;
  set_references(rows, count, opt.quick, references, extrapolated, orders, &dynamic_ref);
  mark_pareto(rows, count);
  printf("references: ");
  for (int p = 0; p < PROBLEM_COUNT; ++p)
    printf("%s uz %.5f m (hex Richardson %.5f, order %.2f)%s", problem_names[p], references[p], extrapolated[p],
           orders[p], p + 1 < PROBLEM_COUNT ? "; " : "\n");
  printf("dynamic: 20x3x3 hex cantilever, tip uz at t = %g s, dt -> 0 value %.6f m\n", opt.time, dynamic_ref);
  print_backends(rows, count);
  printf("%-14s %-14s %-7s %-40s %6s %10s %10s %9s %10s %s\n", "group", "problem", "mode", "row", "dofs", "tip_uz",
         "reference", "error%", "ms", "pareto");
  for (int k = 0; k < count; ++k) print_row(rows + k);
  fascia_file *file = open_out(&opt, "tradeoff.csv");
  if (!file) {
    rc = 1;
    goto done;
  }
  fputs(csv_header, fascia_file_stream(file));
  for (int k = 0; k < count; ++k) csv_row(fascia_file_stream(file), rows + k);
  if (close_out(&opt, file)) {
    rc = 1;
    goto done;
  }
  cJSON *array = cJSON_CreateArray();
  for (int k = 0; k < count && array; ++k) cJSON_AddItemToArray(array, json_row(rows + k));
  char *text = array ? cJSON_Print(array) : NULL;
  int written = text && (file = open_out(&opt, "tradeoff.json"));
  if (written) {
    fprintf(fascia_file_stream(file), "%s\n", text);
    written = !close_out(&opt, file);
  }
  if (written && opt.json) (void)cli_json_emit(array, 0);
  cJSON_free(text);
  cJSON_Delete(array);
  if (!written) {
    rc = 1;
    goto done;
  }
  rc = 0;
  for (int p = 0; p < PROBLEM_COUNT; ++p) rc |= write_points(&opt, rows, count, 0, p);
  rc |= write_points(&opt, rows, count, 1, PROBLEM_CANTILEVER);
  rc |= write_convergence(&opt, rows, count);
  rc |= write_plot_scripts(&opt);
  if (!rc && opt.plot) rc = run_gnuplot(&opt);
done:
  free(rows);
  fascia_ctx_destroy(&ctx);
  return rc;
}
