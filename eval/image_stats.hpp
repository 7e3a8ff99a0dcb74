// Image statistics that decide how a VO sees a scene, for comparing the twin's frames with real
// photographs (the twin-fidelity issue): the power spectrum's slope, the gradient distribution,
// the density of corners per 50x50 px cell and the share of the image that is a mirror image.
#pragma once

#include <opencv2/core.hpp>

#include <vector>

namespace driftlab::eval {

struct ImageStatsOptions {
  int width_px = 1024;  // analysed size: an image of another aspect is centre-cropped to this
  int height_px = 768;  // aspect, then area-resized (the river paper's Bumblebee2: 1024x768)
  // Power spectrum fit range, spatial frequency in cycles per pixel.
  double spectrum_min_cycles_px = 8.0 / 768.0;  // 8 cycles over the image height
  double spectrum_max_cycles_px = 0.25;         // above: the camera's and renderer's filtering
  int spectrum_bins = 20;
  int cell_px = 50;                    // the sparse VO's bucket (river paper Section 2.3.1)
  double corner_min_eigen_grey2 = 25;  // smaller structure-tensor eigenvalue, (grey/px)^2
  int corner_min_distance_px = 5;      // two corners closer than this are one
  int mirror_axis_min_row = 0;         // rows searched for the waterline; 0: a fifth down
  int mirror_axis_depth_px = 150;      // rows either side compared to find the waterline
  double mirror_axis_min_ncc = 0.5;    // a column's best waterline below this: no mirror
  double mirror_pixel_min_ncc = 0.6;   // 9x9 correlation with the mirrored patch
  double mirror_min_sd_grey = 0.75;    // SD down a patch's columns: flat patches (sky on calm
                                       // water) are not counted
};

struct ImageStats {
  // Slope of log10 power against log10 spatial frequency, radially averaged (natural images:
  // about -2; van der Schaaf and van Hateren 1996), and the fit's R^2.
  double spectrum_slope = 0;
  double spectrum_fit_r2 = 0;
  // Gradient magnitude (Sobel / 8, grey levels per pixel): median, 90th and 99th percentile.
  double gradient_median = 0;
  double gradient_p90 = 0;
  double gradient_p99 = 0;
  // Kurtosis of the horizontal difference I(x+1) - I(x): 3 for Gaussian noise, far higher for
  // natural images (sparse edges on smooth areas).
  double derivative_kurtosis = 0;
  // Shi-Tomasi corners (smaller eigenvalue of the 5x5 structure tensor above
  // corner_min_eigen_grey2, at least corner_min_distance_px apart) per whole 50x50 cell, and
  // the share of cells with none (the sparse VO keeps 2 per cell).
  double corners_per_cell = 0;
  double empty_cell_fraction = 0;
  // Share of the image whose 9x9 neighbourhood is a textured mirror image, about a per-column
  // waterline, of the image above it (reflections on water). Each column's mean is removed
  // before comparing: vertical structure (edges, trunks, poles) is its own mirror image.
  double mirror_fraction = 0;
};

/// The image analysed: grey, centre-cropped to the options' aspect and area-resized to its size.
/// `gray` is 8-bit, one channel.
cv::Mat analysed_image(const cv::Mat& gray, const ImageStatsOptions& options);

/// Every statistic of one image already at the analysed size (CV_8U or CV_32F, one channel).
ImageStats image_stats(const cv::Mat& image, const ImageStatsOptions& options);

/// The parts, each one step of image_stats.
struct SpectrumFit {
  double slope = 0;
  double r2 = 0;
};
SpectrumFit power_spectrum_slope(const cv::Mat& image32, const ImageStatsOptions& options);
/// Mask (CV_8U, 255 where mirror-like) of the mirror detector.
cv::Mat mirror_mask(const cv::Mat& image32, const ImageStatsOptions& options);

/// The mean of each field over several images.
ImageStats mean_stats(const std::vector<ImageStats>& stats);

}  // namespace driftlab::eval
