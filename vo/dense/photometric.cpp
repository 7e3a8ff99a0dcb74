#include "vo/dense/photometric.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Cholesky>
#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.hpp"
#include "vo/dense/pieces.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::vo::dense {

LevelCamera level_camera(const PinholeCamera& camera, double scale) {
  LevelCamera c;
  c.width = std::max(1, static_cast<int>(std::lround(camera.width * scale)));
  c.height = std::max(1, static_cast<int>(std::lround(camera.height * scale)));
  c.sx = static_cast<double>(c.width) / camera.width;
  c.sy = static_cast<double>(c.height) / camera.height;
  c.fx = camera.fx * c.sx;
  c.fy = camera.fy * c.sy;
  // cv::resize maps destination pixel centres to (x + 0.5) / s - 0.5 in the source.
  c.cx = (camera.cx + 0.5) * c.sx - 0.5;
  c.cy = (camera.cy + 0.5) * c.sy - 0.5;
  return c;
}

Mat26 warp_jacobian(const Vec3& P, double fx, double fy) {
  // Eq. (7): u = fx X / Z + cx, v = fy Y / Z + cy; Eq. (6) for the small motion exp(xi):
  // d(exp(xi) P)/d xi = [I | -hat(P)] at xi = 0.
  const double iz = 1.0 / P.z();
  Eigen::Matrix<double, 2, 3> dpi;
  dpi << fx * iz, 0.0, -fx * P.x() * iz * iz, 0.0, fy * iz, -fy * P.y() * iz * iz;
  Eigen::Matrix<double, 3, 6> dP;
  dP << Mat3::Identity(), -hat(P);
  return dpi * dP;
}

Row6 photometric_jacobian(double gx, double gy, const Vec3& P, double fx, double fy) {
  // Expanded form of [gx gy] * warp_jacobian(P): with g = [gx gy] * d pi / d P,
  // the translation part is g and the rotation part is -g * hat(P) = (P x g)^T.
  const double iz = 1.0 / P.z();
  const double a = gx * fx * iz, b = gy * fy * iz;
  const double c = -(a * P.x() + b * P.y()) * iz;
  Row6 J;
  J << a, b, c, P.y() * c - P.z() * b, P.z() * a - P.x() * c, P.x() * b - P.y() * a;
  return J;
}

void Pyramid::configure(const PinholeCamera& camera, const std::vector<double>& scales) {
  cameras.clear();
  for (const double s : scales) cameras.push_back(level_camera(camera, s));
  images.resize(cameras.size());
}

void Pyramid::build(const cv::Mat& gray8, double blur_sigma_px, bool area_downscaling) {
  DRIFTLAB_DEMAND(!cameras.empty());
  cv::Mat& full = images.back();  // scale 1 (options validation requires it)
  gray8.convertTo(full, CV_32F);
  if (cameras.size() == 1) return;
  const cv::Mat* src = &full;
  if (blur_sigma_px > 0.0) {
    // Kernel truncated at 3 sigma: 19 taps for the paper's sigma of 3.
    const int k = 2 * static_cast<int>(std::ceil(3.0 * blur_sigma_px)) + 1;
    filter_in_row_pieces(full, &blurred, CV_32FC1, [&](const cv::Mat& in, cv::Mat& out) {
      cv::GaussianBlur(in, out, cv::Size(k, k), blur_sigma_px, blur_sigma_px,
                       cv::BORDER_REFLECT_101);
    });
    src = &blurred;
  }
  for (std::size_t l = 0; l + 1 < cameras.size(); ++l)
    cv::resize(*src, images[l], cv::Size(cameras[l].width, cameras[l].height), 0, 0,
               area_downscaling ? cv::INTER_AREA : cv::INTER_LINEAR);
}

namespace {

// The full-resolution pixels [first, last] a level pixel covers along one axis: those whose
// centres lie within half a level pixel of its centre (x + 0.5) / s - 0.5.
void cover(int level_size, int full_size, double s, std::vector<int>* first,
           std::vector<int>* last) {
  first->resize(static_cast<std::size_t>(level_size));
  last->resize(static_cast<std::size_t>(level_size));
  const double half = 0.5 / s;
  for (int i = 0; i < level_size; ++i) {
    const double c = (i + 0.5) / s - 0.5;
    int a = static_cast<int>(std::ceil(c - half + 1e-9));
    int b = static_cast<int>(std::floor(c + half - 1e-9));
    a = std::clamp(a, 0, full_size - 1);
    b = std::clamp(b, a, full_size - 1);
    (*first)[static_cast<std::size_t>(i)] = a;
    (*last)[static_cast<std::size_t>(i)] = b;
  }
}

// Writes the reference pixel (u, v) of a level with gradient (gx, gy), intensity i and
// disparity D [full-resolution px] as point k of `out`: its point by Eq. (1) and its Jacobian
// row, the expanded photometric_jacobian() in float.
inline void set_point(std::size_t k, float u, float v, float gx, float gy, float i, float D,
                      const LevelCamera& c, float baseline_fx, RefLevel* out) {
  // Eq. (1): Z = f B / D, X = Z (p_x - c_x) / f, Y = Z (p_y - c_y) / f (level intrinsics).
  const float Z = baseline_fx / D;
  const float X = Z * (u - static_cast<float>(c.cx)) / static_cast<float>(c.fx);
  const float Y = Z * (v - static_cast<float>(c.cy)) / static_cast<float>(c.fy);
  const float iz = 1.0f / Z;
  const float a = gx * static_cast<float>(c.fx) * iz, b = gy * static_cast<float>(c.fy) * iz;
  const float cz = -(a * X + b * Y) * iz;
  out->points[k] = {X, Y, Z, i};
  out->jacobians[k] = {{a, b, cz, Y * cz - Z * b, Z * a - X * cz, X * b - Y * a, 0.0f, 0.0f}};
}

// The central-difference gradient of level image I at (u, v).
inline void gradient(const cv::Mat& I, int u, int v, float* gx, float* gy) {
  const float* row = I.ptr<float>(v);
  *gx = 0.5f * (row[u + 1] - row[u - 1]);
  *gy = 0.5f * (I.ptr<float>(v + 1)[u] - I.ptr<float>(v - 1)[u]);
}

// Whether a full-resolution pixel of a row above v_end becomes a reference point.
inline bool kept(const RefSelection& selection, float d, float min_d, std::uint8_t textured) {
  return d >= min_d && (!selection.gradient_mask || textured != 0);
}

// The first pass over the full-resolution rows [v0, v1) (1 <= v0, v1 <= H - 1): the texture mask
// and, per row, its textured pixels, those of them with depth and the points it will give.
void count_full_rows(const Pyramid& pyramid, const cv::Mat& disparity,
                     const RefSelection& selection, int v_end, int v0, int v1, Reference* ref) {
  const cv::Mat& I = pyramid.images.back();
  const int W = disparity.cols;
  const float min_d = static_cast<float>(selection.min_disparity_px);
  const float g2_textured = static_cast<float>(selection.min_gradient * selection.min_gradient);
  for (int v = v0; v < v1; ++v) {
    const float* row = I.ptr<float>(v);
    const float* up = I.ptr<float>(v - 1);
    const float* down = I.ptr<float>(v + 1);
    const float* d = disparity.ptr<float>(v);
    std::uint8_t* mask = ref->textured.ptr<std::uint8_t>(v);
    mask[0] = mask[W - 1] = 0;
    int textured = 0, both = 0, points = 0;
    for (int u = 1; u < W - 1; ++u) {
      const float gx = 0.5f * (row[u + 1] - row[u - 1]);
      const float gy = 0.5f * (down[u] - up[u]);
      const std::uint8_t is_textured = gx * gx + gy * gy >= g2_textured ? 1 : 0;
      mask[u] = is_textured;
      textured += is_textured;
      both += is_textured & (d[u] >= min_d ? 1 : 0);
      points += kept(selection, d[u], min_d, is_textured) ? 1 : 0;
    }
    const std::size_t r = static_cast<std::size_t>(v);
    ref->row_textured[r] = textured;
    ref->row_both[r] = both;
    ref->row_points[r] = v < v_end ? points : 0;
  }
}

// The second pass over a full-resolution row v: its points from point k on.
void write_full_row(const Pyramid& pyramid, const cv::Mat& disparity, float fB,
                    const RefSelection& selection, const Reference& ref, int v, std::size_t k,
                    RefLevel* level) {
  const LevelCamera& c = pyramid.cameras.back();
  const cv::Mat& I = pyramid.images.back();
  const float min_d = static_cast<float>(selection.min_disparity_px);
  const float* d = disparity.ptr<float>(v);
  const std::uint8_t* mask = ref.textured.ptr<std::uint8_t>(v);
  for (int u = 1; u < disparity.cols - 1; ++u) {
    if (!kept(selection, d[u], min_d, mask[u])) continue;
    float gx, gy;
    gradient(I, u, v, &gx, &gy);
    level->textured[k] = mask[u];
    set_point(k++, static_cast<float>(u), static_cast<float>(v), gx, gy, I.ptr<float>(v)[u], d[u],
              c, fB, level);
  }
}

// The first pass over rows [v0, v1) of coarse level l: a pixel is kept when its full-resolution
// block has depth everywhere (and, with the mask, texture on half of it); its disparity, the
// block's mean, goes into ref->level_disparity (NaN: not kept), and each row's count into
// ref->row_points.
void count_coarse_rows(const Pyramid& pyramid, std::size_t l, const cv::Mat& disparity,
                       const RefSelection& selection, int v0, int v1, Reference* ref) {
  const LevelCamera& c = pyramid.cameras[l];
  const float min_d = static_cast<float>(selection.min_disparity_px);
  for (int v = v0; v < v1; ++v) {
    const int r0 = ref->row_first[static_cast<std::size_t>(v)];
    const int r1 = ref->row_last[static_cast<std::size_t>(v)];
    float* out = ref->level_disparity.ptr<float>(v);
    int points = 0;
    for (int u = 1; u < c.width - 1; ++u) {
      const int c0 = ref->col_first[static_cast<std::size_t>(u)];
      const int c1 = ref->col_last[static_cast<std::size_t>(u)];
      float sum = 0.0f;
      int n_textured = 0;
      bool all_valid = true;
      for (int y = r0; y <= r1 && all_valid; ++y) {
        const float* d = disparity.ptr<float>(y);
        const std::uint8_t* mask = ref->textured.ptr<std::uint8_t>(y);
        for (int x = c0; x <= c1; ++x) {
          if (!(d[x] >= min_d)) {
            all_valid = false;
            break;
          }
          sum += d[x];
          n_textured += mask[x];
        }
      }
      const int n = (r1 - r0 + 1) * (c1 - c0 + 1);
      const bool keep = all_valid && !(selection.gradient_mask && 2 * n_textured < n);
      out[u] = keep ? sum / static_cast<float>(n) : std::numeric_limits<float>::quiet_NaN();
      points += keep ? 1 : 0;
    }
    ref->row_points[static_cast<std::size_t>(v)] = points;
  }
}

// The second pass over row v of coarse level l: its points from point k on.
void write_coarse_row(const Pyramid& pyramid, std::size_t l, float fB, const Reference& ref, int v,
                      std::size_t k, RefLevel* level) {
  const LevelCamera& c = pyramid.cameras[l];
  const cv::Mat& I = pyramid.images[l];
  const float* D = ref.level_disparity.ptr<float>(v);
  for (int u = 1; u < c.width - 1; ++u) {
    if (std::isnan(D[u])) continue;
    float gx, gy;
    gradient(I, u, v, &gx, &gy);
    set_point(k++, static_cast<float>(u), static_cast<float>(v), gx, gy, I.ptr<float>(v)[u], D[u],
              c, fB, level);
  }
}

// Rows [first, last) of a level in two passes, each in pieces of rows on OpenCV's threads:
// count(v0, v1) sets ref->row_points of its rows, then write(v, k) writes row v's points from
// point k on (rows without points are skipped), so the points lie in row order, as a serial
// pass would append them.
template <class Count, class Write>
void select_rows(int first, int last, bool with_textured, Reference* ref, RefLevel* level,
                 const Count& count, const Write& write) {
  const std::size_t rows = static_cast<std::size_t>(std::max(last - first, 0));
  for_each_piece(rows, kRowPieces, [&](std::size_t, std::size_t r0, std::size_t r1) {
    count(first + static_cast<int>(r0), first + static_cast<int>(r1));
  });
  std::size_t total = 0;
  for (int v = first; v < last; ++v) {
    ref->row_offset[static_cast<std::size_t>(v)] = total;
    total += static_cast<std::size_t>(ref->row_points[static_cast<std::size_t>(v)]);
  }
  level->resize(total, with_textured);
  for_each_piece(rows, kRowPieces, [&](std::size_t, std::size_t r0, std::size_t r1) {
    for (int v = first + static_cast<int>(r0); v < first + static_cast<int>(r1); ++v)
      if (ref->row_points[static_cast<std::size_t>(v)] > 0)
        write(v, ref->row_offset[static_cast<std::size_t>(v)]);
  });
}

// The per-row scratch of ref for a level of `rows` rows.
void size_rows(std::size_t rows, Reference* ref) {
  ref->row_points.assign(rows, 0);
  ref->row_offset.assign(rows, 0);
}

}  // namespace

void build_reference(const Pyramid& pyramid, const cv::Mat& disparity, double baseline_fx,
                     const RefSelection& selection, Reference* out) {
  DRIFTLAB_DEMAND(disparity.type() == CV_32FC1);
  const int W = disparity.cols, H = disparity.rows;
  const std::size_t n_levels = pyramid.cameras.size();
  DRIFTLAB_DEMAND(pyramid.cameras.back().width == W && pyramid.cameras.back().height == H);
  out->levels.resize(n_levels);
  const float min_d = static_cast<float>(selection.min_disparity_px);
  const float fB = static_cast<float>(baseline_fx);

  std::vector<int> valid(static_cast<std::size_t>(H), 0);
  for_each_row(H, [&](int v) {
    const float* d = disparity.ptr<float>(v);
    int n = 0;
    for (int u = 0; u < W; ++u) n += d[u] >= min_d ? 1 : 0;
    valid[static_cast<std::size_t>(v)] = n;
  });
  out->valid_depth_pixels = 0;
  for (const int n : valid) out->valid_depth_pixels += n;

  // Full resolution first (the last level; validation requires scale 1 last): one disparity
  // per pixel, the texture mask and the frame's texture statistics.
  out->textured.create(H, W, CV_8UC1);
  out->textured.row(0).setTo(0);
  out->textured.row(H - 1).setTo(0);
  const int v_end =
      std::min(H - 1, static_cast<int>(std::ceil((1.0 - selection.lower_mask_fraction) * H)));
  size_rows(static_cast<std::size_t>(H), out);
  out->row_textured.assign(static_cast<std::size_t>(H), 0);
  out->row_both.assign(static_cast<std::size_t>(H), 0);
  select_rows(
      1, H - 1, /*with_textured=*/true, out, &out->levels.back(),
      [&](int v0, int v1) { count_full_rows(pyramid, disparity, selection, v_end, v0, v1, out); },
      [&](int v, std::size_t k) {
        write_full_row(pyramid, disparity, fB, selection, *out, v, k, &out->levels.back());
      });
  out->textured_pixels = out->textured_depth_pixels = 0;
  for (const int n : out->row_textured) out->textured_pixels += n;
  for (const int n : out->row_both) out->textured_depth_pixels += n;

  for (std::size_t l = 0; l + 1 < n_levels; ++l) {
    const LevelCamera& c = pyramid.cameras[l];
    cover(c.width, W, c.sx, &out->col_first, &out->col_last);
    cover(c.height, H, c.sy, &out->row_first, &out->row_last);
    const int level_end =
        std::min(c.height - 1,
                 static_cast<int>(std::ceil((1.0 - selection.lower_mask_fraction) * c.height)));
    size_rows(static_cast<std::size_t>(c.height), out);
    out->level_disparity.create(c.height, c.width, CV_32FC1);
    select_rows(
        1, level_end, /*with_textured=*/false, out, &out->levels[l],
        [&](int v0, int v1) { count_coarse_rows(pyramid, l, disparity, selection, v0, v1, out); },
        [&](int v, std::size_t k) {
          write_coarse_row(pyramid, l, fB, *out, v, k, &out->levels[l]);
        });
  }
}

double Aligner::cost_scale() const {
  // With w = (nu + 1) / (nu + r^2 / sigma^2), the surrogate r^2 / (1 + r^2 / (nu sigma^2)) of
  // warp() is nu / (nu + 1) w r^2.
  return options_.robust ? options_.t_dof / (options_.t_dof + 1.0) : 1.0;
}

namespace {

// What warp() needs of the motion and the level: R, t, the intrinsics and the image.
struct WarpModel {
  float R[3][3], t[3];
  float fx, fy, cx, cy, umax, vmax;
  const float* base;
  std::size_t stride;

  // Eq. (6), G = R P + T, then Eq. (7), and Eq. (9)'s residual: the current image at the warped
  // pixel (Eq. (8)), bilinear, minus the reference; NaN where the point leaves the image or
  // falls behind the camera.
  float residual(const RefPoint& p) const {
    const float qx = R[0][0] * p.x + R[0][1] * p.y + R[0][2] * p.z + t[0];
    const float qy = R[1][0] * p.x + R[1][1] * p.y + R[1][2] * p.z + t[1];
    const float qz = R[2][0] * p.x + R[2][1] * p.y + R[2][2] * p.z + t[2];
    const float iz = 1.0f / qz;
    const float u = fx * qx * iz + cx, v = fy * qy * iz + cy;
    if (!(qz > 1e-3f) || !(u >= 0.0f && u < umax && v >= 0.0f && v < vmax))
      return std::numeric_limits<float>::quiet_NaN();
    const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
    const float ax = u - static_cast<float>(x0), ay = v - static_cast<float>(y0);
    const float* q0 = base + static_cast<std::size_t>(y0) * stride + x0;
    const float* q1 = q0 + stride;
    const float top = q0[0] + ax * (q0[1] - q0[0]);
    const float bottom = q1[0] + ax * (q1[1] - q1[0]);
    return top + ay * (bottom - top) - p.intensity;
  }

#if CV_SIMD128
  // residual() of the four points from p, lane by lane in the same operations (OpenCV's
  // universal intrinsics): the same bytes. Returns how many are finite.
  int residuals4(const RefPoint* p, float* out) const {
    using V = cv::v_float32x4;
    V X = cv::v_load(&p[0].x), Y = cv::v_load(&p[1].x), Z = cv::v_load(&p[2].x),
      I = cv::v_load(&p[3].x);
    cv::v_transpose4x4(V(X), V(Y), V(Z), V(I), X, Y, Z, I);
    auto row = [&](int k) {
      return cv::v_setall_f32(R[k][0]) * X + cv::v_setall_f32(R[k][1]) * Y +
             cv::v_setall_f32(R[k][2]) * Z + cv::v_setall_f32(t[k]);
    };
    const V qx = row(0), qy = row(1), qz = row(2);
    const V iz = cv::v_setall_f32(1.0f) / qz, zero = cv::v_setzero_f32();
    const V u = cv::v_setall_f32(fx) * qx * iz + cv::v_setall_f32(cx);
    const V v = cv::v_setall_f32(fy) * qy * iz + cv::v_setall_f32(cy);
    const V ok = (qz > cv::v_setall_f32(1e-3f)) & (u >= zero) & (u < cv::v_setall_f32(umax)) &
                 (v >= zero) & (v < cv::v_setall_f32(vmax));
    const V us = cv::v_select(ok, u, zero), vs = cv::v_select(ok, v, zero);
    const cv::v_int32x4 x0 = cv::v_trunc(us), y0 = cv::v_trunc(vs);
    const V ax = us - cv::v_cvt_f32(x0), ay = vs - cv::v_cvt_f32(y0);
    const cv::v_int32x4 at = y0 * cv::v_setall_s32(static_cast<int>(stride)) + x0;
    const V a00 = cv::v_lut(base, at), a01 = cv::v_lut(base + 1, at);
    const V a10 = cv::v_lut(base + stride, at), a11 = cv::v_lut(base + stride + 1, at);
    const V top = a00 + ax * (a01 - a00), bottom = a10 + ax * (a11 - a10);
    const V r = top + ay * (bottom - top) - I;
    cv::v_store(out,
                cv::v_select(ok, r, cv::v_setall_f32(std::numeric_limits<float>::quiet_NaN())));
    return std::popcount(static_cast<unsigned>(cv::v_signmask(ok)));
  }
#endif
};

WarpModel warp_model(const cv::Mat& image, const LevelCamera& cam, const SE3& T) {
  WarpModel m;
  const Eigen::Matrix3f R = T.rotation().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m.R[r][c] = R(r, c);
    m.t[r] = t(r);
  }
  m.fx = static_cast<float>(cam.fx);
  m.fy = static_cast<float>(cam.fy);
  m.cx = static_cast<float>(cam.cx);
  m.cy = static_cast<float>(cam.cy);
  m.umax = static_cast<float>(image.cols - 1);
  m.vmax = static_cast<float>(image.rows - 1);
  m.base = image.ptr<float>(0);
  m.stride = image.step1();
  return m;
}

int residuals_of(const WarpModel& m, const RefPoint* points, std::size_t n, bool lanes,
                 float* out) {
  int used = 0;
  std::size_t i = 0;
#if CV_SIMD128
  for (; lanes && i + 4 <= n; i += 4) used += m.residuals4(points + i, out + i);
#else
  static_cast<void>(lanes);
#endif
  for (; i < n; ++i) {
    out[i] = m.residual(points[i]);
    used += out[i] == out[i] ? 1 : 0;
  }
  return used;
}

}  // namespace

int warp_residuals(const RefPoint* points, std::size_t n, const cv::Mat& image,
                   const LevelCamera& cam, const SE3& T, bool lanes, float* out) {
  DRIFTLAB_DEMAND(image.type() == CV_32FC1);
  return residuals_of(warp_model(image, cam, T), points, n, lanes, out);
}

int Aligner::warp(const RefLevel& level, const cv::Mat& image, const LevelCamera& cam, const SE3& T,
                  double sigma2, std::vector<float>* residuals, double* cost) const {
  const std::vector<RefPoint>& points = level.points;
  residuals->resize(points.size());
  const WarpModel m = warp_model(image, cam, T);
  float* out = residuals->data();
  // The step-acceptance cost: r^2 (least squares) or a bounded surrogate of the
  // t-distribution's negative log-likelihood with the same quadratic core (its log would cost
  // more than the warp itself).
  const float inv_nu_s2 =
      options_.robust ? static_cast<float>(1.0 / (options_.t_dof * std::max(sigma2, 1e-12))) : 0.0f;
  constexpr std::size_t kBlock = 1024;
  const std::size_t n_blocks = (points.size() + kBlock - 1) / kBlock;
  std::vector<float> block_cost(n_blocks);
  std::vector<int> block_used(n_blocks);
  for_each_block(points.size(), kBlock, [&](std::size_t b, std::size_t begin, std::size_t end) {
    const int used =
        residuals_of(m, points.data() + begin, end - begin, /*lanes=*/true, out + begin);
    // A separate branch-free pass over the block, so that it vectorises.
    float sum = 0.0f;
    for (std::size_t k = begin; k < end; ++k) {
      const float r = out[k];
      const float rho = r * r / (1.0f + r * r * inv_nu_s2);
      sum += r == r ? rho : 0.0f;  // NaN: not compared
    }
    block_cost[b] = sum;
    block_used[b] = used;
  });
  double sum = 0.0;
  int used = 0;
  for (std::size_t b = 0; b < n_blocks; ++b) {
    sum += block_cost[b];
    used += block_used[b];
  }
  *cost = sum / std::max(used, 1);
  return used;
}

double Aligner::estimate_sigma2(const std::vector<float>& residuals, int used,
                                double sigma2) const {
  // Kerl et al. 2013, Eq. (14): sigma^2 = 1/n sum r^2 (nu + 1) / (nu + (r / sigma)^2), a fixed
  // point iterated from the previous scale; 1% is far below what changes the weights.
  const float nf = static_cast<float>(options_.t_dof);
  constexpr double kFloor = 1e-4;  // (0.01 grey)^2: exact alignments have zero residuals
  constexpr std::size_t kBlock = 1024;
  std::vector<float> block_sum((residuals.size() + kBlock - 1) / kBlock);
  sigma2 = std::max(sigma2, kFloor);
  for (int it = 0; it < 5; ++it) {
    const float inv = static_cast<float>(1.0 / sigma2);
    for_each_block(residuals.size(), kBlock,
                   [&](std::size_t b, std::size_t begin, std::size_t end) {
                     float block = 0.0f;
                     for (std::size_t i = begin; i < end; ++i) {
                       const float r = residuals[i];
                       const float term = r * r * (nf + 1.0f) / (nf + r * r * inv);
                       block += r == r ? term : 0.0f;  // NaN: not compared
                     }
                     block_sum[b] = block;
                   });
    double sum = 0.0;
    for (const float block : block_sum) sum += block;
    const double next = std::max(sum / std::max(used, 1), kFloor);
    const bool done = std::abs(next - sigma2) < 1e-2 * sigma2;
    sigma2 = next;
    if (done) break;
  }
  return sigma2;
}

void Aligner::normal_equations(const RefLevel& level, const std::vector<float>& residuals,
                               double sigma2, Normal* n) const {
  // Per point, with a = J[0..3] and b = (J[4], J[5], r, 0): the products w a a_c, w b a_c
  // (c < 4) and w b b_c (c < 3) hold every entry of w [J r]^T [J r] once, in 11 packet
  // multiply-adds. Sums run in float over blocks of points and in double across blocks: float
  // alone loses digits over 300k points, double alone halves the throughput. The blocks are
  // added in order, so the bytes are fixed.
  using P4 = Eigen::Array<float, 4, 1>;
  struct BlockSums {
    P4 lo[4], hi[7];
  };
  const float nu = static_cast<float>(options_.t_dof);
  const float inv = options_.robust ? static_cast<float>(1.0 / sigma2) : 0.0f;
  const bool robust = options_.robust;
  const std::size_t n_points = level.size();
  constexpr std::size_t kBlock = 256;
  std::vector<BlockSums> blocks((n_points + kBlock - 1) / kBlock);
  for_each_block(n_points, kBlock, [&](std::size_t k, std::size_t begin, std::size_t end) {
    P4 lo[4], hi[7];
    for (P4& x : lo) x.setZero();
    for (P4& x : hi) x.setZero();
    for (std::size_t i = begin; i < end; ++i) {
      const float r = residuals[i];
      if (std::isnan(r)) continue;
      // Kerl et al. 2013: w = (nu + 1) / (nu + (r / sigma)^2); 1 for plain least squares.
      const float w = robust ? (nu + 1.0f) / (nu + r * r * inv) : 1.0f;
      const float* J = level.jacobians[i].J;
      const P4 a = Eigen::Map<const P4, Eigen::Aligned16>(J);
      P4 b = Eigen::Map<const P4, Eigen::Aligned16>(J + 4);
      b[2] = r;
      const P4 wa = w * a, wb = w * b;
      for (int c = 0; c < 4; ++c) {
        lo[c] += wa * a[c];
        hi[c] += wb * a[c];
      }
      for (int c = 0; c < 3; ++c) hi[4 + c] += wb * b[c];
    }
    for (int c = 0; c < 4; ++c) blocks[k].lo[c] = lo[c];
    for (int c = 0; c < 7; ++c) blocks[k].hi[c] = hi[c];
  });
  double lo_sum[4][4] = {}, hi_sum[7][4] = {};
  for (const BlockSums& block : blocks) {
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 4; ++k) lo_sum[c][k] += block.lo[c][k];
    for (int c = 0; c < 7; ++c)
      for (int k = 0; k < 4; ++k) hi_sum[c][k] += block.hi[c][k];
  }
  for (int a = 0; a < 4; ++a)
    for (int c = 0; c < 4; ++c) n->H[a][c] = lo_sum[c][a];
  for (int k = 0; k < 2; ++k) {
    for (int c = 0; c < 4; ++c) n->H[4 + k][c] = n->H[c][4 + k] = hi_sum[c][k];
    for (int m = 0; m < 2; ++m) n->H[4 + k][4 + m] = hi_sum[4 + m][k];
  }
  for (int c = 0; c < 6; ++c) n->b[c] = hi_sum[c][2];
  n->wrr = hi_sum[6][2];
}

AlignSummary Aligner::align(const Reference& ref, const Pyramid& current,
                            const AlignOptions& options, SE3* T_curr_prev) {
  DRIFTLAB_DEMAND(ref.levels.size() == current.images.size());
  DRIFTLAB_DEMAND(options.max_iterations.size() == current.images.size());
  options_ = options;
  AlignSummary s;
  SE3 T = *T_curr_prev;
  constexpr int kMinPoints = 6;
  double sigma2 = 1.0;
  const std::size_t n_levels = ref.levels.size();
  for (std::size_t l = 0; l < n_levels; ++l) {
    const RefLevel& level = ref.levels[l];
    const cv::Mat& image = current.images[l];
    const LevelCamera& cam = current.cameras[l];
    const bool finest = l + 1 == n_levels;
    double c = 0.0;
    int used = warp(level, image, cam, T, sigma2, &res_, &c);
    if (used < kMinPoints) {
      if (!finest) continue;  // a coarse level can be empty; the finer ones decide
      s.failure = "too few reference pixels project into the current image";
      return s;
    }
    Normal ne;
    if (options.robust) {
      // A fresh scale per level: blur makes the coarse levels' residuals smaller.
      double mean2 = 0.0;
      for (const float r : res_)
        if (!std::isnan(r)) mean2 += static_cast<double>(r) * r;
      sigma2 = estimate_sigma2(res_, used, mean2 / used);
    }
    normal_equations(level, res_, sigma2, &ne);
    c = cost_scale() * ne.wrr / used;
    double lambda = options.initial_lambda;
    for (int it = 0; it < options.max_iterations[l]; ++it) {
      ++s.iterations;
      Eigen::Matrix<double, 6, 6> A;
      Vec6 rhs;
      for (int a = 0; a < 6; ++a) {
        rhs[a] = ne.b[a];
        for (int b = 0; b < 6; ++b) A(a, b) = ne.H[a][b];
        // Marquardt's scaling: damp each parameter by its own curvature.
        A(a, a) += lambda * ne.H[a][a];
      }
      const Vec6 xi = A.ldlt().solve(rhs);
      if (!xi.allFinite()) break;
      const bool converged = xi.norm() < options.step_tolerance;
      const bool last = converged || it + 1 == options.max_iterations[l];
      // Inverse compositional update: T <- T exp(xi)^-1.
      const SE3 T_try = T * SE3::exp(xi).inverse();
      double c_try = 0.0;
      const int used_try = warp(level, image, cam, T_try, sigma2, &res_try_, &c_try);
      if (used_try >= kMinPoints && c_try < c) {
        T = T_try;
        std::swap(res_, res_try_);
        used = used_try;
        c = c_try;
        // The level ends here: no next step needs the normal equations.
        if (!last) {
          if (options.robust) sigma2 = estimate_sigma2(res_, used, sigma2);
          normal_equations(level, res_, sigma2, &ne);
          c = cost_scale() * ne.wrr / used;
        }
        lambda = std::max(lambda * 0.1, 1e-12);
      } else {
        lambda = std::max(lambda * 10.0, 1e-6);
      }
      if (converged) break;
    }
    if (finest) {
      // Statistics of the final motion, from the residuals of the accepted state.
      s.used = used;
      const float thr = static_cast<float>(options.inlier_residual);
      const Eigen::Matrix3f R = T.rotation().cast<float>();
      const Eigen::Vector3f t = T.translation().cast<float>();
      double depth = 0.0, sq = 0.0;
      for (std::size_t i = 0; i < level.size(); ++i) {
        const float r = res_[i];
        if (std::isnan(r)) continue;
        sq += static_cast<double>(r) * r;
        const bool textured = level.textured[i] != 0;
        s.textured_used += textured ? 1 : 0;
        if (std::abs(r) > thr) continue;
        ++s.inliers;
        s.textured_inliers += textured ? 1 : 0;
        const RefPoint& p = level.points[i];
        depth += R(2, 0) * p.x + R(2, 1) * p.y + R(2, 2) * p.z + t.z();
      }
      s.mean_inlier_depth_m = s.inliers > 0 ? depth / s.inliers : 0.0;
      s.rms_residual = std::sqrt(sq / used);
      s.sigma = options.robust ? std::sqrt(sigma2) : 0.0;
    }
  }
  if (!::driftlab::vo::detail::is_finite(T)) {
    s.failure = "motion estimate not finite";
    return s;
  }
  s.ok = true;
  *T_curr_prev = T;
  return s;
}

}  // namespace driftlab::vo::dense
