# fascia tradeoff: error against time, log-log, with Pareto fronts (gnuplot pareto.gp)
set terminal pngcairo size 1400,600 font ',10'
set output 'pareto.png'
set datafile separator whitespace
set logscale xy
set grid
set key outside bottom center horizontal
set multiplot layout 1,2
set title 'static tip deflection (discretization)'
set xlabel 'ms per static solve'
set ylabel 'tip uz error, % of the reference'
plot for [p in 'cantilever stiff incompressible'] 'points_static_'.p.'.dat' u 1:2 w p pt 7 ps 0.8 t p, \
     for [p in 'cantilever stiff incompressible'] 'front_static_'.p.'.dat' u 1:2 w l lw 2 t p.' front', \
     'front_static_cantilever.dat' u 1:2:3 w labels left offset 0.5,0.3 font ',7' notitle
set title 'implicit Euler, 20x3x3 hex cantilever (solver, time step, presets)'
set xlabel 'ms per step'
set ylabel 'tip uz(T) error, % of the dt -> 0 value'
plot 'points_dynamic_cantilever.dat' u 1:2 w p pt 7 ps 0.8 t 'rows', \
     'front_dynamic_cantilever.dat' u 1:2 w l lw 2 t 'front', \
     'front_dynamic_cantilever.dat' u 1:2:3 w labels left offset 0.5,0.3 font ',7' notitle
unset multiplot
