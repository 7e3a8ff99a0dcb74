// Shared pieces of the fuzz targets (fuzz/*_fuzz.cpp). Each target feeds its bytes to one
// reader of outside input. The contract under test: bad input ends in driftlab::UserError (a
// clear message) and nothing else: any other exception escapes to libFuzzer as a finding, as
// does a crash, a sanitizer report, a leak or a hang.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace driftlab::fuzz {

/// The input as text.
std::string as_text(const std::uint8_t* data, std::size_t size);

/// The input cut at each line "%%" into at most `parts` pieces (the last takes the rest);
/// missing pieces are empty. Lets one input carry several files.
std::vector<std::string> split_parts(std::string_view text, std::size_t parts);

/// A folder of this process's own, made once and removed at exit.
const std::filesystem::path& scratch_dir();

/// Writes `text` to scratch_dir()/relative (folders made as needed); returns the path.
std::filesystem::path put_file(const std::filesystem::path& relative, std::string_view text);

/// Runs `f`; a UserError is the expected answer to bad input and is swallowed, anything
/// else propagates.
template <class F>
void expect_user_errors_only(F&& f);

}  // namespace driftlab::fuzz

#include "core/error.hpp"

template <class F>
void driftlab::fuzz::expect_user_errors_only(F&& f) {
  try {
    f();
  } catch (const driftlab::UserError&) {
  }
}
