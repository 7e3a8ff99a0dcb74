# The figure of the wave-amplitude sweep (docs/sweeps.md), from the merged sweep:
#   gnuplot -e "runs='out/waves/summary/runs.csv'; out='docs/wave_amplitude.png'" \
#     scenarios/sweeps/wave_amplitude.gp
# Each run a point (the Kalman filter, pnp_ned_kf): north RMSE against the wave amplitude for
# the waves from 40 deg (gamma = 40, direction_deg -40), east RMSE for those from ahead
# (gamma = 0), the errors the basin paper's Table 2 shows growing; beside them the paper's own
# values (Table 2, Kalman filter, experiments 2-4 and 5-7), joined by a line.
set datafile separator ','
set datafile columnheaders
set terminal pngcairo size 1000,420 font ',11'
set output out
set multiplot layout 1,2 title "Basin experiments 2-7: the twin's runs (points) and the basin paper's Table 2 (line), Kalman filter"
set grid
set termoption noenhanced
set key top left
set yrange [0:7]
set xrange [4:12]
set xlabel 'wave amplitude zeta_a [mm]'
kf(d) = (strcol("algorithm") eq 'pnp_ned_kf' && column("direction_deg") == d)
$paper40 << EOD
amplitude_mm,north_rmse_cm
5.0,2.232
7.5,4.087
11.0,6.043
EOD
$paper0 << EOD
amplitude_mm,east_rmse_cm
5.0,3.408
7.5,3.934
11.0,4.340
EOD
set title 'waves from 40 deg: north'
set ylabel 'north RMSE [cm]'
plot runs using (kf(-40) ? 1000 * column("amplitude_m") : 1/0):(100 * column("basin_north_rmse_m")) \
       with points pt 7 ps 1.2 lc 1 title 'twin', \
     $paper40 using 1:2 with linespoints pt 5 ps 1.2 lc 2 title 'paper'
set title 'waves from ahead (0 deg): east'
set ylabel 'east RMSE [cm]'
plot runs using (kf(0) ? 1000 * column("amplitude_m") : 1/0):(100 * column("basin_east_rmse_m")) \
       with points pt 7 ps 1.2 lc 1 title 'twin', \
     $paper0 using 1:2 with linespoints pt 5 ps 1.2 lc 2 title 'paper'
unset multiplot
