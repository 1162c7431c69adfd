set title 'Relative conductivity against relative density'
set xlabel 'relative density'
set ylabel 'sigma_eff/sigma_s'
set grid
set key top left
set logscale y
plot 'conductivity.dat' index 0 using 1:2 with linespoints title 'homogeneous', \
     'conductivity.dat' index 1 using 1:2 with linespoints title 'pore-former', \
     'conductivity.dat' index 2 using 1:2 with linespoints title 'aggregated'
