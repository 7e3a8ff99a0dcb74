#include "core/csv.hpp"

#include <fmt/format.h>

#include "core/error.hpp"

namespace driftlab {
namespace {

std::string trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

}  // namespace

std::vector<std::string> split_csv_line(std::string_view line, CsvTrim trim) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  std::vector<std::string> cells;
  std::string cell;
  bool quoted = false, was_quoted = false;
  auto finish = [&] {
    cells.push_back(trim == CsvTrim::kSpaces && !was_quoted ? trimmed(cell) : cell);
    cell.clear();
    was_quoted = false;
  };
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cell += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cell += c;
      }
    } else if (c == '"' && trimmed(cell).empty()) {
      quoted = was_quoted = true;
      cell.clear();
    } else if (c == ',') {
      finish();
    } else {
      cell += c;
    }
  }
  finish();
  return cells;
}

std::optional<std::size_t> CsvTable::column(std::string_view name) const {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return i;
  return std::nullopt;
}

CsvTable read_csv_table(std::string_view text, const std::string& source,
                        const CsvTableOptions& options) {
  CsvTable t;
  std::size_t line_no = 0;
  while (!text.empty()) {
    const std::size_t end = text.find('\n');
    std::string_view line = text.substr(0, end);
    text = end == std::string_view::npos ? std::string_view() : text.substr(end + 1);
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string_view::npos) continue;
    if (options.comments && line.front() == '#') continue;
    std::vector<std::string> cells = split_csv_line(line, options.trim);
    if (t.header_line == 0) {
      t.header = std::move(cells);
      t.header_line = line_no;
      continue;
    }
    if (!options.ragged && cells.size() != t.header.size())
      throw UserError(fmt::format("{}:{}: got {} cells, expected {} like the header", source,
                                  line_no, cells.size(), t.header.size()));
    t.rows.push_back({line_no, std::move(cells)});
  }
  return t;
}

std::string csv_cell(std::string_view s) {
  if (s.find_first_of(",\"\n\r") == std::string_view::npos) return std::string(s);
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string csv_row(const std::vector<std::string>& cells) {
  std::string out;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (i) out += ',';
    out += csv_cell(cells[i]);
  }
  return out + "\n";
}

}  // namespace driftlab
