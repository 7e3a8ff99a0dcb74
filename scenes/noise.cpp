#include "scenes/noise.hpp"

#include <array>
#include <cmath>

#include "core/rng.hpp"

namespace driftlab::scenes {

namespace {

std::int64_t wrap(std::int64_t i, int period) {
  if (period <= 0) return i;
  const std::int64_t m = i % period;
  return m < 0 ? m + period : m;
}

// Lattice indices i + k for k = 0 .. N-1, wrapped like wrap(): one division for all N (they
// dominate the cost of a texture without it).
template <int N>
std::array<std::int64_t, N> wrap_run(std::int64_t i, int period) {
  std::array<std::int64_t, N> w;
  w[0] = wrap(i, period);
  for (int k = 1; k < N; ++k) w[k] = period > 0 && w[k - 1] + 1 == period ? 0 : w[k - 1] + 1;
  return w;
}

// Quintic fade (Perlin 2002): continuous second derivative, so shading of
// noise-displaced surfaces shows no lattice creases.
double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

double lerp(double a, double b, double t) { return a + (b - a) * t; }

// Eight unit gradient directions; a table instead of cos/sin of a random
// angle keeps the noise free of libm (bytes identical on every platform).
constexpr double kDiag = 0.70710678118654752;
constexpr double kGradX[8] = {1, -1, 0, 0, kDiag, -kDiag, kDiag, -kDiag};
constexpr double kGradY[8] = {0, 0, 1, -1, kDiag, kDiag, -kDiag, -kDiag};

}  // namespace

std::uint64_t Noise::hash(std::int64_t a, std::int64_t b, std::uint64_t salt) const {
  // One full mix of the key and an odd-multiplier combination of the lattice
  // coordinates: collisions need a*K1 ^ (b + salt*K3)*K2 to coincide, which
  // for textures and terrain (|a|, |b| < 2^24) does not visibly happen, and
  // it costs a third of mixing each input separately (textures dominate the
  // scene build time).
  const std::uint64_t ua = static_cast<std::uint64_t>(a), ub = static_cast<std::uint64_t>(b);
  return mix64(key_ ^ (ua * 0x9e3779b97f4a7c15ULL) ^
               ((ub + salt * 0xd1b54a32d192ed03ULL) * 0xc2b2ae3d27d4eb4fULL));
}

double Noise::gradient(double x, double y, int px, int py, std::uint64_t salt) const {
  const double fx = std::floor(x), fy = std::floor(y);
  const double tx = x - fx, ty = y - fy;
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const auto wx = wrap_run<2>(ix, px), wy = wrap_run<2>(iy, py);
  auto corner = [&](int i, int j, double dx, double dy) {
    const std::uint64_t g = hash(wx[i], wy[j], salt) >> 61;  // 0..7
    return kGradX[g] * dx + kGradY[g] * dy;
  };
  const double n00 = corner(0, 0, tx, ty);
  const double n10 = corner(1, 0, tx - 1.0, ty);
  const double n01 = corner(0, 1, tx, ty - 1.0);
  const double n11 = corner(1, 1, tx - 1.0, ty - 1.0);
  const double sx = fade(tx), sy = fade(ty);
  // 2D gradient noise peaks near +-0.7; scale to about +-1.
  return 1.4 * lerp(lerp(n00, n10, sx), lerp(n01, n11, sx), sy);
}

double Noise::value(double x, double y, int px, int py, std::uint64_t salt) const {
  const double fx = std::floor(x), fy = std::floor(y);
  const double tx = x - fx, ty = y - fy;
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const auto wx = wrap_run<2>(ix, px), wy = wrap_run<2>(iy, py);
  auto corner = [&](int i, int j) { return 2.0 * unit(hash(wx[i], wy[j], salt)) - 1.0; };
  const double sx = fade(tx), sy = fade(ty);
  return lerp(lerp(corner(0, 0), corner(1, 0), sx), lerp(corner(0, 1), corner(1, 1), sx), sy);
}

double Noise::fbm(double u, double v, int px0, int py0, int octaves, double gain,
                  std::uint64_t salt) const {
  double sum = 0, amp = 1, norm = 0;
  int px = px0, py = py0;
  for (int k = 0; k < octaves; ++k) {
    // Each octave gets its own salt so octaves are not scaled copies of each other.
    sum += amp * gradient(u * px, v * py, px, py, salt * 64 + static_cast<std::uint64_t>(k));
    norm += amp;
    amp *= gain;
    px *= 2;
    py *= 2;
  }
  return sum / norm;
}

double Noise::fbm_world(double x, double y, double wavelength, int octaves, double gain,
                        std::uint64_t salt) const {
  double sum = 0, amp = 1, norm = 0, f = 1.0 / wavelength;
  for (int k = 0; k < octaves; ++k) {
    sum += amp * gradient(x * f, y * f, 0, 0, salt * 64 + static_cast<std::uint64_t>(k));
    norm += amp;
    amp *= gain;
    f *= 2.0;
  }
  return sum / norm;
}

Noise::Cell Noise::worley(double x, double y, int px, int py, std::uint64_t salt) const {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  Cell c{1e9, 1e9, 0};
  double d1 = 1e18, d2 = 1e18;  // squared distances; one sqrt each at the end
  const auto wx = wrap_run<3>(ix - 1, px), wy = wrap_run<3>(iy - 1, py);
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const std::int64_t cx = ix + dx, cy = iy + dy;
      const std::uint64_t h = hash(wx[dx + 1], wy[dy + 1], salt);
      // Feature point position inside the cell from two independent hash bit fields.
      const double ox = static_cast<double>(h & 0xffffffULL) * 0x1.0p-24;
      const double oy = static_cast<double>((h >> 24) & 0xffffffULL) * 0x1.0p-24;
      const double ex = static_cast<double>(cx) + ox - x;
      const double ey = static_cast<double>(cy) + oy - y;
      const double d = ex * ex + ey * ey;
      if (d < d1) {
        d2 = d1;
        d1 = d;
        c.id = h;
      } else if (d < d2) {
        d2 = d;
      }
    }
  }
  c.f1 = std::sqrt(d1);
  c.f2 = std::sqrt(d2);
  return c;
}

double smoothstep(double e0, double e1, double x) {
  double t = (x - e0) / (e1 - e0);
  t = t < 0 ? 0 : (t > 1 ? 1 : t);
  return t * t * (3.0 - 2.0 * t);
}

}  // namespace driftlab::scenes
