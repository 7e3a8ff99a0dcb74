#include "core/hash.hpp"

#include <fmt/format.h>

namespace driftlab {

std::string hex64(std::uint64_t h) { return fmt::format("{:016x}", h); }

std::string fnv1a64_hex(std::string_view bytes) { return hex64(fnv1a64(bytes)); }

}  // namespace driftlab
