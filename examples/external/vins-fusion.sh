#!/bin/bash
# VINS-Fusion's estimator (vins_node) on a driftlab ROS 1 bag export, as
# examples/external/vins-fusion.yaml runs it: the export's vins_fusion/ configuration (stereo +
# IMU, or stereo alone with MODE stereo), the bag played into it by rosbag at RATE times real
# time (default 1), and OUT written as EuRoC ground truth (the IMU's poses, t [ns], p, q w x y
# z) from its vio.csv, for driftlab to turn into the left camera's.
#
#   vins-fusion.sh ROOT OUT [stereo_imu|stereo] [RATE]
#
# The build: scripts/external/vins-fusion (DRIFTLAB_VINS_FUSION: its workspace, default
# ~/.cache/driftlab/peers/vins-fusion). vins_node subscribes to topics, so the run takes the
# bag's duration divided by RATE, and a frame it cannot keep up with is skipped, as on a vessel.
set -euo pipefail
root=$1 out=$2 mode=${3:-stereo_imu} rate=${4:-1}
ws=${DRIFTLAB_VINS_FUSION:-$HOME/.cache/driftlab/peers/vins-fusion}
source "$(dirname "$0")/runner.sh"
peer_built "$ws/devel/setup.bash" VINS-Fusion vins-fusion
imu=$(with_imu "$mode" stereo_imu stereo)
set +u
source "$ws/devel/setup.bash"
set -u
WORK=$(dirname "$out")/vins-fusion
rm -rf "$WORK"
mkdir -p "$WORK/output"
source "$(dirname "$0")/ros1.sh"
ros1_master

# The export's configuration, with this run's output folder and the IMU on or off.
cp "$root"/vins_fusion/*.yaml "$WORK/"
sed -i -e "s|^output_path:.*|output_path: \"$WORK/output/\"|" -e "s|^imu:.*|imu: $imu|" \
  -e "s|^pose_graph_save_path:.*|pose_graph_save_path: \"$WORK/output/pose_graph/\"|" \
  "$WORK/stereo_imu_config.yaml"
"$ws/devel/lib/vins/vins_node" "$WORK/stereo_imu_config.yaml" >"$WORK/vins_node.log" 2>&1 &
node=$!
sleep 2 # vins_node subscribes before the first message is played
rosbag play --quiet --rate "$rate" "$root/driftlab.bag"
sleep 5 # the last frames' optimisation
kill -INT $node 2>/dev/null || true
wait $node 2>/dev/null || true
tail -n 20 "$WORK/vins_node.log"

awk -F, 'NF >= 8 { printf "%.0f,%s,%s,%s,%s,%s,%s,%s\n", $1, $2, $3, $4, $5, $6, $7, $8 }' \
  "$WORK/output/vio.csv" >"$out"
