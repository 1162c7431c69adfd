set title 'Performance index K_IC/E against relative density'
set xlabel 'relative density'
set ylabel 'K_IC/E (m^0.5)'
set grid
set key top left
set logscale y
plot 'performance.dat' index 0 using 1:2 with linespoints title 'homogeneous', \
     'performance.dat' index 1 using 1:2 with linespoints title 'pore-former', \
     'performance.dat' index 2 using 1:2 with linespoints title 'aggregated'
