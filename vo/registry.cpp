#include "vo/registry.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <mutex>
#include <utility>

#include "core/error.hpp"

namespace driftlab::vo {
namespace {

struct Registry {
  std::mutex mutex;
  std::vector<std::pair<std::string, VoFactory>> entries;
};

Registry& registry() {
  static Registry r;
  return r;
}

}  // namespace

const std::vector<std::string>& built_in_vo_names() {
  static const std::vector<std::string> names = {"sparse", "sparse_kf", "pnp", "dense"};
  return names;
}

void register_vo(const std::string& name, VoFactory factory) {
  if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                             "0123456789_-") != std::string::npos)
    throw UserError(fmt::format(
        "register_vo: name: got '{}', expected letters, digits, '_' and '-' only", name));
  const auto& built_in = built_in_vo_names();
  if (std::find(built_in.begin(), built_in.end(), name) != built_in.end())
    throw UserError(fmt::format("register_vo: got '{}', a built-in VO's name", name));
  if (!factory) throw UserError(fmt::format("register_vo: '{}': no factory", name));
  Registry& r = registry();
  const std::lock_guard lock(r.mutex);
  for (const auto& [n, f] : r.entries)
    if (n == name) throw UserError(fmt::format("register_vo: '{}' is already registered", name));
  r.entries.emplace_back(name, std::move(factory));
}

std::vector<std::string> registered_vo_names() {
  Registry& r = registry();
  const std::lock_guard lock(r.mutex);
  std::vector<std::string> names;
  for (const auto& [n, f] : r.entries) names.push_back(n);
  return names;
}

std::vector<std::string> available_vo_names() {
  std::vector<std::string> names = built_in_vo_names();
  for (auto& n : registered_vo_names()) names.push_back(std::move(n));
  return names;
}

std::unique_ptr<StereoOdometry> make_registered_vo(const std::string& name, const StereoRig& rig,
                                                   Rng rng) {
  VoFactory factory;
  {
    Registry& r = registry();
    const std::lock_guard lock(r.mutex);
    for (const auto& [n, f] : r.entries)
      if (n == name) factory = f;
  }
  return factory ? factory(rig, std::move(rng)) : nullptr;
}

}  // namespace driftlab::vo
