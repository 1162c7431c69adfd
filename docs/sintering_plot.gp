# Densification curve of tomodem-sinter: gnuplot -e "dir='out'" docs/sintering_plot.gp
# Writes dir/densification.png: relative density and shrinkage per axis against time, and the
# temperature program on the right axis.
if (!exists("dir")) dir = "."
set datafile separator ","
set terminal pngcairo size 1000,650 font ",11"
set output dir."/densification.png"
set multiplot layout 2,1
set key autotitle columnhead left top
set xlabel "time (s)"
set ylabel "relative density"
set y2label "temperature (K)"
set y2tics
set ytics nomirror
plot dir."/densification.csv" using 2:4 with lines lw 2 title "density (overlaps once)", \
     "" using 2:5 with lines dt 2 title "density from cell (rho0 V0/V)", \
     "" using 2:3 axes x1y2 with lines lc rgb "gray" title "temperature"
unset y2label
unset y2tics
set ylabel "linear shrinkage"
plot dir."/densification.csv" using 2:7 with lines title "x", "" using 2:8 with lines title "y", \
     "" using 2:9 with lines title "z"
unset multiplot
