// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia prep` runs from a module, fascia-prep.so (cmd_prep.c and the prep
// stage), that the program loads only when the command is asked for. The
// prep stage's libraries (OpenVDB, TBB, CGAL's GMP, assimp, teem, NIfTI)
// take most of a start to load and bind, and the program starts twice
// (main.c): every other command starts without them.
// The module is looked for next to the program (the build folder), then in
// FASCIA_PREP_MODULE_DIR relative to it (the install: ../lib/fascia).
#define _DEFAULT_SOURCE // readlink
#include <dlfcn.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "commands.h"

const char cli_prep_usage[] =
    "usage: fascia prep SCENE.json [-o MODEL.h5] [--json] [--preview DIR] [--labelmap MAP.nii.gz] [--threads N]\n"
    "  builds the connective-tissue model of a scene file (data/scenes/README.md)\n"
    "  -o MODEL.h5     output model file (default: the scene's \"output\" key)\n"
    "  --preview DIR   also write ParaView files into DIR: open DIR/preview.pvd (organs by name,\n"
    "                  region, frames with what holds each, samples, coupling)\n"
    "  --labelmap MAP.nii.gz  also write the organs as a label map (organ k is label k + 1, at the scene's\n"
    "                  voxel size) and its label table MAP.tsv: a segmentation viewer shows them, and a\n"
    "                  scene can build the same organs from labels (docs/labelmaps.md)\n"
    "  --json          print one JSON summary object on stdout\n"
    "  --threads N     worker threads, 1 to 1024 (default: all)\n"
    "  --estimate      print the expected peak memory of preparing (from the label map or the meshes'\n"
    "                  bounds, docs/cohort.md) and stop; nothing is written\n"
    "  --verbose       on failure, also print where the error was found\n";

static int asks_for_help(int argc, char **argv) {
  for (int k = 1; k < argc; ++k)
    if (!strcmp(argv[k], "--help") || !strcmp(argv[k], "-h")) return 1;
  return 0;
}

#ifndef FASCIA_HAVE_PREP

#ifndef FASCIA_PREP_WHY
#define FASCIA_PREP_WHY "unknown reason"
#endif

void cli_prep_status(char *out, size_t size) { snprintf(out, size, "not built (%s)", FASCIA_PREP_WHY); }

void *cli_prep_module_open(const char *command) {
  fprintf(stderr, "fascia %s: the preprocessing stage was not built (%s); reconfigure with -DFASCIA_PREP=ON\n", command,
          FASCIA_PREP_WHY);
  return NULL;
}

int cmd_prep(int argc, char **argv) {
  if (asks_for_help(argc, argv)) printf("%s", cli_prep_usage);
  fprintf(stderr,
          "fascia prep: the preprocessing stage was not built (%s); install libassimp-dev, libcgal-dev, "
          "libopenvdb-dev and libcjson-dev, then reconfigure with -DFASCIA_PREP=ON\n",
          FASCIA_PREP_WHY);
  return 1;
}

#else

#define MODULE_NAME "fascia-prep.so"

// The program's folder into folder (PATH_MAX); 0 where /proc/self/exe does not say.
static int program_folder(char *folder) {
  const ssize_t n = readlink("/proc/self/exe", folder, PATH_MAX - 1);
  if (n > 0) folder[n] = 0;
  char *slash = n > 0 ? strrchr(folder, '/') : NULL;
  if (slash) *slash = 0;
  return slash != NULL;
}

// The module's path into path (PATH_MAX + 64), the first place that has it; 0 for none.
static int find_module(const char *folder, char *path) {
  const char *const places[] = {"", "/" FASCIA_PREP_MODULE_DIR};
  for (size_t k = 0; k < sizeof places / sizeof places[0]; ++k) {
    snprintf(path, PATH_MAX + 64, "%s%s/" MODULE_NAME, folder, places[k]);
    if (access(path, F_OK) == 0) return 1;
  }
  return 0;
}

void cli_prep_status(char *out, size_t size) {
  char folder[PATH_MAX], path[PATH_MAX + 64];
  if (!program_folder(folder))
    snprintf(out, size, "module " MODULE_NAME " not looked for: /proc/self/exe does not say where the program lies");
  else if (find_module(folder, path))
    snprintf(out, size, "module %s", path);
  else
    snprintf(out, size, "module " MODULE_NAME " missing: neither in %s nor in %s/" FASCIA_PREP_MODULE_DIR, folder,
             folder);
}

int cmd_prep(int argc, char **argv) {
  char folder[PATH_MAX];
  if (!program_folder(folder)) {
    fprintf(stderr, "fascia prep: cannot find where the fascia program lies (/proc/self/exe), so not its module "
                    MODULE_NAME "\n");
    return 1;
  }
  char path[PATH_MAX + 64];
  if (find_module(folder, path)) {
    void *module = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!module) { // there but not loadable, e.g. a library of the prep stage missing: dlerror names it
      const char *why = dlerror();
      fprintf(stderr, "fascia prep: cannot load the prep stage: %s\n", why ? why : path);
      return 1;
    }
    fascia_command_fn run;
    *(void **)&run = dlsym(module, "fascia_prep_command");
    if (!run) {
      fprintf(stderr, "fascia prep: %s has no fascia_prep_command: a module of another build\n", path);
      return 1;
    }
    return run(argc, argv); // the module stays loaded until the program ends
  }
  if (asks_for_help(argc, argv)) printf("%s", cli_prep_usage);
  fprintf(stderr,
          "fascia prep: the prep stage's module " MODULE_NAME " is neither in %s nor in %s/" FASCIA_PREP_MODULE_DIR
          ": install fascia again\n",
          folder, folder);
  return 1;
}


void *cli_prep_module_open(const char *command) {
  char folder[PATH_MAX], path[PATH_MAX + 64];
  if (!program_folder(folder) || !find_module(folder, path)) {
    fprintf(stderr, "fascia %s: the prep stage's module " MODULE_NAME " is missing: install fascia again\n", command);
    return NULL;
  }
  void *module = dlopen(path, RTLD_NOW | RTLD_LOCAL);
  if (!module) {
    const char *why = dlerror();
    fprintf(stderr, "fascia %s: cannot load the prep stage: %s\n", command, why ? why : path);
  }
  return module;
}

#endif
