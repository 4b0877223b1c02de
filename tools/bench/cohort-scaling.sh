#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Does the cohort workflow use the cores? N cases (default 20) made from the
# shipped TotalSegmentator label map, each with one label the scene does not
# model removed (a rib, a lung lobe, ...; case 0 the map itself), run by
# tools/cohort/Snakefile with --cores C (default 2) and one thread per job.
# Prints the workflow's wall time, the sum of the cases' own times (estimate,
# prep and run, as each step's record measured them) and their ratio: 1/C
# is perfect packing, 1 no parallelism (issue 46 asks at most 0.6 on 2 cores).
# Writes the per-case table and the totals to OUT (default
# tools/bench/results/2core-debian_cpu/cohort_scaling.csv); the load average
# before and after goes into the totals, as other work on the machine slows
# the cases.
#   tools/bench/cohort-scaling.sh [--cases N] [--cores C] [--out FILE.csv]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
cases=20 cores=2 out="$root/tools/bench/results/2core-debian_cpu/cohort_scaling.csv"
while [ $# -gt 0 ]; do
  case "$1" in
  --cases) cases="$2"; shift 2 ;;
  --cores) cores="$2"; shift 2 ;;
  --out) out="$2"; shift 2 ;;
  *) echo "cohort-scaling.sh: unknown option '$1' (known: --cases N, --cores C, --out FILE.csv)" >&2; exit 2 ;;
  esac
done
work="$(mktemp -d /tmp/fascia-cohort-bench-XXXXXX)"
trap 'rm -rf "$work"' EXIT
mkdir "$work/cases"
/usr/bin/python3 - "$root/data/labelmaps/totalsegmentator/example_seg.nii.gz" "$work/cases" "$cases" <<'EOF'
import gzip, struct, sys
source, folder, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
raw = gzip.decompress(open(source, "rb").read())
offset = int(struct.unpack_from("<f", raw, 108)[0])
# labels the cohort scene does not model: ribs, lung lobes, muscles, vessels
unmodelled = [98, 99, 100, 101, 102, 103, 110, 111, 112, 113, 114, 115, 117, 10, 11, 13, 14, 86, 87, 88, 89, 52, 63]
for k in range(count):
    drop = unmodelled[(k - 1) % len(unmodelled)] if k else None
    table = bytes(0 if v == drop else v for v in range(256))
    open(f"{folder}/case{k:03d}.nii.gz", "wb").write(gzip.compress(raw[:offset] + raw[offset:].translate(table)))
EOF
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
start=$(date +%s.%N)
(cd "$work" && snakemake -s "$root/tools/cohort/Snakefile" --cores "$cores" --quiet \
  --config cases="$work/cases" scene="$root/tools/cohort/abdomen-totalsegmentator-cohort.json" out="$work/out" \
  > "$work/snakemake.log" 2>&1) || { tail -20 "$work/snakemake.log" >&2; exit 1; }
end=$(date +%s.%N)
load_after=$(cut -d' ' -f1-3 /proc/loadavg)
/usr/bin/python3 - "$work/out" "$start" "$end" "$cores" "$load_before" "$load_after" "$out" <<'EOF'
import csv, json, os, sys
folder, start, end, cores, before, after, out = sys.argv[1:8]
wall = float(end) - float(start)
rows, total = [], 0.0
for case in sorted(os.listdir(folder)):
    if not os.path.isdir(os.path.join(folder, case)):
        continue
    seconds = {}
    for step in ("estimate", "prep", "run"):
        with open(os.path.join(folder, case, f"{step}.json")) as f:
            seconds[step] = json.load(f).get("wall_seconds", 0.0)
    with open(os.path.join(folder, case, "prep.json")) as f:
        status = "ok" if json.load(f).get("exit_status") == 0 else "prep failed"
    rows.append([case, status, *(f"{seconds[s]:.3f}" for s in ("estimate", "prep", "run")),
                 f"{sum(seconds.values()):.3f}"])
    total += sum(seconds.values())
tmp = f"{out}.tmp-{os.getpid()}"
with open(tmp, "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["case", "status", "estimate_s", "prep_s", "run_s", "case_s"])
    w.writerows(rows)
    w.writerow([])
    w.writerow(["cases", "cores", "wall_s", "sum_case_s", "wall_over_sum", "load_before", "load_after"])
    w.writerow([len(rows), cores, f"{wall:.2f}", f"{total:.2f}", f"{wall / total:.3f}", before, after])
os.replace(tmp, out)
print(f"cohort-scaling: {len(rows)} cases on {cores} cores: wall {wall:.1f} s, sum of case times {total:.1f} s, "
      f"ratio {wall / total:.3f} (load {before} before, {after} after); {out}")
EOF
