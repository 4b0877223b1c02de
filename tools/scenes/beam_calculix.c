// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The cantilever as a CalculiX deck, and one ccx run on it
// (beam_calculix.h; data/reference/README.md says how the reference was
// refined). Nodes sit on a structured grid of L nx + 1 by L ny + 1 by
// L nz + 1 points (L = 2 for the 20-node brick, whose mid-edge nodes use
// odd indices, 1 for the 8-node one); a grid point is a node when at most
// one of its indices is odd (L = 2), every point (L = 1).
#define _GNU_SOURCE // wait4 (BSD), posix_spawn_file_actions_addchdir_np (glibc 2.29)
#include "beam_calculix.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "scene_util.h"

#define WHO "CalculiX deck"
// Numbers are written with 13 digits: ccx reads each field as at most 20 characters.
#define JOB "beam" // ccx -i beam: beam.inp in, beam.dat, beam.sta out
#define DIR_SIZE 1024                 // the run folder's path, at most
#define PATH_SIZE (DIR_SIZE + 320) // a file in it

static const char *const element_names[FASCIA_CCX_ELEMENT_COUNT_] = {"C3D20R", "C3D8I"};

const char *fascia_ccx_element_name(int element) {
  return element >= 0 && element < FASCIA_CCX_ELEMENT_COUNT_ ? element_names[element] : "unknown";
}

int fascia_ccx_element_from_name(const char *name) {
  for (int k = 0; name && k < FASCIA_CCX_ELEMENT_COUNT_; ++k)
    if (!strcmp(name, element_names[k])) return k;
  return -1;
}

fascia_ccx_beam_def fascia_ccx_beam_def_default(void) {
  fascia_ccx_beam_def def;
  memset(&def, 0, sizeof def);
  def.beam = fascia_scene_beam_def_default();
  def.element = FASCIA_CCX_C3D20R;
  def.cells[0] = 32;
  def.cells[1] = 2;
  def.cells[2] = 2;
  def.grading[0] = def.grading[1] = def.grading[2] = 1;
  def.tight = 1;
  return def;
}

/// The node grid of a deck: L points per element edge, n[d] points along d.
typedef struct node_grid {
  int level;
  int64_t n[3];
} node_grid;

static node_grid grid_of(const fascia_ccx_beam_def *def) {
  node_grid g;
  g.level = def->element == FASCIA_CCX_C3D20R ? 2 : 1;
  for (int d = 0; d < 3; ++d) g.n[d] = g.level * (int64_t)def->cells[d] + 1;
  return g;
}

static int is_node(const node_grid *g, int64_t i, int64_t j, int64_t k) {
  return g->level == 1 || (i % 2) + (j % 2) + (k % 2) <= 1;
}

static long long node_id(const node_grid *g, int64_t i, int64_t j, int64_t k) {
  return (long long)(1 + i + g->n[0] * (j + g->n[1] * k));
}

static fascia_status check_def(fascia_ctx *ctx, const fascia_ccx_beam_def *def) {
  SCENE_CHECK(def, ctx, FASCIA_ERR_ARGUMENT, WHO ": NULL def");
  SCENE_TRY(scene_check_body(ctx, &def->beam, WHO));
  SCENE_CHECK(def->element >= 0 && def->element < FASCIA_CCX_ELEMENT_COUNT_, ctx, FASCIA_ERR_ARGUMENT,
              WHO ": element %d, expected 0 (C3D20R) or 1 (C3D8I)", (int)def->element);
  SCENE_CHECK(def->cells[0] >= 1 && def->cells[0] <= 4096, ctx, FASCIA_ERR_ARGUMENT,
              WHO ": %d elements along x, expected 1 .. 4096", (int)def->cells[0]);
  SCENE_CHECK(def->half == 0 || def->half == 1, ctx, FASCIA_ERR_ARGUMENT, WHO ": half %d, expected 0 or 1",
              (int)def->half);
  for (int d = 1; d < 3; ++d)
    if (d == 1 && def->half)
      SCENE_CHECK(def->cells[1] >= 1 && def->cells[1] <= 256, ctx, FASCIA_ERR_ARGUMENT,
                  WHO ": %d elements across the half width, expected 1 .. 256", (int)def->cells[1]);
    else
      SCENE_CHECK(def->cells[d] >= 2 && def->cells[d] <= 256 && def->cells[d] % 2 == 0, ctx, FASCIA_ERR_ARGUMENT,
                  WHO ": %d elements along %c, expected an even count 2 .. 256 (a node at the end's centre)",
                  (int)def->cells[d], "xyz"[d]);
  for (int d = 0; d < 3; ++d)
    SCENE_CHECK(isfinite(def->grading[d]) && def->grading[d] >= 1 && def->grading[d] <= 1e3, ctx,
                FASCIA_ERR_ARGUMENT, WHO ": grading %g along %c, expected 1 .. 1000", def->grading[d], "xyz"[d]);
  SCENE_CHECK(def->tight == 0 || def->tight == 1, ctx, FASCIA_ERR_ARGUMENT, WHO ": tight %d, expected 0 or 1",
              (int)def->tight);
  const double g = sqrt(def->beam.gravity[0] * def->beam.gravity[0] + def->beam.gravity[1] * def->beam.gravity[1] +
                        def->beam.gravity[2] * def->beam.gravity[2]);
  SCENE_CHECK(g > 0, ctx, FASCIA_ERR_ARGUMENT, WHO ": no gravity, the only load of the deck");
  return FASCIA_OK;
}

// Position in [0, 1] of element boundary e of n with geometric sizes of
// ratio `grading` from first to last.
static double graded(int64_t e, int64_t n, double grading) {
  if (grading == 1 || n < 2) return (double)e / (double)n;
  const double q = pow(grading, 1.0 / (double)(n - 1));
  return (pow(q, (double)e) - 1) / (pow(q, (double)n) - 1);
}

// Coordinate along axis d of grid index idx: element boundaries graded, a
// mid-edge node (odd index on the quadratic grid) halfway between them.
static double coordinate(const fascia_ccx_beam_def *def, const node_grid *g, int d, int64_t idx) {
  const fascia_scene_beam_def *b = &def->beam;
  if (g->level == 2 && idx % 2)
    return (coordinate(def, g, d, idx - 1) + coordinate(def, g, d, idx + 1)) / 2;
  const int64_t e = idx / g->level, n = def->cells[d];
  if (d == 0) return b->length * graded(e, n, def->grading[0]);
  if (d == 1 && def->half) return b->width / 2 * (1 - graded(n - e, n, def->grading[1])); // 0 .. width / 2
  // across: smallest at both surfaces, n / 2 elements on each side of the axis
  const double half = (d == 1 ? b->width : b->height) / 2;
  return e <= n / 2 ? -half + half * graded(e, n / 2, def->grading[d]) : half - half * graded(n - e, n / 2, def->grading[d]);
}

// Node lists: every id with its coordinates, then the clamped face as a set.
static void write_nodes(const fascia_ccx_beam_def *def, const node_grid *g, FILE *out) {
  fprintf(out, "*NODE, NSET=NALL\n");
  for (int64_t k = 0; k < g->n[2]; ++k)
    for (int64_t j = 0; j < g->n[1]; ++j)
      for (int64_t i = 0; i < g->n[0]; ++i)
        if (is_node(g, i, j, k))
          fprintf(out, "%lld, %.13g, %.13g, %.13g\n", node_id(g, i, j, k), coordinate(def, g, 0, i),
                  coordinate(def, g, 1, j), coordinate(def, g, 2, k));
  fprintf(out, "*NSET, NSET=NFIX\n");
  for (int64_t k = 0; k < g->n[2]; ++k)
    for (int64_t j = 0; j < g->n[1]; ++j)
      if (is_node(g, 0, j, k)) fprintf(out, "%lld,\n", node_id(g, 0, j, k));
  const int64_t centre = def->half ? 0 : (g->n[1] - 1) / 2;
  if (def->half) {
    fprintf(out, "*NSET, NSET=NSYM\n");
    for (int64_t k = 0; k < g->n[2]; ++k)
      for (int64_t i = 0; i < g->n[0]; ++i)
        if (is_node(g, i, 0, k)) fprintf(out, "%lld,\n", node_id(g, i, 0, k));
  }
  fprintf(out, "*NSET, NSET=NTIP\n%lld,\n", node_id(g, g->n[0] - 1, centre, (g->n[2] - 1) / 2));
}

// Elements in ccx's (Abaqus') node order: corners counter-clockwise at
// zeta = -1 then +1, for C3D20R the mid-edge nodes of those two faces, then
// of the edges between them; 16 entries at most per line.
static void write_elements(const fascia_ccx_beam_def *def, const node_grid *g, FILE *out) {
  static const int corner[8][3] = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}, {0, 0, 2}, {2, 0, 2}, {2, 2, 2}, {0, 2, 2}};
  static const int mid[12][3] = {{1, 0, 0}, {2, 1, 0}, {1, 2, 0}, {0, 1, 0}, {1, 0, 2}, {2, 1, 2},
                                 {1, 2, 2}, {0, 1, 2}, {0, 0, 1}, {2, 0, 1}, {2, 2, 1}, {0, 2, 1}};
  const int L = g->level, count = L == 2 ? 20 : 8;
  fprintf(out, "*ELEMENT, TYPE=%s, ELSET=EALL\n", fascia_ccx_element_name(def->element));
  long long id = 1;
  for (int64_t ez = 0; ez < def->cells[2]; ++ez)
    for (int64_t ey = 0; ey < def->cells[1]; ++ey)
      for (int64_t ex = 0; ex < def->cells[0]; ++ex, ++id) {
        fprintf(out, "%lld", id);
        for (int a = 0; a < count; ++a) {
          const int *o = a < 8 ? corner[a] : mid[a - 8];
          const int64_t i = L * ex + o[0] * L / 2, j = L * ey + o[1] * L / 2, k = L * ez + o[2] * L / 2;
          fprintf(out, ",%s%lld", a == 15 ? "\n" : " ", node_id(g, i, j, k));
        }
        fputc('\n', out);
      }
}

static void write_material(const fascia_scene_beam_def *b, FILE *out) {
  const double E = b->youngs_modulus, nu = b->poisson_ratio;
  fprintf(out, "*MATERIAL, NAME=BEAM\n");
  if (b->law == FASCIA_LAW_STVK) {
    fprintf(out, "** under NLGEOM: S = lambda tr(E) I + 2 mu E (St. Venant-Kirchhoff)\n*ELASTIC\n%.13g, %.13g\n", E,
            nu);
  } else {
    const double mu = E / (2 * (1 + nu)), bulk = E / (3 * (1 - 2 * nu));
    fprintf(out,
            "** psi = C10 (I1bar - 3) + (J - 1)^2 / D1, C10 = mu / 2, D1 = 2 / K: E = %.13g Pa, nu = %.13g\n"
            "*HYPERELASTIC, NEO HOOKE\n%.13g, %.13g\n",
            E, nu, mu / 2, 2 / bulk);
  }
  fprintf(out, "*DENSITY\n%.13g\n", (double)scene_density(b));
}

fascia_status fascia_ccx_beam_write(fascia_ctx *ctx, const fascia_ccx_beam_def *def, FILE *out) {
  SCENE_TRY(check_def(ctx, def));
  const fascia_scene_beam_def *b = &def->beam;
  const node_grid g = grid_of(def);
  const double *gv = b->gravity, gn = sqrt(gv[0] * gv[0] + gv[1] * gv[1] + gv[2] * gv[2]);
  fprintf(out,
          "** fascia's cantilever (tools/scenes/beam_calculix.c): %g x %g x %g m along x, clamped at x = 0,\n"
          "** its own weight; %s, %d x %d x %d elements graded %g, %g, %g%s; tip = the node at (%g, 0, 0)\n"
          "*HEADING\nfascia cantilever\n",
          b->length, b->width, b->height, fascia_ccx_element_name(def->element), (int)def->cells[0],
          (int)def->cells[1], (int)def->cells[2], def->grading[0], def->grading[1], def->grading[2],
          def->half ? " on the half y >= 0" : "", b->length);
  write_nodes(def, &g, out);
  write_elements(def, &g, out);
  write_material(b, out);
  fprintf(out, "*SOLID SECTION, ELSET=EALL, MATERIAL=BEAM\n*BOUNDARY\nNFIX, 1, 3\n%s",
          def->half ? "NSYM, 2, 2\n" : "");
  // the whole load in one increment (7 Newton iterations on the default beam), ccx cutting it when Newton fails
  fprintf(out, "*STEP, NLGEOM, INC=1000\n*STATIC\n1.0, 1.0, 1e-6, 1.0\n");
  if (def->tight) fprintf(out, "*CONTROLS, PARAMETERS=FIELD\n1e-7, 1e-7, 0., -1., 0.02, 1e-5, 1e-3, 1e-8\n");
  fprintf(out, "*DLOAD\nEALL, GRAV, %.13g, %.13g, %.13g, %.13g\n*NODE PRINT, NSET=NTIP\nU\n*END STEP\n", gn,
          gv[0] / gn, gv[1] / gn, gv[2] / gn);
  return fascia_ccx_deck_written(ctx, out);
}

fascia_status fascia_ccx_deck_written(fascia_ctx *ctx, FILE *out) {
  if (fflush(out) != 0 || ferror(out))
    return SCENE_FAIL(ctx, FASCIA_ERR_IO, WHO ": writing failed (%s)", strerror(errno));
  return FASCIA_OK;
}

const char *fascia_ccx_program(void) {
  const char *chosen = getenv("FASCIA_CCX");
  if (chosen && chosen[0]) return chosen;
  const char *path = getenv("PATH");
  if (!path) return NULL;
  for (const char *p = path; *p;) {
    const char *end = strchr(p, ':');
    const size_t n = end ? (size_t)(end - p) : strlen(p);
    char candidate[4096];
    if (n > 0 && n + 5 < sizeof candidate) {
      memcpy(candidate, p, n);
      strcpy(candidate + n, "/ccx");
      if (access(candidate, X_OK) == 0) return "ccx";
    }
    p += n + (end ? 1 : 0);
  }
  return NULL;
}

// Removes the run folder and everything ccx left in it.
static void remove_folder(const char *dir) {
  DIR *d = opendir(dir);
  if (d) {
    for (struct dirent *e; (e = readdir(d));) {
      if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
      char path[PATH_SIZE];
      snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
      unlink(path);
    }
    closedir(d);
  }
  rmdir(dir);
}

extern char **environ;

// The threads settings ccx reads from its environment
static const char *const ccx_thread_names[] = {"OMP_NUM_THREADS", "CCX_NPROC_EQUATION_SOLVER", "CCX_NPROC_STIFFNESS",
                                               "CCX_NPROC_RESULTS"};
enum { CCX_THREAD_NAMES = sizeof ccx_thread_names / sizeof ccx_thread_names[0] };

// This process's environment with each of ccx_thread_names set to
// `threads` (in `settings`); NULL when out of memory. Free the array only.
static char **ccx_environment(int threads, char settings[CCX_THREAD_NAMES][64]) {
  size_t count = 0;
  while (environ && environ[count]) ++count;
  char **env = malloc((count + CCX_THREAD_NAMES + 1) * sizeof *env);
  if (!env) return NULL;
  size_t used = 0;
  for (size_t k = 0; k < count; ++k) { // getenv takes the first of a name: leave ours out
    int ours = 0;
    for (int j = 0; j < CCX_THREAD_NAMES; ++j) {
      const size_t length = strlen(ccx_thread_names[j]);
      ours |= !strncmp(environ[k], ccx_thread_names[j], length) && environ[k][length] == '=';
    }
    if (!ours) env[used++] = environ[k];
  }
  for (int j = 0; j < CCX_THREAD_NAMES; ++j) {
    snprintf(settings[j], sizeof settings[j], "%s=%d", ccx_thread_names[j], threads);
    env[used++] = settings[j];
  }
  env[used] = NULL;
  return env;
}

int fascia_ccx_deck_fits(const char *path, char *why, size_t size) {
  FILE *f = fopen(path, "r");
  if (!f) {
    snprintf(why, size, "cannot read it (%s)", strerror(errno));
    return 0;
  }
  char line[4096];
  int ok = 1, heading = 0;
  for (long number = 1; ok && fgets(line, sizeof line, f); ++number) {
    if (line[0] == '*') { // keyword and comment lines: no fields; a heading's lines are text
      if (line[1] != '*') heading = !strncasecmp(line, "*HEADING", 8);
      continue;
    }
    if (heading) continue;
    for (const char *field = line;; ++field) {
      const size_t length = strcspn(field, ",\r\n");
      const char *a = field, *b = field + length; // the field without its blanks
      while (a < b && (*a == ' ' || *a == '\t')) ++a;
      while (b > a && (b[-1] == ' ' || b[-1] == '\t')) --b;
      if (b - a > FASCIA_CCX_FIELD) {
        snprintf(why, size, "line %ld has a field of %d characters, '%.*s' (ccx reads %d)", number, (int)(b - a),
                 (int)(b - a), a, FASCIA_CCX_FIELD);
        ok = 0;
        break;
      }
      field += length;
      if (*field != ',') break;
    }
  }
  fclose(f);
  return ok;
}

// The deck of the run in dir, checked before ccx reads it.
static fascia_status deck_check(fascia_ctx *ctx, const char *what, const char *dir) {
  char path[PATH_SIZE], why[256];
  snprintf(path, sizeof path, "%s/" JOB ".inp", dir);
  return fascia_ccx_deck_fits(path, why, sizeof why)
             ? FASCIA_OK
             : SCENE_FAIL(ctx, FASCIA_ERR_FORMAT, "CalculiX %s: the deck %s: %s", what, path, why);
}

// Runs `program -i beam` in dir, output to ccx.log; its exit status (128 +
// the signal that ended it), or -1 with why in *why when it could not be
// started; its processor time (user + system) in *cpu_ms. Spawned (glibc: a
// vfork), not forked: a fork write-protects every page of this process, and
// the bench's next fascia row would pay a page fault for each page it writes
// again, timing the faults instead of the solver.
static int run_ccx(const char *dir, const char *program, int threads, double *cpu_ms, const char **why) {
  char settings[CCX_THREAD_NAMES][64];
  char **env = ccx_environment(threads, settings);
  if (!env) {
    *why = "out of memory";
    return -1;
  }
  posix_spawn_file_actions_t actions;
  pid_t pid = -1;
  // each call returns 0 or an error number
  int failed = posix_spawn_file_actions_init(&actions);
  if (!failed) {
    failed = posix_spawn_file_actions_addchdir_np(&actions, dir);
    if (!failed)
      failed = posix_spawn_file_actions_addopen(&actions, 1, "ccx.log", O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (!failed) failed = posix_spawn_file_actions_adddup2(&actions, 1, 2);
    // a relative path (FASCIA_CCX=./ccx) names a file from here, not from the run folder
    char absolute[PATH_MAX];
    const char *file = strchr(program, '/') && program[0] != '/' && realpath(program, absolute) ? absolute : program;
    char *const argv[] = {(char *)file, "-i", JOB, NULL};
    if (!failed) failed = posix_spawnp(&pid, file, &actions, NULL, argv, env);
    posix_spawn_file_actions_destroy(&actions);
  }
  free(env);
  if (failed) {
    *why = strerror(failed);
    return -1;
  }
  int status = 0;
  struct rusage usage;
  memset(&usage, 0, sizeof usage);
  while (wait4(pid, &status, 0, &usage) < 0)
    if (errno != EINTR) {
      *why = strerror(errno);
      return -1;
    }
  *cpu_ms = 1e3 * (double)(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
            1e-3 * (double)(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// The last non-empty line of the log, for the message of a failed run.
static void last_log_line(const char *dir, char *line, size_t size) {
  char path[PATH_SIZE], buf[512];
  snprintf(path, sizeof path, "%s/ccx.log", dir);
  line[0] = '\0';
  FILE *f = fopen(path, "r");
  if (!f) return;
  while (fgets(buf, sizeof buf, f)) {
    buf[strcspn(buf, "\r\n")] = '\0';
    const char *p = buf + strspn(buf, " ");
    if (*p) snprintf(line, size, "%s", p);
  }
  fclose(f);
}

// The tip displacement of the last increment in beam.dat; its load time in *time.
static int read_dat(const char *dir, double tip[3], double *time) {
  char path[PATH_SIZE], line[512];
  snprintf(path, sizeof path, "%s/" JOB ".dat", dir);
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  int found = 0, pending = 0;
  double t = 0;
  while (fgets(line, sizeof line, f)) {
    const char *at = strstr(line, "displacements");
    const char *tt = at ? strstr(line, "time") : NULL;
    if (tt && sscanf(tt + 4, "%lf", &t) == 1) {
      pending = 1;
      continue;
    }
    char *end;
    double u[3];
    strtoll(line, &end, 10);
    if (pending && end != line && fascia_ccx_dat_numbers(end, u, 3)) {
      memcpy(tip, u, sizeof u);
      *time = t;
      found = 1;
      pending = 0;
    }
  }
  fclose(f);
  return found;
}

// Increments and Newton iterations from beam.sta (one line per increment:
// step, increment, attempt, iterations, total time, step time, increment).
static void read_sta(const char *dir, int32_t *increments, int32_t *iterations) {
  char path[PATH_SIZE], line[512];
  snprintf(path, sizeof path, "%s/" JOB ".sta", dir);
  *increments = *iterations = 0;
  FILE *f = fopen(path, "r");
  if (!f) return;
  while (fgets(line, sizeof line, f)) {
    int step, inc, attempt, iters;
    double total, step_time, inc_time;
    if (sscanf(line, "%d %d %d %d %lf %lf %lf", &step, &inc, &attempt, &iters, &total, &step_time, &inc_time) == 7) {
      *increments += 1;
      *iterations += iters;
    }
  }
  fclose(f);
}

fascia_status fascia_ccx_beam_solve(fascia_ctx *ctx, const fascia_ccx_beam_def *def, const char *program,
                                    int threads, fascia_ccx_result *out) {
  SCENE_CHECK(out && program, ctx, FASCIA_ERR_ARGUMENT, WHO ": NULL program or result");
  SCENE_CHECK(threads >= 1, ctx, FASCIA_ERR_ARGUMENT, WHO ": %d threads, expected >= 1", threads);
  SCENE_TRY(check_def(ctx, def));
  memset(out, 0, sizeof *out);
  const node_grid g = grid_of(def);
  for (int64_t k = 0; k < g.n[2]; ++k)
    for (int64_t j = 0; j < g.n[1]; ++j)
      for (int64_t i = 0; i < g.n[0]; ++i)
        if (is_node(&g, i, j, k)) out->nodes += 1, out->dofs += i == 0 ? 0 : def->half && j == 0 ? 2 : 3;
  out->elements = def->cells[0] * def->cells[1] * def->cells[2];
  const char *tmp = getenv("TMPDIR");
  char dir[DIR_SIZE], deck[PATH_SIZE];
  const int n = snprintf(dir, sizeof dir, "%s/fascia-ccx-XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
  if (n < 0 || n >= (int)sizeof dir || !mkdtemp(dir)) return SCENE_FAIL(ctx, FASCIA_ERR_IO, WHO ": cannot make a folder %s (%s)", dir, strerror(errno));
  snprintf(deck, sizeof deck, "%s/" JOB ".inp", dir);
  fascia_status status = FASCIA_OK;
  const double t0 = scene_now_ms();
  FILE *f = fopen(deck, "w");
  if (!f) {
    status = SCENE_FAIL(ctx, FASCIA_ERR_IO, WHO ": cannot write %s (%s)", deck, strerror(errno));
    goto cleanup;
  }
  status = fascia_ccx_beam_write(ctx, def, f);
  if (fclose(f) != 0 && status == FASCIA_OK)
    status = SCENE_FAIL(ctx, FASCIA_ERR_IO, WHO ": cannot write %s (%s)", deck, strerror(errno));
  if (status == FASCIA_OK) status = deck_check(ctx, "cantilever", dir);
  if (status != FASCIA_OK) goto cleanup;
  const char *why = "";
  const int rc = run_ccx(dir, program, threads, &out->cpu_ms, &why);
  double time = 0;
  const int found = read_dat(dir, out->tip, &time);
  out->ms = scene_now_ms() - t0;
  read_sta(dir, &out->increments, &out->iterations);
  char last[256];
  last_log_line(dir, last, sizeof last);
  if (rc < 0)
    status = SCENE_FAIL(ctx, FASCIA_ERR_IO, "CalculiX: could not run '%s' (%s); install calculix-ccx", program, why);
  else if (rc == 126 || rc == 127) // a shell script that could not run its ccx
    status = SCENE_FAIL(ctx, FASCIA_ERR_IO, "CalculiX: could not run '%s' (exit %d); install calculix-ccx", program, rc);
  else if (rc != 0 || (found && fabs(time - 1) > 1e-9))
    status = SCENE_FAIL(ctx, FASCIA_ERR_NUMERIC, "CalculiX: %s %dx%dx%d stopped (exit %d) at load %g: %s",
                        fascia_ccx_element_name(def->element), (int)def->cells[0], (int)def->cells[1],
                        (int)def->cells[2], rc, time, last);
  else if (!found)
    status = SCENE_FAIL(ctx, FASCIA_ERR_FORMAT, "CalculiX: no tip displacement in %s/" JOB ".dat: %s", dir, last);
cleanup:
  remove_folder(dir);
  return status;
}

// The whole text of a file, NUL-terminated (malloc'd); NULL when unreadable.
static char *read_text(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  size_t size = 0, capacity = 1 << 16;
  char *text = malloc(capacity);
  for (size_t n; text && (n = fread(text + size, 1, capacity - size - 1, f)) > 0;) {
    size += n;
    if (capacity - size < 2) {
      char *bigger = realloc(text, 2 * capacity);
      if (!bigger) free(text);
      text = bigger, capacity *= 2;
    }
  }
  fclose(f);
  if (text) text[size] = '\0';
  return text;
}

// The load time of the last output block ("... for set X and time  T") in
// a .dat text; -1 when it has none.
static double last_output_time(const char *dat) {
  double t = -1;
  for (const char *p = strstr(dat, "and time"); p; p = strstr(p + 8, "and time")) sscanf(p + 8, "%lf", &t);
  return t;
}

fascia_status fascia_ccx_run_deck(fascia_ctx *ctx, const char *what, fascia_ccx_deck_writer write, const void *arg,
                                  const char *program, int threads, char **dat, double *cpu_ms) {
  SCENE_CHECK(dat && cpu_ms && write && what && program, ctx, FASCIA_ERR_ARGUMENT,
              "CalculiX: NULL program, writer or output");
  SCENE_CHECK(threads >= 1, ctx, FASCIA_ERR_ARGUMENT, "CalculiX: %d threads, expected >= 1", threads);
  *dat = NULL;
  *cpu_ms = 0;
  const char *tmp = getenv("TMPDIR");
  char dir[DIR_SIZE], path[PATH_SIZE];
  const int n = snprintf(dir, sizeof dir, "%s/fascia-ccx-XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
  if (n < 0 || n >= (int)sizeof dir || !mkdtemp(dir))
    return SCENE_FAIL(ctx, FASCIA_ERR_IO, "CalculiX %s: cannot make a folder %s (%s)", what, dir, strerror(errno));
  snprintf(path, sizeof path, "%s/" JOB ".inp", dir);
  fascia_status status = FASCIA_OK;
  FILE *f = fopen(path, "w");
  if (!f) {
    status = SCENE_FAIL(ctx, FASCIA_ERR_IO, "CalculiX %s: cannot write %s (%s)", what, path, strerror(errno));
    goto cleanup;
  }
  status = write(ctx, arg, f);
  if (fclose(f) != 0 && status == FASCIA_OK)
    status = SCENE_FAIL(ctx, FASCIA_ERR_IO, "CalculiX %s: cannot write %s (%s)", what, path, strerror(errno));
  if (status == FASCIA_OK) status = deck_check(ctx, what, dir);
  if (status != FASCIA_OK) goto cleanup;
  const char *why = "";
  const int rc = run_ccx(dir, program, threads, cpu_ms, &why);
  snprintf(path, sizeof path, "%s/" JOB ".dat", dir);
  char *text = read_text(path);
  const double time = text ? last_output_time(text) : -1;
  char last[256];
  last_log_line(dir, last, sizeof last);
  if (rc < 0)
    status = SCENE_FAIL(ctx, FASCIA_ERR_IO, "CalculiX %s: could not run '%s' (%s); install calculix-ccx", what,
                        program, why);
  else if (rc == 126 || rc == 127)
    status = SCENE_FAIL(ctx, FASCIA_ERR_IO, "CalculiX %s: could not run '%s' (exit %d); install calculix-ccx", what,
                        program, rc);
  else if (rc != 0 || (text && fabs(time - 1) > 1e-9))
    status = SCENE_FAIL(ctx, FASCIA_ERR_NUMERIC, "CalculiX %s: stopped (exit %d) at load %g: %s", what, rc, time,
                        last);
  else if (!text)
    status = SCENE_FAIL(ctx, FASCIA_ERR_FORMAT, "CalculiX %s: no output %s: %s", what, path, last);
  if (status == FASCIA_OK) *dat = text;
  else free(text);
cleanup:
  remove_folder(dir);
  return status;
}

fascia_status fascia_ccx_run_timed(fascia_ctx *ctx, const char *what, fascia_ccx_deck_writer write, const void *arg,
                                   const char *program, int threads, char **dat, double *ms) {
  const double t0 = scene_now_ms();
  double cpu_ms = 0;
  SCENE_TRY(fascia_ccx_run_deck(ctx, what, write, arg, program, threads, dat, &cpu_ms));
  *ms = scene_now_ms() - t0;
  return FASCIA_OK;
}

const char *fascia_ccx_dat_after(const char *dat, const char *header) {
  const char *found = NULL;
  for (const char *p = strstr(dat, header); p; p = strstr(p + 1, header)) found = p;
  if (!found) return NULL;
  const char *eol = strchr(found, '\n');
  return eol ? eol + 1 : NULL;
}

int fascia_ccx_dat_numbers(const char *line, double *v, int count) {
  const char *p = line;
  for (int k = 0; k < count; ++k) {
    char *end;
    v[k] = strtod(p, &end);
    if (end == p) return 0;
    if ((*end == '-' || *end == '+') && end[1] >= '0' && end[1] <= '9') { // "1.234567-100"
      const long exponent = strtol(end, &end, 10);
      v[k] *= pow(10.0, (double)exponent);
    }
    p = end;
  }
  return 1;
}

int fascia_ccx_dat_triple(const char *block, double v[3]) {
  for (const char *p = block; p && *p;) {
    if (fascia_ccx_dat_numbers(p, v, 3)) return 1;
    if (p[strspn(p, " \t\r")] != '\n') return 0;
    const char *eol = strchr(p, '\n');
    p = eol ? eol + 1 : NULL;
  }
  return 0;
}

int fascia_ccx_dat_node(const char *block, long long node, double v[3]) {
  for (const char *p = block; p && *p;) {
    char *end;
    const long long id = strtoll(p, &end, 10);
    if (end != p && fascia_ccx_dat_numbers(end, v, 3)) {
      if (id == node) return 1;
    } else if (p[strspn(p, " \t\r")] != '\n') {
      return 0; // the block ended
    }
    const char *eol = strchr(p, '\n');
    p = eol ? eol + 1 : NULL;
  }
  return 0;
}

// Copied from data/reference/cantilever-calculix.csv (tests/t361 checks the copy).
static const fascia_ccx_reference references[] = {
    {FASCIA_LAW_STVK, 40000, 0, -1.61135, -6.53479, 0.0002},
    {FASCIA_LAW_STVK, 40000, 0.2, -1.60608, -6.52526, 0.0002},
    {FASCIA_LAW_STVK, 40000, 0.3, -1.59904, -6.51045, 0.0002},
    {FASCIA_LAW_STVK, 40000, 0.45, -1.58157, -6.47227, 0.0007},
    {FASCIA_LAW_STVK, 40000, 0.49, -1.57499, -6.45761, 0.0006},
    {FASCIA_LAW_STVK, 4e+06, 0, -0.0002038, -0.0755744, 2e-06},
    {FASCIA_LAW_STVK, 4e+06, 0.2, -0.0002030, -0.0754387, 2e-06},
    {FASCIA_LAW_STVK, 4e+06, 0.3, -0.0002020, -0.0752261, 2e-06},
    {FASCIA_LAW_STVK, 4e+06, 0.49, -0.0001983, -0.0744742, 8e-06},
    {FASCIA_LAW_NEOHOOKEAN, 40000, 0.3, -1.59212, -6.51244, 0.0003},
    {FASCIA_LAW_NEOHOOKEAN, 40000, 0.49, -1.56830, -6.45978, 0.0008},
};

const fascia_ccx_reference *fascia_ccx_references(int *count) {
  *count = (int)(sizeof references / sizeof references[0]);
  return references;
}

const fascia_ccx_reference *fascia_ccx_reference_find(const fascia_scene_beam_def *def) {
  const fascia_scene_beam_def d = fascia_scene_beam_def_default();
  const double g = def->gravity[0] * def->gravity[0] + def->gravity[1] * def->gravity[1] +
                   (def->gravity[2] - d.gravity[2]) * (def->gravity[2] - d.gravity[2]);
  if (def->length != d.length || def->width != d.width || def->height != d.height || g != 0 ||
      scene_density(def) != scene_density(&d))
    return NULL;
  for (size_t k = 0; k < sizeof references / sizeof references[0]; ++k)
    if (references[k].law == def->law && references[k].youngs_modulus == def->youngs_modulus &&
        references[k].poisson_ratio == def->poisson_ratio)
      return references + k;
  return NULL;
}
