// Determinism check shared by the VO tests: two instances on the same stream,
// and one of them again after reset(), give byte-identical results.
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "vo/stereo_odometry.hpp"

namespace driftlab::vo::test {

/// The numbers of a result, in a fixed order, for byte comparisons.
inline void append_result_bytes(const VoResult& r, std::vector<double>* bytes) {
  const auto& q = r.T_prev_curr.quaternion().coeffs();
  const auto& t = r.T_prev_curr.translation();
  bytes->insert(bytes->end(), {q[0], q[1], q[2], q[3], t[0], t[1], t[2], r.mean_inlier_depth_m,
                               static_cast<double>(r.matches), static_cast<double>(r.inliers),
                               static_cast<double>(r.reference_frames_back)});
}

/// `run(vo)` returns the bytes of a whole sequence processed by `vo`.
template <class Vo, class Run>
void expect_same_bytes_across_instances_and_reset(Vo& a, Vo& b, Run run) {
  const std::vector<double> first = run(a);
  const std::vector<double> second = run(b);
  ASSERT_EQ(first.size(), second.size());
  EXPECT_EQ(std::memcmp(first.data(), second.data(), first.size() * sizeof(double)), 0);
  a.reset();
  const std::vector<double> again = run(a);
  ASSERT_EQ(first.size(), again.size());
  EXPECT_EQ(std::memcmp(first.data(), again.data(), first.size() * sizeof(double)), 0);
}

}  // namespace driftlab::vo::test
