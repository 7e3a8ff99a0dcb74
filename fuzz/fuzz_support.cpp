#include "fuzz/fuzz_support.hpp"

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <system_error>

namespace driftlab::fuzz {

std::string as_text(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

std::vector<std::string> split_parts(std::string_view text, std::size_t parts) {
  std::vector<std::string> out;
  while (out.size() + 1 < parts) {
    const bool at_start = text.substr(0, 3) == "%%\n";
    const std::size_t cut = at_start ? 0 : text.find("\n%%\n");
    if (cut == std::string_view::npos) break;
    out.emplace_back(text.substr(0, cut));
    text.remove_prefix(cut + (at_start ? 3 : 4));
  }
  out.emplace_back(text);
  out.resize(parts);
  return out;
}

namespace {
std::filesystem::path make_scratch() {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("driftlab-fuzz-" + std::to_string(static_cast<long>(::getpid())));
  std::filesystem::create_directories(dir);
  static const std::filesystem::path keep = dir;
  std::atexit([] {
    std::error_code ec;
    std::filesystem::remove_all(keep, ec);
  });
  return dir;
}
}  // namespace

const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path dir = make_scratch();
  return dir;
}

std::filesystem::path put_file(const std::filesystem::path& relative, std::string_view text) {
  const auto path = scratch_dir() / relative;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(text.data(), text.size());
  return path;
}

}  // namespace driftlab::fuzz
