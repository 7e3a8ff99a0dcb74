#include "eval/sections.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "core/error.hpp"

namespace driftlab::eval {
namespace {

constexpr double kSectionsTol = 1e-12;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A camera looking north (optical z = world x) and level: optical x -> east,
// optical y -> down. This is the world orientation of the camera FRD axes = identity.
SE3 camera_at(const Vec3& p, double yaw_rad = 0.0) {
  const Mat3 R_W_F = Eigen::AngleAxisd(yaw_rad, Vec3::UnitZ()).toRotationMatrix();
  return SE3(Mat3(R_W_F * R_optical_frd().transpose()), p);
}

struct Straight {
  std::vector<TimeNs> t;
  std::vector<SE3> gt, est;
};

// 21 poses, 1 m apart northwards, 0.5 s apart.
Straight straight_sections(double est_scale, double est_yaw_drift_rad_per_frame) {
  Straight s;
  for (int i = 0; i <= 20; ++i) {
    s.t.push_back(static_cast<TimeNs>(i) * 500'000'000);
    s.gt.push_back(camera_at(Vec3(i, 0, 0)));
    s.est.push_back(camera_at(Vec3(est_scale * i, 0, 0), est_yaw_drift_rad_per_frame * i));
  }
  return s;
}

TEST(Sections, CutsAtTheFirstPoseAtOrPastTheLength) {
  const auto s = straight_sections(1.0, 0.0);
  const auto sections = compute_sections(s.t, s.gt, s.est, {6.5});
  // Poses at 0..20 m: sections [0,7] and [7,14]; [14, 20] is shorter than 6.5 m.
  ASSERT_EQ(sections.size(), 2u);
  EXPECT_EQ(sections[0].first, 0u);
  EXPECT_EQ(sections[0].last, 7u);
  EXPECT_EQ(sections[1].first, 7u);
  EXPECT_EQ(sections[1].last, 14u);
  EXPECT_DOUBLE_EQ(sections[0].length_m, 7.0);
  EXPECT_NEAR(sections[0].err_p_m, 0.0, kSectionsTol);
  EXPECT_NEAR(sections[0].covariate("v"), 7.0 / 3.5, kSectionsTol);
  EXPECT_NEAR(sections[0].covariate("h"), 0.0, kSectionsTol);
}

TEST(Sections, ScaleErrorGivesItsFractionPerMetre) {
  const auto s = straight_sections(1.1, 0.0);
  const auto sections = compute_sections(s.t, s.gt, s.est, {6.5});
  ASSERT_EQ(sections.size(), 2u);
  for (const auto& sec : sections) {
    // Eq. (10) along the optical axis (FRD x): 7 - 7.7 m.
    EXPECT_NEAR(sec.per_m(sec.err_m.x()), -0.1, kSectionsTol);
    EXPECT_NEAR(sec.per_m(sec.err_m.y()), 0.0, kSectionsTol);
    EXPECT_NEAR(sec.per_m(sec.err_p_m), 0.1, kSectionsTol);
  }
  const SectionSummary sum = summarize_sections(sections);
  EXPECT_NEAR(sum.p_m_per_m.mean, 0.1, kSectionsTol);
  EXPECT_EQ(sum.p_m_per_m.n, 2u);
}

TEST(Sections, YawDriftGivesAnalyticTranslationAndYawErrors) {
  const double d = 0.01;  // rad of extra yaw per frame in the estimate
  const auto s = straight_sections(1.0, d);
  const auto sections = compute_sections(s.t, s.gt, s.est, {6.5});
  ASSERT_EQ(sections.size(), 2u);
  for (const auto& sec : sections) {
    // Truth moves 7 m forward; the estimate's start camera is yawed by
    // i0*d, so it sees the same 7 m displacement rotated by -i0*d.
    const double a = d * static_cast<double>(sec.first);
    EXPECT_NEAR(sec.err_m.x(), 7.0 - 7.0 * std::cos(a), 1e-12);
    EXPECT_NEAR(sec.err_m.y(), 0.0 - (-7.0 * std::sin(a)), 1e-12);
    EXPECT_NEAR(sec.err_m.z(), 0.0, 1e-12);
    // Eq. (11): truth yaw change 0, estimate 7 d.
    EXPECT_NEAR(sec.err_rad.yaw_rad, -7 * d, 1e-12);
    EXPECT_NEAR(sec.err_rad.pitch_rad, 0.0, 1e-12);
    EXPECT_NEAR(sec.err_rad.roll_rad, 0.0, 1e-12);
  }
  const SectionSummary sum = summarize_sections(sections);
  EXPECT_NEAR(sum.yaw_deg_per_m.mean, rad2deg(-7 * d) / 7.0, 1e-10);
}

TEST(Sections, CovariatesFromTheFrameTable) {
  const auto s = straight_sections(1.0, 0.0);
  FrameTable frames;
  frames.names = {"yaw_deg", "inliers", "mean_depth_m", "gps_satellites"};
  frames.columns.resize(4);
  for (int i = 0; i <= 20; ++i) {
    frames.t_ns.push_back(static_cast<TimeNs>(i) * 500'000'000);
    // Yaw crosses +-180 deg: 178, -180 (=180), -178 (=182), ... must unwrap.
    frames.columns[0].push_back(std::remainder(178.0 + 2.0 * i, 360.0));
    frames.columns[1].push_back(100.0 + i);
    frames.columns[2].push_back(i % 2 ? 10.0 : 20.0);
    frames.columns[3].push_back(i < 7 ? 3.0 : 8.0);
  }
  const auto sections = compute_sections(s.t, s.gt, s.est, {6.5}, &frames);
  ASSERT_EQ(sections.size(), 2u);
  const Section& a = sections[0];
  // Rows 0..7 inclusive: yaw 178, 180, ..., 192 -> sample SD of 2*(0..7) = 2*sqrt(6).
  EXPECT_NEAR(a.covariate("h"), 2.0 * std::sqrt(6.0), 1e-9);
  EXPECT_NEAR(a.covariate("f"), 103.5, kSectionsTol);
  EXPECT_NEAR(a.covariate("d"), 15.0, kSectionsTol);
  EXPECT_NEAR(a.covariate("gps_satellites"), (7 * 3.0 + 8.0) / 8.0, kSectionsTol);
  EXPECT_TRUE(std::isnan(a.covariate("inliers")));  // it became f
  const Summary f = summarize_covariate(sections, "f");
  EXPECT_EQ(f.n, 2u);
  EXPECT_NEAR(f.mean, (103.5 + 110.5) / 2.0, kSectionsTol);
}

TEST(Sections, ARunsFrameTableGivesEachVoItsCovariates) {
  // A run's frames.csv: the platform's attitude, a timing column and per VO its block.
  FrameTable run;
  run.names = {"yaw_deg",        "render_ms",           "sparse_valid",
               "sparse_inliers", "sparse_mean_depth_m", "sparse_features",
               "sparse_lost",    "sparse_kf_valid",     "sparse_kf_inliers",
               "moving_px"};
  run.t_ns = {0, 1, 2};
  run.columns = {{1, 2, 3},         {9, 9, 9}, {0, 1, 0}, {0, 120, 0}, {kNaN, 21.5, kNaN},
                 {kNaN, 118, kNaN}, {0, 0, 1}, {0, 1, 1}, {0, 80, 90}, {0, 0.25, 0.5}};
  const std::vector<std::string> vos = run_vo_names(run);
  EXPECT_EQ(vos, (std::vector<std::string>{"sparse", "sparse_kf"}));
  EXPECT_EQ(run_vo_of(vos, "sparse"), "sparse");
  EXPECT_EQ(run_vo_of(vos, "sparse_kf"), "sparse_kf");
  EXPECT_EQ(run_vo_of(vos, "sparse_kf_ca"), "sparse_kf");  // the longest prefix
  EXPECT_EQ(run_vo_of(vos, "sparse_ca"), "sparse");
  EXPECT_EQ(run_vo_of(vos, "sparsely"), "");  // a prefix must end at a '_'
  EXPECT_EQ(run_vo_of(vos, "dense"), "");

  const FrameTable s = run_vo_covariates(run, "sparse", "frames.csv");
  EXPECT_EQ(s.names,
            (std::vector<std::string>{"yaw_deg", "inliers", "mean_depth_m", "lost", "moving_px"}));
  EXPECT_EQ(*s.column("moving_px"), (std::vector<double>{0, 0.25, 0.5}));  // the scene's
  EXPECT_EQ(s.t_ns, run.t_ns);
  // f is the VO's own feature count, not its inliers, and missing where it gave no motion.
  EXPECT_TRUE(std::isnan((*s.column("inliers"))[0]));
  EXPECT_EQ((*s.column("inliers"))[1], 118.0);
  EXPECT_EQ((*s.column("mean_depth_m"))[1], 21.5);
  EXPECT_EQ(*s.column("lost"), (std::vector<double>{0, 0, 1}));

  // A frames.csv from before the `_features` column: the inliers, or the dense VO's valid-depth
  // pixels; no `lost`.
  const FrameTable kf = run_vo_covariates(run, "sparse_kf", "frames.csv");
  EXPECT_EQ(kf.names, (std::vector<std::string>{"yaw_deg", "inliers", "moving_px"}));
  EXPECT_TRUE(std::isnan((*kf.column("inliers"))[0]));
  EXPECT_EQ((*kf.column("inliers"))[2], 90.0);
  run.names[8] = "sparse_kf_valid_depth_px";
  EXPECT_EQ((*run_vo_covariates(run, "sparse_kf", "f.csv").column("inliers"))[2], 90.0);

  try {
    run_vo_covariates(run, "dense", "out/frames.csv");
    ADD_FAILURE() << "no throw";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("out/frames.csv: no columns of a VO called 'dense'"),
              std::string::npos);
    EXPECT_NE(std::string(e.what()).find("sparse, sparse_kf"), std::string::npos);
  }
  // A covariate table of one's own is not a run's.
  FrameTable own;
  own.names = {"inliers", "x_valid"};
  own.columns.resize(2);
  EXPECT_TRUE(run_vo_names(own).empty());
}

TEST(Sections, ReadsFrameTableAndRejectsBadFiles) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("driftlab_frames_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto file = (dir / "frames.csv").string();
  std::ofstream(file) << "t,inliers,mean_depth_m\n0.5,100,20.5\n1.0,,nan\n";
  const FrameTable t = read_frame_table(file);
  ASSERT_EQ(t.t_ns.size(), 2u);
  EXPECT_EQ(t.t_ns[1], 1'000'000'000);
  EXPECT_EQ((*t.column("inliers"))[0], 100.0);
  EXPECT_TRUE(std::isnan((*t.column("inliers"))[1]));
  auto message = [&](const std::string& text) -> std::string {
    std::ofstream(file) << text;
    try {
      read_frame_table(file);
    } catch (const UserError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message("inliers\n3\n").find("no time column"), std::string::npos);
  EXPECT_NE(message("t_ns,x\n5,1\n5,2\n").find("frames.csv:3: time"), std::string::npos);
  EXPECT_NE(message("t_ns,x\n5,abc\n").find("frames.csv:2: x: got 'abc', expected a number"),
            std::string::npos);
  EXPECT_NE(
      message("t_ns,x\n5,1,2\n").find("frames.csv:2: got 3 cells, expected 2 like the header"),
      std::string::npos);
  EXPECT_THROW(read_frame_table((dir / "missing.csv").string()), UserError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace driftlab::eval
