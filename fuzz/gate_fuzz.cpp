// The CI gate's inputs: a baseline file (load_baseline) and the metrics.json it is checked
// against (read_results_metrics, then every baseline key looked up in it).
#include "fuzz/fuzz_support.hpp"
#include "gate/gate.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace driftlab;
  const auto file = fuzz::put_file("baseline.json", fuzz::as_text(data, size));
  fuzz::expect_user_errors_only([&] {
    const gate::Baseline b = gate::load_baseline(file);
    (void)gate::baseline_json(b);
  });
  fuzz::expect_user_errors_only([&] { (void)gate::read_results_metrics(file); });
  return 0;
}
