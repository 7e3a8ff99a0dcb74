#!/bin/bash
# Basalt's basalt_vio on a driftlab EuRoC export, as examples/external/basalt.yaml runs it: the
# export's basalt_calib.json, one of Basalt's own configurations (CONFIG, a file of its data/
# folder; default kitti_config.json, its outdoor one), no GUI, stereo + IMU (MODE vio) or stereo
# alone (MODE vo, --use-imu 0), and OUT written as EuRoC ground truth (the IMU's poses, t [ns],
# p, q w x y z) from its trajectory.csv, for driftlab to turn into the left camera's.
#
#   basalt.sh DIR OUT [vio|vo] [CONFIG]
#
# Why the outdoor configuration: with euroc_config.json (grid 50 px, epipolar error 0.005,
# 3 pyramid levels, a keyframe at most every 5 frames) Basalt loses the river's far bank within
# 20 frames; kitti_config.json tracks it, and does as well as euroc_config.json in the basin
# (docs/datasets.md, "Peers on the twin").
#
# The build: scripts/external/basalt (DRIFTLAB_BASALT: its folder, default
# ~/.cache/driftlab/peers/basalt).
set -euo pipefail
dir=$1 out=$2 mode=${3:-vio} config=${4:-kitti_config.json}
build=${DRIFTLAB_BASALT:-$HOME/.cache/driftlab/peers/basalt}
source "$(dirname "$0")/runner.sh"
peer_built "$build/build/basalt_vio" Basalt basalt
[ -f "$build/src/data/$config" ] || {
  echo "basalt.sh: CONFIG '$config': no such file in $build/src/data (expected one of Basalt's configurations, e.g. kitti_config.json)" >&2
  exit 2
}
imu=$(with_imu "$mode" vio vo)
work=$(dirname "$out")/basalt
rm -rf "$work"
mkdir -p "$work"
cd "$work" # basalt_vio writes its trajectory into the current folder
"$build/build/basalt_vio" --dataset-path "$dir" --dataset-type euroc \
  --cam-calib "$dir/basalt_calib.json" --config-path "$build/src/data/$config" \
  --show-gui 0 --use-imu "$imu" --save-trajectory euroc --save-groundtruth 0
grep -v '^#' trajectory.csv >"$out"
