#include "scenes/photographs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include <fmt/core.h>
#include <openssl/evp.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/error.hpp"
#include "scenes/assets.hpp"

namespace driftlab::scenes {

namespace {

constexpr const char* kFetchHint =
    "run scripts/fetch-materials (it downloads Debian 12's ufoai-textures package and extracts "
    "the photographs), or set scene.river_reach.photographs: false for procedural textures";

std::vector<std::string> split_tabs(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t begin = 0;
  for (std::size_t end; (end = line.find('\t', begin)) != std::string::npos; begin = end + 1)
    fields.push_back(line.substr(begin, end - begin));
  fields.push_back(line.substr(begin));
  return fields;
}

bool is_sha256_hex(const std::string& s) {
  return s.size() == 64 && std::all_of(s.begin(), s.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

PhotographEntry parse_manifest_row(const std::string& path, int line_no, const std::string& line) {
  const std::vector<std::string> f = split_tabs(line);
  if (f.size() != 6)
    throw UserError(
        fmt::format("{} line {}: {} tab-separated fields, expected 6 (kind, sha256, "
                    "source, quarter_turns, licence, credit)",
                    path, line_no, f.size()));
  if (f[3].size() != 1 || f[3][0] < '0' || f[3][0] > '3')
    throw UserError(fmt::format("{} line {}: field quarter_turns: '{}', expected 0, 1, 2 or 3",
                                path, line_no, f[3]));
  PhotographEntry e{f[0], f[1], f[2], f[3][0] - '0', f[4], f[5], line_no};
  if (!is_sha256_hex(e.sha256))
    throw UserError(fmt::format("{} line {}: field sha256: '{}' is not 64 lower-case hex digits",
                                path, line_no, e.sha256));
  const std::string ext = std::filesystem::path(e.source).extension().string();
  if (ext != ".jpg" && ext != ".png")
    throw UserError(fmt::format("{} line {}: field source: '{}' is not a .jpg or .png file", path,
                                line_no, e.source));
  return e;
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// One step of the reduction: each pixel the rounded mean of a 2x2 block.
cv::Mat halve(const cv::Mat& src) {
  cv::Mat dst(src.rows / 2, src.cols / 2, CV_8UC1);
  for (int y = 0; y < dst.rows; ++y)
    for (int x = 0; x < dst.cols; ++x) {
      const int s = src.at<std::uint8_t>(2 * y, 2 * x) + src.at<std::uint8_t>(2 * y, 2 * x + 1) +
                    src.at<std::uint8_t>(2 * y + 1, 2 * x) +
                    src.at<std::uint8_t>(2 * y + 1, 2 * x + 1);
      dst.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>((s + 2) / 4);
    }
  return dst;
}

}  // namespace

std::string PhotographEntry::file_name() const {
  return kind + std::filesystem::path(source).extension().string();
}

std::vector<PhotographEntry> photograph_manifest() {
  const std::string path = shipped_asset("photographs.tsv");
  std::ifstream in(path);
  if (!in)
    throw UserError(
        fmt::format("photograph manifest '{}': cannot be read{}", path, shipped_asset_hint()));
  std::vector<PhotographEntry> rows;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (line.empty() || line[0] == '#') continue;
    rows.push_back(parse_manifest_row(path, line_no, line));
  }
  return rows;
}

std::string materials_dir() {
  if (const char* env = std::getenv("DRIFTLAB_MATERIALS"); env && *env) return env;
  if (const char* xdg = std::getenv("XDG_DATA_HOME"); xdg && *xdg)
    return (std::filesystem::path(xdg) / "driftlab/materials").string();
  const char* home = std::getenv("HOME");
  return (std::filesystem::path(home && *home ? home : ".") / ".local/share/driftlab/materials")
      .string();
}

std::string sha256_hex(const std::string& bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), digest, &n, EVP_sha256(), nullptr) != 1)
    throw InternalError("sha256_hex: OpenSSL's EVP_Digest failed");
  std::string hex;
  for (unsigned int i = 0; i < n; ++i) hex += fmt::format("{:02x}", digest[i]);
  return hex;
}

double mean_gray(const sim::Texture& t) {
  double sum = 0;
  for (const std::uint8_t p : t.pixels) sum += p;
  return t.pixels.empty() ? 0.0 : sum / static_cast<double>(t.pixels.size());
}

sim::Texture load_photograph(TextureKind kind, double mean_gray_target, int max_edge_px) {
  const std::string name(texture_kind_name(kind));
  const std::vector<PhotographEntry> manifest = photograph_manifest();
  const auto row = std::find_if(manifest.begin(), manifest.end(),
                                [&](const PhotographEntry& e) { return e.kind == name; });
  if (row == manifest.end())
    throw UserError(
        fmt::format("no photograph of '{}' in {}", name, shipped_asset("photographs.tsv")));
  const std::string path = (std::filesystem::path(materials_dir()) / row->file_name()).string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw UserError(fmt::format("photograph '{}' ({}) is missing: {}", path, name, kFetchHint));
  const std::string bytes = read_bytes(path);
  if (const std::string got = sha256_hex(bytes); got != row->sha256)
    throw UserError(fmt::format(
        "photograph '{}': SHA-256 {}, expected {} (ufoai-textures' {}, photographs.tsv line {}): "
        "{}",
        path, got, row->sha256, row->source, row->line, kFetchHint));
  cv::Mat gray = cv::imdecode(
      cv::Mat(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data())),
      cv::IMREAD_GRAYSCALE);
  if (gray.empty() || gray.cols < 16 || gray.rows < 16)
    throw UserError(fmt::format("photograph '{}': cannot be decoded as a JPEG or PNG image", path));
  for (int turn = 0; turn < row->quarter_turns; ++turn)
    cv::rotate(gray, gray, cv::ROTATE_90_CLOCKWISE);
  // Square, so that a metre of surface is as long in u as in v: a tiling photograph twice as
  // tall as wide is laid twice side by side.
  if (gray.cols != gray.rows) {
    const int lo = std::min(gray.cols, gray.rows), hi = std::max(gray.cols, gray.rows);
    if (hi % lo != 0)
      throw UserError(fmt::format(
          "photograph '{}': {}x{} pixels; expected a square, or a side a whole multiple of the "
          "other",
          path, gray.cols, gray.rows));
    gray = cv::repeat(gray, hi / gray.rows, hi / gray.cols);
  }
  while (gray.cols > max_edge_px) gray = halve(gray);

  sim::Texture t;
  t.name = name;
  t.width = gray.cols;
  t.height = gray.rows;
  t.pixels.assign(gray.begin<std::uint8_t>(), gray.end<std::uint8_t>());
  const double gain = mean_gray_target / std::max(mean_gray(t), 1.0);
  for (std::uint8_t& p : t.pixels)
    p = static_cast<std::uint8_t>(std::clamp(std::floor(p * gain + 0.5), 0.0, 255.0));
  return t;
}

}  // namespace driftlab::scenes
