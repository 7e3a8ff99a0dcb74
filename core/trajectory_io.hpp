// Trajectory and IMU files in the formats VO tools exchange: TUM, KITTI
// odometry poses, EuRoC/ASL ground truth and IMU CSVs.
//
// Readers are strict: every problem throws UserError
//   "PATH:LINE: <what is wrong>: got '<token>', expected <what>"
// (wrong column count, a non-number, NaN/Inf, a quaternion whose norm is off
// by more than kUnitTolerance, a KITTI matrix that is not a rotation, time
// stamps that do not strictly increase) or "PATH: cannot open for reading: <reason>".
// Smaller quaternion and rotation-matrix deviations are normalised away.
// Blank lines and lines starting with '#' are skipped; an empty file is an
// empty trajectory.
//
// Writers give the shortest text that reads back to the same double, time
// stamps exactly, and write through AtomicFile (nothing half-written on
// failure). They require finite values and strictly increasing stamps
// (DRIFTLAB_DEMAND), so that what they write can always be read back.
#pragma once

#include <array>
#include <filesystem>
#include <string_view>
#include <utility>
#include <vector>

#include "core/se3.hpp"
#include "core/time.hpp"

namespace driftlab {

/// A pose at a time stamp; T_W_C maps points from the camera (or body) frame into the world.
struct StampedPose {
  TimeNs t_ns = 0;
  SE3 T_W_C;
};

using Trajectory = std::vector<StampedPose>;

/// One IMU reading: angular rate of the sensor in its own frame [rad/s] and
/// specific force [m/s^2].
struct ImuSample {
  TimeNs t_ns = 0;
  Vec3 gyro_rad_s = Vec3::Zero();
  Vec3 accel_m_s2 = Vec3::Zero();
};

/// Largest accepted |norm(q) - 1| of a quaternion, and largest accepted entry
/// of |R^T R - I| of a KITTI rotation, before the value is normalised.
inline constexpr double kUnitTolerance = 1e-3;

enum class TrajectoryFormat { kTum, kKitti, kEuroc };

/// Names for the scenario reader (yaml::enum_name and friends).
constexpr auto enum_table(TrajectoryFormat) {
  return std::array{std::pair{TrajectoryFormat::kTum, "tum"},
                    std::pair{TrajectoryFormat::kKitti, "kitti"},
                    std::pair{TrajectoryFormat::kEuroc, "euroc"}};
}

/// "tum", "kitti" or "euroc" (any case); UserError listing these otherwise.
TrajectoryFormat format_from_name(std::string_view name);
/// The lower-case name format_from_name() accepts.
std::string_view format_name(TrajectoryFormat format);

// --- TUM: "t tx ty tz qx qy qz qw", t in decimal seconds, any whitespace.

Trajectory read_tum(const std::filesystem::path& path);
/// Writes a "# timestamp tx ty tz qx qy qz qw" header, then t with 9 decimals.
void write_tum(const std::filesystem::path& path, const Trajectory& trajectory);

// --- KITTI odometry: 12 numbers per line, the row-major 3x4 matrix [R | t]; no time.

/// Where the time stamps of a KITTI file come from, first match wins.
struct KittiTiming {
  /// One stamp per pose.
  std::vector<TimeNs> times_ns{};
  /// A KITTI times.txt: one time in seconds per line ("1.036630e-01" or "0.103663").
  std::filesystem::path times_path{};
  /// Else pose i is at i * period_ns (KITTI's cameras run at 10 Hz). Must be > 0.
  TimeNs period_ns = 100'000'000;
};

Trajectory read_kitti(const std::filesystem::path& path, const KittiTiming& timing = {});
/// Reads a KITTI times.txt (strictly increasing seconds, one per line).
std::vector<TimeNs> read_kitti_times(const std::filesystem::path& path);
/// Writes the poses only (KITTI carries no time; see write_kitti_times()).
void write_kitti(const std::filesystem::path& path, const Trajectory& trajectory);
/// Writes the stamps as a times.txt, seconds with 9 decimals.
void write_kitti_times(const std::filesystem::path& path, const Trajectory& trajectory);

// --- EuRoC / ASL CSV, time stamps in integer nanoseconds.

/// "#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []"
/// and any further columns (velocities, biases), which are ignored.
Trajectory read_euroc_groundtruth(const std::filesystem::path& path);
/// IMU biases at a ground-truth pose: gyroscope [rad/s] and accelerometer [m/s^2], in S.
struct ImuBias {
  Vec3 gyro = Vec3::Zero();
  Vec3 accel = Vec3::Zero();
};

/// Writes the 8 pose columns, plus v_RS_R_{x,y,z} [m s^-1] when `velocities_W_m_s` is
/// non-empty (then one per pose), plus EuRoC's b_w_RS_S_{x,y,z} [rad s^-1] and
/// b_a_RS_S_{x,y,z} [m s^-2] when `biases` is non-empty (then one per pose, and velocities too).
void write_euroc_groundtruth(const std::filesystem::path& path, const Trajectory& trajectory,
                             const std::vector<Vec3>& velocities_W_m_s = {},
                             const std::vector<ImuBias>& biases = {});

/// "#timestamp [ns],w_RS_S_x [rad s^-1],...,a_RS_S_z [m s^-2]": exactly 7 columns.
std::vector<ImuSample> read_euroc_imu(const std::filesystem::path& path);
void write_euroc_imu(const std::filesystem::path& path, const std::vector<ImuSample>& samples);

// --- Dispatch by format.

/// `kitti` is used only for TrajectoryFormat::kKitti.
Trajectory read_trajectory(const std::filesystem::path& path, TrajectoryFormat format,
                           const KittiTiming& kitti = {});
void write_trajectory(const std::filesystem::path& path, const Trajectory& trajectory,
                      TrajectoryFormat format);

}  // namespace driftlab
