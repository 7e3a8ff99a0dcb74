// The basin paper's reference simulated (pipeline/overhead_stage.hpp): the overhead camera's
// rendered frames, tracked, give the markers' positions that projective geometry predicts.
#include "pipeline/overhead_stage.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/rotation.hpp"
#include "pipeline/scenario.hpp"
#include "scenes/build_scene.hpp"
#include "scenes/ship_model.hpp"
#include "sim/physics/vessel/vessel_model.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::pipeline {
namespace {

using driftlab::test::kPi;

// Where the camera at C sees a point p on the horizontal plane at height z: the ray's
// crossing, as a perfectly calibrated overhead camera maps it.
Vec3 seen_on_plane(const Vec3& C, const Vec3& p, double z) {
  return C + (p - C) * ((z - C.z()) / (p.z() - C.z()));
}

TEST(OverheadStage, TrackedMarkersLandWhereTheirRaysCrossTheMarkerPlane) {
  const Scenario sc = load_scenario(test::source_dir() / "scenarios" / "basin_exp1.yaml", {});
  ASSERT_TRUE(sc.sensors.overhead.enabled);
  const sim::SceneGeometry basin = scenes::build_scene(sc.scene, sc.seed, 0.0, 3.0);
  const double z_cg = sim::VesselModel(sc.vessel).design_cg_z_m();
  // Level, turned, and heeled and trimmed (whose markers the camera sees shifted sideways).
  struct Pose {
    double n, e, yaw_deg, roll_deg, pitch_deg, heave_m;
  };
  const std::vector<Pose> poses{{1.0, 0.0, 0, 0, 0, 0},
                                {1.6, 0.12, 17, 0, 0, 0},
                                {2.2, -0.2, -8, 6, 0, 0},
                                {0.7, 0.1, 3, -4, 3, 0.01}};
  MissionTruth mission;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const Pose& p = poses[k];
    const SE3 T_W_B(quat_from_euler_zyx(
                        {p.roll_deg * kPi / 180, p.pitch_deg * kPi / 180, p.yaw_deg * kPi / 180}),
                    Vec3(p.n, p.e, z_cg + p.heave_m));
    const TimeNs t = 50'000'000LL * static_cast<TimeNs>(k);
    mission.frames.push_back({ns_to_seconds(t), T_W_B, Vec6::Zero()});
    mission.camera_gt.push_back({t, T_W_B});
  }
  const auto dir = test::fresh_temp_dir("overhead_stage");
  const OverheadResult out = run_overhead_camera(sc, basin, mission, dir);
  EXPECT_EQ(out.record.tracked, poses.size());
  EXPECT_TRUE(std::filesystem::exists(dir / "overhead_reference.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir / "overhead_frame.png"));

  const Vec3 C = overhead_camera_pose(sc).translation();
  const sim::MarkerOptions& m = sc.sensors.overhead.markers;
  const double zf = scenes::marker_face_z_B(sc.vessel.hull);
  EXPECT_NEAR(out.record.plane_z_m, z_cg + zf, 1e-12);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const SE3& T = mission.frames[k].T_W_B;
    const Vec3 red = seen_on_plane(C, T * Vec3(m.centre_forward_m + m.separation_m / 2, 0, zf),
                                   out.record.plane_z_m);
    const Vec3 green = seen_on_plane(C, T * Vec3(m.centre_forward_m - m.separation_m / 2, 0, zf),
                                     out.record.plane_z_m);
    const Vec3 mid = 0.5 * (red + green);
    const double heading = std::atan2(red.y() - green.y(), red.x() - green.x());
    ASSERT_TRUE(out.reference.valid[k]);
    EXPECT_NEAR(out.reference.north_m[k], mid.x(), 1e-3) << k;
    EXPECT_NEAR(out.reference.east_m[k], mid.y(), 1e-3) << k;
    EXPECT_NEAR(std::remainder(out.reference.heading_rad[k] - heading, 2 * kPi), 0.0,
                0.1 * kPi / 180)
        << k;
    // What the reference cannot know: a heel moves the markers, 9 cm above the centre of
    // gravity, sideways by millimetres from the point under them at the centre's height.
    if (poses[k].roll_deg != 0) {
      const Vec3 body_mid = T * Vec3(m.centre_forward_m, 0, 0);
      EXPECT_GT(std::hypot(mid.x() - body_mid.x(), mid.y() - body_mid.y()), 0.004) << k;
    }
  }
}

TEST(OverheadStage, RefusedOutsideABasin) {
  Scenario sc = load_scenario(test::source_dir() / "scenarios" / "basin_exp1.yaml", {});
  sc.scene.type = scenes::SceneType::kRiverReach;
  const std::string message = driftlab::test::user_error_of([&] { overhead_camera_pose(sc); });
  EXPECT_NE(message.find("expected scene.type wave_basin"), std::string::npos) << message;
  const std::string invalid = driftlab::test::user_error_of([&] { validate_scenario(sc, "s"); });
  EXPECT_NE(invalid.find("sensors.overhead.enabled with scene.type: got true with river_reach"),
            std::string::npos)
      << invalid;
}

}  // namespace
}  // namespace driftlab::pipeline
