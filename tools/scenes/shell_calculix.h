// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Shell organs against CalculiX (docs/measured.md, "Shell organs against
// CalculiX"): one definition gives fascia's scene (a "shell" organ, held by
// its `hold` box, under its own weight) and a CalculiX deck of S8R shells
// (NLGEOM, *ELASTIC: fascia's "stvk" law) of the same geometry.
//  - plate: the paper's cantilever as a thin shell, a plate length x width
//    (x in [0, length], y in [-width/2, width/2], z = 0), its edge x = 0
//    clamped; probe: the free end's centre (length, 0, 0).
//  - bowl: a hemisphere of radius R hanging from its rim (centre at the
//    origin, the rim the circle of radius R in z = 0, the bowl below it),
//    the rim clamped; probe: the bottom (0, 0, -R).
// fascia's scene is the case scaled by `scale` (lengths x scale, E x scale:
// the same strains under the same weight per volume, displacements x scale),
// since prep refuses organs larger than a body; results are scaled back.
// A scene needs a tissue: two fixed boxes joined by a short strand, beside
// the shell and not touching it, carry none of its load.
#ifndef FASCIA_TOOLS_SHELL_CALCULIX_H
#define FASCIA_TOOLS_SHELL_CALCULIX_H
#include <stdio.h>

#include "fascia/fascia.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum fascia_shell_case {
  FASCIA_SHELL_PLATE = 0, ///< the cantilever plate
  FASCIA_SHELL_BOWL = 1,  ///< the hemisphere hanging from its rim
} fascia_shell_case;

/// A shell case. Start from fascia_shell_def_default(kind).
typedef struct fascia_shell_def {
  int32_t kind;          ///< fascia_shell_case
  double length, width;  ///< plate: m; bowl: length is the radius, width unused
  double thickness;      ///< m
  double youngs_modulus; ///< Pa
  double poisson_ratio;
  double density;        ///< kg/m^3
  double gravity;        ///< m/s^2 along -z
  double frame_spacing;  ///< fascia: the shell organ's frame_spacing, m (of the case, before scaling)
  double scale;          ///< fascia's scene: lengths and E times this (<= 1)
  int32_t elements[2];   ///< CalculiX S8R: plate along x, y (y even); bowl around, along the meridian
  int32_t seed;          ///< fascia's scene seed (the draw of the shell's frames), default 1
  int32_t split;         ///< fascia: sample_spacing = frame_spacing / split; 1 (default): none given
} fascia_shell_def;

/// plate: 16 x 1 m, 0.1 m thick, E 4 MPa, nu 0.3, 0.3125 kg/m^3 (the
/// paper's beam's density), gravity 9.81, frames 0.25 m apart, scale 0.1,
/// 64 x 4 S8R. bowl: radius 0.05 m, 1 mm thick, E 100 kPa, nu 0.3,
/// 1000 kg/m^3, frames 6 mm apart, scale 1, 32 x 8 S8R.
fascia_shell_def fascia_shell_def_default(int32_t kind);

/// What a solve gave (either code).
typedef struct fascia_shell_result {
  double probe[3]; ///< displacement of the probe point, m (of the case, scaled back)
  int32_t nodes;   ///< fascia: frames of the shell; CalculiX: shell nodes
  int32_t newton;  ///< fascia: Newton iterations of the static solve; CalculiX: 0
  double ms;       ///< wall time of the solve (fascia: prep excluded; CalculiX: deck, ccx, output)
} fascia_shell_result;

/// The organ's surface mesh, the boxes and scene.json (the "stvk" law) into
/// the existing folder `dir` (the names of tissue_calculix.h). Errors:
/// FASCIA_ERR_ARGUMENT (a bad def, naming the field), FASCIA_ERR_IO.
fascia_status fascia_shell_write_scene(fascia_ctx *ctx, const void *shell_def, const char *dir);
/// The CalculiX deck (def passed as void * for fascia_ccx_run_deck).
fascia_status fascia_shell_write_deck(fascia_ctx *ctx, const void *def, FILE *out);
/// Solves the case with CalculiX (`program`: fascia_ccx_program; one thread).
fascia_status fascia_shell_calculix(fascia_ctx *ctx, const fascia_shell_def *def, const char *program,
                                    fascia_shell_result *out);
/// Solves the case with fascia: scene in a temporary folder, prep's stages,
/// a static solve (CPU, one thread, Newton tolerance 1e-10); the probe's
/// displacement is the shell's own interpolation there (the frames of the
/// wall's triangle under it, their positions and rotations weighted
/// linearly). Only in builds with prep (fascia_tissue_reference).
fascia_status fascia_shell_fascia(fascia_ctx *ctx, const fascia_shell_def *def, fascia_shell_result *out);

#ifdef __cplusplus
}
#endif
#endif
