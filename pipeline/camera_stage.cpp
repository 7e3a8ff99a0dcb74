#include "pipeline/camera_stage.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <future>
#include <limits>
#include <vector>

#include "core/error.hpp"
#include "pipeline/run.hpp"

namespace driftlab::pipeline {
namespace {

cv::Mat as_mat(sim::GrayImage* img) {
  return cv::Mat(img->height, img->width, CV_8UC1, img->pixels.data());
}

}  // namespace

double run_right_offset_s(const sim::CameraOptions& c, const RngStreams& rng) {
  const double spread_s = c.right_offset_spread_ms * 1e-3;
  const double drawn =
      spread_s > 0 ? rng.stream("camera.right_offset").uniform(-spread_s, spread_s) : 0.0;
  return c.right_offset_ms * 1e-3 + drawn;
}

std::vector<ShutterBand> shutter_bands(int height, double line_delay_s, int bands) {
  DRIFTLAB_DEMAND(height >= 1 && bands >= 1 && bands <= height);
  std::vector<ShutterBand> out;
  out.reserve(static_cast<std::size_t>(bands));
  const int base = height / bands, taller = height % bands;
  int row = 0;
  for (int b = 0; b < bands; ++b) {
    const int end = row + base + (b < taller ? 1 : 0);
    const double centre_row = (row + end - 1) / 2.0;
    out.push_back({row, end, (centre_row - (height - 1) / 2.0) * line_delay_s});
    row = end;
  }
  return out;
}

CameraStage::CameraStage(const Scenario& sc, sim::StereoRenderer* renderer, const RngStreams& rng)
    : renderer_(renderer),
      T_B_C_(camera_mount_T_B_C(sc.sensors.camera.mount)),
      blur_samples_(sc.render.motion_blur_samples),
      blur_step_px_(sc.render.motion_blur_step_px),
      single_sampled_(sc.render.msaa_samples == 1),
      camera_{.fx = sc.sensors.camera.fx_px,
              .fy = sc.sensors.camera.fy_px,
              .cx = sc.sensors.camera.cx_px,
              .cy = sc.sensors.camera.cy_px,
              .width = sc.sensors.camera.width_px,
              .height = sc.sensors.camera.height_px},
      shutter_(sc.sensors.camera.shutter),
      line_delay_s_(sc.sensors.camera.line_delay_us * 1e-6),
      band_step_px_(sc.render.rolling_shutter_step_px),
      max_bands_(sc.render.rolling_shutter_max_bands),
      near_m_(sc.render.rolling_shutter_near_m),
      right_offset_s_(run_right_offset_s(sc.sensors.camera, rng)),
      right_jitter_s_(sc.sensors.camera.right_offset_jitter_ms * 1e-3),
      right_jitter_(rng.stream("camera.right_offset.jitter")),
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

SE3 CameraStage::T_W_C(const FrameTruth& truth, double dt_s) const {
  if (dt_s == 0) return T_W_C(truth);
  return truth.T_W_B * SE3::exp(truth.twist_B * dt_s) * T_B_C_;
}

double CameraStage::corner_motion_px(const SE3& T_a_b, double depth_m) const {
  double motion_px = 0;
  for (const double u : {-0.5, camera_.width - 0.5})
    for (const double v : {-0.5, camera_.height - 0.5}) {
      const Vec3 p_a = T_a_b * camera_.unproject(Eigen::Vector2d(u, v), depth_m);
      if (p_a.z() <= 0) return std::numeric_limits<double>::infinity();  // moved out of view
      motion_px = std::max(motion_px, (camera_.project(p_a) - Eigen::Vector2d(u, v)).norm());
    }
  return motion_px;
}

int CameraStage::rolling_bands(const FrameTruth& truth) const {
  if (shutter_ != sim::Shutter::kRolling || camera_.height <= 1) return 1;
  const double readout_s = (camera_.height - 1) * line_delay_s_;
  const SE3 T_first_last = T_W_C(truth, -readout_s / 2).inverse() * T_W_C(truth, readout_s / 2);
  const double needed = std::ceil(corner_motion_px(T_first_last, near_m_) / band_step_px_);
  const int most = std::min(max_bands_, camera_.height);
  return needed >= most ? most : std::max(1, static_cast<int>(needed));
}

sim::StereoImages CameraStage::render_at(const FrameTruth& truth,
                                         const std::vector<ShutterBand>& bands, double d_s,
                                         bool moving_mask) {
  std::vector<sim::RowBand> left, right;
  for (const ShutterBand& b : bands) {
    const double dl = b.dt_s + d_s, dr = dl + last_right_offset_s_;
    left.push_back({T_W_C(truth, dl), truth.t_s + dl, b.row_begin, b.row_end});
    right.push_back({T_W_C(truth, dr), truth.t_s + dr, b.row_begin, b.row_end});
  }
  return renderer_->render_bands(left, right, moving_mask);
}

sim::StereoImages CameraStage::render_blurred(const FrameTruth& truth, bool moving_mask) {
  const double exposure_s = exposure_ms_ * 1e-3;
  const int samples = blur_samples(truth);
  last_blur_samples_ = samples;
  last_rolling_bands_ = rolling_bands(truth);
  const std::vector<ShutterBand> bands =
      shutter_bands(camera_.height, line_delay_s_, last_rolling_bands_);
  if (samples <= 1) {
    // The left image is the ideal camera at the centre of the exposure: one band at dt 0.
    const bool mask = moving_mask && single_sampled_ && bands.size() == 1 && bands[0].dt_s == 0;
    return render_at(truth, bands, 0.0, mask);
  }
  // Sub-frame instants at the centres of `samples` equal parts of the exposure.
  std::vector<std::uint32_t> sum_left, sum_right;
  sim::StereoImages out;
  for (int s = 0; s < samples; ++s) {
    const double d = ((s + 0.5) / samples - 0.5) * exposure_s;
    sim::StereoImages img = render_at(truth, bands, d);
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

sim::StereoImages CameraStage::capture_with_truth(const FrameTruth& truth, bool depth, bool mask,
                                                  double* moving_px) {
  const bool moving = renderer_->has_moving_things();
  sim::StereoImages img = capture(truth, !depth && (mask || moving));
  *moving_px = 0;
  if (!img.moving_left.pixels.empty()) {
    *moving_px = moving_share(img.moving_left);
    if (!mask) img.moving_left = {};
    return img;
  }
  if (depth || mask || moving) {
    sim::TruthImages t = renderer_->render_truth(T_W_C(truth), truth.t_s);
    *moving_px = moving_share(t.moving);
    if (depth) img.depth_left = std::move(t.depth);
    if (depth || mask) img.moving_left = std::move(t.moving);
  }
  return img;
}

double moving_share(const sim::GrayImage& mask) {
  if (mask.pixels.empty()) return 0;
  const auto n =
      std::count_if(mask.pixels.begin(), mask.pixels.end(), [](std::uint8_t v) { return v != 0; });
  return static_cast<double>(n) / static_cast<double>(mask.pixels.size());
}

sim::StereoImages CameraStage::capture(const FrameTruth& truth, bool moving_mask) {
  last_right_offset_s_ = right_offset_s_;
  if (right_jitter_s_ > 0)
    last_right_offset_s_ += right_jitter_s_ * std::clamp(right_jitter_.normal(), -3.0, 3.0);
  sim::StereoImages img = render_blurred(truth, moving_mask);
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
