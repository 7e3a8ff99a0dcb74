#include "sim/render/alpha_mips.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numeric>

#include <fmt/format.h>

#include "core/error.hpp"
#include "sim/render/mip_chain.hpp"

namespace driftlab::sim {

namespace {

// Block means of level 0 for a level of w x h texels: alpha, and grey weighted by alpha.
void block_means(const Texture& t, int w, int h, std::vector<double>* alpha,
                 std::vector<double>* grey) {
  alpha->assign(static_cast<std::size_t>(w) * h, 0.0);
  grey->assign(alpha->size(), 0.0);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const int x0 = i * t.width / w, x1 = (i + 1) * t.width / w;
      const int y0 = j * t.height / h, y1 = (j + 1) * t.height / h;
      double sa = 0, sg = 0, sp = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const std::size_t k = static_cast<std::size_t>(y) * t.width + x;
          sa += t.alpha[k];
          sg += static_cast<double>(t.alpha[k]) * t.pixels[k];
          sp += t.pixels[k];
        }
      const std::size_t o = static_cast<std::size_t>(j) * w + i;
      const double n = static_cast<double>(x1 - x0) * (y1 - y0);
      (*alpha)[o] = sa / n;
      (*grey)[o] = sa > 0 ? sg / sa : sp / n;  // a fully transparent block: its plain mean
    }
}

// Quantised alphas of which exactly `opaque` reach kAlphaOpaqueFrom: the block means scaled so
// that the opaque-th largest lands on the threshold, the order (alpha, then index) kept.
std::vector<std::uint8_t> scaled_alpha(const std::vector<double>& a, std::size_t opaque) {
  std::vector<std::size_t> order(a.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&a](std::size_t p, std::size_t q) { return a[p] > a[q]; });
  // Any scale in [threshold / a_T, threshold / a_{T+1}) passes the T largest: the one nearest 1,
  // so that a level that already covers enough keeps its alpha (an opaque texture stays 255).
  const double threshold = kAlphaOpaqueFrom - 0.5;  // 127.5: the test's 0.5 in 8 bits
  const double a_t = opaque > 0 ? a[order[opaque - 1]] : 0.0;
  const double a_next = opaque < a.size() ? a[order[opaque]] : 0.0;
  double scale = 1.0;
  if (a_t > 0) scale = std::max(scale, threshold / a_t);
  if (a_next > 0) scale = std::min(scale, threshold / a_next);
  std::vector<std::uint8_t> out(a.size());
  for (std::size_t r = 0; r < order.size(); ++r) {
    const double v = std::clamp(std::round(a[order[r]] * scale), 0.0, 255.0);
    out[order[r]] =
        static_cast<std::uint8_t>(r < opaque ? std::max<double>(v, kAlphaOpaqueFrom)
                                             : std::min<double>(v, kAlphaOpaqueFrom - 1));
  }
  return out;
}

}  // namespace

double alpha_coverage(const std::vector<std::uint8_t>& alpha) {
  if (alpha.empty()) return 0.0;
  const auto n = std::count_if(alpha.begin(), alpha.end(),
                               [](std::uint8_t a) { return a >= kAlphaOpaqueFrom; });
  return static_cast<double>(n) / static_cast<double>(alpha.size());
}

std::vector<AlphaMipLevel> coverage_preserving_mips(const Texture& t) {
  const std::size_t n0 = static_cast<std::size_t>(std::max(t.width, 0)) * std::max(t.height, 0);
  if (t.width <= 0 || t.height <= 0 || t.pixels.size() != n0 || t.alpha.size() != n0)
    throw InternalError(
        fmt::format("coverage_preserving_mips: texture '{}' needs {}x{} grey and alpha texels",
                    t.name, t.width, t.height));
  const double c0 = alpha_coverage(t.alpha);
  std::vector<AlphaMipLevel> levels;
  int w = t.width, h = t.height;
  const int count = mip_level_count(t.width, t.height);
  std::vector<double> a, g;
  for (int k = 0; k < count; ++k) {
    block_means(t, w, h, &a, &g);
    const auto opaque = static_cast<std::size_t>(std::llround(c0 * static_cast<double>(a.size())));
    const std::vector<std::uint8_t> alpha = k == 0 ? t.alpha : scaled_alpha(a, opaque);
    AlphaMipLevel L{w, h, std::vector<std::uint8_t>(2 * a.size())};
    for (std::size_t i = 0; i < a.size(); ++i) {
      L.grey_alpha[2 * i] = k == 0 ? t.pixels[i] : static_cast<std::uint8_t>(std::lround(g[i]));
      L.grey_alpha[2 * i + 1] = alpha[i];
    }
    levels.push_back(std::move(L));
    w = std::max(1, w / 2);
    h = std::max(1, h / 2);
  }
  return levels;
}

}  // namespace driftlab::sim
