#include "pipeline/render_stage.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/stopwatch.hpp"
#include "core/trajectory_io.hpp"
#include "core/yaml_io.hpp"
#include "pipeline/camera_stage.hpp"
#include "pipeline/frame_source.hpp"
#include "pipeline/run.hpp"
#include "scenes/build_scene.hpp"
#include "sim/physics/waves/wave_field.hpp"
#include "sim/render/renderer.hpp"

namespace driftlab::pipeline {
namespace {

void write_png(const std::filesystem::path& path, const sim::GrayImage& img) {
  const cv::Mat m(img.height, img.width, CV_8UC1, const_cast<std::uint8_t*>(img.pixels.data()));
  if (!cv::imwrite(path.string(), m))
    throw UserError(fmt::format("{}: cannot write the image", path.string()));
}

void write_pfm(const std::filesystem::path& path, const sim::DepthImage& d) {
  const cv::Mat m(d.height, d.width, CV_32FC1, const_cast<float*>(d.depth_m.data()));
  if (!cv::imwrite(path.string(), m))
    throw UserError(fmt::format("{}: cannot write the depth image", path.string()));
}

}  // namespace

std::string RenderSequenceSummary::brief() const {
  std::string out = fmt::format(
      "rendered {} stereo pairs ({} triangles) at {:.1f} pairs/s; scene built in "
      "{:.2f} s; {}",
      frames, triangles, pairs_per_s, scene_build_s, context);
  if (passes && frames > 0) {
    const double frame_ms = 1e3 * render_s / static_cast<double>(frames);
    out += fmt::format(
        "\nprofile: {:.1f} ms a frame, of which the renderer's passes {:.1f} ms and the camera "
        "stage's own work (exposure, blur, lens, noise) and the rest {:.1f} ms; the passes:\n{}",
        frame_ms, passes->total_ms() / static_cast<double>(frames),
        frame_ms - passes->total_ms() / static_cast<double>(frames), describe_passes(*passes));
  }
  return out;
}

void set_water_surface(sim::StereoRenderer* renderer, const Scenario& sc) {
  const RngStreams rng(sc.seed);
  renderer->set_waves(sim::wave_components(sc.water.waves, rng.stream("waves.phases")));
  renderer->set_ripples(std::make_shared<sim::RippleMaps>(sc.water.wind, sc.water.current,
                                                          rng.stream("water.ripples")));
  renderer->set_sway(sim::vegetation_sway(sc.water.wind, rng.stream("wind.gusts")));
}

bool scene_moves(const Scenario& sc, const sim::SceneGeometry& scene) {
  if (!scene.movers.empty()) return true;
  if (sim::vegetation_sway(sc.water.wind, Rng(0)).empty()) return false;
  return std::any_of(scene.meshes.begin(), scene.meshes.end(),
                     [](const sim::Mesh& m) { return !m.sway.empty(); });
}

StereoRig rig_of(const sim::CameraOptions& c) {
  StereoRig rig;
  rig.camera.fx = c.fx_px;
  rig.camera.fy = c.fy_px;
  rig.camera.cx = c.cx_px;
  rig.camera.cy = c.cy_px;
  rig.camera.width = c.width_px;
  rig.camera.height = c.height_px;
  rig.baseline_m = c.baseline_m;
  return rig;
}

RenderSequenceSummary render_sequence(const Scenario& sc_in, const std::filesystem::path& out_dir,
                                      const RenderSequenceOptions& options) {
  Scenario sc = sc_in;
  if (options.max_frames > 0) sc.pipeline.max_frames = options.max_frames;
  validate_scenario(sc, "scenario '" + sc.name + "'");
  AtomicDirectory dir(out_dir, options.replace_existing);
  std::filesystem::create_directories(dir.path() / "left");
  std::filesystem::create_directories(dir.path() / "right");
  if (options.depth) std::filesystem::create_directories(dir.path() / "depth");
  if (options.masks) std::filesystem::create_directories(dir.path() / "mask");

  // Ground-truth camera poses along the mission.
  const SE3 T_B_C = camera_mount_T_B_C(sc.sensors.camera.mount);
  Trajectory poses;
  std::vector<FrameTruth> truth;
  simulate_scenario_motion(sc, nullptr, [&](const sim::BodySample& b) {
    poses.push_back({b.t_ns, b.state.T_W_B() * T_B_C});
    Vec6 twist;
    twist << b.state.v_B, b.state.w_B;
    truth.push_back({ns_to_seconds(b.t_ns), b.state.T_W_B(), twist});
  });
  double north_min = 0, north_max = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const double n = poses[i].T_W_C.translation().x();
    north_min = i ? std::min(north_min, n) : n;
    north_max = i ? std::max(north_max, n) : n;
  }

  RenderSequenceSummary summary;
  const auto t_scene = SteadyClock::now();
  const sim::SceneGeometry scene = scenes::build_scene(sc.scene, sc.seed, north_min, north_max);
  summary.scene_build_s = seconds_since(t_scene);
  sim::StereoRenderer renderer(rig_of(sc.sensors.camera), sc.render);
  renderer.upload(scene);
  set_water_surface(&renderer, sc);
  renderer.set_profiling(options.profile);
  summary.triangles = renderer.triangles();
  summary.context = renderer.context_description();

  AtomicFile times(dir.path() / "times.csv");
  times.write("frame,t_ns,moving_px\n");
  const bool depth = options.depth || sc.render.ground_truth_depth;
  double render_s = 0;
  // The images as the camera delivers them (blur, rig error, lens, noise) at
  // its clock's stamps; dropped frames are not written.
  const RngStreams rng(sc.seed);
  CameraStage camera(sc, &renderer, rng);
  const std::vector<sim::SampleTime> stamps =
      sim::camera_frame_times(sc.sensors.camera, rng, motion_end_s(sc));
  std::size_t delivered = 0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    if (k < stamps.size() && stamps[k].dropped) continue;
    const auto t0 = SteadyClock::now();
    double moving_px = 0;
    // Ground truth: the ideal pinhole camera at the centre of the exposure.
    sim::StereoImages img = camera.capture_with_truth(truth[k], depth, options.masks, &moving_px);
    render_s += seconds_since(t0);
    ++delivered;
    const std::string name = fmt::format("{:06d}", k);
    write_png(dir.path() / "left" / (name + ".png"), img.left);
    write_png(dir.path() / "right" / (name + ".png"), img.right);
    if (depth) write_pfm(dir.path() / "depth" / (name + ".pfm"), img.depth_left);
    if (options.masks) write_png(dir.path() / "mask" / (name + ".png"), img.moving_left);
    times.write(fmt::format("{},{},{}\n", k,
                            k < stamps.size() ? stamps[k].t_stamp_ns : poses[k].t_ns,
                            yaml::format_double(moving_px)));
  }
  times.commit();
  write_tum(dir.path() / "groundtruth.tum", poses);
  dir.commit();
  summary.frames = delivered;
  summary.render_s = render_s;
  summary.pairs_per_s = render_s > 0 ? static_cast<double>(delivered) / render_s : 0;
  if (options.profile) summary.passes = renderer.pass_times();
  return summary;
}

}  // namespace driftlab::pipeline
