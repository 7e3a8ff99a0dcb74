#include "scenes/wave_basin.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "scenes/mesh_builder.hpp"
#include "scenes/textures.hpp"

namespace driftlab::scenes {

namespace {

constexpr double kGeneratorDepth_m = 0.6;  // housing behind the paddle
constexpr double kCrestHeight_m = 0.25;    // beach crest and platform above the still water
constexpr double kDadoHeight_m = 0.5;      // the tank wall's darker band above the water

}  // namespace

BasinLayout basin_layout(const WaveBasinOptions& o) {
  BasinLayout b;
  b.generator_back_x_m = -kGeneratorDepth_m;
  const double t = std::tan(o.beach_slope_deg * std::numbers::pi / 180.0);
  b.beach_waterline_x_m = o.beach_distance_m;
  // A gentle beach in a short basin would run past the paddle: cut it at x = 0.
  b.beach_toe_x_m = std::max(0.0, o.beach_distance_m - o.water_depth_m / t);
  b.beach_toe_z_m = (o.beach_distance_m - b.beach_toe_x_m) * t;
  b.beach_crest_x_m = std::min(o.length_m, o.beach_distance_m + kCrestHeight_m / t);
  b.beach_crest_z_m = -(b.beach_crest_x_m - o.beach_distance_m) * t;
  // The reference camera hangs over the middle of the test section, just under the ceiling.
  b.camera_mount_W = Eigen::Vector3d(o.beach_distance_m / 2, 0, -o.wall_height_m + 0.32);
  return b;
}

sim::Lighting indoor_lighting() {
  sim::Lighting l;
  l.sun = false;
  l.sun_direction_W = Eigen::Vector3f(0.f, 0.f, -1.f);  // ceiling lights overhead
  l.ambient = 0.6f;
  l.diffuse = 0.4f;
  l.sky_brightness = 0.8f;    // nothing of the sky is visible; kept for the renderer's clear colour
  l.fog_distance_m = 5000.f;  // a lab hall has no haze
  l.sky_zenith_ratio = 1.f;   // uniform: the mirror pass needs no sky
  return l;
}

namespace {

struct BasinTextures {
  int wall, floor, beach, metal, window;
  int poster[kPosterVariants];
};

// The hall's textures, each from its own random stream.
BasinTextures add_textures(sim::SceneGeometry* g, const RngStreams& streams) {
  auto add_texture = [&](TextureKind kind, int variant = 0) {
    return add_scene_texture(g, streams, kind, 1.0, variant);
  };
  BasinTextures t{};
  t.wall = add_texture(TextureKind::kPaintedWall);
  t.floor = add_texture(TextureKind::kLabFloor);
  t.beach = add_texture(TextureKind::kStone);
  t.metal = add_texture(TextureKind::kMetalPanel);
  t.window = add_texture(TextureKind::kWindow);
  for (int v = 0; v < kPosterVariants; ++v) t.poster[v] = add_texture(TextureKind::kPoster, v);
  return t;
}

void add_shell(sim::SceneGeometry* g, const WaveBasinOptions& o, const BasinLayout& B,
               const BasinTextures& t) {
  const double hw = o.width_m / 2, len = o.length_m, D = o.water_depth_m, Hc = o.wall_height_m;
  const double x_back = B.generator_back_x_m;
  // Shell: floor, walls (a darker tank band above the water, paint above),
  // end walls, ceiling with light panels.
  MeshBuilder floor("basin_floor", material(t.floor, 0.7f));
  if (B.beach_toe_x_m > 0)
    floor.quad_m({0, -hw, D}, {B.beach_toe_x_m, -hw, D}, {B.beach_toe_x_m, hw, D}, {0, hw, D},
                 -Vec3::UnitZ(), 1.2, 1.2);
  floor.quad_m({B.beach_crest_x_m, -hw, B.beach_crest_z_m}, {len, -hw, B.beach_crest_z_m},
               {len, hw, B.beach_crest_z_m}, {B.beach_crest_x_m, hw, B.beach_crest_z_m},
               -Vec3::UnitZ(), 1.2, 1.2);
  add_mesh(g, floor.take());

  MeshBuilder beach("beach", material(t.beach, 0.6f));
  beach.quad_m({B.beach_toe_x_m, -hw, B.beach_toe_z_m}, {B.beach_toe_x_m, hw, B.beach_toe_z_m},
               {B.beach_crest_x_m, hw, B.beach_crest_z_m},
               {B.beach_crest_x_m, -hw, B.beach_crest_z_m}, Vec3(-1, 0, -1), 0.6, 0.6);
  add_mesh(g, beach.take());

  MeshBuilder walls("basin_walls", material(t.wall, 0.85f));
  MeshBuilder dado("basin_wall_band", material(t.wall, 0.45f));
  for (int side : {1, -1}) {
    const double y = side * hw;
    const Vec3 in(0, -side, 0);
    walls.quad_m({x_back, y, -Hc}, {len, y, -Hc}, {len, y, -kDadoHeight_m},
                 {x_back, y, -kDadoHeight_m}, in, 2.0, 2.0);
    dado.quad_m({x_back, y, -kDadoHeight_m}, {len, y, -kDadoHeight_m}, {len, y, D}, {x_back, y, D},
                in, 2.0, 2.0);
  }
  for (const auto& [x, dir] : {std::pair{len, -1.0}, std::pair{x_back, 1.0}}) {
    walls.quad_m({x, -hw, -Hc}, {x, hw, -Hc}, {x, hw, -kDadoHeight_m}, {x, -hw, -kDadoHeight_m},
                 Vec3(dir, 0, 0), 2.0, 2.0);
    dado.quad_m({x, -hw, -kDadoHeight_m}, {x, hw, -kDadoHeight_m}, {x, hw, D}, {x, -hw, D},
                Vec3(dir, 0, 0), 2.0, 2.0);
  }
  add_mesh(g, walls.take());
  add_mesh(g, dado.take());

  MeshBuilder ceiling("basin_ceiling", material(t.floor, 0.9f));
  ceiling.quad_m({x_back, -hw, -Hc}, {len, -hw, -Hc}, {len, hw, -Hc}, {x_back, hw, -Hc},
                 Vec3::UnitZ(), 1.2, 1.2);
  add_mesh(g, ceiling.take());
  MeshBuilder lights("basin_lights", material(-1, 1.0f));
  for (double x = 1.0; x + 0.6 <= len; x += 3.0)
    lights.box({x - 0.6, -std::min(0.3, 0.6 * hw), -Hc},
               {x + 0.6, std::min(0.3, 0.6 * hw), -Hc + 0.04}, 1.0,
               MeshBuilder::kAllFaces & ~MeshBuilder::kTop);
  add_mesh(g, lights.take());
}

// Returns the top of the generator's drive (z, down).
double add_generator(sim::SceneGeometry* g, const WaveBasinOptions& o, const BasinLayout& B,
                     const BasinTextures& t) {
  const double hw = o.width_m / 2, D = o.water_depth_m, Hc = o.wall_height_m;
  const double x_back = B.generator_back_x_m;
  // Wave generator: the paddle face at x = 0 across the basin, its housing and drive behind.
  MeshBuilder generator("wave_generator", material(t.metal, 0.7f, 0.2f));
  generator.box({x_back, -hw + 0.02, -0.5}, {0.0, hw - 0.02, D}, 1.0,
                MeshBuilder::kAllFaces & ~MeshBuilder::kBottom);
  const double drive_top = std::max(-0.9, -Hc + 0.05);  // under a low ceiling, a flatter drive
  if (drive_top < -0.55)
    generator.box({x_back, -hw * 0.8, drive_top}, {-0.1, hw * 0.8, -0.5}, 1.0,
                  MeshBuilder::kAllFaces & ~MeshBuilder::kBottom);
  add_mesh(g, generator.take());
  return drive_top;
}

struct WindowBand {
  double top, height;  // z of the panes' top (down), their height
};

WindowBand add_windows(sim::SceneGeometry* g, const WaveBasinOptions& o, const BasinTextures& t) {
  const double hw = o.width_m / 2, len = o.length_m, Hc = o.wall_height_m;
  // Windows high on the west wall, daylight in their panes.
  MeshBuilder windows("basin_windows", material(t.window, 0.95f));
  const double win_h = std::min(1.0, 0.35 * Hc), win_top = -Hc + 0.25;
  for (double x = 1.0; x + 1.2 <= len - 0.3; x += 2.5)
    windows.quad({x, -hw + 0.005, win_top}, {x + 1.2, -hw + 0.005, win_top},
                 {x + 1.2, -hw + 0.005, win_top + win_h}, {x, -hw + 0.005, win_top + win_h},
                 Vec3::UnitY(), {0, 0}, {1, 0}, {1, 1}, {0, 1});
  add_mesh(g, windows.take());
  return {win_top, win_h};
}

void add_posters(sim::SceneGeometry* g, const WaveBasinOptions& o, const BasinLayout& B,
                 const BasinTextures& t, Rng& rng, double drive_top, const WindowBand& windows) {
  const double hw = o.width_m / 2, len = o.length_m, Hc = o.wall_height_m;
  const double x_back = B.generator_back_x_m;
  const double win_top = windows.top, win_h = windows.height;
  // Posters: portrait A1 on the east wall, landscape under the west windows,
  // three on the end wall and two above the generator; variants cycle from a
  // random start, positions jitter.
  std::vector<MeshBuilder> posters;
  for (int v = 0; v < kPosterVariants; ++v)
    posters.emplace_back("basin_posters" + std::to_string(v), material(t.poster[v], 0.95f));
  int variant = static_cast<int>(rng.uniform_int(kPosterVariants));
  auto poster = [&](const Vec3& top_left, const Vec3& right, const Vec3& down, const Vec3& front) {
    posters[static_cast<std::size_t>(variant)].quad(top_left, top_left + right,
                                                    top_left + right + down, top_left + down, front,
                                                    {0, 0}, {1, 0}, {1, 1}, {0, 1});
    variant = (variant + 1) % kPosterVariants;
  };
  const double p_bottom = -0.4;  // posters' lower edge 40 cm above the water
  const double p_h = std::clamp(Hc - 0.6, 0.1, 0.85);
  // Landscape posters stay 10 cm below the windows' lower edge (z grows downwards).
  const double l_h = std::clamp(p_bottom - (win_top + win_h) - 0.1, 0.1, 0.5);
  for (double x = 0.6; x + 0.6 <= len - 0.2; x += 1.8) {
    const double xj = x + rng.uniform(-0.3, 0.3);
    poster({xj, hw - 0.005, p_bottom - p_h}, {0.6, 0, 0}, {0, 0, p_h}, -Vec3::UnitY());
  }
  for (double x = 1.2; x + 0.8 <= len - 0.2; x += 2.5) {
    const double xj = x + rng.uniform(-0.2, 0.2);
    poster({xj, -hw + 0.005, p_bottom - l_h}, {0.8, 0, 0}, {0, 0, l_h}, Vec3::UnitY());
  }
  // Poster widths shrink with a narrow basin so that they stay on their wall.
  const double end_w = std::min(0.6, 0.8 * o.width_m / 3);
  for (int i = 0; i < 3; ++i) {
    const double y = -hw + o.width_m * (i + 0.5) / 3 + end_w / 2;
    poster({len - 0.005, y, p_bottom - p_h}, {0, -end_w, 0}, {0, 0, p_h}, -Vec3::UnitX());
  }
  const double gen_w = std::min(0.6, 0.4 * hw);
  for (double y : {-0.45 * hw, 0.45 * hw}) {
    // Above the generator's drive (top at z = drive_top), below the ceiling.
    const double top = std::max(-Hc + 0.1, drive_top - 0.05 - p_h);
    const double h = std::min(p_h, drive_top - 0.05 - top);
    if (h > 0.1)
      poster({x_back + 0.005, y - gen_w / 2, top}, {0, gen_w, 0}, {0, 0, h}, Vec3::UnitX());
  }
  for (auto& p : posters) add_mesh(g, p.take());
}

void add_pipes_rails_and_mount(sim::SceneGeometry* g, const WaveBasinOptions& o,
                               const BasinLayout& B, const BasinTextures& t) {
  const double hw = o.width_m / 2, len = o.length_m, Hc = o.wall_height_m;
  const double x_back = B.generator_back_x_m;
  // Pipes under the ceiling along both walls, drop pipes on the east wall;
  // carriage rails on brackets 35 cm above the water along both walls.
  MeshBuilder pipes("basin_pipes", material(-1, 0.55f, 0.4f));
  MeshBuilder rails("basin_rails", material(-1, 0.25f, 0.3f));
  for (int side : {1, -1}) {
    for (double dz : {0.15, 0.3})
      pipes.prism({x_back, side * (hw - 0.1), -Hc + dz}, {len, side * (hw - 0.1), -Hc + dz}, 0.04,
                  8, 0.5);
    rails.box({x_back + 0.05, side > 0 ? hw - 0.15 : -hw + 0.09, -0.43},
              {len - 0.05, side > 0 ? hw - 0.09 : -hw + 0.15, -0.35}, 1.0);
    for (double x = 0.5; x < len; x += 1.5)
      rails.box({x - 0.03, side > 0 ? hw - 0.09 : -hw, -0.42},
                {x + 0.03, side > 0 ? hw : -hw + 0.09, -0.36}, 1.0,
                MeshBuilder::kAllFaces & ~(side > 0 ? MeshBuilder::kEast : MeshBuilder::kWest));
  }
  for (double x = 2.5; x < len; x += 5.0)
    pipes.prism({x, hw - 0.06, -Hc + 0.3}, {x, hw - 0.06, -0.3}, 0.03, 8, 0.5);
  add_mesh(g, pipes.take());
  add_mesh(g, rails.take());

  // Overhead camera mount: a beam across the basin and the camera under it.
  MeshBuilder mount("camera_mount", material(t.metal, 0.5f, 0.2f));
  const double mx = B.camera_mount_W.x();
  mount.box({mx - 0.05, -hw, -Hc + 0.05}, {mx + 0.05, hw, -Hc + 0.2}, 1.0);
  mount.box({mx - 0.06, -0.1, -Hc + 0.2}, {mx + 0.06, 0.1, B.camera_mount_W.z()}, 1.0);
  add_mesh(g, mount.take());
}

}  // namespace

sim::SceneGeometry build_wave_basin(const WaveBasinOptions& o, Sky /*sky*/, std::uint64_t seed) {
  yaml::validate_or_throw(o, "scene.wave_basin");
  const BasinLayout B = basin_layout(o);
  const double hw = o.width_m / 2;

  sim::SceneGeometry g;
  g.lighting = indoor_lighting();
  g.water = sim::WaterAppearance{};
  // Tap water: clear and dark; the grid only needs to cover the water between
  // the paddle and the beach around the camera, so the renderer can make it
  // fine enough for the 59 mm waves of the paper's Table 1.
  g.water.extent_m = static_cast<float>(std::max({o.beach_distance_m + 1.0, hw + 0.5, 2.0}));
  g.water.turbidity = 0.15f;
  g.water.body_gray = 0.25f;

  const RngStreams streams(seed);
  const BasinTextures t = add_textures(&g, streams);
  Rng rng = streams.stream("scene.basin.fixtures");
  add_shell(&g, o, B, t);
  const double drive_top = add_generator(&g, o, B, t);
  const WindowBand windows = add_windows(&g, o, t);
  if (o.posters) add_posters(&g, o, B, t, rng, drive_top, windows);
  add_pipes_rails_and_mount(&g, o, B, t);
  return g;
}

}  // namespace driftlab::scenes
