// Covariate tables (read_frame_table): the per-frame CSVs that `driftlab eval` and the
// section statistics read.
#include "eval/sections.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace driftlab;
  const auto file = fuzz::put_file("frames.csv", fuzz::as_text(data, size));
  fuzz::expect_user_errors_only([&] { (void)eval::read_frame_table(file.string()); });
  return 0;
}
