set title 'Fracture toughness against relative density'
set xlabel 'relative density'
set ylabel 'K_IC (Pa m^0.5)'
set grid
set key top left
set logscale y
plot 'toughness.dat' index 0 using 1:2 with linespoints title 'homogeneous', \
     'toughness.dat' index 1 using 1:2 with linespoints title 'pore-former', \
     'toughness.dat' index 2 using 1:2 with linespoints title 'aggregated'
