#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# A hollow organ as a shell against the same organ as a volume (a
# frame-based deformable organ), side by side: what each costs for a given
# accuracy of the force its tissues pass on. A sphere B (radius 15 mm) lies
# between box A (fixed) and box C (prescribed: drawn 3 mm away along x in
# 1 s); tissue fills each 3 mm gap (E 5 kPa), B's material has E 30 kPa, no
# gravity. B is a shell (wall 2 mm) or deformable (its whole volume), at
# each frame spacing; the tissues keep theirs (2.5 mm). Per row: B's frames
# (its own + those it shares with the tissues), the model's frames, samples
# and pairs, the static solve at t = 1 s (CPU ms on one thread, Newton
# iterations), a step of 0.01 s (CPU ms), and the tissue's force on C
# against the finest row of the same kind: the two kinds are different
# organs, a wall and a solid, so each is measured against its own converged
# force. The force is the reaction on C's coupling frames (`fascia run
# --json` organ_force).
# usage: tools/bench/shell-vs-volume.sh [BUILD_DIR] [OUT.txt]
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$here/build}
out=${2:-$here/tools/bench/results/2core-debian_cpu/shell_vs_volume.txt}
fascia=$build/tools/fascia
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
shell_spacings="0.008 0.006 0.005 0.004 0.003"
volume_spacings="0.008 0.006 0.005 0.004 0.003"
# the meshes: an icosphere (5 subdivisions) and two boxes, in metres
python3 - "$work" <<'EOF'
import math, sys
d = sys.argv[1]
R, gap, box = 0.015, 0.003, 0.012
t = (1 + 5 ** 0.5) / 2
v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
     (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
     (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
     (8, 6, 7), (9, 8, 1)]
v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
for _ in range(5):
    mid, g = {}, []
    def m(a, b):
        k = (min(a, b), max(a, b))
        if k not in mid:
            p = [(v[a][i] + v[b][i]) / 2 for i in range(3)]
            n = math.sqrt(sum(x * x for x in p))
            v.append(tuple(x / n for x in p))
            mid[k] = len(v) - 1
        return mid[k]
    for a, b, c in f:
        ab, bc, ca = m(a, b), m(b, c), m(c, a)
        g += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    f = g
with open(d + "/b.obj", "w") as o:
    o.writelines("v %.9f %.9f %.9f\n" % tuple(R * x for x in p) for p in v)
    o.writelines("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in f)
def cube(name, lo, hi):
    c = [(x, y, z) for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])]
    q = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    with open(d + "/" + name, "w") as o:
        o.writelines("v %.9f %.9f %.9f\n" % p for p in c)
        for a, b, e, h in q:
            o.write("f %d %d %d\nf %d %d %d\n" % (a + 1, b + 1, e + 1, a + 1, e + 1, h + 1))
h = 0.6 * R
cube("a.obj", (-R - gap - box, -h, -h), (-R - gap, h, h))
cube("c.obj", (R + gap, -h, -h), (R + gap + box, h, h))
EOF
scene() { # kind spacing -> scene.json
  local organ
  if [ "$1" = shell ]; then
    organ="\"model\": \"shell\", \"material\": \"wall\", \"thickness\": 0.002, \"frame_spacing\": $2"
  else
    organ="\"model\": \"deformable\", \"material\": \"wall\", \"frame_spacing\": $2, \"sample_spacing\": $(awk -v s="$2" 'BEGIN { print s / 2 }')"
  fi
  cat > "$work/scene.json" <<EOF
{"fascia_scene": 1, "name": "shell or volume", "voxel_size": 0.001, "seed": 1, "gravity": [0, 0, 0],
 "materials": {"tissue": {"law": "neohookean", "youngs_modulus": 5000, "poisson_ratio": 0.4, "density": 1050},
               "wall": {"law": "neohookean", "youngs_modulus": 30000, "poisson_ratio": 0.45, "density": 1050}},
 "organs": [{"name": "A", "mesh": "a.obj", "model": "fixed"},
            {"name": "B", "mesh": "b.obj", $organ},
            {"name": "C", "mesh": "c.obj", "model": "prescribed",
             "motion": {"pivot": [0, 0, 0], "keys": [{"time": 0}, {"time": 1, "translation": [0.003, 0, 0]}]}}],
 "tissues": [{"name": "left", "connects": ["A", "B"], "max_gap": 0.009, "material": "tissue",
              "frame_spacing": 0.0025, "sample_spacing": 0.00125},
             {"name": "right", "connects": ["B", "C"], "max_gap": 0.009, "material": "tissue",
              "frame_spacing": 0.0025, "sample_spacing": 0.00125}]}
EOF
}
field() { sed -n "s/.*\"$1\":\([^,}]*\).*/\1/p"; }
rows=$work/rows.txt
: > "$rows"
for kind in shell volume; do
  spacings=$shell_spacings
  [ "$kind" = volume ] && spacings=$volume_spacings
  for s in $spacings; do
    scene "$kind" "$s"
    if ! "$fascia" prep "$work/scene.json" -o "$work/model.h5" --json > "$work/prep.json" 2> "$work/prep.txt"; then
      echo "$kind $s prep failed: $(tail -n 1 "$work/prep.txt")" >&2
      continue
    fi
    "$fascia" inspect "$work/model.h5" --json > "$work/inspect.json"
    python3 - "$kind" "$s" "$work" "$fascia" >> "$rows" <<'PY'
import json, re, resource, subprocess, sys
kind, spacing, work, fascia = sys.argv[1:5]
def cpu(name, *args): # CPU seconds of one fascia run, its JSON to name
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    with open(work + "/" + name, "w") as out:
        subprocess.run([fascia, "run", work + "/model.h5", "--threads", "1", "--json", *args], stdout=out,
                       stderr=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
one = min(cpu("one.json", "--steps", "1", "--dt", "0.01") for _ in range(2)) # loading the model and a step
steps_s = (min(cpu("steps.json", "--steps", "11", "--dt", "0.01") for _ in range(2)) - one) / 10
static_s = cpu("static.json", "--static") - (one - steps_s)
def last(name):
    with open(work + "/" + name) as f:
        lines = [l for l in f.read().splitlines() if l.strip()]
    return json.loads(lines[-1]) if lines else {}
info, static, steps = last("inspect.json"), last("static.json"), last("steps.json")
own = re.search(r"organ 'B':.*; (\d+) frames of its own and (\d+) shared", open(work + "/prep.txt").read())
force = static["organ_force"]["C"]["end"][0] if static.get("converged") else float("nan")
print(kind, spacing, "%s+%s" % own.groups() if own else "?", info.get("frames"), info.get("samples"), info.get("pairs"),
      "%.0f" % (1000 * static_s), static.get("newton_iterations"), "%.2f" % (1000 * steps_s),
      "%.1f" % (steps.get("newton_iterations", 0) / 11), steps.get("converged_steps"), "%.6g" % force)
PY
  done
done
{
  echo "# $(date -u +%Y-%m-%d) $(uname -m), $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg)"
  printf "%-6s %8s %9s %7s %8s %7s %13s %7s %12s %12s %5s %11s %9s\n" kind spacing B_own+sh frames samples pairs \
    static_cpu_ms newton step_cpu_ms newton/step conv force_C_N error_%
  awk '{ ref[$1] = $12 } END { for (k in ref) print k, ref[k] }' "$rows" > "$work/ref.txt"
  awk 'NR == FNR { ref[$1] = $2; next }
       { e = (ref[$1] != 0 && $12 != "nan") ? 100 * ($12 - ref[$1]) / ref[$1] : 0
         printf "%-6s %8s %9s %7s %8s %7s %13s %7s %12s %12s %5s %11.5f %9.2f\n", $1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, e }' \
      "$work/ref.txt" "$rows"
  echo "# error: against the last (finest) row of the same kind; CPU time on one thread, model loading excluded;"
  echo "# step_cpu_ms: per step of 0.01 s (11 steps less 1 from rest, the least of two runs each)"
} > "$work/out.txt"
cat "$work/out.txt"
mv "$work/out.txt" "$out"
