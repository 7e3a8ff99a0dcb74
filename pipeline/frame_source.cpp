#include "pipeline/frame_source.hpp"

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/stopwatch.hpp"
#include "pipeline/frame_cache_key.hpp"
#include "pipeline/render_stage.hpp"
#include "sim/physics/waves/wave_field.hpp"
#include "sim/render/gl_context.hpp"
#include "sim/render/renderer.hpp"

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

// The producers of frames (a named namespace: FrameSource::Impl, declared in the header, holds
// one).
namespace producers {

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
    f.images = camera->capture_with_truth(truth, depth, depth, &f.moving_px);
    f.blur_samples = camera->last_blur_samples();
    f.render_ms = watch.ms();
    return f;
  }
  RenderInfo info() const { return {renderer.context_description(), renderer.triangles()}; }

  RngStreams rng;
  sim::StereoRenderer renderer;
  std::optional<CameraStage> camera;
};

// What the frames come from, one after the other: the renderer, the cache, or the renderer
// filling the cache.
struct Producer {
  virtual ~Producer() = default;
  virtual std::optional<CapturedFrame> next() = 0;
  RenderInfo info;
};

// The frames the camera delivers: the indices at or after `k` not dropped.
struct Delivered {
  const std::vector<sim::SampleTime>& stamps;
  std::size_t frames;
  std::size_t from(std::size_t k) const {
    while (k < frames && stamps[k].dropped) ++k;
    return k;
  }
};

struct RenderProducer : Producer {
  RenderProducer(const Scenario& sc, const sim::SceneGeometry& scene,
                 const std::vector<FrameTruth>& t, Delivered d, bool depth_)
      : r(sc, scene), truth(t), delivered(d), depth(depth_) {
    info = r.info();
  }
  std::optional<CapturedFrame> next() override {
    next_k = delivered.from(next_k);
    if (next_k >= delivered.frames) return std::nullopt;
    const std::size_t k = next_k++;
    return r.capture(k, truth[k], depth);
  }
  Renderer r;
  const std::vector<FrameTruth>& truth;
  Delivered delivered;
  bool depth;
  std::size_t next_k = 0;
};

// A cache entry replayed; its frames must be the delivered ones (the key names the stamps).
struct ReplayProducer : Producer {
  ReplayProducer(std::unique_ptr<FrameCacheReader> r, Delivered d, RenderInfo i)
      : reader(std::move(r)), delivered(d) {
    info = std::move(i);
  }
  std::optional<CapturedFrame> next() override {
    next_k = delivered.from(next_k);
    if (i == reader->size() && next_k >= delivered.frames) return std::nullopt;
    const Stopwatch watch;
    DRIFTLAB_DEMAND_MSG(i < reader->size(), "frame cache entry has fewer frames than its key");
    CacheFrame c = reader->frame(i++);
    if (c.k != next_k)
      throw UserError(
          fmt::format("frame cache entry {}: frame {} is frame {} of the run, its "
                      "key says {}; remove the entry",
                      reader->dir().string(), i - 1, c.k, next_k));
    ++next_k;
    CapturedFrame f;
    f.k = c.k;
    f.exposure_ms = c.exposure_ms;
    f.blur_samples = c.blur_samples;
    f.moving_px = c.moving_px;
    f.images.left = std::move(c.left);
    f.images.right = std::move(c.right);
    f.render_ms = watch.ms();  // reading and decoding
    return f;
  }
  std::unique_ptr<FrameCacheReader> reader;
  Delivered delivered;
  std::size_t i = 0, next_k = 0;
};

// Rendering, each frame also written into a new entry, published after the last one.
struct FillProducer : Producer {
  FillProducer(std::unique_ptr<RenderProducer> r, const FrameCache& c,
               std::unique_ptr<FrameCache::FillLock> l, const std::string& key, FrameCacheStatus* s)
      : render(std::move(r)), cache(c), lock(std::move(l)), writer(c.fill(key)), status(s) {
    info = render->info;
  }
  std::optional<CapturedFrame> next() override {
    std::optional<CapturedFrame> f = render->next();
    if (f) {
      writer->add(
          {f->k, f->exposure_ms, f->blur_samples, f->moving_px, f->images.left, f->images.right});
      return f;
    }
    if (writer) {
      status->state = writer->commit() ? "filled" : "miss";
      if (status->state == "miss") status->note = "another run published the entry first";
      writer.reset();
      lock.reset();
      cache.evict();
    }
    return std::nullopt;
  }
  std::unique_ptr<RenderProducer> render;
  const FrameCache& cache;
  std::unique_ptr<FrameCache::FillLock> lock;
  std::unique_ptr<FrameCacheWriter> writer;
  FrameCacheStatus* status;
};

}  // namespace producers

using producers::Delivered;
using producers::FillProducer;
using producers::Producer;
using producers::RenderProducer;
using producers::ReplayProducer;

struct FrameSource::Impl {
  const Scenario& sc;
  const sim::SceneGeometry& scene;
  const std::vector<FrameTruth>& truth;
  const std::vector<sim::SampleTime>& stamps;
  std::size_t queue_frames;
  bool depth;
  FrameCacheOptions cache_options;
  std::optional<FrameCache> cache;
  FrameCacheStatus cache_status;
  RenderInfo info;
  std::unique_ptr<Producer> serial;

  // Threaded mode: the render thread fills `queue`; `done` after the last frame or an error.
  std::thread worker;
  std::mutex mutex;
  std::condition_variable changed;
  std::deque<CapturedFrame> queue;
  bool done = false, stop = false, info_ready = false;
  std::exception_ptr error;

  Impl(const Scenario& sc_, const sim::SceneGeometry& scene_, const std::vector<FrameTruth>& t,
       const std::vector<sim::SampleTime>& s, std::size_t q, bool d, FrameCacheOptions c)
      : sc(sc_),
        scene(scene_),
        truth(t),
        stamps(s),
        queue_frames(std::max<std::size_t>(1, q)),
        depth(d),
        cache_options(std::move(c)) {}

  Delivered delivered() const { return {stamps, std::min(truth.size(), stamps.size())}; }

  std::unique_ptr<RenderProducer> render() const {
    return std::make_unique<RenderProducer>(sc, scene, truth, delivered(), depth);
  }

  // The producer of this source's frames: a cached entry when one checks, else the renderer
  // (filling the cache when there is one). Waits while another run fills the same entry.
  std::unique_ptr<Producer> open() {
    if (cache_options.dir.empty()) return render();
    if (depth) {
      cache_status.note = "the frame cache keeps no ground-truth depth or masks";
      return render();
    }
    cache.emplace(cache_options.dir, cache_options.max_bytes);
    const std::string gl = sim::create_gl_context(sc.render.backend)->description();
    const std::string key = frame_cache_key(renderer_identity(gl), sc, scene, truth, stamps);
    cache_status.entry = cache->entry_dir(key).string();
    const RenderInfo replay_info{gl, scene.triangle_count()};
    std::string warning;
    auto found = cache->find(key, &warning);
    std::unique_ptr<FrameCache::FillLock> lock;
    if (!found) {
      lock = cache->lock_fill(key);  // another run filling it: wait, then look again
      found = cache->find(key, warning.empty() ? &warning : nullptr);
    }
    if (!warning.empty()) {
      cache_status.note = warning;
      cache_status.warn = true;
    }
    if (found) {
      cache_status.state = "hit";
      return std::make_unique<ReplayProducer>(std::move(found), delivered(), replay_info);
    }
    return std::make_unique<FillProducer>(render(), *cache, std::move(lock), key, &cache_status);
  }

  void produce() {
    try {
      std::unique_ptr<Producer> p = open();
      {
        const std::lock_guard lock(mutex);
        info = p->info;
        info_ready = true;
      }
      while (std::optional<CapturedFrame> f = p->next()) {
        std::unique_lock lock(mutex);
        changed.wait(lock, [&] { return stop || queue.size() < queue_frames; });
        if (stop) return;
        queue.push_back(std::move(*f));
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
      serial = open();
      info = serial->info;
    }
    return serial->next();
  }
};

FrameSource::FrameSource(const Scenario& sc, const sim::SceneGeometry& scene,
                         const std::vector<FrameTruth>& truth,
                         const std::vector<sim::SampleTime>& stamps, int threads,
                         std::size_t queue_frames, bool depth, const FrameCacheOptions& cache)
    : impl_(std::make_unique<Impl>(sc, scene, truth, stamps, queue_frames, depth, cache)) {
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

FrameCacheStatus FrameSource::cache_status() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->cache_status;
}

}  // namespace driftlab::pipeline
