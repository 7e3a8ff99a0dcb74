#include "scenes/vessels.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/rng.hpp"
#include "scenes/mesh_builder.hpp"
#include "scenes/textures.hpp"

namespace driftlab::scenes {
namespace {

constexpr int kHullSections = 12;

sim::Material painted(int texture, float albedo) {
  sim::Material m;
  m.texture = texture;
  m.albedo = albedo;
  m.double_sided = false;  // every part is a closed solid or faces outwards only
  return m;
}

struct VesselTextures {
  int hull, wheelhouse, window;
};

// The hull's shape in the vessel's frame (FRD, origin on the waterline at mid-length).
struct HullShape {
  double length, draft, freeboard;
  double deck_z(double x) const {  // the sheer: the deck rises towards the stem
    const double s = std::max(0.0, x / (length / 2));
    return -freeboard * (1 + 0.35 * s * s);
  }
};

// The hull: two sides from the keel to the sheer line, a flat bottom, the transom, the stem
// and the deck, in painted steel.
sim::Mesh hull_mesh(const std::string& name, const OtherVesselOptions& o, const HullShape& h,
                    int texture) {
  MeshBuilder b(name + ".hull", painted(texture, 0.75f));
  const auto at = [&](int i, int side, bool deck) {
    const double x = -o.length_m / 2 + o.length_m * i / kHullSections;
    const double half = vessel_half_beam(o, x) * (deck ? 1.0 : 0.6);
    return Vec3(x, side * half, deck ? h.deck_z(x) : h.draft);
  };
  for (int i = 0; i < kHullSections; ++i) {
    for (int side : {-1, 1})
      b.quad_m(at(i, side, false), at(i + 1, side, false), at(i + 1, side, true), at(i, side, true),
               Vec3(0, side, 0), 1.0, 1.0);
    b.quad_m(at(i, -1, false), at(i + 1, -1, false), at(i + 1, 1, false), at(i, 1, false),
             Vec3(0, 0, 1), 1.0, 1.0);
    b.quad_m(at(i, -1, true), at(i + 1, -1, true), at(i + 1, 1, true), at(i, 1, true),
             Vec3(0, 0, -1), 1.0, 1.0);
  }
  b.quad_m(at(0, -1, false), at(0, 1, false), at(0, 1, true), at(0, -1, true), Vec3(-1, 0, 0), 1.0,
           1.0);
  const int n = kHullSections;
  b.quad_m(at(n, -1, false), at(n, 1, false), at(n, 1, true), at(n, -1, true), Vec3(1, 0, 0), 1.0,
           1.0);
  return b.take();
}

// The wheelhouse: a painted box aft of mid-length with a window on each side and in front.
std::vector<sim::Mesh> wheelhouse_meshes(const std::string& name, const OtherVesselOptions& o,
                                         const HullShape& h, const VesselTextures& t) {
  const double x0 = -0.3 * o.length_m, x1 = 0.02 * o.length_m;
  const double w = 0.7 * vessel_half_beam(o, x1), height = std::min(1.9, 0.8 * o.beam_m);
  const double z0 = h.deck_z(x1), z1 = z0 - height;
  MeshBuilder house(name + ".wheelhouse", painted(t.wheelhouse, 0.85f));
  house.box(Vec3(x0, -w, z1), Vec3(x1, w, z0 + 0.05), 1.0);
  MeshBuilder windows(name + ".windows", painted(t.window, 0.9f));
  const double zt = z1 + 0.2 * height, zb = z1 + 0.6 * height, e = 0.01;
  const Eigen::Vector2d t0(0, 1), t1(1, 1), t2(1, 0), t3(0, 0);
  for (int side : {-1, 1}) {
    const double y = side * (w + e), xa = x0 + 0.15 * (x1 - x0), xb = x1 - 0.15 * (x1 - x0);
    windows.quad(Vec3(xa, y, zb), Vec3(xb, y, zb), Vec3(xb, y, zt), Vec3(xa, y, zt),
                 Vec3(0, side, 0), t0, t1, t2, t3);
  }
  windows.quad(Vec3(x1 + e, -0.8 * w, zb), Vec3(x1 + e, 0.8 * w, zb), Vec3(x1 + e, 0.8 * w, zt),
               Vec3(x1 + e, -0.8 * w, zt), Vec3(1, 0, 0), t0, t1, t2, t3);
  return {house.take(), windows.take()};
}

}  // namespace

double vessel_half_beam(const OtherVesselOptions& o, double x_m) {
  const double start = 0.25 * o.length_m / 2;  // a quarter of the half-length forward
  const double s = std::clamp((x_m - start) / (o.length_m / 2 - start), 0.0, 1.0);
  return o.beam_m / 2 * std::max(0.1, std::sqrt(1 - s));
}

sim::MoverMotion vessel_motion(const OtherVesselOptions& o, std::uint64_t seed, int index) {
  Rng rng = RngStreams(seed).stream("scene.vessels." + std::to_string(index));
  sim::MoverMotion m;
  m.p0_W = Eigen::Vector3d(o.north_m, o.east_m, 0);
  m.v_W = Eigen::Vector3d(o.speed_mps, 0, 0);
  m.heading_rad = o.speed_mps < 0 ? std::numbers::pi : 0;
  m.roll = {o.roll_deg * std::numbers::pi / 180, o.roll_period_s,
            rng.uniform(0, 2 * std::numbers::pi)};
  const double pitch_phase = rng.uniform(0, 2 * std::numbers::pi);
  m.pitch = {o.pitch_deg * std::numbers::pi / 180, o.pitch_period_s, pitch_phase};
  // Heave a quarter period behind the pitch: the bow is highest as the hull rises.
  m.heave = {o.heave_m, o.pitch_period_s, pitch_phase - std::numbers::pi / 2};
  return m;
}

void add_other_vessels(sim::SceneGeometry* scene, const std::vector<OtherVesselOptions>& vessels,
                       std::uint64_t seed, double texture_contrast) {
  if (vessels.empty()) return;
  const RngStreams streams(seed);
  const VesselTextures t{
      add_scene_texture(scene, streams, TextureKind::kMetalPanel, texture_contrast),
      add_scene_texture(scene, streams, TextureKind::kPaintedWall, texture_contrast),
      add_scene_texture(scene, streams, TextureKind::kWindow, texture_contrast)};
  for (std::size_t i = 0; i < vessels.size(); ++i) {
    const OtherVesselOptions& o = vessels[i];
    const int mover = static_cast<int>(scene->movers.size());
    scene->movers.push_back(vessel_motion(o, seed, static_cast<int>(i)));
    const HullShape h{o.length_m, std::min(0.6, 0.25 * o.beam_m), o.freeboard_m};
    const std::string name = "vessel" + std::to_string(i);
    std::vector<sim::Mesh> parts = wheelhouse_meshes(name, o, h, t);
    parts.insert(parts.begin(), hull_mesh(name, o, h, t.hull));
    for (sim::Mesh& m : parts) {
      m.mover = mover;
      add_mesh(scene, std::move(m));
    }
  }
}

}  // namespace driftlab::scenes
