#!/bin/bash
# OpenVINS's serial node (ov_msckf ros1_serial_msckf, stereo + IMU) on a driftlab ROS 1 bag
# export, as examples/external/openvins.yaml runs it: reads ROOT/driftlab.bag with the
# export's estimator_config.yaml and Kalibr files, and writes OUT as EuRoC ground truth (the
# IMU's poses, t [ns], p, q w x y z), for driftlab to turn into the left camera's.
#
#   openvins.sh ROOT OUT
#
# The build: scripts/external/openvins (DRIFTLAB_OPENVINS: its workspace, default
# ~/.cache/driftlab/peers/openvins).
set -euo pipefail
root=$1 out=$2
ws=${DRIFTLAB_OPENVINS:-$HOME/.cache/driftlab/peers/openvins}
source "$(dirname "$0")/runner.sh"
peer_built "$ws/devel/setup.bash" OpenVINS openvins
set +u
source "$ws/devel/setup.bash"
set -u
WORK=$(dirname "$out")/openvins
mkdir -p "$WORK"
source "$(dirname "$0")/ros1.sh"
ros1_master

# ros1_serial_msckf's private parameters (its launch file serial.launch sets the same); the
# state file (ROS1Visualizer's save_total_state): t [s], q_GtoI (JPL, the numbers of Hamilton's
# q_ItoG) x y z w, p_IinG, ...
status=0
"$ws/devel/lib/ov_msckf/ros1_serial_msckf" __name:=ov_msckf \
  _config_path:="$root/estimator_config.yaml" _path_bag:="$root/driftlab.bag" \
  _use_stereo:=true _max_cameras:=2 _save_total_state:=true \
  _filepath_est:="$WORK/state_estimate.txt" _filepath_std:="$WORK/state_deviation.txt" \
  _filepath_gt:="$WORK/state_groundtruth.txt" >"$WORK/node.log" 2>&1 || status=$?
cat "$WORK/node.log"
# Debian 12's rosbag library aborts when the bag is closed at the node's exit (class_loader's
# LibraryUnloadException, SIGABRT), after the last state is written (one line, flushed, per
# frame): that abort alone is not a failure.
if [ $status -ne 0 ]; then
  if [ $status -eq 134 ] && tail -n 3 "$WORK/node.log" | grep -q LibraryUnloadException; then
    echo "openvins.sh: ros1_serial_msckf aborted at exit in class_loader (Debian's rosbag); its states are complete"
  else
    exit $status
  fi
fi

awk '!/^#/ && NF >= 8 {
  printf "%.0f,%s,%s,%s,%s,%s,%s,%s\n", $1 * 1e9, $6, $7, $8, $5, $2, $3, $4
}' "$WORK/state_estimate.txt" >"$out"
