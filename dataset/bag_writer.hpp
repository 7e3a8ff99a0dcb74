// The bag writers' shared part (ROS 1 and ROS 2 bags carry the same streams, rosbag.hpp): the
// frames, the sensors' CSVs and the truth become one call per message of a BagSink, which
// serialises and stores it in its format; the calibration files are written beside the bag.
// Internal to dataset/.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dataset/dataset.hpp"

namespace driftlab::dataset::detail {

/// One transform of /tf_static: the child frame's pose in the parent's.
struct TransformRecord {
  std::string parent, child;
  SE3 T_parent_child;
};

/// One GPS epoch as NavSatFix carries it.
struct GpsRecord {
  TimeNs t_ns = 0;
  bool fix = false;
  double latitude_deg = 0, longitude_deg = 0, height_m = 0;  ///< NaN without a fix
  /// Diagonal covariance (east, north, up) [m^2], when the fix has one.
  std::optional<Vec3> covariance_enu_m2;
};

/// Where the messages go. Calls come grouped by stream; `seq` counts each topic's messages.
class BagSink {
 public:
  virtual ~BagSink() = default;
  virtual void image(int cam, TimeNs t_ns, std::uint32_t seq, const cv::Mat& gray) = 0;
  /// The rectified pair's camera_info (plumb_bob, zero distortion, cam1's P with -fx B).
  virtual void camera_info(int cam, TimeNs t_ns, std::uint32_t seq, const StereoRig& rig) = 0;
  /// No orientation; the rate's and force's covariance diagonals.
  virtual void imu(const ImuSample& s, std::uint32_t seq, double gyro_var, double accel_var) = 0;
  virtual void gps(const GpsRecord& g, std::uint32_t seq) = 0;
  /// /mag (the field in tesla) and /compass/heading.
  virtual void compass(const CompassReading& r, std::uint32_t seq) = 0;
  /// /groundtruth/pose: the IMU in world_ned.
  virtual void pose(TimeNs t_ns, const SE3& T_W_S, std::uint32_t seq) = 0;
  /// /tf_static, latched (ROS 2: transient local).
  virtual void tf_static(TimeNs t_ns, const std::vector<TransformRecord>& transforms) = 0;
  /// Everything is in: finish the bag's index or database.
  virtual void close() = 0;
};

/// A DatasetWriter that feeds `sink` and writes Kalibr's and VINS-Fusion's files and
/// info.yaml (with `bag_files`, one line on where the bag is) into `root`.
std::unique_ptr<DatasetWriter> make_bag_writer(const std::filesystem::path& root,
                                               const ExportCalibration& calibration,
                                               std::unique_ptr<BagSink> sink, std::string format,
                                               std::string bag_files);

/// The three axes' rotation quaternion of a heading: a turn about the world's down axis.
Quat heading_quaternion(double heading_rad);

}  // namespace driftlab::dataset::detail
