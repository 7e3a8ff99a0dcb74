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

struct RenderSequence::Impl {
  Scenario sc;
  bool depth, masks, profile;
  Trajectory poses;
  std::vector<FrameTruth> truth;
  RenderSequenceSummary summary;
  std::unique_ptr<sim::StereoRenderer> renderer;
  RngStreams rng;
  std::unique_ptr<CameraStage> camera;
  std::vector<sim::SampleTime> stamps;
  std::size_t k = 0;

  Impl(const Scenario& given, int max_frames, bool depth_, bool masks_, bool profile_)
      : sc(given), depth(depth_), masks(masks_), profile(profile_), rng(given.seed) {
    if (max_frames > 0) sc.pipeline.max_frames = max_frames;
    validate_scenario(sc, "scenario '" + sc.name + "'");
    depth = depth || sc.render.ground_truth_depth;
    simulate_truth();
    const auto t_scene = SteadyClock::now();
    const auto [north_min, north_max] = north_extent();
    const sim::SceneGeometry scene = scenes::build_scene(sc.scene, sc.seed, north_min, north_max);
    summary.scene_build_s = seconds_since(t_scene);
    renderer = std::make_unique<sim::StereoRenderer>(rig_of(sc.sensors.camera), sc.render);
    renderer->upload(scene);
    set_water_surface(renderer.get(), sc);
    renderer->set_profiling(profile);
    summary.triangles = renderer->triangles();
    summary.context = renderer->context_description();
    camera = std::make_unique<CameraStage>(sc, renderer.get(), rng);
    stamps = sim::camera_frame_times(sc.sensors.camera, rng, motion_end_s(sc));
  }

  // Ground-truth camera poses along the mission.
  void simulate_truth() {
    const SE3 T_B_C = camera_mount_T_B_C(sc.sensors.camera.mount);
    simulate_scenario_motion(sc, nullptr, [&](const sim::BodySample& b) {
      poses.push_back({b.t_ns, b.state.T_W_B() * T_B_C});
      Vec6 twist;
      twist << b.state.v_B, b.state.w_B;
      truth.push_back({ns_to_seconds(b.t_ns), b.state.T_W_B(), twist});
    });
  }

  std::pair<double, double> north_extent() const {
    double north_min = 0, north_max = 0;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const double n = poses[i].T_W_C.translation().x();
      north_min = i ? std::min(north_min, n) : n;
      north_max = i ? std::max(north_max, n) : n;
    }
    return {north_min, north_max};
  }
};

RenderSequence::RenderSequence(const Scenario& scenario, int max_frames, bool depth, bool masks,
                               bool profile)
    : impl_(std::make_unique<Impl>(scenario, max_frames, depth, masks, profile)) {}

RenderSequence::~RenderSequence() = default;

std::optional<RenderSequence::Frame> RenderSequence::next() {
  Impl& m = *impl_;
  while (m.k < m.poses.size() && m.k < m.stamps.size() && m.stamps[m.k].dropped) ++m.k;
  if (m.k >= m.poses.size()) return std::nullopt;
  const std::size_t k = m.k++;
  const auto t0 = SteadyClock::now();
  Frame f;
  f.k = k;
  f.t_ns = k < m.stamps.size() ? m.stamps[k].t_stamp_ns : m.poses[k].t_ns;
  // Ground truth: the ideal pinhole camera at the centre of the exposure.
  f.images = m.camera->capture_with_truth(m.truth[k], m.depth, m.masks, &f.moving_px);
  m.summary.render_s += seconds_since(t0);
  ++m.summary.frames;
  return f;
}

const Trajectory& RenderSequence::poses() const { return impl_->poses; }

RenderSequenceSummary RenderSequence::summary() const {
  RenderSequenceSummary s = impl_->summary;
  s.pairs_per_s = s.render_s > 0 ? static_cast<double>(s.frames) / s.render_s : 0;
  if (impl_->profile) s.passes = impl_->renderer->pass_times();
  return s;
}

RenderSequenceSummary render_sequence(const Scenario& sc, const std::filesystem::path& out_dir,
                                      const RenderSequenceOptions& options) {
  AtomicDirectory dir(out_dir, options.replace_existing);
  RenderSequence frames(sc, options.max_frames, options.depth, options.masks, options.profile);
  std::filesystem::create_directories(dir.path() / "left");
  std::filesystem::create_directories(dir.path() / "right");
  const bool depth = options.depth || sc.render.ground_truth_depth;
  if (depth) std::filesystem::create_directories(dir.path() / "depth");
  if (options.masks) std::filesystem::create_directories(dir.path() / "mask");
  AtomicFile times(dir.path() / "times.csv");
  times.write("frame,t_ns,moving_px\n");
  while (const auto f = frames.next()) {
    const std::string name = fmt::format("{:06d}", f->k);
    write_png(dir.path() / "left" / (name + ".png"), f->images.left);
    write_png(dir.path() / "right" / (name + ".png"), f->images.right);
    if (depth) write_pfm(dir.path() / "depth" / (name + ".pfm"), f->images.depth_left);
    if (options.masks) write_png(dir.path() / "mask" / (name + ".png"), f->images.moving_left);
    times.write(fmt::format("{},{},{}\n", f->k, f->t_ns, yaml::format_double(f->moving_px)));
  }
  times.commit();
  write_tum(dir.path() / "groundtruth.tum", frames.poses());
  dir.commit();
  return frames.summary();
}

}  // namespace driftlab::pipeline
