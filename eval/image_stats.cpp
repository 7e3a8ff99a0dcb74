#include "eval/image_stats.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>

#include "core/error.hpp"
#include "eval/regression.hpp"

namespace driftlab::eval {
namespace {

cv::Mat as_float(const cv::Mat& image) {
  DRIFTLAB_DEMAND_MSG(image.channels() == 1 && (image.depth() == CV_8U || image.depth() == CV_32F),
                      "image_stats: expected one channel, 8-bit or float");
  cv::Mat out;
  image.convertTo(out, CV_32F);
  return out;
}

// Rows either side of a waterline left out of the mirror comparisons: the brightness step from
// bank to water is no reflection, and its gradient, smoothed over a few rows, would swamp one.
constexpr int kWaterlineGap = 6;

double percentile(std::vector<float> values, double p) {
  if (values.empty()) return 0;
  const auto k = static_cast<std::size_t>(p * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

// Signed frequency of DFT index k on an axis of n samples, in cycles per pixel.
double dft_frequency(int k, int n) { return (k <= n / 2 ? k : k - n) / static_cast<double>(n); }

struct GradientStats {
  double median = 0, p90 = 0, p99 = 0, kurtosis = 0;
};

GradientStats gradient_stats(const cv::Mat& image32) {
  cv::Mat gx, gy, magnitude;
  cv::Sobel(image32, gx, CV_32F, 1, 0, 3, 1.0 / 8.0);
  cv::Sobel(image32, gy, CV_32F, 0, 1, 3, 1.0 / 8.0);
  cv::magnitude(gx, gy, magnitude);
  std::vector<float> values(magnitude.begin<float>(), magnitude.end<float>());
  GradientStats g;
  g.median = percentile(values, 0.5);
  g.p90 = percentile(values, 0.9);
  g.p99 = percentile(values, 0.99);
  // Kurtosis of the plain horizontal difference, in doubles (fourth powers of grey levels).
  double sum = 0, n = 0;
  for (int y = 0; y < image32.rows; ++y)
    for (int x = 0; x + 1 < image32.cols; ++x, ++n)
      sum += image32.at<float>(y, x + 1) - image32.at<float>(y, x);
  const double mean = n > 0 ? sum / n : 0;
  double m2 = 0, m4 = 0;
  for (int y = 0; y < image32.rows; ++y)
    for (int x = 0; x + 1 < image32.cols; ++x) {
      const double d = image32.at<float>(y, x + 1) - image32.at<float>(y, x) - mean;
      m2 += d * d;
      m4 += d * d * d * d;
    }
  g.kurtosis = m2 > 0 ? (m4 / n) / ((m2 / n) * (m2 / n)) : 0;
  return g;
}

// Smaller eigenvalue of the 5x5 mean structure tensor of Sobel / 8 gradients, (grey/px)^2.
cv::Mat min_eigenvalue(const cv::Mat& image32) {
  cv::Mat gx, gy;
  cv::Sobel(image32, gx, CV_32F, 1, 0, 3, 1.0 / 8.0);
  cv::Sobel(image32, gy, CV_32F, 0, 1, 3, 1.0 / 8.0);
  cv::Mat a = gx.mul(gx), b = gx.mul(gy), c = gy.mul(gy);
  const cv::Size box(5, 5);
  cv::boxFilter(a, a, CV_32F, box);
  cv::boxFilter(b, b, CV_32F, box);
  cv::boxFilter(c, c, CV_32F, box);
  cv::Mat lambda(image32.size(), CV_32F, cv::Scalar(0));
  const int border = 3;  // the tensor there sees reflected pixels
  for (int y = border; y < image32.rows - border; ++y)
    for (int x = border; x < image32.cols - border; ++x) {
      const double half_trace = 0.5 * (a.at<float>(y, x) + c.at<float>(y, x));
      const double half_diff = 0.5 * (a.at<float>(y, x) - c.at<float>(y, x));
      lambda.at<float>(y, x) = static_cast<float>(
          half_trace - std::sqrt(half_diff * half_diff + b.at<float>(y, x) * b.at<float>(y, x)));
    }
  return lambda;
}

struct CornerStats {
  double per_cell = 0, empty_fraction = 0;
};

// Greedy selection as Shi and Tomasi's "good features": local maxima above the threshold, the
// strongest first, none within min_distance of one already taken; then a count per whole cell.
CornerStats corner_stats(const cv::Mat& image32, const ImageStatsOptions& o) {
  const cv::Mat lambda = min_eigenvalue(image32);
  cv::Mat dilated;
  cv::dilate(lambda, dilated, cv::Mat());
  struct Candidate {
    float strength;
    int x, y;
  };
  std::vector<Candidate> candidates;
  for (int y = 0; y < lambda.rows; ++y)
    for (int x = 0; x < lambda.cols; ++x) {
      const float v = lambda.at<float>(y, x);
      if (v >= o.corner_min_eigen_grey2 && v == dilated.at<float>(y, x))
        candidates.push_back({v, x, y});
    }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& l, const Candidate& r) { return l.strength > r.strength; });
  const int d = std::max(1, o.corner_min_distance_px);
  std::vector<cv::Point> taken;
  cv::Mat occupied(lambda.rows / d + 1, lambda.cols / d + 1, CV_32SC1, cv::Scalar(-1));
  for (const auto& c : candidates) {
    const int gx = c.x / d, gy = c.y / d;
    bool free = true;
    for (int ny = std::max(0, gy - 1); free && ny <= std::min(occupied.rows - 1, gy + 1); ++ny)
      for (int nx = std::max(0, gx - 1); free && nx <= std::min(occupied.cols - 1, gx + 1); ++nx) {
        const int other = occupied.at<int>(ny, nx);
        if (other >= 0 && std::hypot(taken[other].x - c.x, taken[other].y - c.y) < d) free = false;
      }
    if (!free || occupied.at<int>(gy, gx) >= 0) continue;
    occupied.at<int>(gy, gx) = static_cast<int>(taken.size());
    taken.push_back({c.x, c.y});
  }
  const int cells_x = image32.cols / o.cell_px, cells_y = image32.rows / o.cell_px;
  std::vector<int> counts(static_cast<std::size_t>(cells_x * cells_y), 0);
  for (const auto& p : taken) {
    const int cx = p.x / o.cell_px, cy = p.y / o.cell_px;
    if (cx < cells_x && cy < cells_y) ++counts[static_cast<std::size_t>(cy * cells_x + cx)];
  }
  CornerStats s;
  if (counts.empty()) return s;
  s.per_cell = std::accumulate(counts.begin(), counts.end(), 0.0) / counts.size();
  s.empty_fraction =
      static_cast<double>(std::count(counts.begin(), counts.end(), 0)) / counts.size();
  return s;
}

// Correlation of the image above row `axis` with its mirror image below, over rows
// kWaterlineGap..depth either side and columns [x0, x1), each column's mean removed on either
// side: what does not change down a column (a vertical edge, a trunk, a pole) is its own mirror
// image about any row and must not count. 0 where either side lacks texture (variance below
// min_var).
double mirror_ncc(const cv::Mat& im, int axis, int depth, int x0, int x1, double min_var) {
  double cov = 0, vu = 0, vd = 0, n = 0;
  for (int x = x0; x < x1; ++x) {
    double su = 0, sd = 0, suu = 0, sdd = 0, sud = 0, m = 0;
    for (int k = kWaterlineGap; k < depth; ++k, ++m) {
      const double up = im.at<float>(axis - 1 - k, x), down = im.at<float>(axis + k, x);
      su += up;
      sd += down;
      suu += up * up;
      sdd += down * down;
      sud += up * down;
    }
    cov += sud - su * sd / m;
    vu += suu - su * su / m;
    vd += sdd - sd * sd / m;
    n += m;
  }
  return vu >= min_var * n && vd >= min_var * n ? cov / std::sqrt(vu * vd) : 0;
}

// Per column, the row about which the image is most mirror-symmetric (-1: none good enough),
// compared over up to mirror_axis_depth_px rows either side (at least a quarter of that).
std::vector<int> waterline_rows(const cv::Mat& im, const ImageStatsOptions& o) {
  const int half_width = 8, step = 4,
            min_depth = std::max(2 * kWaterlineGap, o.mirror_axis_depth_px / 4);
  const double min_var = o.mirror_min_sd_grey * o.mirror_min_sd_grey;
  const int first =
      std::max(min_depth, o.mirror_axis_min_row > 0 ? o.mirror_axis_min_row : im.rows / 5);
  std::vector<int> axis(static_cast<std::size_t>(im.cols), -1);
  for (int xc = step / 2; xc < im.cols; xc += step) {
    const int x0 = std::max(0, xc - half_width), x1 = std::min(im.cols, xc + half_width + 1);
    double best = o.mirror_axis_min_ncc;
    int best_row = -1;
    for (int a = first; a + min_depth <= im.rows; ++a) {
      const int depth = std::min({o.mirror_axis_depth_px, a, im.rows - a});
      const double ncc = mirror_ncc(im, a, depth, x0, x1, min_var);
      if (ncc > best) best = ncc, best_row = a;
    }
    for (int x = xc - step / 2; x < std::min(im.cols, xc + step / 2 + 1); ++x)
      axis[static_cast<std::size_t>(x)] = best_row;
  }
  return axis;
}

}  // namespace

cv::Mat analysed_image(const cv::Mat& gray, const ImageStatsOptions& o) {
  DRIFTLAB_DEMAND_MSG(gray.type() == CV_8UC1, "analysed_image: expected an 8-bit grey image");
  const double aspect = static_cast<double>(o.width_px) / o.height_px;
  cv::Rect crop(0, 0, gray.cols, gray.rows);
  if (gray.cols > aspect * gray.rows) {
    crop.width = static_cast<int>(std::lround(aspect * gray.rows));
    crop.x = (gray.cols - crop.width) / 2;
  } else {
    crop.height = static_cast<int>(std::lround(gray.cols / aspect));
    crop.y = (gray.rows - crop.height) / 2;
  }
  cv::Mat out;
  if (crop.size() == cv::Size(o.width_px, o.height_px)) return gray(crop).clone();
  cv::resize(gray(crop), out, cv::Size(o.width_px, o.height_px), 0, 0, cv::INTER_AREA);
  return out;
}

SpectrumFit power_spectrum_slope(const cv::Mat& image32, const ImageStatsOptions& o) {
  cv::Mat centred = image32 - cv::mean(image32)[0];
  cv::Mat window;
  cv::createHanningWindow(window, image32.size(), CV_32F);
  cv::Mat spectrum;
  cv::dft(centred.mul(window), spectrum, cv::DFT_COMPLEX_OUTPUT);
  const int bins = o.spectrum_bins;
  const double log_min = std::log10(o.spectrum_min_cycles_px);
  const double log_max = std::log10(o.spectrum_max_cycles_px);
  std::vector<double> power(static_cast<std::size_t>(bins), 0), log_f(power), count(power);
  for (int ky = 0; ky < spectrum.rows; ++ky)
    for (int kx = 0; kx < spectrum.cols; ++kx) {
      const double f =
          std::hypot(dft_frequency(kx, spectrum.cols), dft_frequency(ky, spectrum.rows));
      if (f < o.spectrum_min_cycles_px || f >= o.spectrum_max_cycles_px) continue;
      const auto bin =
          static_cast<std::size_t>((std::log10(f) - log_min) / (log_max - log_min) * bins);
      const cv::Vec2f v = spectrum.at<cv::Vec2f>(ky, kx);
      power[bin] += static_cast<double>(v[0]) * v[0] + static_cast<double>(v[1]) * v[1];
      log_f[bin] += std::log10(f);
      count[bin] += 1;
    }
  std::vector<double> x, y;
  for (std::size_t b = 0; b < power.size(); ++b)
    if (count[b] > 0 && power[b] > 0) {
      x.push_back(log_f[b] / count[b]);
      y.push_back(std::log10(power[b] / count[b]));
    }
  if (x.size() < 3) return {};
  const OlsResult fit = ols(y, {x}, {"log10_f"});  // river paper Eq. (13)'s fit, one regressor
  return {fit.coefficients.at(1).estimate, fit.r2};
}

cv::Mat mirror_mask(const cv::Mat& image32, const ImageStatsOptions& o) {
  const double min_var = o.mirror_min_sd_grey * o.mirror_min_sd_grey;
  const std::vector<int> axis = waterline_rows(image32, o);
  // The image mirrored about each column's waterline, and where that mirror exists.
  cv::Mat mirrored(image32.size(), CV_32F, cv::Scalar(0));
  cv::Mat valid(image32.size(), CV_32F, cv::Scalar(0));
  for (int x = 0; x < image32.cols; ++x) {
    const int a = axis[static_cast<std::size_t>(x)];
    if (a < 0) continue;
    for (int y = a; y < image32.rows && 2 * a - 1 - y >= 0; ++y) {
      mirrored.at<float>(y, x) = image32.at<float>(2 * a - 1 - y, x);
      valid.at<float>(y, x) = 1;
    }
  }
  // 9x9 patches as in mirror_ncc: sums down each column of the patch (9x1), the column's
  // covariance and variances, then summed across the patch (1x9).
  const int half = 4, size = 2 * half + 1;
  auto column_sum = [&](const cv::Mat& m) {
    cv::Mat out;
    cv::boxFilter(m, out, CV_32F, cv::Size(1, size), cv::Point(-1, -1), false);
    return out;
  };
  const cv::Mat si = column_sum(image32), sm = column_sum(mirrored);
  const cv::Mat col_cov = column_sum(image32.mul(mirrored)) - si.mul(sm) / size;
  const cv::Mat col_vi = column_sum(image32.mul(image32)) - si.mul(si) / size;
  const cv::Mat col_vm = column_sum(mirrored.mul(mirrored)) - sm.mul(sm) / size;
  cv::Mat cov, vi, vm, nvalid;
  const cv::Size row(size, 1), box(size, size);
  cv::boxFilter(col_cov, cov, CV_32F, row, cv::Point(-1, -1), false);
  cv::boxFilter(col_vi, vi, CV_32F, row, cv::Point(-1, -1), false);
  cv::boxFilter(col_vm, vm, CV_32F, row, cv::Point(-1, -1), false);
  cv::boxFilter(valid, nvalid, CV_32F, box, cv::Point(-1, -1), false);
  const double n = size * size;
  cv::Mat mask(image32.size(), CV_8U, cv::Scalar(0));
  for (int y = 0; y < image32.rows; ++y)
    for (int x = 0; x < image32.cols; ++x) {
      const int a = axis[static_cast<std::size_t>(x)];
      if (a < 0 || y < a + half + kWaterlineGap || nvalid.at<float>(y, x) < n - 0.5) continue;
      const double v1 = vi.at<float>(y, x), v2 = vm.at<float>(y, x);
      if (v1 < min_var * n || v2 < min_var * n) continue;
      if (cov.at<float>(y, x) / std::sqrt(v1 * v2) >= o.mirror_pixel_min_ncc)
        mask.at<std::uint8_t>(y, x) = 255;
    }
  return mask;
}

ImageStats image_stats(const cv::Mat& image, const ImageStatsOptions& options) {
  const cv::Mat im = as_float(image);
  ImageStats s;
  const SpectrumFit fit = power_spectrum_slope(im, options);
  s.spectrum_slope = fit.slope;
  s.spectrum_fit_r2 = fit.r2;
  const GradientStats g = gradient_stats(im);
  s.gradient_median = g.median;
  s.gradient_p90 = g.p90;
  s.gradient_p99 = g.p99;
  s.derivative_kurtosis = g.kurtosis;
  const CornerStats c = corner_stats(im, options);
  s.corners_per_cell = c.per_cell;
  s.empty_cell_fraction = c.empty_fraction;
  s.mirror_fraction = cv::countNonZero(mirror_mask(im, options)) / static_cast<double>(im.total());
  return s;
}

ImageStats mean_stats(const std::vector<ImageStats>& stats) {
  ImageStats m;
  if (stats.empty()) return m;
  const double n = static_cast<double>(stats.size());
  for (const auto& s : stats) {
    m.spectrum_slope += s.spectrum_slope / n;
    m.spectrum_fit_r2 += s.spectrum_fit_r2 / n;
    m.gradient_median += s.gradient_median / n;
    m.gradient_p90 += s.gradient_p90 / n;
    m.gradient_p99 += s.gradient_p99 / n;
    m.derivative_kurtosis += s.derivative_kurtosis / n;
    m.corners_per_cell += s.corners_per_cell / n;
    m.empty_cell_fraction += s.empty_cell_fraction / n;
    m.mirror_fraction += s.mirror_fraction / n;
  }
  return m;
}

}  // namespace driftlab::eval
