// Sparse stereo visual odometry: our implementation of the StereoScan method (Geiger, Ziegler,
// Stiller 2011; Kitt et al. 2010) as river paper Section 2.3.1 (Kriechbaumer et al. 2015)
// describes it:
//   (i)   5x5 blob and corner masks, non-maximum and non-minimum suppression;
//   (ii)  descriptors of 11x11 horizontal and vertical Sobel responses compared by SAD,
//         circular matching current left -> previous left -> previous right -> current
//         right -> current left; at most 2 matches per 50x50 px bucket;
//   (iii) 3D points of the previous pair by Eq. (1);
//   (iv)  RANSAC (50 x 3 random matches) around Gauss-Newton on the stereo reprojection
//         error of Eq. (2), then a final refinement on the inliers.
// The global pose follows by Eq. (3) (accumulate_pose in vo/stereo_odometry.hpp).
#pragma once

#include <memory>
#include <span>
#include <string>

#include "core/camera.hpp"
#include "core/rng.hpp"
#include "vo/sparse/sparse_options.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::vo {

namespace sparse {
class SharedDetection;
}

/// The sparse VO's matches are StereoOdometry's MatchInfo.
using SparseMatchInfo = MatchInfo;

/// The sparse VO. Not thread-safe; one instance per stream of frames.
class SparseStereoOdometry final : public StereoOdometry {
 public:
  /// Throws UserError when the rig or the options are invalid. `rng` is the stream RANSAC
  /// draws from (e.g. RngStreams::stream("vo.sparse")).
  /// `shared`: detection shared with other sparse VOs of the same images (made with
  /// detection_settings() equal to this VO's); null detects alone. The same results either way.
  SparseStereoOdometry(const StereoRig& rig, const SparseVoOptions& options, Rng rng,
                       std::shared_ptr<sparse::SharedDetection> shared = nullptr);
  ~SparseStereoOdometry() override;

  VoResult process(const StereoFrame& frame) override;
  void reset() override;
  /// "sparse_kf" with keyframes, "sparse" (the river paper's frame-to-frame method) without.
  std::string name() const override { return options().keyframes ? "sparse_kf" : "sparse"; }

  const SparseVoOptions& options() const;
  /// The bucketed circle matches handed to the estimator by the last process() call.
  std::span<const MatchInfo> last_matches() const override;
  /// Features detected in the last left image (diagnostics).
  int last_feature_count() const;

  /// Pairs this VO detected itself and pairs it took from another VO sharing its detection,
  /// since construction.
  struct DetectionCounts {
    long detected = 0;
    long shared = 0;
  };
  DetectionCounts detection_counts() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace driftlab::vo
