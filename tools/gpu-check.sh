#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The CUDA backend's check on a GPU (docs/gpu.md), in two halves,
# because a GPU machine may have the CUDA driver and toolkit but none of the
# Debian packages fascia builds with:
#
#   tools/gpu-check.sh pack        here: builds build-gpu/ (CUDA on, prep off),
#                                  prepares the demo tissue model, gathers the
#                                  programs and the shared libraries they need
#                                  into build-gpu/pack (about 100 MB, OpenBLAS
#                                  alone 37) and compresses it into
#                                  build-gpu/pack.tar.xz, which must stay under
#                                  the device tool's 64 MiB carry limit
#   tools/gpu-check.sh run [DIR]   on the GPU machine, from the repository root,
#                                  with build-gpu/pack.tar.xz (or the folder)
#                                  carried there: the GPU tests, the benchmarks,
#                                  a kernel profile (ncu) and compute-sanitizer;
#                                  logs and CSV into DIR (default: $OUT, else
#                                  out/gpu-check)
#
# With the session's device tool: run(command="tools/gpu-check.sh run",
# carry=["build-gpu/pack.tar.xz"]); it writes 8 files, what that tool brings back.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
pack="$root/build-gpu/pack"
archive="$root/build-gpu/pack.tar.xz"
carry_limit=$((64 * 1024 * 1024))
# the solver, stability and organ suites, run on the GPU with --backend cuda
solver_tests=(t301_solver_cantilever t302_solver_free_fall t303_solver_determinism t304_solver_prescribed
  t305_solver_loads t306_solver_reduced_integration t307_solver_volumetric_patches t310_stability_time_step
  t311_stability_stiffness t312_stability_poisson t313_stability_inversion t314_stability_few_frames
  t315_stability_inexact_solves t316_stability_step_retry t320_organs_rigid_momentum t321_organs_fixed_holds
  t322_organs_propagation t323_organs_outside_api)

case "${1:-}" in
pack)
  jobs="$(nproc 2>/dev/null || echo 2)"
  prep_fascia="${FASCIA_BUILD_DIR:-$root/build}/tools/fascia"
  [ -x "$prep_fascia" ] || { echo "gpu-check: build first (tools/setup/build.sh): $prep_fascia is missing" >&2; exit 1; }
  mkdir -p "$root/build-gpu"
  cmake -S "$root" -B "$root/build-gpu" -DCMAKE_BUILD_TYPE=Release -DFASCIA_CUDA=ON -DFASCIA_PREP=OFF \
    -DFASCIA_TESTS=ON >"$root/build-gpu/configure.log" 2>&1 || { cat "$root/build-gpu/configure.log" >&2; exit 1; }
  cmake --build "$root/build-gpu" -j "$jobs" --target fascia t330_device_against_cpu t331_device_tissue \
    "${solver_tests[@]}"
  rm -rf "$pack"
  mkdir -p "$pack/bin" "$pack/lib"
  cp "$root/build-gpu/tools/fascia" "$root/build-gpu/tests/t330_device_against_cpu" \
    "$root/build-gpu/tests/t331_device_tissue" "$pack/bin/"
  for t in "${solver_tests[@]}"; do cp "$root/build-gpu/tests/$t" "$pack/bin/"; done
  # every shared library but the C library's own (the GPU machine has those)
  for program in "$pack"/bin/*; do
    ldd "$program" | awk '$3 ~ /^\// {print $3}'
  done | sort -u | grep -vE '/(libc|libm|libdl|librt|libpthread|libresolv|libnsl|libutil|libanl|ld-linux[^/]*)\.so' | while read -r lib; do
    cp -L "$lib" "$pack/lib/"
  done
  "$prep_fascia" prep "$root/data/scenes/pelvis-female-demo.json" -o "$pack/demo.h5" >/dev/null
  tar -C "$root/build-gpu" -cf - pack | xz -6 -T0 >"$archive.tmp"
  mv "$archive.tmp" "$archive"
  size=$(stat -c %s "$archive")
  echo "gpu-check: packed $(du -sh "$pack" | cut -f1) into $pack, $((size / 1048576)) MiB compressed in $archive"
  [ "$size" -lt "$carry_limit" ] ||
    { echo "gpu-check: $archive is over the device tool's 64 MiB carry limit" >&2; exit 1; }
  ;;
run)
  out="${2:-${OUT:-$root/out/gpu-check}}"
  mkdir -p "$out"
  if [ ! -x "$pack/bin/fascia" ] && [ -f "$archive" ]; then xz -dc "$archive" | tar -C "$root/build-gpu" -xf -; fi
  [ -x "$pack/bin/fascia" ] ||
    { echo "gpu-check: $archive is missing: run 'tools/gpu-check.sh pack' first and carry it" >&2; exit 1; }
  export LD_LIBRARY_PATH="$pack/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  status=0
  { nvidia-smi -L || true; date -u +%Y-%m-%dT%H:%MZ; "$pack/bin/fascia" info; } 2>&1 | tee "$out/device.txt"
  echo "== t330: device against CPU (cantilever, random models, edge cases)"
  "$pack/bin/t330_device_against_cpu" --backend cuda 2>&1 | tee "$out/tests.log" || status=1
  echo "== t331: device against CPU on the demo tissue"
  "$pack/bin/t331_device_tissue" --backend cuda "$pack/demo.h5" 2>&1 | tee -a "$out/tests.log" || status=1
  echo "== the solver, stability and organ suites on the GPU (t301-t307, t310-t316, t320-t323)"
  for t in "${solver_tests[@]}"; do
    echo "-- $t" | tee -a "$out/tests.log"
    rc=0
    "$pack/bin/$t" --backend cuda 2>&1 | tee -a "$out/tests.log" || rc=$?
    [ "$rc" = 0 ] || [ "$rc" = 77 ] || status=1 # 77: skipped on a device, with a line that says why
  done
  echo "== the paper's Table 2 and 3 rows on the GPU and the CPU"
  "$pack/bin/fascia" bench paper --backend cuda --csv "$out/bench-paper.csv" 2>&1 | tee "$out/bench-paper.txt" || status=1
  echo "== larger rows on the GPU"
  "$pack/bin/fascia" bench large --backend cuda --no-cpu --csv "$out/bench-large.csv" 2>&1 |
    tee "$out/bench-large.txt" || status=1
  if command -v ncu >/dev/null 2>&1; then
    # where the time of a step goes, kernel by kernel (graph nodes profiled
    # one by one): duration, occupancy, registers; a profile, not a timing
    echo "== ncu: kernels of one paper-mode step of the 34610-sample row"
    ncu --graph-profiling node --launch-count 600 --print-summary per-kernel \
      --metrics gpu__time_duration.sum,sm__warps_active.avg.pct_of_peak_sustained_active,launch__registers_per_thread \
      "$pack/bin/fascia" bench t3-s34610 --backend cuda --no-cpu --repeats 1 --steps 1 >"$out/ncu.txt" 2>&1 ||
      echo "gpu-check: ncu failed (not counted; see ncu.txt)"
    grep -E "k_item|k_reduce|gpu__time_duration" "$out/ncu.txt" | head -60 || true
  fi
  if command -v compute-sanitizer >/dev/null 2>&1; then
    echo "== compute-sanitizer memcheck of t330 (out-of-bounds and uninitialized device memory)"
    compute-sanitizer --tool memcheck --leak-check full "$pack/bin/t330_device_against_cpu" --backend cuda \
      >"$out/memcheck.log" 2>&1 || status=1
    tail -3 "$out/memcheck.log"
  fi
  exit $status
  ;;
*)
  echo "usage: tools/gpu-check.sh pack | run [DIR]" >&2
  exit 2
  ;;
esac
