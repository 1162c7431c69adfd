set title 'Bonds per particle against relative density'
set xlabel 'relative density'
set ylabel 'Z'
set grid
set key top left
plot 'coordination.dat' index 0 using 1:2 with linespoints title 'homogeneous', \
     'coordination.dat' index 1 using 1:2 with linespoints title 'pore-former', \
     'coordination.dat' index 2 using 1:2 with linespoints title 'aggregated'
