// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The subcommands of the fascia CLI. Each returns the process exit status:
// 0 success, 1 failure (one-line reason on stderr), 2 usage error.
#ifndef FASCIA_TOOLS_COMMANDS_H
#define FASCIA_TOOLS_COMMANDS_H

#include <stdio.h>

#include "fascia/base.h"

typedef struct cJSON cJSON;

typedef int (*fascia_command_fn)(int argc, char **argv);

typedef struct fascia_command {
  const char *name;
  fascia_command_fn run;
  const char *help; ///< one line
} fascia_command;

int cmd_info(int argc, char **argv);
int cmd_beam(int argc, char **argv);
int cmd_inspect(int argc, char **argv);
int cmd_prep(int argc, char **argv); ///< loads fascia-prep.so and runs fascia_prep_command (prep_module.c)
int cmd_run(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_tradeoff(int argc, char **argv);

/// `fascia prep` itself, in the module fascia-prep.so (cmd_prep.c); it
/// calls the program's cli_* helpers and its usage text below.
int fascia_prep_command(int argc, char **argv);
/// fascia prep's usage, printed by the program where the module is missing.
extern const char cli_prep_usage[];
/// One line on fascia prep for `fascia info`: "module PATH", "module ... missing: ..." or
/// "not built (why)"; the module is looked for, not loaded.
void cli_prep_status(char *out, size_t size);
/// The prep stage's module, loaded (dlopen) for a command other than prep
/// that calls the prep API through dlsym; NULL after one line on stderr.
void *cli_prep_module_open(const char *command);

/// Prints "fascia NAME: <ctx message>" on stderr (and where, with --verbose)
/// and returns 1.
int cli_fail(const char *command, fascia_ctx *ctx, fascia_status status);
/// A context with a progress printer on stderr when progress is nonzero
/// (and stderr is a terminal or FASCIA_PROGRESS=1), threads as given.
fascia_ctx *cli_ctx(int threads, int progress);
/// "fascia COMMAND: <format with what> (see fascia COMMAND --help)" on stderr; returns 2.
int cli_usage_error(const char *command, const char *format, const char *what);
/// Takes fascia run's own options out of argv, one at a time: from argv[*k]
/// (start at 1, *kept 1) the next that is one of names (NULL-ended) and its
/// value; the arguments before it stay, in order, from argv[*kept] on.
/// Returns 1 with *option and *value set; 0 when none is left (*argc is
/// then what stays); 2 after a usage line where a value is missing (hint
/// follows "needs a value" in it).
int cli_take_option(int *argc, char **argv, int *k, int *kept, const char *const *names, const char *hint,
                    const char **option, const char **value);
/// option is --help or -h: prints usage and more (NULL: none) on stdout
/// and returns 1; else 0.
int cli_help(const char *option, const char *usage, const char *more);
/// argv[*k] is an option that takes a value: one of valued (NULL-ended),
/// with a value after it. Returns -1 with *value set and *k on the value,
/// else 2 after the usage error (unknown option, or no value).
int cli_option_value(const char *command, int argc, char **argv, int *k, const char *const *valued,
                     const char **value);
/// Before parsing, for every command: an option given twice (except --drive,
/// --drive-template, --verbose), or two options that say the same or the
/// opposite thing (-o and --output, --single and --double, --assembled and
/// --matrix-free, ...), is refused. A value that looks like an option
/// ("--...") counts as one. Returns -1 to go on, else 2 after one line on
/// stderr.
int cli_check_repeats(const char *command, int argc, char **argv);
/// A finite number, the whole text: 1, else 0 (out untouched).
int cli_parse_real(const char *text, fascia_real *out);
/// A whole number >= minimum that fits an int: 1, else 0.
int cli_parse_count(const char *text, int *out, long minimum);
/// "NXxNYxNZ", each >= minimum: 1, else 0.
int cli_parse_grid(const char *text, int32_t grid[3], int minimum);
/// A --backend value: "cpu", "cuda", "auto" or "emulated" (fascia_solver_def
/// backend): 1 with *out the name, else 0 (out untouched).
int cli_parse_backend(const char *text, const char **out);
/// Reports a solver that could not be made or run: FASCIA_ERR_ARGUMENT (the
/// settings, e.g. --assembled on the GPU) as a usage error (returns 2); no
/// such device for a backend other than cpu naming the backend (1); else as
/// cli_fail (1).
int cli_solver_fail(const char *command, const char *backend, fascia_ctx *ctx, fascia_status status);
/// Writes text as one quoted CSV field (device names hold commas).
void cli_csv_text(FILE *f, const char *text);
/// Wall clock, ms.
double cli_now_ms(void);
/// Resident memory of the process now, and its peak so far, MiB.
double cli_resident_mb(void);
double cli_peak_mb(void);

/// One file argument of a command, for cli_check_paths.
typedef enum cli_path_kind { CLI_INPUT, CLI_OUTPUT_FILE, CLI_OUTPUT_DIR } cli_path_kind;
typedef struct cli_path {
  const char *option; ///< how messages name it: "-o", "--checkpoint", "the model"
  const char *path;   ///< NULL: not given (skipped); "" is refused
  cli_path_kind kind;
  const char *const *names; ///< CLI_OUTPUT_DIR: files it will hold (NULL-terminated; may be NULL)
  const char *may_be;       ///< option of an input this output may be (--checkpoint may be --resume); NULL
} cli_path;

/// Before any work: every input that exists is a regular file; every output
/// can be written (its folder exists and is writable; it is not a link,
/// FIFO, device or folder that the rename of the finished file would
/// replace), none is one of the inputs or another output (same device and
/// inode, or the same name in the same folder, or in an output folder a name
/// matching one of its patterns, fnmatch), and the temporary files
/// `NAME.tmp-PID-K` that a killed fascia left next to the outputs are
/// removed (fascia_file_remove_stale). Returns -1 to go on, else the exit
/// status after one line on stderr: 2 for a path given wrongly (empty, an
/// input, a link), 1 for an input that is not a regular file or a folder
/// that is missing or read-only.
int cli_check_paths(const char *command, const cli_path *paths, int count);

/// Largest --threads (and OMP_NUM_THREADS) accepted: more threads than this
/// exhaust the OpenMP runtime (it crashes at about 100000) long before they
/// help.
#define CLI_MAX_THREADS 1024
#define CLI_MAX_THREADS_TEXT "1024"
/// A --threads value, 1 to CLI_MAX_THREADS: 1, else 0.
int cli_parse_threads(const char *text, int *out);
/// OMP_NUM_THREADS, when set, must be a whole number 1 to CLI_MAX_THREADS
/// (the first of a list). Returns -1 to go on, else 2 after one line on stderr.
int cli_check_omp_threads(const char *command);

/// --json (cli_json.c): when argv holds --json, stderr is teed so that the
/// last "fascia ..." error line is known, and the command's JSON says it.
void cli_json_setup(const char *command, int argc, char **argv);
/// 1 when --json was given.
int cli_json_on(void);
/// Prints root on stdout as one line of valid UTF-8 (bytes that are not UTF-8
/// replaced by U+FFFD), an object given "exit_status" and "error" (the last
/// error line, null when exit_status is 0). Returns exit_status (1 when out
/// of memory). root stays the caller's.
int cli_json_emit(cJSON *root, int exit_status);
/// After the command: where --json was given and nothing was emitted (a
/// usage error, a file refused), prints {"command", "exit_status", "error"}.
/// Returns exit_status.
int cli_json_finish(int exit_status);
/// A copy of text with each byte that is not UTF-8 replaced by U+FFFD
/// (cJSON_malloc'd; NULL when out of memory).
char *cli_utf8_copy(const char *text);

/// 1 when --verbose was given anywhere on the command line.
extern int cli_verbose;

#endif
