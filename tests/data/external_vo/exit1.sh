#!/bin/sh
# An external VO that fails: a message on standard error and exit code 1.
echo "myvo: cannot open $1/calib.txt: permission denied" >&2
exit 1
