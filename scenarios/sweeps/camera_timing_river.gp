# The figure of docs/camera-timing.md's river half, from the merged sweep:
#   gnuplot -e "runs='out/camera_timing_river/summary/runs.csv'; out='docs/camera_timing_river.png'" \
#     scenarios/sweeps/camera_timing_river.gp
# Each run a point. Left: the rolling
# shutter's line delay, the pair synchronised; right: the right image's offset, global shutter
# (offset 0 is the 0.1 us point, a readout of 77 us in one band, drawn as a global shutter).
set datafile separator ','
set terminal pngcairo size 1200,800 font ',11'
set output out
set multiplot layout 2,2 title 'First river crossing (682 frames, Bumblebee2 1024x768 at 8.2 Hz), 2 replicates a point'
set grid
set termoption noenhanced
set key top left
rolling(a) = (strcol(5) eq 'rolling' && strcol(8) eq a)
offset(a) = ((strcol(5) eq 'global' || $6 == 0.1) && strcol(8) eq a)
set xlabel 'line delay [us] (readout = 767 lines)'
set ylabel 'APE translation RMSE [cm]'
plot for [a in 'sparse sparse_kf'] runs using (rolling(a) ? $6 : 1/0):(100 * $11) with points pt 7 lc (a eq "sparse" ? 1 : 2) title a
set xlabel 'right image offset [ms]'
plot for [a in 'sparse sparse_kf'] runs using (offset(a) ? $7 : 1/0):(100 * $11) with points pt 7 lc (a eq "sparse" ? 1 : 2) title a
set xlabel 'line delay [us] (readout = 767 lines)'
set ylabel 'APE rotation RMSE [deg]'
plot for [a in 'sparse sparse_kf'] runs using (rolling(a) ? $6 : 1/0):12 with points pt 7 lc (a eq "sparse" ? 1 : 2) title a
set xlabel 'right image offset [ms]'
plot for [a in 'sparse sparse_kf'] runs using (offset(a) ? $7 : 1/0):12 with points pt 7 lc (a eq "sparse" ? 1 : 2) title a
unset multiplot
