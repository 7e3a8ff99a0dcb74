// Reading whole input files: one place for the checks and the messages that
// every reader of outside input gives (DESIGN.md "Errors").
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace driftlab {

/// The whole file, bytes as they are. `what` names the kind of file in messages ("scenario
/// file", "sweep file"). Throws UserError "PATH: no such WHAT", "PATH: not a regular file,
/// expected a WHAT" or "PATH: cannot open for reading".
std::string read_text_file(const std::filesystem::path& path, std::string_view what = "file");

}  // namespace driftlab
