# Stand-in for OpenVINS's catkin workspace (tests/data/peers/peer_standin.py): ROS's master is
# not needed by the stand-in node, so roscore and rosparam are shell functions that do nothing.
roscore() { while :; do sleep 1; done; }
rosparam() { :; }
