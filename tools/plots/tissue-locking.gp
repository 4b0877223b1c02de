# SPDX-License-Identifier: MIT
# Volumetric locking in a prepared tissue: the pelvis tissue's mean sag
# against its frames, nu = 0.3 and 0.49, with and without volumetric patches
# (tools/bench/tissue-tradeoff.sh with NU and PATCH=0):
#   gnuplot -e "dir='tools/bench/results/2core-debian_cpu'" tools/plots/tissue-locking.gp
# reads   dir/tissue_tradeoff_nu0{30,49}{,_full}.csv
# writes  dir/tissue_locking.png
if (!exists("dir")) dir = "tools/bench/results/2core-debian_cpu"
set datafile separator ","
set terminal pngcairo size 1000,700 enhanced font "DejaVu Sans,14"
set output dir."/tissue_locking.png"
set title "pelvis tissue under gravity, static: mean displacement against resolution"
set xlabel "frames (frame spacing 8, 6, 5, 4, 3 mm; samples at a third)"
set ylabel "mean tissue displacement (µm)"
set logscale x
set key bottom right
set grid
plot dir."/tissue_tradeoff_nu030_full.csv" every ::1 using 3:($5*1e6) with linespoints lw 2 pt 7 title "ν = 0.3, full integration", \
     dir."/tissue_tradeoff_nu030.csv" every ::1 using 3:($5*1e6) with linespoints lw 2 pt 5 title "ν = 0.3, patches (default)", \
     dir."/tissue_tradeoff_nu049_full.csv" every ::1 using 3:($5*1e6) with linespoints lw 2 pt 9 title "ν = 0.49, full integration (locks)", \
     dir."/tissue_tradeoff_nu049.csv" every ::1 using 3:($5*1e6) with linespoints lw 2 pt 11 title "ν = 0.49, patches (default)"
