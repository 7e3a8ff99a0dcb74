#include "core/file_io.hpp"

#include <fmt/format.h>

#include <fstream>
#include <sstream>
#include <system_error>

#include "core/error.hpp"

namespace driftlab {

std::string read_text_file(const std::filesystem::path& path, std::string_view what) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw UserError(fmt::format("{}: no such {}", path.string(), what));
  if (!std::filesystem::is_regular_file(path, ec))
    throw UserError(fmt::format("{}: not a regular file, expected a {}", path.string(), what));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UserError(fmt::format("{}: cannot open for reading", path.string()));
  std::ostringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  require_utf8(text, path.string());
  return text;
}

namespace {
// Length of the well-formed UTF-8 sequence at text[i] (RFC 3629, Table 3-7 of the Unicode
// standard), or 0.
std::size_t utf8_sequence_length(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b0 = byte(i);
  if (b0 < 0x80) return 1;
  std::size_t n = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // the range of the second byte
  if (b0 >= 0xC2 && b0 <= 0xDF)
    n = 2;
  else if (b0 == 0xE0)
    n = 3, lo = 0xA0;
  else if ((b0 >= 0xE1 && b0 <= 0xEC) || b0 == 0xEE || b0 == 0xEF)
    n = 3;
  else if (b0 == 0xED)
    n = 3, hi = 0x9F;  // no surrogates
  else if (b0 == 0xF0)
    n = 4, lo = 0x90;
  else if (b0 >= 0xF1 && b0 <= 0xF3)
    n = 4;
  else if (b0 == 0xF4)
    n = 4, hi = 0x8F;  // up to U+10FFFF
  if (n == 0 || i + n > text.size()) return 0;
  if (byte(i + 1) < lo || byte(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k)
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  return n;
}
}  // namespace

void require_utf8(std::string_view text, std::string_view label) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t n = utf8_sequence_length(text, i);
    if (n == 0)
      throw UserError(fmt::format("{}:{}:{}: got byte 0x{:02X}, expected UTF-8 text", label, line,
                                  column, static_cast<unsigned char>(text[i])));
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
    i += n;
  }
}

}  // namespace driftlab
