# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# docs/tissue-region.png from slice.dat (x z label, mm): see tissue-region.sh
set terminal pngcairo size 900,500 font ",11"
set output out
set size ratio -1
set key top left
set xrange [-8:40]; set yrange [-4:18]
set xlabel 'x (mm)'; set ylabel 'z (mm)'
set title "Tilted slabs, max\\_gap 6 mm, 0.5 mm voxels: tissue = outside both, d_A + d_B <= max\\_gap"
set palette defined (0 'white', 1 '#e08a3c')
unset colorbox
set cbrange [0:1]
set style fill solid 0.35 noborder
s=1.0/3; G=6; c=sqrt(1+s*s)
set object 1 polygon from -8,-4 to 40,-4 to 40,0 to -8,0 to -8,-4 fc rgb '#7f9fbf' fs solid 0.6 border lc rgb '#30506f' behind
set object 2 polygon from 0,0 to 40,40.0/3 to 40,18 to 30,18 to 0,8 to 0,0 fc rgb '#7f9fbf' fs solid 0.6 border lc rgb '#30506f' behind
set label 'organ A' at 30,-2 center
set label 'organ B' at 24,12.5 center
set label 'gap = max\_gap' at G/s,G+1.2 center font ",9"
set label 'gap = 2 max\_gap' at 2*G/s,2*G+1.2 center font ",9"
set arrow from G/s,0 to G/s,G nohead dt 2 lc rgb 'black'
set arrow from 2*G/s,0 to 2*G/s,2*G nohead dt 2 lc rgb 'black'
plot 'slice.dat' u 1:2:($3>0?1:NaN) w image notitle, \
     '-' w l lw 2 lc rgb '#b03000' t 'exact boundary of d_A + d_B <= max\_gap'
-6 0
0 6

18 6
18.9737 0
e
