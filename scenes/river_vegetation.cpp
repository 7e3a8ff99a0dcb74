#include "scenes/river_reach_parts.hpp"

namespace driftlab::scenes::river {

// ---------------------------------------------------------------------------
// Trees: a 6-sided trunk and a lumpy ellipsoidal crown.

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

}  // namespace driftlab::scenes::river
