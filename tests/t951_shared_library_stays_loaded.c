// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: fascia developers
// The shared library stays loaded when a host lets it go. Python's cffi
// dlcloses libfascia_sim.so as the interpreter exits; unmapping it then
// took OpenMP's runtime along while its idle worker threads still ran in
// it, and the host died of SIGSEGV after its work was done (1 exit in 15
// of examples/retract.py on a busy machine). The library is linked
// -z nodelete: after dlopen, a call and dlclose, it is still mapped.
// Usage: t951_shared_library_stays_loaded PATH/TO/libfascia_sim.so
#define _GNU_SOURCE // RTLD_NOLOAD
#include <dlfcn.h>

#include "check.h"

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: t951_shared_library_stays_loaded PATH/TO/libfascia_sim.so\n");
    return 1;
  }
  void *library = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
  CHECK(library != NULL);
  if (!library) {
    fprintf(stderr, "%s\n", dlerror());
    return CHECK_RESULT();
  }
  const char *(*version)(void) = NULL;
  *(void **)&version = dlsym(library, "fascia_version");
  CHECK(version != NULL && version()[0] != 0);
  CHECK(dlclose(library) == 0);
  void *still = dlopen(argv[1], RTLD_NOW | RTLD_NOLOAD); // NULL once it is unmapped
  CHECK(still != NULL);
  if (still) dlclose(still);
  return CHECK_RESULT();
}
