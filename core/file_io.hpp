// Reading whole input files: one place for the checks and the messages that
// every reader of outside input gives (docs/design.md "Errors").
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace driftlab {

/// The whole file, bytes as they are. `what` names the kind of file in messages ("scenario
/// file", "sweep file"). Throws UserError "PATH: no such WHAT", "PATH: not a regular file,
/// expected a WHAT" or "PATH: cannot open for reading".
/// Also rejects text that is not UTF-8 (see require_utf8).
std::string read_text_file(const std::filesystem::path& path, std::string_view what = "file");

/// Throws UserError "LABEL:LINE:COL: got byte 0x9A, expected UTF-8 text" at the first byte
/// that does not start or continue a well-formed UTF-8 sequence (overlong forms, surrogates
/// and code points past U+10FFFF included). Every text driftlab reads may end up in a JSON
/// file (metrics.json, baselines), and JSON is UTF-8.
void require_utf8(std::string_view text, std::string_view label);

}  // namespace driftlab
