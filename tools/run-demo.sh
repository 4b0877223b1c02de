#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The README's first command: installs missing Debian packages, builds, then
# prepares the shipped female pelvis scene (uterus, urinary bladder and the
# vesicouterine connective tissue, data/scenes/pelvis-female-demo.json: the
# bladder fixed, the uterus pulled by a prescribed traction), simulates 1.5 s
# with progress, and writes results and pictures into out/demo/ with a
# closing summary.
#   --scene abdomen-female   the five-organ upper abdomen instead
#                            (data/scenes/abdomen-female.json), into out/abdomen-female/
#   --scene abdomen-totalsegmentator   the upper abdomen straight from a CT
#                            segmentation label map, into out/abdomen-totalsegmentator/
#   --scene abdomen-ligaments  a ligament (strand) and a membrane (sheet)
#                            between HRA organs, into out/abdomen-ligaments/
#   --scene pelvis-female-shells  the paper's Figure 7: uterus and bladder as
#                            shells, the top of the uterus fixed, into out/pelvis-female-shells/
# Other arguments go to cmake's configure step.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
name=pelvis-female-demo
if [[ "${1:-}" == "--scene" ]]; then
  name="${2:?--scene needs a name: pelvis-female-demo, abdomen-female, abdomen-totalsegmentator, abdomen-ligaments or pelvis-female-shells}"
  shift 2
fi
case "$name" in
pelvis-female-demo)
  out="$root/out/demo" view=sagittal
  what="female pelvis, bladder fixed, uterus under traction"
  motion="bladder fixed, uterus pulled 3 mm up and back, tilted 4 deg" ;;
abdomen-female)
  out="$root/out/abdomen-female" view=coronal
  what="female upper abdomen, liver and kidney fixed, spleen rigid, gallbladder deformable, colon pulled"
  motion="liver and left kidney fixed, spleen rigid, gallbladder deformable, colon pulled 3 mm down and 2 mm forward" ;;
abdomen-totalsegmentator)
  out="$root/out/abdomen-totalsegmentator" view=coronal-ras
  what="upper abdomen from a CT label map, vertebrae and five organs fixed, duodenum and gallbladder rigid, stomach retracted"
  motion="stomach retracted 3 mm anteriorly, duodenum and gallbladder rigid, the rest fixed" ;;
abdomen-ligaments)
  out="$root/out/abdomen-ligaments" view=coronal
  what="splenorenal ligament (a strand) and hepatocolic membrane (a sheet) between HRA organs"
  motion="liver and kidney fixed, spleen drawn along its ligament, colon pulled 3 mm down and 2 mm forward" ;;
pelvis-female-shells)
  out="$root/out/pelvis-female-shells" view=sagittal
  what="female pelvis (the paper's Figure 7), uterus and bladder as shells, the top of the uterus fixed"
  motion="top of the uterus fixed, uterus, bladder and tissue hanging under gravity" ;;
*)
  echo "run-demo.sh: unknown scene '$name' (known: pelvis-female-demo, abdomen-female, abdomen-totalsegmentator, abdomen-ligaments, pelvis-female-shells)" >&2
  exit 2 ;;
esac
"$root/tools/setup/debian-packages.sh"
"$root/tools/setup/build.sh" "$@"
fascia="${FASCIA_BUILD_DIR:-$root/build}/tools/fascia"
scene="$root/data/scenes/$name.json"
steps=30 dt=0.05 save_every=3
rm -rf "$out"
mkdir -p "$out"
export FASCIA_PROGRESS="${FASCIA_PROGRESS:-1}" # progress lines with the time left, also when piped

t0=$(date +%s.%N)
echo "demo: 1/3 preparing $(basename "$scene") (organs -> tissue model)"
"$fascia" prep "$scene" -o "$out/$name.h5" >"$out/prep.txt"
"$fascia" inspect "$out/$name.h5" >"$out/model.txt"
echo "demo: 2/3 simulating $steps implicit steps of $dt s ($motion)"
"$fascia" run "$out/$name.h5" --steps "$steps" --dt "$dt" --save-every "$save_every" --samples \
  -o "$out/results.h5" --history "$out/history.csv" --paraview "$out/paraview" --snapshots "$out/data" \
  | tee "$out/run.txt"
t1=$(date +%s.%N)
echo "demo: 3/3 drawing pictures"
organs=$(awk '/^organs/{on=1; next} on && /^  [^ ]/{print $1} on && !/^  /{on=0}' "$out/model.txt" | tr '\n' ' ')
gnuplot -e "dir='$out'; title='$name'; organs='${organs% }'; view='$view'" "$root/tools/plots/demo.gp"
# the scene pictures rendered by ParaView where it is installed (the tissue
# surface coloured by strain, organs translucent); else gnuplot's stay
pictures="gnuplot (ParaView's pvbatch or xvfb-run not found: the scene pictures are gnuplot's point plots)"
if command -v pvbatch >/dev/null && command -v xvfb-run >/dev/null; then
  pictures="gnuplot (ParaView failed, see $out/paraview.log: the scene pictures are gnuplot's point plots)"
  # a second try: on a loaded machine the X server may not be up in time
  for try in 1 2; do
    if xvfb-run -a -s "-screen 0 1280x1024x24" pvbatch "$root/tools/plots/demo_paraview.py" \
        "$out/paraview/run.pvd" "$out" "$name" "$view" >"$out/paraview.log" 2>&1; then
      pictures="ParaView (scene) and gnuplot (energy, iterations, time)"
      break
    fi
  done
fi
echo "demo: pictures by $pictures"

# closing summary
field() { sed -n "s/^$1 *//p" "$out/run.txt" | head -1; }
frames=$(sed -n 's/^frames *\([0-9]*\).*/\1/p' "$out/model.txt")
samples=$(sed -n 's/^samples *\([0-9]*\).*/\1/p' "$out/model.txt")
ms=$(field time | sed 's/ ms per step.*//')
strain=$(field strain | sed 's/^largest \([^ ]*\).*/\1/')
stress=$(field strain | sed 's/.*largest stress \([^ ]*\) Pa.*/\1/')
seconds=$(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b - a}')
cat <<EOF

demo summary: $what
  model        $frames frames ($(sed -n 's/^frames *[0-9]* (\(.*\))/\1/p' "$out/model.txt")), $samples samples
  simulation   $steps steps of $dt s, $ms ms per step, backend $(field backend), linear solver $(field linear)
  tissue       largest strain $strain (Green-Lagrange norm, over the samples at the end: the colour bars' top), largest stress $stress Pa
  wall time    ${seconds} s to prepare and simulate
  files        $out/
    results.h5 + results.xdmf   tissue frames and samples with displacement, strain and stress per saved step (ParaView)
    paraview/run.pvd            open in ParaView: tissue surface, samples, frames, organs per saved step
    scene-rest.png, scene-deformed.png   tissue coloured by strain between the named organs, the rest shape in grey ($pictures)
    energy.png, iterations.png, ms-per-step.png   the run over time
    history.csv, data/*.csv     the numbers behind the pictures
EOF
