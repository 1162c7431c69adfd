set terminal svg size 900,600
set output 'scaling-strong.svg'
set logscale x 2
set xrange [0.8:1300]
set yrange [0:1.1]
set grid
set key bottom left
set xlabel 'MPI ranks'
set ylabel 'parallel efficiency'
set title 'Strong scaling (model, scene A density)'
plot 'scaling-strong.dat' index 0 using 1:2:3:4 with yerrorlines title 'N=10^6, shared memory', 'scaling-strong.dat' index 1 using 1:2:3:4 with yerrorlines title 'N=10^6, InfiniBand HDR', 'scaling-strong.dat' index 2 using 1:2:3:4 with yerrorlines title 'N=10^8, shared memory', 'scaling-strong.dat' index 3 using 1:2:3:4 with yerrorlines title 'N=10^8, InfiniBand HDR'
