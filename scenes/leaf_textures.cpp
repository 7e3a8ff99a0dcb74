#include "scenes/leaf_textures.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <numbers>
#include <vector>

#include <Eigen/Core>

#include <fmt/format.h>

#include "core/error.hpp"

namespace driftlab::scenes {

namespace {

using Vec2 = Eigen::Vector2d;
constexpr int kSub = 4;               // subsamples per texel edge (4 x 4 supersampling)
constexpr int kBorderPx = 2;          // fully transparent border
constexpr double kTwigGrey = 0.40;    // relative to a mean leaf
constexpr double kMidribGrey = 0.72;  // factor on the leaf's grey
constexpr double kDeg = std::numbers::pi / 180.0;

// alpha = 255 x (share of the 16 subsamples inside), rounded.
std::uint8_t alpha_of(int count) {
  return static_cast<std::uint8_t>((255 * count + kSub * kSub / 2) / (kSub * kSub));
}

// The image at subsample resolution, painted in order (later shapes cover earlier ones).
struct Canvas {
  explicit Canvas(int size_px)
      : size(size_px),
        n(size_px * kSub),
        grey(static_cast<std::size_t>(n) * n, 0.f),
        inside(static_cast<std::size_t>(n) * n, 0),
        count(static_cast<std::size_t>(size_px) * size_px, 0) {}
  int size, n;
  std::vector<float> grey;           // relative grey per subsample (where inside)
  std::vector<std::uint8_t> inside;  // per subsample
  std::vector<std::uint8_t> count;   // inside subsamples per texel
  long opaque = 0;                   // texels with alpha >= kAlphaOpaqueFrom

  // Visits the subsamples within [lo, hi] (pixels) that lie inside the border: f(index, point).
  template <typename F>
  void for_each(const Vec2& lo, const Vec2& hi, F&& f) const {
    const int a = kBorderPx * kSub, b = (size - kBorderPx) * kSub;
    const int x0 = std::max(a, static_cast<int>(std::floor(lo.x() * kSub)));
    const int y0 = std::max(a, static_cast<int>(std::floor(lo.y() * kSub)));
    const int x1 = std::min(b, static_cast<int>(std::ceil(hi.x() * kSub)) + 1);
    const int y1 = std::min(b, static_cast<int>(std::ceil(hi.y() * kSub)) + 1);
    for (int sy = y0; sy < y1; ++sy)
      for (int sx = x0; sx < x1; ++sx)
        f(static_cast<std::size_t>(sy) * n + sx, Vec2((sx + 0.5) / kSub, (sy + 0.5) / kSub));
  }
};

// A shape: its bounding box and, for a point, its relative grey (< 0 outside).
struct Shape {
  Vec2 lo = Vec2::Zero(), hi = Vec2::Zero();
  // Capsule (twig, petiole) or leaf.
  bool leaf = false;
  Vec2 a = Vec2::Zero(), b = Vec2::Zero();  // capsule: segment; leaf: base (b unused)
  double radius = 0;                        // capsule
  Vec2 dir = Vec2::UnitX();                 // leaf: unit direction base -> tip
  double length = 0, width = 0, widest = 0.4, grey = 1;
  LeafShape kind = LeafShape::kBroad;

  double grey_at(const Vec2& p) const {
    if (!leaf) {
      const Vec2 ab = b - a;
      const double t = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
      return (p - (a + t * ab)).norm() <= radius ? grey : -1;
    }
    const Vec2 q = p - a;
    const double x = q.dot(dir), y = q.x() * dir.y() - q.y() * dir.x();
    const double s = x / length;
    if (s < 0 || s > 1) return -1;
    // Half-width: an egg (two half-ellipses meeting at `widest`) for ovate leaves, a pointed
    // profile (two parabolas) for lanceolate ones.
    const double d = (s - widest) / (s < widest ? widest : 1 - widest);
    const double hw =
        0.5 * width * (kind == LeafShape::kBroad ? std::sqrt(std::max(0.0, 1 - d * d)) : 1 - d * d);
    if (std::abs(y) > hw) return -1;
    const double g = grey * (0.94 + 0.12 * s);  // slightly lighter towards the tip
    return std::abs(y) < 0.6 * width / 16 + 0.35 && s < 0.92 ? g * kMidribGrey : g;
  }
};

Shape capsule(const Vec2& a, const Vec2& b, double radius, double grey) {
  Shape s;
  s.a = a;
  s.b = b;
  s.radius = radius;
  s.grey = grey;
  s.lo = a.cwiseMin(b).array() - radius;
  s.hi = a.cwiseMax(b).array() + radius;
  return s;
}

// Subsamples the shape would newly cover.
long gain(const Canvas& c, const Shape& s) {
  long g = 0;
  c.for_each(s.lo, s.hi, [&](std::size_t i, const Vec2& p) {
    if (!c.inside[i] && s.grey_at(p) >= 0) ++g;
  });
  return g;
}

void paint(Canvas* c, const Shape& s) {
  c->for_each(s.lo, s.hi, [&](std::size_t i, const Vec2& p) {
    const double g = s.grey_at(p);
    if (g < 0) return;
    c->grey[i] = static_cast<float>(g);
    if (c->inside[i]) return;
    c->inside[i] = 1;
    const std::size_t sy = i / c->n, sx = i % c->n;
    const std::size_t texel = (sy / kSub) * c->size + sx / kSub;
    const bool was = alpha_of(c->count[texel]) >= sim::kAlphaOpaqueFrom;
    ++c->count[texel];
    if (!was && alpha_of(c->count[texel]) >= sim::kAlphaOpaqueFrom) ++c->opaque;
  });
}

struct Segment {
  Vec2 a, b;
};

// The twig: a main stem from the bottom edge to the top with slight bends, and 4-7 side twigs
// alternating left and right. Painted on `c`; returns the segments leaves attach to.
std::vector<Segment> draw_twigs(Canvas* c, Rng* rng, double scale) {
  const double size = c->size;
  std::vector<Segment> segs;
  std::array<Vec2, 4> main;
  main[0] = {size * rng->uniform(0.4, 0.6), size * 0.98};
  main[3] = {size * rng->uniform(0.4, 0.6), size * 0.04};
  for (int k = 1; k < 3; ++k)
    main[k] = main[0] + (main[3] - main[0]) * (k / 3.0) + Vec2(size * rng->uniform(-0.05, 0.05), 0);
  for (int k = 0; k < 3; ++k) {
    segs.push_back({main[k], main[k + 1]});
    paint(c, capsule(main[k], main[k + 1], 1.5 * scale, kTwigGrey));
  }
  const int sides = 4 + static_cast<int>(rng->uniform_int(4));
  double side = rng->uniform_int(2) ? 1 : -1;
  for (int j = 0; j < sides; ++j) {
    const double t = 0.12 + 0.8 * (j + rng->uniform(0.2, 0.8)) / sides;  // along the main stem
    const double seg_f = t * 3;
    const int k = std::min(2, static_cast<int>(seg_f));
    const Vec2 from = main[k] + (main[k + 1] - main[k]) * (seg_f - k);
    const Vec2 d = (main[k + 1] - main[k]).normalized();
    const double ang = side * rng->uniform(35, 60) * kDeg;
    const Vec2 dir(std::cos(ang) * d.x() - std::sin(ang) * d.y(),
                   std::sin(ang) * d.x() + std::cos(ang) * d.y());
    const Vec2 to = from + size * rng->uniform(0.25, 0.42) * dir;
    segs.push_back({from, to});
    paint(c, capsule(from, to, 1.0 * scale, kTwigGrey));
    side = -side;
  }
  return segs;
}

// One candidate leaf on the twig network: attachment point, petiole and leaf.
struct LeafDraw {
  Shape petiole, leaf;
};

LeafDraw draw_leaf(const std::vector<Segment>& segs, LeafShape kind, double contrast,
                   double petiole_max, double scale, Rng* rng) {
  double total = 0;
  for (const auto& s : segs) total += (s.b - s.a).norm();
  double u = rng->uniform(0, total);
  std::size_t k = 0;
  for (; k + 1 < segs.size(); ++k) {
    const double len = (segs[k].b - segs[k].a).norm();
    if (u <= len) break;
    u -= len;
  }
  const Vec2 d = (segs[k].b - segs[k].a).normalized();
  const Vec2 at = segs[k].a + std::min(u, (segs[k].b - segs[k].a).norm()) * d;
  const double ang = (rng->uniform_int(2) ? 1 : -1) * rng->uniform(25, 70) * kDeg;
  const Vec2 dir(std::cos(ang) * d.x() - std::sin(ang) * d.y(),
                 std::sin(ang) * d.x() + std::cos(ang) * d.y());
  Shape leaf;
  leaf.leaf = true;
  leaf.kind = kind;
  const bool broad = kind == LeafShape::kBroad;
  leaf.length = scale * (broad ? rng->uniform(18, 24) : rng->uniform(26, 36));
  leaf.width = scale * (broad ? rng->uniform(14, 18) : rng->uniform(4, 6));
  leaf.widest = broad ? 0.4 : 0.3;
  leaf.grey = std::max(0.2, 1 + contrast * rng->normal());
  const double petiole = rng->uniform(1.0 * scale, petiole_max);
  leaf.a = at + petiole * dir;
  leaf.dir = dir;
  const Vec2 tip = leaf.a + leaf.length * dir;
  leaf.lo = leaf.a.cwiseMin(tip).array() - 0.5 * leaf.width;
  leaf.hi = leaf.a.cwiseMax(tip).array() + 0.5 * leaf.width;
  return {capsule(at, leaf.a, 0.6 * scale, kTwigGrey), leaf};
}

// Transparent texels take the grey of the nearest opaque texel: a breadth-first search from
// all opaque texels (raster order, 8 neighbours in a fixed order).
void dilate_grey(const std::vector<std::uint8_t>& alpha, int size, std::vector<std::uint8_t>* px) {
  std::vector<std::uint8_t> done(alpha.size(), 0);
  std::deque<int> queue;
  for (int i = 0; i < static_cast<int>(alpha.size()); ++i)
    if (alpha[i] >= sim::kAlphaOpaqueFrom) {
      done[i] = 1;
      queue.push_back(i);
    }
  constexpr int kDx[8] = {-1, 0, 1, -1, 1, -1, 0, 1}, kDy[8] = {-1, -1, -1, 0, 0, 1, 1, 1};
  while (!queue.empty()) {
    const int i = queue.front();
    queue.pop_front();
    const int x = i % size, y = i / size;
    for (int k = 0; k < 8; ++k) {
      const int nx = x + kDx[k], ny = y + kDy[k];
      if (nx < 0 || ny < 0 || nx >= size || ny >= size) continue;
      const int j = ny * size + nx;
      if (done[j]) continue;
      done[j] = 1;
      (*px)[j] = (*px)[i];
      queue.push_back(j);
    }
  }
}

// The arguments every drawn cutout texture checks (`what` names it in the message), and the
// number of opaque texels its share of the texture is.
long checked_target(const char* what, int size_px, double mean_grey, double contrast,
                    double share) {
  DRIFTLAB_DEMAND_MSG(size_px >= 64 && size_px <= 4096,
                      fmt::format("{} size must be 64-4096 px", what));
  DRIFTLAB_DEMAND_MSG(mean_grey >= 0 && mean_grey <= 255 && contrast >= 0,
                      fmt::format("{} needs mean_grey in [0, 255] and contrast >= 0", what));
  return static_cast<long>(std::ceil(share * static_cast<double>(size_px) * size_px));
}

// A leaf-profiled shape from its base `a` along the unit `dir`, its bounding box set.
Shape leaf_shape(LeafShape kind, const Vec2& a, const Vec2& dir, double length, double width,
                 double widest, double grey) {
  Shape leaf;
  leaf.leaf = true;
  leaf.kind = kind;
  leaf.a = a;
  leaf.dir = dir;
  leaf.length = length;
  leaf.width = width;
  leaf.widest = widest;
  leaf.grey = grey;
  const Vec2 tip = a + length * dir;
  leaf.lo = a.cwiseMin(tip).array() - 0.5 * width;
  leaf.hi = a.cwiseMax(tip).array() + 0.5 * width;
  return leaf;
}

// The texture of a painted canvas: alpha from the subsamples, each texel's grey the mean of its
// inside subsamples scaled so that the opaque texels' mean is mean_grey, transparent texels
// dilated.
sim::Texture finish_texture(const Canvas& c, const char* name, double mean_grey) {
  const int size_px = c.size;
  const long texels = static_cast<long>(size_px) * size_px;
  sim::Texture t;
  t.name = name;
  t.width = t.height = size_px;
  t.pixels.assign(texels, 0);
  t.alpha.assign(texels, 0);
  // Texel grey: the mean of its inside subsamples; scaled so the opaque texels' mean is mean_grey.
  std::vector<double> g(texels, 0.0);
  double sum_opaque = 0;
  for (long i = 0; i < texels; ++i) {
    t.alpha[i] = alpha_of(c.count[i]);
    if (c.count[i] == 0) continue;
    const long x = i % size_px, y = i / size_px;
    for (int sy = 0; sy < kSub; ++sy)
      for (int sx = 0; sx < kSub; ++sx) {
        const std::size_t s = static_cast<std::size_t>(y * kSub + sy) * c.n + x * kSub + sx;
        if (c.inside[s]) g[i] += c.grey[s];
      }
    g[i] /= c.count[i];
    if (t.alpha[i] >= sim::kAlphaOpaqueFrom) sum_opaque += g[i];
  }
  const double gain_grey = mean_grey / (sum_opaque / static_cast<double>(c.opaque));
  for (long i = 0; i < texels; ++i)
    t.pixels[i] = static_cast<std::uint8_t>(std::clamp(std::lround(g[i] * gain_grey), 0L, 255L));
  dilate_grey(t.alpha, size_px, &t.pixels);
  return t;
}

}  // namespace

double leaf_target_coverage(LeafShape shape) { return shape == LeafShape::kBroad ? 0.60 : 0.50; }

sim::Texture make_leaf_cluster(LeafShape shape, Rng* rng, double mean_grey, double contrast,
                               int size_px) {
  const long target =
      checked_target("leaf cluster", size_px, mean_grey, contrast, leaf_target_coverage(shape));
  const double scale = size_px / 256.0;
  Canvas c(size_px);
  const std::vector<Segment> segs = draw_twigs(&c, rng, scale);
  // Greedy fill: of 4 candidate leaves the one covering most new area is drawn, so the leaves
  // spread into the gaps; the petioles grow longer when no candidate finds much room.
  double petiole_max = 4 * scale;
  const double leaf_area =
      (shape == LeafShape::kBroad ? 21 * 16 : 31 * 5) * 0.6 * scale * scale * kSub * kSub;
  for (int iter = 0; c.opaque < target; ++iter) {
    DRIFTLAB_DEMAND_MSG(iter < 100000, "leaf cluster did not reach its coverage");
    LeafDraw best;
    long best_gain = -1;
    for (int k = 0; k < 4; ++k) {
      LeafDraw cand = draw_leaf(segs, shape, contrast, petiole_max, scale, rng);
      const long g = gain(c, cand.leaf);
      if (g > best_gain) best_gain = g, best = cand;
    }
    if (best_gain < 0.3 * leaf_area) petiole_max = std::min(petiole_max + 2 * scale, size_px / 2.0);
    paint(&c, best.petiole);
    paint(&c, best.leaf);
  }
  return finish_texture(c, shape == LeafShape::kBroad ? "leaves_broad" : "leaves_narrow",
                        mean_grey);
}

double reed_target_coverage() { return 0.30; }

sim::Texture make_reed_clump(Rng* rng, double mean_grey, double contrast, int size_px) {
  const long target =
      checked_target("reed clump", size_px, mean_grey, contrast, reed_target_coverage());
  const double size = size_px, scale = size_px / 256.0;
  Canvas c(size_px);
  // Blades from a narrow foot at the bottom edge, fanning out up to 28 deg from the vertical,
  // widest at the foot and tapering to a point (Shape's lanceolate profile with its widest
  // point at the foot), until the opaque share reaches the target.
  for (int iter = 0; c.opaque < target; ++iter) {
    DRIFTLAB_DEMAND_MSG(iter < 100000, "reed clump did not reach its coverage");
    const Vec2 foot(size * rng->uniform(0.3, 0.7), size * 0.985);
    const double lean = rng->uniform(-28, 28) * kDeg;
    const double length = size * rng->uniform(0.45, 0.95), width = scale * rng->uniform(5, 9);
    const double grey = std::max(0.2, 1 + contrast * rng->normal());
    paint(&c, leaf_shape(LeafShape::kNarrow, foot, Vec2(std::sin(lean), -std::cos(lean)), length,
                         width, 0, grey));
  }
  return finish_texture(c, "reeds_clump", mean_grey);
}

double billboard_target_coverage() { return 0.35; }

sim::Texture make_tree_billboard(Rng* rng, double mean_grey, double contrast, int size_px) {
  const long target =
      checked_target("tree billboard", size_px, mean_grey, contrast, billboard_target_coverage());
  const double size = size_px, scale = size_px / 256.0;
  Canvas c(size_px);
  // A trunk from the bottom edge into the crown, then the crown: broad leaves at twice a near
  // cluster's size (a far tree's leaf clusters), scattered normally about the crown's
  // centre, the upper side lighter, until the opaque share reaches the target.
  const double cx = size * rng->uniform(0.45, 0.55);
  paint(&c, capsule(Vec2(cx, size * 0.985), Vec2(cx, size * 0.45), 4.0 * scale, kTwigGrey));
  const Vec2 centre(cx, size * rng->uniform(0.38, 0.42));
  const double sx = size * rng->uniform(0.10, 0.12), sy = size * rng->uniform(0.10, 0.12);
  for (int iter = 0; c.opaque < target; ++iter) {
    DRIFTLAB_DEMAND_MSG(iter < 100000, "tree billboard did not reach its coverage");
    const Vec2 at = centre + Vec2(sx * rng->normal(), sy * rng->normal());
    const double ang = rng->uniform(0.0, 2 * std::numbers::pi);
    const double length = 2 * scale * rng->uniform(18, 24);
    const double width = 2 * scale * rng->uniform(14, 18);
    const double up = std::clamp((centre.y() - at.y()) / (2 * sy), -1.0, 1.0);
    const double grey = std::max(0.2, 1 + 0.15 * up + contrast * rng->normal());
    paint(&c, leaf_shape(LeafShape::kBroad, at, Vec2(std::cos(ang), std::sin(ang)), length, width,
                         0.4, grey));
  }
  return finish_texture(c, "tree_billboard", mean_grey);
}

}  // namespace driftlab::scenes
