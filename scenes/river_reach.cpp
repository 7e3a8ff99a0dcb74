#include "scenes/river_reach.hpp"

#include "scenes/river_reach_parts.hpp"

namespace driftlab::scenes {
namespace river {

Bank bank_of(const RiverReachOptions& o) {
  Bank k;
  k.b = o.bank_distance_m;
  k.H = o.bank_height_m;
  // A 90 deg bank is drawn at a slope of 50:1, steep enough to read as a wall
  // and still a function of y.
  k.tan_slope = std::min(std::tan(o.bank_slope_deg * kPi / 180.0), 50.0);
  k.run = k.H / k.tan_slope;
  k.toe_s = -std::min(kToeDepth_m / k.tan_slope, 3.0);
  return k;
}

Noise terrain_noise(std::uint64_t seed) {
  Rng rng = RngStreams(seed).stream("scene.river.terrain");
  return Noise::from(rng);
}

// Terrain height at distance s beyond the water's edge on one side (+1 east,
// -1 west). The plain's undulation fades in from the bank top, so the bank's
// edge and slope are exactly as configured.
double terrain_z(const Bank& k, const Noise& n, double x, double s, int side) {
  if (s < 0) return std::min(-s * k.tan_slope, kToeDepth_m);
  if (s < k.run) return -s * k.tan_slope;
  const double d = s - k.run;
  const double amp = 0.4 * std::min(1.0, d / 6.0) + 0.02 * d;
  return -k.H - kPlainGrade * d - amp * n.fbm_world(x, d, 25.0, 3, 0.5, side > 0 ? 1 : 2);
}

// Height of the far-field skyline at distance s beyond the water's edge: the
// wood's edge and canopy (12-22 m above the bank top), then hills rising to a
// ridge 25-49 m up at kFarFieldEnd_m. `side` picks independent noise.
double far_top_z(const Bank& k, const Noise& n, double x, double s, int side) {
  const std::uint64_t salt = side > 0 ? 10 : (side < 0 ? 20 : 30);
  const double wood = -(k.H + 17.0 + 5.0 * n.fbm_world(x, 0, 40.0, 3, 0.5, salt));
  if (s <= kFarFieldWoodTop_m) return wood - 2.0 * std::max(0.0, s - kFarFieldStart_m) / 35.0;
  const double ridge = -(k.H + 37.0 + 12.0 * n.fbm_world(x, 0, 120.0, 3, 0.5, salt + 1));
  const double t = (s - kFarFieldWoodTop_m) / (kFarFieldEnd_m - kFarFieldWoodTop_m);
  const double wood_back = wood - 2.0;
  return wood_back + (ridge - wood_back) * smoothstep(0.0, 1.0, t);
}

std::string tile_name(int index, const char* what) {
  return "tile" + std::to_string(index) + "." + what;
}

// The material of a surface that bounds a solid: its back faces are never seen.
sim::Material solid(int texture, float albedo) {
  sim::Material m = material(texture, albedo);
  m.double_sided = false;
  return m;
}

// The procedural textures, or where options.photographs asks for them the photographs of the
// same kinds (scenes/photographs.hpp), each at the mean grey of the procedural texture it
// replaces.
Textures add_textures(sim::SceneGeometry* g, std::uint64_t seed, const RiverReachOptions& o) {
  const RngStreams streams(seed);
  const std::vector<PhotographEntry> photos =
      o.photographs ? photograph_manifest() : std::vector<PhotographEntry>{};
  auto add = [&](TextureKind kind) {
    const int index = add_scene_texture(g, streams, kind, o.texture_contrast);
    const bool photographed = std::any_of(photos.begin(), photos.end(), [&](const auto& e) {
      return e.kind == texture_kind_name(kind);
    });
    sim::Texture& t = g->textures[static_cast<std::size_t>(index)];
    if (photographed) t = load_photograph(kind, mean_gray(t));
    return index;
  };
  Textures t{};
  t.grass = add(TextureKind::kGrass);
  t.soil = add(TextureKind::kSoil);
  t.bark = add(TextureKind::kBark);
  t.foliage = add(TextureKind::kFoliage);
  t.reeds = add(TextureKind::kReeds);
  t.concrete = add(TextureKind::kConcrete);
  t.sheet = add(TextureKind::kSheetPiling);
  t.facade = add(TextureKind::kFacade);
  t.roof = add(TextureKind::kRoof);
  t.brick = add(TextureKind::kBrick);
  t.stone = add(TextureKind::kStone);
  const double foliage_grey = mean_gray(g->textures[static_cast<std::size_t>(t.foliage)]);
  for (const auto& [shape, index, name] :
       {std::tuple{LeafShape::kBroad, &t.leaves_broad, "broad"},
        std::tuple{LeafShape::kNarrow, &t.leaves_narrow, "narrow"}}) {
    Rng r = streams.stream(fmt::format("scene.texture.leaves_{}", name));
    *index = static_cast<int>(g->textures.size());
    g->textures.push_back(make_leaf_cluster(shape, &r, foliage_grey, kLeafGreyContrast));
  }
  if (o.far_trees_per_m > 0) {
    Rng r = streams.stream("scene.texture.tree_billboard");
    t.tree_billboard = static_cast<int>(g->textures.size());
    g->textures.push_back(make_tree_billboard(&r, foliage_grey, kLeafGreyContrast));
  }
  if (o.reed_model == ReedModel::kCards) {
    Rng r = streams.stream("scene.texture.reeds_clump");
    t.reed_clump = static_cast<int>(g->textures.size());
    g->textures.push_back(make_reed_clump(
        &r, mean_gray(g->textures[static_cast<std::size_t>(t.reeds)]), kLeafGreyContrast));
  }
  return t;
}

// ---------------------------------------------------------------------------
// Terrain: a grid along x (rows) and across the bank (columns in s).

void add_terrain(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Noise& n,
                 const Textures& tex, int side) {
  const int rows = std::max(2, static_cast<int>(std::ceil((L.x1_m - L.x0_m) / kRowSpacing_m)));
  // Bank face: underwater toe, the water's edge, the slope in <= 1 m steps.
  std::vector<double> bank_s{k.toe_s, 0.0};
  const int slope_steps = std::clamp(static_cast<int>(std::ceil(k.run / 1.0)), 1, 8);
  if (k.run > 0.05)
    for (int i = 1; i <= slope_steps; ++i) bank_s.push_back(k.run * i / slope_steps);
  // Plain: columns widen with distance (the camera sees far ground at grazing
  // angles, where fine columns would only cost vertices).
  std::vector<double> plain_s{bank_s.back()};
  for (double s : {0.5, 1.5, 3.0, 5.0, 8.0, 12.0, 17.0, 23.0, 30.0, 38.0, 47.0, 56.0, 64.0}) {
    const double sp = k.run + s;
    if (sp > plain_s.back() + 0.25 && sp <= kFarFieldStart_m + 4.0) plain_s.push_back(sp);
  }
  if (plain_s.back() < kFarFieldStart_m + 4.0) plain_s.push_back(kFarFieldStart_m + 4.0);

  const Vec3 front(0, -0.5 * side, -1);  // up and towards the river
  auto grid = [&](const std::vector<double>& cols, const char* what, int texture, float albedo,
                  double repeat_m) {
    MeshBuilder mb(tile_name(L.index, what), solid(texture, albedo));
    const int nc = static_cast<int>(cols.size());
    std::vector<Vec3> P(static_cast<std::size_t>((rows + 1) * nc));
    auto at = [&](int r, int c) -> Vec3& { return P[static_cast<std::size_t>(r * nc + c)]; };
    for (int r = 0; r <= rows; ++r) {
      const double x = L.x0_m + (L.x1_m - L.x0_m) * r / rows;
      for (int c = 0; c < nc; ++c)
        at(r, c) = Vec3(x, side * (k.b + cols[c]), terrain_z(k, n, x, cols[c], side));
    }
    std::vector<std::uint32_t> id(P.size());
    for (int r = 0; r <= rows; ++r) {
      double along = 0;  // distance along the ground profile, for v
      for (int c = 0; c < nc; ++c) {
        if (c > 0) along += (at(r, c) - at(r, c - 1)).norm();
        // Normal from central differences on the grid (one-sided at borders).
        const Vec3 dx = at(std::min(r + 1, rows), c) - at(std::max(r - 1, 0), c);
        const Vec3 ds = at(r, std::min(c + 1, nc - 1)) - at(r, std::max(c - 1, 0));
        Vec3 nn = dx.cross(ds);
        if (nn.dot(front) < 0) nn = -nn;
        id[static_cast<std::size_t>(r * nc + c)] =
            mb.vertex(at(r, c), nn, at(r, c).x() / repeat_m, along / repeat_m);
      }
    }
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c + 1 < nc; ++c) {
        const auto i00 = id[static_cast<std::size_t>(r * nc + c)];
        const auto i01 = id[static_cast<std::size_t>(r * nc + c + 1)];
        const auto i10 = id[static_cast<std::size_t>((r + 1) * nc + c)];
        const auto i11 = id[static_cast<std::size_t>((r + 1) * nc + c + 1)];
        mb.triangle(i00, i10, i11, front);
        mb.triangle(i00, i11, i01, front);
      }
    add_mesh(g, mb.take());
  };
  grid(bank_s, side > 0 ? "bank_east" : "bank_west", tex.soil, 0.75f, 4.0);
  // A very gentle bank can run out past the near terrain: then there is no plain.
  if (plain_s.size() >= 2)
    grid(plain_s, side > 0 ? "plain_east" : "plain_west", tex.grass, 0.8f, 8.0);
}

}  // namespace river

using namespace river;  // the reach's parts (river_reach_parts.hpp)

double river_terrain_z(const RiverReachOptions& options, std::uint64_t seed, double x_m,
                       double y_m) {
  const Bank k = bank_of(options);
  const int side = y_m >= 0 ? 1 : -1;
  return terrain_z(k, terrain_noise(seed), x_m, std::abs(y_m) - k.b, side);
}

RiverTileLayout plan_river_tile(const RiverReachOptions& o, std::uint64_t seed, int index) {
  const Bank k = bank_of(o);
  const Noise n = terrain_noise(seed);
  Rng rng = RngStreams(seed).stream("scene.river.tile." + std::to_string(index));
  RiverTileLayout L = plan_structures(o, k, index);
  L.bollards_W = plan_bollards(L, k, n);
  // One stream in this order: buildings, trees, bushes.
  L.buildings = plan_buildings(o, k, n, L, &rng);
  L.trees = plan_trees(o, k, n, L, seed, &rng);
  L.bushes = plan_bushes(o, k, n, L, &rng);
  return L;
}

sim::Lighting outdoor_lighting(Sky sky) {
  sim::Lighting l;
  if (sky == Sky::kSun) {
    // Afternoon sun in the south-west, 40 deg up (the paper's survey was at
    // 16:00 UTC in May, though under cloud).
    l.sun = true;
    l.sun_direction_W = Eigen::Vector3f(-0.72f, -0.26f, -0.64f).normalized();
    l.ambient = 0.35f;
    l.diffuse = 0.75f;
    l.sky_brightness = 0.9f;
    l.fog_distance_m = 800.f;
  } else {
    // Overcast: the sky itself is the light, strongest from straight above: the CIE
    // overcast sky, three times as bright at the zenith as at the horizon (Moon and Spencer
    // 1942), seen through the camera's highlight shoulder, which keeps the horizon at
    // sky_brightness (the fog's grey) and the sky above it below white.
    l.sun = false;
    l.sun_direction_W = Eigen::Vector3f(0.f, 0.f, -1.f);
    l.ambient = 0.55f;
    l.diffuse = 0.45f;
    l.sky_brightness = 0.85f;
    l.fog_distance_m = 400.f;
    l.sky_zenith_ratio = 3.f;
    l.sky_knee = 0.8f;
  }
  return l;
}

sim::SceneGeometry build_river_reach(const RiverReachOptions& options, Sky sky, std::uint64_t seed,
                                     double north_min_m, double north_max_m) {
  yaml::validate_or_throw(options, "scene.river_reach");
  DRIFTLAB_DEMAND_MSG(
      std::isfinite(north_min_m) && std::isfinite(north_max_m) && north_min_m <= north_max_m,
      "build_river_reach needs finite north_min_m <= north_max_m");
  const double len = options.reach_length_m;
  const double lo = north_min_m - options.view_margin_m, hi = north_max_m + options.view_margin_m;
  const auto k0 = static_cast<long long>(std::floor(lo / len));
  const auto k1 = std::max(k0, static_cast<long long>(std::ceil(hi / len)) - 1);
  DRIFTLAB_DEMAND_MSG(k1 - k0 < 1000, "build_river_reach: more than 1000 tiles requested");
  DRIFTLAB_DEMAND_MSG(std::abs(k0) < 1000000 && std::abs(k1) < 1000000, "tile index out of range");

  sim::SceneGeometry g;
  g.lighting = outdoor_lighting(sky);
  if (options.visibility_m)
    g.lighting.fog_distance_m = static_cast<float>(*options.visibility_m / kKoschmiederContrast);
  if (!g.lighting.sun && options.cloud_contrast > 0) {
    g.lighting.cloud_contrast = static_cast<float>(options.cloud_contrast);
    g.sky_clouds = bake_cloud_layer(seed);
  }
  g.water = sim::WaterAppearance{};
  g.water.turbidity = 0.6f;  // a lowland river after rain: murky, brownish-grey
  const Textures tex = add_textures(&g, seed, options);
  const Bank k = bank_of(options);
  const Noise n = terrain_noise(seed);
  sim::Mesh bollard = load_mesh_asset(shipped_asset("bollard.obj"));

  for (auto ki = k0; ki <= k1; ++ki) {
    const int index = static_cast<int>(ki);
    const RiverTileLayout L = plan_river_tile(options, seed, index);
    for (int side : {1, -1}) add_terrain(&g, L, k, n, tex, side);

    Rng lumps = RngStreams(seed).stream("scene.river.tile." + std::to_string(index) + ".crowns");
    if (options.tree_model == TreeModel::kSkeleton) {
      add_skeleton_trees(&g, L, k, tex, options, seed);
    } else {
      add_ellipsoid_trees(&g, L, tex, &lumps);
      MeshBuilder bushes(tile_name(index, "bushes"), solid(tex.foliage, 0.8f));
      for (const TreeSpec& t : L.bushes) add_crown(&bushes, t, 0.5, &lumps);
      add_mesh(&g, bushes.take());
    }

    add_reeds(&g, L, k, n, tex, options, seed, index);
    add_waterline_stones(&g, L, k, n, tex, options, seed, index);
    add_bank_roots(&g, L, k, n, tex, options, seed);
    add_bank_undercuts(&g, L, k, tex, options, seed);

    if (L.bridge) add_bridge(&g, L, k, n, tex);
    if (L.quay) add_quay(&g, L, k, tex, options);
    add_buildings(&g, L, tex);
    for (int side : {1, -1}) {
      add_far_field(&g, L, k, n, tex, side);
      add_far_trees(&g, L, k, n, tex, options, seed, side);
    }

    sim::Mesh bollards;
    bollards.name = tile_name(index, "bollards");
    bollards.material = material(-1, 0.3f, 0.2f);
    for (const Eigen::Vector3d& p : L.bollards_W) append_mesh(&bollards, bollard, p);
    add_mesh(&g, std::move(bollards));
  }
  add_river_bend(&g, static_cast<double>(k1 + 1) * len, -1, k, n, tex);
  add_river_bend(&g, static_cast<double>(k0) * len, 1, k, n, tex);
  add_other_vessels(&g, options.vessels, seed, options.texture_contrast);
  return g;
}

}  // namespace driftlab::scenes
