// CSV cells in and out (RFC 4180): one splitter and one writer for every CSV
// that driftlab reads or writes (trajectories, covariates, sweep tables).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace driftlab {

enum class CsvTrim { kNo, kSpaces };

/// The cells of one CSV line. A quoted cell may hold commas, line breaks and doubled quotes
/// ("a ""b"""); a trailing '\r' is dropped; "a," gives two cells, "" one empty cell. With
/// CsvTrim::kSpaces, spaces and tabs around unquoted cells are removed.
std::vector<std::string> split_csv_line(std::string_view line, CsvTrim trim = CsvTrim::kNo);

/// One cell as written: quoted when it holds a comma, quote or line break.
std::string csv_cell(std::string_view cell);

/// A row of cells joined by commas, ending in '\n'.
std::string csv_row(const std::vector<std::string>& cells);

}  // namespace driftlab
