// Stereo datasets in the layouts other VO and VIO tools read: KITTI odometry, EuRoC/ASL
// ("mav0") and TUM RGB-D. Writers turn a rendered sequence into one of them (`driftlab
// export`); readers give back what a stereo VO needs from one, exported or recorded
// (`driftlab vo`). Only images, calibration, time stamps, IMU and ground truth: no scenario,
// no simulation, so that a real dataset and an exported one go through the same code.
//
// Conventions, per format (each export's info.yaml says the same in words):
//  - KITTI odometry (devkit readme): sequences/NN/image_0|image_1/NNNNNN.png (left, right,
//    8-bit gray, rectified), calib.txt with P0..P3 (3x4 row-major projection matrices of the
//    rectified cameras, P1 = K [I | (-B, 0, 0)]), times.txt (seconds), poses/NN.txt (left
//    camera pose in the first left camera's frame, 12 numbers per line, first the identity).
//  - EuRoC/ASL (Burri et al. 2016): mav0/cam0|cam1/data/<t_ns>.png with data.csv and
//    sensor.yaml (intrinsics fu fv cu cv, distortion, T_BS = the camera in the body frame,
//    which is the IMU's), imu0/data.csv and sensor.yaml (Kalibr noise model),
//    state_groundtruth_estimate0/data.csv (body pose in the world, velocity).
//  - TUM RGB-D (Sturm et al. 2012): rgb/<t>.png, depth/<t>.png (16 bit, 5000 per metre, 0 =
//    no depth), rgb.txt, depth.txt, groundtruth.txt (left camera pose, TUM format).
//  - ROS 1 bag v2.0 (written and read with Debian's rosbag_storage): EuRoC's topic names
//    (/cam0/image_raw, /cam1/image_raw mono8, /imu0), camera_info, /gps/fix, /mag,
//    /compass/heading, /groundtruth/pose and /tf_static, with Kalibr's and VINS-Fusion's
//    calibration files beside the bag (rosbag.hpp says which frame is which).
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "core/trajectory_io.hpp"
#include "dataset/dataset_format.hpp"

namespace driftlab::dataset {

/// TUM RGB-D depth PNGs: 16-bit value = depth [m] * 5000; 0 means no depth.
inline constexpr double kTumDepthScale = 5000.0;

/// The IMU's Kalibr noise model (imu0/sensor.yaml of EuRoC).
struct ImuNoiseModel {
  double rate_hz = 0;                      ///< 0: no IMU in the dataset
  double gyroscope_noise_density = 0;      ///< rad/s/sqrt(Hz)
  double gyroscope_random_walk = 0;        ///< rad/s^2/sqrt(Hz)
  double accelerometer_noise_density = 0;  ///< m/s^2/sqrt(Hz)
  double accelerometer_random_walk = 0;    ///< m/s^3/sqrt(Hz)
  double gravity_m_s2 = 9.80665;           ///< the gravity it measures at rest (standard gravity)
};

/// One compass heading (driftlab's compass.csv: the sensor x axis's heading, clockwise from
/// north; wrapped to (-pi, pi] here).
struct CompassReading {
  TimeNs t_ns = 0;
  double heading_rad = 0;
  Vec3 field_S_nt = Vec3::Zero();  ///< measured field in the compass frame [nT]
};

/// What a writer needs besides the frames.
struct ExportCalibration {
  StereoRig rig;             ///< the rectified pair the images are in
  SE3 T_S_C;                 ///< left camera in the body frame (EuRoC: the IMU's)
  SE3 T_B_S;                 ///< the IMU in the vessel's body frame (FRD at the centre of gravity)
  std::optional<SE3> T_B_M;  ///< the compass in the vessel's body frame, when it has one
  std::optional<Vec3> p_B_gps;  ///< the GPS antenna in the vessel's body frame, when it has one
  double gps_sigma_horizontal_m = 0;  ///< the GPS's horizontal RMS is this times HDOP
  double camera_rate_hz = 0;
  ImuNoiseModel imu;
  std::string sequence = "00";  ///< KITTI sequence number
  std::string source;           ///< one line on where the data come from (info.yaml)
};

/// The body (IMU) frame's true state, for EuRoC's state_groundtruth_estimate0.
struct BodyState {
  TimeNs t_ns = 0;
  SE3 T_W_S;
  Vec3 v_W = Vec3::Zero();
  std::optional<ImuBias> bias;  ///< the simulated IMU's biases at t_ns (when it has one)
};

/// Ground truth and the other sensors, handed to a writer once every frame is in.
struct ExportTruth {
  Trajectory camera;            ///< true left-camera pose of each added frame, in order
  std::vector<BodyState> body;  ///< EuRoC only; may be empty
  /// The other sensors' CSVs, already written (imu.csv in EuRoC's IMU layout, driftlab's own
  /// gps.csv and compass.csv): each is moved into the dataset where its format keeps such
  /// streams (EuRoC: mav0/imu0/data.csv, gps0/, compass0/; KITTI and TUM: sensors/).
  std::vector<std::filesystem::path> sensor_csvs;
};

/// Writes one dataset into `root` (which must exist). Frames come in time order.
class DatasetWriter {
 public:
  virtual ~DatasetWriter() = default;
  /// left, right: 8-bit gray; depth_m: CV_32F metres (non-finite or <= 0: none), or empty.
  virtual void add_frame(TimeNs t_stamp_ns, const cv::Mat& left, const cv::Mat& right,
                         const cv::Mat& depth_m) = 0;
  /// Ground truth, calibration and info.yaml. Call once, after the last frame.
  virtual void finish(const ExportTruth& truth) = 0;
  /// Whether add_frame() wants the depth image.
  virtual bool wants_depth() const = 0;
};

std::unique_ptr<DatasetWriter> make_writer(DatasetFormat format, const std::filesystem::path& root,
                                           const ExportCalibration& calibration);

/// One stereo pair of a dataset: where its images are and when they were taken.
struct DatasetFrame {
  TimeNs t_ns = 0;
  std::filesystem::path left, right;  ///< image files (empty when the images are in a bag)
  TimeNs left_record_ns = 0, right_record_ns = 0;  ///< a bag's record times of the two images
};

/// Where a dataset's images are when they are not files of their own (a bag's messages).
class ImageSource {
 public:
  virtual ~ImageSource() = default;
  /// The raw pair of `frame`, 8-bit gray; UserError naming the container and topic otherwise.
  virtual std::pair<cv::Mat, cv::Mat> read(const DatasetFrame& frame) const = 0;
};

/// Pixel maps (cv::remap) from raw images to the rectified pair of a StereoDataset's rig.
struct Rectification {
  cv::Mat left_map1, left_map2, right_map1, right_map2;
};

/// What a stereo VO needs from a dataset, and the ground truth to judge it by.
struct StereoDataset {
  DatasetFormat format = DatasetFormat::kKitti;
  std::filesystem::path root;
  StereoRig rig;
  std::vector<DatasetFrame> frames;
  Trajectory camera_gt;  ///< left camera; empty when the dataset has none
  std::vector<ImuSample> imu;
  /// The IMU's Kalibr noise model (EuRoC imu0/sensor.yaml), when the dataset has one.
  std::optional<ImuNoiseModel> imu_noise;
  /// Compass headings (a driftlab EuRoC export's mav0/compass0/data.csv); usually empty.
  std::vector<CompassReading> compass;
  SE3 T_S_C;  ///< rectified left camera in the body frame (identity where unknown)
  bool has_extrinsics = false;  ///< whether T_S_C comes from the dataset (EuRoC's T_BS)
  /// Set when the images are raw (EuRoC with lens distortion or a rotated right camera): the
  /// pair is rectified as it is read (read_pair) with OpenCV's stereoRectify (zero disparity
  /// at infinity, no black border: alpha 0).
  std::shared_ptr<const Rectification> rectification;
  /// Set when the images are messages in a container (a bag): read_pair reads them there.
  std::shared_ptr<const ImageSource> images;
};

struct ReadOptions {
  std::string sequence = "00";  ///< KITTI: sequences/NN under the root
  /// ROS bags: the ground truth's topic (geometry_msgs PoseStamped, TransformStamped or
  /// nav_msgs/Odometry, the IMU's pose in the world); empty: the first of /groundtruth/pose
  /// (driftlab's) and /vicon/firefly_sbx/firefly_sbx (EuRoC's Vicon room) in the bag.
  std::string gt_topic;
  /// ROS bags: a Kalibr camera chain (kalibr_imucam_chain.yaml); empty: the one beside the bag.
  std::filesystem::path calibration;
};

/// Reads a dataset's index, calibration and ground truth (not the images). `root` is a folder,
/// or for kRosbag a .bag file (or a folder holding one). Strict: a missing
/// file, a malformed line or a pair that is not rectified throws UserError naming the file.
StereoDataset read_dataset(const std::filesystem::path& root, DatasetFormat format,
                           const ReadOptions& options = {});

/// An 8-bit gray image (colour is converted); UserError naming the file when it cannot be read.
cv::Mat read_gray(const std::filesystem::path& path);

/// The stereo pair of `frame` as the VOs take it: 8-bit gray, rectified for `data.rig`.
std::pair<cv::Mat, cv::Mat> read_pair(const StereoDataset& data, const DatasetFrame& frame);

/// driftlab's compass.csv ("#timestamp [ns],heading [deg],m_S_x [nT],m_S_y [nT],m_S_z [nT]",
/// stamps increasing, headings in [0, 360)); UserError naming the file and line otherwise.
std::vector<CompassReading> read_compass_csv(const std::filesystem::path& path);

/// The pose of `trajectory` (sorted) at time t: interpolated between the neighbours
/// (SE3::interpolate_decoupled), or nothing outside its time span.
std::optional<SE3> pose_at(const Trajectory& trajectory, TimeNs t_ns);

}  // namespace driftlab::dataset
