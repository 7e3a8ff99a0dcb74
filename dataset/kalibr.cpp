// Calibration files of the tools that read bags: Kalibr's camera and IMU chains (as OpenVINS
// and Kimera read them; github.com/ethz-asl/kalibr/wiki/yaml-formats) and
// VINS-Fusion's EuRoC-style configuration (OpenCV FileStorage YAML). Writers and the camera
// chain's reader.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>

#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/yaml_io.hpp"
#include "dataset/dataset_detail.hpp"
#include "dataset/rosbag.hpp"

namespace driftlab::dataset::detail {
namespace fs = std::filesystem;
namespace names = rosbag_names;
namespace {

std::string g(double x) { return yaml::format_double(x); }

// to[to_key] = from[from_key] when `from` has that key (marks, for line numbers, kept).
void copy_key(const YAML::Node& from, const char* from_key, YAML::Node* to, const char* to_key) {
  if (from[from_key]) (*to)[to_key] = from[from_key];
}

// A matrix as Kalibr writes it: a block list of rows, `indent` spaces in.
std::string kalibr_rows(const Eigen::MatrixXd& m, int indent) {
  std::string out;
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    out += fmt::format("{:{}}- [{}]\n", "", indent, matrix_text(m.row(r), ", "));
  return out;
}

// The first lines of a Kalibr chain: a YAML directive, which OpenCV's FileStorage (OpenVINS's
// reader) needs as the file's first bytes to take it for YAML, and which YAML 1.1 readers
// (Kalibr's Python, yaml-cpp) accept before a document marker.
constexpr const char* kKalibrHead = "%YAML 1.0\n---\n";

std::string opencv_matrix(const SE3& T) {
  return fmt::format("!!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n   data: [{}]\n",
                     matrix_text(matrix_4x4(T), ", "));
}

SE3 T_C0_C1(const ExportCalibration& cal) {
  return SE3(Mat3::Identity(), Vec3(cal.rig.baseline_m, 0, 0));
}

// T_cam_imu or (OpenVINS's) T_imu_cam of a Kalibr camera: the camera in the IMU frame.
SE3 kalibr_T_B_C(const YAML::Node& cam, const fs::path& path, const std::string& name) {
  const bool inverse = static_cast<bool>(cam["T_cam_imu"]);
  const YAML::Node rows = cam[inverse ? "T_cam_imu" : "T_imu_cam"];
  const std::string key = name + (inverse ? ".T_cam_imu" : ".T_imu_cam");
  if (!rows || !rows.IsSequence() || rows.size() != 4)
    throw UserError(fmt::format("{}: {}: expected 4 rows of 4 numbers (T_cam_imu or T_imu_cam)",
                                path.string(), key));
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    YAML::Node holder;
    holder["row"] = rows[r];
    const std::vector<double> v = yaml_numbers(holder, "row", 4, path);
    for (int c = 0; c < 4; ++c) m(r, c) = v[static_cast<std::size_t>(c)];
  }
  const Mat3 R = m.topLeftCorner<3, 3>();
  if ((R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff() > 1e-3 || R.determinant() < 0)
    throw UserError(fmt::format("{}: {}: the rotation part is not a rotation", path.string(), key));
  const Eigen::JacobiSVD<Mat3> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const SE3 T(Quat(Mat3(svd.matrixU() * svd.matrixV().transpose())), m.topRightCorner<3, 1>());
  return inverse ? T.inverse() : T;
}

}  // namespace

std::string kalibr_imucam_chain_yaml(const ExportCalibration& cal) {
  const PinholeCamera& c = cal.rig.camera;
  std::string out = fmt::format(
      "{}# driftlab export ({}): the rectified pair, Kalibr's camera chain (T_cam_imu, and its "
      "inverse T_imu_cam, which OpenVINS reads)\n",
      kKalibrHead, cal.source);
  for (int i = 0; i < 2; ++i) {
    const SE3 T_S_Ci = i == 0 ? cal.T_S_C : cal.T_S_C * T_C0_C1(cal);
    out += fmt::format("cam{}:\n  T_cam_imu:\n{}  T_imu_cam:\n{}", i,
                       kalibr_rows(matrix_4x4(T_S_Ci.inverse()), 4),
                       kalibr_rows(matrix_4x4(T_S_Ci), 4));
    if (i == 1) out += "  T_cn_cnm1:\n" + kalibr_rows(matrix_4x4(T_C0_C1(cal).inverse()), 4);
    out += fmt::format(
        "  cam_overlaps: [{}]\n  camera_model: pinhole\n  distortion_coeffs: [0.0, 0.0, 0.0, "
        "0.0]\n  distortion_model: radtan\n  intrinsics: [{}, {}, {}, {}]\n  resolution: [{}, "
        "{}]\n  rostopic: {}\n  timeshift_cam_imu: 0.0\n",
        1 - i, g(c.fx), g(c.fy), g(c.cx), g(c.cy), c.width, c.height, names::kImage[i]);
  }
  return out;
}

std::string kalibr_imu_chain_yaml(const ImuNoiseModel& m) {
  // OpenVINS requires its intrinsic matrices beside Kalibr's keys (gyroscope Tw and
  // R_IMUtoGYRO, accelerometer Ta and R_IMUtoACC, g-sensitivity Tg): the nominal ones here.
  const std::string I = kalibr_rows(Mat3::Identity(), 4), zero = kalibr_rows(Mat3::Zero(), 4);
  return fmt::format(
      "{}# driftlab export: the scenario's IMU, Kalibr's IMU chain (continuous-time densities), "
      "with OpenVINS's nominal intrinsics\n"
      "imu0:\n  T_i_b:\n{}  accelerometer_noise_density: {}\n  accelerometer_random_walk: {}\n"
      "  gyroscope_noise_density: {}\n  gyroscope_random_walk: {}\n  model: calibrated\n"
      "  rostopic: {}\n  time_offset: 0.0\n  update_rate: {}\n  Tw:\n{}  R_IMUtoGYRO:\n{}"
      "  Ta:\n{}  R_IMUtoACC:\n{}  Tg:\n{}",
      kKalibrHead, kalibr_rows(matrix_4x4(SE3()), 4), g(m.accelerometer_noise_density),
      g(m.accelerometer_random_walk), g(m.gyroscope_noise_density), g(m.gyroscope_random_walk),
      names::kImu, g(m.rate_hz), I, I, I, I, zero);
}

std::vector<std::pair<std::string, std::string>> vins_fusion_files(const ExportCalibration& cal) {
  const PinholeCamera& c = cal.rig.camera;
  std::vector<std::pair<std::string, std::string>> files;
  for (int i = 0; i < 2; ++i)
    files.emplace_back(
        fmt::format("cam{}_pinhole.yaml", i),
        fmt::format("%YAML:1.0\n---\nmodel_type: PINHOLE\ncamera_name: cam{}\nimage_width: {}\n"
                    "image_height: {}\ndistortion_parameters:\n   k1: 0.\n   k2: 0.\n   p1: 0.\n"
                    "   p2: 0.\nprojection_parameters:\n   fx: {}\n   fy: {}\n   cx: {}\n"
                    "   cy: {}\n",
                    i, c.width, c.height, g(c.fx), g(c.fy), g(c.cx), g(c.cy)));
  const ImuNoiseModel& m = cal.imu;
  // A density sigma_c [unit/sqrt(Hz)] gives sigma_c^2 dt of variance over a sample period dt;
  // VINS-Fusion's sigma per sample gives sigma^2 dt^2, so sigma = sigma_c / sqrt(dt).
  const double per_sample = std::sqrt(m.rate_hz);
  files.emplace_back(
      "stereo_imu_config.yaml",
      fmt::format(
          "%YAML:1.0\n---\n# driftlab export ({}): VINS-Fusion's stereo + IMU configuration\n"
          "imu: 1\nnum_of_cam: 2\nimu_topic: \"{}\"\nimage0_topic: \"{}\"\n"
          "image1_topic: \"{}\"\noutput_path: \"/tmp/vins_output\"\n"
          "cam0_calib: \"cam0_pinhole.yaml\"\ncam1_calib: \"cam1_pinhole.yaml\"\n"
          "image_width: {}\nimage_height: {}\n"
          "# the cameras in the body (IMU) frame, known exactly\nestimate_extrinsic: 0\n"
          "body_T_cam0: {}body_T_cam1: {}"
          "# 1 would hand the estimator every second image (estimator.cpp's inputImageCnt % 2),\n"
          "# VINS-Fusion's EuRoC setting for a 20 Hz camera: below 20 Hz every image, one thread\n"
          "multiple_thread: {}\nmax_cnt: 150\nmin_dist: 30\nfreq: 10\nF_threshold: 1.0\n"
          "show_track: 0\nflow_back: 1\nmax_solver_time: 0.04\nmax_num_iterations: 8\n"
          "keyframe_parallax: 10.0\n"
          "# the scenario's IMU noise per IMU sample, as VINS-Fusion takes it (its preintegration "
          "adds sigma^2 dt^2 a step): Kalibr's densities times sqrt(rate), {} Hz (VINS-Fusion's "
          "own configs inflate them); the twin's gravity\nacc_n: {}\ngyr_n: {}\nacc_w: {}\n"
          "gyr_w: {}\ng_norm: {}\n"
          "estimate_td: 0\ntd: 0.0\nload_previous_pose_graph: 0\n"
          "pose_graph_save_path: \"/tmp/vins_output/pose_graph/\"\nsave_image: 0\n",
          cal.source, names::kImu, names::kImage[0], names::kImage[1], c.width, c.height,
          opencv_matrix(cal.T_S_C), opencv_matrix(cal.T_S_C * T_C0_C1(cal)),
          cal.camera_rate_hz >= 20 ? 1 : 0, g(m.rate_hz),
          g(m.accelerometer_noise_density * per_sample), g(m.gyroscope_noise_density * per_sample),
          g(m.accelerometer_random_walk * per_sample), g(m.gyroscope_random_walk * per_sample),
          g(m.gravity_m_s2)));
  return files;
}

KalibrChain read_kalibr_camchain(const fs::path& path) {
  const std::string text = read_text_file(path, "Kalibr camera chain");
  KalibrChain chain;
  try {
    const YAML::Node root = YAML::Load(text);
    for (int i = 0; i < 2; ++i) {
      const std::string name = fmt::format("cam{}", i);
      const YAML::Node cam = root.IsMap() ? root[name] : YAML::Node();
      if (!cam || !cam.IsMap())
        throw UserError(fmt::format("{}: {}: missing, expected a camera of the stereo pair",
                                    path.string(), name));
      const std::string model =
          cam["camera_model"] && cam["camera_model"].IsScalar() ? cam["camera_model"].Scalar() : "";
      if (model != "pinhole")
        throw UserError(fmt::format("{}: {}.camera_model: got '{}', expected pinhole",
                                    path.string(), name, model));
      YAML::Node euroc = YAML::Node(YAML::NodeType::Map);  // the camera under EuRoC's keys
      copy_key(cam, "intrinsics", &euroc, "intrinsics");
      copy_key(cam, "resolution", &euroc, "resolution");
      copy_key(cam, "distortion_coeffs", &euroc, "distortion_coefficients");
      copy_key(cam, "distortion_model", &euroc, "distortion_model");
      CameraCalibration& c = chain.cameras[static_cast<std::size_t>(i)];
      c = camera_from_keys(euroc, path, name + ".");
      c.T_B_C = kalibr_T_B_C(cam, path, name);
      if (cam["rostopic"] && cam["rostopic"].IsScalar())
        chain.topics[static_cast<std::size_t>(i)] = cam["rostopic"].Scalar();
    }
  } catch (const YAML::Exception& e) {
    throw UserError(fmt::format("{}:{}: {}", path.string(), e.mark.line + 1, e.msg));
  }
  return chain;
}

ImuNoiseModel read_kalibr_imu_chain(const fs::path& path) {
  const std::string text = read_text_file(path, "Kalibr IMU chain");
  try {
    const YAML::Node root = YAML::Load(text);
    const YAML::Node imu = root.IsMap() ? root["imu0"] : YAML::Node();
    if (!imu || !imu.IsMap())
      throw UserError(path.string() + ": imu0: missing, expected the IMU's noise model");
    YAML::Node euroc = YAML::Node(YAML::NodeType::Map);  // EuRoC's keys
    for (const char* key : {"gyroscope_noise_density", "gyroscope_random_walk",
                            "accelerometer_noise_density", "accelerometer_random_walk"})
      copy_key(imu, key, &euroc, key);
    copy_key(imu, "update_rate", &euroc, "rate_hz");
    return imu_noise_from_keys(euroc, path, "imu0.");
  } catch (const YAML::Exception& e) {
    throw UserError(fmt::format("{}:{}: {}", path.string(), e.mark.line + 1, e.msg));
  }
}

}  // namespace driftlab::dataset::detail
