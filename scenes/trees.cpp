#include "scenes/trees.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Geometry>

#include "core/error.hpp"
#include "sim/physics/wind/gusts.hpp"

namespace driftlab::scenes {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
constexpr double kMaxElevation = 89 * kDeg;  // stems never point straight up or down
constexpr double kBarkRepeat_m = 1.5;        // one bark texture repeat per 1.5 m of circumference

// Starting values in the spirit of Weber & Penn's (1995) tables (shape, base size, counts,
// down/rotate angles, curve, attraction up), set per species from the trees design, section 1.
// name, shape, base, n1 {near, mid}, nLength1, lengthV1, down1 +- V, rotate +- V, curve1 +- V,
// attractionUp, n2, nLength2, lengthV2, down2 +- V, curve2, leaf, card edge / height.
constexpr SpeciesParams kSpecies[] = {
    {"alder", 0,  0.20, {9, 5}, 0.45, 0.15, 60, 10, 137.5, 15,
     0,       10, 0.1,  3,      0.35, 0.2,  45, 15, 0,     LeafShape::kBroad,
     0.135},
    {"willow", 2,  0.35, {7, 4}, 0.60, 0.15, 35, 15, 137.5, 20,
     -30,      15, -0.2, 3,      0.40, 0.2,  40, 15, -30,   LeafShape::kNarrow,
     0.15},
    {"weeping_willow",
     1,
     0.30,
     {7, 4},
     0.60,
     0.15,
     40,
     10,
     137.5,
     20,
     -110,
     20,
     -0.6,
     3,
     0.50,
     0.2,
     30,
     10,
     -110,
     LeafShape::kNarrow,
     0.15},
    {"poplar", 5,  0.25, {10, 6}, 0.40, 0.15, 35, 10, 137.5, 15,
     10,       10, 0.3,  2,       0.30, 0.2,  35, 10, 10,    LeafShape::kBroad,
     0.12},
};

Vec3 direction(double azimuth, double elevation) {  // elevation above the horizon (NED: -z up)
  return {std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
          -std::sin(elevation)};
}
double elevation_of(const Vec3& d) { return std::asin(std::clamp(-d.z(), -1.0, 1.0)); }
double azimuth_of(const Vec3& d) { return std::atan2(d.y(), d.x()); }

Vec3 perpendicular(const Vec3& w) {
  return (std::abs(w.z()) < 0.9 ? w.cross(Vec3::UnitZ()) : w.cross(Vec3::UnitX())).normalized();
}

// The unit direction d turned by `down` away from itself towards azimuth phi about it.
Vec3 branch_off(const Vec3& d, double down, double phi) {
  const Vec3 e1 = perpendicular(d), e2 = d.cross(e1);
  return (std::cos(down) * d + std::sin(down) * (std::cos(phi) * e1 + std::sin(phi) * e2))
      .normalized();
}

// Point and radius of a stem at t (a fraction of its polyline by point index).
template <typename T>
T at_t(const std::vector<T>& v, double t) {
  const double f = std::clamp(t, 0.0, 1.0) * static_cast<double>(v.size() - 1);
  const std::size_t k = std::min(v.size() - 2, static_cast<std::size_t>(f));
  return v[k] + (v[k + 1] - v[k]) * (f - static_cast<double>(k));
}

// What the random draws decide; positions follow from it and the length scale.
struct TwigPlan {
  double fork_t;
  Vec3 dir;
  double length;  // unscaled [m]
};
struct LimbPlan {
  double fork_t;
  std::vector<Vec3> dirs;  // one per segment
  double length;           // unscaled [m]
  std::vector<TwigPlan> twigs;
};

double draw_angle(Rng* rng, double mean_deg, double var_deg) {
  return (mean_deg + var_deg * rng->uniform(-1, 1)) * kDeg;
}

// Limbs (Weber & Penn level 1): forks spread evenly above base_size, azimuth stepping by about
// the rotate angle, length by ShapeRatio, direction bent by curve and attraction per segment.
std::vector<LimbPlan> plan_limbs(const TreeForm& f, const Vec3& trunk_dir, double l0, Rng* rng) {
  const SpeciesParams& sp = species_params(f.species);
  const int n1 = limb_count(f.species, f.lod), nseg = f.lod == 0 ? 3 : 2;
  std::vector<LimbPlan> limbs(n1);
  double phi = rng->uniform(0, 2 * kPi);
  for (int i = 0; i < n1; ++i) {
    LimbPlan& p = limbs[i];
    p.fork_t = sp.base_size + (1 - sp.base_size) * 0.95 * (i + rng->uniform(0.15, 0.85)) / n1;
    if (i > 0) phi += draw_angle(rng, sp.rotate, sp.rotate_v);
    const Vec3 d0 = branch_off(trunk_dir, draw_angle(rng, sp.down1, sp.down_v1), phi);
    const double r = (1 - p.fork_t) / (1 - sp.base_size);
    p.length = sp.n_length1 * l0 * shape_ratio(sp.shape, r) *
               rng->uniform(1 - sp.length_v1, 1 + sp.length_v1);
    const double az = azimuth_of(d0);
    double el = elevation_of(d0);
    p.dirs.push_back(d0);
    for (int j = 1; j < nseg; ++j) {
      el += (draw_angle(rng, sp.curve1, sp.curve_v1) + sp.attraction_up * (kPi / 2 - el)) /
            (nseg - 1);
      el = std::clamp(el, -kMaxElevation, kMaxElevation);
      p.dirs.push_back(direction(az, el));
    }
  }
  return limbs;
}

// Twigs (level 2, near LOD only): round(n2 (0.2 + 0.8 L1 / L1max)) per limb along [0.25, 0.95].
void plan_twigs(const TreeForm& f, std::vector<LimbPlan>* limbs, Rng* rng) {
  const SpeciesParams& sp = species_params(f.species);
  double longest = 0;
  for (const auto& l : *limbs) longest = std::max(longest, l.length);
  for (auto& l : *limbs) {
    const int m = twig_count(f.species, f.lod, l.length / longest);
    double psi = rng->uniform(0, 2 * kPi);
    for (int j = 0; j < m; ++j) {
      TwigPlan tw;
      tw.fork_t = 0.25 + 0.7 * (j + rng->uniform(0.2, 0.8)) / m;
      if (j > 0) psi += draw_angle(rng, sp.rotate, sp.rotate_v);
      const double down = draw_angle(rng, sp.down2, sp.down_v2);
      tw.length = sp.n_length2 * l.length * (1 - 0.6 * tw.fork_t) *
                  rng->uniform(1 - sp.length_v2, 1 + sp.length_v2);
      const std::size_t seg =
          std::min(l.dirs.size() - 1, static_cast<std::size_t>(tw.fork_t * l.dirs.size()));
      const Vec3 d = branch_off(l.dirs[seg], down, psi);
      // One segment: its direction is the bent twig's mean (half the curve and attraction).
      double el = elevation_of(d);
      el += 0.5 * (sp.curve2 * kDeg + sp.attraction_up * (kPi / 2 - el));
      tw.dir = direction(azimuth_of(d), std::clamp(el, -kMaxElevation, kMaxElevation));
      l.twigs.push_back(tw);
    }
  }
}

// The skeleton for a length scale k: trunk, limbs, then twigs; no point above the top.
TreeSkeleton realise(const TreeForm& f, const Vec3& top_W, double l0,
                     const std::vector<LimbPlan>& limbs, double k) {
  TreeSkeleton s;
  s.top_W = top_W;
  s.length_scale = k;
  Stem trunk;
  const int tseg = f.lod == 0 ? 5 : 3;
  for (int i = 0; i <= tseg; ++i) {
    trunk.points.push_back(i == tseg ? top_W : Vec3(f.base_W + (top_W - f.base_W) * i / tseg));
    trunk.radii.push_back(f.trunk_radius_m * (tseg - i) / tseg);
  }
  trunk.length_m = l0;
  s.stems.push_back(trunk);
  std::vector<Stem> twigs;
  for (std::size_t i = 0; i < limbs.size(); ++i) {
    const LimbPlan& p = limbs[i];
    Stem limb{{at_t(s.stems[0].points, p.fork_t)}, {}, 1, 0, p.fork_t, k * p.length};
    const double parent_r = at_t(s.stems[0].radii, p.fork_t);
    const double r0 =
        std::min(0.5 * f.trunk_radius_m * std::sqrt(limb.length_m / l0), 0.8 * parent_r);
    const int nseg = static_cast<int>(p.dirs.size());
    for (int j = 0; j < nseg; ++j)
      limb.points.push_back(limb.points.back() + limb.length_m / nseg * p.dirs[j]);
    for (int j = 0; j <= nseg; ++j) limb.radii.push_back(r0 * (nseg - j) / nseg);
    for (const TwigPlan& tw : p.twigs) {
      const Vec3 fork = at_t(limb.points, tw.fork_t);
      const double r = 0.6 * at_t(limb.radii, tw.fork_t);
      twigs.push_back({{fork, fork + k * tw.length * tw.dir},
                       {r, 0.0},
                       2,
                       static_cast<int>(i) + 1,
                       tw.fork_t,
                       k * tw.length});
    }
    s.stems.push_back(limb);
  }
  s.stems.insert(s.stems.end(), twigs.begin(), twigs.end());
  // Nothing above the top (Weber & Penn's pruning envelope, reduced to the apex height): a point
  // higher than top_W.z + its radius (so its ring stays below the apex too) slides down parallel
  // to the trunk's axis, which keeps its horizontal offset from the axis.
  const Vec3 axis = (top_W - f.base_W) / f.height_m;  // per metre of height (z: -1)
  for (Stem& st : s.stems)
    for (std::size_t i = 0; i < st.points.size(); ++i) {
      const double dz = top_W.z() + st.radii[i] - st.points[i].z();
      if (dz > 0) st.points[i] -= axis * dz;
    }
  // Spread: horizontal distance from the trunk's axis at each point's height.
  for (const Stem& st : s.stems)
    for (const Vec3& q : st.points) {
      const Vec3 on_axis = f.base_W + axis * (f.base_W.z() - q.z());
      s.spread_m = std::max(s.spread_m, (q - on_axis).head<2>().norm());
    }
  return s;
}

}  // namespace

const SpeciesParams& species_params(TreeSpecies species) {
  return kSpecies[static_cast<int>(species)];
}

LeafShape leaf_shape_of(TreeSpecies species) { return species_params(species).leaf; }

double shape_ratio(int shape, double r) {
  switch (shape) {
    case 0:
      return 0.2 + 0.8 * r;
    case 1:
      return 0.2 + 0.8 * std::sin(kPi * r);
    case 2:
      return 0.2 + 0.8 * std::sin(0.5 * kPi * r);
    case 3:
      return 1.0;
    case 4:
      return 0.5 + 0.5 * r;
    case 5:
      return r <= 0.7 ? r / 0.7 : (1 - r) / 0.3;
    case 6:
      return 1 - 0.8 * r;
    case 7:
      return r <= 0.7 ? 0.5 + 0.5 * r / 0.7 : 0.5 + 0.5 * (1 - r) / 0.3;
    default:
      DRIFTLAB_DEMAND_MSG(false, "unknown Weber & Penn shape");
      return 0;
  }
}

int limb_count(TreeSpecies species, int lod) {
  DRIFTLAB_DEMAND_MSG(lod == 0 || lod == 1, "tree lod must be 0 or 1");
  return species_params(species).n1[lod];
}

int twig_count(TreeSpecies species, int lod, double length_ratio) {
  if (lod != 0) return 0;
  return static_cast<int>(std::lround(species_params(species).n2 * (0.2 + 0.8 * length_ratio)));
}

TreeSkeleton grow_tree(const TreeForm& f, Rng* rng) {
  DRIFTLAB_DEMAND_MSG(f.height_m > 0 && f.crown_radius_m > 0 && f.trunk_radius_m > 0,
                      "a tree needs a positive height, crown radius and trunk radius");
  DRIFTLAB_DEMAND_MSG(f.lean_rad >= 0 && f.lean_rad < 1.2, "tree lean must be in [0, 1.2) rad");
  Vec3 lean_dir = f.lean_dir_W;
  lean_dir.z() = 0;
  lean_dir = lean_dir.norm() > 0 ? Vec3(lean_dir.normalized()) : Vec3(Vec3::UnitX());
  // The trunk is h / cos(lean) long, so its top is exactly h above the base.
  const double l0 = f.height_m / std::cos(f.lean_rad);
  const Vec3 top_W(f.base_W.x() + f.height_m * std::tan(f.lean_rad) * lean_dir.x(),
                   f.base_W.y() + f.height_m * std::tan(f.lean_rad) * lean_dir.y(),
                   f.base_W.z() - f.height_m);
  const Vec3 trunk_dir = (top_W - f.base_W).normalized();
  std::vector<LimbPlan> limbs = plan_limbs(f, trunk_dir, l0, rng);
  plan_twigs(f, &limbs, rng);
  // Lengths scaled once so the spread is crown_radius_m: every point off the axis lies on a
  // limb from the axis, so horizontal offsets scale with k and clamping z leaves them alone.
  const double spread1 = realise(f, top_W, l0, limbs, 1.0).spread_m;
  DRIFTLAB_DEMAND_MSG(spread1 > 0, "tree without spread");
  return realise(f, top_W, l0, limbs, f.crown_radius_m / spread1);
}

int tree_triangle_count(const TreeSkeleton& s, int lod, int cards) {
  int n = 0;
  for (const Stem& st : s.stems)
    n += st.level == 0 ? (lod == 0 ? 54 : 25) : st.level == 1 ? (lod == 0 ? 20 : 9) : 0;
  return n + 2 * card_count(cards, lod);
}

namespace {

struct Card {
  Vec3 centre, axis_u, axis_v, normal;
  double out_m;  // distance from the crown's centre
};

// Cards per limb: `n` split by limb length with largest remainders (ties to the earlier limb).
std::vector<int> split_by_length(const std::vector<double>& lengths, int n) {
  double total = 0;
  for (double l : lengths) total += l;
  std::vector<int> out(lengths.size());
  std::vector<std::pair<double, std::size_t>> rest;
  int given = 0;
  for (std::size_t i = 0; i < lengths.size(); ++i) {
    const double q = n * lengths[i] / total;
    out[i] = static_cast<int>(std::floor(q));
    given += out[i];
    rest.push_back({q - out[i], i});
  }
  std::stable_sort(rest.begin(), rest.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  for (int k = 0; given < n; ++k, ++given) ++out[rest[k % rest.size()].second];
  return out;
}

// One card at `at` (draws: edge, jitter, normal noise, roll or hang).
Card make_card(const TreeForm& f, const Vec3& at, const Vec3& crown_c, const Vec3& top_W,
               Rng* rng) {
  const SpeciesParams& sp = species_params(f.species);
  const double edge = sp.card_edge_over_height * f.height_m * rng->uniform(0.85, 1.15) *
                      (f.lod == 0 ? 1.0 : std::sqrt(2.0));
  Vec3 jitter(rng->normal(), rng->normal(), rng->normal());
  jitter = jitter.norm() > 1e-12 ? Vec3(jitter.normalized()) : Vec3(Vec3::UnitX());
  Card c;
  c.centre = at + rng->uniform(0, 0.5 * edge) * jitter;
  const Vec3 out = c.centre - crown_c;
  const Vec3 r_hat = out.norm() > 1e-9 ? Vec3(out.normalized()) : Vec3(-Vec3::UnitZ());
  const Vec3 noise(rng->normal(), rng->normal(), rng->normal());
  Vec3 n = r_hat + 0.6 * noise;
  n = n.norm() > 1e-9 ? Vec3(n.normalized()) : r_hat;
  Vec3 u, v;
  if (sp.leaf == LeafShape::kNarrow) {  // willows: the card hangs, v within 20 deg of down
    const double tilt = rng->uniform(0, 20 * kDeg), az = rng->uniform(0, 2 * kPi);
    v = std::cos(tilt) * Vec3::UnitZ() + std::sin(tilt) * Vec3(std::cos(az), std::sin(az), 0);
    n -= n.dot(v) * v;
    n = n.norm() > 1e-6 ? Vec3(n.normalized()) : perpendicular(v);
    u = v.cross(n);
  } else {
    const double roll = rng->uniform(0, 2 * kPi);
    const Vec3 a = perpendicular(n);
    u = std::cos(roll) * a + std::sin(roll) * n.cross(a);
    v = n.cross(u);
  }
  Vec3 face = u.cross(v);
  if (face.dot(r_hat) < 0) face = -face;
  c.normal = (r_hat + 0.5 * face).normalized();
  c.axis_u = 0.5 * edge * u;
  c.axis_v = 0.5 * edge * v;
  // Nothing above the tree's top: lower the card until its highest corner is at top_W.
  const double high_z = c.centre.z() - std::abs(c.axis_u.z()) - std::abs(c.axis_v.z());
  if (high_z < top_W.z()) c.centre.z() += top_W.z() - high_z;
  c.out_m = (c.centre - crown_c).norm();
  return c;
}

}  // namespace

void dress_tree(const TreeForm& f, const TreeSkeleton& s, int cards, Rng* rng, MeshBuilder* wood,
                MeshBuilder* leaves) {
  DRIFTLAB_DEMAND_MSG(!s.stems.empty() && cards >= 0, "dress_tree needs a skeleton");
  // Twigs carry cards but are not drawn as wood: the leaf-cluster texture draws them, and
  // tubes a centimetre or two thick are a tenth of a pixel from the water, where a rasteriser
  // without anti-aliasing turns them into dotted lines that flicker from frame to frame.
  for (const Stem& st : s.stems) {
    if (st.level >= 2) continue;
    const int sides = st.level == 0 ? (f.lod == 0 ? 6 : 5) : (f.lod == 0 ? 4 : 3);
    wood->tube(st.points, st.radii, sides, kBarkRepeat_m);
  }
  // The crown's centre: the mean of the limbs' and twigs' points.
  Vec3 crown_c = Vec3::Zero();
  int n_pts = 0;
  std::vector<int> limbs;
  std::vector<double> lengths;
  for (std::size_t i = 0; i < s.stems.size(); ++i) {
    if (s.stems[i].level == 0) continue;
    for (const Vec3& q : s.stems[i].points) crown_c += q, ++n_pts;
    if (s.stems[i].level == 1)
      limbs.push_back(static_cast<int>(i)), lengths.push_back(s.stems[i].length_m);
  }
  crown_c = n_pts > 0 ? Vec3(crown_c / n_pts) : Vec3(at_t(s.stems[0].points, 0.7));
  const int total = card_count(cards, f.lod);
  const int n_top = limbs.empty() ? total : static_cast<int>(std::lround(0.1 * total));
  std::vector<Card> out;
  for (int k = 0; k < n_top; ++k)  // around the leader's top
    out.push_back(
        make_card(f, at_t(s.stems[0].points, rng->uniform(0.85, 1.0)), crown_c, s.top_W, rng));
  if (!limbs.empty()) {
    const std::vector<int> per_limb = split_by_length(lengths, total - n_top);
    for (std::size_t i = 0; i < limbs.size(); ++i) {
      std::vector<int> hosts{limbs[i]};  // the limb's end and its twigs
      for (std::size_t j = 0; j < s.stems.size(); ++j)
        if (s.stems[j].level == 2 && s.stems[j].parent == limbs[i])
          hosts.push_back(static_cast<int>(j));
      for (int k = 0; k < per_limb[i]; ++k) {
        const Stem& h = s.stems[hosts[rng->uniform_int(hosts.size())]];
        out.push_back(make_card(f, at_t(h.points, rng->uniform(0.3, 1.0)), crown_c, s.top_W, rng));
      }
    }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const Card& a, const Card& b) { return a.out_m > b.out_m; });
  for (const Card& c : out) leaves->card(c.centre, c.axis_u, c.axis_v, c.normal);
}

void set_plant_sway(sim::Mesh* mesh, const Vec3& base_W, double height_m, float flutter) {
  mesh->sway.resize(mesh->vertices.size());
  const double scale = height_m / sim::kReferenceTreeHeight_m;
  for (std::size_t i = 0; i < mesh->vertices.size(); ++i) {
    const double h = std::clamp((base_W.z() - mesh->vertices[i].z) / height_m, 0.0, 1.0);
    mesh->sway[i] = {static_cast<float>(scale * h * h), flutter};
  }
}

}  // namespace driftlab::scenes
