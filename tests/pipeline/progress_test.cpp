// The frame loop's progress line.
#include "pipeline/progress.hpp"

#include <gtest/gtest.h>

namespace driftlab::pipeline {
namespace {

TEST(Progress, LineShowsFramesRateAndEta) {
  // 50 of 100 frames in 10 s: 5 frames/s, 10 s to go.
  const std::string bar = Progress::line("render+vo", 50, 100, 10.0, true);
  EXPECT_NE(bar.find("[############            ]"), std::string::npos) << bar;
  EXPECT_NE(bar.find("50/100 frames"), std::string::npos) << bar;
  EXPECT_NE(bar.find("5.0/s"), std::string::npos) << bar;
  EXPECT_NE(bar.find("ETA 0:10"), std::string::npos) << bar;
  const std::string plain = Progress::line("render+vo", 100, 100, 3725.0, false);
  EXPECT_EQ(plain.find('['), std::string::npos) << plain;
  EXPECT_NE(plain.find("elapsed 1:02:05"), std::string::npos) << plain;
  EXPECT_NE(plain.find("ETA 0:00"), std::string::npos) << plain;
  // Nothing done yet: no rate, no estimate.
  EXPECT_NE(Progress::line("x", 0, 10, 0.0, false).find("ETA --:--"), std::string::npos);
}

}  // namespace
}  // namespace driftlab::pipeline
