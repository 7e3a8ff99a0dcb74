#include "scenes/river_reach_parts.hpp"

namespace driftlab::scenes::river {

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

}  // namespace driftlab::scenes::river
