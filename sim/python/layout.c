// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Prints the size and every field's offset of the structs the Python
// package declares to cffi (fascia/_cdef.py), as the C compiler lays them
// out: "struct field offset" lines, "struct sizeof size" per struct.
// tests/test_layout.py compares them with cffi's.
#include <stddef.h>
#include <stdio.h>

#include "fascia/fascia.h"

#define FIELD(s, f) printf("%s %s %zu\n", #s, #f, offsetof(s, f))
#define SIZE(s) printf("%s sizeof %zu\n", #s, sizeof(s))

int main(void) {
  SIZE(fascia_ctx_def);
  FIELD(fascia_ctx_def, threads), FIELD(fascia_ctx_def, progress), FIELD(fascia_ctx_def, progress_user);
  FIELD(fascia_ctx_def, cookie_);
  SIZE(fascia_surface);
  FIELD(fascia_surface, vertex_count), FIELD(fascia_surface, triangle_count), FIELD(fascia_surface, vertices);
  FIELD(fascia_surface, triangles);
  SIZE(fascia_solver_def);
  FIELD(fascia_solver_def, backend), FIELD(fascia_solver_def, threads), FIELD(fascia_solver_def, time_step);
  FIELD(fascia_solver_def, newton_iterations), FIELD(fascia_solver_def, newton_tolerance);
  FIELD(fascia_solver_def, cg_iterations), FIELD(fascia_solver_def, cg_fixed), FIELD(fascia_solver_def, cg_tolerance);
  FIELD(fascia_solver_def, precond), FIELD(fascia_solver_def, linear_solver), FIELD(fascia_solver_def, assembled);
  FIELD(fascia_solver_def, single_precision_matrix), FIELD(fascia_solver_def, mass);
  FIELD(fascia_solver_def, mass_damping), FIELD(fascia_solver_def, line_search), FIELD(fascia_solver_def, load_steps);
  FIELD(fascia_solver_def, step_retries), FIELD(fascia_solver_def, require_convergence);
  FIELD(fascia_solver_def, blow_up_strain), FIELD(fascia_solver_def, cookie_);
  SIZE(fascia_profile);
  FIELD(fascia_profile, evaluate_ms), FIELD(fascia_profile, precond_ms), FIELD(fascia_profile, assemble_ms);
  FIELD(fascia_profile, cg_ms), FIELD(fascia_profile, total_ms);
  SIZE(fascia_solve_report);
  FIELD(fascia_solve_report, converged), FIELD(fascia_solve_report, newton_iterations);
  FIELD(fascia_solve_report, cg_iterations), FIELD(fascia_solve_report, line_search_cuts);
  FIELD(fascia_solve_report, watchdog_returns), FIELD(fascia_solve_report, negative_curvature);
  FIELD(fascia_solve_report, direct), FIELD(fascia_solve_report, assembled);
  FIELD(fascia_solve_report, single_precision_matrix), FIELD(fascia_solve_report, factorizations);
  FIELD(fascia_solve_report, gradient_norm), FIELD(fascia_solve_report, reference_norm);
  FIELD(fascia_solve_report, energy), FIELD(fascia_solve_report, inverted_samples);
  FIELD(fascia_solve_report, substeps), FIELD(fascia_solve_report, rejected), FIELD(fascia_solve_report, profile);
  return 0;
}
