# tip deflection against DOFs, like Figure 3 of Bosman et al. 2013 (gnuplot convergence.gp)
set terminal pngcairo size 900,600 font ',10'
set output 'convergence.png'
set datafile separator ','
set logscale x
set grid
set key bottom right
set xlabel 'degrees of freedom (fascia: 6 x frames; FEM: 3 x nodes)'
set ylabel 'tip uz (m)'
set title 'cantilever 16 x 1 x 1 m, static, StVK: reference uz = -6.5104 m'
plot -6.51045 w l dt 2 lc 'black' t 'converged FE reference (CalculiX)', \
  for [m in 'fascia-hex fascia-tet fascia-meshless fascia-hex-patches fascia-tet-patches fascia-meshless-patches calculix-c3d8'] 'convergence.csv' u (strcol(1) eq m ? $3 : NaN):4 w lp pt 7 lw 2 t m
