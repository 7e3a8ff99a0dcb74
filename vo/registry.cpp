#include "vo/registry.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <mutex>
#include <optional>
#include <utility>

#include "core/error.hpp"

namespace driftlab::vo {
namespace {

struct Registered {
  std::string name;
  detail::ErasedFactory make;
  detail::OptionsMaker options;  // null: no options
};

struct Registry {
  std::mutex mutex;
  std::vector<Registered> entries;
};

Registry& registry() {
  static Registry r;
  return r;
}

// The entry called `name`, copied under the lock; nullopt when there is none.
std::optional<Registered> find(const std::string& name) {
  Registry& r = registry();
  const std::lock_guard lock(r.mutex);
  for (const auto& e : r.entries)
    if (e.name == name) return e;
  return std::nullopt;
}

}  // namespace

const std::vector<std::string>& built_in_vo_names() {
  static const std::vector<std::string> names = {"sparse", "sparse_kf", "pnp", "dense"};
  return names;
}

namespace detail {

void register_erased(const std::string& name, ErasedFactory factory, OptionsMaker options) {
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
  for (const auto& e : r.entries)
    if (e.name == name)
      throw UserError(fmt::format("register_vo: '{}' is already registered", name));
  r.entries.push_back({name, std::move(factory), std::move(options)});
}

}  // namespace detail

void register_vo(const std::string& name, VoFactory factory) {
  if (!factory) throw UserError(fmt::format("register_vo: '{}': no factory", name));
  detail::register_erased(
      name,
      [f = std::move(factory)](const StereoRig& rig, Rng rng, const yaml::NamedOptions::Holder*) {
        return f(rig, std::move(rng));
      },
      nullptr);
}

yaml::NamedOptions plugin_options() {
  return yaml::NamedOptions(
      [](const std::string& name) -> std::unique_ptr<yaml::NamedOptions::Holder> {
        const auto e = find(name);
        return e && e->options ? e->options() : nullptr;
      },
      [] {
        Registry& r = registry();
        const std::lock_guard lock(r.mutex);
        std::vector<std::string> names;
        for (const auto& e : r.entries)
          if (e.options) names.push_back(e.name);
        return names;
      });
}

std::vector<std::string> registered_vo_names() {
  Registry& r = registry();
  const std::lock_guard lock(r.mutex);
  std::vector<std::string> names;
  for (const auto& e : r.entries) names.push_back(e.name);
  return names;
}

std::vector<std::string> available_vo_names() {
  std::vector<std::string> names = built_in_vo_names();
  for (auto& n : registered_vo_names()) names.push_back(std::move(n));
  return names;
}

std::unique_ptr<StereoOdometry> make_registered_vo(const std::string& name, const StereoRig& rig,
                                                   Rng rng, const yaml::NamedOptions& plugins) {
  const auto e = find(name);
  return e ? e->make(rig, std::move(rng), plugins.find(name)) : nullptr;
}

}  // namespace driftlab::vo
