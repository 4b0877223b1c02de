// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// Prep on one thread computes on one thread: a context asking for 1 thread
// prepares a scene whose distance fields and surfaces OpenVDB builds (an
// icosphere of 20480 triangles beside a box, 0.5 mm voxels), and no thread
// of the process but the caller's spends CPU time. OpenVDB runs its tools on
// TBB, whose workers took every core whatever `--threads` said; threads the
// libraries keep idle (log4cplus's pool) spend none and pass. Linux only
// (/proc/self/task); skipped on one core, where no worker would start.
#define _GNU_SOURCE // mkdtemp, DIR
#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "prep_fixture.h"

static const char scene[] =
    "{\"fascia_scene\": 1, \"voxel_size\": 0.0005, \"seed\": 2,\n"
    " \"materials\": {\"soft\": {\"youngs_modulus\": 3000, \"poisson_ratio\": 0.3}},\n"
    " \"organs\": [{\"name\": \"A\", \"mesh\": \"a.obj\", \"model\": \"fixed\"},\n"
    "              {\"name\": \"B\", \"mesh\": \"b.obj\", \"model\": \"rigid\"}],\n"
    " \"tissues\": [{\"name\": \"t\", \"connects\": [\"A\", \"B\"], \"max_gap\": 0.006, \"material\": \"soft\",\n"
    "               \"frame_spacing\": 0.004, \"sample_spacing\": 0.002}]}\n";

// CPU ticks (user + system) of thread tid of this process; -1 when unreadable.
static long thread_ticks(const char *tid) {
  char path[300], text[1024];
  snprintf(path, sizeof path, "/proc/self/task/%s/stat", tid);
  FILE *f = fopen(path, "r");
  if (!f) return -1;
  const size_t n = fread(text, 1, sizeof text - 1, f);
  fclose(f);
  text[n] = 0;
  const char *after = strrchr(text, ')'); // the name may hold spaces: fields follow its ')'
  unsigned long utime = 0, stime = 0;
  if (!after || sscanf(after + 2, "%*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %lu %lu", &utime, &stime) != 2)
    return -1;
  return (long)(utime + stime);
}

int main(void) {
  DIR *tasks = opendir("/proc/self/task");
  if (!tasks || sysconf(_SC_NPROCESSORS_ONLN) < 2) {
    printf("skipped: %s\n", tasks ? "one core: no worker thread would start" : "no /proc/self/task");
    if (tasks) closedir(tasks);
    return 77;
  }
  closedir(tasks);
  char dir[256];
  if (!fixture_tmpdir(dir)) return 1;
  const double lo[3] = {-0.03, -0.015, -0.015}, hi[3] = {-0.002, 0.015, 0.015}, centre[3] = {0.012, 0, 0};
  CHECK(fixture_box(dir, "a.obj", lo, hi) && fixture_icosphere(dir, "b.obj", centre, 0.012, 5, 0));
  fascia_ctx_def def = fascia_ctx_def_default();
  def.threads = 1;
  fascia_ctx *ctx = NULL;
  CHECK(fascia_ctx_create(&def, &ctx) == FASCIA_OK);
  fixture_run run = {0};
  const fascia_status status = fixture_prep_text(ctx, dir, scene, &run);
  CHECK(status == FASCIA_OK);
  if (status != FASCIA_OK) fprintf(stderr, "%s\n", fascia_ctx_message(ctx));

  char self[32];
  snprintf(self, sizeof self, "%ld", (long)getpid());
  long mine = thread_ticks(self), others = 0;
  int threads = 0;
  tasks = opendir("/proc/self/task");
  for (struct dirent *e; tasks && (e = readdir(tasks));) {
    if (e->d_name[0] == '.' || !strcmp(e->d_name, self)) continue;
    const long ticks = thread_ticks(e->d_name);
    ++threads;
    if (ticks > 0) others += ticks;
    if (ticks > 0) printf("thread %s: %ld ticks\n", e->d_name, ticks);
  }
  if (tasks) closedir(tasks);
  printf("the caller's thread %ld ticks, %d other threads %ld ticks\n", mine, threads, others);
  CHECK(mine > 0);
  // a tick is 10 ms: a worker that shared the distance fields took hundreds
  CHECK(others <= 2);
  fixture_free(&run);
  fascia_ctx_destroy(&ctx);
  static const char *const files[] = {"a.obj", "b.obj", "scene.json", NULL};
  fixture_cleanup(dir, files);
  return CHECK_RESULT();
}
