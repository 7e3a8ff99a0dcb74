#include "pipeline/tracking.hpp"

#include <gtest/gtest.h>

namespace driftlab::pipeline {
namespace {

vo::VoResult result(bool valid, std::string reason = "") {
  vo::VoResult r;
  r.valid = valid;
  r.reason = std::move(reason);
  return r;
}

// Ten frames at 10 Hz, 1 m apart along x: the first has nothing to match, 4-6 fail, 7 is
// dropped by the camera, 9 fails on its own.
struct Fixture {
  std::vector<vo::VoResult> results;
  Trajectory gt;
  Fixture() {
    for (int k = 0; k < 10; ++k) {
      gt.push_back({k * 100'000'000LL, SE3(Quat::Identity(), Vec3(k, 0, 0))});
      if (k == 0)
        results.push_back(result(false, "first frame"));
      else if (k >= 4 && k <= 6)
        results.push_back(result(false, "too few PnP inliers"));
      else if (k == 7)
        results.push_back(result(false, "frame dropped"));
      else if (k == 9)
        results.push_back(result(false, "motion estimate not finite"));
      else
        results.push_back(result(true));
    }
  }
};

TEST(Tracking, CountsLostFramesByReasonAndFindsTheStretches) {
  const Fixture f;
  const TrackingSummary s = summarize_tracking(f.results, f.gt);
  EXPECT_EQ(s.frames, 8u);  // 1-9 without the dropped 7
  EXPECT_EQ(s.lost, 4u);
  EXPECT_EQ(s.dropped, 1u);
  EXPECT_EQ(s.reasons.at("too few PnP inliers"), 3u);
  EXPECT_EQ(s.reasons.at("motion estimate not finite"), 1u);
  EXPECT_EQ(s.reasons.count("first frame"), 0u);
  ASSERT_EQ(s.stretches.size(), 2u);
  EXPECT_EQ(s.stretches[0].first, 4u);
  EXPECT_EQ(s.stretches[0].frames(), 3u);
  EXPECT_DOUBLE_EQ(s.stretches[0].track_m, 4.0);
  EXPECT_EQ(s.stretches[0].t_end_ns, 600'000'000LL);
  EXPECT_EQ(s.stretches[1].first, 9u);
  EXPECT_EQ(s.longest()->first, 4u);
  const auto r = s.tracking_record();
  EXPECT_EQ(r.lost_frames, 4u);
  EXPECT_DOUBLE_EQ(r.lost_fraction, 0.5);
  EXPECT_EQ(r.longest_stretch_frames, 3u);
  EXPECT_EQ(r.stretches[0].reason, "too few PnP inliers");
}

TEST(Tracking, WarnsOnlyForAStretchAsLongAsTheThreshold) {
  const Fixture f;
  const TrackingSummary s = summarize_tracking(f.results, f.gt);
  EXPECT_EQ(tracking_warning("pnp", s), "");  // 0.2 s < 1 s
  const std::string w = tracking_warning("pnp", s, 0.2);
  EXPECT_NE(w.find("pnp lost track for 3 frames (0.2 s) from t = 0.4 s, 4.0 m along the "
                   "track: too few PnP inliers"),
            std::string::npos)
      << w;
  EXPECT_EQ(tracking_warning("pnp",
                             summarize_tracking({result(false, "first frame"), result(true)},
                                                Trajectory(f.gt.begin(), f.gt.begin() + 2)),
                             0.0),
            "");
  const std::string table = tracking_table_markdown({"pnp"}, {s});
  EXPECT_NE(
      table.find("| pnp | 8 | 4 (50.0 %) | 2 | 3 | t 0.4 s, 4.0 m | too few PnP inliers (3) |"),
      std::string::npos)
      << table;
}

}  // namespace
}  // namespace driftlab::pipeline
