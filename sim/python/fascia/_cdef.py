# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
"""The declarations of libfascia_sim.so that the package calls (cffi, ABI
mode): a copy of the public headers' declarations, never of their logic.
Structs are laid out by cffi from these declarations; tests/test_layout.py
checks every field's offset against the C compiler's (layout.c)."""

CDEF = """
typedef double fascia_real;
typedef int fascia_status;
const char *fascia_status_name(fascia_status status);
const char *fascia_version(void);

typedef void (*fascia_progress_fn)(void *user, const char *stage, double fraction, const char *detail);
typedef struct fascia_ctx fascia_ctx;
typedef struct fascia_ctx_def {
  int threads;
  fascia_progress_fn progress;
  void *progress_user;
  int cookie_;
} fascia_ctx_def;
fascia_ctx_def fascia_ctx_def_default(void);
fascia_status fascia_ctx_create(const fascia_ctx_def *def, fascia_ctx **out);
void fascia_ctx_destroy(fascia_ctx **ctx);
const char *fascia_ctx_message(const fascia_ctx *ctx);

typedef struct fascia_model fascia_model;
fascia_status fascia_model_load(fascia_ctx *ctx, const char *path, fascia_model **out);
void fascia_model_destroy(fascia_model **model);
int32_t fascia_model_find_organ(const fascia_model *model, const char *name);
int32_t fascia_model_organ_count(const fascia_model *model);
const char *fascia_model_organ_name(const fascia_model *model, int32_t organ);
typedef struct fascia_surface {
  int32_t vertex_count;
  int32_t triangle_count;
  fascia_real *vertices;
  int32_t *triangles;
} fascia_surface;
const fascia_surface *fascia_model_tissue_surface(const fascia_model *model);

typedef struct fascia_solver_def {
  const char *backend;
  int threads;
  fascia_real time_step;
  int newton_iterations;
  fascia_real newton_tolerance;
  int cg_iterations;
  int cg_fixed;
  fascia_real cg_tolerance;
  int precond;
  int linear_solver;
  int assembled;
  int single_precision_matrix;
  int mass;
  fascia_real mass_damping;
  int line_search;
  int load_steps;
  int step_retries;
  int require_convergence;
  fascia_real blow_up_strain;
  int cookie_;
} fascia_solver_def;
fascia_solver_def fascia_solver_def_default(void);

typedef struct fascia_profile {
  double evaluate_ms;
  double precond_ms;
  double assemble_ms;
  double cg_ms;
  double total_ms;
} fascia_profile;
typedef struct fascia_solve_report {
  int converged;
  int newton_iterations;
  int cg_iterations;
  int line_search_cuts;
  int watchdog_returns;
  int negative_curvature;
  int direct;
  int assembled;
  int single_precision_matrix;
  int factorizations;
  fascia_real gradient_norm;
  fascia_real reference_norm;
  fascia_real energy;
  int32_t inverted_samples;
  int substeps;
  int rejected;
  fascia_profile profile;
} fascia_solve_report;

typedef struct fascia_solver fascia_solver;
fascia_status fascia_solver_create(fascia_ctx *ctx, const fascia_model *model, const fascia_solver_def *def,
                                   fascia_solver **out);
void fascia_solver_destroy(fascia_solver **solver);
fascia_status fascia_solver_step(fascia_solver *solver, fascia_solve_report *report);
fascia_status fascia_solver_solve_static(fascia_solver *solver, fascia_solve_report *report);
fascia_real fascia_solver_time(const fascia_solver *solver);
fascia_status fascia_solver_set_time(fascia_solver *solver, fascia_real time);
fascia_real fascia_solver_time_step(const fascia_solver *solver);
fascia_status fascia_solver_set_time_step(fascia_solver *solver, fascia_real time_step);
int32_t fascia_solver_frame_count(const fascia_solver *solver);
int32_t fascia_solver_sample_count(const fascia_solver *solver);
const char *fascia_solver_backend(const fascia_solver *solver);
const char *fascia_solver_device(const fascia_solver *solver);
const fascia_real *fascia_solver_frame_positions(const fascia_solver *solver);
const fascia_real *fascia_solver_frame_rotations(const fascia_solver *solver);
const fascia_real *fascia_solver_frame_velocities(const fascia_solver *solver);
void fascia_solver_sample_positions(const fascia_solver *solver, fascia_real *out);
fascia_status fascia_solver_tissue_surface(const fascia_solver *solver, fascia_real *positions, fascia_real *strain);
fascia_status fascia_solver_organ_pose(const fascia_solver *solver, int32_t organ, fascia_real *translation,
                                       fascia_real *rotation);
fascia_status fascia_solver_organ_set_pose(fascia_solver *solver, int32_t organ, const fascia_real *translation,
                                           const fascia_real *rotation);
fascia_status fascia_solver_organ_release(fascia_solver *solver, int32_t organ);
fascia_status fascia_solver_organ_wrench(fascia_solver *solver, int32_t organ, fascia_real *force,
                                         fascia_real *torque, fascia_real *point);
"""

# names of the enum values a setting takes (fascia/solver.h)
ENUMS = {
    "precond": {"none": 0, "jacobi": 1, "block_jacobi": 2},
    "linear_solver": {"auto": 0, "cg": 1, "direct": 2},
    "mass": {"consistent": 0, "lumped": 1},
}
# layout.c prints these structs' sizes and field offsets
STRUCTS = ("fascia_ctx_def", "fascia_surface", "fascia_solver_def", "fascia_profile", "fascia_solve_report")
