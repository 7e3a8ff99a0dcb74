#include "pipeline/camera_stage.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <future>
#include <vector>

#include "core/error.hpp"
#include "pipeline/run.hpp"

namespace driftlab::pipeline {
namespace {

cv::Mat as_mat(sim::GrayImage* img) {
  return cv::Mat(img->height, img->width, CV_8UC1, img->pixels.data());
}

}  // namespace

CameraStage::CameraStage(const Scenario& sc, sim::StereoRenderer* renderer, const RngStreams& rng)
    : renderer_(renderer),
      T_B_C_(camera_mount_T_B_C(sc.sensors.camera.mount)),
      blur_samples_(sc.render.motion_blur_samples),
      blur_step_px_(sc.render.motion_blur_step_px),
      camera_{.fx = sc.sensors.camera.fx_px,
              .fy = sc.sensors.camera.fy_px,
              .cx = sc.sensors.camera.cx_px,
              .cy = sc.sensors.camera.cy_px,
              .width = sc.sensors.camera.width_px,
              .height = sc.sensors.camera.height_px},
      exposure_ms_(sc.sensors.camera.exposure_ms),
      auto_exposure_(sc.sensors.camera.auto_exposure),
      left_noise_(sc.sensors.camera, rng, "camera.left"),
      right_noise_(sc.sensors.camera, rng, "camera.right") {
  DRIFTLAB_DEMAND(renderer_ != nullptr);
  renderer_->set_right_camera(sim::true_T_left_right(sc.sensors.camera));
  if (sc.sensors.camera.lens_distortion.enabled) lens_.emplace(sc.sensors.camera);
  if (auto_exposure_.enabled)
    exposure_ms_ =
        std::clamp(exposure_ms_, auto_exposure_.min_exposure_ms, auto_exposure_.max_exposure_ms);
}

int CameraStage::blur_samples(const FrameTruth& truth) const {
  const double exposure_s = exposure_ms_ * 1e-3;
  if (blur_samples_ <= 1 || exposure_s <= 0) return 1;
  if (blur_step_px_ <= 0) return blur_samples_;
  // The camera's rotation over the exposure, C(start) -> C(end): a ray r_C of the start is
  // R^T r_C at the end.
  const Vec3 w_C = T_B_C_.quaternion().conjugate() * truth.twist_B.tail<3>();
  const Mat3 R_end_start = so3_exp(w_C * exposure_s).conjugate().toRotationMatrix();
  double motion_px = 0;
  for (const double u : {-0.5, camera_.width - 0.5})
    for (const double v : {-0.5, camera_.height - 0.5}) {
      const Vec3 ray = camera_.unproject(Eigen::Vector2d(u, v), 1.0);
      const Vec3 turned = R_end_start * ray;
      if (turned.z() <= 0) return blur_samples_;  // turned out of view
      motion_px = std::max(motion_px, (camera_.project(turned) - Eigen::Vector2d(u, v)).norm());
    }
  const double needed = std::ceil(motion_px / blur_step_px_);
  return needed >= blur_samples_ ? blur_samples_ : std::max(1, static_cast<int>(needed));
}

sim::StereoImages CameraStage::render_blurred(const FrameTruth& truth) {
  const double exposure_s = exposure_ms_ * 1e-3;
  const int samples = blur_samples(truth);
  last_blur_samples_ = samples;
  if (samples <= 1) return renderer_->render(T_W_C(truth), truth.t_s, false);
  // Sub-frame instants at the centres of `samples` equal parts of the exposure.
  std::vector<std::uint32_t> sum_left, sum_right;
  sim::StereoImages out;
  for (int s = 0; s < samples; ++s) {
    const double d = ((s + 0.5) / samples - 0.5) * exposure_s;
    const SE3 T_W_B = truth.T_W_B * SE3::exp(truth.twist_B * d);
    sim::StereoImages img = renderer_->render(T_W_B * T_B_C_, truth.t_s + d, false);
    if (s == 0) {
      sum_left.assign(img.left.pixels.size(), 0);
      sum_right.assign(img.right.pixels.size(), 0);
      out = std::move(img);
      for (std::size_t i = 0; i < sum_left.size(); ++i) sum_left[i] = out.left.pixels[i];
      for (std::size_t i = 0; i < sum_right.size(); ++i) sum_right[i] = out.right.pixels[i];
      continue;
    }
    for (std::size_t i = 0; i < sum_left.size(); ++i) sum_left[i] += img.left.pixels[i];
    for (std::size_t i = 0; i < sum_right.size(); ++i) sum_right[i] += img.right.pixels[i];
  }
  // Rounded mean (integer arithmetic: the same bytes on every machine).
  const auto n = static_cast<std::uint32_t>(samples);
  for (std::size_t i = 0; i < sum_left.size(); ++i)
    out.left.pixels[i] = static_cast<std::uint8_t>((sum_left[i] + n / 2) / n);
  for (std::size_t i = 0; i < sum_right.size(); ++i)
    out.right.pixels[i] = static_cast<std::uint8_t>((sum_right[i] + n / 2) / n);
  return out;
}

sim::StereoImages CameraStage::capture(const FrameTruth& truth) {
  sim::StereoImages img = render_blurred(truth);
  // Lens and noise of the two cameras are independent (separate streams):
  // the left one runs on a second thread, the bytes are the same either way.
  auto process = [this](sim::GrayImage* gray, sim::CameraImageNoise* noise) {
    cv::Mat m = as_mat(gray);
    if (lens_) lens_->distort(&m);
    noise->apply(&m, exposure_ms_);
    if (lens_) {
      lens_->rectify(&m);
      if (m.data != gray->pixels.data()) m.copyTo(as_mat(gray));  // a remap may reallocate
    }
  };
  auto left = std::async(std::launch::async, process, &img.left, &left_noise_);
  process(&img.right, &right_noise_);
  left.get();
  if (auto_exposure_.enabled) {
    std::uint64_t sum = 0;  // integer sum: the same mean on every machine
    for (std::uint8_t v : img.left.pixels) sum += v;
    exposure_ms_ = sim::next_auto_exposure_ms(
        auto_exposure_, exposure_ms_,
        static_cast<double>(sum) / static_cast<double>(img.left.pixels.size()));
  }
  return img;
}

}  // namespace driftlab::pipeline
