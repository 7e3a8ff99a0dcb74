# The figure of the wind sweep (docs/renderer-and-scenes.md, Wind in the vegetation), from the
# merged sweep:
#   gnuplot -e "runs='out/wind_sway/summary/runs.csv'; out='docs/wind_sway.png'" \
#     scenarios/sweeps/wind_sway.gp
# Each run a point: its VO's mean section error e'_p (2 m sections) against the wind speed,
# the vegetation swaying (filled) and standing still (open); the ripples on the water grow with
# the wind either way.
set datafile separator ','
set terminal pngcairo size 1200,420 font ',11'
set output out
set multiplot layout 1,3 title "A survey leg (375 frames, Bumblebee2 1024x768), wind 0-8 m/s, 2 replicates a point"
set grid
set termoption noenhanced
set key horizontal top center outside
set yrange [0:*]
set xlabel 'wind speed [m/s]'
set xrange [-0.5:8.5]
swaying(a) = (strcol(7) eq a && strcol(6) eq 'true')
still(a) = (strcol(7) eq a && strcol(6) eq 'false')
do for [a in 'sparse sparse_kf dense'] {
  set title a
  set ylabel "e'_p mean [m/m]"
  plot runs using (swaying(a) ? $5 : 1/0):8 with points pt 7 ps 1.2 lc 1 title 'swaying', \
       runs using (still(a) ? $5 + 0.15 : 1/0):8 with points pt 6 ps 1.2 lc 2 title 'still'
}
unset multiplot
