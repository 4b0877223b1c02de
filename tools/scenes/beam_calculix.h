// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The paper's cantilever as a CalculiX (ccx) input deck, solved by the ccx
// program: the independent 3-D nonlinear finite-element reference of the
// frame scheme (data/reference/README.md). The deck is the beam of
// fascia_scene_beam_def: the box, its material and gravity, the x = 0 face
// clamped (every node of it held in x, y and z), the displacement of the
// node at the centre of the free end (length, 0, 0) read back.
#ifndef FASCIA_TOOLS_BEAM_CALCULIX_H
#define FASCIA_TOOLS_BEAM_CALCULIX_H
#include <stdio.h>

#include "scenes.h"

#ifdef __cplusplus
extern "C" {
#endif

/// CalculiX element of the deck.
typedef enum fascia_ccx_element {
  FASCIA_CCX_C3D20R = 0, ///< 20-node serendipity brick, reduced (2 x 2 x 2) integration
  FASCIA_CCX_C3D8I = 1,  ///< 8-node brick with incompatible (bending) modes, 2 x 2 x 2 integration
  FASCIA_CCX_ELEMENT_COUNT_
} fascia_ccx_element;

/// "C3D20R", "C3D8I"; "unknown" otherwise.
const char *fascia_ccx_element_name(int element);
/// Element from its name (case as above); -1 if unknown.
int fascia_ccx_element_from_name(const char *name);

/// One deck. The material law follows beam.law: FASCIA_LAW_STVK is ccx's
/// *ELASTIC under NLGEOM (linear in the Green-Lagrange strain and the second
/// Piola-Kirchhoff stress: exactly fascia's StVK); FASCIA_LAW_NEOHOOKEAN is
/// ccx's *HYPERELASTIC, NEO HOOKE, psi = C10 (I1bar - 3) + (J - 1)^2 / D1 with
/// C10 = mu / 2, D1 = 2 / K: the same small-strain moduli as fascia's stable
/// Neo-Hookean but not the same law at finite strain.
typedef struct fascia_ccx_beam_def {
  fascia_scene_beam_def beam; ///< box, law, E, nu, density or mass, gravity; frames and shape ignored
  int32_t element;            ///< fascia_ccx_element
  /// Elements along x, y, z; z even, y even (a node at the end's centre);
  /// with `half`, the elements across the half width.
  int32_t cells[3];
  /// 1: only the half y >= 0, the plane y = 0 held in y (the load and the
  /// body are symmetric, and so is the solution: fascia's too), an eighth of
  /// the factorization's cost. Default 0: the whole beam.
  int32_t half;
  /// Element size ratios, largest to smallest, of a geometric grading
  /// along x (smallest at the clamp) and across y and z (smallest at the
  /// surfaces, symmetric about the axis): the clamped face's edges are singular, and graded
  /// meshes converge there. 1: uniform. Defaults 1, 1, 1.
  double grading[3];
  /// Newton convergence: 0 ccx's default controls (residual 0.5 % of the
  /// mean force), 1 tight (residual 1e-7 of it, correction 1e-7 of the
  /// displacement), for references.
  int32_t tight;
} fascia_ccx_beam_def;

/// Defaults: the beam of fascia_scene_beam_def_default(), C3D20R, 32 x 2 x 2
/// elements, uniform, tight controls.
fascia_ccx_beam_def fascia_ccx_beam_def_default(void);

/// What a solve gave.
typedef struct fascia_ccx_result {
  double tip[3];        ///< displacement of the node at (length, 0, 0), m
  int32_t nodes;        ///< nodes of the mesh
  int32_t elements;     ///< elements
  int32_t dofs;         ///< free degrees of freedom (3 per node off the clamped face)
  int32_t increments;   ///< load increments ccx took
  int32_t iterations;   ///< Newton iterations over all increments
  double ms;            ///< wall time: the deck written, ccx run, its output read
  double cpu_ms;        ///< processor time of the ccx process (user + system, all its threads)
} fascia_ccx_result;

/// Writes the deck to `out`. Errors: FASCIA_ERR_ARGUMENT for a bad def
/// (naming the field), FASCIA_ERR_IO when writing fails.
fascia_status fascia_ccx_beam_write(fascia_ctx *ctx, const fascia_ccx_beam_def *def, FILE *out);

/// The ccx program to run: $FASCIA_CCX if set, else "ccx" when it is on the
/// PATH; NULL when there is none (the caller says CalculiX is not installed).
const char *fascia_ccx_program(void);

/// Writes the deck into a fresh temporary folder (under $TMPDIR or /tmp),
/// runs `program` on it with `threads` threads (>= 1) and reads back the
/// tip displacement and the increments and iterations taken; the folder is
/// removed. Errors: FASCIA_ERR_ARGUMENT (bad def), FASCIA_ERR_IO (the folder,
/// the deck or starting the program), FASCIA_ERR_NUMERIC (ccx failed or did
/// not reach the full load, with the last line it printed), FASCIA_ERR_FORMAT
/// (its output could not be read); *out is then undefined.
fascia_status fascia_ccx_beam_solve(fascia_ctx *ctx, const fascia_ccx_beam_def *def, const char *program,
                                    int threads, fascia_ccx_result *out);

/// The end of a deck writer: FASCIA_ERR_IO with the reason when writing
/// `out` failed (a full disk), else FASCIA_OK.
fascia_status fascia_ccx_deck_written(fascia_ctx *ctx, FILE *out);

/// Writes a deck to `out`; `arg` is the writer's own definition.
typedef fascia_status (*fascia_ccx_deck_writer)(fascia_ctx *ctx, const void *arg, FILE *out);

/// Any deck: written by `write` into a fresh temporary folder (under $TMPDIR
/// or /tmp), `program` run on it with `threads` threads as
/// fascia_ccx_beam_solve does, the whole text of its .dat output returned in
/// *dat (malloc'd, the caller frees it), the folder removed. `what` names the
/// model in messages. ccx must reach the end of its step (load time 1).
/// Errors: those of `write`, FASCIA_ERR_IO (the folder, the deck, starting
/// the program), FASCIA_ERR_NUMERIC (ccx failed or stopped short of the full
/// load, with the last line it printed), FASCIA_ERR_FORMAT (no .dat);
/// *dat is then NULL.
fascia_status fascia_ccx_run_deck(fascia_ctx *ctx, const char *what, fascia_ccx_deck_writer write, const void *arg,
                                  const char *program, int threads, char **dat, double *cpu_ms);
/// fascia_ccx_run_deck, timed: *ms gets the wall-clock milliseconds of the
/// whole run (the deck, ccx, its output), the time the cases report.
fascia_status fascia_ccx_run_timed(fascia_ctx *ctx, const char *what, fascia_ccx_deck_writer write, const void *arg,
                                   const char *program, int threads, char **dat, double *ms);

/// The characters of a deck's data field that ccx reads: it cuts a longer
/// one without a word (-7.61426191299358e-05 is read as -7.6).
#define FASCIA_CCX_FIELD 20
/// 1 when every field of the data lines of the deck at `path` fits in
/// FASCIA_CCX_FIELD characters; else 0 and, in why, the line and field.
/// Every deck is checked before ccx runs it (fascia_ccx_run_deck, the
/// cantilever's run).
int fascia_ccx_deck_fits(const char *path, char *why, size_t size);

/// The line after the last line of a .dat text that holds `header` (where
/// ccx's last block of that output starts); NULL if none.
const char *fascia_ccx_dat_after(const char *dat, const char *header);
/// The first line of three numbers from `block` on, blank lines skipped (a
/// block's total); 0 when the block ends first or is NULL.
int fascia_ccx_dat_triple(const char *block, double v[3]);
/// The three values of `node` in a block of "node v1 v2 v3" lines (blank
/// lines first); 0 when the block ends first or is NULL.
int fascia_ccx_dat_node(const char *block, long long node, double v[3]);
/// The `count` numbers of a .dat line from `line` on, read Fortran's way: an
/// exponent of three digits comes without its E ("1.234567-100", which a C
/// reader takes for 1.234567); 0 unless all of them are there.
int fascia_ccx_dat_numbers(const char *line, double *v, int count);

/// A converged reference of the tip of fascia's cantilever (the box, mass
/// and gravity of fascia_scene_beam_def_default()), stored in
/// data/reference/cantilever-calculix.csv with how it was refined.
typedef struct fascia_ccx_reference {
  int law;                     ///< fascia_law
  double youngs_modulus;       ///< Pa
  double poisson_ratio;
  double tip_ux, tip_uz;       ///< m
  double uncertainty_uz;       ///< m: the refinement's error bound on tip_uz
} fascia_ccx_reference;

/// The stored references; *count gets their number.
const fascia_ccx_reference *fascia_ccx_references(int *count);

/// The stored reference for the law, E and nu of `def` (which must have the
/// default box, mass and gravity); NULL if none.
const fascia_ccx_reference *fascia_ccx_reference_find(const fascia_scene_beam_def *def);

#ifdef __cplusplus
}
#endif
#endif
