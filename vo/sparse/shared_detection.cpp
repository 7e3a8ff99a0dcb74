#include "vo/sparse/shared_detection.hpp"

#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <cstring>
#include <exception>
#include <utility>

namespace driftlab::vo::sparse {

namespace {

// Same size, type and bytes.
bool same_image(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  const std::size_t row_bytes = static_cast<std::size_t>(a.cols) * a.elemSize();
  for (int y = 0; y < a.rows; ++y)
    if (std::memcmp(a.ptr(y), b.ptr(y), row_bytes) != 0) return false;
  return true;
}

}  // namespace

DetectionSettings detection_settings(const SparseVoOptions& o) {
  return {
      o.nms_radius_px,   o.nms_threshold,    o.descriptor_window_px, o.coarse_features_per_class,
      o.bucket_width_px, o.bucket_height_px, o.lk_refinement,        o.lk_window_px};
}

PairDetector::PairDetector(int width, int height, const SparseVoOptions& options)
    : detector_(width, height, options), settings_(detection_settings(options)) {}

void PairDetector::detect(const cv::Mat& left, const cv::Mat& right, PairFeatures* out) {
  detector_.detect(left, &out->left);
  detector_.detect(right, &out->right);
  if (settings_.lk_refinement) {  // into the buffers out already has: no allocation
    const cv::Size window(settings_.lk_window_px, settings_.lk_window_px);
    cv::buildOpticalFlowPyramid(left, out->pyr_left, window, 0, /*withDerivatives=*/true);
    cv::buildOpticalFlowPyramid(right, out->pyr_right, window, 0, /*withDerivatives=*/false);
  } else {
    out->pyr_left.clear();
    out->pyr_right.clear();
  }
}

std::shared_ptr<SharedDetection::Entry> SharedDetection::free_entry() {
  // An entry only the pool holds is free: entries are handed out under mutex_ alone, so no
  // other thread can take one between this check and its reuse.
  for (auto& e : pool_)
    if (e.use_count() == 1 && std::find(recent_.begin(), recent_.end(), e) == recent_.end())
      return e;
  pool_.push_back(std::make_shared<Entry>());
  return pool_.back();
}

SharedDetection::Got SharedDetection::get(const cv::Mat& left, const cv::Mat& right,
                                          PairDetector* detector) {
  std::shared_ptr<Entry> entry;
  std::shared_future<void> done;
  std::promise<void> promise;
  bool mine = false;
  {
    std::lock_guard lock(mutex_);
    const auto found = std::find_if(recent_.begin(), recent_.end(), [&](const auto& e) {
      return same_image(left, e->left) && same_image(right, e->right);
    });
    if (found != recent_.end()) {
      entry = *found;
      ++shared_;
    } else {
      entry = free_entry();
      left.copyTo(entry->left);
      right.copyTo(entry->right);
      entry->done = promise.get_future().share();
      recent_.push_front(entry);
      if (recent_.size() > kRecentPairs) recent_.pop_back();
      mine = true;
      ++detected_;
    }
    done = entry->done;
  }
  if (mine) {
    try {
      detector->detect(left, right, &entry->features);
    } catch (...) {
      promise.set_exception(std::current_exception());
      std::lock_guard lock(mutex_);
      recent_.erase(std::remove(recent_.begin(), recent_.end(), entry), recent_.end());
      throw;
    }
    promise.set_value();
  } else {
    done.get();  // rethrows the detecting caller's error
  }
  // The aliasing constructor: the features, kept alive by their entry.
  return {std::shared_ptr<const PairFeatures>(entry, &entry->features), mine};
}

long SharedDetection::detected() const {
  std::lock_guard lock(mutex_);
  return detected_;
}

long SharedDetection::shared() const {
  std::lock_guard lock(mutex_);
  return shared_;
}

}  // namespace driftlab::vo::sparse
