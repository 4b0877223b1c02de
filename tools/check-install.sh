#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Checks that an installed fascia can be used by a program of your own: builds
# (or reuses a build), installs into a temporary prefix, then builds examples/
# against that prefix only, never the build tree, with find_package(fascia) and
# with pkg-config, on the static and the shared library, and runs them on a
# model the installed CLI prepares; checks that the install names no folder
# of the build machine and that the shared library is versioned.
#
#   tools/check-install.sh [BUILD_DIR]     (default: $FASCIA_BUILD_DIR, else build/)
#
# A BUILD_DIR with a CMakeCache.txt is brought up to date and reused (CI runs
# this after tools/run-tests.sh); else it is configured and built first.
# Ends with "check-install: N passed, N failed"; the exit status is 1 when a
# check failed. Environment: JOBS (default nproc), KEEP=1 keeps the temporary
# folder and says where.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-${FASCIA_BUILD_DIR:-$root/build}}"
jobs="${JOBS:-$(nproc 2>/dev/null || echo 2)}"

if [ -f "$build/CMakeCache.txt" ]; then
  cmake --build "$build" -j "$jobs" >/dev/null
else
  FASCIA_BUILD_DIR="$build" "$root/tools/setup/build.sh"
fi

build="$(cd "$build" && pwd)"
work="$(mktemp -d "${TMPDIR:-/tmp}/fascia-install.XXXXXX")"
if [ "${KEEP:-0}" = 1 ]; then
  echo "check-install: keeping $work"
else
  trap 'rm -rf "$work"' EXIT
fi
prefix="$work/prefix"
passed=0
failed=0
skipped=""

# check NAME COMMAND...: runs it with its output in $work/NAME.log, which is
# shown when it fails
check() {
  local name="$1" log="$work/$1.log"
  shift
  if "$@" >"$log" 2>&1; then
    echo "check-install: ok    $name"
    passed=$((passed + 1))
  else
    echo "check-install: FAIL  $name (its output:)"
    sed 's/^/    /' "$log" | tail -n 30
    failed=$((failed + 1))
  fi
}

# --- the install, and nothing in it that points back at the checkout
check install cmake --install "$build" --prefix "$prefix"
no_source_paths() {
  local found
  found="$(grep -rlF -e "$root" -e "$build" --include='*.h' --include='*.cmake' --include='*.pc' --include='*.py' "$prefix")" || true
  [ -z "$found" ] || { echo "these name the checkout or the build folder: $found"; return 1; }
}
check no-source-paths no_source_paths
# nor a folder of the build machine: the .pc names only ${...} folders (its
# dependencies come as modules), the CMake files only the install's own
# prefix (dependencies come as imported targets, found again where used)
no_machine_paths() {
  local pc bad
  pc="$(find "$prefix" -name fascia.pc | head -n 1)"
  bad="$(grep -nE '(^|[[:space:]=,])(-[LI]|-Wl,-rpath,)?/' "$pc" | grep -v '^[0-9]*:#')" || true
  [ -z "$bad" ] || { echo "$pc names folders of this machine: $bad"; return 1; }
  bad="$(grep -nE '"/(usr|opt|home|root|tmp)/' "$(dirname "$(find "$prefix" -name fasciaConfig.cmake | head -n 1)")"/*.cmake)" || true
  [ -z "$bad" ] || { echo "the CMake package names folders of this machine: $bad"; return 1; }
}
check no-machine-paths no_machine_paths
# the shared library: versioned (soname libfascia_sim.so.MAJOR.MINOR, the
# links beside it), exporting the public API (fascia_*) only
version="$(sed -n 's/^Version: *//p' "$(find "$prefix" -name fascia.pc | head -n 1)")"
soname="libfascia_sim.so.${version%.*}"
shared_library() {
  local lib
  lib="$(find "$prefix" -name "libfascia_sim.so.$version" | head -n 1)"
  [ -n "$lib" ] || { echo "no libfascia_sim.so.$version in the install"; return 1; }
  readelf -d "$lib" | grep -F "[$soname]" | grep -q SONAME || { echo "$lib: soname is not $soname"; return 1; }
  [ "$(readlink "$(dirname "$lib")/$soname")" = "libfascia_sim.so.$version" ] || { echo "no link $soname"; return 1; }
  [ -L "$(dirname "$lib")/libfascia_sim.so" ] || { echo "no link libfascia_sim.so"; return 1; }
  local other
  other="$(nm -D --defined-only "$lib" | awk '{print $3}' | grep -v '^fascia_')" || true
  [ -z "$other" ] || { echo "$lib exports more than fascia_*: $(echo "$other" | head -n 5)"; return 1; }
}
check shared-library shared_library
# every public header compiles on its own against the installed include folder
headers_alone() {
  local h
  for h in "$prefix"/include/fascia/*.h; do
    echo "#include <fascia/$(basename "$h")>" | cc -std=c11 -Wall -Werror -fsyntax-only -x c -I"$prefix/include" - ||
      { echo "$h does not compile alone"; return 1; }
  done
}
check headers-alone headers_alone

# --- a model with organs, by the installed CLI (prep), for the example to
# drive; a build without prep can build the examples but not run them here
cmake_dir="$(dirname "$(find "$prefix" -name fasciaConfig.cmake | head -n 1)")"
have_prep=0
if [ -f "$cmake_dir/fasciaPrepTargets.cmake" ]; then have_prep=1; fi
model="$work/pelvis-female.h5"
if [ $have_prep = 1 ]; then
  check model "$prefix/bin/fascia" prep "$root/data/scenes/pelvis-female.json" -o "$model"
else
  skipped="$skipped model"
fi

# drive_organ's output against what the physics says: at the static
# equilibrium the reactions on the organs carry the tissue's weight
# (balance_error: relative, the Newton tolerance is 1e-6); lifting an organ,
# the tissue holds it back (the reaction along the lift drops); every
# number finite.
example_output_sane() {
  local out="$1" steps="$2"
  awk -v steps="$steps" '
    function finite(v) { return v ~ /^-?[0-9]+(\.[0-9]*)?([eE][-+]?[0-9]+)?$/ } # awk compares nan as equal
    $1 == "balance_error:" { balance = $2; seen_b = 1 }
    $1 == "reaction_change_along_lift_N:" { change = $2; seen_c = 1 }
    $1 ~ /^[0-9]+$/ && NF == 6 { rows++; for (k = 2; k <= 6; ++k) if (!finite($k)) bad = 1 }
    END {
      if (!seen_b || !finite(balance) || balance + 0 > 1e-6) {
        print "balance_error missing or above 1e-6: " balance; exit 1
      }
      if (!seen_c || !finite(change) || !(change + 0 < 0)) {
        print "reaction_change_along_lift_N missing or not negative: " change; exit 1
      }
      if (rows != steps || bad) {
        print "step rows: " rows " (expected " steps "), non-finite values: " bad + 0; exit 1
      }
    }' "$out"
}
run_example() { # BINARY MODEL ORGAN LIFT_MM STEPS: runs it, shows and checks its output
  local steps="$5"
  "$@" >"$work/run.out" || return 1
  cat "$work/run.out"
  example_output_sane "$work/run.out" "$steps"
}

# --- CMake: examples/ as its own project, fascia found in the prefix only
# (-Dfascia_DIR, no package registry), and linked from there
prep_example=OFF
if [ $have_prep = 1 ]; then prep_example=ON; fi
cmake_example() {
  cmake -S "$root/examples" -B "$work/examples" -DCMAKE_BUILD_TYPE=Release -Dfascia_DIR="$cmake_dir" \
    -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DFASCIA_EXAMPLES_PREP=$prep_example &&
    cmake --build "$work/examples" -j "$jobs" &&
    grep -q -F "$prefix/lib" "$work/examples/CMakeFiles/drive_organ.dir/link.txt" &&
    ! grep -q -F "$build" "$work/examples/CMakeFiles/drive_organ.dir/link.txt"
}
check cmake-build cmake_example
if [ $have_prep = 1 ]; then
  check cmake-run run_example "$work/examples/drive_organ" "$model" uterus 2 10
  cat "$work/cmake-run.log"
else
  skipped="$skipped cmake-run"
fi
if [ $have_prep = 1 ]; then
  scene_info_sane() {
    "$work/examples/scene_info" "$root/data/scenes/pelvis-female.json" >"$work/scene.out" &&
      cat "$work/scene.out" && grep -qx "organs: 2" "$work/scene.out" && grep -qx "tissues: 1" "$work/scene.out"
  }
  check cmake-prep-run scene_info_sane
fi

if [ $have_prep = 1 ]; then
  check cmake-shared-run run_example "$work/examples/drive_organ_shared" "$model" uterus 2 3
else
  skipped="$skipped cmake-shared-run"
fi
# drive_organ_shared runs on the installed shared library (found by its rpath)
links_shared() { ldd "$1" | grep -F "$soname => $prefix/"; }
check cmake-shared-links links_shared "$work/examples/drive_organ_shared"

# --- pkg-config: the README's one-line build (the shared library, found at
# run time through the rpath the .pc gives), and a static one (the archive
# and --static); the CUDA runtime's folder is the toolkit's, on LIBRARY_PATH
pc_dir="$(dirname "$(find "$prefix" -name fascia.pc | head -n 1)")"
cuda_lib="$(sed -n 's|^CUDA_cudart_static_LIBRARY:FILEPATH=\(.*\)/[^/]*$|\1|p' "$build/CMakeCache.txt")"
pc_build() { # OUTPUT [--static]
  local out="$1" flags
  shift
  flags="$(PKG_CONFIG_PATH="$pc_dir" pkg-config --cflags --libs "$@" fascia)" || return 1
  if [ "${1:-}" = --static ]; then flags="${flags/-lfascia_sim/-l:libfascia_sim.a}"; fi
  # shellcheck disable=SC2086 # the flags are meant to split
  LIBRARY_PATH="${cuda_lib:+$cuda_lib:}${LIBRARY_PATH:-}" \
    cc -std=c11 -Wall -Wextra -Werror "$root/examples/drive_organ.c" -o "$out" $flags -lm
}
check pkg-config-build pc_build "$work/drive_organ_pc"
check pkg-config-links links_shared "$work/drive_organ_pc"
check pkg-config-static-build pc_build "$work/drive_organ_pc_static" --static
links_static() { ! ldd "$1" | grep -F libfascia_sim; }
check pkg-config-static-links links_static "$work/drive_organ_pc_static"
if [ $have_prep = 1 ]; then
  check pkg-config-run run_example "$work/drive_organ_pc" "$model" bladder 1 3
  check pkg-config-static-run run_example "$work/drive_organ_pc_static" "$model" bladder 1 3
else
  skipped="$skipped pkg-config-run pkg-config-static-run"
fi

# --- the Python package, where it was built: imported from the prefix, on
# the prefix's library, running the example on the model
py_dir="$(find "$prefix" -type d -path '*/dist-packages/fascia' | head -n 1)"
if [ -n "$py_dir" ]; then
  python="$(sed -n 's|^FASCIA_PYTHON_EXECUTABLE:INTERNAL=||p' "$build/CMakeCache.txt")"
  python_import() {
    env -u FASCIA_LIBRARY -u FASCIA_CLI PYTHONPATH="$(dirname "$py_dir")" "${python:-python3}" -c \
      "import fascia, sys; p = fascia.library_path(); print(fascia.version(), p); sys.exit(not p.startswith('$prefix/'))"
  }
  check python-import python_import
  if [ $have_prep = 1 ]; then
    python_example() {
      env -u FASCIA_LIBRARY -u FASCIA_CLI PYTHONPATH="$(dirname "$py_dir")" "${python:-python3}" \
        "$root/examples/retract.py" "$model" --steps 3 && return 0
    }
    check python-example python_example
  fi
else
  skipped="$skipped python (not built)"
fi

if [ -n "$skipped" ]; then
  echo "check-install: skipped (this build has no prep to make a model with organs):$skipped"
fi
echo "check-install: $passed passed, $failed failed"
[ "$failed" = 0 ]
