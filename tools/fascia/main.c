// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The fascia command-line program: dispatches to one subcommand per file
// (cmd_<name>.c) through the table below. Only the CLI prints or exits.
#define _POSIX_C_SOURCE 200809L // setenv
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "commands.h"
#include "fascia/fascia.h"

int cli_verbose = 0;

static const fascia_command commands[] = {
    {"info", cmd_info, "print the version, build options and backends"},
    {"beam", cmd_beam, "write the paper's cantilever beam as a model file"},
    {"prep", cmd_prep, "build a tissue model from organ meshes and a scene file"},
    {"inspect", cmd_inspect, "check a model file and print a summary (--json for one JSON object)"},
    {"run", cmd_run, "solve a model statically or with implicit Euler steps; write results"},
    {"bench", cmd_bench, "time the paper's tables (paper) and the cantilever accuracy sweep (cantilever)"},
    {"tradeoff", cmd_tradeoff, "speed against accuracy on your scene (SCENE.json) or the cantilever: Pareto, advice"},
};
static const int command_count = (int)(sizeof commands / sizeof commands[0]);

static void usage(FILE *out) {
  fprintf(out, "usage: fascia COMMAND [OPTIONS]   (fascia COMMAND --help for its options)\n\ncommands:\n");
  for (int k = 0; k < command_count; ++k) fprintf(out, "  %-10s %s\n", commands[k].name, commands[k].help);
}

int cli_fail(const char *command, fascia_ctx *ctx, fascia_status status) {
  const char *message = fascia_ctx_message(ctx);
  fprintf(stderr, "fascia %s: ", command);
  // one line, whatever a library put in the message
  for (const char *c = message && message[0] ? message : fascia_status_name(status); *c; ++c)
    fputc(*c == '\n' || *c == '\r' ? ' ' : *c, stderr);
  fputc('\n', stderr);
  if (cli_verbose) fprintf(stderr, "  (%s at %s)\n", fascia_status_name(status), fascia_ctx_where(ctx));
  return 1;
}

static void print_progress(void *user, const char *stage, double fraction, const char *detail) {
  (void)user;
  if (!strcmp(stage, "step")) return; // fascia run draws its own step line, with the time left
  if (fraction >= 0)
    fprintf(stderr, "\r%-24s %5.1f%%  %s\033[K", stage, 100 * fraction, detail ? detail : "");
  else
    fprintf(stderr, "\r%-24s %s\033[K", stage, detail ? detail : "");
  if (fraction >= 1) fputc('\n', stderr);
  fflush(stderr);
}

fascia_ctx *cli_ctx(int threads, int progress) {
  fascia_ctx_def def = fascia_ctx_def_default();
  def.threads = threads;
  const char *env = getenv("FASCIA_PROGRESS");
  int show = progress && (isatty(2) || (env && !strcmp(env, "1")));
  if (env && !strcmp(env, "0")) show = 0;
  if (show) def.progress = print_progress;
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&def, &ctx) != FASCIA_OK) {
    fprintf(stderr, "fascia: out of memory\n");
    exit(1);
  }
  return ctx;
}

// OpenMP threads that spin while they wait for a core they do not get make
// a run on a busy machine many times slower (docs/measured.md, "On a busy
// machine"); with the passive wait policy it degrades with the cores it
// gets. A short spin (FASCIA_OMP_SPIN rounds of libgomp's pause loop)
// before a thread sleeps is kept: CG passes follow each other within
// microseconds, and waking a sleeping thread for each would slow a step.
// OpenBLAS, the direct solver's BLAS, starts a worker per core as it loads,
// and each spins before it sleeps although the solver runs BLAS on one
// thread (sim/src/cpu/direct.c): OPENBLAS_NUM_THREADS=1 keeps them from being
// started. Both libraries read these as they load, so the program sets
// them and starts itself again, keeping each the user chose (a start is
// cheap: the prep stage's libraries are loaded by `fascia prep` only,
// prep_module.c). A function in the program's preinit array runs before
// the libraries' constructors, but glibc 2.36 sets up the environment after
// it, and its setenv is lost. If the new start fails the run goes on as it is.
#define FASCIA_OMP_SPIN "3000"

static void start_settings(char **argv) {
  int again = 0;
  if (!getenv("OMP_WAIT_POLICY") && !getenv("GOMP_SPINCOUNT")) {
    if (setenv("OMP_WAIT_POLICY", "PASSIVE", 1) != 0 || setenv("GOMP_SPINCOUNT", FASCIA_OMP_SPIN, 1) != 0) return;
    again = 1;
  }
  if (!getenv("OPENBLAS_NUM_THREADS")) {
    if (setenv("OPENBLAS_NUM_THREADS", "1", 1) != 0) return;
    again = 1;
  }
  if (again) execv("/proc/self/exe", argv);
}

// The solver's set-up allocates arrays of a few hundred kB to a few MB and
// frees them with the solver. glibc maps a block above a threshold of its
// own on fresh pages, moves that threshold with the sizes freed so far, and
// hands the heap's free top back to the system: a program that makes one
// solver after another (the bench's repeats, the trade study's sweeps)
// would meet fresh pages, a page fault each, again and again, more or fewer
// with the order its rows run in, so that a row's time would depend on the
// rows before it. With both thresholds fixed, freed memory is kept for the next
// allocation, not given back (blocks over 32 MB still are), and each row's
// time is the same in any order.
static void keep_freed_memory(void) {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
#endif
}

int main(int argc, char **argv) {
  start_settings(argv);
  keep_freed_memory();
  fascia_hdf5_quiet(); // every HDF5 failure reaches the user through fascia's own one-line message
  for (int k = 1; k < argc; ++k)
    if (!strcmp(argv[k], "--verbose")) cli_verbose = 1;
  if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
    usage(argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  if (!strcmp(argv[1], "--version")) {
    printf("fascia %s\n", fascia_version());
    return 0;
  }
  for (int k = 0; k < command_count; ++k)
    if (!strcmp(argv[1], commands[k].name)) {
      // before any parallel region: the OpenMP runtime crashes on a huge count
      cli_json_setup(commands[k].name, argc - 1, argv + 1);
      int rc = cli_check_repeats(commands[k].name, argc - 1, argv + 1);
      if (rc < 0) rc = cli_check_omp_threads(commands[k].name);
      return cli_json_finish(rc >= 0 ? rc : commands[k].run(argc - 1, argv + 1));
    }
  fprintf(stderr, "fascia: unknown command '%s'\n", argv[1]);
  usage(stderr);
  return 2;
}
