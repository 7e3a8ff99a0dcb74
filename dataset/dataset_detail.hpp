// Helpers shared by the format files of dataset/ (not part of its interface).
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <opencv2/core.hpp>

#include "core/se3.hpp"
#include "dataset/dataset.hpp"

namespace driftlab::dataset::detail {

/// The non-empty, non-comment ('#') lines of a text file with their 1-based numbers.
struct TextLine {
  int number = 0;
  std::string text;
};
std::vector<TextLine> data_lines(const std::filesystem::path& path, std::string_view what);

/// A finite number; UserError "PATH:LINE: FIELD: got 'TOKEN', expected a number" otherwise.
double parse_number(std::string_view token, const std::filesystem::path& path, int line,
                    std::string_view field);
/// A non-negative integer time stamp in nanoseconds.
TimeNs parse_stamp_ns(std::string_view token, const std::filesystem::path& path, int line);

/// Writes an 8-bit (or 16-bit) PNG; UserError naming the file when it cannot.
void write_png(const std::filesystem::path& path, const cv::Mat& image);

/// The numbers of a 3x4 or 4x4 matrix, row-major, shortest round-trip text, joined by `sep`.
std::string matrix_text(const Eigen::MatrixXd& m, std::string_view sep);
/// [R | t] of a pose as a 3x4 matrix; its 4x4 homogeneous form.
Eigen::Matrix<double, 3, 4> matrix_3x4(const SE3& T);
Eigen::Matrix4d matrix_4x4(const SE3& T);

/// One camera of a calibration file (EuRoC's sensor.yaml, a Kalibr camera chain).
struct CameraCalibration {
  PinholeCamera camera;
  std::string distortion_model;    ///< radial-tangential (radtan, plumb_bob) or empty
  std::vector<double> distortion;  ///< k1, k2, p1, p2 [, k3]
  SE3 T_B_C;                       ///< the camera in the body (IMU) frame
};

/// The rectified pair of two calibrated cameras (OpenCV's stereoRectify, zero disparity at
/// infinity, alpha 0), or the pair as it is when it is already rectified.
struct RectifiedPair {
  StereoRig rig;
  SE3 T_C0_Crect;  ///< the rectified left camera in the raw left one (a rotation)
  std::shared_ptr<const Rectification> rectification;  ///< null: already rectified
};
/// UserError naming `cam1_file` when cam1 is not a second camera to the right of cam0.
RectifiedPair rectify_pair(const CameraCalibration& c0, const CameraCalibration& c1,
                           const std::filesystem::path& cam1_file);

/// A list of `count` finite numbers (any count when 0) under `key` of the mapping `root`.
/// `prefix` goes before the key in messages (Kalibr's "cam0.").
std::vector<double> yaml_numbers(const YAML::Node& root, const char* key, std::size_t count,
                                 const std::filesystem::path& path, std::string_view prefix = {});
/// A camera under Kalibr's keys as EuRoC's sensor.yaml names them (intrinsics, resolution,
/// distortion_model, distortion_coefficients), without its pose; UserError naming `path`.
CameraCalibration camera_from_keys(const YAML::Node& root, const std::filesystem::path& path,
                                   std::string_view prefix);
/// The IMU's Kalibr noise model under EuRoC's keys (rate_hz and the four densities).
ImuNoiseModel imu_noise_from_keys(const YAML::Node& root, const std::filesystem::path& path,
                                  std::string_view prefix);

// Kalibr's and VINS-Fusion's calibration files (kalibr.cpp).
std::string kalibr_imucam_chain_yaml(const ExportCalibration& calibration);
std::string kalibr_imu_chain_yaml(const ImuNoiseModel& imu);
/// VINS-Fusion's stereo + IMU configuration and its two camera files: (name, text).
std::vector<std::pair<std::string, std::string>> vins_fusion_files(
    const ExportCalibration& calibration);
// Basalt's and ORB-SLAM3's settings for a EuRoC export, OpenVINS's for a bag (peer_configs.cpp).
/// Basalt's camera calibration (calib.json for basalt_vio --cam-calib): the rectified pair as two
/// pinholes in the IMU frame, the IMU's Kalibr model (Basalt's defaults without an IMU).
std::string basalt_calibration_json(const ExportCalibration& calibration);
/// ORB-SLAM3's v1.0 settings: stereo (Camera.type Rectified), and with `inertial` the IMU's.
std::string orbslam3_settings_yaml(const ExportCalibration& calibration, bool inertial);
/// The times file of ORB-SLAM3's EuRoC examples: each image's stamp [ns], its PNG's name.
std::string orbslam3_times(const std::vector<TimeNs>& stamps);
/// OpenVINS's estimator_config.yaml beside a bag's Kalibr files: stereo, the IMU as calibrated,
/// the dynamic initialiser, every key its serial node requires.
std::string openvins_estimator_config_yaml(const ExportCalibration& calibration);
/// A Kalibr camera chain's two cameras (pinhole, radtan) and their topics.
struct KalibrChain {
  std::array<CameraCalibration, 2> cameras;
  std::array<std::string, 2> topics;  ///< rostopic; empty when the file names none
};
KalibrChain read_kalibr_camchain(const std::filesystem::path& path);
ImuNoiseModel read_kalibr_imu_chain(const std::filesystem::path& path);

/// Moves `from` to `to`, creating to's parent.
void move_file(const std::filesystem::path& from, const std::filesystem::path& to);

// Per-format writers and readers (kitti.cpp, euroc.cpp, tum_rgbd.cpp).
std::unique_ptr<DatasetWriter> make_kitti_writer(const std::filesystem::path& root,
                                                 const ExportCalibration& calibration);
std::unique_ptr<DatasetWriter> make_euroc_writer(const std::filesystem::path& root,
                                                 const ExportCalibration& calibration);
std::unique_ptr<DatasetWriter> make_tum_rgbd_writer(const std::filesystem::path& root,
                                                    const ExportCalibration& calibration);
std::unique_ptr<DatasetWriter> make_rosbag_writer(const std::filesystem::path& root,
                                                  const ExportCalibration& calibration);
std::unique_ptr<DatasetWriter> make_rosbag2_writer(const std::filesystem::path& root,
                                                   const ExportCalibration& calibration);
/// UserError naming the byte of the first record of the ROS 1 bag at `path` whose lengths,
/// chunk sizes or counts do not fit the file (rosbag_check.cpp). Reads the headers only.
void check_bag_structure(const std::filesystem::path& path);
StereoDataset read_rosbag(const std::filesystem::path& path, const ReadOptions& options);
StereoDataset read_kitti(const std::filesystem::path& root, const ReadOptions& options);
StereoDataset read_euroc(const std::filesystem::path& root);

}  // namespace driftlab::dataset::detail
