# SPDX-License-Identifier: MIT
# Pictures of a `fascia run` without a display (gnuplot, pngcairo):
#   gnuplot -e "dir='out/demo'" tools/plots/demo.gp
#   (optional: title='...', organs='name ...' in the model's order, view='sagittal', 'coronal' or 'coronal-ras')
# Strain is a magnitude (0 up): a sequential colour map (viridis) from 0 to
# the largest sample strain at the end, the summary's "largest strain", its
# value on the bar's top; the deformed picture draws the samples at rest in
# grey behind the deformed ones. Keys sit below the plots (no data under
# them); an axis whose data span more than a decade is logarithmic; a series
# that is all zero (CG iterations with the direct solver) is left out and the
# title says so.
# reads   dir/data/{tissue,organs}-{rest,final}.csv  (fascia run --snapshots dir/data)
#         dir/history.csv                            (fascia run --history dir/history.csv)
# writes  dir/scene-rest.png, dir/scene-deformed.png  tissue samples coloured by strain, organ surface points
#         dir/energy.png (potential linear, kinetic logarithmic), dir/iterations.png, dir/ms-per-step.png
if (!exists("dir")) dir = "out/demo"
if (!exists("title")) title = "fascia"
set datafile separator ","
set terminal pngcairo size 1200,900 enhanced font "DejaVu Sans,14"

# --- the scene, at rest and deformed -------------------------------------
# The HRA meshes have +y superior, +z anterior and +x to the patient's left.
# sagittal (default): anterior to the right, superior up (a view from the
# patient's left); coronal: the patient's right on the left, superior up (a
# view from the front). across: the column (x 1, z 3 of x, y, z) drawn
# across the picture (times sign), depth: the other horizontal one, up: the
# vertical one. Scenes from label maps are in RAS (+x the patient's right,
# +y anterior, +z superior): coronal-ras is their view from the front.
if (!exists("view")) view = "sagittal"
ras = view eq "coronal-ras"
coronal = view eq "coronal" || ras
across = coronal ? 1 : 3
depth = ras ? 2 : (coronal ? 3 : 1)
up = ras ? 3 : 2
sign = ras ? -1 : 1 # the patient's left to the right of the picture
stats dir."/data/tissue-final.csv" using 4 every ::1 nooutput
strain_max = STATS_max > 0 ? STATS_max : 1
stats dir."/data/tissue-rest.csv" using 1 every ::1 nooutput
samples = STATS_records
stats dir."/data/organs-rest.csv" using (sign*column(across + 1)*1000) every ::1 nooutput
h_lo = STATS_min - 5; h_hi = STATS_max + 5
stats dir."/data/organs-rest.csv" using (column(up + 1)*1000) every ::1 nooutput
y_lo = STATS_min - 5; y_hi = STATS_max + 5
if (!exists("organs")) organs = "organ-0 organ-1 organ-2 organ-3 organ-4 organ-5 organ-6 organ-7 organ-8 organ-9"
organ_count = words(organs)
zoom = ras ? 1.5 : (coronal ? 0.95 : 1.35) # the HRA abdomen is tall, the CT's field of view wide: all of it in the picture
set view 90, 0, zoom, zoom
set view equal xyz
set xyplane 0
set xrange [h_lo:h_hi]
set zrange [y_lo:y_hi]
if (coronal) { # the tall abdomen leaves no room for splot's x label: a label of the picture instead
  set label 1 (ras ? "-x, the patient's left (mm)" : "x, the patient's left (mm)") at screen 0.5, 0.03 center
} else {
  set xlabel "z, anterior (mm)" offset 0,-1
}
set zlabel (ras ? "z, superior (mm)" : "y, superior (mm)") rotate parallel offset -2,0
unset ylabel
set ytics format ""
set grid
# viridis (sequential, readable in grey and by the colour-blind)
set palette defined (0 "#440154", 0.125 "#482878", 0.25 "#3e4989", 0.375 "#31688e", 0.5 "#26828e", \
                     0.625 "#1f9e89", 0.75 "#35b779", 0.875 "#6ece58", 1 "#fde725")
set cbrange [0:strain_max]
set cbtics add (sprintf("max %.3g", strain_max) strain_max)
set cblabel "tissue strain: Green-Lagrange |E| (0 to the largest at the end)"
if (coronal) { set key at screen 0.01, 0.92 left top Left reverse width -10 box opaque samplen 1 font ",11" } else { set key top left box opaque }
set colorbox vertical user origin 0.84, 0.2 size 0.03, 0.6
mm = 1000
array organ_colour[10] = ["#c97b9b", "#d9b13b", "#7fa36b", "#8a8ac9", "#b5835a", "#5fa8a8", "#9e9e9e", "#e07b39", \
                          "#6b8fd4", "#a3c94f"]
do for [stage in "rest final"] {
  out = stage eq "rest" ? "scene-rest.png" : "scene-deformed.png"
  set output dir."/".out
  set title sprintf("%s: %s, %s (%d tissue samples)", title, \
                    stage eq "rest" ? "at rest" : "deformed, end of the run", \
                    coronal ? "coronal view from the front" : "sagittal view from the left", samples)
  at_rest = stage eq "rest" # the rest samples behind the deformed ones only
  splot for [k=0:organ_count-1] dir."/data/organs-".stage.".csv" every ::1 \
          using ($1 == k ? sign*column(across + 1)*mm : NaN):(column(depth + 1)*mm):(column(up + 1)*mm) \
          with points pt 7 ps 0.3 lc rgb organ_colour[k % 10 + 1] title word(organs, k+1)." surface" noenhanced, \
        dir."/data/tissue-rest.csv" every ::1 \
          using (at_rest ? NaN : sign*column(across)*mm):(column(depth)*mm):(column(up)*mm) \
          with points pt 7 ps 0.8 lc rgb "#c8c8c8" title (at_rest ? "" : "tissue samples at rest (grey)"), \
        dir."/data/tissue-".stage.".csv" every ::1 using (sign*column(across)*mm):(column(depth)*mm):(column(up)*mm):4 \
          with points pt 7 ps 0.8 palette title "tissue samples (colour: strain)"
}
reset

# --- history: energy, iterations, ms per step ------------------------------
set datafile separator ","
set terminal pngcairo size 1200,800 enhanced font "DejaVu Sans,14"
set grid
set key outside top center horizontal box opaque
set xlabel "time (s)"

set output dir."/energy.png"
set multiplot layout 2,1
set title title.": energy per step"
set ylabel "potential energy (J)"
set format y "%.3g"
unset xlabel
plot dir."/history.csv" every ::1 using 2:3 with linespoints lw 2 pt 7 ps 0.6 lc rgb "#31688e" \
     title "potential (elastic + gravity)"
set xlabel "time (s)"
unset title
set ylabel "kinetic energy (J)"
stats dir."/history.csv" using ($4 > 0 ? $4 : NaN) every ::1 nooutput
if (STATS_records > 0 && STATS_max > 10 * STATS_min) { set logscale y; set format y "10^{%L}" }
plot dir."/history.csv" every ::1 using 2:($4 > 0 ? $4 : NaN) with linespoints lw 2 pt 5 ps 0.6 lc rgb "#35b779" \
     title "kinetic (steps with 0 not drawn on the log axis)"
unset logscale y
set format y "%.3g"
unset multiplot

set terminal pngcairo size 1200,700 enhanced font "DejaVu Sans,14"
set output dir."/iterations.png"
stats dir."/history.csv" using 6 every ::1 nooutput
cg_max = STATS_max
set yrange [0:*]
if (cg_max > 0) {
  set title title.": solver iterations per step"
  set ylabel "Newton iterations"
  set y2label "CG iterations"
  set ytics nomirror
  set y2tics
  set y2range [0:*]
  plot dir."/history.csv" every ::1 using 2:5 with linespoints lw 2 pt 7 ps 0.6 axes x1y1 title "Newton", \
       "" every ::1 using 2:6 with linespoints lw 2 pt 5 ps 0.6 axes x1y2 title "CG"
} else {
  set title title.": Newton iterations per step (direct linear solver: no CG iterations)"
  set ylabel "Newton iterations"
  plot dir."/history.csv" every ::1 using 2:5 with linespoints lw 2 pt 7 ps 0.6 title "Newton"
}
unset y2label
unset y2tics
set ytics mirror
set autoscale y

set output dir."/ms-per-step.png"
set title title.": wall time per step"
set ylabel "ms per step"
stats dir."/history.csv" using ($7 > 0 ? $7 : NaN) every ::1 nooutput
if (STATS_records > 0 && STATS_max > 10 * STATS_min) { set logscale y }
plot dir."/history.csv" every ::1 using 2:7 with linespoints lw 2 pt 7 ps 0.6 title "ms per step"
set output
