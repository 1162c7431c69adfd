# error-vs-cpu_E_rel: made by tomodem (core/plot.hpp). Re-make: gnuplot error-vs-cpu_E_rel.gp, or gnuplot -e "output_file='error-vs-cpu_E_rel.svg'" error-vs-cpu_E_rel.gp
# tomodem's one plot style (issue 21). write_plot (libs/core/src/plot.cpp) compiles this file in
# and puts it at the top of every script it writes; scripts that call gnuplot themselves
# (tests/bench/mpi/scaling_model.py) `load` it. Change the look of every figure here, nowhere else.
# The terminal and its size are set by plot_terminal_png/svg below, so `gnuplot -e "set terminal
# ...; set output ..." NAME.gp` can still re-make a figure elsewhere.
plot_terminal_png = "pngcairo size 800,560 enhanced font 'DejaVu Sans,11' linewidth 1.5"
plot_terminal_svg = "svg size 800,560 enhanced font 'DejaVu Sans,11' linewidth 1.5 background rgb 'white'"
set encoding utf8
set border 3 linewidth 1.0
set tics nomirror out scale 0.75
set grid xtics ytics mxtics mytics linecolor rgb '#dddddd' linewidth 0.5 dashtype 1, linecolor rgb '#eeeeee' linewidth 0.5
set key top left opaque box linecolor rgb '#bbbbbb' samplen 2.5 spacing 1.1
set style line 100 linecolor rgb '#444444'
set pointsize 0.9
set bars small
# Okabe & Ito (2008) colours, distinguishable with the common colour-vision deficiencies.
set linetype 1 linecolor rgb '#0072B2' linewidth 1.5 pointtype 7 dashtype 1
set linetype 2 linecolor rgb '#D55E00' linewidth 1.5 pointtype 5 dashtype 1
set linetype 3 linecolor rgb '#009E73' linewidth 1.5 pointtype 9 dashtype 1
set linetype 4 linecolor rgb '#CC79A7' linewidth 1.5 pointtype 13 dashtype 1
set linetype 5 linecolor rgb '#E69F00' linewidth 1.5 pointtype 11 dashtype 1
set linetype 6 linecolor rgb '#56B4E9' linewidth 1.5 pointtype 3 dashtype 1
set linetype 7 linecolor rgb '#000000' linewidth 1.5 pointtype 1 dashtype 1
set linetype 8 linecolor rgb '#F0E442' linewidth 1.5 pointtype 2 dashtype 1
set linetype cycle 8

if (!exists('output_file')) output_file = 'error-vs-cpu_E_rel.png'
if (!exists('output_format')) output_format = output_file[strlen(output_file)-2:] eq 'svg' ? 'svg' : 'png'
eval('set terminal ' . (output_format eq 'svg' ? plot_terminal_svg : plot_terminal_png))
set output output_file
set title '95 % half-width of the mean of E_rel against CPU time' noenhanced
set xlabel 'CPU time spent (s, sum over replicas)' noenhanced
set ylabel 'relative 95 % half-width (-)' noenhanced
set logscale x 10
set format x '10^{%L}'
set mxtics 10
set logscale y 10
set format y '10^{%L}'
set mytics 10
plot 'error-vs-cpu_E_rel.dat' index 0 using 1:2 with linespoints linetype 1 title 'family=homogeneous, particles=500.0, density=0.6' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 1 using 1:2 with linespoints linetype 2 title 'family=homogeneous, particles=500.0, density=0.8' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 2 using 1:2 with linespoints linetype 3 title 'family=homogeneous, particles=2000.0, density=0.6' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 3 using 1:2 with linespoints linetype 4 title 'family=homogeneous, particles=2000.0, density=0.8' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 4 using 1:2 with linespoints linetype 5 title 'family=homogeneous, particles=8000.0, density=0.6' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 5 using 1:2 with linespoints linetype 6 title 'family=homogeneous, particles=8000.0, density=0.8' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 6 using 1:2 with linespoints linetype 7 title 'family=homogeneous, particles=32000.0, density=0.6' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 7 using 1:2 with linespoints linetype 8 title 'family=homogeneous, particles=32000.0, density=0.8' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 8 using 1:2 with linespoints linetype 1 title 'family=pore-former, particles=500.0, density=0.6' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 9 using 1:2 with linespoints linetype 2 title 'family=pore-former, particles=500.0, density=0.8' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 10 using 1:2 with linespoints linetype 3 title 'family=pore-former, particles=2000.0, density=0.6' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 11 using 1:2 with linespoints linetype 4 title 'family=pore-former, particles=2000.0, density=0.8' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 12 using 1:2 with linespoints linetype 5 title 'family=pore-former, particles=8000.0, density=0.6' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 13 using 1:2 with linespoints linetype 6 title 'family=pore-former, particles=8000.0, density=0.8' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 14 using 1:2 with linespoints linetype 7 title 'family=pore-former, particles=32000.0, density=0.6' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 15 using 1:2 with linespoints linetype 8 title 'family=pore-former, particles=32000.0, density=0.8' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 16 using 1:2 with linespoints linetype 1 title 'family=aggregated, particles=500.0, density=0.6' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 17 using 1:2 with linespoints linetype 2 title 'family=aggregated, particles=500.0, density=0.8' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 18 using 1:2 with linespoints linetype 3 title 'family=aggregated, particles=2000.0, density=0.6' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 19 using 1:2 with linespoints linetype 4 title 'family=aggregated, particles=2000.0, density=0.8' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 20 using 1:2 with linespoints linetype 5 title 'family=aggregated, particles=8000.0, density=0.6' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 21 using 1:2 with linespoints linetype 6 title 'family=aggregated, particles=8000.0, density=0.8' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 22 using 1:2 with linespoints linetype 7 title 'family=aggregated, particles=32000.0, density=0.6' noenhanced, \
     'error-vs-cpu_E_rel.dat' index 23 using 1:2 with linespoints linetype 8 title 'family=aggregated, particles=32000.0, density=0.8' noenhanced
