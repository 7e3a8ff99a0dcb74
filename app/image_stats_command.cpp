#include "app/image_stats_command.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iostream>
#include <string_view>

#include "app/cli_main.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "dataset/dataset.hpp"
#include "eval/image_stats.hpp"

namespace fs = std::filesystem;

namespace driftlab::app {
namespace {

// One argument: LABEL=PATH or PATH, a file or a folder of images.
struct Input {
  std::string label;
  std::vector<fs::path> files;
};

bool is_image(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".ppm";
}

Input collect(const std::string& arg, int per_folder) {
  Input in;
  std::string path = arg;
  if (const auto eq = arg.find('='); eq != std::string::npos && eq > 0) {
    in.label = arg.substr(0, eq);
    path = arg.substr(eq + 1);
  }
  if (fs::is_regular_file(path)) {
    if (in.label.empty()) in.label = fs::path(path).stem().string();
    in.files.push_back(path);
    return in;
  }
  if (!fs::is_directory(path))
    throw UserError(fmt::format("imagestats: {}: no such file or folder", path));
  if (in.label.empty()) in.label = path;
  std::vector<fs::path> all;
  for (const auto& e : fs::directory_iterator(path))
    if (e.is_regular_file() && is_image(e.path())) all.push_back(e.path());
  std::sort(all.begin(), all.end());
  const std::size_t n = all.size(), wanted = static_cast<std::size_t>(per_folder);
  if (per_folder == 0 || n <= wanted) {
    in.files = all;
  } else {  // evenly spaced, the first and the last included
    for (std::size_t i = 0; i < wanted; ++i)
      in.files.push_back(all[wanted == 1 ? 0 : i * (n - 1) / (wanted - 1)]);
  }
  if (in.files.empty())
    throw UserError(fmt::format(
        "imagestats: {}: no images (expected .png, .jpg, .jpeg, .pgm or .ppm files)", path));
  return in;
}

// WIDTHxHEIGHT, each 1-5 digits.
eval::ImageStatsOptions parse_size(const std::string& size) {
  eval::ImageStatsOptions o;
  const auto x = size.find('x');
  const auto digits = [](std::string_view v) {
    return !v.empty() && v.size() <= 5 &&
           std::all_of(v.begin(), v.end(), [](unsigned char c) { return std::isdigit(c); });
  };
  const std::string_view whole(size);
  if (x == std::string::npos || !digits(whole.substr(0, x)) || !digits(whole.substr(x + 1)))
    throw UsageError(fmt::format("--size: got '{}', expected WIDTHxHEIGHT", size));
  o.width_px = std::stoi(size.substr(0, x));
  o.height_px = std::stoi(size.substr(x + 1));
  if (o.width_px < 200 || o.height_px < 150)
    throw UsageError(
        fmt::format("--size: got {}, expected at least 200x150 (the mirror search compares "
                    "{} rows either side of a waterline)",
                    size, o.mirror_axis_depth_px));
  o.spectrum_min_cycles_px = 8.0 / o.height_px;
  return o;
}

nlohmann::json to_json(const eval::ImageStats& s) {
  return {{"spectrum_slope", s.spectrum_slope},     {"spectrum_fit_r2", s.spectrum_fit_r2},
          {"gradient_median", s.gradient_median},   {"gradient_p90", s.gradient_p90},
          {"gradient_p99", s.gradient_p99},         {"derivative_kurtosis", s.derivative_kurtosis},
          {"corners_per_cell", s.corners_per_cell}, {"empty_cell_fraction", s.empty_cell_fraction},
          {"mirror_fraction", s.mirror_fraction}};
}

std::string markdown_row(const std::string& label, std::size_t n, const eval::ImageStats& s) {
  return fmt::format(
      "| {} | {} | {:.2f} ({:.3f}) | {:.1f} / {:.1f} / {:.1f} | {:.1f} | {:.2f} | "
      "{:.0f} % | {:.1f} % |\n",
      label, n, s.spectrum_slope, s.spectrum_fit_r2, s.gradient_median, s.gradient_p90,
      s.gradient_p99, s.derivative_kurtosis, s.corners_per_cell, 100 * s.empty_cell_fraction,
      100 * s.mirror_fraction);
}

// The first analysed image of each input, a third of its size, three to a row, labelled, its
// mirror-like pixels tinted blue.
cv::Mat montage(const std::vector<std::pair<std::string, cv::Mat>>& firsts,
                const eval::ImageStatsOptions& options) {
  std::vector<cv::Mat> tiles;
  for (const auto& [label, image] : firsts) {
    cv::Mat tile;
    cv::resize(image, tile, cv::Size(image.cols / 3, image.rows / 3), 0, 0, cv::INTER_AREA);
    cv::cvtColor(tile, tile, cv::COLOR_GRAY2BGR);
    // Mirror-like pixels tinted blue.
    cv::Mat mask, image32;
    image.convertTo(image32, CV_32F);
    cv::resize(eval::mirror_mask(image32, options), mask, tile.size(), 0, 0, cv::INTER_NEAREST);
    cv::Mat tinted = tile.clone();
    tinted.setTo(cv::Scalar(255, 120, 0), mask);
    cv::addWeighted(tile, 0.6, tinted, 0.4, 0, tile);
    cv::putText(tile, label, {6, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.55, {0, 0, 0}, 3);
    cv::putText(tile, label, {6, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.55, {0, 230, 255}, 1);
    tiles.push_back(tile);
  }
  const std::size_t per_row = std::min<std::size_t>(3, tiles.size());
  while (tiles.size() % per_row != 0) tiles.push_back(cv::Mat::zeros(tiles[0].size(), CV_8UC3));
  std::vector<cv::Mat> rows;
  for (std::size_t i = 0; i < tiles.size(); i += per_row) {
    cv::Mat row;
    cv::hconcat(std::vector<cv::Mat>(tiles.begin() + static_cast<std::ptrdiff_t>(i),
                                     tiles.begin() + static_cast<std::ptrdiff_t>(i + per_row)),
                row);
    rows.push_back(row);
  }
  cv::Mat out;
  cv::vconcat(rows, out);
  return out;
}

}  // namespace

ImageStatsCommand::ImageStatsCommand(CLI::App& app) {
  cmd_ = app.add_subcommand(
      "imagestats",
      "Image statistics a VO depends on (power spectrum slope, gradients, corners per 50x50 "
      "cell, mirror-like share) for photographs and rendered frames side by side");
  cmd_->add_option("INPUT", inputs_,
                   "Image files or folders of images, each optionally LABEL=PATH; a folder is one "
                   "row (the mean over its images)")
      ->required();
  cmd_->add_option("--size", size_,
                   "Analysed size WIDTHxHEIGHT: other aspects are centre-cropped, then "
                   "area-resized")
      ->capture_default_str();
  cmd_->add_option("--per-folder", per_folder_,
                   "Images taken from each folder, evenly spaced in name order (0 = all)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd_->add_option("--out", out_, "Write the Markdown table to this file (default: stdout)");
  cmd_->add_option("--json", json_, "Also write every image's statistics as JSON");
  cmd_->add_option(
      "--montage", montage_,
      "Also write each input's first image as analysed, labelled, mirror-like pixels tinted "
      "(.png or .jpg)");
}

std::optional<int> ImageStatsCommand::dispatch() const {
  if (!cmd_->parsed()) return std::nullopt;
  return run();
}

int ImageStatsCommand::run() const {
  const eval::ImageStatsOptions options = parse_size(size_);
  if (!montage_.empty()) {
    const std::string ext = fs::path(montage_).extension().string();
    if (ext != ".png" && ext != ".jpg" && ext != ".jpeg")
      throw UsageError(fmt::format(
          "--montage: got '{}', expected a name ending in .png, .jpg or .jpeg", montage_));
  }
  std::vector<Input> inputs;
  for (const auto& arg : inputs_) inputs.push_back(collect(arg, per_folder_));
  std::string table =
      "| images | n | spectrum slope (R^2) | gradient median / p90 / p99 (grey/px) | "
      "kurtosis of dI/dx | corners per 50x50 cell | cells without a corner | mirror-like |\n"
      "|---|---|---|---|---|---|---|---|\n";
  nlohmann::json json = nlohmann::json::object();
  std::vector<std::pair<std::string, cv::Mat>> firsts;  // each input's first image, once
  std::vector<fs::path> shown;
  for (const auto& in : inputs) {
    std::vector<eval::ImageStats> stats;
    nlohmann::json images = nlohmann::json::array();
    for (const auto& file : in.files) {
      const cv::Mat image = eval::analysed_image(dataset::read_gray(file), options);
      if (&file == &in.files.front() &&
          std::find(shown.begin(), shown.end(), file) == shown.end()) {
        firsts.emplace_back(in.label, image);
        shown.push_back(file);
      }
      stats.push_back(eval::image_stats(image, options));
      images.push_back({{"file", file.string()}, {"stats", to_json(stats.back())}});
    }
    const eval::ImageStats mean = eval::mean_stats(stats);
    table += markdown_row(in.label, stats.size(), mean);
    json[in.label] = {{"mean", to_json(mean)}, {"images", images}};
  }
  if (!json_.empty()) write_file_atomic(json_, json.dump(2) + "\n");
  if (!montage_.empty()) {
    std::vector<unsigned char> bytes;
    cv::imencode(fs::path(montage_).extension().string(), montage(firsts, options), bytes);
    write_file_atomic(montage_, std::string(bytes.begin(), bytes.end()));
  }
  if (out_.empty()) {
    std::cout << table;
  } else {
    write_file_atomic(out_, table);
    std::cerr << "driftlab imagestats: wrote " << out_ << "\n";
  }
  return 0;
}

}  // namespace driftlab::app
