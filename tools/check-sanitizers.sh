#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The test suite under AddressSanitizer + UndefinedBehaviorSanitizer, and the
# simulator core under valgrind with no leaks.
#
#   tools/check-sanitizers.sh asan [--core [--quick]]
#                                             ASan+UBSan build (FASCIA_SANITIZE=ON) in its own
#                                             folder, then ctest -LE gpu; --core: the simulator
#                                             core, CLI and fuzz replays only (FASCIA_PREP=OFF);
#                                             --quick: without the tests labelled slow (what CI
#                                             runs: .ci/run)
#   tools/check-sanitizers.sh valgrind        the core tests (t0xx-t3xx, not 'slow') of a normal
#                                             build under valgrind: no errors, no leaks
#
# Environment: FASCIA_SANITIZE_BUILD (default build-sanitize[-core]/ in the checkout), FASCIA_VALGRIND_BUILD
# (default build-valgrind/), JOBS (default nproc).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
jobs="${JOBS:-$(nproc 2>/dev/null || echo 2)}"
mode="${1:-asan}"
shift || true

# sim/src/solve/newton.c calls clock_gettime without asking for POSIX; gcc's omp.h
# happens to define _POSIX_C_SOURCE, clang's does not: say it here.
posix="-D_POSIX_C_SOURCE=200809L"

case "$mode" in
asan)
  core=0
  # hdf5-damage: tests that feed damaged files to HDF5, whose own memory
  # errors on them ASan reports (tests/CMakeLists.txt); they run unsanitized
  exclude="gpu|hdf5-damage"
  if [ "${1:-}" = "--core" ]; then core=1; fi
  if [ "${2:-}" = "--quick" ]; then exclude="gpu|slow|hdf5-damage"; fi
  build="${FASCIA_SANITIZE_BUILD:-$root/build-sanitize$([ $core = 1 ] && echo -core || true)}"
  prep=ON
  if [ $core = 1 ]; then prep=OFF; fi
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFASCIA_SANITIZE=ON -DFASCIA_PREP=$prep \
    -DFASCIA_CUDA=OFF -DFASCIA_WERROR=ON -DCMAKE_C_FLAGS="$posix" >"$build.configure.log" 2>&1 ||
    { cat "$build.configure.log" >&2; exit 1; }
  cmake --build "$build" -j "$jobs"
  # leaks are errors; UBSan stops the test at its first report. A malloc too
  # large to satisfy returns NULL, as the C library's does: HDF5 asks for
  # petabytes when a damaged file names a wild address, and must get its
  # failure back to report it (t208, t915), not an abort
  export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1:allocator_may_return_null=1}"
  export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
  export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$root/tests/fuzz/lsan-third-party.supp:print_suppressions=0}"
  cd "$build"
  ctest --output-on-failure -j "$jobs" -LE "$exclude" --timeout 1800
  ;;
valgrind)
  command -v valgrind >/dev/null || { echo "check-sanitizers: valgrind is not installed (apt-get install valgrind)" >&2; exit 2; }
  build="${FASCIA_VALGRIND_BUILD:-$root/build-valgrind}"
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFASCIA_PREP=OFF -DFASCIA_CUDA=OFF \
    -DCMAKE_C_FLAGS="$posix" >"$build.configure.log" 2>&1 || { cat "$build.configure.log" >&2; exit 1; }
  cmake --build "$build" -j "$jobs"
  cd "$build/tests" # where ctest runs them
  # one OpenMP thread: libgomp's pool is reported as "possibly lost" otherwise
  export OMP_NUM_THREADS=1
  failed=0
  count=0
  # each core test (t0xx-t3xx, not labelled slow or gpu) with its ctest arguments
  while IFS=$'\t' read -r name command; do
    [ -n "$name" ] || continue
    count=$((count + 1))
    log="$build/valgrind-$name.log"
    # shellcheck disable=SC2086 # the command line is ctest's, already split into words
    if valgrind --quiet --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite,indirect \
      --show-leak-kinds=definite,indirect --log-file="$log" $command >/dev/null 2>&1; then
      echo "valgrind: $name clean"
    else
      echo "valgrind: $name FAILED (see $log)"
      failed=$((failed + 1))
    fi
  done < <(ctest --test-dir "$build" --show-only=json-v1 -R '^t[0-3][0-9][0-9]_' -LE 'slow|gpu' | python3 -c '
import json, shlex, sys
for t in json.load(sys.stdin)["tests"]:
    print(t["name"] + "\t" + " ".join(shlex.quote(a) for a in t["command"]))')
  echo "valgrind: $count core tests, $failed failed"
  [ "$failed" -eq 0 ]
  ;;
*)
  echo "usage: tools/check-sanitizers.sh asan [--core] | valgrind" >&2
  exit 2
  ;;
esac
