// Scenario files and their --set overrides: parse_scenario (YAML, every section's reader and
// validation). Input: the scenario's YAML, then after a "%%" line one override per line.
#include <sstream>

#include "fuzz/fuzz_support.hpp"
#include "pipeline/scenario.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace driftlab;
  const auto parts = fuzz::split_parts(fuzz::as_text(data, size), 2);
  std::vector<std::string> overrides;
  std::istringstream lines(parts[1]);
  for (std::string line; std::getline(lines, line);)
    if (!line.empty()) overrides.push_back(line);
  fuzz::expect_user_errors_only([&] {
    const pipeline::Scenario sc =
        pipeline::parse_scenario(parts[0], "fuzz.yaml", fuzz::scratch_dir(), overrides);
    (void)pipeline::resolved_yaml(sc);
  });
  return 0;
}
