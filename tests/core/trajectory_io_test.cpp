#include "core/trajectory_io.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab {
namespace {
namespace fs = std::filesystem;

using driftlab::test::kEps;

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

// SE3 normalises its quaternion on construction, and that is not idempotent:
// for ~1.5 % of quaternions, dividing by the norm again flips the last bit back
// and forth. Only quaternions that are a fixed point of SE3's normalisation can
// survive write -> read -> SE3 bit for bit; the writer's text is exact for all
// (WrittenTextHoldsEveryBit), but the reader has to construct an SE3.
std::optional<SE3> settled_pose(const Quat& q, const Vec3& t) {
  SE3 pose(q, t);
  for (int i = 0; i < 4; ++i) {
    const SE3 again(pose.quaternion(), t);
    if (again.quaternion().coeffs() == pose.quaternion().coeffs()) return again;
    pose = again;
  }
  return std::nullopt;
}

// Translations over the whole double range, including the awkward ones.
Trajectory random_trajectory(std::uint64_t seed, int n, TimeNs t0_ns) {
  Rng rng = RngStreams(seed).stream("test.trajectory");
  const std::vector<double> special = {-0.0,
                                       0.1,
                                       1.0 / 3.0,
                                       std::numeric_limits<double>::denorm_min(),
                                       std::numeric_limits<double>::min(),
                                       std::numeric_limits<double>::max(),
                                       std::numeric_limits<double>::lowest(),
                                       -123456789.123456789};
  Trajectory out;
  TimeNs t = t0_ns;
  while (static_cast<int>(out.size()) < n) {
    const Quat q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t pick = rng.uniform_int(4);
      if (pick == 0) {
        p(k) = special[rng.uniform_int(special.size())];
      } else {
        const int exponent = static_cast<int>(rng.uniform_int(601)) - 300;
        p(k) = rng.normal() * std::pow(10.0, exponent);
      }
    }
    const std::optional<SE3> pose = settled_pose(q, p);
    if (!pose) continue;
    out.push_back({t, *pose});
    t += 1 + static_cast<TimeNs>(rng.uniform_int(3'000'000'000ULL));
  }
  return out;
}

class TrajectoryIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("driftlab_trajio_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write_text(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }

  static std::string read_text(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }

  std::vector<std::string> entries() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir_)) out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
  }

  // Runs `f`, expects UserError with exactly `message`.
  static void expect_error(const std::function<void()>& f, const std::string& message) {
    try {
      f();
      ADD_FAILURE() << "no exception, expected: " << message;
    } catch (const UserError& e) {
      EXPECT_EQ(std::string(e.what()), message);
    }
  }

  fs::path dir_;
};

void expect_bit_exact(const Trajectory& expected, const Trajectory& actual) {
  ASSERT_EQ(expected.size(), actual.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(expected[i].t_ns, actual[i].t_ns) << "pose " << i;
    for (int k = 0; k < 3; ++k)
      EXPECT_TRUE(same_bits(expected[i].T_W_C.translation()(k), actual[i].T_W_C.translation()(k)))
          << "pose " << i << " t(" << k << "): " << expected[i].T_W_C.translation()(k) << " vs "
          << actual[i].T_W_C.translation()(k);
    for (int k = 0; k < 4; ++k)
      EXPECT_TRUE(same_bits(expected[i].T_W_C.quaternion().coeffs()(k),
                            actual[i].T_W_C.quaternion().coeffs()(k)))
          << "pose " << i << " q(" << k << ")";
  }
}

// ---------------------------------------------------------------------------
// Round trips

TEST_F(TrajectoryIoTest, TumRoundTripIsBitExact) {
  const Trajectory traj = random_trajectory(1, 500, -5'000'000'001);
  const fs::path p = dir_ / "traj.tum";
  write_tum(p, traj);
  const Trajectory back = read_tum(p);
  expect_bit_exact(traj, back);
  // Writing what was read gives the same bytes.
  write_tum(dir_ / "again.tum", back);
  EXPECT_EQ(read_text(p), read_text(dir_ / "again.tum"));
  EXPECT_EQ(read_text(p).substr(0, 33), "# timestamp tx ty tz qx qy qz qw\n");
}

TEST_F(TrajectoryIoTest, WrittenTextHoldsEveryBit) {
  // Any quaternion, settled or not: the text parses (strtod, independent of the
  // reader) to exactly the doubles the SE3 holds.
  Rng rng(10);
  Trajectory traj;
  for (int i = 0; i < 2000; ++i) {
    const Quat q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
    const Vec3 p(rng.normal() * 1e-5, rng.normal(), rng.normal() * 1e9);
    traj.push_back({static_cast<TimeNs>(i), SE3(q, p)});
  }
  write_tum(dir_ / "t.tum", traj);
  std::istringstream in(read_text(dir_ / "t.tum"));
  std::string header;
  std::getline(in, header);
  for (const StampedPose& pose : traj) {
    std::string t;
    std::array<double, 7> v{};
    in >> t >> v[0] >> v[1] >> v[2] >> v[3] >> v[4] >> v[5] >> v[6];
    ASSERT_TRUE(in);
    EXPECT_EQ(t, format_seconds(pose.t_ns));
    const Vec3& p = pose.T_W_C.translation();
    const Quat& q = pose.T_W_C.quaternion();
    const std::array<double, 7> expected = {p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w()};
    for (int k = 0; k < 7; ++k) EXPECT_TRUE(same_bits(v[k], expected[k])) << "column " << k + 2;
  }
}

TEST_F(TrajectoryIoTest, EurocGroundTruthRoundTripIsBitExact) {
  const Trajectory traj = random_trajectory(2, 500, 1403636579758555392);
  write_euroc_groundtruth(dir_ / "gt.csv", traj);
  expect_bit_exact(traj, read_euroc_groundtruth(dir_ / "gt.csv"));

  // With velocities: 11 columns, the reader ignores the extra three.
  std::vector<Vec3> v;
  for (std::size_t i = 0; i < traj.size(); ++i) v.emplace_back(0.1 * i, -1.0 / 3.0, 2e-300);
  write_euroc_groundtruth(dir_ / "gt_v.csv", traj, v);
  expect_bit_exact(traj, read_euroc_groundtruth(dir_ / "gt_v.csv"));
  const std::string text = read_text(dir_ / "gt_v.csv");
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],"
            "q_RS_z [],v_RS_R_x [m s^-1],v_RS_R_y [m s^-1],v_RS_R_z [m s^-1]");
}

TEST_F(TrajectoryIoTest, EurocImuRoundTripIsBitExact) {
  Rng rng(3);
  std::vector<ImuSample> samples;
  TimeNs t = 1403636579758555392;
  for (int i = 0; i < 1000; ++i) {
    ImuSample s;
    s.t_ns = t;
    s.gyro_rad_s = Vec3(rng.normal(), rng.normal() * 1e-7, -0.0);
    s.accel_m_s2 = Vec3(rng.normal(0.0, 0.1), rng.normal(), 9.80665 + rng.normal());
    samples.push_back(s);
    t += 5'000'000 + static_cast<TimeNs>(rng.uniform_int(1000));
  }
  write_euroc_imu(dir_ / "imu.csv", samples);
  const std::vector<ImuSample> back = read_euroc_imu(dir_ / "imu.csv");
  ASSERT_EQ(back.size(), samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    EXPECT_EQ(back[i].t_ns, samples[i].t_ns);
    for (int k = 0; k < 3; ++k) {
      EXPECT_TRUE(same_bits(back[i].gyro_rad_s(k), samples[i].gyro_rad_s(k)));
      EXPECT_TRUE(same_bits(back[i].accel_m_s2(k), samples[i].accel_m_s2(k)));
    }
  }
  const std::string text = read_text(dir_ / "imu.csv");
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
            "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]");
}

TEST_F(TrajectoryIoTest, KittiRoundTripKeepsTranslationExactAndRotationToRounding) {
  const Trajectory traj = random_trajectory(4, 300, 0);
  write_kitti(dir_ / "poses.txt", traj);
  write_kitti_times(dir_ / "times.txt", traj);
  const Trajectory back = read_kitti(dir_ / "poses.txt", {.times_path = dir_ / "times.txt"});
  ASSERT_EQ(back.size(), traj.size());
  for (std::size_t i = 0; i < traj.size(); ++i) {
    EXPECT_EQ(back[i].t_ns, traj[i].t_ns);
    for (int k = 0; k < 3; ++k)
      EXPECT_TRUE(same_bits(back[i].T_W_C.translation()(k), traj[i].T_W_C.translation()(k)));
    // The file holds the matrix, not the quaternion: equal up to conversion rounding.
    EXPECT_LT((back[i].T_W_C.rotation() - traj[i].T_W_C.rotation()).cwiseAbs().maxCoeff(),
              8 * kEps);
  }
  // Each line is 12 numbers.
  const std::string text = read_text(dir_ / "poses.txt");
  const std::string first = text.substr(0, text.find('\n'));
  EXPECT_EQ(std::count(first.begin(), first.end(), ' '), 11);
}

TEST_F(TrajectoryIoTest, KittiTimesFromVectorOrPeriod) {
  const Trajectory traj = random_trajectory(5, 4, 0);
  write_kitti(dir_ / "poses.txt", traj);
  const Trajectory by_period = read_kitti(dir_ / "poses.txt");
  ASSERT_EQ(by_period.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i)
    EXPECT_EQ(by_period[i].t_ns, static_cast<TimeNs>(i) * 100'000'000);
  EXPECT_EQ(read_kitti(dir_ / "poses.txt", {.period_ns = 50'000'000})[3].t_ns, 150'000'000);
  const std::vector<TimeNs> times = {10, 20, 35, 1'000'000'000'000};
  const Trajectory by_vector = read_kitti(dir_ / "poses.txt", {.times_ns = times});
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(by_vector[i].t_ns, times[i]);
}

TEST_F(TrajectoryIoTest, DispatchersRoundTripEveryFormat) {
  const Trajectory traj = random_trajectory(6, 20, 1'000'000'000);
  for (const auto format :
       {TrajectoryFormat::kTum, TrajectoryFormat::kKitti, TrajectoryFormat::kEuroc}) {
    const fs::path p = dir_ / ("traj." + std::string(format_name(format)));
    write_trajectory(p, traj, format);
    KittiTiming timing;
    for (const auto& pose : traj) timing.times_ns.push_back(pose.t_ns);
    const Trajectory back = read_trajectory(p, format, timing);
    ASSERT_EQ(back.size(), traj.size()) << format_name(format);
    for (std::size_t i = 0; i < traj.size(); ++i) {
      EXPECT_EQ(back[i].t_ns, traj[i].t_ns);
      EXPECT_TRUE(back[i].T_W_C.is_approx(traj[i].T_W_C, 1e-300, 1e-14)) << format_name(format);
    }
  }
}

TEST_F(TrajectoryIoTest, WritersLeaveOnlyTheTarget) {
  const Trajectory traj = random_trajectory(7, 10, 0);
  write_tum(dir_ / "a.tum", traj);
  write_kitti(dir_ / "b.txt", traj);
  write_euroc_groundtruth(dir_ / "c.csv", traj);
  write_euroc_imu(dir_ / "d.csv", {ImuSample{}});
  EXPECT_EQ(entries(), (std::vector<std::string>{"a.tum", "b.txt", "c.csv", "d.csv"}));
}

TEST_F(TrajectoryIoTest, WriterToAMissingDirectoryThrowsAndLeavesNothing) {
  const fs::path p = dir_ / "missing" / "traj.tum";
  expect_error([&] { write_tum(p, random_trajectory(8, 3, 0)); },
               p.string() + ": cannot write: No such file or directory");
  EXPECT_TRUE(entries().empty());
}

TEST_F(TrajectoryIoTest, WritersRefuseWhatTheirReadersWouldReject) {
  Trajectory traj = random_trajectory(9, 3, 0);
  traj[2].t_ns = traj[1].t_ns;
  EXPECT_THROW(write_tum(dir_ / "dup.tum", traj), InternalError);
  traj = random_trajectory(9, 3, 0);
  traj[1].T_W_C = SE3(Quat::Identity(), Vec3(0.0, std::nan(""), 0.0));
  EXPECT_THROW(write_euroc_groundtruth(dir_ / "nan.csv", traj), InternalError);
  EXPECT_TRUE(entries().empty());
}

// ---------------------------------------------------------------------------
// Hand-written files with values worked out by hand

TEST_F(TrajectoryIoTest, TumHandWrittenFileParsesToKnownPoses) {
  // 0.70710678118654752 = sin 45 deg = cos 45 deg.
  const fs::path p = write_text("hand.tum",
                                "\xEF\xBB\xBF# timestamp tx ty tz qx qy qz qw\n"
                                "\n"
                                "1403636579.758555650 1.5 -2.25 3e-3 0 0 "
                                "0.70710678118654752 0.70710678118654752\n"
                                "   # indented comment\n"
                                // tabs, CRLF, norm off by 4e-4
                                "1403636580\t\t0  0\t0   0 0 0 1.0004  \r\n"
                                "1403636580.5 +1 -0 1e2 -1 0 0 0\n");
  const Trajectory traj = read_tum(p);
  ASSERT_EQ(traj.size(), 3u);

  EXPECT_EQ(traj[0].t_ns, 1403636579758555650);
  EXPECT_EQ(traj[0].T_W_C.translation(), Vec3(1.5, -2.25, 0.003));
  // 90 deg about z: x -> y, y -> -x.
  EXPECT_LT((traj[0].T_W_C.rotation() * Vec3::UnitX() - Vec3::UnitY()).norm(), 4 * kEps);
  EXPECT_LT((traj[0].T_W_C.rotation() * Vec3::UnitY() + Vec3::UnitX()).norm(), 4 * kEps);

  EXPECT_EQ(traj[1].t_ns, 1403636580'000000000);
  EXPECT_EQ(traj[1].T_W_C.translation(), Vec3::Zero());
  EXPECT_LT((traj[1].T_W_C.quaternion().coeffs() - Quat::Identity().coeffs()).norm(), 2 * kEps)
      << "normalised";

  EXPECT_EQ(traj[2].t_ns, 1403636580'500000000);
  EXPECT_EQ(traj[2].T_W_C.translation(), Vec3(1.0, 0.0, 100.0));
  EXPECT_EQ(traj[2].T_W_C.quaternion().coeffs(), Quat(0, -1, 0, 0).coeffs());  // 180 deg about x
}

TEST_F(TrajectoryIoTest, EurocHandWrittenFileParsesToKnownPoses) {
  // A real EuRoC file has 17 columns (and spaces after the commas in its header).
  const fs::path p = write_text(
      "gt.csv",
      "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
      "q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], "
      "b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
      "b_a_RS_S_z [m s^-2]\n"
      "1403636580838555648,4.688319,-1.786938,0.783338,0.5,0.5,0.5,0.5,-0.027876,0.033207,"
      "0.800006,-0.003172,0.021267,0.078502,-0.025266,0.136696,0.075593\r\n"
      "1403636580843555328, 1 , 2 , 3 ,1,0,0,0\n");
  const Trajectory traj = read_euroc_groundtruth(p);
  ASSERT_EQ(traj.size(), 2u);
  EXPECT_EQ(traj[0].t_ns, 1403636580838555648);
  EXPECT_EQ(traj[0].T_W_C.translation(), Vec3(4.688319, -1.786938, 0.783338));
  // w = x = y = z = 1/2 is 120 deg about (1,1,1): it cycles the axes x -> y -> z -> x.
  EXPECT_LT((traj[0].T_W_C.rotation() * Vec3::UnitX() - Vec3::UnitY()).norm(), 4 * kEps);
  EXPECT_LT((traj[0].T_W_C.rotation() * Vec3::UnitY() - Vec3::UnitZ()).norm(), 4 * kEps);
  EXPECT_EQ(traj[1].t_ns, 1403636580843555328);
  EXPECT_EQ(traj[1].T_W_C.translation(), Vec3(1, 2, 3));
  EXPECT_EQ(traj[1].T_W_C.quaternion().coeffs(), Quat::Identity().coeffs());
}

TEST_F(TrajectoryIoTest, EurocImuHandWritten) {
  const fs::path p = write_text("imu.csv",
                                "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],"
                                "w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],"
                                "a_RS_S_z [m s^-2]\n"
                                "1403636579758555392,-0.099134701513277898,0.14730578886832138,"
                                "0.02722713633111154,8.1476917083333333,-0.37592158333333331,"
                                "-2.4026292499999999\n");
  const std::vector<ImuSample> imu = read_euroc_imu(p);
  ASSERT_EQ(imu.size(), 1u);
  EXPECT_EQ(imu[0].t_ns, 1403636579758555392);
  EXPECT_EQ(imu[0].gyro_rad_s,
            Vec3(-0.099134701513277898, 0.14730578886832138, 0.02722713633111154));
  EXPECT_EQ(imu[0].accel_m_s2, Vec3(8.1476917083333333, -0.37592158333333331, -2.4026292499999999));
}

TEST_F(TrajectoryIoTest, KittiRotationMatrixGivesTheHandComputedQuaternion) {
  // R = Rz(90 deg) = [0 -1 0; 1 0 0; 0 0 1], t = (1, 2, 3); by hand
  // q = (cos 45, 0, 0, sin 45) = (w, x, y, z) = (1/sqrt2, 0, 0, 1/sqrt2).
  // The second line is KITTI's own 6-digit style, orthonormal only to ~1e-6.
  const fs::path p = write_text("poses.txt",
                                "0 -1 0 1 1 0 0 2 0 0 1 3\n"
                                "1.000000e+00 9.043680e-12 2.326809e-11 5.551115e-17 "
                                "9.043683e-12 1.000000e+00 2.392370e-10 3.330669e-16 "
                                "2.326810e-11 2.392370e-10 9.999999e-01 -4.440892e-16\n");
  const Trajectory traj = read_kitti(p);
  ASSERT_EQ(traj.size(), 2u);
  Quat q = traj[0].T_W_C.quaternion();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const double h = std::sqrt(0.5);
  EXPECT_NEAR(q.w(), h, 2 * kEps);
  EXPECT_NEAR(q.x(), 0.0, 2 * kEps);
  EXPECT_NEAR(q.y(), 0.0, 2 * kEps);
  EXPECT_NEAR(q.z(), h, 2 * kEps);
  EXPECT_EQ(traj[0].T_W_C.translation(), Vec3(1, 2, 3));
  EXPECT_EQ(traj[1].T_W_C.translation(), Vec3(5.551115e-17, 3.330669e-16, -4.440892e-16));
  EXPECT_LT(std::abs(traj[1].T_W_C.quaternion().w()), 1.0 + 1e-15);
  EXPECT_GT(std::abs(traj[1].T_W_C.quaternion().w()), 1.0 - 1e-9);
}

TEST_F(TrajectoryIoTest, KittiTimesTxtInScientificNotation) {
  const fs::path p = write_text("times.txt", "0.000000e+00\n1.036630e-01\n2.073220e-01\n");
  EXPECT_EQ(read_kitti_times(p), (std::vector<TimeNs>{0, 103'663'000, 207'322'000}));
}

TEST_F(TrajectoryIoTest, EmptyAndCommentOnlyFilesAreEmptyTrajectories) {
  EXPECT_TRUE(read_tum(write_text("empty.tum", "")).empty());
  EXPECT_TRUE(read_euroc_groundtruth(write_text("c.csv", "#timestamp,...\n\n  \n")).empty());
  EXPECT_TRUE(read_kitti(write_text("k.txt", "\n")).empty());
}

TEST_F(TrajectoryIoTest, FormatNames) {
  EXPECT_EQ(format_from_name("tum"), TrajectoryFormat::kTum);
  EXPECT_EQ(format_from_name("KITTI"), TrajectoryFormat::kKitti);
  EXPECT_EQ(format_from_name("EuRoC"), TrajectoryFormat::kEuroc);
  for (const auto f : {TrajectoryFormat::kTum, TrajectoryFormat::kKitti, TrajectoryFormat::kEuroc})
    EXPECT_EQ(format_from_name(format_name(f)), f);
  expect_error([] { format_from_name("tum2"); },
               "unknown trajectory format: got 'tum2', expected one of: tum, kitti, euroc");
}

// ---------------------------------------------------------------------------
// Errors: file, line, offending token and what was expected

TEST_F(TrajectoryIoTest, MissingFile) {
  const fs::path p = dir_ / "nope.tum";
  expect_error([&] { read_tum(p); },
               p.string() + ": cannot open for reading: No such file or directory");
  expect_error([&] { read_tum(dir_); },
               dir_.string() + ": cannot open for reading: Is a directory");
}

TEST_F(TrajectoryIoTest, TumWrongColumnCount) {
  const fs::path p = write_text("t.tum", "# header\n1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n");
  expect_error([&] { read_tum(p); },
               p.string() +
                   ":3: wrong number of columns (7): got '2 0 0 0 0 0 1', expected 8 columns "
                   "(t tx ty tz qx qy qz qw)");
}

TEST_F(TrajectoryIoTest, TumNotANumber) {
  const fs::path p = write_text("t.tum", "1 0 0 0 0 0 0 1\n2 0 abc 0 0 0 0 1\n");
  expect_error(
      [&] { read_tum(p); },
      p.string() + ":2: column 3 (ty) is not a number: got 'abc', expected a decimal number");
  const fs::path q = write_text("u.tum", "1 0 0 0 0 0 0 1x\n");
  expect_error(
      [&] { read_tum(q); },
      q.string() + ":1: column 8 (qw) is not a number: got '1x', expected a decimal number");
}

TEST_F(TrajectoryIoTest, TumNanAndInf) {
  const fs::path p = write_text("t.tum", "1 nan 0 0 0 0 0 1\n");
  expect_error([&] { read_tum(p); },
               p.string() + ":1: column 2 (tx) is not finite: got 'nan', expected a finite number");
  const fs::path q = write_text("u.tum", "\n\n1 0 0 -inf 0 0 0 1\n");
  expect_error(
      [&] { read_tum(q); },
      q.string() + ":3: column 4 (tz) is not finite: got '-inf', expected a finite number");
  const fs::path r = write_text("v.tum", "inf 0 0 0 0 0 0 1\n");
  expect_error([&] { read_tum(r); }, r.string() +
                                         ":1: column 1 (t) is not finite: got 'inf', expected a "
                                         "finite time in seconds");
  const fs::path s = write_text("w.tum", "1 1e400 0 0 0 0 0 1\n");
  expect_error([&] { read_tum(s); }, s.string() +
                                         ":1: column 2 (tx) is out of range: got '1e400', expected "
                                         "a number within double range");
}

TEST_F(TrajectoryIoTest, TumBadTime) {
  const fs::path p = write_text("t.tum", "12:30 0 0 0 0 0 0 1\n");
  expect_error([&] { read_tum(p); },
               p.string() +
                   ":1: column 1 (t) is not a time: got '12:30', expected seconds such as "
                   "1403636579.758555650 (within +-292 years)");
}

TEST_F(TrajectoryIoTest, TumNonUnitQuaternion) {
  const fs::path p = write_text("t.tum", "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1.5\n");
  expect_error([&] { read_tum(p); },
               p.string() +
                   ":2: quaternion is not unit length (norm 1.5): got '0 0 0 1.5', expected a norm "
                   "within 0.001 of 1");
  // Just outside the tolerance.
  const fs::path q = write_text("u.tum", "1 0 0 0 0 0 0 0.9985\n");
  EXPECT_THROW(read_tum(q), UserError);
}

TEST_F(TrajectoryIoTest, TumTimeMustStrictlyIncrease) {
  const fs::path p = write_text("t.tum",
                                "1.5 0 0 0 0 0 0 1\n"
                                "# comment\n"
                                "1.500000000 0 0 0 0 0 0 1\n");
  expect_error([&] { read_tum(p); },
               p.string() +
                   ":3: time stamp does not increase: got '1.500000000', expected a time after "
                   "'1.5' (line 1)");
  const fs::path q = write_text("u.tum", "2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n");
  expect_error([&] { read_tum(q); }, q.string() +
                                         ":2: time stamp does not increase: got '1', expected a "
                                         "time after '2' (line 1)");
}

TEST_F(TrajectoryIoTest, KittiWrongColumnCount) {
  const fs::path p = write_text("k.txt", "1 0 0 0 0 1 0 0 0 0 1\n");
  expect_error([&] { read_kitti(p); },
               p.string() +
                   ":1: wrong number of columns (11): got '1 0 0 0 0 1 0 0 0 0 1', expected 12 "
                   "columns (r11 r12 r13 tx r21 r22 r23 ty r31 r32 r33 tz)");
}

TEST_F(TrajectoryIoTest, KittiNotARotation) {
  const fs::path p = write_text("k.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n2 0 0 0 0 2 0 0 0 0 2 0\n");
  expect_error([&] { read_kitti(p); },
               p.string() +
                   ":2: rotation part is not a rotation matrix (max |R^T R - I| = 3, det = 8): got "
                   "'2 0 0 0 2 0 0 0 2', expected an orthonormal matrix with determinant +1 "
                   "(within 0.001)");
  const fs::path q = write_text("m.txt", "-1 0 0 0 0 1 0 0 0 0 1 0\n");  // a reflection
  expect_error(
      [&] { read_kitti(q); },
      q.string() +
          ":1: rotation part is not a rotation matrix (max |R^T R - I| = 0, det = -1): got "
          "'-1 0 0 0 1 0 0 0 1', expected an orthonormal matrix with determinant +1 "
          "(within 0.001)");
  const fs::path r = write_text("n.txt", "1 0 0 0 0 1 0 nan 0 0 1 0\n");
  expect_error([&] { read_kitti(r); },
               r.string() + ":1: column 8 (ty) is not finite: got 'nan', expected a finite number");
}

TEST_F(TrajectoryIoTest, KittiTimesMustMatchThePoses) {
  const fs::path p = write_text("k.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  const fs::path t = write_text("times.txt", "0.0\n0.1\n0.2\n");
  expect_error([&] { read_kitti(p, {.times_path = t}); },
               p.string() +
                   ": pose count does not match the time stamps: got '2' poses, expected 3 (one "
                   "per time stamp in " +
                   t.string() + ")");
  const fs::path u = write_text("times2.txt", "0.0\n0.0\n");
  expect_error([&] { read_kitti(p, {.times_path = u}); },
               u.string() +
                   ":2: time stamp does not increase: got '0.0', expected a time after '0.0' "
                   "(line 1)");
  expect_error(
      [&] {
        read_kitti(p, {.times_ns = {5, 5}});
      },
      p.string() +
          ": time stamps do not increase at pose 1: got '0.000000005', expected a time "
          "after 0.000000005 (the given time stamps)");
  expect_error(
      [&] { read_kitti(p, {.period_ns = 0}); },
      p.string() + ": cannot assign time stamps: got period '0' ns, expected a period > 0");
}

TEST_F(TrajectoryIoTest, EurocErrors) {
  const fs::path p = write_text("gt.csv", "#timestamp,...\n1,0,0,0,1,0,0\n");
  expect_error([&] { read_euroc_groundtruth(p); },
               p.string() +
                   ":2: wrong number of columns (7): got '1,0,0,0,1,0,0', expected at least 8 "
                   "columns (#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x "
                   "[],q_RS_y [],q_RS_z [])");
  const fs::path q = write_text("gt2.csv", "1.4e18,0,0,0,1,0,0,0\n");
  expect_error([&] { read_euroc_groundtruth(q); },
               q.string() +
                   ":1: column 1 (#timestamp) is not an integer time stamp: got '1.4e18', expected "
                   "an integer number of nanoseconds such as 1403636579758555392");
  const fs::path r = write_text("gt3.csv", "1,0,0,0,NaN,0,0,0\n");
  expect_error(
      [&] { read_euroc_groundtruth(r); },
      r.string() + ":1: column 5 (q_RS_w []) is not finite: got 'NaN', expected a finite number");
  const fs::path s = write_text("gt4.csv", "1,0,0,0,0.5,0,0,0\n");
  expect_error([&] { read_euroc_groundtruth(s); },
               s.string() +
                   ":1: quaternion is not unit length (norm 0.5): got '0.5,0,0,0', expected a norm "
                   "within 0.001 of 1");
  const fs::path t = write_text("gt5.csv", "10,0,0,0,1,0,0,0\n9,0,0,0,1,0,0,0\n");
  expect_error(
      [&] { read_euroc_groundtruth(t); },
      t.string() +
          ":2: time stamp does not increase: got '9', expected a time after '10' (line 1)");
}

TEST_F(TrajectoryIoTest, EurocImuErrors) {
  const fs::path p = write_text("imu.csv", "#timestamp [ns],...\n1,0,0,0,0,0,9.8,7\n");
  expect_error([&] { read_euroc_imu(p); },
               p.string() +
                   ":2: wrong number of columns (8): got '1,0,0,0,0,0,9.8,7', expected 7 columns "
                   "(#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad "
                   "s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2])");
  const fs::path q = write_text("imu2.csv", "1,0,0,0,0,0,9.8\n1,0,0,0,0,0,9.8\n");
  expect_error(
      [&] { read_euroc_imu(q); },
      q.string() + ":2: time stamp does not increase: got '1', expected a time after '1' (line 1)");
  const fs::path r = write_text("imu3.csv", "1,0,0,0,0,,9.8\n");
  expect_error([&] { read_euroc_imu(r); },
               r.string() +
                   ":1: column 6 (a_RS_S_y [m s^-2]) is not a number: got '', expected a decimal "
                   "number");
}

TEST_F(TrajectoryIoTest, LongLinesAreCutInMessages) {
  const std::string junk(500, 'z');
  const fs::path p = write_text("t.tum", junk + "\n");
  try {
    read_tum(p);
    FAIL();
  } catch (const UserError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(p.string() + ":1: wrong number of columns (1): got 'zzz"),
              std::string::npos);
    EXPECT_NE(what.find("zzz...'"), std::string::npos);
    EXPECT_LT(what.size(), 300u);
  }
}

}  // namespace
}  // namespace driftlab
