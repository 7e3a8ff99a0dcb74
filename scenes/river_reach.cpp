#include "scenes/river_reach.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <tuple>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "scenes/assets.hpp"
#include "scenes/mesh_builder.hpp"
#include "scenes/noise.hpp"
#include "scenes/photographs.hpp"
#include "scenes/sky_clouds.hpp"
#include "scenes/textures.hpp"
#include "scenes/trees.hpp"
#include "scenes/vessels.hpp"

namespace driftlab::scenes {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kToeDepth_m = 0.8;           // the bank slope continues this far under water
constexpr double kPlainGrade = 0.01;          // rise of the plain behind the bank top
constexpr double kRowSpacing_m = 1.5;         // terrain grid spacing along the river
constexpr double kTreeSpacingAtFull_m = 4.0;  // tree spacing per row at vegetation_density 1
constexpr double kTreeRowGap_m = 6.0;         // second tree row behind the tree line
constexpr double kCrownAxisFrac = 0.38;       // crown's vertical semi-axis / tree height
constexpr double kFarFieldWoodTop_m = 95.0;   // the far wood's canopy reaches back to here
constexpr double kBridgeClearance_m = 3.5;    // deck underside above the bank top
constexpr double kDeckDepth_m = 0.9;
constexpr double kBridgeLandSpan_m = 12.0;  // abutment length behind the water's edge
constexpr double kRampGrade = 0.15;
constexpr double kQuayLength_m = 30.0;
constexpr int kReedBlades = 14;            // blades per reed clump
constexpr double kQuayPaving_m = 8.0;      // depth of the paved quay behind the wall
constexpr double kLeafGreyContrast = 0.3;  // relative spread of the leaves' grey in a cluster

// Cross-section of one bank, from the options.
struct Bank {
  double b = 0;  // water's edge |y| [m]
  double H = 0;  // bank top above the water [m]
  double tan_slope = 0;
  double run = 0;    // horizontal extent of the slope [m]
  double toe_s = 0;  // s (distance beyond the water's edge) of the underwater toe, < 0
};

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

struct Textures {
  int grass, soil, bark, foliage, reeds, concrete, sheet, facade, roof, brick, stone;
  int leaves_broad, leaves_narrow;  // leaf-cluster cards (alpha), at the foliage's mean grey
  int reed_clump = -1;              // reed_model cards (alpha), at the reeds' mean grey
  int tree_billboard = -1;          // far_trees_per_m (alpha), at the foliage's mean grey
};

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

// ---------------------------------------------------------------------------
// Trees: a 6-sided trunk and a lumpy ellipsoidal crown.

// What a lumpy ellipsoid looks like: its grid (sides around, bands pole to pole), the range of
// the random scale of its vertices off the poles, and one texture repeat every repeat_m.
struct Lumps {
  int sides = 9, bands = 6;
  double lo = 0.85, hi = 1.15;
  double repeat_m = 3.0;
};

// A lumpy ellipsoid centred at c, horizontal semi-axis r and vertical a: the poles exact, the
// other vertices scaled by uniform(lo, hi) so that it does not look machine-made; u wraps
// around (whole repeats), v runs from the upper pole down.
void add_lumpy_ellipsoid(MeshBuilder* mb, const Vec3& c, double r, double a, const Lumps& form,
                         Rng* lumps) {
  const int kSides = form.sides, kBands = form.bands;
  std::vector<Vec3> P(static_cast<std::size_t>((kBands + 1) * kSides));
  auto at = [&](int j, int i) -> Vec3& {
    return P[static_cast<std::size_t>(j * kSides + ((i % kSides) + kSides) % kSides)];
  };
  for (int j = 0; j <= kBands; ++j) {
    const double th = kPi * j / kBands;
    for (int i = 0; i < kSides; ++i) {
      const double f = (j == 0 || j == kBands) ? 1.0 : lumps->uniform(form.lo, form.hi);
      const double ph = 2 * kPi * i / kSides;
      at(j, i) = c + Vec3(r * f * std::sin(th) * std::cos(ph), r * f * std::sin(th) * std::sin(ph),
                          -a * f * std::cos(th));
    }
  }
  const double u_repeats = std::max(1.0, std::round(2 * kPi * r / form.repeat_m));
  const double v_len = kPi * 0.5 * (r + a) / form.repeat_m;
  std::vector<std::uint32_t> id(static_cast<std::size_t>((kBands + 1) * (kSides + 1)));
  auto vid = [&](int j, int i) -> std::uint32_t& {
    return id[static_cast<std::size_t>(j * (kSides + 1) + i)];
  };
  for (int j = 0; j <= kBands; ++j)
    for (int i = 0; i <= kSides; ++i) {  // i == kSides repeats i == 0 with u = u_repeats
      Vec3 nn;
      if (j == 0) {
        nn = -Vec3::UnitZ();
      } else if (j == kBands) {
        nn = Vec3::UnitZ();
      } else {
        nn = (at(j + 1, i) - at(j - 1, i)).cross(at(j, i + 1) - at(j, i - 1));
        if (nn.dot(at(j, i) - c) < 0) nn = -nn;
      }
      vid(j, i) = mb->vertex(at(j, i), nn, u_repeats * i / kSides, v_len * j / kBands);
    }
  for (int j = 0; j < kBands; ++j)
    for (int i = 0; i < kSides; ++i) {
      const Vec3 mid = (at(j, i) + at(j + 1, i + 1)) / 2 - c;
      if (j > 0) mb->triangle(vid(j, i), vid(j, i + 1), vid(j + 1, i + 1), mid);
      if (j + 1 < kBands) mb->triangle(vid(j, i), vid(j + 1, i + 1), vid(j + 1, i), mid);
    }
}

// A lumpy ellipsoid whose apex is at the tree's height and whose vertical
// semi-axis is `a_frac` x the height (0.38 for a tree, 0.5 for a bush sitting
// on the ground).
void add_crown(MeshBuilder* mb, const TreeSpec& t, double a_frac, Rng* lumps) {
  const double a = a_frac * t.height_m;
  add_lumpy_ellipsoid(mb, t.base_W - Vec3(0, 0, t.height_m - a), t.crown_radius_m, a, Lumps{},
                      lumps);
}

// ---------------------------------------------------------------------------
// The bridge: deck on two abutments and piers, railings, embankment ramps.

void add_bridge(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Noise& n,
                const Textures& tex) {
  MeshBuilder concrete(tile_name(L.index, "bridge"), material(tex.concrete, 0.8f));
  MeshBuilder ramps(tile_name(L.index, "bridge_ramps"), material(tex.grass, 0.8f));
  MeshBuilder rails(tile_name(L.index, "bridge_railings"), material(-1, 0.45f, 0.3f));
  const double bx = L.bridge_x_m, hw = L.bridge_half_width_m;
  const double z_under = L.bridge_deck_bottom_z_m, z_top = z_under - kDeckDepth_m;
  const double land = k.b + kBridgeLandSpan_m;
  // Deck over the water; abutments from just behind the water's edge to the
  // end of the land span, their tops level with the road.
  concrete.box({bx - hw, -(k.b + 0.5), z_top}, {bx + hw, k.b + 0.5, z_under}, 4.0);
  for (int side : {1, -1}) {
    const double y0 = side > 0 ? k.b + 0.5 : -land, y1 = side > 0 ? land : -(k.b + 0.5);
    concrete.box({bx - hw, y0, z_top}, {bx + hw, y1, 0.5}, 4.0, MeshBuilder::kNoBottom);
    // Embankment ramp from the abutment down to the plain at kRampGrade.
    const double ramp_len = std::max(2.0, (-z_top - k.H) / kRampGrade);
    const double s_end = kBridgeLandSpan_m + ramp_len;
    const double y_end = side * (k.b + s_end), y_start = side * land;
    const double z_end = terrain_z(k, n, bx, s_end, side);
    const Vec3 out(0, side, 0);
    concrete.quad_m({bx - hw, y_start, z_top}, {bx + hw, y_start, z_top}, {bx + hw, y_end, z_end},
                    {bx - hw, y_end, z_end}, -Vec3::UnitZ() + 0.1 * out, 2 * hw, 4.0);
    for (double xs : {bx - hw, bx + hw}) {
      const double zg0 = terrain_z(k, n, xs, kBridgeLandSpan_m, side) + 0.5;
      const double zg1 = terrain_z(k, n, xs, s_end, side) + 0.5;
      ramps.quad_m({xs, y_start, z_top}, {xs, y_end, z_end}, {xs, y_end, zg1}, {xs, y_start, zg0},
                   Vec3(xs < bx ? -1 : 1, 0, 0), 8.0, 8.0);
    }
  }
  // Piers from below the water to the deck's underside, with a wider cap.
  for (double yp : L.pier_y_m) {
    // Sides only for the shaft (its top is under the cap, its foot in the
    // river bed); the cap's underside shows from the water.
    concrete.box({bx - hw + 0.6, yp - 0.6, z_under + 0.5}, {bx + hw - 0.6, yp + 0.6, 1.0}, 4.0,
                 MeshBuilder::kAllFaces & ~(MeshBuilder::kBottom | MeshBuilder::kTop));
    concrete.box({bx - hw + 0.3, yp - 0.9, z_under}, {bx + hw - 0.3, yp + 0.9, z_under + 0.5}, 4.0,
                 MeshBuilder::kAllFaces & ~MeshBuilder::kTop);
  }
  // Railings: posts every 2 m and two rails, on both edges of the deck.
  for (double xr : {bx - hw + 0.15, bx + hw - 0.15}) {
    for (double y = -land; y <= land + 1e-9; y += 2.0)
      rails.box({xr - 0.06, y - 0.06, z_top - 1.1}, {xr + 0.06, y + 0.06, z_top}, 1.0,
                MeshBuilder::kNoBottom);
    for (double zr : {z_top - 1.1, z_top - 0.6})
      rails.box({xr - 0.05, -land, zr}, {xr + 0.05, land, zr + 0.1}, 1.0);
  }
  add_mesh(g, concrete.take());
  add_mesh(g, ramps.take());
  add_mesh(g, rails.take());
}

// ---------------------------------------------------------------------------
// The quay: corrugated steel sheet piling along the east bank, a concrete
// capping beam and a paved quay behind; optionally a wet band on the piling
// (quay_stain_height_m) and steel ladders on its face (quay_ladder_spacing_m).

// Ladders on the quay's face (east bank, facing -y), centred at each x of `xs`: two rails
// from 1 m below the water to handholds 0.9 m above the capping beam at z_cap_top, rungs every
// 0.3 m, standing off the beam's face (b - 0.15) by 0.1 m.
void add_quay_ladders(sim::SceneGeometry* g, const RiverTileLayout& L, double b, double z_cap_top,
                      const std::vector<double>& xs) {
  if (xs.empty()) return;
  MeshBuilder ladders(tile_name(L.index, "quay_ladders"), material(-1, 0.45f, 0.2f));
  const double y = b - 0.25, z_bottom = 1.0, z_top = z_cap_top - 0.9;
  for (const double x : xs) {
    for (const double dx : {-0.225, 0.225})
      ladders.prism({x + dx, y, z_top}, {x + dx, y, z_bottom}, 0.025, 6, 0.2);
    for (double z = 0.7; z > z_cap_top; z -= 0.3)
      ladders.prism({x - 0.225, y, z}, {x + 0.225, y, z}, 0.015, 4, 0.1);
  }
  add_mesh(g, ladders.take());
}

void add_quay(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Textures& tex,
              const RiverReachOptions& o) {
  MeshBuilder pile(tile_name(L.index, "quay_piling"), material(tex.sheet, 0.55f, 0.15f));
  MeshBuilder wet(tile_name(L.index, "quay_piling_wet"), material(tex.sheet, 0.55f * 0.55f, 0.25f));
  MeshBuilder cap(tile_name(L.index, "quay_cap"), material(tex.concrete, 0.8f));
  MeshBuilder paving(tile_name(L.index, "quay_paving"), material(tex.stone, 0.7f));
  const double b = k.b, z_pile_top = -(k.H + 0.4), z_foot = 1.0;
  const double z_cap_top = z_pile_top - 0.5;
  // The wet band's top (NED: up is -z), never above the piling.
  const double z_stain = -std::min(o.quay_stain_height_m, -z_pile_top);
  // Larssen-type profile per 1.2 m pitch: outer pan, web, inner pan, web.
  static constexpr double kPx[5] = {0.0, 0.35, 0.6, 0.95, 1.2};
  static constexpr double kPy[5] = {0.0, 0.0, 0.22, 0.22, 0.0};
  const double pitch = 1.2;
  const int pitches = static_cast<int>(std::floor((L.quay_x1_m - L.quay_x0_m) / pitch));
  // One facet of the piling from z_a down to z_b; texture anchored to the world (u = x / 2.4 m)
  // so pans line up across facets.
  const auto facet = [&](MeshBuilder* mb, double xa, double xb, double ya, double yb, double z_a,
                         double z_b) {
    const Eigen::Vector2d t0(xa / 2.4, z_a / 2.0), t1(xb / 2.4, z_a / 2.0);
    const Eigen::Vector2d t2(xb / 2.4, z_b / 2.0), t3(xa / 2.4, z_b / 2.0);
    mb->quad({xa, ya, z_a}, {xb, yb, z_a}, {xb, yb, z_b}, {xa, ya, z_b}, -Vec3::UnitY(), t0, t1, t2,
             t3);
  };
  for (int p = 0; p < pitches; ++p)
    for (int s = 0; s < 4; ++s) {
      const double xa = L.quay_x0_m + p * pitch + kPx[s], xb = L.quay_x0_m + p * pitch + kPx[s + 1];
      const double ya = b + kPy[s], yb = b + kPy[s + 1];
      if (z_stain < 0) {
        facet(&pile, xa, xb, ya, yb, z_pile_top, z_stain);
        facet(&wet, xa, xb, ya, yb, z_stain, z_foot);
      } else {
        facet(&pile, xa, xb, ya, yb, z_pile_top, z_foot);
      }
    }
  const double x0 = L.quay_x0_m, x1 = L.quay_x0_m + pitches * pitch;
  // End plates close the gap between the piles and the paving at both ends.
  for (double xe : {x0, x1})
    pile.quad_m({xe, b, z_cap_top}, {xe, b + 0.7, z_cap_top}, {xe, b + 0.7, z_foot},
                {xe, b, z_foot}, Vec3(xe == x0 ? -1 : 1, 0, 0), 2.4, 2.0);
  cap.box({x0, b - 0.15, z_cap_top}, {x1, b + 0.7, z_pile_top + 0.1}, 4.0, MeshBuilder::kNoBottom);
  paving.box({x0, b + 0.7, z_cap_top}, {x1, b + kQuayPaving_m, 0.3}, 3.0,
             MeshBuilder::kNoBottom & ~MeshBuilder::kWest);
  add_mesh(g, pile.take());
  if (z_stain < 0) add_mesh(g, wet.take());
  add_mesh(g, cap.take());
  add_mesh(g, paving.take());
  std::vector<double> ladder_x;
  if (o.quay_ladder_spacing_m > 0)
    for (double x = x0 + o.quay_ladder_spacing_m / 2; x < x1 - 0.5; x += o.quay_ladder_spacing_m)
      ladder_x.push_back(x);
  add_quay_ladders(g, L, b, z_cap_top, ladder_x);
}

// ---------------------------------------------------------------------------
// Buildings: facade walls (brick with windows, one 3 m bay per texture
// repeat), gable roof along the longer side.

void add_buildings(sim::SceneGeometry* g, const RiverTileLayout& L, const Textures& tex) {
  MeshBuilder walls(tile_name(L.index, "building_walls"), material(tex.facade, 0.85f));
  MeshBuilder gables(tile_name(L.index, "building_gables"), material(tex.brick, 0.85f));
  MeshBuilder roofs(tile_name(L.index, "building_roofs"), material(tex.roof, 0.7f));
  for (const BuildingSpec& B : L.buildings) {
    const double zt = B.eave_z_m, zb = B.ground_z_m;
    const Vec3 c((B.x0_m + B.x1_m) / 2, (B.y0_m + B.y1_m) / 2, 0);
    // Facade v = 0 at the eave so whole storeys (3 m) line up with the texture.
    auto wall = [&](const Vec3& a, const Vec3& b, const Vec3& out) {
      const double w = (b - a).norm() / 3.0, h0 = 0.0, h1 = (zb - zt) / 3.0;
      walls.quad({a.x(), a.y(), zt}, {b.x(), b.y(), zt}, {b.x(), b.y(), zb}, {a.x(), a.y(), zb},
                 out, {0, h0}, {w, h0}, {w, h1}, {0, h1});
    };
    const Vec3 p00(B.x0_m, B.y0_m, 0), p10(B.x1_m, B.y0_m, 0), p11(B.x1_m, B.y1_m, 0),
        p01(B.x0_m, B.y1_m, 0);
    wall(p00, p10, -Vec3::UnitY());
    wall(p10, p11, Vec3::UnitX());
    wall(p11, p01, Vec3::UnitY());
    wall(p01, p00, -Vec3::UnitX());
    // Gable roof: the ridge runs along the longer horizontal side.
    const bool ridge_along_x = (B.x1_m - B.x0_m) >= (B.y1_m - B.y0_m);
    const double o = 0.3;  // eave overhang
    const double zr = B.ridge_z_m;
    if (ridge_along_x) {
      const double yc = c.y();
      roofs.quad_m({B.x0_m - o, B.y0_m - o, zt + 0.2}, {B.x1_m + o, B.y0_m - o, zt + 0.2},
                   {B.x1_m + o, yc, zr}, {B.x0_m - o, yc, zr}, Vec3(0, -1, -1), 4.0, 4.0);
      roofs.quad_m({B.x1_m + o, B.y1_m + o, zt + 0.2}, {B.x0_m - o, B.y1_m + o, zt + 0.2},
                   {B.x0_m - o, yc, zr}, {B.x1_m + o, yc, zr}, Vec3(0, 1, -1), 4.0, 4.0);
      for (double xg : {B.x0_m, B.x1_m}) {
        const Vec3 out(xg == B.x0_m ? -1 : 1, 0, 0);
        const auto a = gables.vertex({xg, B.y0_m, zt}, out, B.y0_m / 0.9, zt / 0.6);
        const auto b2 = gables.vertex({xg, B.y1_m, zt}, out, B.y1_m / 0.9, zt / 0.6);
        const auto r = gables.vertex({xg, yc, zr}, out, yc / 0.9, zr / 0.6);
        gables.triangle(a, b2, r, out);
      }
    } else {
      const double xc = c.x();
      roofs.quad_m({B.x0_m - o, B.y1_m + o, zt + 0.2}, {B.x0_m - o, B.y0_m - o, zt + 0.2},
                   {xc, B.y0_m - o, zr}, {xc, B.y1_m + o, zr}, Vec3(-1, 0, -1), 4.0, 4.0);
      roofs.quad_m({B.x1_m + o, B.y0_m - o, zt + 0.2}, {B.x1_m + o, B.y1_m + o, zt + 0.2},
                   {xc, B.y1_m + o, zr}, {xc, B.y0_m - o, zr}, Vec3(1, 0, -1), 4.0, 4.0);
      for (double yg : {B.y0_m, B.y1_m}) {
        const Vec3 out(0, yg == B.y0_m ? -1 : 1, 0);
        const auto a = gables.vertex({B.x0_m, yg, zt}, out, B.x0_m / 0.9, zt / 0.6);
        const auto b2 = gables.vertex({B.x1_m, yg, zt}, out, B.x1_m / 0.9, zt / 0.6);
        const auto r = gables.vertex({xc, yg, zr}, out, xc / 0.9, zr / 0.6);
        gables.triangle(a, b2, r, out);
      }
    }
  }
  add_mesh(g, walls.take());
  add_mesh(g, gables.take());
  add_mesh(g, roofs.take());
}

// ---------------------------------------------------------------------------
// Far field: the edge of a wood beyond the near terrain, its canopy, and hills.

void add_far_field(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Noise& n,
                   const Textures& tex, int side) {
  MeshBuilder wood(tile_name(L.index, side > 0 ? "far_wood_east" : "far_wood_west"),
                   solid(tex.foliage, 0.7f));
  MeshBuilder hills(tile_name(L.index, side > 0 ? "far_hills_east" : "far_hills_west"),
                    solid(tex.foliage, 0.55f));
  const int segs = std::max(1, static_cast<int>(std::ceil((L.x1_m - L.x0_m) / 5.0)));
  const double s_edge = kFarFieldStart_m + 2.0;
  const Vec3 towards_river(0, -side, 0);
  for (int i = 0; i < segs; ++i) {
    const double xa = L.x0_m + (L.x1_m - L.x0_m) * i / segs;
    const double xb = L.x0_m + (L.x1_m - L.x0_m) * (i + 1) / segs;
    auto y = [&](double s) { return side * (k.b + s); };
    const double ga = terrain_z(k, n, xa, s_edge, side) + 1.0,
                 gb = terrain_z(k, n, xb, s_edge, side) + 1.0;
    const Vec3 ea(xa, y(s_edge), far_top_z(k, n, xa, s_edge, side));
    const Vec3 eb(xb, y(s_edge), far_top_z(k, n, xb, s_edge, side));
    const Vec3 wa(xa, y(kFarFieldWoodTop_m), far_top_z(k, n, xa, kFarFieldWoodTop_m, side));
    const Vec3 wb(xb, y(kFarFieldWoodTop_m), far_top_z(k, n, xb, kFarFieldWoodTop_m, side));
    const Vec3 ha(xa, y(kFarFieldEnd_m), far_top_z(k, n, xa, kFarFieldEnd_m, side));
    const Vec3 hb(xb, y(kFarFieldEnd_m), far_top_z(k, n, xb, kFarFieldEnd_m, side));
    // Texture anchored in world x so segments and tiles join seamlessly.
    auto q = [&](MeshBuilder& mb, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                 const Vec3& front, double rep, double va, double vb) {
      mb.quad(a, b, c, d, front, {a.x() / rep, va}, {b.x() / rep, va}, {c.x() / rep, vb},
              {d.x() / rep, vb});
    };
    q(wood, {xa, ea.y(), ga}, {xb, eb.y(), gb}, eb, ea, towards_river, 6.0, 0.0,
      (ga - ea.z()) / 6.0);
    q(wood, ea, eb, wb, wa, towards_river - Vec3::UnitZ(), 6.0, 0.0,
      (kFarFieldWoodTop_m - s_edge) / 6.0);
    q(hills, wa, wb, hb, ha, towards_river - Vec3::UnitZ(), 20.0, 0.0,
      (kFarFieldEnd_m - kFarFieldWoodTop_m) / 20.0);
  }
  add_mesh(g, wood.take());
  add_mesh(g, hills.take());
}

// Far trees (far_trees_per_m a metre of the far wood's front on each side): world-fixed crossed
// billboards (two upright alpha-tested cards at right angles, never turned towards an eye or a
// frame: the scene stays rigid for stereo), 10-16 m tall, growing out of the far wood's canopy
// within 25 m of its front (their feet 6 m below the canopy), so that the wood's skyline breaks
// into crowns.
void add_far_trees(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Noise& n,
                   const Textures& tex, const RiverReachOptions& options, std::uint64_t seed,
                   int side) {
  if (options.far_trees_per_m <= 0) return;
  MeshBuilder trees(tile_name(L.index, side > 0 ? "far_trees_east" : "far_trees_west"),
                    material(tex.tree_billboard, 0.7f));
  Rng rf = RngStreams(seed).stream(
      fmt::format("scene.river.tile.{}.far_trees.{}", L.index, side > 0 ? "east" : "west"));
  const int count = static_cast<int>(std::round(options.far_trees_per_m * options.reach_length_m));
  const double s_edge = kFarFieldStart_m + 2.0;
  for (int i = 0; i < count; ++i) {
    const double x = rf.uniform(L.x0_m, L.x1_m), s = s_edge + rf.uniform(0.0, 25.0);
    const double height = rf.uniform(10.0, 16.0), a = rf.uniform(0.0, kPi / 2);
    const double foot = far_top_z(k, n, x, s, side) + 6.0;
    const Vec3 centre(x, side * (k.b + s), foot - height / 2);
    for (const double phi : {a, a + kPi / 2}) {
      const Vec3 u(std::cos(phi), std::sin(phi), 0);
      trees.card(centre, 0.35 * height * u, Vec3(0, 0, height / 2), Vec3(-u.y(), u.x(), 0));
    }
  }
  add_mesh(g, trees.take());
}

// A wooded river bend closing the valley at x = x_end, facing `facing` (+1:
// faces north, -1: faces south); its skyline follows the side's far field.
void add_river_bend(sim::SceneGeometry* g, double x_end, int facing, const Bank& k, const Noise& n,
                    const Textures& tex) {
  MeshBuilder mb(facing < 0 ? "river_bend_north" : "river_bend_south", solid(tex.foliage, 0.65f));
  const double half = k.b + kFarFieldEnd_m;
  const int segs = static_cast<int>(std::ceil(2 * half / 5.0));
  const Vec3 front(facing, 0, 0);
  auto top = [&](double y) {
    const double s = std::abs(y) - k.b;
    if (s < kFarFieldStart_m) {
      // Across the valley floor and the river: the same wood, its own noise.
      return -(k.H + 17.0 + 5.0 * n.fbm_world(x_end, y, 40.0, 3, 0.5, 40 + (facing > 0 ? 1 : 0)));
    }
    return far_top_z(k, n, x_end, s, y > 0 ? 1 : -1);
  };
  for (int i = 0; i < segs; ++i) {
    const double ya = -half + 2 * half * i / segs, yb = -half + 2 * half * (i + 1) / segs;
    const Vec3 a(x_end, ya, 1.0), b(x_end, yb, 1.0), c(x_end, yb, top(yb)), d(x_end, ya, top(ya));
    mb.quad(a, b, c, d, front, {ya / 6.0, 1.0 / 6.0}, {yb / 6.0, 1.0 / 6.0},
            {yb / 6.0, c.z() / 6.0}, {ya / 6.0, d.z() / 6.0});
  }
  add_mesh(g, mb.take());
}

// ---------------------------------------------------------------------------

bool inside(const BuildingSpec& b, double x, double y, double margin) {
  return x > b.x0_m - margin && x < b.x1_m + margin && y > b.y0_m - margin && y < b.y1_m + margin;
}

bool inside_any(const std::vector<BuildingSpec>& buildings, double x, double y, double margin) {
  bool in_building = false;
  for (const auto& B : buildings) in_building = in_building || inside(B, x, y, margin);
  return in_building;
}

// The tile's extent and where its bridge (with its piers) and quay go, without the bollards.
RiverTileLayout plan_structures(const RiverReachOptions& o, const Bank& k, int index) {
  const double len = o.reach_length_m;
  RiverTileLayout L;
  L.index = index;
  L.x0_m = index * len;
  L.x1_m = L.x0_m + len;

  L.bridge = o.bridge;
  L.bridge_x_m = L.x0_m + 0.6 * len;
  L.bridge_half_width_m = std::min(4.0, 0.07 * len);
  L.bridge_deck_bottom_z_m = -(k.H + kBridgeClearance_m);
  if (L.bridge) {
    // Two piers split a river wider than 12 m into thirds-ish; a narrow one gets one.
    if (k.b >= 6.0) {
      L.pier_y_m = {-k.b / 2, k.b / 2};
    } else if (k.b >= 1.5) {
      L.pier_y_m = {0.0};
    }
  }
  L.quay = o.quay_wall;
  L.quay_x0_m = L.x0_m + 0.15 * len;
  L.quay_x1_m = L.quay_x0_m + std::min(kQuayLength_m, 0.3 * len);
  return L;
}

// Bollards along the quay wall's cap, or one on the east bank when there is no quay.
std::vector<Eigen::Vector3d> plan_bollards(const RiverTileLayout& L, const Bank& k,
                                           const Noise& n) {
  std::vector<Eigen::Vector3d> bollards_W;
  if (L.quay) {
    const double z_cap_top = -(k.H + 0.4) - 0.5;
    for (double x = L.quay_x0_m + 5.0; x < L.quay_x1_m - 1.0; x += 10.0)
      bollards_W.emplace_back(x, k.b + 0.3, z_cap_top);
  } else {
    const double x = L.quay_x0_m + 5.0, s = k.run + 1.0;
    bollards_W.emplace_back(x, k.b + s, terrain_z(k, n, x, s, 1));
  }
  return bollards_W;
}

// Buildings: evenly spread along the tile, alternating banks, behind the
// trees; none on the bridge's road.
std::vector<BuildingSpec> plan_buildings(const RiverReachOptions& o, const Bank& k, const Noise& n,
                                         const RiverTileLayout& L, Rng* rng) {
  const double len = o.reach_length_m;
  std::vector<BuildingSpec> buildings;
  const int nb = o.buildings;
  for (int i = 0; i < nb; ++i) {
    const int side = i % 2 == 0 ? 1 : -1;
    const double slot = len / nb;
    double xc = L.x0_m + (i + 0.5) * slot + rng->uniform(-0.15, 0.15) * slot;
    const double w = std::min(rng->uniform(8.0, 14.0), 0.8 * slot);
    const double d = rng->uniform(8.0, 12.0);
    const int floors = 1 + static_cast<int>(rng->uniform_int(3));
    const double s_front = std::min(o.tree_line_distance_m + 10.0 + rng->uniform(0.0, 12.0),
                                    kFarFieldStart_m - 2.0 - d);
    if (L.bridge && std::abs(xc - L.bridge_x_m) < w / 2 + L.bridge_half_width_m + 3.0)
      xc = L.bridge_x_m + (xc >= L.bridge_x_m ? 1 : -1) * (w / 2 + L.bridge_half_width_m + 3.0);
    BuildingSpec B;
    B.x0_m = xc - w / 2;
    B.x1_m = xc + w / 2;
    const double ya = side * (k.b + s_front), yb = side * (k.b + s_front + d);
    B.y0_m = std::min(ya, yb);
    B.y1_m = std::max(ya, yb);
    double zlow = -1e9, zhigh = 1e9;  // lowest and highest ground under the corners
    for (double x : {B.x0_m, B.x1_m})
      for (double y : {B.y0_m, B.y1_m}) {
        const double z = terrain_z(k, n, x, std::abs(y) - k.b, side);
        zlow = std::max(zlow, z);
        zhigh = std::min(zhigh, z);
      }
    B.ground_z_m = zlow + 0.3;  // walls start below the ground everywhere
    B.eave_z_m = zhigh - 3.0 * floors;
    B.ridge_z_m = B.eave_z_m - 0.5 * std::min(w, d) * std::tan(35.0 * kPi / 180.0);
    buildings.push_back(B);
  }
  return buildings;
}

// Trees: two rows per bank, the first at the tree line. Every candidate
// draws the same numbers whether or not it is kept, so removing one (for the
// bridge, the quay, a building) does not move the others.
// A tree's species, lean and form seed, from a stream of its own (so that the tile's stream, and
// with it every position and size, is the same for either tree model). The mix: willows by the
// water, alders and poplars behind them (species of lowland river banks in Britain).
void choose_form(TreeSpec* t, const RngStreams& streams, const RiverTileLayout& L, int side,
                 int row, int i) {
  Rng r = streams.stream(fmt::format("scene.river.tile.{}.tree.{}.{}.{}", L.index,
                                     side > 0 ? "east" : "west", row, i));
  constexpr std::array<std::array<double, 4>, 2> kMix{{
      {0.40, 0.35, 0.15, 0.10},  // row 0: alder, willow, weeping willow, poplar
      {0.45, 0.20, 0.00, 0.35},  // row 1
  }};
  const double u = r.uniform();
  double acc = 0;
  int species = 3;
  for (int sp = 0; sp < 4; ++sp) {
    acc += kMix[static_cast<std::size_t>(row)][static_cast<std::size_t>(sp)];
    if (u < acc) {
      species = sp;
      break;
    }
  }
  t->species = static_cast<TreeSpecies>(species);
  const bool willow =
      t->species == TreeSpecies::kWillow || t->species == TreeSpecies::kWeepingWillow;
  const double lean_deg = r.uniform(0.0, 1.0), azimuth = r.uniform(0.0, 2 * kPi);
  if (willow && row == 0) {  // willows by the water lean over it
    t->lean_rad = (8.0 + 17.0 * lean_deg) * kPi / 180.0;
    t->lean_dir_W = Vec3(0, -side, 0);
  } else {
    t->lean_rad = 5.0 * lean_deg * kPi / 180.0;
    t->lean_dir_W = Vec3(std::cos(azimuth), std::sin(azimuth), 0);
  }
  t->form_seed = r.next_u64();
}

std::vector<TreeSpec> plan_trees(const RiverReachOptions& o, const Bank& k, const Noise& n,
                                 const RiverTileLayout& L, std::uint64_t seed, Rng* rng) {
  const RngStreams streams(seed);
  std::vector<TreeSpec> trees;
  if (!(o.vegetation_density > 0)) return trees;
  const double len = o.reach_length_m;
  const double spacing = kTreeSpacingAtFull_m / o.vegetation_density;
  const int per_row = std::max(1, static_cast<int>(std::floor(len / spacing)));
  for (int side : {1, -1})
    for (int row = 0; row < 2; ++row)
      for (int i = 0; i < per_row; ++i) {
        const double x = L.x0_m + len * (i + 0.5) / per_row + rng->uniform(-0.3, 0.3) * spacing;
        // Separate statements: the order of two draws in one expression is unspecified.
        double ds = rng->uniform(-0.5, 0.5);
        if (row > 0) ds += rng->uniform(-1.5, 1.5);
        TreeSpec t;
        t.height_m = o.tree_height_m * rng->uniform(kTreeHeightMin, kTreeHeightMax);
        t.crown_radius_m = t.height_m * rng->uniform(0.22, 0.32);
        t.trunk_radius_m = 0.1 + 0.02 * t.height_m;
        // The whole trunk stands behind the water's edge.
        const double s =
            std::max(o.tree_line_distance_m + row * kTreeRowGap_m + ds, t.trunk_radius_m + 0.3);
        const double y = side * (k.b + s);
        choose_form(&t, streams, L, side, row, i);
        t.lod = s <= o.tree_detail_distance_m ? 0 : 1;
        if (L.bridge && std::abs(x - L.bridge_x_m) < L.bridge_half_width_m + 3.0 &&
            s < kBridgeLandSpan_m + 25.0)
          continue;
        if (L.quay && side > 0 && x > L.quay_x0_m - 3.0 && x < L.quay_x1_m + 3.0 &&
            s < kQuayPaving_m + 1.0)
          continue;
        if (inside_any(L.buildings, x, y, 1.0)) continue;
        t.base_W = Vec3(x, y, terrain_z(k, n, x, s, side));
        trees.push_back(t);
      }
  return trees;
}

// Reeds: clumps straddling the water's edge, fewer with lower vegetation density; none at the
// quay or the bridge. reed_model blades: thin two-sided blades (single triangles, so the tops
// are ragged without alpha textures); cards: three crossed alpha-tested cards a clump. Either
// bends from its foot (texture v = 1) to its tip (v = 0): psi = (1 - v)^2, a reed's tip as
// compliant as a tall tree's top, and fluttering at half a leaf's.
void add_reeds(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Noise& n,
               const Textures& tex, const RiverReachOptions& options, std::uint64_t seed,
               int index) {
  const bool cards = options.reed_model == ReedModel::kCards;
  MeshBuilder reeds(tile_name(index, "reeds"), material(cards ? tex.reed_clump : tex.reeds, 0.85f));
  Rng rr = RngStreams(seed).stream("scene.river.tile." + std::to_string(index) + ".reeds");
  const int clumps =
      static_cast<int>(std::round(options.vegetation_density * options.reach_length_m / 2.5));
  for (int side : {1, -1})
    for (int c = 0; c < clumps; ++c) {
      const double x = rr.uniform(L.x0_m, L.x1_m), s = rr.uniform(-0.6, 0.8);
      const double height = rr.uniform(1.0, 2.0), radius = rr.uniform(0.3, 0.7);
      const bool skip = (L.quay && side > 0 && x > L.quay_x0_m - 1.0 && x < L.quay_x1_m + 1.0) ||
                        (L.bridge && std::abs(x - L.bridge_x_m) < L.bridge_half_width_m + 1.0);
      if (cards) {
        const double phase = rr.uniform(0.0, kPi / 3);
        if (skip) continue;
        const double zg = terrain_z(k, n, x, s, side);
        const double foot = zg + 0.2, top = std::min(zg, 0.0) - height;
        const Vec3 centre(x, side * (k.b + s), 0.5 * (foot + top));
        for (int card = 0; card < 3; ++card) {
          const double a = phase + card * kPi / 3;
          const Vec3 u(std::cos(a), std::sin(a), 0);
          reeds.card(centre, 1.2 * radius * u, Vec3(0, 0, 0.5 * (foot - top)),
                     Vec3(-u.y(), u.x(), 0));
        }
        continue;
      }
      for (int blade = 0; blade < kReedBlades; ++blade) {
        // Every blade draws its numbers, kept or not, so skipping a clump
        // leaves the next clumps unchanged.
        const double r = radius * std::sqrt(rr.uniform()), phi = rr.uniform(0.0, 2 * kPi);
        const double face = rr.uniform(0.0, kPi), h = height * rr.uniform(0.6, 1.0);
        const double lean_x = rr.uniform(-0.25, 0.25), lean_y = rr.uniform(-0.25, 0.25);
        const double half_w = rr.uniform(0.03, 0.06);
        if (skip) continue;
        const double bx = x + r * std::cos(phi), sb = s + r * std::sin(phi);
        const double zg = terrain_z(k, n, bx, sb, side);
        const Vec3 base(bx, side * (k.b + sb), zg + 0.2);
        const Vec3 across(std::cos(face) * half_w, std::sin(face) * half_w, 0);
        const Vec3 tip(bx + lean_x, base.y() + lean_y, std::min(zg, 0.0) - h);
        const Vec3 nrm = (base + across - tip).cross(base - across - tip);
        for (const Vec3& nn : {nrm, Vec3(-nrm)}) {
          // A narrow strip of the reed texture, a different one per blade.
          const double u0 = face / kPi;
          const auto a = reeds.vertex(base - across, nn, u0, 1.0);
          const auto b = reeds.vertex(base + across, nn, u0 + 0.08, 1.0);
          const auto t = reeds.vertex(tip, nn, u0 + 0.04, 0.0);
          reeds.triangle(a, b, t, nn);
        }
      }
    }
  sim::Mesh reed_mesh = reeds.take();
  for (const sim::Vertex& v : reed_mesh.vertices) {
    const float h = 1.f - v.v;
    reed_mesh.sway.push_back({h * h, 0.5f * h});
  }
  add_mesh(g, std::move(reed_mesh));
}

// Stones at the water's edge (waterline_stones_per_m a metre of bank on each side): lumpy
// flattened ellipsoids, most small and a few large (radius 0.08 + 0.35 u^2 m), sunk by a third
// of their height into the bank or the river bed on either side of the water line, in the
// soil's grain (the photographs have no stones of this size); none at the quay or the
// bridge. Faceted (a normal a face), so that the overcast light from above breaks each one into
// lit tops and darker flanks.
void add_waterline_stones(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k,
                          const Noise& n, const Textures& tex, const RiverReachOptions& options,
                          std::uint64_t seed, int index) {
  if (options.waterline_stones_per_m <= 0) return;
  MeshBuilder smooth(tile_name(index, "stones"), solid(tex.soil, 0.8f));
  Rng rs = RngStreams(seed).stream("scene.river.tile." + std::to_string(index) + ".stones");
  const int count =
      static_cast<int>(std::round(options.waterline_stones_per_m * options.reach_length_m));
  const Lumps form{5, 3, 0.75, 1.25, 0.3};
  for (int side : {1, -1})
    for (int i = 0; i < count; ++i) {
      const double x = rs.uniform(L.x0_m, L.x1_m), s = rs.uniform(-0.5, 0.6);
      const double u = rs.uniform(), r = 0.08 + 0.35 * u * u, a = r * rs.uniform(0.45, 0.8);
      if ((L.quay && side > 0 && x > L.quay_x0_m - 1.0 && x < L.quay_x1_m + 1.0) ||
          (L.bridge && std::abs(x - L.bridge_x_m) < L.bridge_half_width_m + 1.0))
        continue;
      const Vec3 c(x, side * (k.b + s), terrain_z(k, n, x, s, side) + a / 3);
      add_lumpy_ellipsoid(&smooth, c, r, a, form, &rs);
    }
  const sim::Mesh m = smooth.take();
  MeshBuilder stones(m.name, m.material);
  for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    std::array<Vec3, 3> p;
    for (int j = 0; j < 3; ++j) {
      const sim::Vertex& v = m.vertices[m.indices[t + static_cast<std::size_t>(j)]];
      p[static_cast<std::size_t>(j)] = Vec3(v.x, v.y, v.z);
    }
    const Vec3 nrm = (p[1] - p[0]).cross(p[2] - p[0]);
    std::array<std::uint32_t, 3> id;
    for (int j = 0; j < 3; ++j) {
      const sim::Vertex& v = m.vertices[m.indices[t + static_cast<std::size_t>(j)]];
      id[static_cast<std::size_t>(j)] =
          stones.vertex(p[static_cast<std::size_t>(j)], nrm, v.u, v.v);
    }
    stones.triangle(id[0], id[1], id[2], nrm);
  }
  add_mesh(g, stones.take());
}

// Roots laid bare by the current (bank_roots_per_tree) in front of each tree within 6 m of the
// water's edge: a tube of bark from a point on the bank slope (at most 3 m up it), arching up
// to 15 cm out of it, to the toe just under the water, 5 cm thick at the slope and 1 cm at its
// end. None on a bank whose slope runs less than 0.5 m (vertical, or no bank): there the arch
// would bend tighter than the root is thick and fold its tube inside out.
void add_bank_roots(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Noise& n,
                    const Textures& tex, const RiverReachOptions& options, std::uint64_t seed) {
  if (options.bank_roots_per_tree <= 0 || k.run < 0.5) return;
  MeshBuilder roots(tile_name(L.index, "bank_roots"), solid(tex.bark, 0.7f));
  Rng rr = RngStreams(seed).stream("scene.river.tile." + std::to_string(L.index) + ".roots");
  constexpr int kPoints = 6;
  for (const TreeSpec& t : L.trees) {
    const int side = t.base_W.y() > 0 ? 1 : -1;
    if (std::abs(t.base_W.y()) - k.b > 6.0) continue;
    for (int j = 0; j < options.bank_roots_per_tree; ++j) {
      const double x = t.base_W.x() + rr.uniform(-1.5, 1.5);
      const double s0 = std::min(rr.uniform(0.25, 0.9) * k.run, 3.0), s1 = rr.uniform(-0.2, 0.0);
      const double bulge = rr.uniform(0.05, 0.15), drift = rr.uniform(-0.4, 0.4);
      std::vector<Vec3> points;
      std::vector<double> radii;
      for (int i = 0; i < kPoints; ++i) {
        const double u = static_cast<double>(i) / (kPoints - 1);
        const double s = s0 + (s1 - s0) * u, xi = x + drift * u;
        // Out of the slope (NED: up is -z) along the arch, back into the toe at its end.
        const double lift = bulge * std::sin(kPi * std::min(1.0, 1.25 * u));
        points.emplace_back(xi, side * (k.b + s), terrain_z(k, n, xi, s, side) - lift);
        radii.push_back(0.05 - 0.04 * u);
      }
      roots.tube(points, radii, 5, 0.3);
    }
  }
  add_mesh(g, roots.take());
}

// Stretches [x0, x1) of one bank undercut by the current (bank_undercut_share): 3-10 m long,
// the gaps between them drawn (uniform, mean len (1 - share) / share) so that the share asked
// for is undercut on average; clipped out of the quay (east bank) and the bridge, pieces
// under a metre dropped.
std::vector<std::pair<double, double>> plan_undercuts(const RiverTileLayout& L, double share,
                                                      int side, Rng* rng) {
  std::vector<std::pair<double, double>> keep_out;
  if (L.quay && side > 0) keep_out.emplace_back(L.quay_x0_m - 1.0, L.quay_x1_m + 1.0);
  if (L.bridge)
    keep_out.emplace_back(L.bridge_x_m - L.bridge_half_width_m - 1.0,
                          L.bridge_x_m + L.bridge_half_width_m + 1.0);
  std::sort(keep_out.begin(), keep_out.end());
  std::vector<std::pair<double, double>> out;
  auto gap = [&](double len) { return rng->uniform(0.0, 2.0) * len * (1 - share) / share; };
  double x = L.x0_m + gap(6.5);
  while (x < L.x1_m) {
    const double len = rng->uniform(3.0, 10.0);
    double a = x;
    const double b = std::min(x + len, L.x1_m);
    for (const auto& [k0, k1] : keep_out) {
      if (k1 <= a || k0 >= b) continue;
      if (k0 - a >= 1.0) out.emplace_back(a, k0);
      a = std::max(a, k1);
    }
    if (b - a >= 1.0) out.emplace_back(a, b);
    x = b + gap(len);
  }
  return out;
}

// One undercut stretch [x0, x1) of a bank: stations every 0.25 m at u = (i + 0.5) / steps, the
// lip (its top from where the slope stands h_l above the water, a jagged front, its
// underside 0.15 m lower back into the slope) reaching taper(u) = sqrt(sin(pi u)) of the way
// from the slope out to d beyond the water's edge, and under it the slope's foot in shade, 2 cm
// in front of the slope, from below the water up to the underside.
void add_undercut(MeshBuilder* lip, MeshBuilder* hollow, const Bank& k, double x0, double x1,
                  int side, Rng* rng) {
  constexpr double kThick_m = 0.15, kShadeOffset_m = 0.02, kRepeat_m = 4.0;
  const double h_l = std::min(rng->uniform(0.3, 0.6), 0.7 * k.H);
  const double d = rng->uniform(0.2, 0.4);
  const double s_root = h_l / k.tan_slope, s_under = (h_l - kThick_m) / k.tan_slope;
  const int steps = std::max(2, static_cast<int>(std::ceil((x1 - x0) / 0.25)));
  const double cos_a = 1 / std::sqrt(1 + k.tan_slope * k.tan_slope);
  const Vec3 slope_n(0, -side * k.tan_slope * cos_a, -cos_a);  // up and towards the river
  auto at = [&](double x, double s, double h) { return Vec3(x, side * (k.b + s), -h); };
  struct Station {
    double x, s_front, h_top, s_shade;
  };
  std::vector<Station> st;
  for (int i = 0; i < steps; ++i) {
    const double u = (i + 0.5) / steps;
    const double tau = std::sqrt(std::sin(kPi * u));
    const double reach = d * rng->uniform(0.75, 1.25);  // the jagged front
    st.push_back({x0 + (x1 - x0) * u, s_under - tau * (s_under + reach), h_l - (1 - tau) * kThick_m,
                  s_under - tau * (s_under + 0.15)});
  }
  const Vec3 up(0, 0, -1), down(0, 0, 1), river(0, -side, 0);
  const double h_u = h_l - kThick_m;
  for (std::size_t i = 0; i + 1 < st.size(); ++i) {
    const Station &a = st[i], &b = st[i + 1];
    lip->quad_m(at(a.x, s_root, h_l), at(b.x, s_root, h_l), at(b.x, b.s_front, b.h_top),
                at(a.x, a.s_front, a.h_top), up, kRepeat_m, kRepeat_m);
    lip->quad_m(at(a.x, a.s_front, a.h_top), at(b.x, b.s_front, b.h_top), at(b.x, b.s_front, h_u),
                at(a.x, a.s_front, h_u), river, kRepeat_m, kRepeat_m);
    lip->quad_m(at(a.x, a.s_front, h_u), at(b.x, b.s_front, h_u), at(b.x, s_under, h_u),
                at(a.x, s_under, h_u), down, kRepeat_m, kRepeat_m);
    auto shade = [&](double x, double s) {
      return Vec3(at(x, s, s * k.tan_slope) + kShadeOffset_m * slope_n);
    };
    hollow->quad_m(shade(a.x, a.s_shade), shade(b.x, b.s_shade), shade(b.x, s_under),
                   shade(a.x, s_under), slope_n, kRepeat_m, kRepeat_m);
  }
}

void add_bank_undercuts(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k,
                        const Textures& tex, const RiverReachOptions& options, std::uint64_t seed) {
  if (options.bank_undercut_share <= 0 || k.H < 0.5 || k.run < 0.5) return;
  MeshBuilder lip(tile_name(L.index, "bank_undercut"), solid(tex.soil, 0.75f));
  MeshBuilder hollow(tile_name(L.index, "bank_undercut_hollow"), solid(tex.soil, 0.3f));
  Rng ru = RngStreams(seed).stream("scene.river.tile." + std::to_string(L.index) + ".undercuts");
  for (int side : {1, -1})
    for (const auto& [x0, x1] : plan_undercuts(L, options.bank_undercut_share, side, &ru))
      add_undercut(&lip, &hollow, k, x0, x1, side, &ru);
  if (lip.triangle_count() == 0) return;
  add_mesh(g, lip.take());
  add_mesh(g, hollow.take());
}

// Bushes (willow scrub) on the bank between the reeds and the tree line,
// drawn after the trees so that they do not move them.
std::vector<TreeSpec> plan_bushes(const RiverReachOptions& o, const Bank& k, const Noise& n,
                                  const RiverTileLayout& L, Rng* rng) {
  const double len = o.reach_length_m;
  std::vector<TreeSpec> bushes;
  const int count = static_cast<int>(std::round(o.vegetation_density * len / 6.0));
  for (int side : {1, -1})
    for (int i = 0; i < count; ++i) {
      const double x = rng->uniform(L.x0_m, L.x1_m);
      const double s = rng->uniform(0.5, std::max(1.0, o.tree_line_distance_m));
      TreeSpec t;
      t.height_m = rng->uniform(1.5, 3.5);
      t.crown_radius_m = t.height_m * rng->uniform(0.5, 0.8);
      const double y = side * (k.b + s);
      if (L.bridge && std::abs(x - L.bridge_x_m) < L.bridge_half_width_m + 3.0) continue;
      if (L.quay && side > 0 && x > L.quay_x0_m - 3.0 && x < L.quay_x1_m + 3.0) continue;
      if (inside_any(L.buildings, x, y, 1.0)) continue;
      t.base_W = Vec3(x, y, terrain_z(k, n, x, s, side));
      bushes.push_back(t);
    }
  return bushes;
}

// The trees of earlier rounds: a 6-sided trunk under a lumpy ellipsoid (tree_model: ellipsoid).
void add_ellipsoid_trees(sim::SceneGeometry* g, const RiverTileLayout& L, const Textures& tex,
                         Rng* lumps) {
  MeshBuilder trunks(tile_name(L.index, "tree_trunks"), solid(tex.bark, 0.7f));
  MeshBuilder crowns(tile_name(L.index, "tree_crowns"), solid(tex.foliage, 0.8f));
  for (const TreeSpec& t : L.trees) {
    const double z_crown_centre = t.base_W.z() - (1.0 - kCrownAxisFrac) * t.height_m;
    trunks.prism(t.base_W + Vec3(0, 0, 0.3), Vec3(t.base_W.x(), t.base_W.y(), z_crown_centre),
                 t.trunk_radius_m, 6, 1.5);
    add_crown(&crowns, t, kCrownAxisFrac, lumps);
  }
  add_mesh(g, trunks.take());
  add_mesh(g, crowns.take());
}

// Whether a tree keeps the boats' water clear: nothing nearer the centre line than
// b - min(2 m, b / 5), nothing over the water lower than 1.5 m above it.
bool clear_of_the_water(const sim::Mesh& m, const Bank& k) {
  const double nearest = k.b - std::min(2.0, 0.2 * k.b);
  for (const sim::Vertex& v : m.vertices) {
    const double y = std::abs(static_cast<double>(v.y));
    if (y < nearest || (y < k.b && v.z > -1.5)) return false;
  }
  return true;
}

// One skeleton tree's wood and leaves, its lean halved until it keeps the water clear (at no
// lean it stands as planted).
std::pair<sim::Mesh, sim::Mesh> grow_and_dress(const TreeSpec& t, const Bank& k,
                                               const Textures& tex, int cards) {
  TreeForm f{t.base_W,  t.height_m, t.crown_radius_m, t.trunk_radius_m,
             t.species, t.lod,      t.lean_dir_W,     t.lean_rad};
  const int leaves_tex =
      leaf_shape_of(t.species) == LeafShape::kBroad ? tex.leaves_broad : tex.leaves_narrow;
  for (int attempt = 0;; ++attempt) {
    Rng rng(t.form_seed);
    MeshBuilder wood("wood", solid(tex.bark, 0.7f)), leaves("leaves", material(leaves_tex, 0.8f));
    dress_tree(f, grow_tree(f, &rng), cards, &rng, &wood, &leaves);
    sim::Mesh w = wood.take(), l = leaves.take();
    if (f.lean_rad == 0 || (clear_of_the_water(w, k) && clear_of_the_water(l, k)))
      return {std::move(w), std::move(l)};
    f.lean_rad = attempt < 3 ? 0.5 * f.lean_rad : 0.0;
  }
}

// A bush as a skeleton (willow or alder scrub branching low), from a stream of its own.
TreeSpec scrub(const TreeSpec& bush, std::uint64_t seed, int tile, std::size_t i) {
  Rng r = RngStreams(seed).stream(fmt::format("scene.river.tile.{}.bush.{}", tile, i));
  TreeSpec t = bush;
  t.species = r.uniform() < 0.6 ? TreeSpecies::kWillow : TreeSpecies::kAlder;
  t.trunk_radius_m = 0.03 + 0.01 * t.height_m;
  t.lod = 0;
  t.lean_rad = 0;
  t.form_seed = r.next_u64();
  return t;
}

// Skeleton trees (scenes/trees.hpp) and scrub, gathered per bank and per 50 m of river into one
// wood and one leaf mesh per leaf shape: the renderer culls them by those chunks.
void add_skeleton_trees(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k,
                        const Textures& tex, const RiverReachOptions& o, std::uint64_t seed) {
  constexpr double kChunk_m = 50.0;
  std::map<std::tuple<int, long long, int>, sim::Mesh> chunks;  // side, chunk, part
  const auto chunk = [&](const TreeSpec& t, int part, const sim::Mesh& m) -> sim::Mesh& {
    const int side = t.base_W.y() > 0 ? 1 : -1;
    const auto c = static_cast<long long>(std::floor(t.base_W.x() / kChunk_m));
    const auto [it, fresh] = chunks.try_emplace({side, c, part});
    if (fresh) {
      static constexpr std::array<const char*, 6> kPart{
          "tree_wood",   "tree_leaves_broad",   "tree_leaves_narrow",
          "bushes_wood", "bushes_leaves_broad", "bushes_leaves_narrow"};
      it->second.name = fmt::format("tile{}.{}_{}{}", L.index,
                                    kPart[static_cast<std::size_t>(part)], side > 0 ? "e" : "w", c);
      it->second.material = m.material;
    }
    return it->second;
  };
  const auto add = [&](const TreeSpec& t, int cards, int first_part) {
    auto [wood, leaves] = grow_and_dress(t, k, tex, cards);
    set_plant_sway(&wood, t.base_W, t.height_m, 0.f);
    set_plant_sway(&leaves, t.base_W, t.height_m, 1.f);
    append_mesh(&chunk(t, first_part, wood), wood, Vec3::Zero());
    const int part = first_part + (leaf_shape_of(t.species) == LeafShape::kBroad ? 1 : 2);
    append_mesh(&chunk(t, part, leaves), leaves, Vec3::Zero());
  };
  for (const TreeSpec& t : L.trees) add(t, o.leaf_cards_per_tree, 0);
  for (std::size_t i = 0; i < L.bushes.size(); ++i)
    add(scrub(L.bushes[i], seed, L.index, i), std::max(8, o.leaf_cards_per_tree / 3), 3);
  for (auto& [key, m] : chunks) add_mesh(g, std::move(m));
}

}  // namespace

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
