set title 'Relative Young''s modulus against relative density'
set xlabel 'relative density'
set ylabel 'E/E_s'
set grid
set key top left
set logscale y
plot 'stiffness.dat' index 0 using 1:2 with linespoints title 'homogeneous', \
     'stiffness.dat' index 1 using 1:2 with linespoints title 'pore-former', \
     'stiffness.dat' index 2 using 1:2 with linespoints title 'aggregated'
