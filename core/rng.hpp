// Named, seeded random streams (docs/design.md "Randomness"): every consumer of
// randomness draws from its own stream, derived from the scenario seed and the
// stream's name, so adding or changing one sensor never shifts another's noise.
//
// The engine is std::mt19937_64, whose output sequence the C++ standard fixes.
// The std:: distributions are implementation-defined, so the distributions here
// are our own and use only IEEE-exact operations (+ - * / sqrt and a portable
// logarithm): the same seed gives the same bytes with any standard library.
//
// Seed derivation (stable; changing it changes every golden value):
//   mix64(z)   = SplitMix64 finaliser: z ^= z >> 30; z *= 0xbf58476d1ce4e5b9;
//                z ^= z >> 27; z *= 0x94d049bb133111eb; z ^= z >> 31
//   fnv1a64(s) = FNV-1a 64 over the bytes of s (offset 0xcbf29ce484222325,
//                prime 0x100000001b3)
//   derive_seed(seed, name) = mix64(mix64(seed + 0x9e3779b97f4a7c15) ^ fnv1a64(name))
// and a stream is std::mt19937_64 constructed from that single 64-bit value.
#pragma once

#include <cstdint>
#include <random>
#include <string_view>

namespace driftlab {

/// One random stream. Copying it copies its state (both copies then give the
/// same numbers). Not thread-safe: give each thread its own named stream.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}

  /// The engine's next raw 64-bit output.
  std::uint64_t next_u64() { return engine_(); }

  /// Uniform in [0, 1) with 53 random bits (multiples of 2^-53).
  double uniform() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }

  /// Uniform in [a, b), a <= b finite. Rounding of a + (b - a) u can give b
  /// when b - a is tiny relative to |a| or |b|.
  double uniform(double a, double b);

  /// Uniform integer in [0, n), n >= 1, without modulo bias (rejection).
  std::uint64_t uniform_int(std::uint64_t n);

  /// Standard normal, Marsaglia's polar method. Each accepted pair gives two
  /// values; the second is returned by the next call.
  double normal();

  /// Normal with the given mean and standard deviation (sd >= 0).
  double normal(double mean, double sd);

 private:
  std::mt19937_64 engine_;
  double cached_normal_ = 0.0;
  bool has_cached_normal_ = false;
};

/// The seed of the stream `name` under `seed` (algorithm in the file comment).
std::uint64_t derive_seed(std::uint64_t seed, std::string_view name);

/// SplitMix64's finaliser: a full-avalanche 64-bit mix (nearby inputs, unrelated outputs).
constexpr std::uint64_t mix64(std::uint64_t z) {
  z ^= z >> 30;
  z *= 0xbf58476d1ce4e5b9ULL;
  z ^= z >> 27;
  z *= 0x94d049bb133111ebULL;
  z ^= z >> 31;
  return z;
}

/// The named streams of one scenario run.
class RngStreams {
 public:
  explicit RngStreams(std::uint64_t scenario_seed) : seed_(scenario_seed) {}

  /// A fresh stream for `name` (non-empty, e.g. "imu.gyro"); the same name
  /// always gives the same sequence, whatever other streams exist.
  Rng stream(std::string_view name) const;

  std::uint64_t seed() const { return seed_; }

 private:
  std::uint64_t seed_;
};

namespace detail {
/// Natural logarithm of a finite x > 0 from + - * / only, within about 1 ulp of
/// the true value, so that normal() does not depend on the platform's libm.
double portable_log(double x);
}  // namespace detail

}  // namespace driftlab
