#!/bin/sh
# An external VO that hangs (and starts a child of its own, which must be killed too).
sleep 300 &
sleep 300
