#include "pipeline/frame_source.hpp"

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/stopwatch.hpp"
#include "pipeline/render_stage.hpp"
#include "sim/render/renderer.hpp"
#include "sim/waves/wave_field.hpp"

namespace driftlab::pipeline {

cv::Mat cv_view(const sim::GrayImage& img) {
  return cv::Mat(img.height, img.width, CV_8UC1, const_cast<std::uint8_t*>(img.pixels.data()));
}

cv::Mat cv_view(const sim::DepthImage& d) {
  if (d.depth_m.empty()) return {};
  return cv::Mat(d.height, d.width, CV_32FC1, const_cast<float*>(d.depth_m.data()));
}

int run_threads(int requested) {
  if (requested > 0) return requested;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

namespace {

// The render stage proper: the renderer, its scene, and the camera effects, all created and
// used on one thread (a GL context belongs to the thread that made it current).
struct Renderer {
  Renderer(const Scenario& sc, const sim::SceneGeometry& scene)
      : rng(sc.seed), renderer(rig_of(sc.sensors.camera), sc.render) {
    renderer.upload(scene);
    set_water_surface(&renderer, sc);
    camera.emplace(sc, &renderer, rng);
  }
  CapturedFrame capture(std::size_t k, const FrameTruth& truth, bool depth) {
    CapturedFrame f;
    f.k = k;
    const Stopwatch watch;
    f.exposure_ms = camera->exposure_ms();  // this frame's (auto exposure)
    f.images = camera->capture(truth);
    f.blur_samples = camera->last_blur_samples();
    if (depth)  // ground truth: the ideal pinhole depth at the centre of the exposure
      f.images.depth_left = renderer.render(camera->T_W_C(truth), truth.t_s, true).depth_left;
    f.render_ms = watch.ms();
    return f;
  }
  RenderInfo info() const { return {renderer.context_description(), renderer.triangles()}; }

  RngStreams rng;
  sim::StereoRenderer renderer;
  std::optional<CameraStage> camera;
};

}  // namespace

struct FrameSource::Impl {
  const Scenario& sc;
  const sim::SceneGeometry& scene;
  const std::vector<FrameTruth>& truth;
  const std::vector<sim::SampleTime>& stamps;
  std::size_t queue_frames;
  bool depth;
  RenderInfo info;
  std::size_t next_k = 0;  // serial mode: the next frame index to look at
  std::unique_ptr<Renderer> serial;

  // Threaded mode: the render thread fills `queue`; `done` after the last frame or an error.
  std::thread worker;
  std::mutex mutex;
  std::condition_variable changed;
  std::deque<CapturedFrame> queue;
  bool done = false, stop = false, info_ready = false;
  std::exception_ptr error;

  Impl(const Scenario& sc_, const sim::SceneGeometry& scene_, const std::vector<FrameTruth>& t,
       const std::vector<sim::SampleTime>& s, std::size_t q, bool d)
      : sc(sc_),
        scene(scene_),
        truth(t),
        stamps(s),
        queue_frames(std::max<std::size_t>(1, q)),
        depth(d) {}

  std::size_t frames() const { return std::min(truth.size(), stamps.size()); }

  // The next delivered frame index at or after k, or frames() when there is none.
  std::size_t delivered_from(std::size_t k) const {
    while (k < frames() && stamps[k].dropped) ++k;
    return k;
  }

  void produce() {
    try {
      Renderer r(sc, scene);
      {
        const std::lock_guard lock(mutex);
        info = r.info();
        info_ready = true;
      }
      for (std::size_t k = delivered_from(0); k < frames(); k = delivered_from(k + 1)) {
        CapturedFrame f = r.capture(k, truth[k], depth);
        std::unique_lock lock(mutex);
        changed.wait(lock, [&] { return stop || queue.size() < queue_frames; });
        if (stop) return;
        queue.push_back(std::move(f));
        changed.notify_all();
      }
    } catch (...) {
      const std::lock_guard lock(mutex);
      error = std::current_exception();
    }
    const std::lock_guard lock(mutex);
    done = true;
    changed.notify_all();
  }

  std::optional<CapturedFrame> next_threaded() {
    std::unique_lock lock(mutex);
    changed.wait(lock, [&] { return !queue.empty() || done; });
    if (!queue.empty()) {
      CapturedFrame f = std::move(queue.front());
      queue.pop_front();
      changed.notify_all();
      return f;
    }
    if (error) std::rethrow_exception(error);
    return std::nullopt;
  }

  std::optional<CapturedFrame> next_serial() {
    if (!serial) {
      serial = std::make_unique<Renderer>(sc, scene);
      info = serial->info();
    }
    next_k = delivered_from(next_k);
    if (next_k >= frames()) return std::nullopt;
    const std::size_t k = next_k++;
    return serial->capture(k, truth[k], depth);
  }
};

FrameSource::FrameSource(const Scenario& sc, const sim::SceneGeometry& scene,
                         const std::vector<FrameTruth>& truth,
                         const std::vector<sim::SampleTime>& stamps, int threads,
                         std::size_t queue_frames, bool depth)
    : impl_(std::make_unique<Impl>(sc, scene, truth, stamps, queue_frames, depth)) {
  if (threads >= 2) impl_->worker = std::thread([this] { impl_->produce(); });
}

FrameSource::~FrameSource() {
  if (!impl_->worker.joinable()) return;
  {
    const std::lock_guard lock(impl_->mutex);
    impl_->stop = true;
  }
  impl_->changed.notify_all();
  impl_->worker.join();
}

std::optional<CapturedFrame> FrameSource::next() {
  return impl_->worker.joinable() ? impl_->next_threaded() : impl_->next_serial();
}

const RenderInfo& FrameSource::info() const {
  if (impl_->worker.joinable()) {
    const std::lock_guard lock(impl_->mutex);
    DRIFTLAB_DEMAND_MSG(impl_->info_ready || impl_->done, "FrameSource::info before any frame");
  }
  return impl_->info;
}

}  // namespace driftlab::pipeline
