// FNV-1a 64 (Fowler, Noll and Vo; offset 0xcbf29ce484222325, prime 0x100000001b3): the one
// non-cryptographic hash of the project, for seeds (core/rng), plan hashes (study) and the
// frame cache's names and checksums (pipeline/frame_cache).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace driftlab {

/// FNV-1a 64 of `bytes`; `h` continues an earlier hash (streaming).
constexpr std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t h = 0xcbf29ce484222325ULL) {
  for (const char c : bytes) {
    h ^= static_cast<std::uint8_t>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

/// The same as 16 lower-case hex digits.
std::string fnv1a64_hex(std::string_view bytes);

/// A hash as 16 lower-case hex digits.
std::string hex64(std::uint64_t h);

}  // namespace driftlab
