// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia bench`: the benchmarks (docs/measured.md).
//   paper       the rows of Tables 2 and 3 of Bosman et al. 2013 (sec. 4.3),
//               run in the paper's mode (implicit Euler, one Newton iteration,
//               exactly 60 CG iterations per step): minimum ms per step over
//               repeats, against the paper's CPU figure, with the per-stage split;
//               on a device backend (--backend cuda, emulated) against the
//               paper's GPU figure and the same run on this machine's CPU.
//   large       rows of Table 3's density beyond the paper (100k to 2M samples)
//               in the same mode, for the GPU goals (docs/gpu.md).
//   cantilever  accuracy against cost on the paper's cantilever (sec. 4.1):
//               static tip deflection against the converged CalculiX reference
//               (data/reference/) over shape kinds, frame grids, samples,
//               neighbours, rotation smoothing; where ccx is installed, beside
//               each row CalculiX's time to the same error (C3D8I, C3D20R).
// Rows are printed as a text table, one JSON array (--json) or CSV (--csv).
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "bench_calculix.h"
#include "commands.h"
#include "fascia/fascia.h"
#include "scenes.h"

static const char bench_usage[] =
    "usage: fascia bench [--list] [paper | large | cantilever | ROW ...] [--table 2|3]\n"
    "                    [--backend cpu|cuda|auto|emulated [--no-cpu]]\n"
    "                    [--threads T] [--repeats R] [--steps S] [--json] [--csv FILE]\n"
    "                    [--assembled [--single|--double]] [--linear-solver cg|direct|auto] [--no-calculix]\n"
    "                    [--shapes hex,tet,meshless,strand,sheet] [--frames 10x2x2,20x3x3,...]\n"
    "                    [--samples-per-cell N,...] [--neighbours K,...] [--rotation-smoothing R,...]\n"
    "\n"
    "  paper                 every row of the paper's Tables 2 and 3 (the default), in the paper's\n"
    "                        mode: implicit Euler steps of 0.01 s, 1 Newton iteration, exactly 60\n"
    "                        CG iterations; ROW (or --scene ROW) runs one row (see --list)\n"
    "  large                 rows beyond the paper at Table 3's density (4 neighbours, one frame\n"
    "                        per five samples): 100k, 300k, 1M and 2M samples, the same mode;\n"
    "                        on cuda the GPU goals (docs/gpu.md) are checked: t3-s34610 in <= 1 ms per\n"
    "                        step, the 1M row at >= 60 steps per second\n"
    "  cantilever            static cantilever: tip deflection error against the converged\n"
    "                        CalculiX reference, Newton and CG iterations, time (the solver's\n"
    "                        set-up and the solve); where ccx (calculix-ccx) is installed,\n"
    "                        CalculiX's time to the same error (C3D8I, C3D20R, NLGEOM; deck,\n"
    "                        run and files) measured in the same run, the least of as many repeats\n"
    "  --list                print the benchmarks and rows\n"
    "  --table 2|3           paper: only the rows of this table\n"
    "  --backend NAME        cpu (default), cuda (the GPU), auto (cuda where there is a GPU, else\n"
    "                        cpu) or emulated (the GPU solver in host loops: slow, for tests). The\n"
    "                        GPU solver is matrix-free CG: no --assembled, --single or direct.\n"
    "                        Beside cuda or emulated each row also runs on the CPU, and the table\n"
    "                        compares with the paper's GPU figure (GTX 570) and this CPU\n"
    "  --no-cpu              beside cuda or emulated: skip the CPU run of each row\n"
    "  --threads T           worker threads, 1 to 1024 (default: OpenMP's)\n"
    "  --repeats R           repeats, the minimum time is reported (default 3 paper, 1 cantilever)\n"
    "  --steps S             paper: timed steps per repeat, after 2 warm-up steps (default 5)\n"
    "  --json                one JSON array of row objects on stdout\n"
    "  --csv FILE            also write the rows as CSV with a header row (one benchmark at a time)\n"
    "  --assembled           CG multiplies by the assembled block matrix (default: where it fits)\n"
    "  --single              ... stored in float (half the memory traffic of the products; the\n"
    "                        default in the paper's mode and where the CG tolerance is 1e-6 or looser)\n"
    "  --double              ... stored in double\n"
    "  --linear-solver KIND  cantilever: cg, direct or auto (default: the solver's default)\n"
    "  --no-calculix         cantilever: no CalculiX peer figures\n";

// (a second string: ISO C bounds a string literal's length)
static const char bench_usage_sweep[] =
    "cantilever sweep (any of these replaces the default rows by the product of the lists):\n"
    "  --shapes LIST              hex, tet, meshless, strand (1-D), sheet (2-D) (default hex)\n"
    "  --frames LIST              frame grids NXxNYxNZ (default 20x3x3); a strand takes NX and a sheet\n"
    "                             NXxNY, or the leading counts of a longer grid\n"
    "  --samples-per-cell LIST    hex, meshless: N^3 per cell; tet: per tetrahedron; strand, sheet:\n"
    "                             stations along the axis (default 2; tet 4; strand, sheet 1)\n"
    "  --neighbours LIST          meshless: frames per sample (default 8); strand, sheet: 0, the\n"
    "                             frames of the sample's interval or cell (default), or K nearest\n"
    "  --rotation-smoothing LIST  0 is the paper's scheme (default: the beam's, 0.05 tet, else 0.1)\n"
    "  --nu LIST                  Poisson ratios with a converged reference: 0.3, 0.45, 0.49 (default 0.3)\n"
    "  --volumetric LIST          auto (cell patches from nu = 0.3, as fascia beam), full, cell, frame\n"
    "                             (default auto; docs/mechanics.md, \"Volumetric locking\")\n"
    "  --modes LIST               enhanced strain modes on the patches: auto (as fascia beam), on\n"
    "                             (the shape's set, fascia beam --modes on), off (default auto)\n"
    "  A row whose beam cannot be built (say MLS neighbours in one plane) is reported with the\n"
    "  reason and the others still run; the exit status is then 1.\n";

#define PAPER_WARMUP_STEPS 2
#define PAPER_CG_ITERATIONS 60
#define PAPER_TIME_STEP 0.01
#define MAX_LIST 16
#define MAX_ROWS 64
#define BENCH_MAX_NU 4 // Poisson ratios with CalculiX peers in one run

/// A comma-separated list option of the cantilever sweep.
typedef struct value_list {
  int count;
  double real[MAX_LIST];
  int32_t grid[MAX_LIST][3];
} value_list;

// Enhanced strain modes of a cantilever row: fascia beam's rule (on for
// hex and tet with patches), or forced (on: the shape's set).
enum { MODES_AUTO = 0, MODES_ON = 1, MODES_OFF = 2 };

// kind: 's' shape name, 'g' grid, 'i' integer >= 1, 'r' real >= 0, 'v' volumetric integration,
// 'm' enhanced modes (auto, on, off).
static int parse_list(const char *text, char kind, value_list *out) {
  char buffer[1024];
  if (strlen(text) >= sizeof buffer) return 0;
  strcpy(buffer, text);
  out->count = 0;
  for (char *item = buffer, *next; item; item = next) {
    next = strchr(item, ',');
    if (next) *next++ = '\0';
    if (out->count == MAX_LIST) return 0;
    double *v = out->real + out->count;
    char *end = NULL;
    int n = 0;
    if (kind == 's') {
      const int shape = fascia_scene_shape_from_name(item);
      if (shape < 0) return 0;
      *v = shape;
    } else if (kind == 'g') {
      if (!fascia_scene_frames_parse(item, out->grid[out->count])) return 0;
    } else if (kind == 'm') {
      *v = !strcmp(item, "auto") ? MODES_AUTO : !strcmp(item, "on") ? MODES_ON : !strcmp(item, "off") ? MODES_OFF : -1;
      if (*v < 0) return 0;
    } else if (kind == 'v') {
      *v = fascia_scene_patch_from_name(item);
      if (*v == -2 || *v == FASCIA_SCENE_PATCH_POISSON) return 0;
    } else if (kind == 'i') {
      if (!cli_parse_count(item, &n, 1)) return 0;
      *v = n;
    } else {
      errno = 0;
      *v = strtod(item, &end);
      if (!item[0] || *end || errno || !isfinite(*v) || *v < 0) return 0;
    }
    out->count++;
  }
  return out->count > 0;
}

/// Everything the command line sets.
typedef struct bench_options {
  int list, json, threads, repeats, steps, table, paper_all, large_all, cantilever, assembled, single;
  int no_cpu;      ///< beside a device backend: no CPU run of each row
  int no_calculix; ///< cantilever: no CalculiX peer
  int linear_given;
  fascia_linear_solver linear;
  const char *backend, *csv;
  int row_count;
  const fascia_scene_paper_row *rows[MAX_ROWS];
  value_list shapes, grids, spc, neighbours, smoothing, nus, volumetric, modes;
  int sweep; ///< a cantilever list option was given
} bench_options;

static int add_row_name(bench_options *opt, const char *name) {
  if (!strcmp(name, "paper")) opt->paper_all = 1;
  else if (!strcmp(name, "large")) opt->large_all = 1;
  else if (!strcmp(name, "cantilever")) opt->cantilever = 1;
  else {
    const fascia_scene_paper_row *row = fascia_scene_paper_find(name);
    if (!row) return cli_usage_error("bench", "unknown benchmark or row '%s'; fascia bench --list shows them", name);
    if (opt->row_count == MAX_ROWS) return cli_usage_error("bench", "%s", "too many rows");
    opt->rows[opt->row_count++] = row;
  }
  return -1;
}

// Parses argv. Returns -1 to go on, else the exit status (already reported).
static int parse_options(int argc, char **argv, bench_options *opt) {
  memset(opt, 0, sizeof *opt);
  opt->backend = "cpu";
  opt->single = FASCIA_SINGLE_AUTO;
  for (int k = 1; k < argc; ++k) {
    const char *o = argv[k];
    if (cli_help(o, bench_usage, bench_usage_sweep)) return 0;
    if (o[0] != '-') {
      const int rc = add_row_name(opt, o);
      if (rc >= 0) return rc;
      continue;
    }
    if (!strcmp(o, "--verbose")) continue;
    if (!strcmp(o, "--list")) opt->list = 1;
    else if (!strcmp(o, "--json")) opt->json = 1;
    else if (!strcmp(o, "--assembled")) opt->assembled = 1;
    else if (!strcmp(o, "--single")) opt->single = 1;
    else if (!strcmp(o, "--double")) opt->single = 0;
    else if (!strcmp(o, "--no-cpu")) opt->no_cpu = 1;
    else if (!strcmp(o, "--no-calculix")) opt->no_calculix = 1;
    else {
      static const char *const valued[] = {"--table", "--backend", "--threads", "--repeats", "--steps", "--csv",
                                           "--scene", "--linear-solver", "--shapes", "--frames",
                                           "--samples-per-cell", "--neighbours", "--rotation-smoothing", "--nu",
                                           "--volumetric", "--modes", NULL};
      const char *v = NULL;
      const int bad = cli_option_value("bench", argc, argv, &k, valued, &v);
      if (bad >= 0) return bad;
      int ok = 1;
      if (!strcmp(o, "--table")) ok = cli_parse_count(v, &opt->table, 2) && opt->table <= 3;
      else if (!strcmp(o, "--backend")) ok = cli_parse_backend(v, &opt->backend);
      else if (!strcmp(o, "--threads")) ok = cli_parse_threads(v, &opt->threads);
      else if (!strcmp(o, "--repeats")) ok = cli_parse_count(v, &opt->repeats, 1);
      else if (!strcmp(o, "--steps")) ok = cli_parse_count(v, &opt->steps, 1);
      else if (!strcmp(o, "--csv")) opt->csv = v;
      else if (!strcmp(o, "--scene")) {
        const int rc = add_row_name(opt, v);
        if (rc >= 0) return rc;
      } else if (!strcmp(o, "--linear-solver")) {
        ok = !strcmp(v, "cg") || !strcmp(v, "direct") || !strcmp(v, "auto");
        opt->linear = !strcmp(v, "cg") ? FASCIA_LINEAR_CG : !strcmp(v, "direct") ? FASCIA_LINEAR_DIRECT : FASCIA_LINEAR_AUTO;
        opt->linear_given = 1;
      } else {
        opt->sweep = 1;
        if (!strcmp(o, "--shapes")) ok = parse_list(v, 's', &opt->shapes);
        else if (!strcmp(o, "--frames")) ok = parse_list(v, 'g', &opt->grids);
        else if (!strcmp(o, "--samples-per-cell")) ok = parse_list(v, 'i', &opt->spc);
        else if (!strcmp(o, "--neighbours")) ok = parse_list(v, 'i', &opt->neighbours);
        else if (!strcmp(o, "--nu")) ok = parse_list(v, 'r', &opt->nus);
        else if (!strcmp(o, "--volumetric")) ok = parse_list(v, 'v', &opt->volumetric);
        else if (!strcmp(o, "--modes")) ok = parse_list(v, 'm', &opt->modes);
        else ok = parse_list(v, 'r', &opt->smoothing);
      }
      if (!ok) {
        fprintf(stderr, "fascia bench: bad value '%s' for %s%s (see fascia bench --help)\n", v, o,
                !strcmp(o, "--threads") ? ": expected a whole number from 1 to " CLI_MAX_THREADS_TEXT : "");
        return 2;
      }
    }
  }
  if (opt->sweep) opt->cantilever = 1;
  for (int a = 0; a < opt->modes.count; ++a) // modes live on patches: refused before any row runs
    for (int b = 0; b < opt->volumetric.count; ++b)
      if (opt->modes.real[a] == MODES_ON && opt->volumetric.real[b] == FASCIA_SCENE_PATCH_NONE)
        return cli_usage_error("bench", "%s",
                               "--modes on needs volumetric patches: it cannot go with --volumetric full");
  if (opt->table) opt->paper_all = 1;
  if (!opt->list && !opt->paper_all && !opt->large_all && !opt->cantilever && !opt->row_count) opt->paper_all = 1;
  const int paper = opt->paper_all || opt->large_all || opt->row_count;
  if (opt->csv && paper && opt->cantilever)
    return cli_usage_error("bench", "%s", "--csv writes one benchmark at a time: run paper and cantilever separately");
  if (!opt->repeats) opt->repeats = paper ? 3 : 1;
  if (!opt->steps) opt->steps = 5;
  return -1;
}

// A figure, or "-" where there is none (0: the paper gives none; not measured).
static const char *figure(char *buf, size_t size, const char *format, double x) {
  if (x > 0 && isfinite(x)) snprintf(buf, size, format, x);
  else snprintf(buf, size, "-");
  return buf;
}

static void print_rows(const char *title, const fascia_scene_paper_row *rows, int count) {
  char a[32], b[32];
  printf("\n%s\n  %-26s %5s %6s %7s %10s %12s %12s\n", title, "name", "table", "frames", "samples", "neighbours",
         "paper_cpu_ms", "paper_gpu_ms");
  for (int k = 0; k < count; ++k)
    printf("  %-26s %5d %6d %7d %10d %12s %12s\n", rows[k].name, rows[k].table, (int)rows[k].frames,
           (int)rows[k].samples, (int)rows[k].neighbours, figure(a, sizeof a, "%.2f", rows[k].paper_cpu_ms),
           figure(b, sizeof b, "%.2f", rows[k].paper_gpu_ms));
}

static void print_list(void) {
  int paper_count = 0, large_count = 0;
  const fascia_scene_paper_row *paper = fascia_scene_paper_rows(&paper_count);
  const fascia_scene_paper_row *large = fascia_scene_large_rows(&large_count);
  printf("benchmarks\n  paper        the paper rows below, in the paper's mode (60 CG iterations per step)\n"
         "  large        the large rows below, in the same mode (not in the paper; the GPU goals)\n"
         "  cantilever   static cantilever accuracy against cost\n");
  print_rows("paper rows", paper, paper_count);
  print_rows("large rows (table 0: not in the paper, Table 3's density)", large, large_count);
}

static int progress_wanted(void) {
  const char *env = getenv("FASCIA_PROGRESS");
  if (env && !strcmp(env, "0")) return 0;
  return isatty(2) || (env && !strcmp(env, "1"));
}

static void progress_line(const char *bench, int k, int total, const char *what) {
  fprintf(stderr, "\rbench %s %d/%d: %s\033[K", bench, k, total, what);
  fflush(stderr);
}

static int32_t max_neighbours(const fascia_model *m) {
  int32_t k = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    const int32_t n = m->sample_offsets[s + 1] - m->sample_offsets[s];
    k = n > k ? n : k;
  }
  return k;
}

// ---------------------------------------------------------------- paper --

typedef struct paper_result {
  const fascia_scene_paper_row *row;
  int frames, samples, neighbours, threads, assembled; ///< assembled: the products used the assembled matrix
  int single; ///< ... its float copy
  double ms, evaluate_ms, precond_ms, assemble_ms, cg_ms; ///< per step, best repeat
  double cg_per_step, peak_memory_mb, memory_mb;
  /// The same run on the CPU, ms per step: beside a device backend unless
  /// --no-cpu, ms itself when the run was on the CPU; 0: not measured.
  double cpu_ms;
  char backend[16], device[256]; ///< where the timed run ran (fascia_solver_backend, _device)
} paper_result;

// Times the paper's mode on one backend: warm-up steps, then `repeats` runs
// of `steps` steps, each from the rest state; keeps the repeat with the least
// time per step. Sets the times, where it ran and the memory grown since
// base_mb while the solver lives.
static fascia_status time_paper_mode(fascia_ctx *ctx, const bench_options *opt, const fascia_model *model,
                                     const char *backend, double base_mb, paper_result *out) {
  fascia_solver *solver = NULL;
  fascia_solver_def def = fascia_solver_def_default();
  def.backend = backend;
  def.threads = opt->threads;
  def.time_step = PAPER_TIME_STEP;
  def.newton_iterations = 1;
  def.require_convergence = 0; // one Newton iteration per step is the mode
  def.cg_fixed = 1;
  def.cg_iterations = PAPER_CG_ITERATIONS;
  def.line_search = 0;
  def.linear_solver = FASCIA_LINEAR_CG; // the paper's mode, whatever the default
  if (opt->assembled) def.assembled = 1; // else the default: the faster product
  def.single_precision_matrix = opt->single;
  fascia_status st = fascia_solver_create(ctx, model, &def, &solver);
  if (st != FASCIA_OK) return st;
  snprintf(out->backend, sizeof out->backend, "%s", fascia_solver_backend(solver));
  snprintf(out->device, sizeof out->device, "%s", fascia_solver_device(solver));
  fascia_solve_report report;
  out->ms = INFINITY;
  for (int r = 0; r < opt->repeats && st == FASCIA_OK; ++r) {
    // every repeat from rest, its warm-up untimed: the first step from rest
    // can be split (t3-s34610's is, three solves' work), the steady steps not
    st = fascia_solver_set_state(solver, model->frame_position, model->frame_rotation, NULL);
    for (int w = 0; w < PAPER_WARMUP_STEPS && st == FASCIA_OK; ++w) st = fascia_solver_step(solver, &report);
    fascia_profile sum;
    memset(&sum, 0, sizeof sum);
    double ms = 0, cg = 0;
    for (int n = 0; n < opt->steps && st == FASCIA_OK; ++n) {
      const double t0 = cli_now_ms();
      st = fascia_solver_step(solver, &report);
      ms += cli_now_ms() - t0;
      fascia_profile_add(&sum, &report.profile);
      cg += report.cg_iterations;
    }
    if (st == FASCIA_OK && ms / opt->steps < out->ms) {
      out->ms = ms / opt->steps;
      out->evaluate_ms = sum.evaluate_ms / opt->steps;
      out->precond_ms = sum.precond_ms / opt->steps;
      out->assemble_ms = sum.assemble_ms / opt->steps;
      out->cg_ms = sum.cg_ms / opt->steps;
      out->cg_per_step = cg / opt->steps;
      out->assembled = report.assembled;
      out->single = report.single_precision_matrix;
    }
  }
  out->memory_mb = cli_resident_mb() - base_mb;
  fascia_solver_destroy(&solver);
  return st;
}

// Times one row on the chosen backend and, beside a device backend, the
// same run on the CPU (not with --no-cpu).
static fascia_status bench_paper_row(fascia_ctx *ctx, const bench_options *opt, const fascia_scene_paper_row *row,
                                     paper_result *out) {
  memset(out, 0, sizeof *out);
  out->row = row;
  const double base_mb = cli_resident_mb();
  fascia_model *model = NULL;
  fascia_status st = fascia_scene_paper_build(ctx, row, NULL, &model);
  if (st != FASCIA_OK) return st;
  out->frames = model->frame_count;
  out->samples = model->sample_count;
  out->neighbours = max_neighbours(model);
  out->threads = opt->threads > 0 ? opt->threads : fascia_ctx_threads(ctx);
  st = time_paper_mode(ctx, opt, model, opt->backend, base_mb, out);
  if (st == FASCIA_OK && !strcmp(out->backend, "cpu")) {
    out->cpu_ms = out->ms;
  } else if (st == FASCIA_OK && !opt->no_cpu) {
    paper_result cpu;
    memset(&cpu, 0, sizeof cpu);
    st = time_paper_mode(ctx, opt, model, "cpu", base_mb, &cpu);
    out->cpu_ms = cpu.ms;
  }
  out->peak_memory_mb = cli_peak_mb();
  fascia_model_destroy(&model);
  return st;
}

// The backend and device above the rows, once, and again where a row ran on
// another backend (auto decides per row); shown holds the backend printed. A
// device is named by fascia_backend_available: the solver's text adds the
// model's device memory, which differs per row (--json has it).
static void text_device_line(char *shown, size_t size, const char *backend, const char *device) {
  if (!strcmp(shown, backend)) return;
  char name[256];
  if (strcmp(backend, "cpu") && fascia_backend_available(backend, name, sizeof name)) device = name;
  printf("backend %s on %s\n", backend, device);
  snprintf(shown, size, "%s", backend);
}

// With --backend cpu the table of the paper's CPU column; beside a device
// backend the comparison with the paper's GPU column (GTX 570) and the CPU.
static void paper_text_header(const bench_options *opt) {
  if (!strcmp(opt->backend, "cpu"))
    printf("%-5s %-26s %6s %7s %3s %10s %10s %8s %10s %8s %9s %9s %9s %9s %7s %s\n", "table", "name", "frames",
           "samples", "k", "ms/step", "paper_ms", "speedup", "paper_gpu", "peak_MB", "eval_ms", "precnd_ms", "asm_ms",
           "cg_ms", "cg_iter", "product");
  else
    printf("%-5s %-26s %6s %7s %3s %10s %10s %9s %10s %8s %8s %9s %9s %9s %7s\n", "table", "name", "frames",
           "samples", "k", "ms/step", "paper_gpu", "gpu_ratio", "cpu_ms", "cpu/gpu", "peak_MB", "eval_ms",
           "precnd_ms", "cg_ms", "cg_iter");
}

// The GPU goal of a row, on a GPU only: "goal ...: met" or "NOT met".
static void paper_text_goal(const paper_result *r) {
  if (!(r->row->gpu_goal_ms > 0) || strcmp(r->backend, "cuda")) return;
  printf("      GPU goal for %s: <= %.3g ms/step (%.0f steps/s): %s (%.3f ms/step, %.1f steps/s)\n",
         r->row->name, r->row->gpu_goal_ms, 1000 / r->row->gpu_goal_ms, r->ms <= r->row->gpu_goal_ms ? "met" : "NOT met",
         r->ms, 1000 / r->ms);
}

static void paper_text_row(const paper_result *r, const bench_options *opt) {
  char a[32], b[32], c[32], d[32];
  const fascia_scene_paper_row *row = r->row;
  if (!strcmp(opt->backend, "cpu"))
    printf("%-5d %-26s %6d %7d %3d %10.3f %10s %8s %10s %8.1f %9.3f %9.3f %9.3f %9.3f %7.1f %s\n", row->table, row->name,
           r->frames, r->samples, r->neighbours, r->ms, figure(a, sizeof a, "%.2f", row->paper_cpu_ms),
           figure(b, sizeof b, "%.2f", row->paper_cpu_ms / r->ms), figure(c, sizeof c, "%.2f", row->paper_gpu_ms),
           r->peak_memory_mb, r->evaluate_ms, r->precond_ms, r->assemble_ms, r->cg_ms, r->cg_per_step,
           !r->assembled ? "matrix-free" : r->single ? "float" : "double");
  else
    printf("%-5d %-26s %6d %7d %3d %10.3f %10s %9s %10s %8s %8.1f %9.3f %9.3f %9.3f %7.1f\n", row->table, row->name,
           r->frames, r->samples, r->neighbours, r->ms, figure(a, sizeof a, "%.2f", row->paper_gpu_ms),
           figure(b, sizeof b, "%.2f", row->paper_gpu_ms / r->ms), figure(c, sizeof c, "%.3f", r->cpu_ms),
           figure(d, sizeof d, "%.2f", r->cpu_ms / r->ms), r->peak_memory_mb, r->evaluate_ms, r->precond_ms, r->cg_ms,
           r->cg_per_step);
  paper_text_goal(r);
  fflush(stdout);
}

static cJSON *paper_json(const paper_result *r, const bench_options *opt) {
  const fascia_scene_paper_row *row = r->row;
  cJSON *o = cJSON_CreateObject();
  cJSON_AddStringToObject(o, "bench", row->table ? "paper" : "large");
  cJSON_AddNumberToObject(o, "table", row->table);
  cJSON_AddStringToObject(o, "name", row->name);
  cJSON_AddNumberToObject(o, "frames", r->frames);
  cJSON_AddNumberToObject(o, "frames_requested", row->frames);
  cJSON_AddNumberToObject(o, "samples", r->samples);
  cJSON_AddNumberToObject(o, "neighbours", r->neighbours);
  cJSON_AddNumberToObject(o, "ms_per_step", r->ms);
  if (row->paper_cpu_ms > 0) {
    cJSON_AddNumberToObject(o, "paper_ms", row->paper_cpu_ms);
    cJSON_AddNumberToObject(o, "speedup", row->paper_cpu_ms / r->ms);
  }
  if (row->paper_gpu_ms > 0) cJSON_AddNumberToObject(o, "paper_gpu_ms", row->paper_gpu_ms);
  cJSON_AddNumberToObject(o, "peak_memory_mb", r->peak_memory_mb);
  cJSON_AddNumberToObject(o, "memory_mb", r->memory_mb);
  cJSON_AddNumberToObject(o, "evaluate_ms", r->evaluate_ms);
  cJSON_AddNumberToObject(o, "precond_ms", r->precond_ms);
  cJSON_AddNumberToObject(o, "assemble_ms", r->assemble_ms);
  cJSON_AddNumberToObject(o, "cg_ms", r->cg_ms);
  cJSON_AddNumberToObject(o, "cg_iterations_per_step", r->cg_per_step);
  cJSON_AddStringToObject(o, "backend", r->backend);
  cJSON_AddStringToObject(o, "device", r->device);
  if (strcmp(opt->backend, "cpu")) { // the comparisons of a device backend
    if (row->paper_gpu_ms > 0) cJSON_AddNumberToObject(o, "paper_gpu_ratio", row->paper_gpu_ms / r->ms);
    if (r->cpu_ms > 0) {
      cJSON_AddNumberToObject(o, "cpu_ms_per_step", r->cpu_ms);
      cJSON_AddNumberToObject(o, "cpu_gpu_ratio", r->cpu_ms / r->ms);
    }
  }
  if (row->gpu_goal_ms > 0) {
    cJSON_AddNumberToObject(o, "gpu_goal_ms", row->gpu_goal_ms);
    if (!strcmp(r->backend, "cuda")) cJSON_AddBoolToObject(o, "goal_met", r->ms <= row->gpu_goal_ms);
  }
  cJSON_AddNumberToObject(o, "threads", r->threads);
  cJSON_AddBoolToObject(o, "assembled", r->assembled);
  cJSON_AddBoolToObject(o, "single_precision_matrix", r->single);
  cJSON_AddNumberToObject(o, "steps", opt->steps);
  cJSON_AddNumberToObject(o, "repeats", opt->repeats);
  return o;
}

// A CSV figure, empty where there is none.
static void csv_figure(FILE *f, const char *format, double x) {
  if (x > 0 && isfinite(x)) fprintf(f, format, x);
}

// The columns of the CPU runs first, as before; those of a device backend
// after them.
static void paper_csv(FILE *f, const paper_result *rows, int count, const bench_options *opt) {
  fprintf(f, "table,name,frames,frames_requested,samples,neighbours,ms_per_step,paper_ms,paper_gpu_ms,speedup,"
             "peak_memory_mb,memory_mb,evaluate_ms,precond_ms,assemble_ms,cg_ms,cg_iterations_per_step,backend,"
             "threads,assembled,steps,repeats,device,cpu_ms_per_step,paper_gpu_ratio,cpu_gpu_ratio,single_precision_matrix\n");
  const int device = strcmp(opt->backend, "cpu") != 0;
  for (int k = 0; k < count; ++k) {
    const paper_result *r = rows + k;
    fprintf(f, "%d,%s,%d,%d,%d,%d,%.4f,", r->row->table, r->row->name, r->frames, (int)r->row->frames, r->samples,
            r->neighbours, r->ms);
    csv_figure(f, "%.2f", r->row->paper_cpu_ms);
    fputc(',', f);
    csv_figure(f, "%.2f", r->row->paper_gpu_ms);
    fputc(',', f);
    csv_figure(f, "%.3f", r->row->paper_cpu_ms / r->ms);
    fprintf(f, ",%.1f,%.2f,%.4f,%.4f,%.4f,%.4f,%.1f,%s,%d,%d,%d,%d,", r->peak_memory_mb, r->memory_mb,
            r->evaluate_ms, r->precond_ms, r->assemble_ms, r->cg_ms, r->cg_per_step, r->backend, r->threads,
            r->assembled, opt->steps, opt->repeats);
    cli_csv_text(f, r->device);
    fputc(',', f);
    if (device) csv_figure(f, "%.4f", r->cpu_ms);
    fputc(',', f);
    if (device) csv_figure(f, "%.3f", r->row->paper_gpu_ms / r->ms);
    fputc(',', f);
    if (device) csv_figure(f, "%.3f", r->cpu_ms / r->ms);
    fprintf(f, ",%d\n", r->single);
  }
}

// ----------------------------------------------------------- cantilever --

typedef struct cantilever_case {
  int shape, spc, neighbours;
  int32_t grid[3];
  double smoothing;
  int linear; ///< fascia_linear_solver for this row, -1: --linear-solver or the solver's default
  double nu;
  int volumetric; ///< a FASCIA_SCENE_PATCH_* kind (AUTO: fascia beam's rule)
  int modes;      ///< MODES_*
} cantilever_case;

typedef struct cantilever_result {
  cantilever_case c;
  int frames, samples, neighbours, newton, cg, converged, direct, threads;
  double tip[3], error_uz_percent, error_ux_percent, twist, ms;
  double reference_uz; ///< the converged reference for this row's law, E and nu
  int patches;         ///< volumetric patches of the model (0: full integration)
  int modes;           ///< 1: the patches carry enhanced strain modes
  char backend[16], device[256]; ///< where it ran (fascia_solver_backend, _device)
  const bench_peer *peer[FASCIA_CCX_ELEMENT_COUNT_]; ///< CalculiX at the same error, NULL: none or not run
  char failed[320]; ///< why this row's beam could not be built ("": it was); the sweep goes on without it
} cantilever_result;

// The converged reference of the default cantilever (data/reference/).
static const fascia_ccx_reference *cantilever_reference(void) {
  const fascia_scene_beam_def def = fascia_scene_beam_def_default();
  return fascia_ccx_reference_find(&def);
}

// The default sweep (about 2 to 3 minutes on 2 cores): grids per shape
// kind, then one knob at a time on the 20 x 3 x 3 hexahedral beam: samples,
// the paper's scheme (rotation smoothing 0), CG instead of the default
// linear solver; full integration against the default volumetric patches;
// tet without its enhanced strain modes; the nearly incompressible beam
// (nu = 0.49); the strand (1-D) and the sheet (2-D) at two resolutions and
// at nu = 0.49. The paper's scheme on
// 40 x 5 x 5 is left out: minutes.
static int default_cases(cantilever_case *cases) {
  const int H = FASCIA_SCENE_HEX, T = FASCIA_SCENE_TET, M = FASCIA_SCENE_MESHLESS, L = FASCIA_SCENE_STRAND,
            P = FASCIA_SCENE_SHEET, A = FASCIA_SCENE_PATCH_AUTO,
            F = FASCIA_SCENE_PATCH_NONE;
  const double S = FASCIA_SCENE_SMOOTHING_AUTO; // fascia beam's rotation smoothing by shape kind
  const cantilever_case table[] = {
      {H, 2, 0, {10, 2, 2}, S, -1, 0.3, A, MODES_AUTO},  {H, 2, 0, {20, 3, 3}, S, -1, 0.3, A, MODES_AUTO},
      {H, 2, 0, {40, 5, 5}, S, -1, 0.3, A, MODES_AUTO},  {H, 1, 0, {20, 3, 3}, S, -1, 0.3, A, MODES_AUTO},
      {H, 3, 0, {20, 3, 3}, S, -1, 0.3, A, MODES_AUTO},  {H, 2, 0, {10, 2, 2}, 0, -1, 0.3, A, MODES_AUTO},
      {H, 2, 0, {20, 3, 3}, 0, -1, 0.3, A, MODES_AUTO},    {H, 2, 0, {20, 3, 3}, S, FASCIA_LINEAR_CG, 0.3, A, MODES_AUTO},
      {T, 4, 0, {10, 2, 2}, S, -1, 0.3, A, MODES_AUTO},  {T, 4, 0, {20, 3, 3}, S, -1, 0.3, A, MODES_AUTO},
      {T, 4, 0, {40, 5, 5}, S, -1, 0.3, A, MODES_AUTO},  {T, 1, 0, {20, 3, 3}, S, -1, 0.3, A, MODES_AUTO},
      {M, 2, 8, {10, 2, 2}, S, -1, 0.3, A, MODES_AUTO},  {M, 2, 8, {20, 3, 3}, S, -1, 0.3, A, MODES_AUTO},
      {M, 2, 16, {20, 3, 3}, S, -1, 0.3, A, MODES_AUTO}, {M, 2, 8, {40, 5, 5}, S, -1, 0.3, A, MODES_AUTO},
      {H, 2, 0, {20, 3, 3}, S, -1, 0.3, F, MODES_AUTO},  {T, 4, 0, {20, 3, 3}, S, -1, 0.3, F, MODES_AUTO},
      {M, 2, 8, {20, 3, 3}, S, -1, 0.3, F, MODES_AUTO},  {M, 2, 16, {20, 3, 3}, S, -1, 0.3, F, MODES_AUTO},
      {T, 4, 0, {20, 3, 3}, S, -1, 0.3, A, MODES_OFF}, {T, 4, 0, {20, 3, 3}, S, -1, 0.49, A, MODES_OFF},
      {H, 2, 0, {20, 3, 3}, S, -1, 0.49, A, MODES_AUTO}, {T, 4, 0, {20, 3, 3}, S, -1, 0.49, A, MODES_AUTO},
      {M, 2, 8, {20, 3, 3}, S, -1, 0.49, A, MODES_AUTO}, {M, 2, 16, {20, 3, 3}, S, -1, 0.49, A, MODES_AUTO},
      {H, 2, 0, {20, 3, 3}, S, -1, 0.49, F, MODES_AUTO},
      {L, 1, 0, {20, 1, 1}, S, -1, 0.3, A, MODES_AUTO},  {L, 1, 0, {40, 1, 1}, S, -1, 0.3, A, MODES_AUTO},
      {P, 1, 0, {20, 3, 1}, S, -1, 0.3, A, MODES_AUTO},  {P, 1, 0, {40, 5, 1}, S, -1, 0.3, A, MODES_AUTO},
      {L, 1, 0, {20, 1, 1}, S, -1, 0.49, A, MODES_AUTO}, {P, 1, 0, {20, 3, 1}, S, -1, 0.49, A, MODES_AUTO},
  };
  const int count = (int)(sizeof table / sizeof table[0]);
  memcpy(cases, table, sizeof table);
  return count;
}

// The product of the list options, defaults filling the lists not given.
static int sweep_cases(const bench_options *opt, cantilever_case *cases, int capacity) {
  value_list shapes = opt->shapes, grids = opt->grids, spc = opt->spc, kn = opt->neighbours, sm = opt->smoothing;
  value_list nus = opt->nus, vol = opt->volumetric, modes = opt->modes;
  if (!modes.count) modes.count = 1, modes.real[0] = MODES_AUTO;
  if (!nus.count) nus.count = 1, nus.real[0] = 0.3;
  if (!vol.count) vol.count = 1, vol.real[0] = FASCIA_SCENE_PATCH_AUTO;
  if (!shapes.count) shapes.count = 1, shapes.real[0] = FASCIA_SCENE_HEX;
  if (!grids.count) grids.count = 1, grids.grid[0][0] = 20, grids.grid[0][1] = 3, grids.grid[0][2] = 3;
  const int reduced_kn = kn.count > 0; // strands and sheets: their own frames unless K is given
  if (!kn.count) kn.count = 1, kn.real[0] = 8;
  if (!sm.count) sm.count = 1, sm.real[0] = FASCIA_SCENE_SMOOTHING_AUTO;
  int count = 0;
  for (int a = 0; a < shapes.count; ++a)
    for (int b = 0; b < grids.count; ++b) {
      // a grid with fewer counts than the shape has dimensions is not this shape's
      const int dim = fascia_scene_shape_dimension((int)shapes.real[a]);
      if (dim > 1 && grids.grid[b][dim - 1] < 2) continue;
      const int reduced = dim < 3, ks = shapes.real[a] == FASCIA_SCENE_MESHLESS || (reduced && reduced_kn) ? kn.count : 1;
      for (int c = 0; c < (spc.count ? spc.count : 1); ++c)
        for (int d = 0; d < ks; ++d)
          for (int e = 0; e < sm.count; ++e)
            for (int f = 0; f < nus.count; ++f)
              for (int g = 0; g < vol.count * modes.count; ++g) {
                if (count == capacity) return -1;
                cantilever_case *x = cases + count++;
                x->modes = (int)modes.real[g % modes.count];
                x->shape = (int)shapes.real[a];
                memcpy(x->grid, grids.grid[b], sizeof x->grid);
                for (int k = dim; k < 3; ++k) x->grid[k] = 1;
                x->spc = spc.count ? (int)spc.real[c] : x->shape == FASCIA_SCENE_TET ? 4 : reduced ? 1 : 2;
                x->neighbours = x->shape == FASCIA_SCENE_MESHLESS || (reduced && reduced_kn) ? (int)kn.real[d] : 0;
                x->smoothing = sm.real[e];
                x->linear = -1;
                x->nu = nus.real[f];
                x->volumetric = (int)vol.real[g / modes.count];
              }
    }
  return count;
}

// Largest |rotation about x| over the frames, rad: the x component of each
// frame's rotation vector (the beam axis is x; bending turns about y).
static double max_twist(const fascia_real *q, int32_t frame_count) {
  double twist = 0;
  for (int32_t i = 0; i < frame_count; ++i) {
    const fascia_real *qi = q + 4 * i;
    const double sign = qi[0] < 0 ? -1 : 1, v = sqrt(qi[1] * qi[1] + qi[2] * qi[2] + qi[3] * qi[3]);
    if (v == 0) continue;
    const double angle = 2 * atan2(v, sign * qi[0]);
    const double about_x = fabs(angle * sign * qi[1] / v);
    twist = about_x > twist ? about_x : twist;
  }
  return twist;
}

// Builds one beam and solves it statically from rest, timed from a new
// solver (the bench's repeats call it again and keep the least time). A
// solve that does not converge is reported (converged 0), not an error; a
// beam that cannot be built (a combination of the sweep's lists that makes
// no beam, or MLS neighbours that span no volume) is reported in
// out->failed, and the other rows still run.
static fascia_status bench_cantilever_case(fascia_ctx *ctx, const bench_options *opt, const cantilever_case *c,
                                           cantilever_result *out) {
  memset(out, 0, sizeof *out);
  out->c = *c;
  fascia_scene_beam_def bdef = fascia_scene_beam_def_of_shape(c->shape);
  memcpy(bdef.frames, c->grid, sizeof bdef.frames);
  bdef.shape = c->shape;
  if (c->shape == FASCIA_SCENE_TET) bdef.samples_per_tet = c->spc;
  else bdef.samples_per_cell_dir = c->spc;
  if (c->shape == FASCIA_SCENE_MESHLESS || fascia_scene_shape_dimension(c->shape) < 3) bdef.neighbours = c->neighbours;
  bdef.rotation_smoothing = c->smoothing;
  bdef.poisson_ratio = c->nu;
  bdef.volumetric_patch = c->volumetric;
  bdef.enhanced_modes = c->modes == MODES_ON    ? fascia_scene_beam_modes_of_shape(c->shape)
                       : c->modes == MODES_OFF ? FASCIA_MODES_NONE
                                               : -1;
  const fascia_ccx_reference *ref = fascia_ccx_reference_find(&bdef);
  if (!ref)
    return fascia_ctx_fail(ctx, FASCIA_ERR_ARGUMENT, __FILE__, __LINE__,
                       "cantilever: no converged reference for nu = %g (data/reference/ has 0.3, 0.45 and 0.49)",
                       c->nu);
  out->reference_uz = ref->tip_uz;
  fascia_model *model = NULL;
  fascia_solver *solver = NULL;
  fascia_status st = fascia_scene_beam_build(ctx, &bdef, &model);
  if (st == FASCIA_ERR_ARGUMENT || st == FASCIA_ERR_NUMERIC) {
    snprintf(out->failed, sizeof out->failed, "%s", fascia_ctx_message(ctx));
    fascia_ctx_clear(ctx);
    return FASCIA_OK;
  }
  if (st != FASCIA_OK) goto cleanup;
  out->patches = fascia_model_patch_count(model, NULL);
  out->c.smoothing = model->materials[0].rotation_smoothing; // the rule's choice where the row left it to it
  for (int32_t s = 0; s < model->sample_count; ++s) out->modes |= model->sample_modes[s];
  fascia_solver_def def = fascia_solver_def_default();
  def.backend = opt->backend;
  def.threads = opt->threads;
  def.newton_iterations = 100; // the static solve's limit (solver.h)
  if (opt->assembled) def.assembled = 1; // else the default: the faster product
  def.single_precision_matrix = opt->single;
  if (opt->linear_given) def.linear_solver = opt->linear;
  if (c->linear >= 0) def.linear_solver = (fascia_linear_solver)c->linear;
  out->frames = model->frame_count;
  out->samples = model->sample_count;
  out->neighbours = max_neighbours(model);
  out->threads = opt->threads > 0 ? opt->threads : fascia_ctx_threads(ctx);
  const int32_t tip = fascia_model_find_probe(model, "tip");
  // timed from the model in memory, as CalculiX from its deck: the
  // solver's set-up (system, patches, assembly plan) and the solve
  const double t0 = cli_now_ms();
  if ((st = fascia_solver_create(ctx, model, &def, &solver)) != FASCIA_OK) goto cleanup;
  snprintf(out->backend, sizeof out->backend, "%s", fascia_solver_backend(solver));
  snprintf(out->device, sizeof out->device, "%s", fascia_solver_device(solver));
  fascia_solve_report report;
  st = fascia_solver_solve_static(solver, &report);
  out->ms = cli_now_ms() - t0;
  if (st != FASCIA_OK && st != FASCIA_ERR_NUMERIC) goto cleanup;
  if (st == FASCIA_ERR_NUMERIC && report.newton_iterations == 0) goto cleanup; // failed, not just unconverged
  st = FASCIA_OK;
  out->newton = report.newton_iterations;
  out->cg = report.cg_iterations;
  out->converged = report.converged;
  out->direct = report.direct;
  fascia_real position[3] = {0, 0, 0};
  if (tip >= 0) fascia_solver_probe_position(solver, tip, position);
  for (int k = 0; k < 3; ++k) out->tip[k] = tip >= 0 ? position[k] - model->probe_position[3 * tip + k] : NAN;
  out->error_uz_percent = 100 * (out->tip[2] - ref->tip_uz) / fabs(ref->tip_uz);
  out->error_ux_percent = 100 * (out->tip[0] - ref->tip_ux) / fabs(ref->tip_ux);
  out->twist = max_twist(fascia_solver_frame_rotations(solver), model->frame_count);
cleanup:
  fascia_solver_destroy(&solver);
  fascia_model_destroy(&model);
  return st;
}

// NXxNYxNZ; a strand's NX, a sheet's NXxNY (the counts it does not use are 1)
static void grid_text(const int32_t grid[3], char *out, size_t size) {
  if (grid[1] == 1) snprintf(out, size, "%d", (int)grid[0]);
  else if (grid[2] == 1) snprintf(out, size, "%dx%d", (int)grid[0], (int)grid[1]);
  else snprintf(out, size, "%dx%dx%d", (int)grid[0], (int)grid[1], (int)grid[2]);
}

static void cantilever_text_header(void) {
  printf("%-8s %-8s %6s %7s %3s %4s %6s %4s %-7s %-6s %9s %9s %9s %8s %9s %6s %6s %4s %10s\n", "shape", "grid", "frames",
         "samples", "k", "spc", "smooth", "nu", "vol", "linear", "ux_m", "uy_m", "uz_m", "err_uz%", "twist_rad", "newton",
         "cg", "conv", "ms");
}

// The row's volumetric integration as run: full, or the patch kind.
static const char *row_volumetric(const cantilever_result *r) {
  const int v = r->c.volumetric;
  return r->patches <= 0 ? "full" : v == FASCIA_SCENE_PATCH_AUTO ? "cell" : fascia_scene_patch_name(v);
}

// The same for the tables, "+m" where the patches carry enhanced strain modes.
static const char *row_volumetric_text(const cantilever_result *r, char *buf, size_t size) {
  snprintf(buf, size, "%s%s", row_volumetric(r), r->modes ? "+m" : "");
  return buf;
}

static void cantilever_text_row(const cantilever_result *r) {
  char grid[48], vol[16];
  grid_text(r->c.grid, grid, sizeof grid);
  if (r->failed[0]) {
    printf("%-8s %-8s failed: %s\n", fascia_scene_shape_name(r->c.shape), grid, r->failed);
    return;
  }
  printf("%-8s %-8s %6d %7d %3d %4d %6.3g %4.2f %-7s %-6s %9.4f %9.2e %9.4f %8.2f %9.2e %6d %6d %4s %10.1f\n",
         fascia_scene_shape_name(r->c.shape), grid, r->frames, r->samples, r->neighbours, r->c.spc, r->c.smoothing,
         r->c.nu, row_volumetric_text(r, vol, sizeof vol), r->direct ? "direct" : "cg", r->tip[0], r->tip[1], r->tip[2], r->error_uz_percent, r->twist, r->newton, r->cg,
         r->converged ? "yes" : "NO", r->ms);
  fflush(stdout);
}

static cJSON *cantilever_json(const cantilever_result *r) {
  char grid[48];
  grid_text(r->c.grid, grid, sizeof grid);
  cJSON *o = cJSON_CreateObject();
  cJSON_AddStringToObject(o, "bench", "cantilever");
  cJSON_AddStringToObject(o, "shape", fascia_scene_shape_name(r->c.shape));
  cJSON_AddStringToObject(o, "grid", grid);
  if (r->failed[0]) { // the row's settings (those it gave) and why no beam was made of them
    cJSON_AddNumberToObject(o, "samples_per_cell", r->c.spc);
    if (r->c.shape == FASCIA_SCENE_MESHLESS) cJSON_AddNumberToObject(o, "neighbours", r->c.neighbours);
    if (r->c.smoothing >= 0) cJSON_AddNumberToObject(o, "rotation_smoothing", r->c.smoothing);
    cJSON_AddNumberToObject(o, "poisson_ratio", r->c.nu);
    cJSON_AddStringToObject(o, "error", r->failed);
    return o;
  }
  cJSON_AddNumberToObject(o, "frames", r->frames);
  cJSON_AddNumberToObject(o, "samples", r->samples);
  cJSON_AddNumberToObject(o, "neighbours", r->neighbours);
  cJSON_AddNumberToObject(o, "samples_per_cell", r->c.spc);
  cJSON_AddNumberToObject(o, "rotation_smoothing", r->c.smoothing);
  cJSON_AddNumberToObject(o, "poisson_ratio", r->c.nu);
  cJSON_AddStringToObject(o, "volumetric", row_volumetric(r));
  cJSON_AddNumberToObject(o, "volumetric_patches", r->patches);
  cJSON_AddBoolToObject(o, "enhanced_modes", r->modes);
  cJSON_AddStringToObject(o, "linear_solver", r->direct ? "direct" : "cg");
  cJSON_AddItemToObject(o, "tip_displacement", cJSON_CreateDoubleArray(r->tip, 3));
  cJSON_AddNumberToObject(o, "tip_ux", r->tip[0]);
  cJSON_AddNumberToObject(o, "tip_uz", r->tip[2]);
  cJSON_AddNumberToObject(o, "reference_uz", r->reference_uz);
  cJSON_AddNumberToObject(o, "error_uz_percent", r->error_uz_percent);
  cJSON_AddNumberToObject(o, "error_ux_percent", r->error_ux_percent);
  cJSON_AddNumberToObject(o, "twist_rad", r->twist);
  cJSON_AddNumberToObject(o, "newton_iterations", r->newton);
  cJSON_AddNumberToObject(o, "cg_iterations", r->cg);
  cJSON_AddBoolToObject(o, "converged", r->converged);
  cJSON_AddNumberToObject(o, "ms", r->ms);
  cJSON_AddNumberToObject(o, "threads", r->threads);
  cJSON_AddStringToObject(o, "backend", r->backend);
  cJSON_AddStringToObject(o, "device", r->device);
  // CalculiX at the same error: null where ccx did not run or no mesh of its ladder reached it
  cJSON *peers = cJSON_AddObjectToObject(o, "calculix");
  for (int e = 0; e < FASCIA_CCX_ELEMENT_COUNT_; ++e) {
    const bench_peer *p = r->peer[e];
    if (!p) {
      cJSON_AddNullToObject(peers, fascia_ccx_element_name(e));
      continue;
    }
    char mesh[64];
    bench_calculix_mesh_text(p, mesh, sizeof mesh);
    cJSON *x = cJSON_AddObjectToObject(peers, fascia_ccx_element_name(e));
    cJSON_AddStringToObject(x, "mesh", mesh);
    cJSON_AddNumberToObject(x, "dofs", p->result.dofs);
    cJSON_AddNumberToObject(x, "tip_uz", p->result.tip[2]);
    cJSON_AddNumberToObject(x, "error_uz_percent", p->error_uz_percent);
    cJSON_AddNumberToObject(x, "newton_iterations", p->result.iterations);
    cJSON_AddNumberToObject(x, "ms", p->result.ms);
  }
  return o;
}

static const char cantilever_csv_header[] =
    "shape,grid,frames,samples,neighbours,samples_per_cell,rotation_smoothing,poisson_ratio,volumetric,"
    "linear_solver,tip_ux,tip_uy,"
    "tip_uz,reference_uz,error_uz_percent,error_ux_percent,twist_rad,newton_iterations,cg_iterations,"
    "converged,ms,threads,backend,device,calculix_c3d20r_mesh,calculix_c3d20r_error_uz_percent,"
    "calculix_c3d20r_ms,calculix_c3d8i_mesh,calculix_c3d8i_error_uz_percent,calculix_c3d8i_ms,enhanced_modes,"
    "error\n";

static void cantilever_csv(FILE *f, const cantilever_result *rows, int count) {
  fputs(cantilever_csv_header, f);
  int separators = 0; // the header's: a failed row's empty fields are counted from it, so the error stays last
  for (const char *c = cantilever_csv_header; *c; ++c) separators += *c == ',';
  for (int k = 0; k < count; ++k) {
    const cantilever_result *r = rows + k;
    char grid[48];
    grid_text(r->c.grid, grid, sizeof grid);
    if (r->failed[0]) { // the row's settings (those it gave), no figures, and why
      char neighbours[16] = "", smoothing[32] = "";
      if (r->c.shape == FASCIA_SCENE_MESHLESS) snprintf(neighbours, sizeof neighbours, "%d", r->c.neighbours);
      if (r->c.smoothing >= 0) snprintf(smoothing, sizeof smoothing, "%g", r->c.smoothing);
      fprintf(f, "%s,%s,,,%s,%d,%s,%g", fascia_scene_shape_name(r->c.shape), grid, neighbours, r->c.spc, smoothing,
              r->c.nu);
      for (int c = 7; c < separators; ++c) fputc(',', f); // the 8 fields above, then empty ones up to the error
      cli_csv_text(f, r->failed);
      fputc('\n', f);
      continue;
    }
    fprintf(f, "%s,%s,%d,%d,%d,%d,%g,%g,%s,%s,%.6f,%.3e,%.6f,%.3f,%.3f,%.3f,%.3e,%d,%d,%d,%.1f,%d,%s,",
            fascia_scene_shape_name(r->c.shape), grid, r->frames, r->samples, r->neighbours, r->c.spc, r->c.smoothing,
            r->c.nu, row_volumetric(r), r->direct ? "direct" : "cg", r->tip[0], r->tip[1], r->tip[2], r->reference_uz,
            r->error_uz_percent, r->error_ux_percent, r->twist, r->newton, r->cg, r->converged, r->ms, r->threads,
            r->backend);
    cli_csv_text(f, r->device);
    for (int e = 0; e < FASCIA_CCX_ELEMENT_COUNT_; ++e) {
      char mesh[64] = "";
      if (r->peer[e]) bench_calculix_mesh_text(r->peer[e], mesh, sizeof mesh);
      fprintf(f, ",%s,", mesh);
      if (r->peer[e]) fprintf(f, "%.3f,%.1f", r->peer[e]->error_uz_percent, r->peer[e]->result.ms);
      else fputc(',', f);
    }
    fprintf(f, ",%d,\n", r->modes);
  }
}

// ------------------------------------------------------- CalculiX peer --

static void peer_ladder_text(double nu, const bench_peer *p, int count) {
  for (int k = 0; k < count; ++k, ++p) {
    char mesh[64];
    bench_calculix_mesh_text(p, mesh, sizeof mesh);
    printf("%-4.2f %-7s %-16s %7d %9.4f %8.3f %6d %10.1f\n", nu, fascia_ccx_element_name(p->element), mesh, p->result.dofs,
           p->result.tip[2], p->error_uz_percent, p->result.iterations, p->result.ms);
  }
}

// fascia's rows against CalculiX's cheapest mesh at least as accurate.
static void peer_match_text(const cantilever_result *rows, int count) {
  printf("\ntime to the same error: each row against CalculiX's fastest mesh at least as accurate\n"
         "%-8s %-8s %4s %-7s %8s %10s", "shape", "grid", "nu", "vol", "err_uz%", "ms");
  for (int e = 0; e < FASCIA_CCX_ELEMENT_COUNT_; ++e)
    printf(" | %-6s %-9s %8s %10s %7s", fascia_ccx_element_name(e), "mesh", "err_uz%", "ms", "ratio");
  printf("\n");
  for (int k = 0; k < count; ++k) {
    const cantilever_result *r = rows + k;
    char grid[48], vol[16];
    grid_text(r->c.grid, grid, sizeof grid);
    if (r->failed[0]) {
      printf("%-8s %-8s %4.2f failed\n", fascia_scene_shape_name(r->c.shape), grid, r->c.nu);
      continue;
    }
    printf("%-8s %-8s %4.2f %-7s %8.3f %10.1f", fascia_scene_shape_name(r->c.shape), grid, r->c.nu,
           row_volumetric_text(r, vol, sizeof vol),
           r->error_uz_percent, r->ms);
    for (int e = 0; e < FASCIA_CCX_ELEMENT_COUNT_; ++e) {
      const bench_peer *p = r->peer[e];
      char mesh[64] = "not reached";
      if (p) bench_calculix_mesh_text(p, mesh, sizeof mesh);
      if (p) printf(" | %-16s %8.3f %10.1f %7.2f", mesh, p->error_uz_percent, p->result.ms, r->ms / p->result.ms);
      else printf(" | %-16s %8s %10s %7s", mesh, "-", "-", "-");
    }
    printf("\n");
  }
  printf("ratio: fascia's ms over CalculiX's (< 1: fascia faster at that error)\n");
}

/// CalculiX's side of the cantilever bench, kept over its repeats: per
/// Poisson ratio of the rows, each element's ladder and how far it went.
typedef struct peer_runs {
  const char *program; ///< ccx, NULL where it is not installed
  int threads, nu_count;
  double nus[BENCH_MAX_NU];
  int solved[BENCH_MAX_NU][FASCIA_CCX_ELEMENT_COUNT_];
  bench_peer peers[BENCH_MAX_NU][FASCIA_CCX_ELEMENT_COUNT_][BENCH_PEER_MAX];
} peer_runs;

// One pass of CalculiX on the same cantilever. The first solves, per
// Poisson ratio of the rows, each element's ladder until it is as accurate
// as the most accurate converged row of that ratio; each later one solves
// the same meshes again, keeping their least times, so that the repeats
// alternate between fascia's rows and CalculiX's (a slow spell of a shared
// machine falls on both). Returns 0, or the exit status of a failure.
static int cantilever_peers_pass(fascia_ctx *ctx, const bench_options *opt, const cantilever_result *rows, int count,
                                 int show, peer_runs *runs, int pass) {
  if (pass == 0) {
    runs->threads = opt->threads > 0 ? opt->threads : fascia_ctx_threads(ctx);
    runs->nu_count = 0;
    for (int k = 0; k < count; ++k) {
      int known = 0;
      for (int j = 0; j < runs->nu_count; ++j) known |= runs->nus[j] == rows[k].c.nu;
      if (!known && rows[k].converged && runs->nu_count < BENCH_MAX_NU) runs->nus[runs->nu_count++] = rows[k].c.nu;
    }
  }
  for (int j = 0; j < runs->nu_count; ++j) {
    double target = INFINITY, reference = 0;
    for (int k = 0; k < count; ++k)
      if (rows[k].c.nu == runs->nus[j] && rows[k].converged && fabs(rows[k].error_uz_percent) < target) {
        target = fabs(rows[k].error_uz_percent);
        reference = rows[k].reference_uz;
      }
    fascia_scene_beam_def beam = fascia_scene_beam_def_default();
    beam.poisson_ratio = runs->nus[j];
    for (int e = 0; e < FASCIA_CCX_ELEMENT_COUNT_; ++e) {
      if (show) progress_line("calculix", e + 1, FASCIA_CCX_ELEMENT_COUNT_, fascia_ccx_element_name(e));
      bench_peer *ladder = runs->peers[j][e];
      const fascia_status st =
          pass == 0 ? bench_calculix_ladder(ctx, runs->program, e, &beam, reference, target, runs->threads, ladder,
                                            &runs->solved[j][e])
                    : bench_calculix_retime(ctx, runs->program, &beam, runs->threads, ladder, runs->solved[j][e]);
      if (show) fprintf(stderr, "\r\033[K");
      if (st != FASCIA_OK) return cli_fail("bench", ctx, st);
    }
  }
  return 0;
}

// Each row's fastest CalculiX mesh at least as accurate as itself, after
// the last pass.
static void cantilever_peers_match(cantilever_result *rows, int count, const peer_runs *runs) {
  for (int j = 0; j < runs->nu_count; ++j)
    for (int e = 0; e < FASCIA_CCX_ELEMENT_COUNT_; ++e)
      for (int k = 0; k < count; ++k)
        if (rows[k].converged && rows[k].c.nu == runs->nus[j])
          rows[k].peer[e] = bench_calculix_match(runs->peers[j][e], runs->solved[j][e], rows[k].error_uz_percent);
}

static void cantilever_peers_text(const bench_options *opt, const cantilever_result *rows, int count,
                                  const peer_runs *runs) {
  if (!runs->program) {
    printf("\nCalculiX: not installed (apt-get install calculix-ccx), no peer figures\n");
    return;
  }
  printf("\nCalculiX (%s) on the same cantilever: NLGEOM, St. Venant-Kirchhoff, its default controls, %d thread(s),\n"
         "meshes graded towards the clamp (g: largest over smallest element along x); ms: wall time, deck and\n"
         "files included, the least of %d run(s), which alternate with fascia's (whose ms: the solver's set-up\n"
         "and the solve)\n%-4s %-7s %-16s %7s %9s %8s %6s %10s\n",
         runs->program, runs->threads, opt->repeats, "nu", "element", "mesh", "dofs", "uz_m", "err_uz%", "newton",
         "ms");
  for (int j = 0; j < runs->nu_count; ++j)
    for (int e = 0; e < FASCIA_CCX_ELEMENT_COUNT_; ++e)
      peer_ladder_text(runs->nus[j], runs->peers[j][e], runs->solved[j][e]);
  peer_match_text(rows, count);
}

// ----------------------------------------------------------------- main --

// The rows selected: the paper's (filtered by --table), the large ones,
// then named ones.
static int select_paper_rows(const bench_options *opt, const fascia_scene_paper_row **rows) {
  int count = 0, total = 0, large_total = 0;
  const fascia_scene_paper_row *all = fascia_scene_paper_rows(&total);
  const fascia_scene_paper_row *large = fascia_scene_large_rows(&large_total);
  if (opt->paper_all)
    for (int k = 0; k < total && count < MAX_ROWS; ++k)
      if (!opt->table || all[k].table == opt->table) rows[count++] = all + k;
  if (opt->large_all)
    for (int k = 0; k < large_total && count < MAX_ROWS; ++k) rows[count++] = large + k;
  for (int k = 0; k < opt->row_count && count < MAX_ROWS; ++k) rows[count++] = opt->rows[k];
  return count;
}

static int write_csv_file(const char *path, const bench_options *opt, const paper_result *paper, int paper_count,
                          const cantilever_result *cant, int cant_count) {
  fascia_ctx *ctx = cli_ctx(1, 0);
  fascia_file *file = NULL;
  fascia_status st = fascia_file_open(ctx, "--csv", path, &file);
  if (st == FASCIA_OK) {
    if (paper_count) paper_csv(fascia_file_stream(file), paper, paper_count, opt);
    else cantilever_csv(fascia_file_stream(file), cant, cant_count);
    st = fascia_file_commit(&file);
  }
  const int rc = st == FASCIA_OK ? 0 : cli_fail("bench", ctx, st);
  fascia_ctx_destroy(&ctx);
  return rc;
}

int cmd_bench(int argc, char **argv) {
  bench_options opt;
  int rc = parse_options(argc, argv, &opt);
  if (rc >= 0) return rc;
  const cli_path csv = {"--csv", opt.csv, CLI_OUTPUT_FILE, NULL, NULL};
  if ((rc = cli_check_paths("bench", &csv, 1)) >= 0) return rc; // before hours of timing
  if (opt.list) {
    print_list();
    if (!opt.paper_all && !opt.large_all && !opt.row_count && !opt.cantilever) return 0;
  }
  const fascia_scene_paper_row *rows[MAX_ROWS];
  const int paper_count = select_paper_rows(&opt, rows);
  cantilever_case cases[MAX_ROWS];
  int case_count = 0;
  if (opt.cantilever) {
    case_count = opt.sweep ? sweep_cases(&opt, cases, MAX_ROWS) : default_cases(cases);
    if (case_count < 0) return cli_usage_error("bench", "the sweep has more than %s rows; give shorter lists", "64");
  }
  paper_result *paper = calloc((size_t)paper_count + 1, sizeof *paper);
  cantilever_result *cant = calloc((size_t)case_count + 1, sizeof *cant);
  static peer_runs runs;
  cJSON *array = opt.json ? cJSON_CreateArray() : NULL;
  fascia_ctx *ctx = cli_ctx(opt.threads, 0);
  const int show = progress_wanted();
  fascia_status st = FASCIA_OK;
  if (!paper || !cant || (opt.json && !array)) {
    fprintf(stderr, "fascia bench: out of memory\n");
    rc = 1;
    goto done;
  }
  char shown[16] = ""; // the backend of the last device line printed
  for (int k = 0; k < paper_count && st == FASCIA_OK; ++k) {
    if (show) progress_line("paper", k + 1, paper_count, rows[k]->name);
    st = bench_paper_row(ctx, &opt, rows[k], paper + k);
    if (show) fprintf(stderr, "\r\033[K");
    if (st != FASCIA_OK) break;
    if (opt.json) {
      cJSON_AddItemToArray(array, paper_json(paper + k, &opt));
      continue;
    }
    text_device_line(shown, sizeof shown, paper[k].backend, paper[k].device);
    if (k == 0 && strcmp(opt.backend, "cpu") && opt.no_cpu) printf("cpu_ms: not measured (--no-cpu)\n");
    else if (k == 0 && strcmp(opt.backend, "cpu"))
      printf("cpu_ms: the same run on this machine's CPU, %d threads; gpu_ratio = paper_gpu / ms/step\n",
             paper[k].threads);
    if (k == 0) paper_text_header(&opt);
    paper_text_row(paper + k, &opt);
  }
  runs.program = case_count && !opt.no_calculix ? fascia_ccx_program() : NULL;
  for (int pass = 0; pass < (case_count ? opt.repeats : 0) && st == FASCIA_OK; ++pass) {
    for (int k = 0; k < case_count && st == FASCIA_OK; ++k) {
      if (pass > 0 && cant[k].failed[0]) continue; // its beam cannot be built: the same again
      char what[96], grid[48];
      grid_text(cases[k].grid, grid, sizeof grid);
      snprintf(what, sizeof what, "%s %s (%d of %d)", fascia_scene_shape_name(cases[k].shape), grid, pass + 1,
               opt.repeats);
      if (show) progress_line("cantilever", k + 1, case_count, what);
      cantilever_result once;
      st = bench_cantilever_case(ctx, &opt, cases + k, &once);
      if (show) fprintf(stderr, "\r\033[K");
      if (pass == 0) cant[k] = once;
      else if (once.ms < cant[k].ms) cant[k].ms = once.ms;
    }
    if (st == FASCIA_OK && runs.program && (rc = cantilever_peers_pass(ctx, &opt, cant, case_count, show, &runs, pass)))
      goto done;
  }
  if (st != FASCIA_OK) { // FASCIA_ERR_ARGUMENT: settings the backend refuses, or a beam the options cannot build
    rc = cli_solver_fail("bench", opt.backend, ctx, st);
    goto done;
  }
  if (runs.program) cantilever_peers_match(cant, case_count, &runs);
  for (int k = 0; k < case_count && !opt.json; ++k) {
    if (k == 0) {
      if (paper_count) printf("\n");
      printf("cantilever 16 x 1 x 1 m, static; reference tip u = (%.4f, 0, %.4f) m at nu = 0.3 (CalculiX, converged:\n"
             "data/reference/, one per nu); err_uz%% > 0: too stiff; twist: largest |rotation about x| over frames;\n"
             "vol: volumetric integration (full, or mean dilatation over cell patches: fascia beam's default from\n"
             "nu = 0.3; +m: with enhanced strain modes per patch, fascia beam's defaults: the nine for tet,\n"
             "the three normal ones for hex); ms: the solver's set-up and the static solve, the least of %d\n",
             cantilever_reference()->tip_ux, cantilever_reference()->tip_uz, opt.repeats);
      shown[0] = '\0';
    }
    if (!cant[k].failed[0]) text_device_line(shown, sizeof shown, cant[k].backend, cant[k].device);
    if (k == 0) cantilever_text_header();
    cantilever_text_row(cant + k);
  }
  if (case_count && !opt.no_calculix && !opt.json) cantilever_peers_text(&opt, cant, case_count, &runs);
  for (int k = 0; opt.json && k < case_count; ++k) cJSON_AddItemToArray(array, cantilever_json(cant + k));
  if (opt.json) {
    if ((rc = cli_json_emit(array, 0)) != 0) goto done;
  }
  rc = opt.csv ? write_csv_file(opt.csv, &opt, paper, paper_count, cant, case_count) : 0;
  int failed_rows = 0;
  for (int k = 0; k < case_count; ++k) failed_rows += cant[k].failed[0] != '\0';
  if (failed_rows && !rc) { // the figures of the others are out; the exit status says some are missing
    fflush(stdout);
    fprintf(stderr, "fascia bench: %d of %d cantilever rows could not be built (their lines say why)\n", failed_rows,
            case_count);
    rc = 1;
  }
done:
  cJSON_Delete(array);
  free(paper);
  free(cant);
  fascia_ctx_destroy(&ctx);
  return rc;
}
