set terminal svg size 900,600
set output 'scaling-weak.svg'
set logscale x 2
set xrange [0.8:1300]
set yrange [0:1.1]
set grid
set key bottom left
set xlabel 'MPI ranks'
set ylabel 'weak efficiency'
set title 'Weak scaling (model, scene A density)'
plot 'scaling-weak.dat' index 0 using 1:2:3:4 with yerrorlines title '977 per rank, shared memory', 'scaling-weak.dat' index 1 using 1:2:3:4 with yerrorlines title '977 per rank, InfiniBand HDR', 'scaling-weak.dat' index 2 using 1:2:3:4 with yerrorlines title '97656 per rank, shared memory', 'scaling-weak.dat' index 3 using 1:2:3:4 with yerrorlines title '97656 per rank, InfiniBand HDR'
