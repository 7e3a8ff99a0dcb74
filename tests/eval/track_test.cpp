#include "eval/track.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "core/rotation.hpp"
#include "eval/eval_options.hpp"

namespace driftlab::eval {
namespace {

TEST(Track, ConstantOffsetGivesThatErrorEverywhere) {
  std::vector<SE3> gt, est;
  for (int i = 0; i <= 100; ++i) {
    gt.push_back(SE3::from_translation(Vec3(0.5 * i, 0, 0)));
    est.push_back(SE3::from_translation(Vec3(0.5 * i + 0.3, 0.4, 1.2)));
  }
  const TrackErrors r = track_errors(gt, est, EvalOptions{}.length_sample_m);
  EXPECT_EQ(r.n, 101u);
  EXPECT_NEAR(r.rmse_3d_m, 1.3, 1e-12);  // sqrt(0.09 + 0.16 + 1.44)
  EXPECT_NEAR(r.max_3d_m, 1.3, 1e-12);
  EXPECT_NEAR(r.rmse_2d_m, 0.5, 1e-12);
  EXPECT_NEAR(r.length_gt_m, 50.0, 1e-12);
  EXPECT_NEAR(r.rmse_3d_pct, 1.3 / 50.0 * 100, 1e-10);
  EXPECT_NEAR(r.length_error_pct, 0.0, 1e-12);
}

TEST(Track, RmseIsEq14AndLengthErrorHasItsSign) {
  // Errors 0, 1, 2, 3 m along east: RMSE = sqrt(14/4); estimate path longer.
  std::vector<SE3> gt, est;
  for (int i = 0; i < 4; ++i) {
    gt.push_back(SE3::from_translation(Vec3(10.0 * i, 0, 0)));
    est.push_back(SE3::from_translation(Vec3(10.0 * i, 1.0 * i, 0)));
  }
  const TrackErrors r = track_errors(gt, est, EvalOptions{}.length_sample_m);
  EXPECT_NEAR(r.rmse_3d_m, std::sqrt(14.0 / 4.0), 1e-12);
  EXPECT_NEAR(r.max_2d_m, 3.0, 1e-12);
  EXPECT_NEAR(r.length_est_m, 3 * std::sqrt(101.0), 1e-12);
  EXPECT_GT(r.length_error_pct, 0.0);
  EXPECT_NEAR(r.length_error_pct, (3 * std::sqrt(101.0) - 30.0) / 30.0 * 100, 1e-10);
}

TEST(Track, PoseNoiseAddsNoLengthAtTheDefaultSampling) {
  // A 10 m straight run at 1 cm per frame; the estimate is 5 % short and zig-zags +-1 cm
  // across the track frame by frame. Summed frame by frame the zig-zag alone adds ~120 % of
  // length; through one pose every 0.5 m of true travel the error is the scale's, -5 %, to
  // within what a 2 cm jump adds to each of the 20 samples' 0.475 m (< 0.1 % in all).
  std::vector<SE3> gt, est;
  for (int i = 0; i <= 1000; ++i) {
    gt.push_back(SE3::from_translation(Vec3(0.01 * i, 0, 0)));
    est.push_back(SE3::from_translation(Vec3(0.0095 * i, i % 2 == 0 ? 0.01 : -0.01, 0)));
  }
  const TrackErrors per_frame = track_errors(gt, est, 0.0);
  EXPECT_GT(per_frame.length_error_pct, 100.0);
  const TrackErrors sampled = track_errors(gt, est, EvalOptions{}.length_sample_m);
  EXPECT_NEAR(sampled.length_gt_m, 10.0, 1e-9);
  EXPECT_NEAR(sampled.length_error_pct, -5.0, 0.1);
}

TEST(Track, LengthSamplesFollowTrueTravelAndKeepBothEnds) {
  std::vector<SE3> gt;
  for (int i = 0; i <= 10; ++i) gt.push_back(SE3::from_translation(Vec3(0.3 * i, 0, 0)));
  // Every 0.3 m; at least 0.5 m apart: 0, 2 (0.6 m), 4, 6, 8, 10.
  EXPECT_EQ(length_sample_indices(gt, 0.5), (std::vector<std::size_t>{0, 2, 4, 6, 8, 10}));
  EXPECT_EQ(length_sample_indices(gt, 0.0).size(), gt.size());
  EXPECT_EQ(length_sample_indices(gt, 100.0), (std::vector<std::size_t>{0, 10}));
}

TEST(Track, PlanarStatesOfACircle) {
  // Body moving on a circle of radius R at speed V, bow along the velocity:
  // surge = V, sway = 0, heading = tangent direction.
  const double R = 5.0, V = 0.5, w = V / R;
  std::vector<TimeNs> t;
  std::vector<SE3> T;
  for (int i = 0; i < 200; ++i) {
    const double s = 0.01 * i;
    const double a = w * s;
    t.push_back(seconds_to_ns(s));
    const Vec3 p(R * std::sin(a), R - R * std::cos(a), 0);  // starts at 0 heading north, turns east
    T.push_back(SE3(quat_from_euler_zyx({0, 0, a}), p));
  }
  const PlanarStates st = planar_states(t, T, false);
  for (int i = 1; i < 199; ++i) {
    EXPECT_NEAR(st.surge_m_s[i], V, 1e-5);
    EXPECT_NEAR(st.sway_m_s[i], 0.0, 1e-5);
    EXPECT_NEAR(st.heading_rad[i], w * 0.01 * i, 1e-12);
  }
  const BasinTable same = basin_table(st, st);
  EXPECT_EQ(same.north_m.rmse, 0.0);
  PlanarStates shifted = st;
  for (auto& h : shifted.heading_rad) h += 2 * std::numbers::pi + 0.01;  // wraps
  for (auto& n : shifted.north_m) n += 0.02;
  const BasinTable b = basin_table(st, shifted);
  EXPECT_NEAR(b.heading_deg.rmse, rad2deg(0.01), 1e-9);
  EXPECT_NEAR(b.north_m.rmse, 0.02, 1e-12);
  EXPECT_NEAR(b.north_m.sd_sample, 0.0, 1e-12);
}

// The table against a reference at its own times equals the table against the same states
// paired index by index (a second method), and the pairing skips what the reference lacks.
TEST(Track, BasinTableAgainstAReferenceAtItsOwnTimes) {
  std::vector<TimeNs> t;
  std::vector<SE3> T;
  for (int i = 0; i < 50; ++i) {
    t.push_back(seconds_to_ns(0.05 * i));
    T.push_back(SE3(quat_from_euler_zyx({0, 0, 0.01 * i}), Vec3(0.15 * 0.05 * i, 0.001 * i, 0)));
  }
  const PlanarStates truth = planar_states(t, T, false);
  PlanarStates est = truth;
  for (std::size_t i = 0; i < est.north_m.size(); ++i) {
    est.north_m[i] += 0.01 * std::sin(0.3 * i);
    est.heading_rad[i] += 0.002 * std::cos(0.2 * i);
  }
  const BasinTable direct = basin_table(truth, est);
  PlanarReference ref{t, truth};
  for (auto& s : ref.t_ns) s += 3'000'000;  // 3 ms late: still the same frames
  std::size_t pairs = 0;
  const BasinTable paired = basin_table(ref, t, est, 10'000'000, &pairs);
  EXPECT_EQ(pairs, t.size());
  EXPECT_NEAR(paired.north_m.rmse, direct.north_m.rmse, 1e-15);
  EXPECT_NEAR(paired.heading_deg.rmse, direct.heading_deg.rmse, 1e-12);
  EXPECT_EQ(paired.east_m.n, t.size());
  // A reference sample without a heading counts for the others; one too far off, for none.
  ref.states.heading_rad[4] = std::numeric_limits<double>::quiet_NaN();
  ref.t_ns[7] += 22'000'000;  // halfway between frames 7 and 8: 25 ms from either
  const BasinTable holes = basin_table(ref, t, est, 20'000'000, &pairs);
  EXPECT_EQ(pairs, t.size() - 1);
  EXPECT_EQ(holes.heading_deg.n, t.size() - 2);
  EXPECT_EQ(holes.north_m.n, t.size() - 1);
}

TEST(Track, CameraOpticalAxisIsTheHeading) {
  // Camera looking east: optical z = world y.
  Mat3 R;
  R.col(0) = Vec3(-1, 0, 0);  // optical x (right) -> south
  R.col(1) = Vec3(0, 0, 1);   // optical y (down) -> down
  R.col(2) = Vec3(0, 1, 0);   // optical z -> east
  const std::vector<TimeNs> t{0, 1'000'000'000};
  const std::vector<SE3> T{SE3(R, Vec3(0, 0, 0)), SE3(R, Vec3(0, 1, 0))};
  const PlanarStates st = planar_states(t, T, true);
  EXPECT_NEAR(st.heading_rad[0], std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(st.surge_m_s[0], 1.0, 1e-12);
  EXPECT_NEAR(st.sway_m_s[0], 0.0, 1e-12);
}

}  // namespace
}  // namespace driftlab::eval
