# A private ROS 1 master for one run of a peer (sourced by the ROS 1 runners here): a free port,
# logs under the run's own folder, stopped when the runner exits. Needs WORK set to a folder of
# the run's own.
ros1_master() {
  local port
  port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  export ROS_MASTER_URI=http://127.0.0.1:$port ROS_HOME=$WORK/ros ROS_LOG_DIR=$WORK/ros/log
  mkdir -p "$ROS_LOG_DIR"
  roscore -p "$port" >"$WORK/roscore.log" 2>&1 &
  MASTER_PID=$!
  trap 'status=$?; kill $MASTER_PID 2>/dev/null; wait $MASTER_PID 2>/dev/null || true; exit $status' EXIT
  local tries=0
  until rosparam list >/dev/null 2>&1; do
    tries=$((tries + 1))
    if [ $tries -gt 60 ] || ! kill -0 $MASTER_PID 2>/dev/null; then
      echo "ros1.sh: roscore did not start on port $port:" >&2
      cat "$WORK/roscore.log" >&2
      exit 1
    fi
    sleep 0.5
  done
}
