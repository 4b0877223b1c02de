#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# A hollow organ as a shell against the same organ as a volume, side by side:
# what each costs for a given accuracy of the force its tissues pass on.
# Organ B is a hollow sphere, its wall 3 mm thick between radii 27 and 30 mm
# (E 30 kPa, nu 0.45), between box A (fixed) and box C (prescribed: drawn
# 3 mm away along x in 1 s); a tissue layer 3 mm thick (E 5 kPa, nu 0.4)
# joins each box to B, no gravity.
#   shell:  "model": "shell", thickness 3 mm on the wall's mid-surface
#           (radius 28.5 mm, the boxes 3 mm from it), at each frame spacing;
#   volume: "model": "deformable" on one closed surface of two spheres, the
#           inner one reversed (prep fills the wall between them), at each
#           frame / sample spacing.
# The tissues keep their sampling (frames 2.5 mm, samples 1.25 mm), voxels
# 0.5 mm in both. Per row: B's frames (its own + those it shares with the
# tissues), the model's frames, samples and pairs; the static solve at
# t = 1 s (wall ms on 2 threads, Newton iterations) and the tissue's force
# on A and on C (the reaction on their coupling frames, `fascia run --json`
# organ_force, x); its error against the finest row of the same kind and
# against the finest row of the other kind; 10 steps of 0.01 s and 10 of
# 0.05 s (wall ms per step on 2 threads, Newton iterations per step, steps
# converged).
# usage: tools/bench/shell-vs-volume.sh [BUILD_DIR] [OUT.txt]
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$here/build}
out=${2:-$here/tools/bench/results/2core-debian_cpu/shell_vs_volume.txt}
fascia=$build/tools/fascia
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
shell_spacings=${SHELL_SPACINGS:-"0.012 0.010 0.008 0.006 0.005 0.004 0.0032"}
# frame_spacing:sample_spacing
volume_spacings=${VOLUME_SPACINGS:-"0.012:0.0015 0.010:0.0015 0.008:0.0015 0.006:0.0015 0.005:0.00125 0.004:0.001 0.003:0.00075 0.0025:0.00075"}
threads=2
# the meshes, in metres: icospheres (5 subdivisions, 20480 triangles each),
# the hollow one with its inner sphere reversed, and two boxes for each kind
python3 - "$work" <<'EOF'
import math, sys
d = sys.argv[1]
R, wall, gap, box = 0.030, 0.003, 0.003, 0.012
S = 0.00013 # everything shifted off the 0.5 mm voxel centres: a box face on them loses most of its coupling
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
n = len(v)
with open(d + "/hollow.obj", "w") as o: # outer sphere outward, inner sphere inward
    o.writelines("v %.9f %.9f %.9f\n" % tuple(S + R * x for x in p) for p in v)
    o.writelines("v %.9f %.9f %.9f\n" % tuple(S + (R - wall) * x for x in p) for p in v)
    o.writelines("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in f)
    o.writelines("f %d %d %d\n" % (n + a + 1, n + c + 1, n + b + 1) for a, b, c in f)
with open(d + "/mid.obj", "w") as o: # the wall's mid-surface
    o.writelines("v %.9f %.9f %.9f\n" % tuple(S + (R - wall / 2) * x for x in p) for p in v)
    o.writelines("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in f)
def cube(name, lo, hi):
    c = [(x, y, z) for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])]
    q = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    with open(d + "/" + name, "w") as o:
        o.writelines("v %.9f %.9f %.9f\n" % tuple(S + x for x in p) for p in c)
        for a, b, e, h in q:
            o.write("f %d %d %d\nf %d %d %d\n" % (a + 1, b + 1, e + 1, a + 1, e + 1, h + 1))
h = 0.6 * R
for kind, face in (("volume", R + gap), ("shell", R - wall / 2 + gap)):
    cube("a_%s.obj" % kind, (-face - box, -h, -h), (-face, h, h))
    cube("c_%s.obj" % kind, (face, -h, -h), (face + box, h, h))
EOF
scene() { # kind frame_spacing sample_spacing [rigid] -> scene.json
  local organ
  if [ "${4:-}" = rigid ]; then
    organ="\"mesh\": \"$([ "$1" = shell ] && echo mid || echo hollow).obj\", \"model\": \"rigid\""
  elif [ "$1" = shell ]; then
    organ="\"mesh\": \"mid.obj\", \"model\": \"shell\", \"material\": \"wall\", \"thickness\": 0.003, \"frame_spacing\": $2"
  else
    organ="\"mesh\": \"hollow.obj\", \"model\": \"deformable\", \"material\": \"wall\", \"frame_spacing\": $2, \"sample_spacing\": $3"
  fi
  cat > "$work/scene.json" <<EOF
{"fascia_scene": 1, "name": "hollow organ, $1", "voxel_size": 0.0005, "seed": 1, "gravity": [0, 0, 0],
 "materials": {"tissue": {"law": "neohookean", "youngs_modulus": 5000, "poisson_ratio": 0.4, "density": 1050},
               "wall": {"law": "neohookean", "youngs_modulus": 30000, "poisson_ratio": 0.45, "density": 1050}},
 "organs": [{"name": "A", "mesh": "a_$1.obj", "model": "fixed"},
            {"name": "B", $organ},
            {"name": "C", "mesh": "c_$1.obj", "model": "prescribed",
             "motion": {"pivot": [0, 0, 0], "keys": [{"time": 0}, {"time": 1, "translation": [0.003, 0, 0]}]}}],
 "tissues": [{"name": "left", "connects": ["A", "B"], "max_gap": 0.009, "material": "tissue",
              "frame_spacing": 0.0025, "sample_spacing": 0.00125},
             {"name": "right", "connects": ["B", "C"], "max_gap": 0.009, "material": "tissue",
              "frame_spacing": 0.0025, "sample_spacing": 0.00125}]}
EOF
}
static_force_c() { # the force on C of the static solve of model.h5
  "$fascia" run "$work/model.h5" --static --threads "$threads" --json |
    python3 -c 'import json, sys; d = json.loads(sys.stdin.read().splitlines()[-1]); print("%.6g" % d["organ_force"]["C"]["end"][0])'
}
rigid=""
: > "$work/rigid.txt"
for kind in shell volume; do # the bound: B rigid, the tissues alone in series
  scene "$kind" 0 0 rigid
  "$fascia" prep "$work/scene.json" -o "$work/model.h5" > /dev/null 2> "$work/prep.txt"
  f=$(static_force_c)
  echo "$kind $f" >> "$work/rigid.txt"
  rigid="$rigid $kind $f N"
done
rows=$work/rows.txt
: > "$rows"
for kind in shell volume; do
  spacings=$shell_spacings
  [ "$kind" = volume ] && spacings=$volume_spacings
  for s in $spacings; do
    frame=${s%%:*}
    sample=${s#*:}
    scene "$kind" "$frame" "$sample"
    if ! "$fascia" prep "$work/scene.json" -o "$work/model.h5" > /dev/null 2> "$work/prep.txt"; then
      echo "$kind $s prep failed: $(tail -n 1 "$work/prep.txt")" >&2
      continue
    fi
    "$fascia" inspect "$work/model.h5" --json > "$work/inspect.json"
    python3 - "$kind" "$s" "$work" "$fascia" "$threads" >> "$rows" <<'PY'
import json, re, subprocess, sys
kind, spacing, work, fascia, threads = sys.argv[1:6]
def run(*args): # the last JSON line of one fascia run
    r = subprocess.run([fascia, "run", work + "/model.h5", "--threads", threads, "--json", *args],
                       capture_output=True, text=True)
    lines = [l for l in r.stdout.splitlines() if l.strip()]
    return json.loads(lines[-1]) if lines else {}
info = json.loads([l for l in open(work + "/inspect.json").read().splitlines() if l.strip()][-1])
static = run("--static")
fine = [run("--steps", "10", "--dt", "0.01") for _ in range(2)]
coarse = [run("--steps", "10", "--dt", "0.05") for _ in range(2)]
def best(runs): # the faster of two runs (the machine is shared)
    ok = [r for r in runs if "ms_per_step" in r]
    return min(ok, key=lambda r: r["ms_per_step"]) if ok else {}
fine, coarse = best(fine), best(coarse)
own = re.search(r"organ 'B':.*?(\d+) frames of its own and (\d+) shared", open(work + "/prep.txt").read())
if not own: # a shell's line
    own = re.search(r"shell organ 'B':.*?(\d+) frames.*?(\d+) shared", open(work + "/prep.txt").read())
force = lambda o: static["organ_force"][o]["end"][0] if static.get("converged") else float("nan")
def steps(r):
    n = r.get("steps", 0) or 1
    return "%.1f %.1f %s/%s" % (r.get("ms_per_step", float("nan")), r.get("newton_iterations", 0) / n,
                                r.get("converged_steps", 0), r.get("steps", 0))
print(kind, spacing, "%s+%s" % own.groups() if own else "?", info.get("frames"), info.get("samples"),
      info.get("pairs"), "%.0f" % static.get("ms_per_step", float("nan")), static.get("newton_iterations"),
      "%.6g" % force("A"), "%.6g" % force("C"), steps(fine), steps(coarse))
PY
  done
done
{
  echo "# $(date -u +%Y-%m-%d) $(uname -m), $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg)" \
    "($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'))"
  python3 - "$rows" "$work/rigid.txt" <<'PY'
import math, sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
rigid = {l.split()[0]: abs(float(l.split()[1])) for l in open(sys.argv[2]) if l.strip()}
def compliance(kind, f): # B's own, mm/N: the pull (3 mm) over the force, less the tissues' (B rigid)
    return 3 / abs(f) - 3 / rigid[kind] if f and not math.isnan(f) else float("nan")
ref = {}
for r in rows: # the last (finest) converged row of each kind
    if r[9] != "nan": ref[r[0]] = float(r[9])
other = {"shell": "volume", "volume": "shell"}
print("%-6s %13s %9s %6s %7s %7s %9s %6s %10s %10s %7s %7s %7s %7s %9s %6s %6s %9s %6s %6s" % (
    "kind", "spacing", "B_own+sh", "frames", "samples", "pairs", "static_ms", "newton", "force_A_N", "force_C_N",
    "err_%", "vs_oth%", "B_mm/N", "B_oth%", "ms/0.01s", "newt", "conv", "ms/0.05s", "newt", "conv"))
for r in rows:
    c = float(r[9])
    e = 100 * (c - ref[r[0]]) / ref[r[0]] if r[0] in ref and not math.isnan(c) else float("nan")
    o = other[r[0]]
    x = 100 * (c - ref[o]) / ref[o] if o in ref and not math.isnan(c) else float("nan")
    b = compliance(r[0], c)
    bo = compliance(o, ref[o]) if o in ref else float("nan")
    print("%-6s %13s %9s %6s %7s %7s %9s %6s %10s %10s %7.2f %7.2f %7.3f %7.2f %9s %6s %6s %9s %6s %6s" % (
        r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9], e, x, b, 100 * (b - bo) / bo, *r[10:16]))
PY
  echo "# B rigid instead, force on C:$rigid (the tissues alone; the shell's sphere is 1.5 mm smaller)"
  echo "# spacing: B's frame spacing (volume: frame:sample spacing); static_ms, ms/0.01s, ms/0.05s: wall ms on 2 threads"
  echo "# (the steps: the faster of two runs of 10 steps from rest); err_%: force on C against the finest row of the"
  echo "# same kind; vs_oth%: against the finest row of the other kind; B_mm/N: B's own compliance, 3 mm / force less"
  echo "# 3 mm / the force with B rigid; B_oth%: against the other kind's finest; newt: Newton iterations per step"
} > "$work/out.txt"
cat "$work/out.txt"
cp "$work/out.txt" "$out.tmp"
mv "$out.tmp" "$out"
