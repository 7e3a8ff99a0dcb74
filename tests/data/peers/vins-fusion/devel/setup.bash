# Stand-in for VINS-Fusion's catkin workspace (tests/data/peers/peer_standin.py): the stand-in
# node reads no topics: roscore and rosparam are shell functions that do nothing, and `rosbag
# play ... BAG` only tells the node (through ROS_HOME/played) which bag was played.
roscore() { while :; do sleep 1; done; }
rosparam() { :; }
rosbag() { echo "${@: -1}" >"$ROS_HOME/played"; }
