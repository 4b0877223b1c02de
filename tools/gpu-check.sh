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
# carry=["build-gpu/pack.tar.xz"]); it writes 7 files (that tool brings back
# 8 at most): summary.txt, tests.log, bench.txt, bench-paper.csv,
# bench-large.csv, ncu.txt, memcheck.log.
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
  bin="$pack/bin"
  summary="$out/summary.txt"
  status=0
  # Each stage runs under its own time limit, and all of them under
  # GPU_CHECK_SECONDS (default 360), so that one that hangs costs its limit
  # and not the whole lease; summary.txt gets one line per stage.
  # Usage: stage NAME SECONDS LOG COMMAND...; 77 counts as skipped.
  deadline=$((SECONDS + ${GPU_CHECK_SECONDS:-360}))
  stage() {
    local name="$1" limit="$2" log="$3" started=$SECONDS rc=0
    shift 3
    if [ $((deadline - SECONDS)) -lt "$limit" ]; then limit=$((deadline - SECONDS)); fi
    if [ "$limit" -le 0 ]; then
      printf '%-44s %-26s\n' "$name" "not run: GPU_CHECK_SECONDS spent" | tee -a "$summary"
      status=1
      return
    fi
    echo "== $name (at most ${limit} s)" | tee -a "$log"
    timeout -k 5 "$limit" "$@" >>"$log" 2>&1 || rc=$?
    local verdict=passed
    case "$rc" in
    0) ;;
    77) verdict=skipped ;;
    124 | 137) verdict="timed out after ${limit} s"; status=1 ;;
    *) verdict="failed (exit $rc)"; status=1 ;;
    esac
    printf '%-44s %-26s %4d s\n' "$name" "$verdict" $((SECONDS - started)) | tee -a "$summary"
  }
  {
    date -u +%Y-%m-%dT%H:%MZ
    nvidia-smi -L || true
    nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm,power.limit --format=csv || true
    "$bin/fascia" info
    echo "host: $(nproc) CPUs, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-)"
  } >"$summary" 2>&1
  cat "$summary"
  tests="$out/tests.log"
  stage "t330 device against CPU" 90 "$tests" "$bin/t330_device_against_cpu" --backend cuda
  stage "t331 device against CPU, demo tissue" 60 "$tests" "$bin/t331_device_tissue" --backend cuda "$pack/demo.h5"
  for t in "${solver_tests[@]}"; do stage "$t" 30 "$tests" "$bin/$t" --backend cuda; done
  bench="$out/bench.txt"
  stage "bench paper, GPU and CPU" 150 "$bench" \
    "$bin/fascia" bench paper --backend cuda --csv "$out/bench-paper.csv"
  stage "bench large, GPU" 150 "$bench" "$bin/fascia" bench large --backend cuda --no-cpu --csv "$out/bench-large.csv"
  if command -v ncu >/dev/null 2>&1; then
    # where the time of a step goes, kernel by kernel (graph nodes profiled
    # one by one): duration, occupancy, registers, bandwidth; a profile, not a
    # timing. The clocks are left as they are.
    stage "ncu kernels of t3-s34610 (a profile)" 120 "$out/ncu.txt" \
      ncu --clock-control none --graph-profiling node --launch-count 400 --print-summary per-kernel \
      --metrics gpu__time_duration.sum,sm__warps_active.avg.pct_of_peak_sustained_active,launch__registers_per_thread,dram__throughput.avg.pct_of_peak_sustained_elapsed \
      "$bin/fascia" bench t3-s34610 --backend cuda --no-cpu --repeats 1 --steps 1
  fi
  if command -v compute-sanitizer >/dev/null 2>&1; then
    # out-of-bounds and uninitialized device memory, and leaks
    stage "compute-sanitizer memcheck of t330" 150 "$out/memcheck.log" \
      compute-sanitizer --tool memcheck --leak-check full --error-exitcode 3 "$bin/t330_device_against_cpu" --backend cuda
  fi
  echo "== summary"
  cat "$summary"
  grep -E "^(table|[023] )" "$bench" | head -40 || true
  exit $status
  ;;
*)
  echo "usage: tools/gpu-check.sh pack | run [DIR]" >&2
  exit 2
  ;;
esac
