// One typed suite over every implementation of fusion::Filter (fusion/filter.hpp; Sophus style,
// one typed test per interface): the NED Kalman and particle filters of the basin paper, the
// error-state Kalman filter and the river paper's constant-acceleration smoother. Every filter
// sees the same synthetic scenario, built here from an analytic truth: a vessel moving at
// 0.5 m/s on a straight line with a constant heading of 30 deg (not north, so that north and
// east are mixed) for 20 s, with exact measurements of every sensor. The expectations are that
// truth, never anything a filter computed.
//
// Adding an implementation: write a traits struct like NedKfTraits (how to build the filter
// from the Scenario, which sensors it has a model of, its tolerances with their reasons, its
// counters) and add it to Implementations.
#include "fusion/filter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "core/time.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::fusion {
namespace {

using driftlab::test::kDeg;

// ---------------------------------------------------------------------------------------------
// The scenario: the analytic truth and exact measurements of it.

constexpr TimeNs kCameraPeriodNs = 100'000'000;   // 10 Hz
constexpr TimeNs kImuPeriodNs = 10'000'000;       // 100 Hz
constexpr TimeNs kCompassPeriodNs = 200'000'000;  // 5 Hz
constexpr TimeNs kGpsPeriodNs = 1'000'000'000;    // 1 Hz
constexpr TimeNs kDurationNs = 20'000'000'000;    // 20 s: frames at 0, 0.1, ..., 20 s
constexpr double kSpeedMS = 0.5;                  // along the bow
constexpr double kHeadingRad = 30.0 * kDeg;       // constant; clockwise from north
constexpr double kGravityMS2 = 9.80665;           // g_W = (0, 0, +g), world NED
constexpr double kGpsSdHorizontalM = 0.01;        // exact fixes, small stated error
constexpr double kGpsSdVerticalM = 0.02;
// The frame whose VO result is broken in the fault tests: in the middle of the run, and odd, so
// that no compass sample falls on it (the NED filters then get no measurement at that step).
constexpr int kBadFrame = 101;

using Counts = std::vector<std::pair<std::string, std::int64_t>>;

struct Scenario {
  // Mounts in body FRD (x bow, y starboard, z down).
  SE3 T_B_C;  // left camera, OpenCV optical frame
  SE3 T_B_I;  // IMU
  Vec3 p_B_antenna_m;
  // The truth: the body starts at p_W_B0 (its centre of gravity on the water plane, down = 0)
  // and moves with v_W, level, at kHeadingRad.
  Vec3 p_W_B0_m;
  Quat q_W_B;
  Vec3 v_W_m_s;
  // Exact measurements.
  std::vector<TimeNs> frame_t_ns;
  std::vector<vo::VoResult> vo;  // vo[k]: the motion from t_k - 0.1 s to t_k (all valid)
  std::vector<ImuSample> imu;
  std::vector<HeadingMeasurement> compass;
  std::vector<GpsPositionMeasurement> gps;

  std::int64_t frames() const { return static_cast<std::int64_t>(frame_t_ns.size()); }
  SE3 T_W_B(TimeNs t_ns) const { return SE3(q_W_B, p_W_B0_m + v_W_m_s * ns_to_seconds(t_ns)); }
  SE3 T_W_C(TimeNs t_ns) const { return T_W_B(t_ns) * T_B_C; }
};

Scenario make_scenario() {
  Scenario s;
  // As tests/fusion/eskf_test.cpp: forward-looking, pitched 5 deg down, 1 m ahead of the CG,
  // 0.2 m to starboard, 0.6 m up, so that the lever arm and the pitch enter every conversion.
  s.T_B_C = SE3(R_frd_optical() * Eigen::AngleAxisd(-5 * kDeg, Vec3::UnitX()).toRotationMatrix(),
                Vec3(1.0, 0.2, -0.6));
  // The IMU turned 90 deg about down and off the CG, so that its extrinsics matter too.
  s.T_B_I = SE3(quat_from_euler_zyx({0.0, 0.0, 90 * kDeg}), Vec3(-0.3, 0.1, 0.2));
  s.p_B_antenna_m = Vec3(0.0, 0.0, -1.5);
  s.p_W_B0_m = Vec3(3.0, -2.0, 0.0);
  s.q_W_B = quat_from_euler_zyx({0.0, 0.0, kHeadingRad});
  s.v_W_m_s = s.q_W_B * Vec3(kSpeedMS, 0.0, 0.0);

  for (TimeNs t = 0; t <= kDurationNs; t += kCameraPeriodNs) {
    s.frame_t_ns.push_back(t);
    vo::VoResult r;
    r.valid = true;
    r.T_prev_curr = s.T_W_C(t - kCameraPeriodNs).inverse() * s.T_W_C(t);
    r.matches = r.inliers = 200;
    s.vo.push_back(r);
  }
  // The IMU: no rotation, no acceleration, so it measures gravity's reaction only:
  // f_I = R_W_I^T (a_W - g_W) with a_W = 0.
  const Quat q_W_I = s.q_W_B * s.T_B_I.quaternion();
  const Vec3 f_I = q_W_I.conjugate() * Vec3(0.0, 0.0, -kGravityMS2);
  for (TimeNs t = 0; t <= kDurationNs; t += kImuPeriodNs) s.imu.push_back({t, Vec3::Zero(), f_I});
  for (TimeNs t = 0; t <= kDurationNs; t += kCompassPeriodNs)
    s.compass.push_back({t, kHeadingRad});  // the compass sits level in the body
  for (TimeNs t = 0; t <= kDurationNs; t += kGpsPeriodNs) {
    s.gps.push_back(GpsPositionMeasurement::with_sd(t, s.T_W_B(t) * s.p_B_antenna_m,
                                                    kGpsSdHorizontalM, kGpsSdVerticalM));
  }
  return s;
}

const Scenario& scenario() {
  static const Scenario s = make_scenario();
  return s;
}

// Which measurement streams a run feeds (the pipeline feeds every enabled sensor to every
// filter; a filter without a model of a sensor must ignore it).
struct Sensors {
  bool imu = true;
  bool compass = true;
  bool gps = true;
};

struct RunOutput {
  std::vector<SE3> poses;  // what vo() returned, per frame
  FilterSummary summary;
  std::size_t ned_states = 0;
};

// Feeds the scenario as pipeline/filter_stage.cpp's FilterTrack does: before each frame's vo(),
// every measurement with t <= the frame's time, in time order, IMU first on a tie, then the
// compass, then GPS.
RunOutput run_filter(Filter* filter, const Scenario& s, const std::vector<vo::VoResult>& vo,
                     Sensors feed = {}) {
  RunOutput out;
  std::size_t ii = 0, ic = 0, ig = 0;
  constexpr TimeNs kNever = std::numeric_limits<TimeNs>::max();
  for (std::size_t k = 0; k < s.frame_t_ns.size(); ++k) {
    const TimeNs t = s.frame_t_ns[k];
    for (;;) {
      const TimeNs ti = ii < s.imu.size() ? s.imu[ii].t_ns : kNever;
      const TimeNs tc = ic < s.compass.size() ? s.compass[ic].t_ns : kNever;
      const TimeNs tg = ig < s.gps.size() ? s.gps[ig].t_ns : kNever;
      const TimeNs tmin = std::min({ti, tc, tg});
      if (tmin > t || tmin == kNever) break;
      if (ti == tmin) {
        const ImuSample& m = s.imu[ii++];
        if (feed.imu) filter->imu(m);
      } else if (tc == tmin) {
        const HeadingMeasurement& m = s.compass[ic++];
        if (feed.compass) filter->heading(m);
      } else {
        const GpsPositionMeasurement& m = s.gps[ig++];
        if (feed.gps) filter->gps(m);
      }
    }
    out.poses.push_back(filter->vo(t, vo[k]));
  }
  out.summary = filter->summary();
  out.ned_states = filter->ned_states().size();
  return out;
}

// ---------------------------------------------------------------------------------------------
// What differs per filter.

enum class Fault {
  kNone,
  kNonfiniteVo,  // frame kBadFrame: valid = true, NaN in T_prev_curr's translation
  kInvalidVo,    // frame kBadFrame: valid = false, carrying a wild (finite) motion
};

std::vector<vo::VoResult> vo_with(const Scenario& s, Fault fault) {
  std::vector<vo::VoResult> vo = s.vo;
  vo::VoResult& r = vo[kBadFrame];
  if (fault == Fault::kNonfiniteVo) {
    r.T_prev_curr = SE3(r.T_prev_curr.quaternion(),
                        Vec3(std::numeric_limits<double>::quiet_NaN(),
                             r.T_prev_curr.translation().y(), r.T_prev_curr.translation().z()));
  } else if (fault == Fault::kInvalidVo) {
    // An invalid result must not be read: were this motion (1 m sideways and down, 1 m back,
    // 10 deg about each axis) fused, every filter would leave the truth by decimetres.
    r.valid = false;
    r.reason = "too few inliers";
    r.T_prev_curr = SE3(so3_exp(Vec3::Constant(10 * kDeg)), Vec3(1.0, 1.0, -1.0));
  }
  return vo;
}

std::int64_t faults(Fault f) { return f == Fault::kNone ? 0 : 1; }

// The basin paper's Kalman filter (NED, planar: [N, E, u, v, psi]).
struct NedKfTraits {
  static constexpr const char* kName = "NedKalmanFilter";
  // VO body velocities and the compass; no model of the IMU or GPS.
  static constexpr Sensors kSensors{.imu = false, .compass = true, .gps = false};
  // Started at the truth and fed exact measurements of a motion its constant-velocity planar
  // model describes exactly, every innovation is zero: only rounding is left (measured 1.5e-13 m
  // and 0 rad). 1 um leaves room for other compilers' rounding, while a VO scale error of 1e-6
  // already moves the end point 10 m away by 10 um.
  static constexpr double kPositionTolM = 1e-6;
  static constexpr double kHeadingTolRad = 1e-9;
  static constexpr bool kHasNedStates = true;
  static constexpr const char* kFusedCounter = "vo_fused";

  static std::unique_ptr<Filter> make(const Scenario& s) {
    return make_ned_kalman_filter(NedFilterOptions{}, initial(s), s.T_B_C, s.T_W_B(0));
  }
  static NedState initial(const Scenario& s) {
    return {.north_m = s.p_W_B0_m.x(),
            .east_m = s.p_W_B0_m.y(),
            .surge_m_s = kSpeedMS,
            .sway_m_s = 0.0,
            .heading_rad = kHeadingRad};
  }
  // The first step has no time step (dt = 0): its VO result, valid as it is, gives no velocity
  // and is not fused (filter.hpp: "the first call only starts the filter"). Every compass sample
  // falls on a frame time and is fused at that frame. A bad result is not fused.
  static Counts expected_counts(const Scenario& s, Fault f) {
    return {{"steps", s.frames()},
            {"vo_fused", s.frames() - 1 - faults(f)},
            {"heading_fused", static_cast<std::int64_t>(s.compass.size())},
            {"nonfinite_guards", f == Fault::kNonfiniteVo ? 1 : 0}};
  }
};

// The basin paper's particle filter: the same model, its defaults (the paper's 1000 particles,
// multinomial resampling at every update), seeded.
struct NedPfTraits {
  static constexpr const char* kName = "NedParticleFilter";
  static constexpr Sensors kSensors{.imu = false, .compass = true, .gps = false};
  // With exact data the KF's answer is the truth, so the PF's error is its Monte-Carlo error.
  // Position is never measured: the default (position: integrated) moves the previous position
  // by the weighted mean velocity and heading, so what is left is their Monte-Carlo error
  // integrated over the run: 1.1 cm at the end for this seed, 0.7 cm worst with a bad frame.
  // (The particles' own mean, the paper's Eq. (10), collapses under resampling at every step:
  // over 40 seeds 7.7 cm RMS at the end, 0.19 m worst.) 3 cm is 0.3 % of the 10 m run.
  static constexpr double kPositionTolM = 0.03;
  // The heading's Monte-Carlo error is largest early, under the prior's 0.05 rad: over 40 seeds
  // 0.8 mrad RMS at the end and 5.8 mrad worst at any frame; this seed: 2.8 mrad.
  static constexpr double kHeadingTolRad = 0.01;
  static constexpr bool kHasNedStates = true;
  static constexpr const char* kFusedCounter = "vo_fused";

  static std::unique_ptr<Filter> make(const Scenario& s) {
    return make_ned_particle_filter(NedParticleFilterOptions{}, RngStreams(2020).stream("test.pf"),
                                    NedKfTraits::initial(s), s.T_B_C, s.T_W_B(0));
  }
  // As NedKfTraits, plus "resampled": the default multinomial resampling runs at every step
  // with a measurement; clean, every step has one (step 0 the compass sample at t = 0); the bad
  // frame has neither a usable VO result nor a compass sample.
  static Counts expected_counts(const Scenario& s, Fault f) {
    return {{"steps", s.frames()},
            {"vo_fused", s.frames() - 1 - faults(f)},
            {"heading_fused", static_cast<std::int64_t>(s.compass.size())},
            {"resampled", s.frames() - faults(f)},
            {"nonfinite_guards", f == Fault::kNonfiniteVo ? 1 : 0}};
  }
};

// The error-state Kalman filter on the IMU, the VO, the GPS and the compass.
struct EskfTraits {
  static constexpr const char* kName = "Eskf";
  static constexpr Sensors kSensors{.imu = true, .compass = true, .gps = true};
  // Started at the truth with exact IMU samples of a motion without rotation or acceleration,
  // the second-order propagation is exact and every innovation zero: rounding only (measured
  // 3.4e-14 m, 2.2e-16 rad); the margins as NedKfTraits.
  static constexpr double kPositionTolM = 1e-6;
  static constexpr double kHeadingTolRad = 1e-9;
  static constexpr bool kHasNedStates = false;
  // Eskf::update_vo counts a non-finite valid result as a guard and moves the clone on.
  static constexpr const char* kFusedCounter = "vo_fused";

  static std::unique_ptr<Filter> make(const Scenario& s) {
    EskfExtrinsics ex;
    ex.T_I_C = s.T_B_I.inverse() * s.T_B_C;
    ex.p_I_antenna_m = s.T_B_I.inverse() * s.p_B_antenna_m;
    ex.R_I_M = s.T_B_I.rotation().transpose();  // the compass sits level in the body
    EskfState init;
    init.t_ns = s.imu.front().t_ns;
    const SE3 T_W_I = s.T_W_B(init.t_ns) * s.T_B_I;
    init.q_W_I = T_W_I.quaternion();
    init.p_W_m = T_W_I.translation();
    init.v_W_m_s = s.v_W_m_s;  // no rotation: the IMU moves with the CG
    EskfOptions o;
    o.gravity_m_s2 = kGravityMS2;
    return make_eskf(o, ex, init);
  }
  // The first frame has no clone to measure from: skipped. Every IMU sample, fix and compass
  // sample up to the last frame is fed and fused (no gates set). A non-finite result is a guard
  // (neither fused, skipped nor gated); an invalid one is skipped.
  static Counts expected_counts(const Scenario& s, Fault f) {
    const std::int64_t guards = f == Fault::kNonfiniteVo ? 1 : 0;
    return {{"imu_samples", static_cast<std::int64_t>(s.imu.size())},
            {"vo_fused", s.frames() - 1 - faults(f)},
            {"vo_skipped", 1 + (f == Fault::kInvalidVo ? 1 : 0)},
            {"vo_gated", 0},
            {"gps_fused", static_cast<std::int64_t>(s.gps.size())},
            {"gps_gated", 0},
            {"heading_fused", static_cast<std::int64_t>(s.compass.size())},
            {"heading_gated", 0},
            {"nonfinite_guards", guards}};
  }
};

// The river paper's constant-acceleration smoother, chained from the true first camera pose.
struct CaSmootherTraits {
  static constexpr const char* kName = "CaSmoother";
  // VO only.
  static constexpr Sensors kSensors{.imu = false, .compass = false, .gps = false};
  // The smoother's twist starts at zero (its prior, sd 5 m/s): the first measured step takes
  // the VO's 0.5 m/s with gain P / (P + R) ~ 1 - 1e-4 (R = (5 mm / 0.1 s)^2), a 5 um shortfall,
  // and a small acceleration estimate that decays over the next steps: measured 8.5 um. 0.1 mm
  // leaves a factor 10; a VO scale error of 1e-4 moves the end point by 1 mm. No rotation is
  // ever measured, so the heading is the start pose's: rounding only (measured 0).
  static constexpr double kPositionTolM = 1e-4;
  static constexpr double kHeadingTolRad = 1e-9;
  static constexpr bool kHasNedStates = false;
  // ConstantAccelerationSmoother::update counts a non-finite twist as a guard and predicts only.
  // It has no counter of fused results; nonfinite_guards is its only counter.
  static constexpr const char* kFusedCounter = nullptr;

  static std::unique_ptr<Filter> make(const Scenario& s) {
    return make_ca_smoother(CaSmootherOptions{}, s.T_W_C(s.frame_t_ns.front()));
  }
  static Counts expected_counts(const Scenario&, Fault f) {
    return {{"nonfinite_guards", f == Fault::kNonfiniteVo ? 1 : 0}};
  }
};

using Implementations = ::testing::Types<NedKfTraits, NedPfTraits, EskfTraits, CaSmootherTraits>;

template <class T>
class FilterTest : public ::testing::Test {};
TYPED_TEST_SUITE(FilterTest, Implementations);

// ---------------------------------------------------------------------------------------------
// Helpers

double body_yaw(const Scenario& s, const SE3& T_W_C) {
  return euler_zyx_from_quat((T_W_C * s.T_B_C.inverse()).quaternion()).yaw_rad;
}

struct Errors {
  double max_position_m = 0.0, final_position_m = 0.0;
  double max_heading_rad = 0.0, final_heading_rad = 0.0;
  bool finite = true;
};

// Against the analytic truth, every frame.
Errors errors_of(const Scenario& s, const std::vector<SE3>& poses) {
  Errors e;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const SE3& T = poses[k];
    e.finite = e.finite && T.translation().allFinite() && T.quaternion().coeffs().allFinite();
    const double dp = (T.translation() - s.T_W_C(s.frame_t_ns[k]).translation()).norm();
    const double dh = std::abs(wrap_angle_rad(body_yaw(s, T) - kHeadingRad));
    e.max_position_m = std::max(e.max_position_m, dp);
    e.max_heading_rad = std::max(e.max_heading_rad, dh);
    e.final_position_m = dp;
    e.final_heading_rad = dh;
  }
  return e;
}

void report(const char* filter, const char* what, const Errors& e) {
  std::printf(
      "[  metrics ] %s, %s: camera position error final %.3g m, max %.3g m; heading error final "
      "%.3g rad, max %.3g rad\n",
      filter, what, e.final_position_m, e.max_position_m, e.final_heading_rad, e.max_heading_rad);
  ::testing::Test::RecordProperty(std::string(what) + "_max_position_error_m",
                                  std::to_string(e.max_position_m));
  ::testing::Test::RecordProperty(std::string(what) + "_max_heading_error_rad",
                                  std::to_string(e.max_heading_rad));
}

std::string counts_text(const Counts& c) {
  std::string out;
  for (const auto& [n, v] : c) out += (out.empty() ? "" : ", ") + n + " " + std::to_string(v);
  return out;
}

bool same_pose(const SE3& a, const SE3& b) { return a.matrix() == b.matrix(); }

// ---------------------------------------------------------------------------------------------
// The tests

TEST(FilterScenarioTest, IsTheStraightTrackItClaims) {
  // The scenario generator against numbers written down independently: 10 m in 20 s at 30 deg
  // (once, not per filter: every filter's tests rest on it).
  const Scenario& s = scenario();
  ASSERT_EQ(s.frames(), 201);
  ASSERT_EQ(s.imu.size(), 2001u);
  ASSERT_EQ(s.compass.size(), 101u);
  ASSERT_EQ(s.gps.size(), 21u);
  const Vec3 d = s.T_W_B(kDurationNs).translation() - s.T_W_B(0).translation();
  EXPECT_NEAR(d.x(), 10.0 * std::cos(std::numbers::pi / 6), 1e-12);
  EXPECT_NEAR(d.y(), 5.0, 1e-12);
  EXPECT_EQ(d.z(), 0.0);
  // The camera's increment in its own frame: 5 cm along the bow, seen through the 5 deg pitch.
  const Vec3 t = s.vo[7].T_prev_curr.translation();
  EXPECT_NEAR(t.norm(), 0.05, 1e-12);
  EXPECT_NEAR(t.z(), 0.05 * std::cos(5 * kDeg), 1e-12);
  EXPECT_NEAR(s.imu[3].accel_m_s2.norm(), kGravityMS2, 1e-12);
}

TYPED_TEST(FilterTest, ExactMeasurementsOfAStraightTrackGiveTheTruePosition) {
  const Scenario& s = scenario();
  auto f = TypeParam::make(s);
  const RunOutput out = run_filter(f.get(), s, s.vo);
  ASSERT_EQ(out.poses.size(), s.frame_t_ns.size());
  const Errors e = errors_of(s, out.poses);
  report(TypeParam::kName, "clean", e);
  ASSERT_TRUE(e.finite);
  EXPECT_LE(e.final_position_m, TypeParam::kPositionTolM);
  EXPECT_LE(e.max_position_m, TypeParam::kPositionTolM);
  // The first call only starts the filter: it returns the start pose.
  EXPECT_LE((out.poses.front().translation() - s.T_W_C(0).translation()).norm(),
            TypeParam::kPositionTolM);
}

TYPED_TEST(FilterTest, ExactMeasurementsOfAStraightTrackGiveTheTrueHeading) {
  const Scenario& s = scenario();
  auto f = TypeParam::make(s);
  const RunOutput out = run_filter(f.get(), s, s.vo);
  const Errors e = errors_of(s, out.poses);
  ASSERT_TRUE(e.finite);
  EXPECT_LE(e.final_heading_rad, TypeParam::kHeadingTolRad);
  EXPECT_LE(e.max_heading_rad, TypeParam::kHeadingTolRad);
  // The whole attitude: level, as the truth (no filter may tilt the camera).
  const SE3& last = out.poses.back();
  EXPECT_LE(angle_between(last.quaternion(), s.T_W_C(kDurationNs).quaternion()),
            TypeParam::kHeadingTolRad);
}

TYPED_TEST(FilterTest, SameInputsGiveBitIdenticalPosesAtEveryFrame) {
  const Scenario& s = scenario();
  auto a = TypeParam::make(s);
  auto b = TypeParam::make(s);
  const RunOutput ra = run_filter(a.get(), s, s.vo);
  const RunOutput rb = run_filter(b.get(), s, s.vo);
  ASSERT_EQ(ra.poses.size(), rb.poses.size());
  for (std::size_t k = 0; k < ra.poses.size(); ++k)
    ASSERT_TRUE(same_pose(ra.poses[k], rb.poses[k])) << "frame " << k;
  EXPECT_EQ(ra.summary.counts, rb.summary.counts);
}

TYPED_TEST(FilterTest, SensorsWithoutAModelAreIgnored) {
  // filter.hpp: "A filter without a model of a sensor ignores its measurements": withholding
  // them changes no bit.
  const Scenario& s = scenario();
  auto all = TypeParam::make(s);
  auto used = TypeParam::make(s);
  const RunOutput ra = run_filter(all.get(), s, s.vo);
  const RunOutput ru = run_filter(used.get(), s, s.vo, TypeParam::kSensors);
  for (std::size_t k = 0; k < ra.poses.size(); ++k)
    ASSERT_TRUE(same_pose(ra.poses[k], ru.poses[k])) << "frame " << k;
}

TYPED_TEST(FilterTest, CountersCountEveryUsableVoResultAndNoGuards) {
  const Scenario& s = scenario();
  auto f = TypeParam::make(s);
  const RunOutput out = run_filter(f.get(), s, s.vo);
  const FilterSummary& sum = out.summary;
  std::printf("[  metrics ] %s counts: %s\n", TypeParam::kName, counts_text(sum.counts).c_str());
  ASSERT_FALSE(sum.counts.empty());
  EXPECT_EQ(sum.counts.back().first, "nonfinite_guards");
  EXPECT_EQ(sum.counts.back().second, sum.nonfinite_guards);
  EXPECT_EQ(sum.nonfinite_guards, 0);
  EXPECT_EQ(sum.count("nonfinite_guards"), 0);
  EXPECT_EQ(sum.count("no such counter"), -1);
  if (TypeParam::kFusedCounter != nullptr) {
    // Every VO result is valid; the first cannot be used (nothing before it to move from).
    EXPECT_EQ(sum.count(TypeParam::kFusedCounter), s.frames() - 1);
  } else {
    EXPECT_EQ(sum.count("vo_fused"), -1);
  }
  EXPECT_EQ(sum.counts, TypeParam::expected_counts(s, Fault::kNone));
  if (sum.count("vo_skipped") >= 0) {  // the ESKF: every frame is fused, skipped or gated
    EXPECT_EQ(sum.count("vo_fused") + sum.count("vo_skipped") + sum.count("vo_gated"), s.frames());
  }
  if (sum.count("steps") >= 0) {
    EXPECT_EQ(sum.count("steps"), s.frames());
  }
  EXPECT_EQ(out.ned_states, TypeParam::kHasNedStates ? s.frame_t_ns.size() : 0u);
}

TYPED_TEST(FilterTest, NonFiniteVoResultIsNotFusedAndPosesStayFinite) {
  const Scenario& s = scenario();
  auto f = TypeParam::make(s);
  const RunOutput out = run_filter(f.get(), s, vo_with(s, Fault::kNonfiniteVo));
  const Errors e = errors_of(s, out.poses);
  report(TypeParam::kName, "nonfinite_vo", e);
  ASSERT_TRUE(e.finite);
  const FilterSummary& sum = out.summary;
  std::printf("[  metrics ] %s counts: %s\n", TypeParam::kName, counts_text(sum.counts).c_str());
  if (TypeParam::kFusedCounter != nullptr) {
    EXPECT_EQ(sum.count(TypeParam::kFusedCounter), s.frames() - 2);  // one fewer than clean
  }
  // Every filter counts a non-finite input it skips (filter.hpp); the NED filters' adapter counts
  // it itself, since body_velocity_from_vo() makes it an invalid measurement first.
  EXPECT_EQ(sum.nonfinite_guards, 1);
  EXPECT_EQ(sum.counts, TypeParam::expected_counts(s, Fault::kNonfiniteVo));
  // One frame without a VO increment at constant velocity: each filter's motion model bridges it.
  EXPECT_LE(e.max_position_m, TypeParam::kPositionTolM);
  EXPECT_LE(e.max_heading_rad, TypeParam::kHeadingTolRad);
}

TYPED_TEST(FilterTest, InvalidVoResultIsNotFusedAndPosesStayFinite) {
  const Scenario& s = scenario();
  auto f = TypeParam::make(s);
  const RunOutput out = run_filter(f.get(), s, vo_with(s, Fault::kInvalidVo));
  const Errors e = errors_of(s, out.poses);
  report(TypeParam::kName, "invalid_vo", e);
  ASSERT_TRUE(e.finite);
  const FilterSummary& sum = out.summary;
  if (TypeParam::kFusedCounter != nullptr) {
    EXPECT_EQ(sum.count(TypeParam::kFusedCounter), s.frames() - 2);  // one fewer than clean
  }
  EXPECT_EQ(sum.nonfinite_guards, 0);
  EXPECT_EQ(sum.counts, TypeParam::expected_counts(s, Fault::kInvalidVo));
  // Not read: the wild motion it carries would move every filter by decimetres (the smoother,
  // which has no counter, is checked by this alone).
  EXPECT_LE(e.max_position_m, TypeParam::kPositionTolM);
  EXPECT_LE(e.max_heading_rad, TypeParam::kHeadingTolRad);
}

}  // namespace
}  // namespace driftlab::fusion
