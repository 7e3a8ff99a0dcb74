#include "scenes/textures.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "scenes/noise.hpp"

namespace driftlab::scenes {

namespace {

// A float image in grey levels (0 .. 255 nominal); quantised once at the end so
// that contrast scaling does not compound rounding.
struct Canvas {
  int n = 0;  // edge length [px]
  std::vector<double> p;
  explicit Canvas(int size) : n(size), p(static_cast<std::size_t>(size) * size, 0.0) {}
  double& at(int x, int y) { return p[static_cast<std::size_t>(y) * n + x]; }

  // Evaluates f(u, v, x, y) at every pixel centre; (u, v) in [0, 1).
  template <class F>
  void fill(F&& f) {
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) at(x, y) = f((x + 0.5) / n, (y + 0.5) / n, x, y);
  }
};

double clamp(double x, double lo, double hi) { return x < lo ? lo : (x > hi ? hi : x); }

// Fractional part in [0, 1), also for negative x.
double fract(double x) { return x - std::floor(x); }

// Distance [px] from pixel coordinate `x` (in [0, n)) to the nearest multiple
// of `spacing` px, measured around the wrap so lines at 0 and n coincide.
double dist_to_grid(double x, double spacing) {
  const double f = fract(x / spacing) * spacing;
  return std::min(f, spacing - f);
}

sim::Texture finish(TextureKind kind, Canvas& c, double contrast, int variant) {
  // Contrast scales deviations from the image mean, so that `texture_contrast`
  // changes the pixel standard deviation by the same factor (until clamping).
  double mean = 0;
  for (double v : c.p) mean += v;
  mean /= static_cast<double>(c.p.size());
  sim::Texture t;
  t.name = std::string(texture_kind_name(kind));
  if (kind == TextureKind::kPoster) t.name += std::to_string(variant);
  t.width = t.height = c.n;
  t.pixels.resize(c.p.size());
  for (std::size_t i = 0; i < c.p.size(); ++i) {
    const double v = clamp(mean + contrast * (c.p[i] - mean), 0.0, 255.0);
    t.pixels[i] = static_cast<std::uint8_t>(std::floor(v + 0.5));
  }
  return t;
}

void grass(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  c.fill([&](double u, double v, int, int) {
    const double macro = n.fbm(u, v, 2, 2, 3, 0.5, 1);              // wet / dry patches, ~1 m
    const double mid = n.fbm(u, v, 8, 8, 4, 0.55, 2);               // clumps, ~10-50 cm
    const double blades = n.gradient(u * 128, v * 16, 128, 16, 3);  // streaks
    const Noise::Cell t = n.worley(u * 24, v * 24, 24, 24, 4);
    const double tuft = smoothstep(0.45, 0.0, t.f1) * (Noise::unit(t.id) - 0.4);
    return 118 + 60 * macro + 75 * mid + 22 * blades + 50 * tuft;
  });
}

void soil(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  c.fill([&](double u, double v, int, int) {
    double s = 105 + 80 * n.fbm(u, v, 4, 4, 5, 0.55, 1);
    const Noise::Cell p = n.worley(u * 12, v * 12, 12, 12, 2);
    const double r = 0.15 + 0.25 * Noise::unit(p.id);
    if (Noise::unit(p.id >> 7) < 0.5) {
      // A pebble: brighter, shaded from its top (lit from above-left).
      const double w = smoothstep(r, r * 0.7, p.f1);
      const double stone = 150 + 60 * Noise::unit(p.id >> 17) - 40 * p.f1 / r;
      s = s * (1 - w) + stone * w;
    }
    // Grass tufts where a low-frequency mask is high: vertical bright streaks.
    const double tuft_mask = smoothstep(0.0, 0.35, n.fbm(u, v, 3, 3, 3, 0.5, 3));
    const double blades = n.gradient(u * 96, v * 12, 96, 12, 4);
    return s + tuft_mask * (25 + 35 * blades);
  });
}

void bark(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  c.fill([&](double u, double v, int, int) {
    // Ridges are long along the trunk (v) and narrow across it (u).
    // Value noise (not gradient noise, which is 0 at every lattice point and
    // would put a fissure knot on a regular grid).
    const double r = n.value(u * 12, v * 2, 12, 2, 1) + 0.5 * n.value(u * 24, v * 4, 24, 4, 2);
    const double fissure = smoothstep(0.16, 0.0, std::abs(r));
    const double fine = n.fbm(u, v, 32, 8, 3, 0.5, 3);
    const double lichen = smoothstep(0.3, 0.55, n.fbm(u, v, 4, 4, 3, 0.5, 4));
    return 120 + 30 * r + 40 * fine - 75 * fissure + 45 * lichen;
  });
}

void foliage(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  c.fill([&](double u, double v, int, int) {
    // Leaf clusters at two scales: small ones modulated by larger ones.
    const Noise::Cell l = n.worley(u * 40, v * 40, 40, 40, 1);
    const Noise::Cell L = n.worley(u * 10, v * 10, 10, 10, 4);
    const double leaf =
        (50 + 90 * Noise::unit(l.id) + 70 * Noise::unit(L.id)) * (1.0 - 0.45 * l.f1);
    const double gap = smoothstep(0.14, 0.0, l.f2 - l.f1);  // dark edges between clusters
    const double light = n.fbm(u, v, 3, 3, 3, 0.5, 2);      // sunlit / shaded parts of the crown
    const double hole = smoothstep(-0.35, -0.55, n.fbm(u, v, 6, 6, 3, 0.5, 3));  // deep shadow
    const double s = leaf * (1.0 - 0.7 * gap) + 90 * light;
    return s * (1 - hole) + 18 * hole;
  });
}

void reeds(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  c.fill([&](double u, double v, int, int) {
    // Blades: bright where a vertically stretched noise is positive, dark gaps between.
    const double b =
        n.gradient(u * 48, v * 1, 48, 1, 1) + 0.6 * n.gradient(u * 96, v * 2, 96, 2, 2);
    const double blade = smoothstep(-0.1, 0.25, b);
    const double tone = n.fbm(u, v, 4, 2, 3, 0.5, 3);
    return 45 + 125 * blade + 25 * tone;
  });
}

void stone(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  c.fill([&](double u, double v, int, int) {
    const Noise::Cell s = n.worley(u * 6, v * 6, 6, 6, 1);
    const double edge = s.f2 - s.f1;
    const double mortar = smoothstep(0.10, 0.05, edge);
    const double rock = 120 + 80 * (Noise::unit(s.id) - 0.5) + 20 * n.fbm(u, v, 16, 16, 4, 0.5, 2) -
                        28 * smoothstep(0.3, 0.1, edge);
    const double joint = 70 + 10 * n.fbm(u, v, 32, 32, 2, 0.5, 3);
    return rock * (1 - mortar) + joint * mortar;
  });
}

// Stretcher bond: `rows` courses, `cols` bricks per course, odd courses offset
// by half a brick; joints `joint_px` wide. Shared by brick and facade.
double brick_at(const Noise& n, double u, double v, int size, int rows, int cols, double joint_px) {
  const double y = v * rows;
  const double row = std::floor(y);
  const auto irow = static_cast<std::int64_t>(row);
  const double x = u * cols + ((irow % 2) != 0 ? 0.5 : 0.0);
  const auto icol = static_cast<std::int64_t>(std::floor(x)) % cols;
  const double row_px = static_cast<double>(size) / rows;
  const double col_px = static_cast<double>(size) / cols;
  const double dy = std::min(y - row, 1.0 - (y - row)) * row_px;
  const double dx = std::min(fract(x), 1.0 - fract(x)) * col_px;
  const double m = smoothstep(joint_px * 0.5 + 0.75, joint_px * 0.5 - 0.25, std::min(dx, dy));
  const std::uint64_t id = n.hash(icol, irow, 7);
  const double brick = 95 + 50 * (Noise::unit(id) - 0.5) + 12 * n.fbm(u, v, 16, 16, 3, 0.5, 8) +
                       8 * n.value(u * size * 0.5, v * size * 0.5, size / 2, size / 2, 9);
  const double mortar = 178 + 8 * n.fbm(u, v, 32, 32, 2, 0.5, 10);
  return brick * (1 - m) + mortar * m;
}

void brick(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  c.fill([&](double u, double v, int, int) { return brick_at(n, u, v, c.n, 8, 4, c.n / 64.0); });
}

void concrete(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  const double px = c.n;
  c.fill([&](double u, double v, int x, int y) {
    double s = 140 + 55 * n.fbm(u, v, 3, 3, 5, 0.55, 1) + 20 * n.fbm(u, v, 48, 48, 2, 0.5, 2);
    const Noise::Cell p = n.worley(u * 64, v * 64, 64, 64, 3);
    if (Noise::unit(p.id) < 0.3) s -= 45 * smoothstep(0.14, 0.05, p.f1);  // air pits
    // Formwork joints every half texture, and tie holes between them.
    s -= 20 * smoothstep(2.0, 0.5, dist_to_grid(y + 0.5, px / 2));
    const double hx = dist_to_grid(x + 0.5 - px / 4, px / 2),
                 hy = dist_to_grid(y + 0.5 - px / 4, px / 2);
    s -= 60 * smoothstep(px / 100 + 1, px / 100, std::sqrt(hx * hx + hy * hy));
    return s;
  });
}

void sheet_piling(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  const double pan_px = c.n / 2.0;  // two sheet-pile pans across the texture
  // A flat shade per facet of the trapezoidal profile (outer flange, web,
  // inner flange, web): the vertical corrugation bands of a piled wall.
  auto facet = [&](double f_px) {
    static constexpr double kEdge[3] = {0.3, 0.5, 0.8};
    static constexpr double kShade[4] = {125, 110, 118, 132};
    const double f = fract(f_px / pan_px);
    int k = 0;
    while (k < 3 && f >= kEdge[k]) ++k;
    return kShade[k];
  };
  c.fill([&](double u, double v, int x, int) {
    // Box filter over one pixel so the facet steps are anti-aliased.
    const double s = (facet(x + 1.0 / 6) + facet(x + 0.5) + facet(x + 5.0 / 6)) / 3.0;
    const double rust = n.gradient(u * 32, v * 2, 32, 2, 1);
    return s + 8 * rust + 5 * n.fbm(u, v, 4, 4, 3, 0.5, 2) + 3 * n.fbm(u, v, 64, 64, 1, 0.5, 3);
  });
}

void painted_wall(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  c.fill([&](double u, double v, int, int) {
    return 190 + 12 * n.fbm(u, v, 2, 2, 4, 0.5, 1) + 6 * n.fbm(u, v, 32, 32, 2, 0.5, 2);
  });
}

// Posters: bold, high-contrast print inside a white margin (so the texture
// wraps trivially and its outline is a strong feature on a plain wall).
void poster(Canvas& c, Rng& rng, int variant) {
  const int N = c.n;
  const int margin = N / 18;
  const int inner = N - 2 * margin;
  c.fill([](double, double, int, int) { return 235.0; });
  auto rect = [&](int x0, int y0, int x1, int y1, double g) {
    for (int y = std::max(y0, margin); y < std::min(y1, N - margin); ++y)
      for (int x = std::max(x0, margin); x < std::min(x1, N - margin); ++x) c.at(x, y) = g;
  };
  switch (variant) {
    case 0: {  // block code: random black/white cells with three finder squares
      const int cells = 12;
      const int cs = inner / cells;
      for (int j = 0; j < cells; ++j)
        for (int i = 0; i < cells; ++i)
          if (rng.uniform() < 0.5)
            rect(margin + i * cs, margin + j * cs, margin + (i + 1) * cs, margin + (j + 1) * cs,
                 15);
      auto finder = [&](int i, int j) {
        const int x = margin + i * cs, y = margin + j * cs;
        rect(x, y, x + 3 * cs, y + 3 * cs, 15);
        rect(x + cs / 2, y + cs / 2, x + 3 * cs - cs / 2, y + 3 * cs - cs / 2, 240);
        rect(x + cs, y + cs, x + 2 * cs, y + 2 * cs, 15);
      };
      finder(0, 0);
      finder(cells - 3, 0);
      finder(0, cells - 3);
      break;
    }
    case 1: {  // discs of random size and grey over a mid-grey field, and a target
      rect(0, 0, N, N, 128);
      const int discs = 10 + static_cast<int>(rng.uniform_int(6));
      for (int k = 0; k < discs; ++k) {
        const double cx = margin + rng.uniform() * inner, cy = margin + rng.uniform() * inner;
        const double r = inner * (0.04 + 0.1 * rng.uniform());
        const double g = rng.uniform() < 0.5 ? 20.0 : 240.0;
        for (int y = margin; y < N - margin; ++y)
          for (int x = margin; x < N - margin; ++x) {
            const double dx = x + 0.5 - cx, dy = y + 0.5 - cy;
            if (dx * dx + dy * dy < r * r) c.at(x, y) = g;
          }
      }
      const double cx = N / 2.0, cy = N / 2.0, ring = inner / 16.0;
      for (int y = margin; y < N - margin; ++y)
        for (int x = margin; x < N - margin; ++x) {
          const double d =
              std::sqrt((x + 0.5 - cx) * (x + 0.5 - cx) + (y + 0.5 - cy) * (y + 0.5 - cy));
          if (d < 4 * ring) c.at(x, y) = (static_cast<int>(d / ring) % 2 == 0) ? 15.0 : 240.0;
        }
      break;
    }
    case 2: {  // title bar, lines of "text" and a bar chart
      rect(margin, margin, N - margin, margin + inner / 8, 25);
      int y = margin + inner / 8 + inner / 24;
      const int line = std::max(3, inner / 40);
      for (int l = 0; l < 8; ++l, y += 2 * line) {
        int x = margin + inner / 20;
        while (x < N - margin - inner / 20) {
          const int word = line * (2 + static_cast<int>(rng.uniform_int(6)));
          rect(x, y, std::min(x + word, N - margin - inner / 20), y + line, 30);
          x += word + line;
        }
      }
      const int base = N - margin - inner / 12, left = margin + inner / 10;
      const int bars = 7, bw = (inner * 8 / 10) / (2 * bars);
      rect(left - 2, base - inner * 4 / 10, left, base, 20);
      rect(left - 2, base, N - margin - inner / 20, base + 2, 20);
      for (int k = 0; k < bars; ++k) {
        const int h = static_cast<int>(inner * (0.08 + 0.3 * rng.uniform()));
        const double g = (k % 2 == 0) ? 20.0 : 110.0;
        rect(left + bw / 2 + 2 * k * bw, base - h, left + bw / 2 + 2 * k * bw + bw, base, g);
      }
      break;
    }
    default: {  // rectangles split recursively, black lines between (Mondrian)
      static constexpr double kGrey[5] = {20, 90, 170, 240, 240};
      struct Box {
        int x0, y0, x1, y1, depth;
      };
      std::vector<Box> stack{{margin, margin, N - margin, N - margin, 0}};
      const int lw = std::max(2, N / 64);
      while (!stack.empty()) {
        const Box b = stack.back();
        stack.pop_back();
        const int w = b.x1 - b.x0, h = b.y1 - b.y0;
        if (b.depth < 4 && std::max(w, h) > inner / 5) {
          const bool vertical = w > h;
          const int len = vertical ? w : h;
          const int cut = static_cast<int>(len * (0.3 + 0.4 * rng.uniform()));
          if (vertical) {
            stack.push_back({b.x0, b.y0, b.x0 + cut, b.y1, b.depth + 1});
            stack.push_back({b.x0 + cut, b.y0, b.x1, b.y1, b.depth + 1});
          } else {
            stack.push_back({b.x0, b.y0, b.x1, b.y0 + cut, b.depth + 1});
            stack.push_back({b.x0, b.y0 + cut, b.x1, b.y1, b.depth + 1});
          }
        } else {
          rect(b.x0, b.y0, b.x1, b.y1, 15);
          rect(b.x0 + lw, b.y0 + lw, b.x1 - lw, b.y1 - lw, kGrey[rng.uniform_int(5)]);
        }
      }
      break;
    }
  }
}

void window(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  const double N = c.n;
  const double frame = N * 0.055, mullion = N * 0.032;
  const double streak_phase = rng.uniform();
  c.fill([&](double u, double v, int x, int y) {
    const double px = x + 0.5, py = y + 0.5;
    const double d_edge = std::min(std::min(px, N - px), std::min(py, N - py));
    const double d_mull = std::min(std::abs(px - N / 2), std::abs(py - N / 2));
    if (d_edge < frame) return d_edge > frame - 2 ? 185.0 : 60.0;  // frame with a lit bevel
    if (d_mull < mullion / 2) return d_mull > mullion / 2 - 1.5 ? 175.0 : 70.0;
    // A pane: sky reflection brighter towards the pane's top, clouds / trees
    // mirrored in it, and a diagonal glint.
    const double pv = fract(v * 2);
    const double streak =
        smoothstep(0.06, 0.0, std::abs(fract(u * 2 + pv * 0.6 + streak_phase) - 0.5));
    return 150 + 60 * (1 - pv) + 28 * n.fbm(u, v, 3, 3, 4, 0.5, 1) + 25 * streak;
  });
}

void lab_floor(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  const double tile = c.n / 4.0;
  c.fill([&](double u, double v, int x, int y) {
    const double d = std::min(dist_to_grid(x + 0.5, tile), dist_to_grid(y + 0.5, tile));
    const double grout = smoothstep(2.0, 1.0, d);
    const std::uint64_t id =
        n.hash(static_cast<std::int64_t>(x / tile), static_cast<std::int64_t>(y / tile), 1);
    const double t = 160 + 22 * (Noise::unit(id) - 0.5) + 6 * n.fbm(u, v, 8, 8, 3, 0.5, 2) +
                     6 * n.value(u * c.n * 0.5, v * c.n * 0.5, c.n / 2, c.n / 2, 3);
    return t * (1 - grout) + 85 * grout;
  });
}

void roof(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  const int rows = 8, cols = 8;
  c.fill([&](double u, double v, int, int) {
    const double y = v * rows;
    const auto irow = static_cast<std::int64_t>(std::floor(y));
    const double fy = y - std::floor(y);
    const double x = u * cols + ((irow % 2) != 0 ? 0.5 : 0.0);
    const auto icol = static_cast<std::int64_t>(std::floor(x)) % cols;
    const double gap_px = std::min(fract(x), 1 - fract(x)) * c.n / cols;
    const double t = 95 + 34 * (Noise::unit(n.hash(icol, irow, 1)) - 0.5) -
                     40 * smoothstep(0.7, 1.0, fy) + 9 * n.fbm(u, v, 16, 16, 3, 0.5, 2);
    return gap_px < 1.2 ? 35.0 : t;
  });
}

void facade(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  const double N = c.n;
  // A 3 m x 3 m bay: window 1.2 m wide, 1.5 m tall, sill 0.9 m above the floor
  // (v = 1 is the floor), with a concrete lintel and sill.
  const double wx0 = N * 0.3, wx1 = N * 0.7, wy0 = N * 0.2, wy1 = N * 0.7;
  c.fill([&](double u, double v, int x, int y) {
    const double px = x + 0.5, py = y + 0.5;
    if (px > wx0 && px < wx1 && py > wy0 && py < wy1) {
      const double d = std::min(std::min(px - wx0, wx1 - px), std::min(py - wy0, wy1 - py));
      if (d < N * 0.02) return 55.0;                     // frame
      if (std::abs(px - N / 2) < N * 0.01) return 60.0;  // mullion
      return 190 - 55 * (py - wy0) / (wy1 - wy0) +
             25 * n.fbm(u, v, 4, 4, 3, 0.5, 1);  // glass, sky-lit at the top
    }
    if (px > wx0 - N * 0.03 && px < wx1 + N * 0.03 && py > wy0 - N * 0.07 && py < wy0) return 190.0;
    if (px > wx0 - N * 0.03 && px < wx1 + N * 0.03 && py > wy1 && py < wy1 + N * 0.04) return 200.0;
    return brick_at(n, u, v, c.n, 32, 8, 1.0);
  });
}

void metal_panel(Canvas& c, Rng& rng) {
  const Noise n = Noise::from(rng);
  const double N = c.n;
  const double bolt_r = N / 64.0;
  c.fill([&](double u, double v, int x, int y) {
    const double px = x + 0.5, py = y + 0.5;
    double s = 150 + 7 * n.fbm(u, v, 2, 2, 4, 0.5, 1) + 7 * n.gradient(u * 16, v * 2, 16, 2, 2);
    const double dx = dist_to_grid(px, N), dy = dist_to_grid(py, N);
    const double seam = std::min(dx, dy);
    if (seam < 1.5) return 70.0;
    if (seam < 3.0) s = 190;  // bevel catching the light
    // Bolts every eighth of the panel along both seams, lit from above.
    const double off = N * 0.035;
    const double bx = dist_to_grid(px - N / 16, N / 8), by = dist_to_grid(py - N / 16, N / 8);
    const double ay = std::abs(dy - off), ax = std::abs(dx - off);
    const double r = std::sqrt(std::min(bx * bx + ay * ay, ax * ax + by * by));
    if (r < bolt_r) return 110 + 60 * (1 - r / bolt_r);
    return s;
  });
}

}  // namespace

std::string_view texture_kind_name(TextureKind kind) {
  switch (kind) {
    case TextureKind::kGrass:
      return "grass";
    case TextureKind::kSoil:
      return "soil";
    case TextureKind::kBark:
      return "bark";
    case TextureKind::kFoliage:
      return "foliage";
    case TextureKind::kReeds:
      return "reeds";
    case TextureKind::kStone:
      return "stone";
    case TextureKind::kBrick:
      return "brick";
    case TextureKind::kConcrete:
      return "concrete";
    case TextureKind::kSheetPiling:
      return "sheet_piling";
    case TextureKind::kPaintedWall:
      return "painted_wall";
    case TextureKind::kPoster:
      return "poster";
    case TextureKind::kWindow:
      return "window";
    case TextureKind::kLabFloor:
      return "lab_floor";
    case TextureKind::kRoof:
      return "roof";
    case TextureKind::kFacade:
      return "facade";
    case TextureKind::kMetalPanel:
      return "metal_panel";
  }
  DRIFTLAB_DEMAND_MSG(false, "TextureKind without a name");
  return {};
}

int default_texture_size(TextureKind kind) {
  switch (kind) {
    case TextureKind::kGrass:
    case TextureKind::kFoliage:
    case TextureKind::kConcrete:
      return 512;
    default:
      return 256;
  }
}

sim::Texture make_texture(TextureKind kind, Rng& rng, double contrast, int variant, int size_px) {
  DRIFTLAB_DEMAND_MSG(contrast >= 0 && std::isfinite(contrast), "texture contrast must be >= 0");
  DRIFTLAB_DEMAND_MSG(size_px == 0 || (size_px >= 16 && size_px <= 4096),
                      "texture size out of range");
  DRIFTLAB_DEMAND_MSG(kind != TextureKind::kPoster || (variant >= 0 && variant < kPosterVariants),
                      "poster variant out of range");
  Canvas c(size_px == 0 ? default_texture_size(kind) : size_px);
  switch (kind) {
    case TextureKind::kGrass:
      grass(c, rng);
      break;
    case TextureKind::kSoil:
      soil(c, rng);
      break;
    case TextureKind::kBark:
      bark(c, rng);
      break;
    case TextureKind::kFoliage:
      foliage(c, rng);
      break;
    case TextureKind::kReeds:
      reeds(c, rng);
      break;
    case TextureKind::kStone:
      stone(c, rng);
      break;
    case TextureKind::kBrick:
      brick(c, rng);
      break;
    case TextureKind::kConcrete:
      concrete(c, rng);
      break;
    case TextureKind::kSheetPiling:
      sheet_piling(c, rng);
      break;
    case TextureKind::kPaintedWall:
      painted_wall(c, rng);
      break;
    case TextureKind::kPoster:
      poster(c, rng, variant);
      break;
    case TextureKind::kWindow:
      window(c, rng);
      break;
    case TextureKind::kLabFloor:
      lab_floor(c, rng);
      break;
    case TextureKind::kRoof:
      roof(c, rng);
      break;
    case TextureKind::kFacade:
      facade(c, rng);
      break;
    case TextureKind::kMetalPanel:
      metal_panel(c, rng);
      break;
  }
  return finish(kind, c, contrast, variant);
}

int add_scene_texture(sim::SceneGeometry* g, const RngStreams& streams, TextureKind kind,
                      double contrast, int variant) {
  std::string name = "scene.texture." + std::string(texture_kind_name(kind));
  if (kind == TextureKind::kPoster) name += std::to_string(variant);
  Rng rng = streams.stream(name);
  g->textures.push_back(make_texture(kind, rng, contrast, variant));
  return static_cast<int>(g->textures.size() - 1);
}

}  // namespace driftlab::scenes
