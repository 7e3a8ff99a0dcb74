#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "sim/physics/vessel/guidance.hpp"
#include "sim/physics/vessel/simulator.hpp"
#include "sim/physics/waves/wave_field.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::sim {
namespace {

using driftlab::test::kPi;

struct SimRun {
  std::vector<BodySample> samples;
  MotionSummary summary;
};

SimRun run(const VesselModel& model, const Environment& env, const VesselState& init,
           double seconds, const VesselInputs& inputs = {}, Guidance* guidance = nullptr) {
  SimRun r;
  MotionOptions mo;
  mo.physics_rate_hz = model.options().physics_rate_hz;
  mo.max_duration_s = seconds;
  mo.fixed_inputs = inputs;
  r.summary = simulate(
      model, env, guidance, init, mo, {}, [&](const BodySample& b) { r.samples.push_back(b); },
      nullptr);
  return r;
}

// Mean period from upward zero crossings of x(t) - x_eq (linear interpolation).
double period_s(const std::vector<double>& t, const std::vector<double>& x, double x_eq) {
  std::vector<double> crossings;
  for (std::size_t i = 1; i < x.size(); ++i) {
    const double a = x[i - 1] - x_eq, b = x[i] - x_eq;
    if (a < 0 && b >= 0) crossings.push_back(t[i - 1] + (t[i] - t[i - 1]) * a / (a - b));
  }
  if (crossings.size() < 2) return 0;
  return (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
}

Environment calm() {
  Environment env;
  return env;
}

TEST(Vessel, SettlesAtDesignDraftAndStaysPut) {
  const VesselModel model(VesselOptions{});
  // Design draft of the box: displaced volume over waterplane area.
  const auto& h = model.options().hull;
  EXPECT_NEAR(model.design_draft_m(), 55.0 / (1000 * h.length_m * h.beam_m), 1e-15);
  VesselState s = initial_state(model, Vec2(0, 0), 0.3);
  s.p_W.z() -= 0.05;  // dropped from 5 cm too high
  const SimRun settle = run(model, calm(), s, 30);
  const VesselState end = settle.samples.back().state;
  EXPECT_NEAR(end.p_W.z(), model.design_cg_z_m(), 1e-4);
  // Then 60 s at rest from the design draft.
  const VesselState rest = initial_state(model, Vec2(3, 4), 0.3);
  const SimRun r = run(model, calm(), rest, 60);
  double drift = 0, attitude = 0;
  for (const auto& b : r.samples) {
    drift = std::max(drift, (b.state.p_W - rest.p_W).norm());
    attitude = std::max(attitude, angle_between(b.state.q_W_B, rest.q_W_B));
  }
  EXPECT_LT(drift, 1e-3);
  EXPECT_LT(rad2deg(attitude), 0.01);
}

TEST(Vessel, HeaveRollAndPitchNaturalPeriodsMatchTheHydrostatics) {
  for (const auto preset : {VesselPreset::kSurveyBoat, VesselPreset::kBasinModel}) {
    const VesselModel model(VesselOptions::preset_defaults(preset));
    const auto& o = model.options();
    const double m = o.mass_kg;
    const auto& r = o.gyration_radii_m;
    // 2 pi sqrt((m + A) / C) with C from the box's own geometry.
    const double T_heave = 2 * kPi * std::sqrt((m + o.added_mass[2]) / model.heave_stiffness());
    const double T_roll =
        2 * kPi * std::sqrt((m * r[0] * r[0] + o.added_mass[3]) / model.roll_stiffness());
    const double T_pitch =
        2 * kPi * std::sqrt((m * r[1] * r[1] + o.added_mass[4]) / model.pitch_stiffness());
    Environment env = calm();
    env.damping_enabled = false;
    VesselState s = initial_state(model, Vec2(0, 0), 0);
    s.p_W.z() += 0.004;
    SimRun rh = run(model, env, s, 10 * T_heave);
    VesselState s2 = initial_state(model, Vec2(0, 0), 0);
    s2.q_W_B = quat_from_euler_zyx({deg2rad(2), 0, 0});
    SimRun rr = run(model, env, s2, 10 * T_roll);
    VesselState s3 = initial_state(model, Vec2(0, 0), 0);
    s3.q_W_B = quat_from_euler_zyx({0, deg2rad(0.5), 0});
    SimRun rp = run(model, env, s3, 10 * T_pitch);
    std::vector<double> t, z, roll, tr, tp, pitch;
    for (const auto& b : rh.samples) {
      t.push_back(ns_to_seconds(b.t_ns));
      z.push_back(b.state.p_W.z());
    }
    for (const auto& b : rr.samples) {
      tr.push_back(ns_to_seconds(b.t_ns));
      roll.push_back(euler_zyx_from_quat(b.state.q_W_B).roll_rad);
    }
    for (const auto& b : rp.samples) {
      tp.push_back(ns_to_seconds(b.t_ns));
      pitch.push_back(euler_zyx_from_quat(b.state.q_W_B).pitch_rad);
    }
    SCOPED_TRACE(static_cast<int>(preset));
    EXPECT_NEAR(period_s(t, z, model.design_cg_z_m()) / T_heave, 1.0, 0.05);
    EXPECT_NEAR(period_s(tr, roll, 0.0) / T_roll, 1.0, 0.05);
    EXPECT_NEAR(period_s(tp, pitch, 0.0) / T_pitch, 1.0, 0.05);
  }
}

// Heave amplitude (half the peak-to-peak CG motion) over the last half of a run in
// regular head waves.
double heave_amplitude(const VesselModel& model, double amplitude_m, double wavelength_m,
                       double seconds) {
  WaveOptions w;
  w.model = WaveModel::kAiry;
  w.water_depth_m = 3.0;
  w.airy.amplitude_m = amplitude_m;
  w.airy.wavelength_m = wavelength_m;
  w.airy.direction_deg = 180;  // towards the south: head seas for a bow pointing north
  const auto waves = make_wave_field(w, RngStreams(1).stream("waves.phases"));
  Environment env;
  env.waves = waves.get();
  const SimRun r = run(model, env, initial_state(model, Vec2(0, 0), 0.0), seconds);
  double lo = 1e9, hi = -1e9;
  for (const auto& b : r.samples) {
    if (ns_to_seconds(b.t_ns) < seconds / 2) continue;
    lo = std::min(lo, b.state.p_W.z());
    hi = std::max(hi, b.state.p_W.z());
  }
  return (hi - lo) / 2;
}

TEST(Vessel, FollowsLongWavesAndIgnoresShortOnes) {
  const VesselModel model(VesselOptions{});
  const double L = model.options().hull.length_m;
  // 20 hull lengths: the hull rides the surface (quasi-static heave).
  EXPECT_NEAR(heave_amplitude(model, 0.02, 20 * L, 40) / 0.02, 1.0, 0.10);
  // Shorter than a quarter hull length: the pressure averages out along the hull.
  EXPECT_LT(heave_amplitude(model, 0.01, 0.2 * L, 20) / 0.01, 0.20);
}

TEST(Vessel, ConstantThrustReachesTheDampingBalanceSpeed) {
  const VesselModel model(VesselOptions{});
  VesselInputs in;
  in.thrust_command_n = {10.0, 10.0};
  const VesselState s = initial_state(model, Vec2(0, 0), 0);
  const SimRun r = run(model, calm(), s, 40, in);
  const double d1 = model.options().linear_damping[0], d2 = model.options().quadratic_damping[0];
  // 20 N = d1 u + d2 u^2
  const double u = (-d1 + std::sqrt(d1 * d1 + 4 * d2 * 20.0)) / (2 * d2);
  EXPECT_NEAR(r.samples.back().state.v_B.x() / u, 1.0, 0.02);
  EXPECT_NEAR(r.samples.back().state.v_B.y(), 0.0, 1e-6);
}

TEST(Vessel, EnergyIsConservedWithoutDampingOrForcing) {
  const VesselModel model(VesselOptions{});
  Environment env = calm();
  env.damping_enabled = false;
  const VesselState eq = initial_state(model, Vec2(0, 0), 0);
  VesselState s = eq;
  s.p_W.z() += 0.005;
  s.q_W_B = quat_from_euler_zyx({deg2rad(1.5), deg2rad(0.3), 0.2});
  s.v_B = Vec3(0.2, 0.05, 0.01);
  s.w_B = Vec3(0.05, -0.02, 0.1);
  const double e_eq = model.calm_water_energy(eq);
  const double e0 = model.calm_water_energy(s);
  const SimRun r = run(model, env, s, 60);
  const double e1 = model.calm_water_energy(r.samples.back().state);
  ASSERT_GT(e0 - e_eq, 0.0);
  // Within 0.1 % of the energy put in above the floating equilibrium.
  EXPECT_LT(std::abs(e1 - e0) / (e0 - e_eq), 1e-3)
      << "e_eq " << e_eq << " e0 " << e0 << " e1 " << e1;
}

TEST(Vessel, LosKeepsCrossTrackSmallOnStraightLegs) {
  const VesselModel model(VesselOptions{});
  MissionOptions m;
  m.type = MissionType::kWaypoints;
  m.speed_mps = 0.6;
  m.waypoints_ne_m = {{0, 0}, {40, 0}, {40, 30}};
  const auto segments = plan_mission(m, Vec2(0, 1.5), 0.0, {});
  Guidance g(model, segments, m);
  VesselState s = initial_state(model, Vec2(0, 1.5), 0.0);  // 1.5 m off the first leg
  std::vector<double> xte;
  MotionOptions mo;
  MotionSummary sum = simulate(
      model, calm(), &g, s, mo, {},
      [&](const BodySample& b) {
        const auto& p = b.state.p_W;
        // Settled parts of the straight legs.
        if (p.x() > 15 && p.x() < 38 && std::abs(p.y()) < 3) xte.push_back(p.y());
        if (p.y() > 12 && p.y() < 28 && std::abs(p.x() - 40) < 3) xte.push_back(p.x() - 40);
      },
      nullptr);
  EXPECT_TRUE(sum.mission_completed);
  ASSERT_GT(xte.size(), 1000u);
  double worst = 0;
  for (double e : xte) worst = std::max(worst, std::abs(e));
  EXPECT_LT(worst, 0.2);
}

TEST(Vessel, TransectsMissionCrossesTheRiverFourTimes) {
  const VesselModel model(VesselOptions{});
  MissionOptions m;  // defaults: 4 crossings of 13.5 m at 0.17 m/s
  const Vec2 start(0, -6.75);
  const auto segments = plan_mission(m, start, 0.0, {});
  EXPECT_NEAR(planned_length_m(segments), 54.0, 1e-12);
  Guidance g(model, segments, m);
  int crossings = 0;
  bool at_east = false;
  double max_abs_north = 0;
  MotionSummary sum = simulate(
      model, calm(), &g, initial_state(model, start, 0.0), {}, {},
      [&](const BodySample& b) {
        const double e = b.state.p_W.y();
        if (!at_east && e > 6.5) {
          at_east = true;
          ++crossings;
        } else if (at_east && e < -6.5) {
          at_east = false;
          ++crossings;
        }
        max_abs_north = std::max(max_abs_north, std::abs(b.state.p_W.x()));
      },
      nullptr);
  EXPECT_TRUE(sum.mission_completed);
  EXPECT_EQ(crossings, 4);
  EXPECT_LT(max_abs_north, 0.5);
  EXPECT_NEAR(sum.distance_m, 54.0, 2.0);
}

TEST(Vessel, SurveyLanesKeepAQuarterOfTheWidthFromTheBanks) {
  MissionOptions m;
  m.type = MissionType::kSurvey;
  m.survey_length_m = 150;
  m.survey_leg_length_m = 30;
  MissionContext ctx;  // a 20 m river along east = 0: lanes at -5 and +5
  auto legs_of = [&](const Vec2& start) {
    std::vector<MissionSegment> legs;
    for (const auto& g : plan_mission(m, start, 0.0, ctx))
      if (g.kind == MissionSegment::Kind::kLeg) legs.push_back(g);
    return legs;
  };
  for (const double lane0 : {-5.0, 5.0}) {
    const auto legs = legs_of(Vec2(3, lane0));
    // 30 m north, 10 m across, 30 m south, 10 m across, ...: 150 m are 4 legs
    // and 3 crossings, ending on the other lane where the run began.
    ASSERT_EQ(legs.size(), 7u);
    for (std::size_t i = 0; i < legs.size(); ++i) {
      EXPECT_NEAR(legs[i].to.y(), ((i + 1) / 2) % 2 == 0 ? lane0 : -lane0, 1e-12) << i;
      const double north = i % 2 ? 0.0 : (i % 4 ? -30.0 : 30.0);
      EXPECT_NEAR(legs[i].to.x() - legs[i].from.x(), north, 1e-12) << i;
    }
    EXPECT_NEAR(legs.back().to.x(), 3.0, 1e-12);
  }
  // A start off the lanes joins the lane on its side along the first leg (the
  // centre line counts as west); the planned length still holds.
  for (const Vec2& start : {Vec2(0, 0), Vec2(0, 9)}) {
    const auto legs = legs_of(start);
    EXPECT_NEAR(legs.front().to.y(), start.y() > 0 ? 5.0 : -5.0, 1e-12);
    double length = 0;
    for (const auto& g : legs) length += (g.to - g.from).norm();
    EXPECT_NEAR(length, 150.0, 1e-9);
  }
}

TEST(Vessel, SamplesBetweenPhysicsStepsLieOnTheTrajectory) {
  const VesselModel model(VesselOptions{});
  VesselInputs in;
  in.thrust_command_n = {12.0, 8.0};
  const VesselState s = initial_state(model, Vec2(0, 0), 0);
  // Samples at 13 Hz fall between 400 Hz steps; at 1/80 s they land on steps.
  std::vector<TimeNs> times = sample_times(13.0, 5.0);
  std::vector<BodySample> phys, cam;
  MotionOptions mo;
  mo.max_duration_s = 5;
  mo.fixed_inputs = in;
  simulate(
      model, calm(), nullptr, s, mo, times, [&](const BodySample& b) { phys.push_back(b); },
      [&](const BodySample& b) { cam.push_back(b); });
  ASSERT_EQ(cam.size(), times.size());
  for (std::size_t k = 0; k < cam.size(); ++k) EXPECT_EQ(cam[k].t_ns, times[k]);
  // Against a run whose physics steps land on the sample times (rate 13 * 40 Hz):
  // the same trajectory to RK4 accuracy.
  VesselOptions fine = model.options();
  fine.physics_rate_hz = 520;
  const VesselModel model_fine(fine);
  std::vector<BodySample> ref;
  mo.physics_rate_hz = 520;
  simulate(model_fine, calm(), nullptr, s, mo, times, nullptr,
           [&](const BodySample& b) { ref.push_back(b); });
  ASSERT_EQ(ref.size(), cam.size());
  for (std::size_t k = 0; k < cam.size(); ++k)
    EXPECT_LT((cam[k].state.p_W - ref[k].state.p_W).norm(), 1e-6) << k;
}

TEST(Vessel, SameInputsSameBytes) {
  const VesselModel model(VesselOptions{});
  MissionOptions m;
  m.type = MissionType::kStraight;
  m.survey_length_m = 5;
  auto once = [&] {
    Guidance g(model, plan_mission(m, Vec2(0, 0), 0.0, {}), m);
    std::vector<double> bytes;
    simulate(
        model, calm(), &g, initial_state(model, Vec2(0, 0), 0.0), {}, {},
        [&](const BodySample& b) {
          bytes.push_back(b.state.p_W.x());
          bytes.push_back(b.state.q_W_B.w());
        },
        nullptr);
    return bytes;
  };
  const auto a = once(), b = once();
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0);
}

TEST(Vessel, BadInputIsAClearError) {
  VesselOptions o;
  o.mass_kg = -3;
  EXPECT_THROW(VesselModel{o}, UserError);
  o.mass_kg = 1e6;  // sinks
  try {
    VesselModel model(o);
    FAIL();
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("vessel.mass_kg"), std::string::npos) << e.what();
  }
  o = VesselOptions{};
  o.hull.length_m = std::nan("");
  EXPECT_THROW(VesselModel{o}, UserError);
  MissionOptions m;
  m.type = MissionType::kWaypoints;
  m.waypoints_ne_m = {{1, 1}};
  EXPECT_THROW(plan_mission(m, Vec2(0, 0), 0, {}), UserError);
}

}  // namespace
}  // namespace driftlab::sim
