// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The peer figure of `fascia bench cantilever`: CalculiX (ccx) on the same
// cantilever, timed in the same run, at the same tip error as each of
// fascia's rows (tools/scenes/beam_calculix.h).
#ifndef FASCIA_TOOLS_BENCH_CALCULIX_H
#define FASCIA_TOOLS_BENCH_CALCULIX_H
#include "beam_calculix.h"

#define BENCH_PEER_MAX 16

/// One mesh of CalculiX's ladder and what it gave.
typedef struct bench_peer {
  int element;     ///< fascia_ccx_element
  int32_t cells[3];
  double grading;  ///< along x, from the clamp
  fascia_ccx_result result;
  double error_uz_percent; ///< against the reference; > 0: too stiff
} bench_peer;

/// Solves the ladder of `element` (coarsest first, each mesh once, with
/// ccx's default controls and `threads` threads) on the beam of `beam`'s
/// law, E and nu until a mesh is within
/// `target_percent` of `reference_uz` or the ladder ends. *count gets the
/// meshes solved. Errors: those of fascia_ccx_beam_solve (message on ctx).
fascia_status bench_calculix_ladder(fascia_ctx *ctx, const char *program, int element,
                                    const fascia_scene_beam_def *beam, double reference_uz, double target_percent,
                                    int threads, bench_peer *peers, int *count);

/// Solves the `count` meshes of a ladder once more, each keeping the least
/// of its wall times (the bench's repeats).
fascia_status bench_calculix_retime(fascia_ctx *ctx, const char *program, const fascia_scene_beam_def *beam,
                                    int threads, bench_peer *peers, int count);

/// The fastest mesh of the ladder whose |error| is at most |error_percent|,
/// NULL when none reached it.
const bench_peer *bench_calculix_match(const bench_peer *peers, int count, double error_percent);

/// "64x2x2 g16" into out.
void bench_calculix_mesh_text(const bench_peer *p, char *out, size_t size);

#endif
