#!/bin/bash
# Basalt's basalt_vio on a driftlab EuRoC export, as examples/external/basalt.yaml runs it: the
# export's basalt_calib.json, Basalt's own EuRoC configuration (data/euroc_config.json), no GUI,
# stereo + IMU (MODE vio) or stereo alone (MODE vo, --use-imu 0), and OUT written as EuRoC
# ground truth (the IMU's poses, t [ns], p, q w x y z) from its trajectory.csv, for driftlab to
# turn into the left camera's.
#
#   basalt.sh DIR OUT [vio|vo]
#
# The build: scripts/external/basalt (DRIFTLAB_BASALT: its folder, default
# ~/.cache/driftlab/peers/basalt).
set -euo pipefail
dir=$1 out=$2 mode=${3:-vio}
build=${DRIFTLAB_BASALT:-$HOME/.cache/driftlab/peers/basalt}
[ -x "$build/build/basalt_vio" ] || {
  echo "basalt.sh: $build/build/basalt_vio: not found; build Basalt with scripts/external/basalt" >&2
  exit 2
}
case "$mode" in
  vio) imu=1 ;;
  vo) imu=0 ;;
  *) echo "basalt.sh: mode '$mode': expected vio or vo" >&2; exit 2 ;;
esac
work=$(dirname "$out")/basalt
rm -rf "$work"
mkdir -p "$work"
cd "$work" # basalt_vio writes its trajectory into the current folder
"$build/build/basalt_vio" --dataset-path "$dir" --dataset-type euroc \
  --cam-calib "$dir/basalt_calib.json" --config-path "$build/src/data/euroc_config.json" \
  --show-gui 0 --use-imu "$imu" --save-trajectory euroc --save-groundtruth 0
grep -v '^#' trajectory.csv >"$out"
