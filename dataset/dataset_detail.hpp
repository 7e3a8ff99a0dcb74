// Helpers shared by the format files of dataset/ (not part of its interface).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "core/se3.hpp"
#include "dataset/dataset.hpp"

namespace driftlab::dataset::detail {

/// The non-empty, non-comment ('#') lines of a text file with their 1-based numbers.
struct TextLine {
  int number = 0;
  std::string text;
};
std::vector<TextLine> data_lines(const std::filesystem::path& path, std::string_view what);

/// A finite number; UserError "PATH:LINE: FIELD: got 'TOKEN', expected a number" otherwise.
double parse_number(std::string_view token, const std::filesystem::path& path, int line,
                    std::string_view field);
/// A non-negative integer time stamp in nanoseconds.
TimeNs parse_stamp_ns(std::string_view token, const std::filesystem::path& path, int line);

/// Writes an 8-bit (or 16-bit) PNG; UserError naming the file when it cannot.
void write_png(const std::filesystem::path& path, const cv::Mat& image);

/// The numbers of a 3x4 or 4x4 matrix, row-major, shortest round-trip text, joined by `sep`.
std::string matrix_text(const Eigen::MatrixXd& m, std::string_view sep);
/// [R | t] of a pose as a 3x4 matrix; its 4x4 homogeneous form.
Eigen::Matrix<double, 3, 4> matrix_3x4(const SE3& T);
Eigen::Matrix4d matrix_4x4(const SE3& T);

/// Moves `from` to `to`, creating to's parent.
void move_file(const std::filesystem::path& from, const std::filesystem::path& to);

// Per-format writers and readers (kitti.cpp, euroc.cpp, tum_rgbd.cpp).
std::unique_ptr<DatasetWriter> make_kitti_writer(const std::filesystem::path& root,
                                                 const ExportCalibration& calibration);
std::unique_ptr<DatasetWriter> make_euroc_writer(const std::filesystem::path& root,
                                                 const ExportCalibration& calibration);
std::unique_ptr<DatasetWriter> make_tum_rgbd_writer(const std::filesystem::path& root,
                                                    const ExportCalibration& calibration);
StereoDataset read_kitti(const std::filesystem::path& root, const ReadOptions& options);
StereoDataset read_euroc(const std::filesystem::path& root);

}  // namespace driftlab::dataset::detail
