#!/bin/sh
# An external VO that exits 0 but writes something that is not a trajectory. Usage: OUT
echo "frame 0: ok" > "$1"
echo "frame 1: lost" >> "$1"
