#include "core/rng.hpp"

#include <cmath>

#include "core/error.hpp"
#include "core/hash.hpp"

// The bytes must not depend on whether a compiler fuses a * b + c into an FMA.
// GCC in ISO mode (CMAKE_CXX_EXTENSIONS OFF) does not; clang does unless told.
#ifdef __clang__
#pragma STDC FP_CONTRACT OFF
#endif

namespace driftlab {

namespace {

constexpr std::uint64_t kGoldenGamma = 0x9e3779b97f4a7c15ULL;

}  // namespace

std::uint64_t derive_seed(std::uint64_t seed, std::string_view name) {
  // The seed is mixed before the name hash is folded in, so nearby seeds
  // (42, 43) and similar names ("imu.gyro", "imu.accel") land far apart; the
  // outer mix spreads the XOR over all bits before it seeds the engine.
  return mix64(mix64(seed + kGoldenGamma) ^ fnv1a64(name));
}

Rng RngStreams::stream(std::string_view name) const {
  DRIFTLAB_DEMAND_MSG(!name.empty(), "random streams need a non-empty name");
  return Rng(derive_seed(seed_, name));
}

double Rng::uniform(double a, double b) {
  DRIFTLAB_DEMAND_MSG(std::isfinite(a) && std::isfinite(b) && a <= b,
                      "uniform(a, b) needs finite a <= b");
  return a + (b - a) * uniform();
}

std::uint64_t Rng::uniform_int(std::uint64_t n) {
  DRIFTLAB_DEMAND_MSG(n >= 1, "uniform_int(n) needs n >= 1");
  // 2^64 mod n: the outputs below it are the surplus that would make small
  // remainders more likely, so they are redrawn (at most half of all draws).
  const std::uint64_t threshold = (0 - n) % n;
  for (;;) {
    const std::uint64_t r = next_u64();
    if (r >= threshold) return r % n;
  }
}

double Rng::normal() {
  if (has_cached_normal_) {
    has_cached_normal_ = false;
    return cached_normal_;
  }
  // Polar rather than Box-Muller: it needs no sin/cos, whose results differ
  // between libms; 2u - 1 is exact for our 53-bit uniforms.
  double u = 0.0;
  double v = 0.0;
  double s = 0.0;
  do {
    u = 2.0 * uniform() - 1.0;
    v = 2.0 * uniform() - 1.0;
    s = u * u + v * v;
  } while (s >= 1.0 || s == 0.0);
  const double factor = std::sqrt(-2.0 * detail::portable_log(s) / s);
  cached_normal_ = v * factor;
  has_cached_normal_ = true;
  return u * factor;
}

double Rng::normal(double mean, double sd) {
  DRIFTLAB_DEMAND_MSG(sd >= 0.0, "normal(mean, sd) needs sd >= 0");
  return mean + sd * normal();
}

namespace detail {

double portable_log(double x) {
  DRIFTLAB_DEMAND_MSG(x > 0.0 && std::isfinite(x), "portable_log needs a finite x > 0");
  // x = m 2^e with m in [sqrt(1/2), sqrt(2)); frexp and the scaling are exact.
  int e = 0;
  double m = std::frexp(x, &e);
  if (m < 0.70710678118654752440) {
    m *= 2.0;
    --e;
  }
  // log(m) = 2 atanh(f) = 2 (f + f^3/3 + f^5/5 + ...), f = (m - 1) / (m + 1),
  // |f| <= 0.1716, so terms up to f^23 reach double precision. m - 1 is exact.
  const double f = (m - 1.0) / (m + 1.0);
  const double s = f * f;
  double p = 1.0 / 23.0;
  p = 1.0 / 21.0 + s * p;
  p = 1.0 / 19.0 + s * p;
  p = 1.0 / 17.0 + s * p;
  p = 1.0 / 15.0 + s * p;
  p = 1.0 / 13.0 + s * p;
  p = 1.0 / 11.0 + s * p;
  p = 1.0 / 9.0 + s * p;
  p = 1.0 / 7.0 + s * p;
  p = 1.0 / 5.0 + s * p;
  p = 1.0 / 3.0 + s * p;
  const double r = 2.0 * f;
  const double log_m = r + r * s * p;
  // ln 2 split so that e * kLn2Hi is exact for any double exponent.
  constexpr double kLn2Hi = 6.93147180369123816490e-01;
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  const double de = static_cast<double>(e);
  return de * kLn2Hi + (log_m + de * kLn2Lo);
}

}  // namespace detail

}  // namespace driftlab
