// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia run -o R.h5 --organs DIR` opened in ParaView with both R.xdmf and
// DIR/organs.pvd loaded holds exactly one time per saved step, every organ at
// each: dynamic (dt = 0.1 s, whose sums drift from k dt), with an organ
// driven by --drive, and static (rest and equilibrium as two steps, 0 and 1).
// Before, the PVD wrote %.9g of the solver's summed clock and the XDMF %.17g
// (19 times for 11 steps on the demo), a driven organ vanished after t = 0,
// and a static run wrote two PVD entries at time 0 and one results step.
// Usage: t930_cli_paraview_times PATH/TO/fascia WORK_DIR PATH/TO/check_times.py
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "cli_exec.h"
#include "organ_fixture.h"

static cli_result result;

static int paraview_agrees(const char *script, const char *dir, const char *name, int organs) {
  char command[8192];
  snprintf(command, sizeof command, "pvbatch '%s' '%s/%s.xdmf' '%s/%s.h5' '%s/%s/organs.pvd' %d 2>&1", script, dir,
           name, dir, name, dir, name, organs);
  fflush(stdout);
  const int status = system(command);
  return status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

int main(int argc, char **argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: t930_cli_paraview_times PATH/TO/fascia WORK_DIR PATH/TO/check_times.py\n");
    return 1;
  }
  if (system("command -v pvbatch >/dev/null 2>&1") != 0) {
    printf("t930: skipped: pvbatch (Debian's python3-paraview, tools/setup/debian-packages.sh) is not installed\n");
    return TEST_SKIP;
  }
  const char *fascia = argv[1];
  char dir[1024], model[1200], err[1200], args[8192], csv[1200];
  snprintf(dir, sizeof dir, "%s/t930", argv[2]);
  snprintf(model, sizeof model, "%s/organs.h5", dir);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  snprintf(csv, sizeof csv, "%s/drive.csv", dir);
  snprintf(args, sizeof args, "rm -rf '%s' && mkdir -p '%s/dyn' '%s/stat' '%s/drv'", dir, dir, dir, dir);
  CHECK(system(args) == 0);
  fascia_ctx_def cd = fascia_ctx_def_default();
  cd.threads = 1;
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cd, &ctx) != FASCIA_OK) return 1;
  organ_fixture_def fd = organ_fixture_def_default();
  fd.kind_b = FASCIA_ORGAN_PRESCRIBED;
  fd.pull_b[0] = 0.01;
  fascia_model *m = NULL;
  CHECK_OK(organ_fixture_build(ctx, &fd, &m), ctx);
  CHECK_OK(fascia_model_save(ctx, m, model), ctx);
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);

  snprintf(args, sizeof args, "run '%s' --steps 10 --dt 0.1 --threads 1 --samples -o '%s/dyn.h5' --organs '%s/dyn'",
           model, dir, dir);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  CHECK(paraview_agrees(argv[3], dir, "dyn", 2));

  snprintf(args, sizeof args, "run '%s' --static --threads 1 --samples -o '%s/stat.h5' --organs '%s/stat'", model,
           dir, dir);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  CHECK(paraview_agrees(argv[3], dir, "stat", 2));

  // b driven from a file: its template at rest, then held there
  snprintf(args, sizeof args, "run '%s' --steps 4 --dt 0.1 --drive-template 'b=%s'", model, csv);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  snprintf(args, sizeof args, "run '%s' --steps 4 --dt 0.1 --threads 1 --drive 'b=%s' -o '%s/drv.h5' --organs '%s/drv'",
           model, csv, dir, dir);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  if (result.status) fprintf(stderr, "%s", result.err);
  CHECK(paraview_agrees(argv[3], dir, "drv", 2));
  return CHECK_RESULT();
}
