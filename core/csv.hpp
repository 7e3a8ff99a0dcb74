// CSV cells in and out (RFC 4180): one splitter, one table reader and one writer for every
// CSV that driftlab reads or writes (trajectories, covariates, sections, sweep tables).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace driftlab {

enum class CsvTrim { kNo, kSpaces };

/// The cells of one CSV line. A quoted cell may hold commas, line breaks and doubled quotes
/// ("a ""b"""); a trailing '\r' is dropped; "a," gives two cells, "" one empty cell. With
/// CsvTrim::kSpaces, spaces and tabs around unquoted cells are removed.
std::vector<std::string> split_csv_line(std::string_view line, CsvTrim trim = CsvTrim::kNo);

/// A CSV table: its header's cells and each row's, with the row's line number for messages.
struct CsvTable {
  struct Row {
    std::size_t line = 0;  ///< 1-based line of the text
    std::vector<std::string> cells;
  };
  std::vector<std::string> header;
  std::size_t header_line = 0;  ///< 0: the text has no header
  std::vector<Row> rows;
  /// The index of the column `name`, nullopt when the header has none.
  std::optional<std::size_t> column(std::string_view name) const;
};

struct CsvTableOptions {
  CsvTrim trim = CsvTrim::kNo;
  bool comments = false;  ///< skip lines whose first character is '#'
  bool ragged = false;    ///< keep rows of another length than the header (the reader checks)
};

/// Reads CSV text whose first line (after blank lines, and comments when asked) is the header.
/// Blank lines are skipped; every row must have as many cells as the header, else UserError
/// "SOURCE:LINE: got N cells, expected M like the header" (unless `ragged`). Text without a header
/// line gives an empty table (header_line 0).
CsvTable read_csv_table(std::string_view text, const std::string& source,
                        const CsvTableOptions& options = {});

/// One cell as written: quoted when it holds a comma, quote or line break.
std::string csv_cell(std::string_view cell);

/// A row of cells joined by commas, ending in '\n'.
std::string csv_row(const std::vector<std::string>& cells);

}  // namespace driftlab
