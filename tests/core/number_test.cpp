// The one rule for numbers in text (core/number.hpp), as every reader applies it.
#include "core/number.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "core/yaml_io.hpp"

namespace driftlab {
namespace {

TEST(Number, ReadsDecimalAndExponentNotationWithAnOptionalPlus) {
  double v = 0;
  EXPECT_EQ(read_number("1.036630e-01", &v), NumberStatus::kOk);
  EXPECT_EQ(v, 0.103663);
  EXPECT_EQ(read_number("+2.5", &v), NumberStatus::kOk);
  EXPECT_EQ(v, 2.5);
  EXPECT_EQ(read_number("-.5", &v), NumberStatus::kOk);
  EXPECT_EQ(v, -0.5);
  for (const char* bad : {"", "+", "+-1", "++1", " 1", "1 ", "1,5", "0x10", "1e", "abc"})
    EXPECT_EQ(read_number(bad, &v), NumberStatus::kNotNumber) << bad;
}

TEST(Number, NamesWhatIsNotFiniteAndWhatIsOutOfRange) {
  double v = 0;
  EXPECT_EQ(read_number("nan", &v), NumberStatus::kNotFinite);
  EXPECT_TRUE(std::isnan(v));
  EXPECT_EQ(read_number("-INF", &v), NumberStatus::kNotFinite);
  EXPECT_EQ(v, -INFINITY);
  EXPECT_EQ(read_number("1e400", &v), NumberStatus::kOutOfRange);
  std::int64_t i = 0;
  EXPECT_EQ(read_number("9223372036854775808", &i), NumberStatus::kOutOfRange);
  EXPECT_EQ(read_number("+42", &i), NumberStatus::kOk);
  EXPECT_EQ(i, 42);
  EXPECT_EQ(read_number("4.0", &i), NumberStatus::kNotNumber);
  std::uint64_t u = 0;
  EXPECT_EQ(read_number("-1", &u), NumberStatus::kNotNumber);
  int small = 0;
  EXPECT_EQ(read_number("2147483648", &small), NumberStatus::kOutOfRange);
  EXPECT_EQ(read_number("-2147483648", &small), NumberStatus::kOk);
  EXPECT_EQ(small, -2147483648LL);
}

// YAML's own spellings are a thin wrapper: the same rule, plus .nan and .inf.
TEST(Number, YamlAddsItsSpellingsOfTheSpecialValuesToTheSameRule) {
  double v = 0;
  EXPECT_TRUE(yaml::parse_double("-.inf", &v));
  EXPECT_EQ(v, -INFINITY);
  EXPECT_TRUE(yaml::parse_double(".NaN", &v));
  EXPECT_TRUE(std::isnan(v));
  EXPECT_TRUE(yaml::parse_double("+7", &v));
  EXPECT_FALSE(yaml::parse_double("+-7", &v));
  std::int64_t i = 0;
  EXPECT_FALSE(yaml::parse_int64("+-7", &i));
}

}  // namespace
}  // namespace driftlab
