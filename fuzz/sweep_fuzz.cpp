// Sweep files (parse_sweep) and the shard files of a running sweep (parse_shard).
#include "fuzz/fuzz_support.hpp"
#include "study/sweep.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace driftlab;
  const std::string text = fuzz::as_text(data, size);
  fuzz::expect_user_errors_only(
      [&] { (void)study::parse_sweep(text, "fuzz_sweep.yaml", fuzz::scratch_dir()); });
  fuzz::expect_user_errors_only([&] { (void)study::parse_shard(text); });
  return 0;
}
