#include "pipeline/overhead_stage.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <opencv2/imgcodecs.hpp>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "pipeline/render_stage.hpp"
#include "scenes/ship_model.hpp"
#include "scenes/wave_basin.hpp"
#include "sim/physics/vessel/vessel_model.hpp"
#include "sim/render/renderer.hpp"

namespace driftlab::pipeline {
namespace {

std::string cell(double v) { return std::isfinite(v) ? fmt::format("{:.6f}", v) : ""; }

std::string point_cells(const std::optional<cv::Point2d>& p) {
  return p ? fmt::format("{:.3f},{:.3f}", p->x, p->y) : std::string(",");
}

void write_reference_csv(const std::filesystem::path& path,
                         const std::vector<sim::MarkerFix>& fixes, const sim::MarkerReference& r) {
  AtomicFile f(path);
  f.write(
      "t_ns,red_u_px,red_v_px,green_u_px,green_v_px,north_m,east_m,heading_deg,surge_m_s,"
      "sway_m_s,valid\n");
  for (std::size_t k = 0; k < r.t_ns.size(); ++k)
    f.write(fmt::format("{},{},{},{},{},{},{},{},{}\n", r.t_ns[k], point_cells(fixes[k].red),
                        point_cells(fixes[k].green), cell(r.north_m[k]), cell(r.east_m[k]),
                        cell(r.heading_rad[k] * 180 / std::numbers::pi), cell(r.surge_m_s[k]),
                        cell(r.sway_m_s[k]), r.valid[k] ? 1 : 0));
  f.commit();
}

}  // namespace

PinholeCamera overhead_camera(const sim::OverheadOptions& o) {
  PinholeCamera c;
  c.width = o.width_px;
  c.height = o.height_px;
  c.fx = c.fy = 0.5 * o.width_px / std::tan(0.5 * o.hfov_deg * std::numbers::pi / 180);
  c.cx = 0.5 * (o.width_px - 1);
  c.cy = 0.5 * (o.height_px - 1);
  return c;
}

SE3 overhead_camera_pose(const Scenario& sc) {
  if (sc.scene.type != scenes::SceneType::kWaveBasin)
    throw UserError(
        "sensors.overhead.enabled: the overhead camera hangs from a wave basin's ceiling; "
        "expected scene.type wave_basin");
  // Optical x along north, y along east, z down: the world's axes.
  return SE3(Eigen::Quaterniond::Identity(),
             scenes::basin_layout(sc.scene.wave_basin).camera_mount_W);
}

std::array<double, 2> pixel_to_plane_ne(const PinholeCamera& c, const SE3& T_W_C,
                                        const cv::Point2d& px, double plane_z_m) {
  const Vec3 d = T_W_C.quaternion() * Vec3((px.x - c.cx) / c.fx, (px.y - c.cy) / c.fy, 1.0);
  const Vec3 o = T_W_C.translation();
  DRIFTLAB_DEMAND(std::abs(d.z()) > 1e-9);
  const double s = (plane_z_m - o.z()) / d.z();
  return {o.x() + s * d.x(), o.y() + s * d.y()};
}

eval::PlanarReference planar_reference(const sim::MarkerReference& r) {
  eval::PlanarReference p;
  p.t_ns = r.t_ns;
  p.states.north_m = r.north_m;
  p.states.east_m = r.east_m;
  p.states.heading_rad = r.heading_rad;
  p.states.surge_m_s = r.surge_m_s;
  p.states.sway_m_s = r.sway_m_s;
  return p;
}

OverheadResult run_overhead_camera(const Scenario& sc, const sim::SceneGeometry& basin,
                                   const MissionTruth& mission, const std::filesystem::path& dir) {
  const sim::OverheadOptions& o = sc.sensors.overhead;
  const SE3 T_W_C = overhead_camera_pose(sc);
  StereoRig rig;
  rig.camera = overhead_camera(o);
  rig.baseline_m = 0.1;  // one eye is drawn; the rig wants a baseline
  sim::SceneGeometry scene = basin;
  for (sim::Mesh& m : scenes::ship_model_meshes(sc.vessel.hull, o.markers))
    scene.meshes.push_back(std::move(m));
  sim::StereoRenderer renderer(rig, sc.render, sim::ImageKind::kColour);
  renderer.upload(scene);
  set_water_surface(&renderer, sc);

  // The pixels are mapped onto the markers' plane with the model at rest, level at its design
  // draft: heave, roll and pitch move the markers off it, as they moved the paper's.
  OverheadResult out;
  OverheadRecord& rec = out.record;
  rec.plane_z_m =
      sim::VesselModel(sc.vessel).design_cg_z_m() + scenes::marker_face_z_B(sc.vessel.hull);
  std::vector<sim::MarkerFix> fixes;
  std::vector<sim::MarkerPlanePositions> planar;
  const std::size_t n = mission.frames.size();
  for (std::size_t k = 0; k < n; ++k) {
    const FrameTruth& f = mission.frames[k];
    const auto t0 = SteadyClock::now();
    renderer.set_body_pose(f.T_W_B);
    sim::ColourImage img = renderer.render_colour(T_W_C, f.t_s);
    const auto t1 = SteadyClock::now();
    const cv::Mat bgr(img.height, img.width, CV_8UC3, img.bgr.data());
    fixes.push_back(sim::track_markers(bgr, o.tracker));
    rec.track_s += seconds_since(t1);
    rec.render_s += std::chrono::duration<double>(t1 - t0).count();
    if (k == n / 2 && !cv::imwrite((dir / rec.frame_file).string(), bgr))
      throw UserError(fmt::format("{}: cannot write the image", (dir / rec.frame_file).string()));
    sim::MarkerPlanePositions p;
    p.t_ns = mission.camera_gt[k].t_ns;
    if (fixes.back().red)
      p.red_ne_m = pixel_to_plane_ne(rig.camera, T_W_C, *fixes.back().red, rec.plane_z_m);
    if (fixes.back().green)
      p.green_ne_m = pixel_to_plane_ne(rig.camera, T_W_C, *fixes.back().green, rec.plane_z_m);
    rec.tracked += p.red_ne_m && p.green_ne_m ? 1 : 0;
    planar.push_back(p);
  }
  rec.frames = n;
  out.reference = sim::marker_reference(planar);
  write_reference_csv(dir / rec.reference_file, fixes, out.reference);
  return out;
}

}  // namespace driftlab::pipeline
