// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Helpers shared by the subcommands: numbers that must be whole and finite,
// NXxNYxNZ grids, backend names, the one-line usage error, the report of a
// solver that could not be made, CSV text fields, a wall clock, memory in use.
#define _POSIX_C_SOURCE 200809L // clock_gettime, sysconf
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "commands.h"
#include "fascia/solver.h"

int cli_usage_error(const char *command, const char *format, const char *what) {
  fprintf(stderr, "fascia %s: ", command);
  fprintf(stderr, format, what);
  fprintf(stderr, " (see fascia %s --help)\n", command);
  return 2;
}

int cli_option_value(const char *command, int argc, char **argv, int *k, const char *const *valued,
                     const char **value) {
  const char *o = argv[*k];
  int known = 0;
  for (const char *const *v = valued; *v; ++v) known |= !strcmp(o, *v);
  if (!known) return cli_usage_error(command, "unknown option '%s'", o);
  if (*k + 1 >= argc) return cli_usage_error(command, "option %s needs a value", o);
  *value = argv[++*k];
  return -1;
}

int cli_take_option(int *argc, char **argv, int *k, int *kept, const char *const *names, const char *hint,
                    const char **option, const char **value) {
  for (; *k < *argc; ++*k) {
    const char *o = argv[*k];
    int mine = 0;
    for (const char *const *n = names; *n; ++n) mine |= !strcmp(o, *n);
    if (!mine) {
      argv[(*kept)++] = argv[*k];
      continue;
    }
    if (*k + 1 >= *argc) {
      fprintf(stderr, "fascia run: option %s needs a value%s (see fascia run --help)\n", o, hint);
      return 2;
    }
    *option = o;
    *value = argv[++*k];
    ++*k;
    return 1;
  }
  *argc = *kept;
  return 0;
}

int cli_help(const char *option, const char *usage, const char *more) {
  if (strcmp(option, "--help") && strcmp(option, "-h")) return 0;
  fputs(usage, stdout);
  if (more) fputs(more, stdout);
  return 1;
}

// Options that say the same thing, or opposite things: at most one of each
// group on a command line. Every other option at most once, except these.
static const char *const option_groups[][3] = {
    {"-o", "--output", NULL},           {"--paraview", "--organs", NULL},
    {"--single", "--double", NULL},     {"--assembled", "--matrix-free", NULL},
    {"--static", "--steps", NULL},      {"--require-convergence", "--accept-unconverged", NULL},
    {"--static-time", "--steps", NULL},
};
static const char *const repeatable_options[] = {"--drive", "--drive-template", "--verbose"};

static int is_option(const char *a) { return (a[0] == '-' && a[1] == '-' && a[2]) || !strcmp(a, "-o") || !strcmp(a, "-h"); }

// The group of option a (its index), or -1.
static int group_of(const char *a, int after) {
  for (int g = after + 1; g < (int)(sizeof option_groups / sizeof option_groups[0]); ++g)
    for (int k = 0; k < 3 && option_groups[g][k]; ++k)
      if (!strcmp(a, option_groups[g][k])) return g;
  return -1;
}

int cli_check_repeats(const char *command, int argc, char **argv) {
  for (int k = 1; k < argc; ++k) {
    const char *a = argv[k];
    if (!is_option(a)) continue;
    int repeatable = 0;
    for (size_t r = 0; r < sizeof repeatable_options / sizeof repeatable_options[0]; ++r)
      repeatable |= !strcmp(a, repeatable_options[r]);
    for (int j = 1; j < k; ++j) {
      const char *b = argv[j];
      if (!is_option(b)) continue;
      if (!strcmp(a, b) && !repeatable) {
        fprintf(stderr, "fascia %s: option %s is given twice; give it once (see fascia %s --help)\n", command, a,
                command);
        return 2;
      }
      for (int g = group_of(a, -1); g >= 0; g = group_of(a, g))
        if (strcmp(a, b) && group_of(b, g - 1) == g) {
          fprintf(stderr, "fascia %s: options %s and %s exclude each other; give one (see fascia %s --help)\n",
                  command, b, a, command);
          return 2;
        }
    }
  }
  return -1;
}

int cli_parse_real(const char *text, fascia_real *out) {
  char *end = NULL;
  errno = 0;
  const double x = strtod(text, &end);
  if (!text[0] || *end || errno || !isfinite(x)) return 0;
  *out = x;
  return 1;
}

int cli_parse_count(const char *text, int *out, long minimum) {
  char *end = NULL;
  errno = 0;
  const long x = strtol(text, &end, 10);
  if (!text[0] || *end || errno || x < minimum || x > 2147483647L) return 0;
  *out = (int)x;
  return 1;
}

int cli_parse_grid(const char *text, int32_t grid[3], int minimum) {
  char extra;
  int a, b, c;
  if (sscanf(text, "%dx%dx%d%c", &a, &b, &c, &extra) != 3 || a < minimum || b < minimum || c < minimum) return 0;
  grid[0] = a, grid[1] = b, grid[2] = c;
  return 1;
}

int cli_parse_backend(const char *text, const char **out) {
  if (!strcmp(text, "auto")) {
    *out = "auto";
    return 1;
  }
  for (int k = 0; fascia_backend_name(k); ++k)
    if (!strcmp(text, fascia_backend_name(k))) {
      *out = fascia_backend_name(k); // static: outlives argv edits
      return 1;
    }
  return 0;
}

int cli_solver_fail(const char *command, const char *backend, fascia_ctx *ctx, fascia_status status) {
  if (status == FASCIA_ERR_ARGUMENT) { // an impossible setting, such as --assembled on the GPU: the user's option
    fprintf(stderr, "fascia %s: %s (see fascia %s --help)\n", command, fascia_ctx_message(ctx), command);
    return 2;
  }
  if (status == FASCIA_ERR_UNSUPPORTED && backend && strcmp(backend, "cpu")) { // no GPU here, or not built
    fprintf(stderr, "fascia %s: backend %s: %s; --backend auto falls back to the CPU\n", command, backend,
            fascia_ctx_message(ctx));
    if (cli_verbose) fprintf(stderr, "  (%s at %s)\n", fascia_status_name(status), fascia_ctx_where(ctx));
    return 1;
  }
  return cli_fail(command, ctx, status);
}

void cli_csv_text(FILE *f, const char *text) {
  fputc('"', f);
  for (const char *c = text ? text : ""; *c; ++c) {
    if (*c == '"') fputc('"', f); // RFC 4180: a quote inside is doubled
    fputc(*c, f);
  }
  fputc('"', f);
}

double cli_now_ms(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

double cli_resident_mb(void) {
  FILE *f = fopen("/proc/self/statm", "r"); // Linux; 0 where absent
  long pages = 0, resident = 0;
  if (!f) return 0;
  if (fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
  fclose(f);
  return (double)resident * (double)sysconf(_SC_PAGESIZE) / (1024.0 * 1024.0);
}

double cli_peak_mb(void) {
  struct rusage usage; // ru_maxrss is KiB on Linux
  return getrusage(RUSAGE_SELF, &usage) == 0 ? (double)usage.ru_maxrss / 1024.0 : 0;
}

int cli_parse_threads(const char *text, int *out) {
  int threads = 0;
  if (!cli_parse_count(text, &threads, 1) || threads > CLI_MAX_THREADS) return 0;
  *out = threads;
  return 1;
}

int cli_check_omp_threads(const char *command) {
  const char *env = getenv("OMP_NUM_THREADS");
  if (!env || !env[0]) return -1;
  char *end = NULL;
  errno = 0;
  const long threads = strtol(env, &end, 10);
  if (end == env) return -1; // not a number: the OpenMP runtime warns and ignores it
  if (errno || threads < 1 || threads > CLI_MAX_THREADS) {
    fprintf(stderr,
            "fascia %s: OMP_NUM_THREADS=%s is out of range: fascia runs 1 to %d threads; set a smaller value or "
            "unset it (--threads T overrides it per command)\n",
            command, env, CLI_MAX_THREADS);
    return 2;
  }
  return -1;
}
