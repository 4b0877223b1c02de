// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// `fascia beam`: writes the paper's cantilever (sec. 4.1) as a model file,
// built by tools/scenes/beam.c with the chosen frame grid, shape functions
// and material.
#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "fascia/fascia.h"
#include "scenes.h"

static const char beam_usage[] =
    "usage: fascia beam [--frames NXxNYxNZ] [--shape hex|tet|meshless|strand|sheet] [--samples-per-cell N]\n"
    "                   [--neighbours K] [--section-points Q]\n"
    "                   [--E PA --nu V | --lambda PA --mu PA] [--law stvk|neohookean]\n"
    "                   [--mass KG] [--density KG_M3] [--rotation-coupling R]\n"
    "                   [--rotation-smoothing R] [--volumetric auto|full|cell|frame|poisson|reduced]\n"
    "                   [--patch-radius M] [--modes auto|on|nine|normal|off] -o BEAM.h5 [--json]\n"
    "\n"
    "The cantilever of Bosman et al. 2013 sec. 4.1: 16 x 1 x 1 m along x, clamped at x = 0,\n"
    "loaded by gravity, probe 'tip' at (16, 0, 0).\n"
    "  --frames NXxNYxNZ       frame grid, faces included (default 20x3x3); strand: NX frames on\n"
    "                          the axis (default 20); sheet: NXxNY in the mid-plane (default 20x3)\n"
    "  --shape KIND            hex: trilinear, 8 neighbours; tet: barycentric on the 6-tet split\n"
    "                          of each cell, 4 neighbours; meshless: MLS over K nearest (default hex);\n"
    "                          strand: a 1-D model, frames on the axis, MLS along it, the 1 x 1 m\n"
    "                          section carried by the frames' rotations; sheet: a 2-D model, frames\n"
    "                          in the mid-plane, MLS in it, the 1 m thickness carried by the\n"
    "                          rotations (docs/mechanics.md, \"Strands and sheets\")\n"
    "  --samples-per-cell N    hex, meshless: N^3 Gauss points per cell, N = 1..4 (default 2;\n"
    "                          1 leaves hex hourglass modes that cost no energy: no static solve);\n"
    "                          tet: samples per tetrahedron, 1 or 4 (default 4); strand: stations\n"
    "                          per interval, sheet: N along x and max(N, 2) across per cell\n"
    "                          (default 1: more stiffen them, shear locking)\n"
    "  --neighbours K          meshless: frames per sample (default 8); strand, sheet: 0, the\n"
    "                          frames of the sample's interval or cell (default), or K nearest\n"
    "  --section-points Q      strand: Q x Q Gauss points over the section; sheet: Q through the\n"
    "                          thickness (1 .. 4, default 2)\n"
    ;
// (a second string: ISO C bounds a string literal's length)
static const char beam_usage_more[] =
    "  --E PA, --nu V          Young's modulus (default 40000) and Poisson ratio (default 0.3)\n"
    "  --lambda PA, --mu PA    or the Lame parameters instead (both, and neither --E nor --nu)\n"
    "  --law NAME              stvk (default) or neohookean\n"
    "  --mass KG               total mass (default 5); --density KG_M3 overrides it\n"
    "  --rotation-coupling R   Cosserat coupling as a fraction of mu (default 0)\n"
    "  --volumetric KIND       how the volumetric energy is integrated (docs/mechanics.md):\n"
    "                          auto (default): cell for nu >= 0.3, else full; full: at every sample;\n"
    "                          cell: mean dilatation over each cell's samples (cures locking as\n"
    "                          nu -> 0.5); frame: over the samples nearest each frame; poisson:\n"
    "                          over Poisson-disk patches of --patch-radius (as fascia prep makes\n"
    "                          them); reduced: one extra sample per cell (per tetrahedron)\n"
    "  --patch-radius M        radius of the poisson patches, m (default 0.5)\n"
    "  --modes SET             enhanced strain modes per volumetric patch, the cure of the shape\n"
    "                          functions' stiffness in bending (docs/mechanics.md): nine\n"
    "                          (Wilson's: entry (r, c) of F varies along X_c), normal (the three\n"
    "                          entries (c, c) only), on (the shape's set: nine for tet, normal\n"
    "                          for hex and meshless) or off; auto (default): on for hex and for\n"
    "                          tet with 4 samples per tetrahedron, where there are patches\n"
    "                          (meshless and the centroid rule are soft enough already)\n"
    "  --rotation-smoothing R  rotation smoothing, relative to the frame spacing (default 0.1, and\n"
    "                          0.05 for tet, whose frames carry twice the rotation; 0 is the\n"
    "                          paper's scheme, which has zero-energy twist modes)\n"
    "  -o PATH                 model file to write (required)\n"
    "  --json                  print a JSON summary on stdout\n";

static int print_json(const fascia_model *m, const char *path) {
  int32_t neighbours = 0;
  for (int32_t s = 0; s < m->sample_count; ++s) {
    const int32_t n = m->sample_offsets[s + 1] - m->sample_offsets[s];
    neighbours = n > neighbours ? n : neighbours;
  }
  cJSON *root = cJSON_CreateObject();
  cJSON_AddNumberToObject(root, "frames", m->frame_count);
  cJSON_AddNumberToObject(root, "samples", m->sample_count);
  cJSON_AddNumberToObject(root, "pairs", m->pair_count);
  cJSON_AddNumberToObject(root, "neighbours", neighbours);
  cJSON_AddNumberToObject(root, "volume", fascia_model_volume(m));
  cJSON_AddNumberToObject(root, "mass", fascia_model_mass(m));
  cJSON_AddStringToObject(root, "path", path);
  const int rc = cli_json_emit(root, 0);
  cJSON_Delete(root);
  return rc;
}

int cmd_beam(int argc, char **argv) {
  // the shape decides the defaults of the frame grid, neighbours and samples
  int shape = FASCIA_SCENE_HEX;
  for (int k = 1; k + 1 < argc; ++k)
    if (!strcmp(argv[k], "--shape")) shape = fascia_scene_shape_from_name(argv[k + 1]);
  fascia_scene_beam_def def = fascia_scene_beam_def_of_shape(shape < 0 ? FASCIA_SCENE_HEX : shape);
  const char *path = NULL, *frames_text = NULL;
  int json = 0, samples_given = 0, young_given = 0;
  double lambda = -1, mu = -1;
  int32_t samples_per_cell = 0;
  def.volumetric_patch = FASCIA_SCENE_PATCH_AUTO; // cell patches from FASCIA_PATCH_MIN_POISSON on
  def.enhanced_modes = -1;                        // fascia beam's rule: hex and tet patches
  int modes_on = 0;                               // --modes on: the shape's set, known after parsing
  for (int k = 1; k < argc; ++k) {
    const char *opt = argv[k];
    if (cli_help(opt, beam_usage, beam_usage_more)) return 0;
    if (!strcmp(opt, "--json")) {
      json = 1;
      continue;
    }
    if (!strcmp(opt, "--verbose")) continue;
    static const char *const valued[] = {"--frames", "--shape", "--samples-per-cell", "--neighbours", "--E", "--nu", "--lambda", "--mu",
                                         "--law", "--mass", "--density", "--rotation-coupling", "--rotation-smoothing", "--volumetric", "--patch-radius", "--modes", "--section-points", "-o", "--output", NULL};
    const char *value = NULL;
    const int bad = cli_option_value("beam", argc, argv, &k, valued, &value);
    if (bad >= 0) return bad;
    int ok = 1;
    if (!strcmp(opt, "--frames"))
      ok = (frames_text = value) != NULL; // read once the shape is known
    else if (!strcmp(opt, "--section-points"))
      ok = cli_parse_count(value, &def.section_points, -2147483647L);
    else if (!strcmp(opt, "--shape"))
      ok = (def.shape = fascia_scene_shape_from_name(value)) >= 0;
    else if (!strcmp(opt, "--samples-per-cell"))
      ok = samples_given = cli_parse_count(value, &samples_per_cell, -2147483647L);
    else if (!strcmp(opt, "--neighbours"))
      ok = cli_parse_count(value, &def.neighbours, -2147483647L);
    else if (!strcmp(opt, "--E"))
      ok = young_given = cli_parse_real(value, &def.youngs_modulus);
    else if (!strcmp(opt, "--nu"))
      ok = young_given = cli_parse_real(value, &def.poisson_ratio);
    else if (!strcmp(opt, "--lambda"))
      ok = cli_parse_real(value, &lambda);
    else if (!strcmp(opt, "--mu"))
      ok = cli_parse_real(value, &mu);
    else if (!strcmp(opt, "--law"))
      ok = (def.law = fascia_law_from_name(value)) >= 0;
    else if (!strcmp(opt, "--mass"))
      ok = cli_parse_real(value, &def.mass);
    else if (!strcmp(opt, "--density"))
      ok = cli_parse_real(value, &def.density);
    else if (!strcmp(opt, "--rotation-coupling"))
      ok = cli_parse_real(value, &def.rotation_coupling);
    else if (!strcmp(opt, "--rotation-smoothing"))
      ok = cli_parse_real(value, &def.rotation_smoothing);
    else if (!strcmp(opt, "--patch-radius"))
      ok = cli_parse_real(value, &def.patch_radius);
    else if (!strcmp(opt, "--modes")) {
      modes_on = !strcmp(value, "on");
      def.enhanced_modes = !strcmp(value, "auto")     ? -1
                           : !strcmp(value, "nine")   ? FASCIA_MODES_NINE
                           : !strcmp(value, "normal") ? FASCIA_MODES_NORMAL
                           : !strcmp(value, "off")    ? FASCIA_MODES_NONE
                                                      : -2;
      ok = modes_on || def.enhanced_modes != -2;
    } else if (!strcmp(opt, "--volumetric")) {
      def.reduced_volumetric = !strcmp(value, "reduced");
      def.volumetric_patch = def.reduced_volumetric ? FASCIA_SCENE_PATCH_NONE : fascia_scene_patch_from_name(value);
      ok = def.volumetric_patch != -2;
    }
    else
      path = value;
    if (!ok) {
      fprintf(stderr, "fascia beam: bad value '%s' for %s (see fascia beam --help)\n", value, opt);
      return 2;
    }
  }
  if (!path) return cli_usage_error("beam", "%s", "missing -o PATH, the model file to write");
  if (frames_text) {
    const int dim = fascia_scene_shape_dimension(def.shape);
    int32_t grid[3];
    const int counts = fascia_scene_frames_parse(frames_text, grid);
    if (counts != dim && !(dim == 3 && cli_parse_grid(frames_text, grid, -2147483647))) {
      char what[256];
      snprintf(what, sizeof what, "--frames '%.60s': a %s takes %s", frames_text, fascia_scene_shape_name(def.shape),
               dim == 1   ? "one count >= 2, the frames on the axis (e.g. 20)"
               : dim == 2 ? "NXxNY, counts >= 2, the frames in the mid-plane (e.g. 20x3)"
                          : "NXxNYxNZ frames (e.g. 20x3x3)");
      return cli_usage_error("beam", "%s", what);
    }
    memcpy(def.frames, grid, sizeof grid);
  }
  if (lambda >= 0 || mu >= 0) { // Lame parameters: both, instead of E and nu
    if (young_given) return cli_usage_error("beam", "%s", "give either --E/--nu or --lambda/--mu, not both");
    if (!(lambda >= 0 && mu > 0)) return cli_usage_error("beam", "%s", "--lambda needs a value >= 0 and --mu one > 0, both given");
    fascia_lame_to_young(lambda, mu, &def.youngs_modulus, &def.poisson_ratio);
  }
  if (samples_given) {
    if (def.shape == FASCIA_SCENE_TET)
      def.samples_per_tet = samples_per_cell;
    else
      def.samples_per_cell_dir = samples_per_cell;
  }
  if (modes_on) def.enhanced_modes = fascia_scene_beam_modes_of_shape(def.shape);
  const cli_path output = {"-o", path, CLI_OUTPUT_FILE, NULL, NULL};
  const int paths_rc = cli_check_paths("beam", &output, 1);
  if (paths_rc >= 0) return paths_rc;
  fascia_ctx *ctx = cli_ctx(0, 1);
  fascia_model *model = NULL;
  fascia_status st = fascia_scene_beam_build(ctx, &def, &model);
  // a bad def is the user's option: a usage error naming it
  if (st == FASCIA_ERR_ARGUMENT) {
    fprintf(stderr, "fascia beam: %s (see fascia beam --help)\n", fascia_ctx_message(ctx));
    fascia_ctx_destroy(&ctx);
    return 2;
  }
  if (st == FASCIA_OK) st = fascia_model_save(ctx, model, path);
  int rc = st == FASCIA_OK ? 0 : cli_fail("beam", ctx, st);
  if (rc == 0 && json) rc = print_json(model, path);
  fascia_model_destroy(&model);
  fascia_ctx_destroy(&ctx);
  return rc;
}
