// One stereo pair's sparse features, detected once and shared by the sparse VOs of a run that
// detect alike (sparse and sparse_kf with the shipped options): each frame's detection, Sobel
// planes and Lucas-Kanade pyramids are a pure function of the images and a few options, so the
// second VO takes the first one's result instead of computing it again.
#pragma once

#include <opencv2/core.hpp>

#include <deque>
#include <future>
#include <memory>
#include <mutex>
#include <vector>

#include "vo/sparse/features.hpp"
#include "vo/sparse/sparse_options.hpp"

namespace driftlab::vo::sparse {

/// What SparseStereoOdometry detects in one stereo pair.
struct PairFeatures {
  ImageFeatures left, right;
  /// lk_refinement: each image's one-level optical flow pyramid (cv::buildOpticalFlowPyramid,
  /// bordered for the LK window; the left one with its Scharr derivatives). Empty otherwise.
  std::vector<cv::Mat> pyr_left, pyr_right;
};

/// The options a pair's detection depends on. Two VOs may share detection when theirs are equal.
struct DetectionSettings {
  int nms_radius_px = 0;
  int nms_threshold = 0;
  int descriptor_window_px = 0;
  int coarse_features_per_class = 0;
  int bucket_width_px = 0;
  int bucket_height_px = 0;
  bool lk_refinement = false;
  int lk_window_px = 0;
  bool operator==(const DetectionSettings&) const = default;
};
DetectionSettings detection_settings(const SparseVoOptions& options);

/// Detects a pair into a PairFeatures: the features of both images and, when the settings ask
/// for them, the LK pyramids. Holds the detector's scratch buffers.
class PairDetector {
 public:
  PairDetector(int width, int height, const SparseVoOptions& options);
  void detect(const cv::Mat& left, const cv::Mat& right, PairFeatures* out);

 private:
  FeatureDetector detector_;
  DetectionSettings settings_;
};

/// The latest pairs' features for every VO that asks for the same images; thread-safe (a run's
/// VOs process frames side by side, each VO at its own frame: pipeline/vo_pipeline.hpp). The
/// first caller for a pair detects it; a caller with the same images (compared byte for byte)
/// waits for that result. The last kRecentPairs pairs are kept for callers that come later;
/// results live as long as a VO holds them (the reference pair); pairs nobody holds any more
/// are refilled, not reallocated.
class SharedDetection {
 public:
  /// Pairs kept for later callers: more than the frames a run's VOs may be apart
  /// (pipeline/vo_pipeline.hpp's lookahead).
  static constexpr std::size_t kRecentPairs = 8;
  explicit SharedDetection(const DetectionSettings& settings) : settings_(settings) {}
  const DetectionSettings& settings() const { return settings_; }

  struct Got {
    std::shared_ptr<const PairFeatures> features;
    bool detected_here = false;  ///< false: taken from the caller that detected them
  };
  /// The features of (left, right), detected by `detector` unless another caller did.
  Got get(const cv::Mat& left, const cv::Mat& right, PairDetector* detector);
  /// How many pairs were detected and how many were taken from another caller (the guard
  /// counters: a run that shares should take about half).
  long detected() const;
  long shared() const;

 private:
  struct Entry {
    PairFeatures features;
    cv::Mat left, right;  // copies of the images: what later callers compare against
    std::shared_future<void> done;
  };
  std::shared_ptr<Entry> free_entry();  // under mutex_

  DetectionSettings settings_;
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<Entry>> pool_;
  std::deque<std::shared_ptr<Entry>> recent_;  // newest first
  long detected_ = 0, shared_ = 0;
};

}  // namespace driftlab::vo::sparse
