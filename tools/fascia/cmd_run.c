// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia run MODEL.h5`: loads a model, solves it statically or with
// implicit Euler steps (docs/mechanics.md), optionally writes the
// results file (HDF5 + XDMF), and prints a summary: steps, ms per step,
// Newton and CG iterations, each probe's displacement, the largest strain;
// as text or as one JSON object on stdout (the CLI contract of docs/cli.md).
// SIGINT/SIGTERM during a dynamic run stop it after the current step; the
// results file is then closed cleanly with the steps done.
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/statvfs.h>
#include <time.h>
#include <unistd.h>

#include "commands.h"
#include "drive.h"
#include "run_outputs.h"
#include "fascia/fascia.h"
#include "presets.h"

static const char run_usage[] =
    "usage: fascia run MODEL.h5 [--static | --steps N [--dt S]] [-o RESULTS.h5] [--save-every K]\n"
    "                  [--samples] [--json] [--backend cpu|cuda|auto|emulated] [--threads T]\n"
    "                  [--newton-iterations N] [--newton-tolerance X] [--cg-iterations N]\n"
    "                  [--cg-tolerance X] [--cg-fixed] [--precond none|jacobi|block]\n"
    "                  [--mass consistent|lumped] [--damping ALPHA] [--load-steps N]\n"
    "                  [--linear-solver cg|direct|auto] [--assembled|--matrix-free] [--preset NAME]\n"
    "\n"
    "Solves a model file: static equilibrium (default) or N implicit Euler steps.\n"
    "  --static               static equilibrium under gravity and loads (the default)\n"
    "  --static-time T        the time (s) the equilibrium is for: prescribed organs stand where\n"
    "                         their motions put them then (default: the end of the motions)\n"
    "  --steps N              N implicit (backward) Euler steps instead\n"
    "  --dt S                 time step, s (default 0.01; needs --steps)\n"
    "  -o RESULTS.h5          write frame states (HDF5) and RESULTS.xdmf for ParaView\n"
    "  --save-every K         dynamic: save the rest state, every K-th step and the last (default 1)\n"
    "  --samples              also save sample positions and the fields 'strain', 'stress'\n"
    "  --json                 print one JSON object on stdout instead of text\n"
    "  --backend NAME         cpu; cuda (the GPU: matrix-free CG only, no --assembled, --single\n"
    "                         or --linear-solver direct); auto (the default: cuda\n"
    "                         where there is a GPU and the settings run there, else cpu); or\n"
    "                         emulated (the GPU solver in host loops: slow, for tests)\n"
    "  --threads T            worker threads, 1 to 1024 (default: OpenMP's, OMP_NUM_THREADS)\n"
    "  --newton-iterations N  most Newton iterations per solve (default 20; static 100)\n"
    "  --newton-tolerance X   relative gradient tolerance (default 1e-6)\n"
    "  --cg-iterations N      most CG iterations per linear solve (default 200)\n"
    "  --cg-tolerance X       relative CG residual (default 1e-3)\n"
    "  --cg-fixed             always exactly --cg-iterations CG iterations (the paper's mode)\n"
    "  --precond KIND         none, jacobi or block (6x6 block Jacobi, default)\n"
    "  --mass KIND            consistent or lumped (default lumped)\n"
    "  --damping ALPHA        Rayleigh mass damping, 1/s (default 0)\n"
    "  --load-steps N         static: apply the load, and the prescribed organs' motion up to the\n"
    "                         equilibrium's time, in N increments (default 1)\n"
    "  --step-retries N       a failed step is redone as halved steps, N halvings at most (default 4);\n"
    "                         0 stops at the first failure, the last good state saved\n"
    "  --require-convergence  a step whose Newton iterations do not converge counts as failed and\n"
    "                         is split (the default, and every preset's)\n"
    "  --accept-unconverged   keep a step whose Newton iterations did not converge\n"
    "  --blow-up-strain E     a step after which a sample's strain passes E has blown up and fails\n"
    "                         (default 10; 0: off). Blown-up steps, overflow and diverging Newton\n"
    "                         solves end the run with exit 1 (docs/mechanics.md)\n"
    "  --linear-solver KIND   cg, direct (sparse Cholesky of the assembled tangent) or auto\n"
    "                         (the default: direct up to 2e9 flops per factorization, else CG;\n"
    "                         docs/mechanics.md)\n"
    "  --assembled            CG multiplies by the assembled block matrix (the default on the CPU\n"
    "                         up to a 2 GiB matrix)\n"
    "  --matrix-free          CG multiplies without a matrix (the default beyond that and on a GPU)\n"
    "  --single               ... stored in float for the products (half their memory traffic; the\n"
    "                         default where the CG tolerance is 1e-6 or looser, or --cg-fixed)\n"
    "  --double               ... stored in double for the products\n";
// the rest of the help, split off: C99 guarantees string literals of 4095 bytes only
static const char run_usage_notes[] =
    "  --preset NAME          interactive, balanced or accurate: every step converged (else split,\n"
    "                         then refused) to a Newton tolerance of 1e-2, 1e-4 or 1e-8 (and CG\n"
    "                         1e-6); looser is fewer iterations, interactive at most the default's\n"
    "                         (docs/cli.md, measured on every shipped scene); options after it\n"
    "                         override it; a static solve keeps its Newton limit of 100\n"
    "  --verbose              on failure, also print where the error was found\n"
    "Progress with the time left goes to stderr when it is a terminal (or FASCIA_PROGRESS=1).\n"
    "Every output is written as NAME.tmp-PID-K and renamed when complete; the next run writing\n"
    "it removes those a killed run left. SIGINT/SIGTERM (also repeated) stop a dynamic run after\n"
    "the current step with the outputs written; the exit status is then 1. Exit 2: usage error,\n"
    "including an output that is an input or another output.\n";

// Set by SIGINT/SIGTERM during a dynamic run; checked after every step.
static volatile sig_atomic_t run_stop_requested = 0;

static void on_stop_signal(int sig) {
  (void)sig;
  run_stop_requested = 1;
}

// sigaction, not signal(): in strict C11 mode glibc's signal() resets the
// handler on delivery, so a second Ctrl-C killed the run with nothing saved.
// Installed from before the outputs open until they are closed.
static void catch_stop_signals(struct sigaction old[2]) {
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, &old[0]);
  sigaction(SIGTERM, &sa, &old[1]);
}

static void restore_signals(const struct sigaction old[2]) {
  sigaction(SIGINT, &old[0], NULL);
  sigaction(SIGTERM, &old[1], NULL);
}

// --- checkpoints and restart ---------------------------------------------
// Taken out of argv before parse_options, so they stay apart from the
// solver options; the hooks are in run_steps and cmd_run.

static const char checkpoint_usage[] =
    "Checkpoints (dynamic runs):\n"
    "  --checkpoint FILE      write the full state (time, step, frame positions, rotations,\n"
    "                         velocities) to FILE every K steps, after the last step and when\n"
    "                         stopped by SIGINT/SIGTERM; written to a temporary name, then renamed\n"
    "  --checkpoint-every K   steps between checkpoints (default 10)\n"
    "  --resume FILE          continue from checkpoint FILE (same model) up to --steps N in all\n"
    "                         (N counts every step from t = 0: below the checkpoint's step it is\n"
    "                         an error, equal to it the run is complete and nothing is done):\n"
    "                         the same final state, bit for bit on the CPU, as a run never\n"
    "                         interrupted; -o then holds the steps from the resumed one on. The run\n"
    "                         continues with the solver settings stored in FILE (--dt, Newton, CG,\n"
    "                         preconditioner, linear solver, mass, damping, retries): an option or\n"
    "                         --preset that asks for another value is refused, naming both values.\n"
    "                         A damaged or edited checkpoint (its state checksum, its step and\n"
    "                         time) or one of another model is refused (docs/results-format.md)\n";

typedef struct checkpoint_options {
  const char *path, *resume;
  int every;       ///< steps between checkpoints
  int first_step;  ///< first step to take: 1, or the resumed step + 1
  int help;        ///< --help was given
  fascia_ctx *ctx; ///< for fascia_checkpoint_save in run_steps
  uint64_t inputs; ///< run_drive_digest, recorded with each checkpoint
} checkpoint_options;

// Removes --checkpoint, --checkpoint-every and --resume (with their values)
// from argv. Returns -1 to go on, else the exit status (2: usage error).
static int take_checkpoint_options(int *argc, char **argv, checkpoint_options *c) {
  memset(c, 0, sizeof *c);
  c->every = 10;
  c->first_step = 1;
  int kept = 1;
  for (int k = 1; k < *argc; ++k) {
    const char *o = argv[k];
    if (!strcmp(o, "--help") || !strcmp(o, "-h")) c->help = 1; // printed after the usage
    if (strcmp(o, "--checkpoint") && strcmp(o, "--checkpoint-every") && strcmp(o, "--resume")) {
      argv[kept++] = argv[k];
      continue;
    }
    if (k + 1 >= *argc) return cli_usage_error("run", "option %s needs a value", o);
    const char *v = argv[++k];
    if (!strcmp(o, "--checkpoint")) c->path = v;
    else if (!strcmp(o, "--resume")) c->resume = v;
    else if (!cli_parse_count(v, &c->every, 1)) {
      fprintf(stderr, "fascia run: bad value '%s' for %s (see fascia run --help)\n", v, o);
      return 2;
    }
  }
  *argc = kept;
  return -1;
}

// After step n: a checkpoint every K steps, after the last and on a stop.
static fascia_status checkpoint_after(const checkpoint_options *c, const fascia_solver *solver, int n, int last) {
  if (!c || !c->path || (n % c->every != 0 && !last)) return FASCIA_OK;
  return fascia_checkpoint_save_inputs(c->ctx, solver, n, c->inputs, c->path);
}

/// Everything the command line sets.
typedef struct run_options {
  const char *model_path, *results_path;
  int dynamic, static_given, steps, save_every, samples, json, threads;
  int newton_given;
  int static_time_given;  ///< --static-time T
  fascia_real static_time; ///< s: the time the static equilibrium is for
  const char *static_time_why; ///< where static_time came from, in words
  fascia_solver_def solver;
  const checkpoint_options *checkpoint; ///< --checkpoint, --resume; NULL: none
  run_outputs *outputs;                 ///< --history, --paraview, --snapshots; NULL: none
  run_drive *drive;                     ///< --drive ORGAN=FILE.csv; NULL: none
} run_options;

// Parses argv into opt. Returns -1 to go on, else the exit status (0 for
// --help, 2 for a usage error, already reported).
static int parse_options(int argc, char **argv, run_options *opt, const fascia_solver_def *start) {
  memset(opt, 0, sizeof *opt);
  opt->solver = start ? *start : fascia_solver_def_default();
  opt->save_every = 1;
  int dt_given = 0;
  for (int k = 1; k < argc; ++k) {
    const char *o = argv[k];
    if (cli_help(o, run_usage, run_usage_notes)) return 0;
    if (o[0] != '-' || !o[1]) {
      if (opt->model_path) return cli_usage_error("run", "unexpected argument '%s': one model file only", o);
      opt->model_path = o;
      continue;
    }
    if (!strcmp(o, "--verbose")) continue;
    if (!strcmp(o, "--static")) opt->static_given = 1;
    else if (!strcmp(o, "--samples")) opt->samples = 1;
    else if (!strcmp(o, "--json")) opt->json = 1;
    else if (!strcmp(o, "--cg-fixed")) opt->solver.cg_fixed = 1;
    else if (!strcmp(o, "--assembled")) opt->solver.assembled = 1;
    else if (!strcmp(o, "--matrix-free")) opt->solver.assembled = 0;
    else if (!strcmp(o, "--single")) opt->solver.single_precision_matrix = 1;
    else if (!strcmp(o, "--double")) opt->solver.single_precision_matrix = 0;
    else if (!strcmp(o, "--require-convergence")) opt->solver.require_convergence = 1;
    else if (!strcmp(o, "--accept-unconverged")) opt->solver.require_convergence = 0;
    else {
      static const char *const valued[] = {"--steps", "--dt", "-o", "--output", "--save-every", "--backend",
                                           "--threads", "--newton-iterations", "--newton-tolerance",
                                           "--cg-iterations", "--cg-tolerance", "--precond", "--mass", "--damping",
                                           "--load-steps", "--linear-solver", "--preset", "--step-retries",
                                           "--blow-up-strain", "--static-time", NULL};
      const char *v = NULL;
      const int bad = cli_option_value("run", argc, argv, &k, valued, &v);
      if (bad >= 0) return bad;
      fascia_solver_def *d = &opt->solver;
      int ok = 1;
      if (!strcmp(o, "--steps")) ok = cli_parse_count(v, &opt->steps, 1), opt->dynamic = 1;
      else if (!strcmp(o, "--dt")) ok = cli_parse_real(v, &d->time_step) && d->time_step > 0, dt_given = 1;
      else if (!strcmp(o, "-o") || !strcmp(o, "--output")) opt->results_path = v;
      else if (!strcmp(o, "--save-every")) ok = cli_parse_count(v, &opt->save_every, 1);
      else if (!strcmp(o, "--backend")) ok = cli_parse_backend(v, &d->backend);
      else if (!strcmp(o, "--threads")) ok = cli_parse_threads(v, &opt->threads), d->threads = opt->threads;
      else if (!strcmp(o, "--newton-iterations")) ok = cli_parse_count(v, &d->newton_iterations, 1), opt->newton_given = 1;
      else if (!strcmp(o, "--newton-tolerance")) ok = cli_parse_real(v, &d->newton_tolerance) && d->newton_tolerance >= 0;
      else if (!strcmp(o, "--cg-iterations")) ok = cli_parse_count(v, &d->cg_iterations, 1);
      else if (!strcmp(o, "--cg-tolerance"))
        ok = cli_parse_real(v, &d->cg_tolerance) && d->cg_tolerance >= 0 && d->cg_tolerance < 1;
      else if (!strcmp(o, "--precond")) {
        ok = !strcmp(v, "none") || !strcmp(v, "jacobi") || !strcmp(v, "block");
        d->precond = !strcmp(v, "none") ? FASCIA_PRECOND_NONE
                     : !strcmp(v, "jacobi") ? FASCIA_PRECOND_JACOBI
                                            : FASCIA_PRECOND_BLOCK_JACOBI;
      } else if (!strcmp(o, "--mass")) {
        ok = !strcmp(v, "consistent") || !strcmp(v, "lumped");
        d->mass = !strcmp(v, "lumped") ? FASCIA_MASS_LUMPED : FASCIA_MASS_CONSISTENT;
      } else if (!strcmp(o, "--linear-solver")) {
        ok = !strcmp(v, "cg") || !strcmp(v, "direct") || !strcmp(v, "auto");
        d->linear_solver = !strcmp(v, "cg")       ? FASCIA_LINEAR_CG
                           : !strcmp(v, "direct") ? FASCIA_LINEAR_DIRECT
                                                  : FASCIA_LINEAR_AUTO;
      } else if (!strcmp(o, "--preset")) {
        ok = cli_preset_apply(v, d); // a static solve keeps its own Newton limit (100)
      } else if (!strcmp(o, "--damping")) ok = cli_parse_real(v, &d->mass_damping) && d->mass_damping >= 0;
      else if (!strcmp(o, "--step-retries")) ok = cli_parse_count(v, &d->step_retries, 0);
      else if (!strcmp(o, "--static-time"))
        ok = cli_parse_real(v, &opt->static_time) && opt->static_time >= 0, opt->static_time_given = 1;
      else if (!strcmp(o, "--blow-up-strain")) ok = cli_parse_real(v, &d->blow_up_strain) && d->blow_up_strain >= 0;
      else ok = cli_parse_count(v, &d->load_steps, 1); // --load-steps
      if (!ok) {
        fprintf(stderr, "fascia run: bad value '%s' for %s%s (see fascia run --help)\n", v, o,
                !strcmp(o, "--threads") ? ": expected a whole number from 1 to " CLI_MAX_THREADS_TEXT : "");
        return 2;
      }
    }
  }
  if (!opt->model_path) return cli_usage_error("run", "%s", "missing MODEL.h5, the model file to run");
  if (opt->static_given && opt->dynamic) return cli_usage_error("run", "%s", "--static and --steps exclude each other");
  if (opt->static_time_given && opt->dynamic)
    return cli_usage_error("run", "%s", "--static-time is for a static solve; it excludes --steps");
  if (dt_given && !opt->dynamic) return cli_usage_error("run", "%s", "--dt needs --steps N (a dynamic run)");
  if (opt->dynamic && !isfinite((fascia_real)opt->steps * opt->solver.time_step)) {
    char what[160];
    snprintf(what, sizeof what, "--steps %d --dt %g end past the largest time a double holds", opt->steps,
             opt->solver.time_step);
    return cli_usage_error("run", "%s", what);
  }
  if (!opt->dynamic && !opt->newton_given) opt->solver.newton_iterations = 100;
  return -1;
}

/// What the run did, for the summary.
typedef struct run_totals {
  int steps, newton, cg, factorizations, converged_steps, interrupted, saved, direct_steps, assembled_steps, single_steps;
  int capacity;                       ///< of the per-step arrays, grown as steps are done
  int *newton_per_step, *cg_per_step; ///< [steps done]
  fascia_ctx *ctx;                    ///< for the out-of-memory message
  double solve_ms;                    ///< wall time inside the solver
  double largest_step_ms;             ///< the solver's wall time in the longest step
  fascia_profile profile;             ///< summed over steps
  fascia_real energy;                 ///< potential energy at the end, J
  fascia_real *organ_force_start;     ///< [3 organs] the tissue's force on each organ before the first step, N
} run_totals;

// The tissue's total force on each organ [3 organs], N: the sum of its
// reaction on the organ's coupling frames (elastic, and the weight of the
// tissue those frames carry). An organ without coupling frames gets 0.
static fascia_status organ_forces(fascia_solver *solver, const fascia_model *m, fascia_real *out) {
  fascia_real *forces = malloc(3 * ((size_t)m->coupling_count + 1) * sizeof *forces);
  if (!forces) return FASCIA_ERR_MEMORY;
  fascia_status st = FASCIA_OK;
  for (int32_t o = 0; o < m->organ_count && st == FASCIA_OK; ++o) {
    int32_t count = 0;
    for (int32_t c = 0; c < m->coupling_count; ++c) count += m->coupling_organ[c] == o;
    out[3 * o] = out[3 * o + 1] = out[3 * o + 2] = 0;
    if (!count) continue;
    st = fascia_solver_organ_reaction(solver, o, forces, NULL);
    for (int32_t c = 0; st == FASCIA_OK && c < count; ++c)
      for (int r = 0; r < 3; ++r) out[3 * o + r] += forces[3 * c + r];
  }
  free(forces);
  return st;
}

static double norm3(const fascia_real *v) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// The per-step counts grow with the steps done, not with --steps: a huge
// --steps must not fail up front for memory it would need only at the end.
static fascia_status add_report(run_totals *t, const fascia_solve_report *r) {
  if (t->steps == t->capacity) {
    const int capacity = t->capacity < 1024 ? 1024 : t->capacity < INT_MAX / 2 ? 2 * t->capacity : INT_MAX;
    int *newton = realloc(t->newton_per_step, (size_t)capacity * sizeof *newton);
    if (newton) t->newton_per_step = newton;
    int *cg = newton ? realloc(t->cg_per_step, (size_t)capacity * sizeof *cg) : NULL;
    if (cg) t->cg_per_step = cg;
    if (!newton || !cg || capacity == t->capacity)
      return fascia_ctx_fail(t->ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__,
                             "run: out of memory for the iteration counts of %d steps", t->steps + 1);
    t->capacity = capacity;
  }
  t->newton_per_step[t->steps] = r->newton_iterations;
  t->cg_per_step[t->steps] = r->cg_iterations;
  t->newton += r->newton_iterations;
  t->cg += r->cg_iterations;
  t->factorizations += r->factorizations;
  t->converged_steps += r->converged != 0;
  t->direct_steps += r->direct != 0;
  t->assembled_steps += r->assembled != 0;
  t->single_steps += r->single_precision_matrix != 0;
  fascia_profile_add(&t->profile, &r->profile);
  if (r->profile.total_ms > t->largest_step_ms) t->largest_step_ms = r->profile.total_ms;
  t->energy = r->energy;
  t->steps++;
  return FASCIA_OK;
}

static int progress_wanted(void) {
  const char *env = getenv("FASCIA_PROGRESS");
  if (env && !strcmp(env, "0")) return 0;
  return isatty(2) || (env && !strcmp(env, "1"));
}

// One progress line on stderr with an estimate of the time left.
static void print_step_progress(int done, int total, fascia_real t, double elapsed_ms, int final) {
  const long left_s = done > 0 ? lround(elapsed_ms / done * (total - done) / 1e3) : 0;
  fprintf(stderr, "\rstep %d/%d  t = %.4g s  %.3g ms/step  time left %ld:%02ld:%02ld\033[K%s", done, total, t,
          done > 0 ? elapsed_ms / done : 0.0, left_s / 3600, left_s / 60 % 60, left_s % 60, final ? "\n" : "");
  fflush(stderr);
}

// The time of solver step n, as every output writes it: n dt from t = 0 (a
// resumed run counts its steps from t = 0 too). The solver's own clock sums
// the steps and drifts from it by rounding, which gave ParaView two times
// per step when the results and the organs were loaded together.
static fascia_real step_time(const run_options *opt, int n) { return (fascia_real)n * opt->solver.time_step; }

// The run's settings as the results record them (run_settings): what was
// asked, in the options' own words; NULL when out of memory.
static const char *setting_text(const char *name, double value, int digits, char *buf, size_t size);

static char *settings_json(const run_options *opt) {
  const fascia_solver_def *d = &opt->solver;
  char buf[64];
  cJSON *o = cJSON_CreateObject();
  if (!o) return NULL;
  cJSON_AddStringToObject(o, "mode", opt->dynamic ? "dynamic" : "static");
  if (opt->dynamic) {
    cJSON_AddNumberToObject(o, "steps", opt->steps);
    cJSON_AddNumberToObject(o, "dt", d->time_step);
    cJSON_AddNumberToObject(o, "save_every", opt->save_every);
  } else {
    cJSON_AddNumberToObject(o, "static_time", opt->static_time);
    cJSON_AddNumberToObject(o, "load_steps", d->load_steps);
  }
  cJSON_AddStringToObject(o, "backend", d->backend ? d->backend : "auto");
  cJSON_AddNumberToObject(o, "threads", opt->threads);
  cJSON_AddNumberToObject(o, "newton_iterations", d->newton_iterations);
  cJSON_AddNumberToObject(o, "newton_tolerance", d->newton_tolerance);
  cJSON_AddStringToObject(o, "linear_solver", setting_text("linear_solver", d->linear_solver, 0, buf, sizeof buf));
  cJSON_AddNumberToObject(o, "cg_iterations", d->cg_iterations);
  cJSON_AddNumberToObject(o, "cg_tolerance", d->cg_tolerance);
  cJSON_AddBoolToObject(o, "cg_fixed", d->cg_fixed);
  cJSON_AddStringToObject(o, "precond", setting_text("precond", d->precond, 0, buf, sizeof buf));
  cJSON_AddStringToObject(o, "assembled", d->assembled == FASCIA_ASSEMBLED_AUTO ? "auto" : d->assembled ? "yes" : "no");
  cJSON_AddStringToObject(o, "single_precision_matrix",
                          setting_text("single_precision_matrix", d->single_precision_matrix, 0, buf, sizeof buf));
  cJSON_AddStringToObject(o, "mass", setting_text("mass", d->mass, 0, buf, sizeof buf));
  cJSON_AddNumberToObject(o, "damping", d->mass_damping);
  cJSON_AddNumberToObject(o, "step_retries", d->step_retries);
  cJSON_AddBoolToObject(o, "require_convergence", d->require_convergence);
  cJSON_AddNumberToObject(o, "blow_up_strain", d->blow_up_strain);
  char *text = cJSON_PrintUnformatted(o);
  cJSON_Delete(o);
  return text;
}

// Opens the results file, its fields described and what made them recorded
// (docs/results-format.md).
static fascia_status open_results(fascia_ctx *ctx, const run_options *opt, const fascia_model *model,
                                  const fascia_results_def *def, fascia_results **res) {
  fascia_status st = fascia_results_open(ctx, opt->results_path, model, def, res);
  if (st == FASCIA_OK) {
    char *settings = settings_json(opt);
    st = settings ? fascia_results_set_run(*res, opt->model_path, settings)
                  : fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__,
                                    "results '%s': out of memory for the run's settings", opt->results_path);
    cJSON_free(settings);
  }
  if (st == FASCIA_OK && !opt->dynamic)
    st = fascia_results_set_time_meaning(*res, "load factor of a static run: 0 the rest state, 1 the equilibrium");
  if (st == FASCIA_OK && opt->samples)
    st = fascia_results_describe_field(*res, "strain", "1",
                                       "Frobenius norm of the Green-Lagrange strain E = (F^T F - I) / 2");
  if (st == FASCIA_OK && opt->samples)
    st = fascia_results_describe_field(*res, "stress", "Pa", "Frobenius norm of the first Piola-Kirchhoff stress P");
  return st;
}

// Appends the solver's current state (and sample data) to the results at `time`.
static fascia_status save_state(fascia_results *res, const fascia_solver *solver, fascia_real time, int samples,
                                fascia_real *sample_buffer, fascia_real *strain, fascia_real *stress) {
  if (samples) fascia_solver_sample_positions(solver, sample_buffer);
  fascia_status st = fascia_results_append(res, time, fascia_solver_frame_positions(solver),
                                           fascia_solver_frame_rotations(solver), samples ? sample_buffer : NULL);
  if (st != FASCIA_OK || !samples) return st;
  fascia_solver_sample_strain(solver, strain, stress);
  st = fascia_results_append_field(res, "strain", strain);
  if (st == FASCIA_OK) st = fascia_results_append_field(res, "stress", stress);
  return st;
}

// Dynamic run: steps with the results saved every K steps; stops early on
// a signal or a failed step (its status returned, the state before it kept).
static fascia_status run_steps(fascia_solver *solver, const run_options *opt,
                               fascia_results *res, fascia_real *buffers[3], run_totals *tot) {
  const int show = progress_wanted();
  fascia_status st = FASCIA_OK;
  const int first = opt->checkpoint ? opt->checkpoint->first_step : 1;
  if (res) st = save_state(res, solver, step_time(opt, first - 1), opt->samples, buffers[0], buffers[1], buffers[2]);
  double last_print = -1e30;
  int last_saved = 0;
  for (int n = first; n <= opt->steps && st == FASCIA_OK; ++n) {
    fascia_solve_report report;
    const double t0 = cli_now_ms();
    if (opt->drive && opt->drive->count) // driven organs: their frames at this step's end
      st = run_drive_before_step(opt->drive, solver, fascia_solver_time(solver) + opt->solver.time_step);
    if (st != FASCIA_OK) break;
    st = fascia_solver_step(solver, &report);
    tot->solve_ms += cli_now_ms() - t0;
    if (st != FASCIA_OK) break;
    if ((st = add_report(tot, &report)) != FASCIA_OK) break;
    const int stop = run_stop_requested != 0; // read once: a signal from here on stops after the next step
    const int last = n == opt->steps || stop;
    if (res && (n % opt->save_every == 0 || last)) {
      st = save_state(res, solver, step_time(opt, n), opt->samples, buffers[0], buffers[1], buffers[2]);
      last_saved = n;
    }
    if (st == FASCIA_OK && opt->outputs)
      st = run_outputs_step(opt->outputs, solver, n, &report, cli_now_ms() - t0, n % opt->save_every == 0 || last,
                            step_time(opt, n));
    if (st == FASCIA_OK) st = checkpoint_after(opt->checkpoint, solver, n, last);
    if (show && (cli_now_ms() - last_print > 200 || last)) {
      print_step_progress(n, opt->steps, fascia_solver_time(solver), tot->solve_ms, last);
      last_print = cli_now_ms();
    }
    if (stop) {
      tot->interrupted = 1;
      break;
    }
  }
  // a failed step: keep the last good state in the file
  if (res && st == FASCIA_ERR_NUMERIC && first - 1 + tot->steps > last_saved)
    (void)save_state(res, solver, step_time(opt, first - 1 + tot->steps), opt->samples, buffers[0], buffers[1],
                     buffers[2]);
  if (show && tot->steps < opt->steps && !tot->interrupted) fputc('\n', stderr); // a failed step
  return st;
}

static fascia_real largest(const fascia_real *values, int32_t count) {
  fascia_real m = 0;
  for (int32_t s = 0; s < count; ++s)
    if (values[s] > m || values[s] != values[s]) m = values[s]; // NaN shows
  return m;
}

static void probe_state(const fascia_solver *solver, const fascia_model *m, int32_t p, fascia_real pos[3],
                        fascia_real disp[3]) {
  fascia_solver_probe_position(solver, p, pos);
  for (int c = 0; c < 3; ++c) disp[c] = pos[c] - m->probe_position[3 * p + c];
}

// Which linear solver the steps used: "direct", "cg" or "mixed".
static const char *linear_name(const run_totals *t) {
  return t->direct_steps == 0 ? "cg" : t->direct_steps == t->steps ? "direct" : "mixed";
}

static void print_text(const run_options *opt, const fascia_model *m, fascia_solver *solver,
                       const run_totals *t, fascia_real max_strain, fascia_real max_stress, int failed) {
  const int steps = t->steps > 0 ? t->steps : 1;
  printf("model       %s (%d frames, %d samples)\n", opt->model_path, (int)m->frame_count, (int)m->sample_count);
  if (opt->dynamic)
    printf("run         %d of %d implicit Euler steps of %g s%s, t = %g s\n", t->steps, opt->steps,
           opt->solver.time_step, t->interrupted ? " (interrupted)" : "", fascia_solver_time(solver));
  else
    printf("run         static equilibrium at t = %g s (%s), %s\n", opt->static_time, opt->static_time_why,
           failed ? "FAILED" : t->converged_steps == t->steps ? "converged" : "NOT converged");
  if (failed) // the figures below are of the last good state; the reason follows on stderr
    printf("ended       failed%s\n", opt->dynamic ? " (the state after the last step taken)" : " (the state reached)");
  printf("backend     %s\n", fascia_solver_backend(solver));
  printf("device      %s\n", fascia_solver_device(solver));
  printf("linear      %s%s\n", linear_name(t),
         t->direct_steps > 0        ? ""
         : t->assembled_steps == 0  ? " (matrix-free)"
         : t->single_steps > 0      ? " (assembled matrix, float copy for the products)"
                                    : " (assembled matrix)");
  printf("time        %.3f ms per step (evaluate %.3f, preconditioner %.3f, assembly %.3f, linear solves %.3f)\n",
         t->solve_ms / steps, t->profile.evaluate_ms / steps, t->profile.precond_ms / steps,
         t->profile.assemble_ms / steps, t->profile.cg_ms / steps);
  printf("iterations  Newton %d (%.2f per step), CG %d (%.1f per step)", t->newton, (double)t->newton / steps,
         t->cg, (double)t->cg / steps);
  if (t->direct_steps > 0) printf(", %d factorizations (chord steps keep one)", t->factorizations);
  if (opt->dynamic) printf(", %d of %d steps converged", t->converged_steps, t->steps);
  printf("\nenergy      potential %.9g J, kinetic %.9g J\n", t->energy,
         fascia_solver_kinetic_energy(solver));
  printf("strain      largest %.6g (Green-Lagrange norm), largest stress %.6g Pa\n", max_strain, max_stress);
  fascia_real *end = t->organ_force_start ? malloc(3 * (size_t)m->organ_count * sizeof *end) : NULL;
  if (end && organ_forces(solver, m, end) == FASCIA_OK) {
    printf("organs      the tissue's force on each organ, change over the run (N):");
    for (int32_t o = 0; o < m->organ_count; ++o) {
      const fascia_real change[3] = {end[3 * o] - t->organ_force_start[3 * o],
                                     end[3 * o + 1] - t->organ_force_start[3 * o + 1],
                                     end[3 * o + 2] - t->organ_force_start[3 * o + 2]};
      printf("%s %s %.3g", o ? "," : "", m->organs[o].name, norm3(change));
    }
    printf("\n");
  }
  free(end);
  for (int32_t p = 0; p < m->probe_count; ++p) {
    fascia_real pos[3], u[3];
    probe_state(solver, m, p, pos, u);
    printf("probe %-12s displacement (%.6g, %.6g, %.6g) m, position (%.6g, %.6g, %.6g) m\n", m->probe_name[p],
           u[0], u[1], u[2], pos[0], pos[1], pos[2]);
  }
  for (int k = 0; opt->drive && k < opt->drive->count; ++k) {
    const drive_organ *d = opt->drive->organs + k;
    printf("drive       organ %s from %s (%d rows, t = %g to %g s)\n", d->organ_name, d->path, (int)d->row_count,
           d->time[0], d->time[d->row_count - 1]);
  }
  if (opt->results_path) printf("results     %s (%d saved steps)\n", opt->results_path, t->saved);
}

static cJSON *int_array(const int *values, int count) {
  cJSON *a = cJSON_CreateArray();
  for (int k = 0; a && k < count; ++k) cJSON_AddItemToArray(a, cJSON_CreateNumber(values[k]));
  return a;
}

// Displacement of the body from rest: the volume-weighted mean over samples
// (an integral of |u|, comparable across resolutions) and the largest (m).
// Samples that integrate only the volumetric energy repeat the volume of
// others and are left out.
static void sample_displacements(const fascia_model *m, const fascia_solver *solver, double *mean, double *max) {
  *mean = *max = 0;
  fascia_real *p = malloc(3 * (size_t)m->sample_count * sizeof *p);
  if (!p) return;
  fascia_solver_sample_positions(solver, p);
  double volume = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    if (m->materials[m->sample_material[s]].part == FASCIA_PART_VOLUMETRIC) continue;
    double u2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double d = p[3 * (int64_t)s + c] - m->sample_position[3 * (int64_t)s + c];
      u2 += d * d;
    }
    const double u = sqrt(u2);
    *mean += m->sample_volume[s] * u;
    volume += m->sample_volume[s];
    if (u > *max) *max = u;
  }
  if (volume > 0) *mean /= volume;
  free(p);
}

// The summary as one JSON object, without how the run ended: cmd_run adds
// that ("ended", "converged", "exit_status", "error") once it is known.
static cJSON *summary_json(const run_options *opt, const fascia_model *m, fascia_solver *solver, const run_totals *t,
                           fascia_real max_strain, fascia_real max_stress) {
  const int steps = t->steps > 0 ? t->steps : 1;
  cJSON *root = cJSON_CreateObject();
  if (!root) return NULL;
  cJSON_AddStringToObject(root, "model", opt->model_path);
  cJSON_AddStringToObject(root, "mode", opt->dynamic ? "dynamic" : "static");
  if (!opt->dynamic) {
    cJSON_AddNumberToObject(root, "static_time", opt->static_time);
    cJSON_AddStringToObject(root, "static_time_of", opt->static_time_why);
  }
  cJSON_AddStringToObject(root, "backend", fascia_solver_backend(solver));
  cJSON_AddStringToObject(root, "device", fascia_solver_device(solver));
  cJSON_AddStringToObject(root, "linear_solver", linear_name(t));
  // what CG multiplied by: "none" where every step solved directly
  cJSON_AddStringToObject(root, "cg_product", t->direct_steps == t->steps && t->steps > 0 ? "none"
                                              : t->assembled_steps == 0                  ? "matrix-free"
                                              : t->single_steps > 0                      ? "assembled float"
                                                                                         : "assembled double");
  cJSON_AddNumberToObject(root, "threads", opt->threads);
  cJSON_AddNumberToObject(root, "frames", m->frame_count);
  cJSON_AddNumberToObject(root, "samples", m->sample_count);
  cJSON_AddNumberToObject(root, "steps", t->steps);
  if (opt->dynamic) cJSON_AddNumberToObject(root, "dt", opt->solver.time_step);
  cJSON_AddNumberToObject(root, "time", fascia_solver_time(solver));
  cJSON_AddNumberToObject(root, "converged_steps", t->converged_steps);
  cJSON_AddBoolToObject(root, "interrupted", t->interrupted);
  cJSON_AddNumberToObject(root, "ms_per_step", t->solve_ms / steps);
  cJSON_AddNumberToObject(root, "wall_ms", t->solve_ms);
  cJSON_AddNumberToObject(root, "newton_iterations", t->newton);
  cJSON_AddNumberToObject(root, "cg_iterations", t->cg);
  cJSON_AddNumberToObject(root, "factorizations", t->factorizations);
  cJSON_AddItemToObject(root, "newton_iterations_per_step", int_array(t->newton_per_step, t->steps));
  cJSON_AddNumberToObject(root, "largest_step_ms", t->largest_step_ms);
  cJSON_AddItemToObject(root, "cg_iterations_per_step", int_array(t->cg_per_step, t->steps));
  cJSON *profile = cJSON_AddObjectToObject(root, "profile_ms_per_step");
  cJSON_AddNumberToObject(profile, "evaluate", t->profile.evaluate_ms / steps);
  cJSON_AddNumberToObject(profile, "precond", t->profile.precond_ms / steps);
  cJSON_AddNumberToObject(profile, "assemble", t->profile.assemble_ms / steps);
  cJSON_AddNumberToObject(profile, "cg", t->profile.cg_ms / steps);
  cJSON_AddNumberToObject(profile, "total", t->profile.total_ms / steps);
  cJSON_AddNumberToObject(root, "energy", t->energy);
  cJSON_AddNumberToObject(root, "kinetic_energy", fascia_solver_kinetic_energy(solver));
  cJSON_AddNumberToObject(root, "max_strain", max_strain);
  cJSON_AddNumberToObject(root, "max_stress", max_stress);
  double mean_u, max_u;
  sample_displacements(m, solver, &mean_u, &max_u);
  cJSON *displacement = cJSON_AddObjectToObject(root, "displacement");
  cJSON_AddNumberToObject(displacement, "mean", mean_u);
  cJSON_AddNumberToObject(displacement, "max", max_u);
  cJSON *probes = cJSON_AddObjectToObject(root, "probes");
  for (int32_t p = 0; p < m->probe_count; ++p) {
    fascia_real pos[3], u[3];
    probe_state(solver, m, p, pos, u);
    cJSON *item = cJSON_AddObjectToObject(probes, m->probe_name[p]);
    cJSON_AddItemToObject(item, "displacement", cJSON_CreateDoubleArray(u, 3));
    cJSON_AddItemToObject(item, "position", cJSON_CreateDoubleArray(pos, 3));
    cJSON_AddItemToObject(item, "rest_position", cJSON_CreateDoubleArray(m->probe_position + 3 * p, 3));
  }
  fascia_real *end = t->organ_force_start ? malloc(3 * (size_t)m->organ_count * sizeof *end) : NULL;
  if (end && organ_forces(solver, m, end) == FASCIA_OK) { // organ name -> the tissue's force at the start and end
    cJSON *organs = cJSON_AddObjectToObject(root, "organ_force");
    for (int32_t o = 0; o < m->organ_count; ++o) {
      cJSON *item = cJSON_AddObjectToObject(organs, m->organs[o].name);
      cJSON_AddItemToObject(item, "start", cJSON_CreateDoubleArray(t->organ_force_start + 3 * o, 3));
      cJSON_AddItemToObject(item, "end", cJSON_CreateDoubleArray(end + 3 * o, 3));
    }
  }
  free(end);
  cJSON *driven = cJSON_AddObjectToObject(root, "drive"); // organ name -> its CSV file
  for (int k = 0; opt->drive && k < opt->drive->count; ++k)
    cJSON_AddStringToObject(driven, opt->drive->organs[k].organ_name, opt->drive->organs[k].path);
  if (opt->results_path) {
    cJSON_AddStringToObject(root, "results", opt->results_path);
    cJSON_AddNumberToObject(root, "saved_steps", t->saved);
  } else {
    cJSON_AddNullToObject(root, "results");
  }
  return root;
}

// How the run ended, added to its summary and printed: "completed" (every
// step asked for was taken, and "converged" says whether each converged),
// "interrupted" or "failed" (then "converged" is false whatever the steps
// before the failure did, and "error" holds the reason).
static int emit_json(cJSON *root, const run_options *opt, const run_totals *t, int exit_status) {
  const char *ended = exit_status == 0 ? "completed" : t->interrupted ? "interrupted" : "failed";
  const int all_done = opt->dynamic ? t->steps > 0 && t->steps + (opt->checkpoint ? opt->checkpoint->first_step - 1 : 0) == opt->steps : t->steps == 1;
  cJSON_AddStringToObject(root, "ended", ended);
  cJSON_AddBoolToObject(root, "converged", exit_status == 0 && all_done && t->converged_steps == t->steps);
  return cli_json_emit(root, exit_status);
}

// --- resuming: the checkpoint's settings, the command line's --steps --------

// The run option that sets each checkpointed setting (by its name).
static const char *setting_option(const char *name) {
  static const char *const table[][2] = {
      {"time_step", "--dt"},           {"newton_iterations", "--newton-iterations"},
      {"newton_tolerance", "--newton-tolerance"}, {"cg_iterations", "--cg-iterations"},
      {"cg_fixed", "--cg-fixed"},      {"cg_tolerance", "--cg-tolerance"},
      {"precond", "--precond"},        {"linear_solver", "--linear-solver"},
      {"assembled", "--assembled"},    {"single_precision_matrix", "--single or --double"},
      {"mass", "--mass"},              {"mass_damping", "--damping"},
      {"step_retries", "--step-retries"}, {"require_convergence", "--require-convergence"},
      {"blow_up_strain", "--blow-up-strain"}};
  for (size_t k = 0; k < sizeof table / sizeof table[0]; ++k)
    if (!strcmp(table[k][0], name)) return table[k][1];
  return "no option";
}

// A setting's value as the option spells it: "block", "lumped", "on", 0.005.
static const char *setting_text(const char *name, double value, int digits, char *buf, size_t size) {
  static const char *const precond[] = {"none", "jacobi", "block"}, *const linear[] = {"auto", "cg", "direct"},
                           *const mass[] = {"consistent", "lumped"};
  const int i = (int)value;
  const int flag = !strcmp(name, "cg_fixed") || !strcmp(name, "assembled") || !strcmp(name, "single_precision_matrix") ||
                   !strcmp(name, "line_search") || !strcmp(name, "require_convergence");
  if (!strcmp(name, "precond") && i >= 0 && i < 3) return precond[i];
  if (!strcmp(name, "linear_solver") && i >= 0 && i < 3) return linear[i];
  if (!strcmp(name, "mass") && i >= 0 && i < 2) return mass[i];
  if (flag && (i == 0 || i == 1)) return i ? "on" : "off";
  if ((!strcmp(name, "single_precision_matrix") && i == FASCIA_SINGLE_AUTO) ||
      (!strcmp(name, "assembled") && i == FASCIA_ASSEMBLED_AUTO))
    return "auto";
  snprintf(buf, size, "%.*g", digits, value);
  return buf;
}

#define SETTING_UNSET 2000000001.0 // beyond every setting's valid range: no option or preset sets it

// Resuming takes the settings stored in the checkpoint; a setting the command
// line sets itself (an option or --preset, found by parsing argv again over
// a def of SETTING_UNSET values) must agree with it. Returns -1 to go on with
// opt->solver holding the checkpoint's settings, else the exit status (2).
static int take_resume_settings(int argc, char **argv, run_options *opt, const fascia_solver_def *recorded,
                                const char *checkpoint) {
  fascia_solver_def unset = opt->solver;
  const int count = fascia_checkpoint_setting_count();
  for (int k = 0; k < count; ++k) fascia_checkpoint_setting_set(&unset, k, SETTING_UNSET);
  run_options given;
  if (parse_options(argc, argv, &given, &unset) >= 0) return 2; // cannot happen: argv parsed once already
  int preset = 0;
  for (int k = 1; k < argc; ++k) preset |= !strcmp(argv[k], "--preset");
  for (int k = 0; k < count; ++k) {
    const double asked = fascia_checkpoint_setting_get(&given.solver, k);
    const double stored = fascia_checkpoint_setting_get(recorded, k);
    if (asked != SETTING_UNSET && asked != stored) {
      const char *name = fascia_checkpoint_setting_name(k);
      char there_buf[32], here_buf[32];
      const char *there = setting_text(name, stored, 15, there_buf, sizeof there_buf);
      const char *here = setting_text(name, asked, 15, here_buf, sizeof here_buf);
      if (!strcmp(there, here)) { // apart beyond 15 digits: show them all
        there = setting_text(name, stored, 17, there_buf, sizeof there_buf);
        here = setting_text(name, asked, 17, here_buf, sizeof here_buf);
      }
      fprintf(stderr,
              "fascia run: checkpoint '%s' was written with %s = %s, the command line asks for %s (%s%s); a "
              "resumed run keeps the settings it started with: leave the option out (see fascia run --help)\n",
              checkpoint, name, there, here, setting_option(name), preset ? " or --preset" : "");
      return 2;
    }
    fascia_checkpoint_setting_set(&opt->solver, k, stored);
  }
  return -1;
}

// Every file the run reads or writes, checked before any work
// (cli_check_paths): -o and its XDMF sidecar, --checkpoint (which may be the
// --resume file: continuing into it is the normal use), the text outputs
// and the drive templates against the model, --resume and the drive files.
static int check_run_paths(const run_options *opt, const checkpoint_options *ck, const run_outputs *outs,
                           const run_drive *drive) {
  // per saved step: <organ>-<k>.vtp, tissue-<k>.vtp, samples-<k>.vtu, frames-<k>.vtu, tetrahedra-<k>.vtu
  static const char *const organ_names[] = {"run.pvd", "organs.pvd", "*-[0-9]*.vtp", "*-[0-9]*.vtu", NULL};
  static const char *const snapshot_names[] = {"tissue-rest.csv", "tissue-final.csv", "organs-rest.csv",
                                               "organs-final.csv", NULL};
  const int most = 8 + drive->count + drive->template_count;
  cli_path *paths = calloc((size_t)most, sizeof *paths);
  if (!paths) {
    fprintf(stderr, "fascia run: out of memory\n");
    return 1;
  }
  char sidecar[4096] = "";
  if (opt->results_path) fascia_results_sidecar_path(opt->results_path, sidecar, sizeof sidecar);
  int n = 0;
  paths[n++] = (cli_path){"model", opt->model_path, CLI_INPUT, NULL, NULL};
  paths[n++] = (cli_path){"--resume", ck->resume, CLI_INPUT, NULL, NULL};
  for (int k = 0; k < drive->count; ++k) paths[n++] = (cli_path){"--drive", drive->organs[k].path, CLI_INPUT, NULL, NULL};
  paths[n++] = (cli_path){"-o", opt->results_path, CLI_OUTPUT_FILE, NULL, NULL};
  paths[n++] = (cli_path){"-o (its XDMF sidecar)", opt->results_path && opt->results_path[0] ? sidecar : NULL,
                          CLI_OUTPUT_FILE, NULL, NULL};
  paths[n++] = (cli_path){"--checkpoint", ck->path, CLI_OUTPUT_FILE, NULL, "--resume"};
  paths[n++] = (cli_path){"--history", outs->history_path, CLI_OUTPUT_FILE, NULL, NULL};
  paths[n++] = (cli_path){"--paraview", outs->paraview_dir, CLI_OUTPUT_DIR, organ_names, NULL};
  paths[n++] = (cli_path){"--snapshots", outs->snapshots_dir, CLI_OUTPUT_DIR, snapshot_names, NULL};
  for (int k = 0; k < drive->template_count; ++k)
    paths[n++] = (cli_path){"--drive-template", drive->templates[k].path, CLI_OUTPUT_FILE, NULL, NULL};
  const int rc = cli_check_paths("run", paths, n);
  free(paths);
  return rc;
}

// A byte count for people: "3.2 GB", "180 kB".
static const char *human_bytes(double bytes, char *out, size_t size) {
  static const char *const units[] = {"bytes", "kB", "MB", "GB", "TB", "PB"};
  int u = 0;
  while (bytes >= 1000 && u < 5) bytes /= 1000, ++u;
  snprintf(out, size, "%.3g %s", bytes, units[u]);
  return out;
}

// Refuses a results file the disk cannot hold, before the first step: a
// huge --steps saves a row per K steps of every frame (and sample).
static fascia_status check_results_size(fascia_ctx *ctx, const run_options *opt, const checkpoint_options *ck,
                                        const fascia_model *m) {
  if (!opt->results_path) return FASCIA_OK;
  const double steps = opt->dynamic ? (double)opt->steps - ck->first_step + 1 : 1;
  const double saved = opt->dynamic ? floor(steps / opt->save_every) + 2 : 2; // the rest state and the last too
  const double row = 8.0 * (1 + 7.0 * m->frame_count + (opt->samples ? 5.0 * m->sample_count : 0));
  const double bytes = saved * row + (double)FASCIA_RESULTS_SPACE_MARGIN; // as the writer will ask for
  char folder[4096];
  fascia_path_folder(opt->results_path, folder, sizeof folder);
  struct statvfs fs;
  if (statvfs(folder, &fs) != 0) return FASCIA_OK;
  const double free_bytes = (double)fs.f_bavail * (double)fs.f_frsize;
  if (bytes <= free_bytes) return FASCIA_OK;
  char total[32], room[32];
  return fascia_ctx_fail(ctx, FASCIA_ERR_ARGUMENT, __FILE__, __LINE__,
                         "-o '%s': %.0f saved steps of %.0f bytes each (%d frames%s) make %s of results, and folder "
                         "'%s' has %s free; save fewer steps (--save-every K, fewer --steps) or write elsewhere",
                         opt->results_path, saved, row, (int)m->frame_count, opt->samples ? " and samples" : "",
                         human_bytes(bytes, total, sizeof total), folder, human_bytes(free_bytes, room, sizeof room));
}

int cmd_run(int argc, char **argv) {
  run_options opt;
  checkpoint_options ck;
  int rc = take_checkpoint_options(&argc, argv, &ck);
  if (rc >= 0) return rc;
  run_outputs outs;
  if ((rc = run_outputs_take(&argc, argv, &outs)) >= 0) return rc;
  run_drive drive;
  if ((rc = run_drive_take(&argc, argv, &drive)) < 0) rc = parse_options(argc, argv, &opt, NULL);
  if (rc == 0 && ck.help) fputs(checkpoint_usage, stdout), fputs("Outputs for people and plots:\n", stdout),
                          fputs(run_outputs_usage, stdout), fputs(run_drive_usage, stdout);
  if (rc < 0 && (ck.path || ck.resume) && !opt.dynamic)
    rc = cli_usage_error("run", "%s", "--checkpoint and --resume need a dynamic run (--steps N)");
  if (rc < 0 && drive.count && !opt.dynamic && !drive.template_count)
    rc = cli_usage_error("run", "%s", "--drive needs a dynamic run (--steps N)");
  if (rc < 0) rc = check_run_paths(&opt, &ck, &outs, &drive);
  if (rc >= 0) {
    run_drive_free(&drive);
    return rc;
  }
  opt.checkpoint = &ck;
  opt.outputs = &outs;
  opt.drive = &drive;
  fascia_ctx *ctx = cli_ctx(opt.threads, 1);
  if (opt.threads <= 0) opt.threads = fascia_ctx_threads(ctx); // for the summary
  fascia_model *model = NULL;
  fascia_solver *solver = NULL;
  fascia_results *res = NULL;
  fascia_real *buffers[3] = {NULL, NULL, NULL}; // sample positions [3S], strain [S], stress [S]
  cJSON *summary = NULL; // --json: printed once the exit status is known
  run_totals tot;
  memset(&tot, 0, sizeof tot);
  tot.ctx = ctx;
  struct sigaction old_signals[2];
  int signals_caught = 0;
  fascia_status st = fascia_model_load(ctx, opt.model_path, &model);
  if (st != FASCIA_OK) goto done;
  int64_t done_steps = 0;
  if (ck.resume) { // the settings come from the checkpoint, --steps counts from t = 0
    fascia_solver_def recorded = opt.solver;
    if ((st = fascia_checkpoint_read_settings(ctx, ck.resume, model, &recorded, &done_steps)) != FASCIA_OK) goto done;
    if ((rc = take_resume_settings(argc, argv, &opt, &recorded, ck.resume)) >= 0) goto done;
    if (done_steps == opt.steps) { // a run resumed after it finished (a script resuming blindly): said, not run
      fprintf(stderr, "fascia run: checkpoint '%s' is at step %lld of --steps %d: the run is already complete, "
              "nothing to do\n", ck.resume, (long long)done_steps, opt.steps);
      rc = 0;
      goto done;
    }
    if (done_steps > opt.steps) {
      fprintf(stderr,
              "fascia run: checkpoint '%s' is at step %lld, past --steps %d; --steps counts every step from t = 0: "
              "give --steps larger than %lld to continue (see fascia run --help)\n",
              ck.resume, (long long)done_steps, opt.steps, (long long)done_steps);
      rc = 2;
      goto done;
    }
  }
  st = fascia_solver_create(ctx, model, &opt.solver, &solver);
  if (st == FASCIA_ERR_FORMAT) { // the model cannot be simulated as it is (an organ, say): not a usage error
    fprintf(stderr, "fascia run: model '%s': %s\n", opt.model_path, fascia_ctx_message(ctx));
    rc = 1;
    st = FASCIA_OK;
    goto done;
  }
  if (st != FASCIA_OK) { // an impossible setting (usage error) or no such device
    rc = cli_solver_fail("run", opt.solver.backend, ctx, st);
    st = FASCIA_OK;
    goto done;
  }
  ck.ctx = ctx;
  if (ck.resume) { // the state, time and step count of the checkpoint
    if ((st = fascia_checkpoint_load(ctx, solver, ck.resume, &done_steps)) != FASCIA_OK) goto done;
    ck.first_step = (int)done_steps + 1; // done_steps < opt.steps, checked above
    fprintf(stderr, "fascia run: resumed from '%s' after step %lld (t = %.9g s)\n", ck.resume,
            (long long)done_steps, fascia_solver_time(solver));
  }
  if (drive.template_count) { // --drive-template: write them and stop, nothing solved
    if ((st = run_drive_write_templates(&drive, ctx, model, solver)) != FASCIA_OK) goto done;
    for (int k = 0; k < drive.template_count; ++k)
      printf("drive template for organ %s (%d coupling frames): %s\n", drive.templates[k].organ_name,
             (int)drive.templates[k].frame_count, drive.templates[k].path);
    rc = 0;
    goto done;
  }
  // every drive file is read and checked before any output is opened
  if ((st = run_drive_load(&drive, ctx, model, solver)) != FASCIA_OK) goto done;
  ck.inputs = run_drive_digest(&drive);
  if (ck.resume) { // the organs driven as the run that saved the checkpoint drove them
    uint64_t recorded = 0;
    if ((st = fascia_checkpoint_read_inputs(ctx, ck.resume, model, &recorded)) != FASCIA_OK) goto done;
    if (recorded != ck.inputs) {
      fprintf(stderr, "fascia run: --resume '%s': %s; resume with the same --drive ORGAN=FILE.csv options and "
              "unchanged files, or start the run again\n", ck.resume,
              !recorded ? "the run that saved it drove no organ from a file, and this one gives --drive"
              : !ck.inputs ? "the run that saved it drove organs from --drive files, and this one gives none"
                           : "the run that saved it drove its organs from other --drive files or other rows");
      rc = 2;
      goto done;
    }
  }
  if ((st = check_results_size(ctx, &opt, &ck, model)) != FASCIA_OK) goto done;
  const size_t S = (size_t)model->sample_count + 1;
  buffers[0] = malloc(3 * S * sizeof(fascia_real));
  buffers[1] = malloc(S * sizeof(fascia_real));
  buffers[2] = malloc(S * sizeof(fascia_real));
  if (!buffers[0] || !buffers[1] || !buffers[2]) {
    st = fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "run: out of memory for %d samples",
                         (int)model->sample_count);
    goto done;
  }
  fascia_results_def rdef = fascia_results_def_default();
  rdef.write_samples = opt.samples != 0;
  rdef.every = opt.dynamic ? opt.save_every : 1;
  if (opt.dynamic) catch_stop_signals(old_signals), signals_caught = 1;
  // the results file first: its space check is the strictest, and it fails
  // before a text output has been started
  if (opt.results_path && (st = open_results(ctx, &opt, model, &rdef, &res)) != FASCIA_OK) goto done;
  // a static run saves two steps, the rest state (0) and the equilibrium (1)
  if ((st = run_outputs_begin(&outs, ctx, model, solver, opt.dynamic ? step_time(&opt, ck.first_step - 1) : 0)) !=
      FASCIA_OK)
    goto done;
  tot.organ_force_start = malloc(3 * ((size_t)model->organ_count + 1) * sizeof *tot.organ_force_start);
  if (tot.organ_force_start && organ_forces(solver, model, tot.organ_force_start) != FASCIA_OK)
    free(tot.organ_force_start), tot.organ_force_start = NULL; // a state not finite: no forces to report
  if (opt.dynamic) {
    st = run_steps(solver, &opt, res, buffers, &tot);
  } else {
    fascia_solve_report report;
    // prescribed organs stand where their motions end, unless told otherwise:
    // the equilibrium at t = 0 would ignore the motion altogether
    const fascia_real end = fascia_model_motion_end(model);
    if (!opt.static_time_given) opt.static_time = end;
    opt.static_time_why = opt.static_time_given ? "given by --static-time"
                          : model->motion_count > 0 ? "the end of the prescribed motions"
                                                    : "no prescribed motion";
    if (res && (st = save_state(res, solver, 0, opt.samples, buffers[0], buffers[1], buffers[2])) != FASCIA_OK) goto done;
    if ((st = fascia_solver_set_time(solver, opt.static_time)) != FASCIA_OK) goto done;
    const double t0 = cli_now_ms();
    st = fascia_solver_solve_static(solver, &report);
    tot.solve_ms = cli_now_ms() - t0;
    if (st == FASCIA_OK || st == FASCIA_ERR_NUMERIC) { // not converged: state kept
      const fascia_status ast = add_report(&tot, &report);
      if (ast != FASCIA_OK) st = ast;
    }
    if (st == FASCIA_OK) st = run_outputs_step(&outs, solver, 1, &report, tot.solve_ms, 1, 1);
    // the equilibrium (or the state reached) is written either way
    if ((st == FASCIA_OK || st == FASCIA_ERR_NUMERIC) && res) {
      const fascia_status wst = save_state(res, solver, 1, opt.samples, buffers[0], buffers[1], buffers[2]);
      if (wst != FASCIA_OK) st = wst;
    }
  }
  if (st == FASCIA_OK) st = run_outputs_end(&outs, solver, 1);
  if (res) {
    tot.saved = fascia_results_step_count(res);
    fascia_status cst = fascia_results_close(&res);
    if (st == FASCIA_OK) st = cst;
  }
  if (tot.steps > 0 || !opt.dynamic || opt.json) { // JSON also for a run that failed at its first step
    fascia_solver_sample_strain(solver, buffers[1], buffers[2]);
    const fascia_real max_strain = largest(buffers[1], model->sample_count);
    const fascia_real max_stress = largest(buffers[2], model->sample_count);
    if (opt.json) {
      summary = summary_json(&opt, model, solver, &tot, max_strain, max_stress);
      if (!summary) st = fascia_ctx_fail(ctx, FASCIA_ERR_MEMORY, __FILE__, __LINE__, "run: out of memory for --json");
    } else {
      print_text(&opt, model, solver, &tot, max_strain, max_stress, st != FASCIA_OK);
    }
    fflush(stdout);
  }
  if (tot.interrupted && st == FASCIA_OK) { // not what was asked: a failure, with the steps done kept
    fprintf(stderr, "fascia run: interrupted after step %d of %d%s\n", tot.steps, opt.steps,
            opt.results_path ? "; results file closed with the steps done" : "");
    rc = 1;
  }
done:
  if (st != FASCIA_OK && rc != 2) rc = cli_fail("run", ctx, st);
  else if (rc < 0) rc = 0;
  if (summary) rc = emit_json(summary, &opt, &tot, rc); // else cli_json_finish says how it ended
  cJSON_Delete(summary);
  // closes what is still open after an error; a run that took no step keeps
  // the older files of those names rather than replace them with nothing
  if (tot.steps > 0) (void)run_outputs_end(&outs, solver, 0);
  else run_outputs_discard(&outs);
  fascia_results_destroy(&res);
  // Every output is closed or removed. A run a signal stopped keeps catching
  // them until it exits: a repeated Ctrl-C that lands after the outputs are
  // closed must not turn "exit 1, steps saved" into "killed by a signal".
  if (signals_caught && !run_stop_requested) restore_signals(old_signals);
  run_drive_free(&drive);
  free(buffers[0]), free(buffers[1]), free(buffers[2]);
  free(tot.newton_per_step), free(tot.cg_per_step), free(tot.organ_force_start);
  fascia_solver_destroy(&solver);
  fascia_model_destroy(&model);
  fascia_ctx_destroy(&ctx);
  return rc;
}
