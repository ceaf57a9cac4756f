# docs/conic-deviation.png from conic_figures' CSV:
#   build-conic/tb/conic/conic_figures --csv conic.csv && gnuplot -e "csv='conic.csv'; out='docs/conic-deviation.png'" tb/conic/conic_figures.gp
set datafile separator ","
set terminal pngcairo size 900,600 font ",10"
set output out
set multiplot layout 2,1
set logscale x 2
set xrange [1:4096]
set ylabel "max node distance (steps)"
set key bottom right
set yrange [0:0.75]
plot csv using 1:2 every ::1 with lines title "combined steps (cp\\_conic)", \
     csv using 1:5 every ::1 with lines title "one axis at a time", \
     0.5 dt 2 lc rgb "gray" title "1/2", sqrt(0.5) dt 3 lc rgb "gray" title "sqrt(1/2)"
set ylabel "moves per quarter / r"
set xlabel "radius r (steps)"
set yrange [0.9:2.1]
plot csv using 1:($3/$1) every ::1 with lines title "combined steps", \
     csv using 1:($6/$1) every ::1 with lines title "one axis at a time", \
     sqrt(2) dt 2 lc rgb "gray" title "sqrt(2)"
unset multiplot
