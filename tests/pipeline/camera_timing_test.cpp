// Cameras as they are (docs/sensors.md, "Shutter and stereo timing"): a rolling shutter and an
// unsynchronised stereo pair, each against its closed form on rendered frames.
//
// The scene is a white wall facing the camera over a black sky, so that each
// row's edge position is the count of white pixels: x_e = W - 0.5 - count,
// quantised to a pixel per row without anti-aliasing. Where the true edge
// moves across rows the quantisation averages out over windows of rows (and in
// a line fit over all of them), which is how the sub-pixel claims are checked.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "pipeline/camera_stage.hpp"
#include "pipeline/render_stage.hpp"
#include "pipeline/run.hpp"

namespace driftlab::pipeline {
namespace {

// The basin paper's camera (rolling shutter, free-running pair) without noise, looking north
// from the origin, level.
Scenario ps3_eye_scenario() {
  Scenario sc;
  sc.sensors.camera.apply_preset(sim::CameraPreset::kPs3Eye);
  sc.sensors.camera.noise.enabled = false;
  sc.sensors.camera.right_offset_spread_ms = 0;
  return sc;
}

// A wall facing south (towards the camera) `north_m` ahead, its west edge through east_m at
// depth 0 and leaning east by `lean` (east per metre downwards), white on a black sky.
sim::SceneGeometry wall_scene(double north_m, double east_m, double lean = 0.0) {
  sim::SceneGeometry s;
  s.lighting.ambient = 2.0f;  // saturates to white
  s.lighting.diffuse = 0.0f;
  s.lighting.sky_brightness = 0.0f;
  s.lighting.fog_distance_m = 1e9f;
  s.water.enabled = false;
  sim::Mesh m;
  m.name = "wall";
  m.material.albedo = 1.0f;
  auto vertex = [&](double east, double down) {
    return sim::Vertex{static_cast<float>(north_m),
                       static_cast<float>(east + lean * down),
                       static_cast<float>(down),
                       -1.f,
                       0.f,
                       0.f,
                       0.f,
                       0.f};
  };
  for (const auto& [e, d] : {std::pair{0.0, -50.0}, {50.0, -50.0}, {50.0, 50.0}, {0.0, 50.0}})
    m.vertices.push_back(vertex(east_m + e, d));
  m.indices = {0, 1, 2, 0, 2, 3};
  s.meshes.push_back(m);
  return s;
}

struct TimingRendering {
  TimingRendering(const Scenario& sc, const sim::SceneGeometry& scene)
      : renderer(rig_of(sc.sensors.camera), sc.render) {
    renderer.upload(scene);
  }
  sim::StereoRenderer renderer;
};

// The edge's column in each row, from the count of white pixels.
std::vector<double> edge_columns(const sim::GrayImage& img) {
  std::vector<double> x(static_cast<std::size_t>(img.height));
  for (int y = 0; y < img.height; ++y) {
    int white = 0;
    for (int c = 0; c < img.width; ++c) white += img.at(c, y) > 127;
    x[static_cast<std::size_t>(y)] = img.width - 0.5 - white;
  }
  return x;
}

// Least-squares line x = a + b (r - centre) through per-row values: {a, b}.
std::pair<double, double> line_fit(const std::vector<double>& x) {
  const double centre = (static_cast<double>(x.size()) - 1) / 2;
  double sxx = 0, sxy = 0, sy = 0;
  for (std::size_t r = 0; r < x.size(); ++r) {
    const double d = static_cast<double>(r) - centre;
    sxx += d * d;
    sxy += d * x[r];
    sy += x[r];
  }
  return {sy / static_cast<double>(x.size()), sxy / sxx};
}

// Largest difference of the means over windows of `window` rows.
double largest_window_error(const std::vector<double>& got, const std::vector<double>& want,
                            int window) {
  double worst = 0;
  for (std::size_t r0 = 0; r0 + window <= got.size(); r0 += window / 2) {
    double g = 0, w = 0;
    for (std::size_t r = r0; r < r0 + window; ++r) {
      g += got[r];
      w += want[r];
    }
    worst = std::max(worst, std::abs(g - w) / window);
  }
  return worst;
}

FrameTruth moving(const Vec6& twist_B) {
  FrameTruth f;
  f.t_s = 1.0;
  f.T_W_B = SE3();  // at the origin, heading north, level
  f.twist_B = twist_B;
  return f;
}

TEST(CameraTiming, ShutterBandsCoverEveryRowOnceAtTheirCentreRowsTimes) {
  const std::vector<ShutterBand> bands = shutter_bands(10, 1e-3, 3);
  ASSERT_EQ(bands.size(), 3u);
  EXPECT_EQ(bands[0].row_begin, 0);
  EXPECT_EQ(bands[0].row_end, 4);  // 10 = 4 + 3 + 3
  EXPECT_EQ(bands[1].row_end, 7);
  EXPECT_EQ(bands[2].row_end, 10);
  // Row r at (r - 4.5) ms; band centres at rows 1.5, 5 and 8.
  EXPECT_DOUBLE_EQ(bands[0].dt_s, -3e-3);
  EXPECT_DOUBLE_EQ(bands[1].dt_s, 0.5e-3);
  EXPECT_DOUBLE_EQ(bands[2].dt_s, 3.5e-3);
  EXPECT_EQ(shutter_bands(480, 65e-6, 1)[0].dt_s, 0.0);  // one band: the frame time
}

// The column of the wall's edge (wall_scene(Z, e, lean)) in row `row` of a level camera at
// (0, p, 0) heading psi: the edge point (Z, e + lean d, d) in the optical frame is
// z = Z cos psi + (e + lean d - p) sin psi, x = -Z sin psi + (e + lean d - p) cos psi, y = d,
// and the row fixes d through row - cy = f d / z.
double edge_column(const sim::CameraOptions& cam, double row, double psi, double p, double Z,
                   double e, double lean) {
  const double c = std::cos(psi), s = std::sin(psi), dv = row - cam.cy_px;
  const double d = dv * (Z * c + (e - p) * s) / (cam.fy_px - dv * lean * s);
  const double z = Z * c + (e + lean * d - p) * s, x = -Z * s + (e + lean * d - p) * c;
  return cam.cx_px + cam.fx_px * x / z;
}

// The edge's columns when row r is seen from (0, v dt, 0) heading w dt, dt = the row's time.
std::vector<double> rolling_edge(const sim::CameraOptions& cam, double w, double v, double Z,
                                 double e, double lean) {
  std::vector<double> x(static_cast<std::size_t>(cam.height_px));
  for (std::size_t row = 0; row < x.size(); ++row) {
    const double dt =
        (static_cast<double>(row) - (cam.height_px - 1) / 2.0) * cam.line_delay_us * 1e-6;
    x[row] = edge_column(cam, static_cast<double>(row), w * dt, v * dt, Z, e, lean);
  }
  return x;
}

// The wall's edge leans so that the rows see it at every sub-pixel phase: their
// one-pixel quantisation averages out over a few rows.
constexpr double kLean = 0.137;

TEST(CameraTiming, RollingShutterShearsAVerticalEdgeUnderAYawRate) {
  // Turning right at 0.5 rad/s: row r is exposed (r - 239.5) line delays after the frame time,
  // when the camera has turned by w dt, so the edge at bearing beta lies at about
  // u = cx + f tan(beta - w dt(r)): line_delay * w * f = 0.017 px further left per row.
  Scenario sc = ps3_eye_scenario();
  const auto& cam = sc.sensors.camera;
  const double w = 0.5, north = 4.0, east = 0.3;
  TimingRendering r(sc, wall_scene(north, east, kLean));
  CameraStage stage(sc, &r.renderer, RngStreams(1));
  Vec6 twist;
  twist << 0, 0, 0, 0, 0, w;
  const std::vector<double> got = edge_columns(stage.capture(moving(twist)).left);
  EXPECT_GT(stage.last_rolling_bands(), 20);
  const std::vector<double> want = rolling_edge(cam, w, 0, north, east, kLean);
  EXPECT_LT(largest_window_error(got, want, 32), 0.1);
  EXPECT_NEAR(line_fit(got).first, line_fit(want).first, 0.05);
  // A global shutter sees the edge at the middle row's pose in every row; the shear per row is
  // the difference of the two slopes.
  sc.sensors.camera.shutter = sim::Shutter::kGlobal;
  CameraStage global(sc, &r.renderer, RngStreams(1));
  const std::vector<double> straight = edge_columns(global.capture(moving(twist)).left);
  EXPECT_EQ(global.last_rolling_bands(), 1);
  std::vector<double> still = want;
  for (std::size_t row = 0; row < still.size(); ++row)
    still[row] = edge_column(cam, static_cast<double>(row), 0, 0, north, east, kLean);
  EXPECT_LT(largest_window_error(straight, still, 32), 0.1);
  const double shear = line_fit(got).second - line_fit(straight).second;
  const double closed_form = -cam.line_delay_us * 1e-6 * w * cam.fx_px;  // at the centre column
  EXPECT_NEAR(shear, closed_form * (1 + std::pow(east / north, 2)), 0.02 * std::abs(closed_form));
  std::printf(
      "[ measured ] yaw: %d bands, edge within %.3f px (32-row means), shear %.5f px/row "
      "(closed form %.5f)\n",
      stage.last_rolling_bands(), largest_window_error(got, want, 32), shear,
      closed_form * (1 + std::pow(east / north, 2)));
}

TEST(CameraTiming, RollingShutterShiftsRowsByTheirOwnTranslation) {
  // Moving east at 1 m/s past a wall 3 m ahead: the edge at row r lies at
  // u = cx + f (east + lean d - v dt(r)) / Z, line_delay * v * f / Z = 0.011 px per row more.
  Scenario sc = ps3_eye_scenario();
  const auto& cam = sc.sensors.camera;
  const double v = 1.0, north = 3.0, east = 0.2;
  TimingRendering r(sc, wall_scene(north, east, kLean));
  CameraStage stage(sc, &r.renderer, RngStreams(1));
  Vec6 twist;
  twist << 0, v, 0, 0, 0, 0;  // body FRD: y is starboard, east when heading north
  const std::vector<double> got = edge_columns(stage.capture(moving(twist)).left);
  const std::vector<double> want = rolling_edge(cam, 0, v, north, east, kLean);
  EXPECT_LT(largest_window_error(got, want, 32), 0.1);
  const double per_row = cam.line_delay_us * 1e-6 * v * cam.fx_px / north;
  EXPECT_NEAR(line_fit(got).second, kLean - per_row, 0.02 * per_row);
  EXPECT_NEAR(line_fit(got).first, cam.cx_px + cam.fx_px * east / north, 0.05);
  std::printf(
      "[ measured ] translation: %d bands, edge within %.3f px (32-row means), %.5f px/row "
      "(closed form %.5f)\n",
      stage.last_rolling_bands(), largest_window_error(got, want, 32), kLean - line_fit(got).second,
      per_row);
}

TEST(CameraTiming, AnUnsynchronisedRightImageSeesTheRigWhereItIsAtItsOwnTime) {
  // Global shutter, right image 10 ms late, moving east at 1 m/s past a wall 3 m ahead whose
  // edge leans (so that rows sample it at every sub-pixel phase): the edge's disparity is
  // f (B + v offset) / Z instead of f B / Z, which the VO reads as a wrong depth.
  Scenario sc = ps3_eye_scenario();
  auto& cam = sc.sensors.camera;
  cam.shutter = sim::Shutter::kGlobal;
  cam.right_offset_ms = 10;
  const double v = 1.0, north = 3.0, east = 0.2;
  TimingRendering r(sc, wall_scene(north, east, kLean));
  Vec6 twist;
  twist << 0, v, 0, 0, 0, 0;
  CameraStage stage(sc, &r.renderer, RngStreams(1));
  const sim::StereoImages img = stage.capture(moving(twist));
  EXPECT_DOUBLE_EQ(stage.last_right_offset_s(), 0.010);
  const double disparity =
      line_fit(edge_columns(img.left)).first - line_fit(edge_columns(img.right)).first;
  EXPECT_NEAR(disparity, cam.fx_px * (cam.baseline_m + v * 0.010) / north, 0.05);
  cam.right_offset_ms = 0;
  CameraStage synced(sc, &r.renderer, RngStreams(1));
  const sim::StereoImages same = synced.capture(moving(twist));
  EXPECT_NEAR(line_fit(edge_columns(same.left)).first - line_fit(edge_columns(same.right)).first,
              cam.fx_px * cam.baseline_m / north, 0.05);
  EXPECT_EQ(same.left.pixels, img.left.pixels);  // the left image is not moved
}

TEST(CameraTiming, AFreeRunningPairDrawsItsOffsetPerRunAndJittersPerFrame) {
  sim::CameraOptions cam;
  cam.apply_preset(sim::CameraPreset::kPs3Eye);
  ASSERT_NEAR(cam.right_offset_spread_ms, 16.67, 0.01);
  // Per run: uniform in +-spread, the same for the same seed.
  double sum = 0, sum_sq = 0, largest = 0;
  const int runs = 2000;
  for (int seed = 0; seed < runs; ++seed) {
    const double o = run_right_offset_s(cam, RngStreams(static_cast<std::uint64_t>(seed)));
    EXPECT_EQ(o, run_right_offset_s(cam, RngStreams(static_cast<std::uint64_t>(seed))));
    sum += o;
    sum_sq += o * o;
    largest = std::max(largest, std::abs(o));
  }
  const double spread_s = cam.right_offset_spread_ms * 1e-3;
  EXPECT_LE(largest, spread_s);
  EXPECT_GT(largest, 0.99 * spread_s);
  EXPECT_NEAR(sum / runs, 0.0, 4 * spread_s / std::sqrt(3.0 * runs));
  EXPECT_NEAR(std::sqrt(sum_sq / runs), spread_s / std::sqrt(3.0), 0.03 * spread_s);
  // Per frame: Gaussian jitter about the run's offset, truncated at 3 sigma.
  Scenario sc = ps3_eye_scenario();
  sc.sensors.camera.width_px = 64;  // a small image: only the offsets are looked at
  sc.sensors.camera.height_px = 48;
  sc.sensors.camera.cx_px = 31.5;
  sc.sensors.camera.cy_px = 23.5;
  sc.sensors.camera.right_offset_ms = 2;
  sc.sensors.camera.right_offset_jitter_ms = 1;
  TimingRendering r(sc, wall_scene(4, 0));
  CameraStage stage(sc, &r.renderer, RngStreams(3));
  double s = 0, ss = 0;
  const int frames = 400;
  for (int k = 0; k < frames; ++k) {
    stage.capture(moving(Vec6::Zero()));
    const double o = stage.last_right_offset_s() * 1e3 - 2;
    EXPECT_LE(std::abs(o), 3.0);
    s += o;
    ss += o * o;
  }
  EXPECT_NEAR(s / frames, 0.0, 4 / std::sqrt(frames));
  EXPECT_NEAR(std::sqrt(ss / frames), 0.986, 0.1);  // a 3-sigma-truncated unit normal's sd
}

TEST(CameraTiming, OffsetsAndReadoutsBeyondTheFramePeriodAreClearErrors) {
  Scenario sc = ps3_eye_scenario();
  validate_scenario(sc, "test");
  sc.sensors.camera.line_delay_us = 200;  // 480 rows x 200 us = 96 ms > 50 ms
  EXPECT_THROW(validate_scenario(sc, "test"), UserError);
  sc.sensors.camera.line_delay_us = 0;
  EXPECT_THROW(validate_scenario(sc, "test"), UserError);
  sc.sensors.camera.shutter = sim::Shutter::kGlobal;
  validate_scenario(sc, "test");
  sc.sensors.camera.right_offset_ms = 20;  // + 0 spread: within 25 ms
  validate_scenario(sc, "test");
  sc.sensors.camera.right_offset_jitter_ms = 2;  // 20 + 6 > 25
  EXPECT_THROW(validate_scenario(sc, "test"), UserError);
}

}  // namespace
}  // namespace driftlab::pipeline
