// FNV-1a 64 against the published test vectors (Fowler, Noll, Vo reference test suite), and
// streaming: a hash continued over a second piece equals the hash of the whole.
#include "core/hash.hpp"

#include <gtest/gtest.h>

namespace driftlab {
namespace {

TEST(Hash, Fnv1aMatchesPublishedVectors) {
  EXPECT_EQ(fnv1a64_hex(""), "cbf29ce484222325");
  EXPECT_EQ(fnv1a64_hex("a"), "af63dc4c8601ec8c");
  EXPECT_EQ(fnv1a64_hex("foobar"), "85944171f73967e8");
  static_assert(fnv1a64("a") == 0xaf63dc4c8601ec8cULL);
}

TEST(Hash, StreamingEqualsTheWhole) {
  EXPECT_EQ(fnv1a64("bar", fnv1a64("foo")), fnv1a64("foobar"));
  EXPECT_EQ(hex64(0x1f), "000000000000001f");
}

}  // namespace
}  // namespace driftlab
