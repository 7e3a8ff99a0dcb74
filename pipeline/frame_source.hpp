// The frames a run's VOs see, in order: render and camera effects (CameraStage) of every
// delivered frame, on a thread of their own when the run may use more than one, so that frame
// k+1 renders while frame k is matched (the pipelined frame loop of the performance issue).
// The frames, and so every output byte, are the same whatever the thread count: the render
// thread runs the same stage in the same order, and the consumer takes frames in order.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "pipeline/camera_stage.hpp"
#include "pipeline/frame_cache.hpp"
#include "pipeline/scenario.hpp"
#include "sim/render/scene_geometry.hpp"
#include "sim/sensors/clock.hpp"

namespace driftlab::pipeline {

/// One delivered stereo pair and what the frames.csv row says about it.
struct CapturedFrame {
  std::size_t k = 0;         ///< index into the run's frame times
  sim::StereoImages images;  ///< what the camera delivers (rectified, 8-bit)
  double render_ms = 0;      ///< wall-clock time of rendering and camera effects
  double exposure_ms = 0;    ///< the exposure this frame was taken with
  int blur_samples = 1;      ///< renders averaged for its motion blur (CameraStage::blur_samples)
  /// The share of the left image's pixels that show moving things (the scene's movers) at the
  /// centre of the exposure, by sim::StereoRenderer::render_truth's mask; 0 in a scene without
  /// movers (no pass drawn).
  double moving_px = 0;
};

/// What the frame cache did for a source (metrics.json "frame_cache").
struct FrameCacheStatus {
  /// "off" (no cache, or frames it cannot keep), "hit" (replayed), "filled" (rendered and
  /// kept), "miss" (rendered, not kept: `note` says why).
  std::string state = "off";
  std::string entry;  ///< the entry's folder, when there is a cache
  std::string note;   ///< why off or not kept; a broken entry removed (a warning)
  bool warn = false;  ///< `note` is a warning of the run
};

/// What the renderer reports once it has run.
struct RenderInfo {
  std::string context;  ///< GL version and renderer
  std::size_t triangles = 0;
};

class FrameSource {
 public:
  /// Renders `scene` at the camera poses of `truth` (one per frame time), skipping the frames
  /// `stamps` marks dropped. threads >= 2: on a thread of its own, at most `queue_frames`
  /// ahead of the consumer; 1: inside next(). `scene` and `truth` must outlive the source.
  /// depth: each frame also carries the true depth of the left image and its mask of moving
  /// things (images.depth_left, images.moving_left; the frame cache keeps neither, so such a
  /// source renders). `cache`: where frames are kept (an empty folder: nowhere).
  FrameSource(const Scenario& sc, const sim::SceneGeometry& scene,
              const std::vector<FrameTruth>& truth, const std::vector<sim::SampleTime>& stamps,
              int threads, std::size_t queue_frames = 4, bool depth = false,
              const FrameCacheOptions& cache = {});
  ~FrameSource();
  FrameSource(const FrameSource&) = delete;
  FrameSource& operator=(const FrameSource&) = delete;

  /// The next delivered frame, or nothing after the last. Rethrows what the render thread threw.
  std::optional<CapturedFrame> next();
  /// Valid once next() has returned the first frame (or nothing).
  const RenderInfo& info() const;
  /// Final once next() has returned nothing.
  FrameCacheStatus cache_status() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// OpenCV views (no copy) of a frame's images, valid while the image lives; an empty depth
/// image gives an empty matrix.
cv::Mat cv_view(const sim::GrayImage& image);
cv::Mat cv_view(const sim::DepthImage& depth);

/// The threads a run uses: `requested`, or every core when it is 0.
int run_threads(int requested);

}  // namespace driftlab::pipeline
