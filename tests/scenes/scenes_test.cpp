// Tests of the procedural scenes: textures, other vessels on the river, the wave basin, mesh
// assets and the scene dispatcher (the river reach itself: river_reach_test.cpp). Expectations
// come from the options and the papers, not from the code.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <unistd.h>
#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "scenes/assets.hpp"
#include "scenes/build_scene.hpp"
#include "scenes/river_reach.hpp"
#include "scenes/scene_options.hpp"
#include "scenes/textures.hpp"
#include "scenes/vessels.hpp"
#include "scenes/wave_basin.hpp"
#include "tests/scenes/scenes_fixtures.hpp"

namespace driftlab::scenes {
namespace {

using fixtures::default_reach;
using fixtures::expect_well_formed;
using fixtures::find_mesh;
using fixtures::kSeed;
using fixtures::name_has;
using fixtures::pos;
using fixtures::RayCaster;
using fixtures::river_defaults;

// ---------------------------------------------------------------------------
// Helpers

constexpr TextureKind kAllKinds[] = {
    TextureKind::kGrass,       TextureKind::kSoil,     TextureKind::kBark,
    TextureKind::kFoliage,     TextureKind::kReeds,    TextureKind::kStone,
    TextureKind::kBrick,       TextureKind::kConcrete, TextureKind::kSheetPiling,
    TextureKind::kPaintedWall, TextureKind::kPoster,   TextureKind::kWindow,
    TextureKind::kLabFloor,    TextureKind::kRoof,     TextureKind::kFacade,
    TextureKind::kMetalPanel};

sim::Texture texture(TextureKind kind, std::uint64_t seed, double contrast = 1.0, int variant = 0) {
  Rng rng = RngStreams(seed).stream("test.texture");
  return make_texture(kind, rng, contrast, variant);
}

double pixel_sd(const sim::Texture& t) {
  double mean = 0, var = 0;
  for (auto p : t.pixels) mean += p;
  mean /= static_cast<double>(t.pixels.size());
  for (auto p : t.pixels) var += (p - mean) * (p - mean);
  return std::sqrt(var / static_cast<double>(t.pixels.size()));
}

int px(const sim::Texture& t, int x, int y) {
  return t.pixels[static_cast<std::size_t>(y) * t.width + x];
}

// A scratch file removed when the test ends.
class TempFile {
 public:
  TempFile(const std::string& name, const std::string& content)
      : path_(std::filesystem::temp_directory_path() /
              ("driftlab_scenes_test_" + std::to_string(::getpid()) + "_" + name)) {
    std::ofstream(path_, std::ios::binary) << content;
  }
  ~TempFile() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  std::string path() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

// ---------------------------------------------------------------------------
// Textures

TEST(Textures, SameSeedGivesSameBytes) {
  for (TextureKind k : kAllKinds)
    for (int v = 0; v < (k == TextureKind::kPoster ? kPosterVariants : 1); ++v) {
      const sim::Texture a = texture(k, 7, 1.0, v), b = texture(k, 7, 1.0, v);
      EXPECT_EQ(a.pixels, b.pixels) << a.name;
      EXPECT_EQ(a.name, b.name);
    }
}

TEST(Textures, OtherSeedGivesOtherBytes) {
  for (TextureKind k : kAllKinds) {
    const sim::Texture a = texture(k, 7), b = texture(k, 8);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) differ += a.pixels[i] != b.pixels[i];
    // Most pixels differ (posters keep their white margin and layout grid).
    EXPECT_GT(differ, a.pixels.size() / 10) << a.name;
  }
}

TEST(Textures, SizesNamesAndUseOfTheGreyRange) {
  for (TextureKind k : kAllKinds) {
    const sim::Texture t = texture(k, 3);
    EXPECT_EQ(t.width, t.height);
    EXPECT_GE(t.width, 256);
    EXPECT_LE(t.width, 512);
    EXPECT_EQ(t.width, default_texture_size(k));
    EXPECT_EQ(t.name.rfind(std::string(texture_kind_name(k)), 0), 0u);
    // Every texture has some structure; the feature-poor ones (paint, sheet
    // piling) have little, posters and foliage a lot.
    EXPECT_GT(pixel_sd(t), 2.0) << t.name;
  }
  EXPECT_LT(pixel_sd(texture(TextureKind::kPaintedWall, 3)), 8.0);
  EXPECT_LT(pixel_sd(texture(TextureKind::kSheetPiling, 3)), 15.0);
  for (int v = 0; v < kPosterVariants; ++v)
    EXPECT_GT(pixel_sd(texture(TextureKind::kPoster, 3, 1.0, v)), 60.0) << v;
  EXPECT_GT(pixel_sd(texture(TextureKind::kFoliage, 3)), 25.0);
  EXPECT_EQ(texture(TextureKind::kGrass, 3, 1.0, 0).pixels.size(), 512u * 512u);
  Rng rng(1);
  EXPECT_EQ(make_texture(TextureKind::kBark, rng, 1.0, 0, 64).width, 64);
}

TEST(Textures, ContrastScalesThePixelStandardDeviation) {
  // Natural textures stay inside [0, 255] up to contrast 1.5, so the standard
  // deviation scales by the factor (up to rounding to whole grey levels).
  for (TextureKind k : {TextureKind::kGrass, TextureKind::kSoil, TextureKind::kBark,
                        TextureKind::kConcrete, TextureKind::kStone, TextureKind::kSheetPiling}) {
    const double sd1 = pixel_sd(texture(k, 11, 1.0));
    for (double c : {0.5, 1.5}) {
      const double sd = pixel_sd(texture(k, 11, c));
      EXPECT_NEAR(sd / sd1, c, 0.03 * c) << texture_kind_name(k) << " contrast " << c;
    }
    EXPECT_LT(pixel_sd(texture(k, 11, 0.0)), 0.6) << "contrast 0 is flat grey";
  }
}

TEST(Textures, WrapAroundIsSeamless) {
  // Across the wrap seam (last column next to the first, last row next to the
  // first) neighbours differ no more than interior neighbours do: no more
  // than the most different interior pair (patterned textures put a brick
  // joint or a roof-tile row edge on the seam, as on every other repeat), and
  // for the noise-only textures also close to the interior mean.
  for (TextureKind k : kAllKinds) {
    const sim::Texture t = texture(k, 5);
    const int n = t.width;
    for (const bool across_x : {true, false}) {
      auto at = [&](int i, int j) { return across_x ? px(t, i, j) : px(t, j, i); };
      auto pair_diff = [&](int i0, int i1) {  // mean |difference| of two columns (rows)
        double d = 0;
        for (int j = 0; j < n; ++j) d += std::abs(at(i1, j) - at(i0, j));
        return d / n;
      };
      double mean = 0, max = 0;
      for (int i = 0; i + 1 < n; ++i) {
        const double d = pair_diff(i, i + 1);
        mean += d / (n - 1);
        max = std::max(max, d);
      }
      const double seam = pair_diff(n - 1, 0);
      const char* dir = across_x ? " left/right" : " top/bottom";
      EXPECT_LE(seam, max + 1.0) << t.name << dir;
      if (k == TextureKind::kGrass || k == TextureKind::kSoil || k == TextureKind::kBark ||
          k == TextureKind::kFoliage || k == TextureKind::kReeds || k == TextureKind::kStone ||
          k == TextureKind::kPaintedWall) {
        EXPECT_LE(seam, 1.5 * mean + 1.0) << t.name << dir;
      }
    }
  }
}

// ---------------------------------------------------------------------------
// Other vessels

// Other vessels (scene.river_reach.vessels): each is a mover whose pose is its
// closed-form motion, whose hull stays within its length, beam and draft, and whose options are
// checked against the river; a reach without vessels is the scene it was.
TEST(OtherVessels, MoveAsTheirOptionsSay) {
  OtherVesselOptions launch;
  launch.north_m = 70;
  launch.east_m = 4;
  launch.speed_mps = -1.5;
  const sim::MoverMotion m = vessel_motion(launch, kSeed, 0);
  EXPECT_NEAR(m.heading_rad, std::numbers::pi, 1e-12);  // heading south, down the river
  for (double t : {0.0, 10.0, 47.3}) {
    const SE3 T = m.T_W_M(t);
    EXPECT_NEAR(T.translation().x(), 70 - 1.5 * t, 1e-9);
    EXPECT_NEAR(T.translation().y(), 4, 1e-9);
    EXPECT_LE(std::abs(T.translation().z()), launch.heave_m + 1e-12);
  }
  // Its roll reaches the amplitude asked for over a period, and no more.
  double most = 0;
  for (int i = 0; i < 1000; ++i) {
    const double t = launch.roll_period_s * i / 1000;
    most = std::max(most, std::abs(m.roll.at(t)));
  }
  EXPECT_NEAR(most, launch.roll_deg * std::numbers::pi / 180, 1e-4);
  OtherVesselOptions moored;
  moored.speed_mps = 0;
  const sim::MoverMotion still = vessel_motion(moored, kSeed, 1);
  EXPECT_EQ(still.heading_rad, 0.0);
  EXPECT_NEAR((still.T_W_M(100).translation() - still.T_W_M(0).translation()).head<2>().norm(), 0.0,
              1e-12);
  // The phases are the seed's: the same again, another for another vessel or seed.
  EXPECT_EQ(vessel_motion(launch, kSeed, 0).roll.phase_rad, m.roll.phase_rad);
  EXPECT_NE(vessel_motion(launch, kSeed, 1).roll.phase_rad, m.roll.phase_rad);
  EXPECT_NE(vessel_motion(launch, kSeed + 1, 0).roll.phase_rad, m.roll.phase_rad);
}

TEST(OtherVessels, HullsStayInTheirDimensionsAndTheRestOfTheSceneIsUnchanged) {
  RiverReachOptions o = river_defaults();
  OtherVesselOptions a, b;
  a.east_m = -5;
  b.east_m = 8.6;
  b.length_m = 6;
  b.beam_m = 2.2;
  o.vessels = {a, b};
  const sim::SceneGeometry with = build_river_reach(o, Sky::kOvercast, kSeed, 0, 120);
  const sim::SceneGeometry& without = default_reach();
  expect_well_formed(with);
  ASSERT_EQ(with.movers.size(), 2u);
  EXPECT_TRUE(without.movers.empty());
  ASSERT_GT(with.meshes.size(), without.meshes.size());
  for (std::size_t i = 0; i < without.meshes.size(); ++i) {
    EXPECT_EQ(with.meshes[i].name, without.meshes[i].name);
    EXPECT_EQ(with.meshes[i].mover, -1);
    EXPECT_EQ(with.meshes[i].vertices.size(), without.meshes[i].vertices.size());
  }
  for (std::size_t i = 0; i < without.textures.size(); ++i)
    EXPECT_TRUE(with.textures[i].pixels == without.textures[i].pixels) << i;
  for (std::size_t i = without.meshes.size(); i < with.meshes.size(); ++i) {
    const sim::Mesh& m = with.meshes[i];
    ASSERT_GE(m.mover, 0) << m.name;
    const OtherVesselOptions& v = m.mover == 0 ? a : b;
    for (const sim::Vertex& p : m.vertices) {
      EXPECT_LE(std::abs(p.x), v.length_m / 2 + 1e-4) << m.name;
      EXPECT_LE(std::abs(p.y), vessel_half_beam(v, p.x) + 0.02) << m.name;
      EXPECT_LE(p.z, 0.6 + 1e-4) << m.name;                     // the draft
      EXPECT_GE(p.z, -(v.freeboard_m * 1.35 + 2.0)) << m.name;  // the wheelhouse's roof
    }
  }
  EXPECT_EQ(vessel_half_beam(a, 0), a.beam_m / 2);
  EXPECT_NEAR(vessel_half_beam(a, a.length_m / 2), 0.1 * a.beam_m / 2, 1e-12);
}

TEST(OtherVessels, AVesselOffTheWaterIsRefusedNamingIt) {
  RiverReachOptions o = river_defaults();
  OtherVesselOptions v;
  v.east_m = 9.5;  // 9.5 + 1.2 > the bank at 10 m
  o.vessels = {OtherVesselOptions{}, v};
  try {
    build_river_reach(o, Sky::kOvercast, kSeed, 0, 10);
    ADD_FAILURE() << "a vessel on the bank was accepted";
  } catch (const UserError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("vessels"), std::string::npos) << what;
    EXPECT_NE(what.find("vessel 1"), std::string::npos) << what;
    EXPECT_NE(what.find("10.7"), std::string::npos) << what;
  }
}

// ---------------------------------------------------------------------------
// Wave basin

TEST(WaveBasin, ExtremeOptionsStayInsideTheBasin) {
  std::vector<WaveBasinOptions> cases(4);
  cases[0].width_m = 0.5;
  cases[1].wall_height_m = 0.5;
  cases[2].length_m = 3.1;       // the beach's crest reaches the end wall
  cases[3].beach_slope_deg = 5;  // a long beach cut at the paddle
  cases[3].water_depth_m = 2.0;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE("case " + std::to_string(i));
    const WaveBasinOptions& o = cases[i];
    const auto g = build_wave_basin(o, Sky::kOvercast, kSeed);
    expect_well_formed(g);
    for (const auto& m : g.meshes)
      for (const auto& v : m.vertices) {
        ASSERT_LE(std::abs(v.y), o.width_m / 2 + 1e-5) << m.name;
        ASSERT_GE(v.z, -o.wall_height_m - 1e-5) << m.name;
        ASSERT_LE(v.z, o.water_depth_m + 1e-5) << m.name;
        ASSERT_LE(v.x, o.length_m + 1e-5) << m.name;
      }
  }
  WaveBasinOptions bad;
  bad.beach_distance_m = 40;  // beyond the end wall
  EXPECT_THROW(build_wave_basin(bad, Sky::kOvercast, kSeed), UserError);
}

TEST(WaveBasin, WellFormedIndoorAndDeterministic) {
  const WaveBasinOptions o;
  const auto g = build_wave_basin(o, Sky::kSun, kSeed);
  expect_well_formed(g);
  EXPECT_FALSE(g.lighting.sun);  // indoors, whatever the sky
  const auto again = build_wave_basin(o, Sky::kOvercast, kSeed);
  ASSERT_EQ(g.meshes.size(), again.meshes.size());
  for (std::size_t i = 0; i < g.meshes.size(); ++i)
    EXPECT_EQ(0, std::memcmp(g.meshes[i].vertices.data(), again.meshes[i].vertices.data(),
                             g.meshes[i].vertices.size() * sizeof(sim::Vertex)));
  std::printf("[ wave basin ] %zu triangles in %zu meshes; water grid half-size %.1f m\n",
              g.triangle_count(), g.meshes.size(), g.water.extent_m);
  // The water grid covers the test section between the paddle and the beach.
  EXPECT_GE(g.water.extent_m, o.beach_distance_m);
}

// Plain walls: no poster mesh, every other mesh the same vertices as with the posters.
TEST(WaveBasin, PlainWallsDropThePostersAndKeepEverythingElse) {
  WaveBasinOptions plain;
  plain.posters = false;
  const auto with = build_wave_basin(WaveBasinOptions{}, Sky::kOvercast, kSeed);
  const auto without = build_wave_basin(plain, Sky::kOvercast, kSeed);
  expect_well_formed(without);
  auto is_poster = [](const sim::Mesh& m) { return m.name.rfind("basin_posters", 0) == 0; };
  std::size_t posters = 0;
  for (const auto& m : with.meshes) posters += is_poster(m) && !m.vertices.empty();
  EXPECT_GE(posters, 1u);
  for (const auto& m : without.meshes) EXPECT_FALSE(is_poster(m)) << m.name;
  std::size_t kept = 0;
  for (const auto& m : with.meshes) {
    if (is_poster(m)) continue;
    const auto* same = find_mesh(without, m.name);
    ASSERT_TRUE(same) << m.name;
    ASSERT_EQ(same->vertices.size(), m.vertices.size()) << m.name;
    EXPECT_EQ(0, std::memcmp(same->vertices.data(), m.vertices.data(),
                             m.vertices.size() * sizeof(sim::Vertex)))
        << m.name;
    ++kept;
  }
  EXPECT_EQ(kept, without.meshes.size());
}

TEST(WaveBasin, WallsAtHalfWidthAndGeneratorAtZero) {
  WaveBasinOptions o;
  o.width_m = 5.0;
  const auto g = build_wave_basin(o, Sky::kOvercast, kSeed);
  const auto* walls = find_mesh(g, "basin_walls");
  ASSERT_TRUE(walls);
  int side_vertices = 0;
  for (const auto& v : walls->vertices) {
    EXPECT_LE(std::abs(v.y), o.width_m / 2 + 1e-5);
    side_vertices += std::abs(std::abs(v.y) - o.width_m / 2) < 1e-5 && std::abs(v.nx) < 1e-6;
    EXPECT_GE(v.z, -o.wall_height_m - 1e-5);
  }
  EXPECT_GE(side_vertices, 8);
  // Nothing lies outside the walls, the ceiling or the floor.
  for (const auto& m : g.meshes)
    for (const auto& v : m.vertices) {
      EXPECT_LE(std::abs(v.y), o.width_m / 2 + 1e-5) << m.name;
      EXPECT_GE(v.z, -o.wall_height_m - 1e-5) << m.name;
      EXPECT_LE(v.z, o.water_depth_m + 1e-5) << m.name;
      EXPECT_LE(v.x, o.length_m + 1e-5) << m.name;
    }
  RayCaster rc(g);
  std::string what;
  // From mid-basin, 15 cm above the water: the walls at +-width/2.
  for (double dir : {1.0, -1.0}) {
    const double t = rc.cast({1.5, 0, -1.0}, {0, dir, 0}, &what);
    EXPECT_NEAR(t, o.width_m / 2, 0.15) << what;  // pipes, rails and posters sit on the walls
  }
  // Looking south from the test section at water level: the generator's paddle at x = 0.
  EXPECT_NEAR(rc.cast({1.5, 0.1, -0.15}, {-1, 0, 0}, &what), 1.5, 1e-6);
  EXPECT_EQ(what, "wave_generator");
}

TEST(WaveBasin, BeachMeetsTheWaterAtBeachDistance) {
  for (double bd : {3.0, 5.0, 1.0}) {
    WaveBasinOptions o;
    o.beach_distance_m = bd;
    const auto g = build_wave_basin(o, Sky::kOvercast, kSeed);
    RayCaster rc(g);
    std::string what;
    // Along the still-water line from the paddle northwards: the beach at bd.
    const double t = rc.cast({0.01, 0.3, -1e-4}, {1, 0, 0}, &what);
    EXPECT_EQ(what, "beach") << bd;
    EXPECT_NEAR(0.01 + t, bd, 1e-3) << bd;
    // Under water the slope is nearer, above it farther (it rises northwards).
    EXPECT_LT(rc.cast({0.01, 0.3, 0.1}, {1, 0, 0}), t);
    const BasinLayout L = basin_layout(o);
    EXPECT_NEAR(L.beach_waterline_x_m, bd, 1e-12);
    EXPECT_LT(L.beach_crest_z_m, 0.0);  // the crest is dry
  }
}

TEST(WaveBasin, PostersAndPaintAreTheTexture) {
  const auto g = build_wave_basin(WaveBasinOptions{}, Sky::kOvercast, kSeed);
  int posters = 0;
  for (const auto& m : g.meshes) {
    if (!name_has(m, "poster")) continue;
    posters += static_cast<int>(m.indices.size() / 6);
    EXPECT_GT(pixel_sd(g.textures[static_cast<std::size_t>(m.material.texture)]), 60.0) << m.name;
  }
  EXPECT_GE(posters, 20);
  const auto* walls = find_mesh(g, "basin_walls");
  ASSERT_TRUE(walls);
  EXPECT_LT(pixel_sd(g.textures[static_cast<std::size_t>(walls->material.texture)]), 8.0);
  EXPECT_TRUE(find_mesh(g, "basin_windows"));
  EXPECT_TRUE(find_mesh(g, "basin_pipes"));
  EXPECT_TRUE(find_mesh(g, "basin_rails"));
  const auto* mount = find_mesh(g, "camera_mount");
  ASSERT_TRUE(mount);
  // The overhead mount spans the basin above the test section.
  float ymin = 1e9f, ymax = -1e9f;
  for (const auto& v : mount->vertices) {
    ymin = std::min(ymin, v.y);
    ymax = std::max(ymax, v.y);
    EXPECT_LT(v.z, -1.0f);
  }
  EXPECT_NEAR(ymax - ymin, WaveBasinOptions{}.width_m, 1e-5);
}

// ---------------------------------------------------------------------------
// Assets

TEST(Assets, ShippedBollardLoads) {
  const sim::Mesh m = load_mesh_asset(shipped_asset("bollard.obj"));
  EXPECT_EQ(m.indices.size() / 3, 66u);  // 2 + 4 x 2 plate, 3 x 8 x 2 body and head, 8 cap
  sim::SceneGeometry g;
  g.meshes.push_back(m);
  expect_well_formed(g);
  Eigen::AlignedBox3d box;
  for (const auto& v : m.vertices) box.extend(pos(v));
  EXPECT_NEAR(box.min().z(), -0.6, 1e-6);  // stands 0.6 m tall, z down
  EXPECT_NEAR(box.max().z(), 0.0, 1e-6);
  EXPECT_NEAR(box.max().x(), 0.25, 1e-6);
  // Normals point away from the bollard's axis on its sides.
  for (const auto& v : m.vertices)
    if (std::abs(v.nz) < 0.1) {
      EXPECT_GT(v.nx * v.x + v.ny * v.y, 0.f);
    }
  EXPECT_LT(std::filesystem::file_size(shipped_asset("bollard.obj")), 5000u);
}

TEST(Assets, PlyAndGltfLoad) {
  const TempFile ply("tri.ply",
                     "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                     "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                     "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(load_mesh_asset(ply.path()).indices.size(), 3u);
  // One triangle in an embedded buffer, under a node moved 2 m up (z = -2).
  const TempFile gltf(
      "tri.gltf",
      R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0,)"
      R"("translation":[0,0,-2]}],"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],)"
      R"("buffers":[{"byteLength":42,"uri":"data:application/octet-stream;base64,)"
      R"(AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIA"}],"bufferViews":[{"buffer":0,)"
      R"("byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],"accessors":)"
      R"([{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},)"
      R"({"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}]})");
  const sim::Mesh m = load_mesh_asset(gltf.path());
  ASSERT_EQ(m.indices.size(), 3u);
  for (const auto& v : m.vertices) EXPECT_FLOAT_EQ(v.z, -2.f);
}

void expect_user_error_naming(const std::string& path, const std::string& also = "") {
  try {
    load_mesh_asset(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const UserError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    if (!also.empty()) {
      EXPECT_NE(what.find(also), std::string::npos) << what;
    }
  }
}

TEST(Assets, MissingFileIsAUserErrorNamingIt) {
  expect_user_error_naming("/nonexistent/driftlab/buoy.obj", "no such file");
}

TEST(Assets, CorruptFilesAreUserErrorsNamingThem) {
  const TempFile bad_index("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n");
  expect_user_error_naming(bad_index.path(), "index out of range");  // assimp's message
  const TempFile truncated(
      "truncated.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n");
  expect_user_error_naming(truncated.path());
  const TempFile garbage("garbage.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [ {");
  expect_user_error_naming(garbage.path());
  const TempFile text("text.obj", "this is not a mesh\n");
  expect_user_error_naming(text.path());
}

// ---------------------------------------------------------------------------
// Dispatcher

TEST(BuildScene, DispatchesOnTypeAndAppendsExtraAssets) {
  SceneOptions s;
  s.type = SceneType::kWaveBasin;
  s.extra_assets = {shipped_asset("bollard.obj")};
  const auto basin = build_scene(s, kSeed, 0, 0);
  EXPECT_TRUE(find_mesh(basin, "beach"));
  ASSERT_FALSE(basin.meshes.empty());
  EXPECT_EQ(basin.meshes.back().name, shipped_asset("bollard.obj"));
  EXPECT_EQ(basin.meshes.back().material.texture, -1);
  // Placed as given: the file's coordinates are world coordinates.
  float zmin = 0;
  for (const auto& v : basin.meshes.back().vertices) zmin = std::min(zmin, v.z);
  EXPECT_NEAR(zmin, -0.6f, 1e-6f);

  s.type = SceneType::kRiverReach;
  s.sky = Sky::kSun;
  s.extra_assets.clear();
  const auto river = build_scene(s, kSeed, 0, 50);
  EXPECT_TRUE(find_mesh(river, "tile0.plain_east"));
  EXPECT_TRUE(river.lighting.sun);

  s.extra_assets = {"/nonexistent/extra.ply"};
  EXPECT_THROW(build_scene(s, kSeed, 0, 50), UserError);
}

}  // namespace
}  // namespace driftlab::scenes