// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The shipped demo's outputs open in every reader a user may pick when an
// organ's name holds XML's special characters, quotes and non-ASCII (the
// uterus renamed `uterus & <adnexa> "ü" 'x'`): run.pvd, organs.pvd and the
// XDMF sidecar are well-formed XML naming the organ as given, meshio reads
// every file run.pvd lists with its units and time, h5py finds every dataset
// the sidecar names, and ParaView opens the blocks by name and the tissue
// coloured by strain (tests/paraview/check_outputs.py). The demo's pictures
// are drawn from them (tools/plots/: gnuplot without a warning, ParaView
// under xvfb-run) with the colour bar's top the run's largest strain, to
// its printed digits. Skipped without Python 3 and its xml module; the
// pictures without gnuplot, pvbatch or xvfb-run.
// Usage: t933_cli_outputs_any_reader PATH/TO/fascia WORK_DIR TESTS/paraview data/scenes/pelvis-female-demo.json
//        TOOLS/plots
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "scene_copy.h"

#include <unistd.h>

static const char organ_name[] = "uterus & <adnexa> \"\xC3\xBC\" 'x'";

static cli_result result;

// Every string in `item` that names the uterus names it organ_name instead
// (the organ, the tissue's `connects`).
static void rename_uterus(cJSON *item, void *arg) {
  (void)arg;
  for (; item; item = item->next) {
    if (cJSON_IsString(item) && strcmp(item->valuestring, "uterus") == 0) cJSON_SetValuestring(item, organ_name);
    rename_uterus(item->child, NULL);
  }
}

// The demo's pictures from the run's outputs: gnuplot's without a warning;
// ParaView's with the colour bar's top the largest strain the run printed.
static void check_pictures(const char *plots, const char *dir, int pvbatch) {
  char command[8192], text[256] = "", *largest = strstr(result.out, "strain      largest ");
  if (largest) sscanf(largest, "strain      largest %63s", text);
  CHECK(text[0]);
  if (system("command -v gnuplot >/dev/null 2>&1") == 0) {
    snprintf(command, sizeof command,
             "gnuplot -e \"dir='%s'; title='t933'; organs='a b'\" '%s/demo.gp' 2>&1 | tee /dev/stderr | grep -q .", dir,
             plots);
    CHECK(system(command) != 0); // nothing printed
  } else {
    printf("t933: gnuplot pictures skipped: gnuplot is not installed\n");
  }
  if (!pvbatch || system("command -v xvfb-run >/dev/null 2>&1") != 0) {
    printf("t933: ParaView pictures skipped: pvbatch or xvfb-run is not installed\n");
    return;
  }
  // the X server's number searched from one of this process's own (two
  // xvfb-run -a started together both take the first free number), and up
  // to three tries: on a loaded machine pvbatch sometimes meets an X server
  // not yet accepting ("bad X server connection"); a wrong colour bar fails
  // every try
  int rendered = 0;
  for (int attempt = 0; attempt < 3 && !rendered; ++attempt) {
    snprintf(command, sizeof command,
             "xvfb-run -a -n %d -s '-screen 0 1280x1024x24' pvbatch '%s/demo_paraview.py' '%s/pv/run.pvd' '%s' t933 "
             "sagittal 2>/dev/null | grep -q '^strain colour bar: 0 to %s$'",
             100 + (int)((getpid() + 97 * attempt) % 800), plots, dir, dir, text);
    rendered = system(command) == 0;
  }
  CHECK(rendered);
}

int main(int argc, char **argv) {
  if (argc < 6) {
    fprintf(stderr, "usage: t933_cli_outputs_any_reader PATH/TO/fascia WORK_DIR TESTS/paraview DEMO-SCENE.json "
                    "TOOLS/plots\n");
    return 1;
  }
  const int pvbatch = system("command -v pvbatch >/dev/null 2>&1") == 0;
  const char *python = pvbatch ? "pvbatch" : cli_python_with("xml");
  if (!python) {
    printf("t933: skipped: neither pvbatch nor python3 is installed\n");
    return TEST_SKIP;
  }
  if (!pvbatch) printf("t933: ParaView part skipped: pvbatch (Debian's python3-paraview) is not installed\n");
  char dir[1024], path[1200], args[8192];
  snprintf(dir, sizeof dir, "%s/t933", argv[2]);
  snprintf(args, sizeof args, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
  CHECK(system(args) == 0);
  snprintf(path, sizeof path, "%s/scene.json", dir);
  CHECK(scene_copy(argv[4], path, rename_uterus, NULL));
  snprintf(path, sizeof path, "%s/name.txt", dir);
  FILE *f = fopen(path, "wb");
  CHECK(f && fputs(organ_name, f) >= 0);
  if (f) fclose(f);

  snprintf(args, sizeof args, "prep '%s/scene.json' -o '%s/model.h5'", dir, dir);
  snprintf(path, sizeof path, "%s/stderr.txt", dir);
  CHECK(cli_exec(argv[1], args, path, &result) && result.status == 0);
  // 4 steps of the demo's traction, every other saved: rest and 2 more
  snprintf(args, sizeof args,
           "run '%s/model.h5' --steps 4 --dt 0.05 --save-every 2 --threads 1 --samples -o '%s/results.h5' "
           "--paraview '%s/pv' --history '%s/history.csv' --snapshots '%s/data'",
           dir, dir, dir, dir, dir);
  CHECK(cli_exec(argv[1], args, path, &result) && result.status == 0);
  snprintf(args, sizeof args,
           "%s '%s/check_outputs.py' '%s/pv' '%s/results.h5' '%s/name.txt' 2>&1 | grep -v -i openpmd"
           " | tee /dev/stderr | grep -q ', 0 failures'",
           python, argv[3], dir, dir, dir);
  fflush(stdout);
  CHECK(system(args) == 0);
  check_pictures(argv[5], dir, pvbatch);
  return CHECK_RESULT();
}
