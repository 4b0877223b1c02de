// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A results file opens right in ParaView: every XDMF reader ParaView 5.11
// offers (Xdmf3ReaderS, Xdmf3ReaderT, XDMF Reader) shows one time per saved
// step, the blocks "frames" and "samples" under stable names, every point,
// and the arrays (displacement, frame axes, rest positions, organ, fields)
// with the values of the HDF5 file; every dataset carries a unit and a
// meaning. The checks run in ParaView's own Python (pvbatch,
// tests/paraview/check_results.py); without pvbatch the test is skipped.
// Before the sidecar named per-step virtual datasets and explicit vertex
// lists, the Xdmf3 readers loaded 0 points and the blocks were renamed
// "frames[2]" at later steps.
// Usage: t230_io_results_paraview PATH/TO/check_results.py
#define _POSIX_C_SOURCE 200809L

#include "check.h"
#include <sys/wait.h>
#include <unistd.h>

#include "io_fixture.h"

#define STEPS 4

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t230_io_results_paraview PATH/TO/check_results.py\n");
    return 1;
  }
  if (system("command -v pvbatch >/dev/null 2>&1") != 0) {
    printf("t230: skipped: pvbatch (Debian's python3-paraview, tools/setup/debian-packages.sh) is not installed\n");
    return TEST_SKIP;
  }
  fascia_ctx_def cdef = fascia_ctx_def_default();
  fascia_ctx *ctx = NULL;
  if (fascia_ctx_create(&cdef, &ctx) != FASCIA_OK) return 1;
  char dir[] = "t230-XXXXXX";
  CHECK(mkdtemp(dir) != NULL);
  char path[1400], xdmf[1400], command[4096], cwd[1024];
  CHECK(getcwd(cwd, sizeof cwd) != NULL);
  // absolute paths: the Xdmf3 readers resolve the HDF5 file wrongly from a bare file name
  snprintf(path, sizeof path, "%s/%s/results.h5", cwd, dir);
  snprintf(xdmf, sizeof xdmf, "%s/%s/results.xdmf", cwd, dir);
  fascia_model *m = NULL;
  CHECK_OK(fixture_model(ctx, 0, &m), ctx);
  fascia_results_def def = fascia_results_def_default();
  def.write_samples = true;
  fascia_results *r = NULL;
  double x[15], q[20], p[9], strain[3];
  CHECK(m->frame_count == 5 && m->sample_count == 3);
  CHECK_OK(fascia_results_open(ctx, path, m, &def, &r), ctx);
  CHECK_OK(fascia_results_describe_field(r, "strain", "1", "a test field"), ctx);
  for (int t = 0; t < STEPS; ++t) {
    for (int32_t i = 0; i < m->frame_count; ++i) {
      for (int c = 0; c < 3; ++c) x[3 * i + c] = m->frame_position[3 * i + c] + 0.001 * t * (c + 1) + 1e-3 * i;
      const double angle = 0.1 * t + 0.2 * i;
      q[4 * i] = cos(angle), q[4 * i + 1] = sin(angle) * 0.6, q[4 * i + 2] = 0, q[4 * i + 3] = sin(angle) * 0.8;
    }
    for (int32_t s = 0; s < m->sample_count; ++s) {
      for (int c = 0; c < 3; ++c) p[3 * s + c] = m->sample_position[3 * s + c] - 0.002 * t / 3.0 * (c + s);
      strain[s] = 1e-3 * t / 7.0 + s;
    }
    CHECK_OK(fascia_results_append(r, 0.1 * t, x, q, p), ctx);
    CHECK_OK(fascia_results_append_field(r, "strain", strain), ctx);
  }
  CHECK_OK(fascia_results_close(&r), ctx);
  snprintf(command, sizeof command, "pvbatch '%s' '%s' '%s' 2>&1", argv[1], xdmf, path);
  fflush(stdout);
  const int status = system(command);
  CHECK(status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0);
  if (!check_failures_) {
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    (void)system(command);
  }
  fascia_model_destroy(&m);
  fascia_ctx_destroy(&ctx);
  return CHECK_RESULT();
}
