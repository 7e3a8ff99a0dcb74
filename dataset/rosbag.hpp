// ROS bags as driftlab writes them: ROS 1 (format 2.0, wiki.ros.org/Bags/Format/2.0, written
// and read through Debian's rosbag_storage) and ROS 2 (rosbag2's sqlite3 storage, CDR; written
// only). Shared by the writers and the reader (not included outside dataset/). A ROS 2 bag
// carries the same topics with ROS 2's types (sensor_msgs/msg/Image, ...), every stamp as it
// is (no record time), and /tf_static offered transient local.
//
// Topics (EuRoC's names where EuRoC has the stream):
//   /cam0/image_raw, /cam1/image_raw  sensor_msgs/Image, mono8, rectified; frame camN_optical
//   /cam0/camera_info, /cam1/camera_info  sensor_msgs/CameraInfo (plumb_bob, zero distortion;
//                                     cam1's P carries Tx = -fx B)
//   /imu0                             sensor_msgs/Imu, frame imu; no orientation (covariance -1)
//   /gps/fix                          sensor_msgs/NavSatFix, frame gps (the antenna)
//   /mag                              sensor_msgs/MagneticField [T], frame compass
//   /compass/heading                  geometry_msgs/QuaternionStamped, frame world_ned: the
//                                     compass's heading as a turn about the world's down axis
//   /groundtruth/pose                 geometry_msgs/PoseStamped: frame imu in world_ned
//   /tf_static                        tf2_msgs/TFMessage (latched): base_link -> imu, gps,
//                                     compass; imu -> cam0_optical, cam1_optical
// Frames (REP 103): base_link is the vessel's body, x forward, y left, z up; imu and compass
// are the sensors' own axes (driftlab's FRD at zero mount angles); camN_optical x right, y down,
// z forward; world_ned is the scenario's world (x north, y east, z down: REP 103's _ned suffix).
// Header stamps are the sensors' own (ns since the mission's start). A bag cannot record a
// message at time zero (rosbag's TIME_MIN), so a message stamped 0 is recorded at 1 ns.
#pragma once

#include <cstdint>

#include "core/time.hpp"

namespace driftlab::dataset::rosbag_names {

inline constexpr const char* kBagFile = "driftlab.bag";
/// A ROS 2 export's bag: this folder, with metadata.yaml and rosbag2_0.db3.
inline constexpr const char* kBag2Folder = "rosbag2";
inline constexpr const char* kCamchainFile = "kalibr_imucam_chain.yaml";
inline constexpr const char* kImuChainFile = "kalibr_imu_chain.yaml";

inline constexpr const char* kImage[2] = {"/cam0/image_raw", "/cam1/image_raw"};
inline constexpr const char* kCameraInfo[2] = {"/cam0/camera_info", "/cam1/camera_info"};
inline constexpr const char* kImu = "/imu0";
inline constexpr const char* kGps = "/gps/fix";
inline constexpr const char* kMag = "/mag";
inline constexpr const char* kHeading = "/compass/heading";
inline constexpr const char* kGroundTruth = "/groundtruth/pose";
inline constexpr const char* kTfStatic = "/tf_static";
/// EuRoC's Vicon-room ground truth (geometry_msgs/TransformStamped).
inline constexpr const char* kEurocVicon = "/vicon/firefly_sbx/firefly_sbx";
/// TUM-VI's motion-capture ground truth (geometry_msgs/TransformStamped).
inline constexpr const char* kTumViMocap = "/vrpn_client/raw_transform";

inline constexpr const char* kOpticalFrame[2] = {"cam0_optical", "cam1_optical"};
inline constexpr const char* kImuFrame = "imu";
inline constexpr const char* kBaseFrame = "base_link";
inline constexpr const char* kWorldFrame = "world_ned";

/// The record time of a message stamped `t_ns` (at least 1 ns: rosbag's TIME_MIN).
inline TimeNs record_ns(TimeNs t_ns) { return t_ns < 1 ? 1 : t_ns; }

}  // namespace driftlab::dataset::rosbag_names
