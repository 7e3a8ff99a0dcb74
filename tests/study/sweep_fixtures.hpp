// Paths and scratch folders that the sweep tests share (sweep_test.cpp, sweep_cli_test.cpp).
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

#include "tests/support/test_support.hpp"

namespace driftlab::study::fixtures {

// The source tree, the `driftlab` program and the test sweeps.
inline const std::filesystem::path kSource = driftlab::test::source_dir();
inline const std::filesystem::path kCli = driftlab::test::cli_path();
inline const std::filesystem::path kSweeps = kSource / "tests/data/sweeps";

// A scratch folder of this process, removed if it is there.
inline std::filesystem::path temp_dir(const std::string& name) {
  const std::filesystem::path d = std::filesystem::temp_directory_path() /
                                  ("driftlab_sweep_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  return d;
}

}  // namespace driftlab::study::fixtures
