// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia run --paraview DIR` gives one file that opens everything:
// DIR/run.pvd, opened in ParaView (pvbatch, tests/paraview/check_run_pvd.py),
// holds one time per saved step and at each the blocks tissue (the model's
// tissue surface), tetrahedra, samples, frames and both organs by name, with the arrays docs/results-format.md lists and no
// other, displacement = position - rest, and the frames shared with an
// organ on its surface as drawn; meshio reads every per-step samples and
// frames file with the same arrays (tests/paraview/check_meshio.py). A
// dynamic run (organ b prescribed), a static one (b rigid, rest and
// equilibrium) and one with b driven from a file. The dynamic run's
// results.h5 holds exactly the datasets and attributes its docs list
// (h5py, tests/paraview/check_results_docs.py). Without pvbatch and
// without meshio the test is skipped, saying which is missing.
// A prepared scene with a deformable organ (the shipped uterus) is drawn
// with its surface within 0.5 mm of the frames it shares (skinned).
// Usage: t931_cli_paraview_folder PATH/TO/fascia WORK_DIR TESTS/paraview DOCS/results-format.md
//        data/scenes/pelvis-female-deformable.json
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "cli_exec.h"
#include "organ_fixture.h"

static cli_result result;

static int run_script(const char *command) {
  fflush(stdout);
  const int status = system(command);
  return status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

typedef struct paths {
  const char *fascia, *scripts, *doc, *python;
  int pvbatch;
  int32_t samples, frames;
} paths;

static void check_folder(const paths *p, const char *folder, int steps, const char *organs, double tolerance) {
  char command[8192];
  if (p->pvbatch) {
    snprintf(command, sizeof command, "pvbatch '%s/check_run_pvd.py' '%s' '%s' %d %s %g 2>&1 | grep -v -i openpmd",
             p->scripts, folder, p->doc, steps, organs, tolerance);
    // the pipe keeps grep's status: the script prints its failures, the count decides
    snprintf(command + strlen(command), sizeof command - strlen(command), " | tee /dev/stderr | grep -q ', 0 failures'");
    CHECK(run_script(command));
  }
  if (p->python) {
    snprintf(command, sizeof command, "%s '%s/check_meshio.py' '%s' '%s' %d %d", p->python, p->scripts, folder, p->doc,
             (int)p->samples, (int)p->frames);
    CHECK(run_script(command));
  }
}

static int build(const char *path, int kind_b, int32_t *samples, int32_t *frames) {
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1;
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 0;
  organ_fixture_def fd = organ_fixture_def_default();
  fd.kind_b = kind_b;
  fd.pull_b[0] = 0.01;
  fascia_model *m = NULL;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  if (m) CHECK_OK(organ_fixture_add_surface(ctx, m), ctx);
  if (m) { // two tetrahedra to draw, as a tet tissue has
    CHECK_OK(fascia_model_tetrahedra_alloc(ctx, m, 2), ctx);
    const int32_t N = m->frame_count, corners[8] = {0, 1, 2, N - 1, 3, 4, 5, N - 2};
    memcpy(m->tetrahedra, corners, sizeof corners);
  }
  if (m) *samples = m->sample_count, *frames = m->frame_count;
  CHECK_OK(fascia_model_save(ctx, m, path), ctx);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return 1;
}

int main(int argc, char **argv) {
  if (argc < 6) {
    fprintf(stderr, "usage: t931_cli_paraview_folder PATH/TO/fascia WORK_DIR TESTS/paraview RESULTS-FORMAT.md "
                    "DEFORMABLE-SCENE.json\n");
    return 1;
  }
  paths p = {argv[1], argv[3], argv[4], cli_python_with("meshio"), system("command -v pvbatch >/dev/null 2>&1") == 0, 0, 0};
  if (!p.pvbatch) printf("t931: ParaView part skipped: pvbatch (Debian's python3-paraview) is not installed\n");
  if (!p.python) printf("t931: meshio part skipped: meshio (Debian's python3-meshio) is not installed\n");
  if (!p.pvbatch && !p.python) return TEST_SKIP;
  char dir[1024], moving[1200], rigid[1200], err[1200], csv[1200], args[8192], folder[1300];
  snprintf(dir, sizeof dir, "%s/t931", argv[2]);
  snprintf(moving, sizeof moving, "%s/moving.h5", dir);
  snprintf(rigid, sizeof rigid, "%s/rigid.h5", dir);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  snprintf(csv, sizeof csv, "%s/drive.csv", dir);
  snprintf(args, sizeof args, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
  CHECK(system(args) == 0);
  CHECK(build(moving, FASCIA_ORGAN_PRESCRIBED, &p.samples, &p.frames));

  // dynamic: 6 steps, every 3rd saved, with the rest: 3 steps; the results file against its docs too
  snprintf(folder, sizeof folder, "%s/dyn", dir);
  snprintf(args, sizeof args,
           "run '%s' --steps 6 --dt 0.1 --save-every 3 --threads 1 --paraview '%s' --samples -o '%s/dyn.h5'", moving,
           folder, dir);
  CHECK(cli_exec(p.fascia, args, err, &result) && result.status == 0);
  check_folder(&p, folder, 3, "a,b", 1e-6);
  char command[4096];
  snprintf(command, sizeof command, "%s -c 'import h5py' 2>/dev/null", p.python ? p.python : "false");
  if (system(command) == 0) {
    snprintf(command, sizeof command, "%s '%s/check_results_docs.py' '%s/dyn.h5' '%s'", p.python, p.scripts, dir,
             p.doc);
    CHECK(run_script(command));
  } else {
    printf("t931: results-docs part skipped: h5py (Debian's python3-h5py) is not installed\n");
  }

  // b driven from a file (its template: held at rest)
  snprintf(args, sizeof args, "run '%s' --steps 2 --dt 0.1 --drive-template 'b=%s'", moving, csv);
  CHECK(cli_exec(p.fascia, args, err, &result) && result.status == 0);
  snprintf(folder, sizeof folder, "%s/drv", dir);
  snprintf(args, sizeof args, "run '%s' --steps 2 --dt 0.1 --threads 1 --drive 'b=%s' --paraview '%s'", moving, csv,
           folder);
  CHECK(cli_exec(p.fascia, args, err, &result) && result.status == 0);
  check_folder(&p, folder, 3, "a,b", 1e-6);

  // static, b rigid: rest and equilibrium
  CHECK(build(rigid, FASCIA_ORGAN_RIGID, &p.samples, &p.frames));
  snprintf(folder, sizeof folder, "%s/stat", dir);
  snprintf(args, sizeof args, "run '%s' --static --threads 1 --organs '%s'", rigid, folder);
  CHECK(cli_exec(p.fascia, args, err, &result) && result.status == 0);
  check_folder(&p, folder, 2, "a,b", 1e-6);

  // a deformable organ: the shipped uterus sags about 3 mm in a static solve; its skinned surface stays
  // within 0.5 mm of the frames it shares with the tissue (t584: 0.3 mm)
  snprintf(args, sizeof args, "prep '%s' -o '%s/deformable.h5'", argv[5], dir);
  if (cli_exec(p.fascia, args, err, &result) && result.status == 0) {
    snprintf(folder, sizeof folder, "%s/def", dir);
    snprintf(args, sizeof args, "run '%s/deformable.h5' --static --threads 1 --paraview '%s'", dir, folder);
    CHECK(cli_exec(p.fascia, args, err, &result) && result.status == 0);
    const paths pv = {p.fascia, p.scripts, p.doc, NULL, p.pvbatch, 0, 0}; // ParaView only: meshio was read above
    check_folder(&pv, folder, 2, "uterus,bladder", 5e-4);
  } else {
    printf("t931: deformable part skipped: fascia prep did not run (%.200s)\n", result.err);
  }
  return CHECK_RESULT();
}
