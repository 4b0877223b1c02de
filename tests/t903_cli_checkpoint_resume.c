// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// A dynamic `fascia run` killed with SIGKILL at random moments (after its
// first checkpoint) and resumed with --resume reaches the same final state,
// bit for bit, as a run never interrupted: time, step, frame positions,
// rotations and velocities of the final checkpoints are compared with the
// HDF5 API. A checkpoint of another model is refused with a message saying
// so, and another --dt as an option that contradicts the checkpoint. The
// beam is tetrahedral: its patches' enhanced strain modes are solved afresh
// at each evaluation, so a resumed run needs nothing more than the frames.
// Usage: t903_cli_checkpoint_resume PATH/TO/fascia WORK_DIR
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <hdf5.h>
#include <signal.h>
#include <stdint.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "cli_exec.h"

#define STEPS "60"
#define DT "0.005"
#define KILLS 3

static cli_result result;

static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void sleep_s(double s) {
  struct timespec t = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
  while (nanosleep(&t, &t) != 0 && errno == EINTR) {
  }
}

static int file_exists(const char *path) {
  struct stat st;
  return stat(path, &st) == 0;
}

// Starts `fascia run MODEL --steps N --dt DT --threads 1 --checkpoint CK
// --checkpoint-every 2` (stdout and stderr to /dev/null); returns its pid.
static pid_t start_run(const char *fascia, const char *model, const char *checkpoint) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (!freopen("/dev/null", "w", stdout) || !freopen("/dev/null", "w", stderr)) _exit(127);
    setenv("FASCIA_PROGRESS", "0", 1);
    execl(fascia, fascia, "run", model, "--steps", STEPS, "--dt", DT, "--threads", "1", "--checkpoint", checkpoint,
          "--checkpoint-every", "2", (char *)NULL);
    _exit(127);
  }
  return pid;
}

// Reads dataset `name` of a checkpoint as raw bytes (up to size); returns the
// byte count, 0 on failure.
static size_t read_raw(const char *path, const char *name, void *out, size_t size) {
  hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return 0;
  size_t bytes = 0;
  hid_t dset = H5Dopen2(file, name, H5P_DEFAULT);
  if (dset >= 0) {
    hid_t type = H5Dget_type(dset), space = H5Dget_space(dset);
    bytes = (size_t)H5Sget_simple_extent_npoints(space) * H5Tget_size(type);
    if (bytes > size || H5Dread(dset, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) < 0) bytes = 0;
    H5Tclose(type);
    H5Sclose(space);
    H5Dclose(dset);
  }
  H5Fclose(file);
  return bytes;
}

// 0 when the two checkpoints hold the same bits in every state dataset.
static int compare_checkpoints(const char *a, const char *b, int attempt) {
  static const char *const names[] = {"/run/step", "/run/time", "/state/position", "/state/rotation",
                                      "/state/velocity"};
  static unsigned char da[1 << 20], db[1 << 20];
  int failed = 0;
  for (size_t k = 0; k < sizeof names / sizeof names[0]; ++k) {
    const size_t na = read_raw(a, names[k], da, sizeof da), nb = read_raw(b, names[k], db, sizeof db);
    if (na == 0 || na != nb || memcmp(da, db, na) != 0) {
      size_t first = 0;
      while (first < na && first < nb && da[first] == db[first]) ++first;
      fprintf(stderr, "kill %d: %s differs from the uninterrupted run (%zu and %zu bytes, first difference at byte %zu)\n",
              attempt, names[k], na, nb, first);
      failed = 1;
    }
  }
  return failed;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: %s PATH/TO/fascia WORK_DIR\n", argv[0]);
    return 2;
  }
  const char *fascia = argv[1];
  char dir[4096], model[4200], other[4200], ref[4200], ck[4200], err[4200], args[16384];
  snprintf(dir, sizeof dir, "%s/t903-%ld", argv[2], (long)getpid());
  if (mkdir(dir, 0755) != 0) {
    perror(dir);
    return 1;
  }
  snprintf(model, sizeof model, "%s/beam.h5", dir);
  snprintf(other, sizeof other, "%s/other.h5", dir);
  snprintf(ref, sizeof ref, "%s/reference.ck.h5", dir);
  snprintf(err, sizeof err, "%s/stderr.txt", dir);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);

  // the model, and an uninterrupted run whose last checkpoint is the reference
  snprintf(args, sizeof args, "beam --frames 10x3x3 --shape tet -o '%s'", model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  snprintf(args, sizeof args, "beam --frames 10x3x3 --shape tet --E 50000 -o '%s'", other);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  const double t0 = now_s();
  snprintf(args, sizeof args,
           "run '%s' --steps " STEPS " --dt " DT " --threads 1 --checkpoint '%s' --checkpoint-every 1000", model, ref);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
  const double run_s = now_s() - t0;
  CHECK(file_exists(ref));
  if (CHECK_RESULT()) {
    fprintf(stderr, "reference run failed: %s\n", result.err);
    return 1;
  }

  // kill at random moments of a run (after its first checkpoint), resume, compare
  unsigned long long seed = 0x9e3779b97f4a7c15ull;
  int killed_mid_run = 0;
  for (int attempt = 0; attempt < KILLS; ++attempt) {
    snprintf(ck, sizeof ck, "%s/killed-%d.ck.h5", dir, attempt);
    seed ^= seed << 13, seed ^= seed >> 7, seed ^= seed << 17;
    const double fraction = 0.1 + 0.8 * (double)(seed % 1000) / 1000.0;
    const pid_t pid = start_run(fascia, model, ck);
    CHECK(pid > 0);
    const double start = now_s();
    while (!file_exists(ck) && now_s() - start < 60) sleep_s(0.002);
    sleep_s(fraction * run_s);
    int status = 0;
    const int alive = waitpid(pid, &status, WNOHANG) == 0;
    if (alive) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      killed_mid_run += WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
    }
    CHECK(file_exists(ck));
    snprintf(args, sizeof args,
             "run '%s' --steps " STEPS " --dt " DT " --threads 1 --resume '%s' --checkpoint '%s' --checkpoint-every 2",
             model, ck, ck);
    CHECK(cli_exec(fascia, args, err, &result) && result.status == 0);
    if (result.status != 0) fprintf(stderr, "kill %d: resume failed: %s\n", attempt, result.err);
    CHECK(compare_checkpoints(ref, ck, attempt) == 0);
  }
  // the test is only meaningful when runs were really cut short
  CHECK(killed_mid_run >= 1);

  // another model, another time step: refused with a message
  snprintf(args, sizeof args, "run '%s' --steps " STEPS " --dt " DT " --resume '%s'", other, ref);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 1);
  CHECK(strstr(result.err, "another model") != NULL);
  // (resuming keeps the checkpoint's settings: another --dt is a conflicting option)
  snprintf(args, sizeof args, "run '%s' --steps " STEPS " --dt 0.01 --resume '%s'", model, ref);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 2);
  CHECK(strstr(result.err, "time_step") != NULL && strstr(result.err, "--dt") != NULL);
  // a model file is not a checkpoint
  snprintf(args, sizeof args, "run '%s' --steps " STEPS " --dt " DT " --resume '%s'", model, model);
  CHECK(cli_exec(fascia, args, err, &result) && result.status == 1);
  CHECK(strstr(result.err, "not a fascia checkpoint") != NULL);
  if (CHECK_RESULT()) fprintf(stderr, "last stderr: %s\n", result.err);

  // clean up (temporary names left by killed runs included)
  if (!CHECK_RESULT()) {
    char command[8400];
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    if (system(command) != 0) fprintf(stderr, "could not remove %s\n", dir);
  }
  return CHECK_RESULT();
}
