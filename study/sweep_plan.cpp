// Planning a sweep: the design's points, each replicate's seed, every job checked against the
// scenario before any runs, and the sweep folder written (sweep.json, scenario.yaml,
// manifest.jsonl).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/rng.hpp"
#include "core/yaml_io.hpp"
#include "pipeline/scenario.hpp"
#include "study/sweep.hpp"

#ifndef DRIFTLAB_VERSION
#define DRIFTLAB_VERSION "unknown"
#endif

namespace driftlab::study {

using pipeline::load_scenario;
using pipeline::parse_scenario;
using pipeline::resolved_yaml;
using pipeline::Scenario;
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kMaxJobs = 1000000;  // a typo in a range should not plan a billion runs
constexpr std::size_t kMaxErrors = 20;     // per plan: the first problems are the useful ones

}  // namespace

// ---------------------------------------------------------------------------
// Plan

std::uint64_t replicate_seed(std::uint64_t sweep_seed, std::size_t replicate) {
  // Kept below 2^53 so that every JSON reader (jq, Python, JavaScript) reads it exactly.
  return derive_seed(sweep_seed, "sweep.replicate." + std::to_string(replicate)) &
         ((std::uint64_t{1} << 53) - 1);
}

namespace {

bool key_in_schema(const std::string& key) {
  static const std::vector<yaml::SchemaRow> rows = yaml::schema_of(Scenario{});
  return std::any_of(rows.begin(), rows.end(),
                     [&](const yaml::SchemaRow& r) { return r.key_path == key; });
}

// The problem lines of a scenario error without its header line.
std::string problems_of(const UserError& e) {
  std::string what = e.what();
  const auto nl = what.find('\n');
  if (nl != std::string::npos && what.substr(0, nl).find("invalid scenario:") != std::string::npos)
    what = what.substr(nl + 1);
  std::string out;
  std::istringstream in(what);
  std::string line;
  while (std::getline(in, line)) out += (out.empty() ? "" : "; ") + line;
  return out;
}

// Whether the scenario text with these overrides is a valid scenario.
bool parses(const std::string& text, const std::string& label, const fs::path& dir,
            const std::vector<std::string>& overrides) {
  try {
    parse_scenario(text, label, dir, overrides);
    return true;
  } catch (const UserError&) {
    return false;
  }
}

// Point values (YAML text per axis) of the design.
std::vector<std::vector<std::string>> design_points(const Sweep& s, std::uint64_t seed) {
  std::vector<std::vector<std::string>> points;
  const std::size_t d = s.axes.size();
  switch (s.design) {
    case SweepDesign::kGrid: {
      double total = 1;
      for (const auto& a : s.axes) total *= static_cast<double>(a.levels.size());
      if (total > static_cast<double>(kMaxJobs))
        throw UserError(fmt::format("{}: axes: a grid of {:.0f} points, expected at most {}",
                                    s.file.string(), total, kMaxJobs));
      // Row-major: the first axis varies slowest.
      std::vector<std::size_t> k(d, 0);
      while (true) {
        std::vector<std::string> p;
        for (std::size_t i = 0; i < d; ++i) p.push_back(s.axes[i].levels[k[i]]);
        points.push_back(std::move(p));
        std::size_t i = d;
        while (i > 0) {
          --i;
          if (++k[i] < s.axes[i].levels.size()) break;
          k[i] = 0;
          if (i == 0) return points;
        }
        if (d == 0) return points;
      }
    }
    case SweepDesign::kZip: {
      for (std::size_t k = 0; k < s.axes.front().levels.size(); ++k) {
        std::vector<std::string> p;
        for (const auto& a : s.axes) p.push_back(a.levels[k]);
        points.push_back(std::move(p));
      }
      return points;
    }
    case SweepDesign::kRandom: {
      // Latin hypercube: each axis is cut into N equal strata (of [0, 1), mapped
      // onto the axis), every stratum is used once, strata are paired across axes by
      // independent random permutations, and each sample falls uniformly in its stratum.
      const std::size_t n = s.samples;
      Rng rng(derive_seed(seed, "sweep.latin_hypercube"));
      points.assign(n, std::vector<std::string>(d));
      for (std::size_t i = 0; i < d; ++i) {
        std::vector<std::size_t> perm(n);
        for (std::size_t k = 0; k < n; ++k) perm[k] = k;
        for (std::size_t k = n; k > 1; --k) std::swap(perm[k - 1], perm[rng.uniform_int(k)]);
        const SweepAxis& a = s.axes[i];
        for (std::size_t k = 0; k < n; ++k) {
          const double u = (static_cast<double>(perm[k]) + rng.uniform()) / static_cast<double>(n);
          if (a.continuous) {
            const double v =
                a.spec == AxisSpec::kLogspace
                    ? std::exp(std::log(a.start) + (std::log(a.stop) - std::log(a.start)) * u)
                    : a.start + (a.stop - a.start) * u;
            points[k][i] = yaml::format_double(detail::tidy_level(std::clamp(v, a.start, a.stop)));
          } else {
            const auto level =
                std::min(static_cast<std::size_t>(u * static_cast<double>(a.levels.size())),
                         a.levels.size() - 1);
            points[k][i] = a.levels[level];
          }
        }
      }
      return points;
    }
  }
  return points;
}

}  // namespace

SweepPlan plan_sweep(const Sweep& s) {
  SweepPlan plan;
  plan.sweep = s;
  const std::string sweep_label = s.file.string();
  const fs::path base_dir = s.base.parent_path();

  // The base scenario alone, then each fixed override on it, then all of them.
  Scenario base;
  try {
    base = load_scenario(s.base);
  } catch (const UserError& e) {
    throw UserError(fmt::format("{}: base: the base scenario {} is invalid:\n{}", s.base_where,
                                s.base.string(), e.what()));
  }
  const std::string base_yaml = resolved_yaml(base);
  yaml::ErrorList errors;
  std::vector<std::string> set_overrides;
  for (std::size_t i = 0; i < s.set.size(); ++i) {
    const std::string o = s.set[i].first + "=" + s.set[i].second;
    set_overrides.push_back(o);
  }
  // Each fixed override alone, for an error at its line; one that only the others make valid
  // (shutter: rolling with its line_delay_us) is not one.
  const bool set_valid = parses(base_yaml, s.base.string(), base_dir, set_overrides);
  for (std::size_t i = 0; i < s.set.size() && !set_valid; ++i) {
    try {
      parse_scenario(base_yaml, s.base.string(), base_dir, {set_overrides[i]});
    } catch (const UserError& e) {
      errors.add(fmt::format("{}: set.{}: got '{}', expected {} of the base scenario {}: {}",
                             s.set_where[i], s.set[i].first, s.set[i].second,
                             key_in_schema(s.set[i].first) ? "a valid value" : "a key path",
                             s.base.string(), problems_of(e)));
    }
  }
  errors.throw_if_any();
  Scenario resolved_base;
  try {
    resolved_base = parse_scenario(base_yaml, s.base.string(), base_dir, set_overrides);
  } catch (const UserError& e) {
    throw UserError(
        fmt::format("{}: set: the fixed overrides together make the base scenario "
                    "invalid: {}",
                    sweep_label, problems_of(e)));
  }
  plan.scenario_yaml = resolved_yaml(resolved_base);
  plan.seed = s.seed.value_or(resolved_base.seed);
  const std::string& R = plan.scenario_yaml;

  // Every key path and every value of every axis, one at a time. A value that the base rejects
  // alone is an error unless a point of the design that holds it is valid (a zip of shutter:
  // rolling with its line delays); the points themselves are checked below.
  const auto points = design_points(s, plan.seed);
  const auto valid_in_a_point = [&](std::size_t axis, const std::string& value) {
    for (const auto& point : points) {
      if (point[axis] != value) continue;
      std::vector<std::string> overrides;
      for (std::size_t i = 0; i < s.axes.size(); ++i)
        overrides.push_back(s.axes[i].key + "=" + point[i]);
      if (parses(R, s.base.string(), base_dir, overrides)) return true;
    }
    return false;
  };
  for (std::size_t i = 0; i < s.axes.size(); ++i) {
    const SweepAxis& a = s.axes[i];
    std::vector<std::string> probe = a.levels;
    if (a.continuous) probe = {yaml::format_double(a.start), yaml::format_double(a.stop)};
    for (std::size_t k = 0; k < probe.size(); ++k) {
      try {
        parse_scenario(R, s.base.string(), base_dir, {a.key + "=" + probe[k]});
      } catch (const UserError& e) {
        if (key_in_schema(a.key) && !a.continuous && valid_in_a_point(i, probe[k])) continue;
        if (!key_in_schema(a.key)) {
          errors.add(
              fmt::format("{}: axes[{}].key: got '{}', expected a key path of the base "
                          "scenario {}: {}",
                          a.where, i, a.key, s.base.string(), problems_of(e)));
          break;
        }
        const std::string at =
            a.spec == AxisSpec::kValues && k < a.level_where.size() ? a.level_where[k] : a.where;
        errors.add(fmt::format("{}: axes[{}] ({}): got {}, which the base scenario rejects: {}", at,
                               i, a.key, probe[k], problems_of(e)));
      }
      if (errors.messages().size() >= kMaxErrors) break;
    }
  }
  errors.throw_if_any();

  plan.points = points.size();
  if (static_cast<double>(points.size()) * static_cast<double>(s.replicates) >
      static_cast<double>(kMaxJobs))
    throw UserError(fmt::format("{}: {} points x {} replicates, expected at most {} jobs",
                                sweep_label, points.size(), s.replicates, kMaxJobs));
  for (std::size_t p = 0; p < points.size(); ++p) {
    for (std::size_t r = 0; r < s.replicates; ++r) {
      SweepJob job;
      job.id = fmt::format("p{:04}-r{:02}", p, r);
      job.index = plan.jobs.size();
      job.point = p;
      job.replicate = r;
      job.seed = replicate_seed(plan.seed, r);
      for (std::size_t i = 0; i < s.axes.size(); ++i) {
        job.params.emplace_back(s.axes[i].name, points[p][i]);
        job.overrides.push_back(s.axes[i].key + "=" + points[p][i]);
      }
      job.overrides.push_back("seed=" + std::to_string(job.seed));
      try {
        const Scenario sc = parse_scenario(R, s.base.string(), base_dir, job.overrides);
        job.hash = fnv1a64_hex(yaml::to_yaml(sc, false));
      } catch (const UserError& e) {
        std::string where;
        for (const auto& [name, value] : job.params)
          where += (where.empty() ? "" : ", ") + name + "=" + value;
        if (errors.messages().size() < kMaxErrors)
          errors.add(
              fmt::format("{}: point {} ({}): the combination is rejected by the base "
                          "scenario: {}",
                          sweep_label, p, where, problems_of(e)));
      }
      plan.jobs.push_back(std::move(job));
    }
  }
  errors.throw_if_any();
  return plan;
}

nlohmann::json yaml_text_to_json(const std::string& text) {
  std::function<nlohmann::json(const YAML::Node&)> convert = [&](const YAML::Node& n) {
    if (n.IsSequence()) {
      nlohmann::json a = nlohmann::json::array();
      for (const auto& e : n) a.push_back(convert(e));
      return a;
    }
    if (n.IsMap()) {
      nlohmann::json o = nlohmann::json::object();
      for (auto it = n.begin(); it != n.end(); ++it) o[it->first.Scalar()] = convert(it->second);
      return o;
    }
    if (!n.IsScalar()) return nlohmann::json();
    const std::string& s = n.Scalar();
    std::int64_t i = 0;
    double d = 0;
    if (n.Tag() != "!") {  // a quoted scalar stays a string
      if (yaml::parse_int64(s, &i)) return nlohmann::json(i);
      if (yaml::parse_double(s, &d) && std::isfinite(d)) return nlohmann::json(d);
      if (s == "true" || s == "false") return nlohmann::json(s == "true");
    }
    return nlohmann::json(s);
  };
  try {
    return convert(YAML::Load(text));
  } catch (const YAML::Exception&) {
    return nlohmann::json(text);
  }
}

SweepInfoRecord SweepPlan::info() const {
  SweepInfoRecord r;
  r.name = sweep.name;
  r.description = sweep.description;
  r.sweep_file = sweep.file.string();
  r.base = sweep.base.string();
  r.base_dir = sweep.base.parent_path().string();
  r.design = sweep.design;
  if (sweep.design == SweepDesign::kRandom) r.samples = sweep.samples;
  r.replicates = sweep.replicates;
  r.seed = seed;
  r.points = points;
  r.jobs = jobs.size();
  for (const auto& [k, v] : sweep.set) r.set[k] = yaml_text_to_json(v);
  for (const auto& a : sweep.axes) {
    SweepAxisRecord ar{a.key, a.name, a.spec, a.numeric, std::nullopt, std::nullopt};
    if (a.continuous) {
      ar.interval = std::array{a.start, a.stop};
    } else {
      ar.values.emplace();
      for (const auto& l : a.levels) ar.values->push_back(yaml_text_to_json(l));
    }
    r.axes.push_back(ar);
  }
  r.driftlab_version = DRIFTLAB_VERSION;
  return r;
}

std::string SweepPlan::manifest_jsonl() const {
  std::string out;
  for (const auto& job : jobs) {
    ManifestJobRecord r{job.id,   job.index, job.point,     job.replicate,
                        job.seed, {},        job.overrides, job.hash};
    for (const auto& [name, value] : job.params) r.params[name] = yaml_text_to_json(value);
    out += record_json::to_ordered_json(r).dump() + "\n";
  }
  return out;
}

std::string PlanWriteSummary::brief() const {
  std::string s =
      fmt::format("{} jobs ({} points) in {}", jobs, points, (dir / "manifest.jsonl").string());
  if (unchanged) s += " (unchanged: the folder already held this plan)";
  if (replaced) s += " (replaced the previous plan; runs whose parameters changed are now stale)";
  return s;
}

PlanWriteSummary write_plan(const SweepPlan& plan, const fs::path& dir_in, bool force) {
  const fs::path dir = fs::absolute(dir_in).lexically_normal();
  PlanWriteSummary summary;
  summary.dir = dir;
  summary.jobs = plan.jobs.size();
  summary.points = plan.points;
  const std::string manifest = plan.manifest_jsonl();
  const std::string info = record_json::to_json(plan.info()).dump(2) + "\n";  // keys sorted
  std::error_code ec;
  if (fs::exists(dir / "manifest.jsonl", ec)) {
    std::string old_manifest, old_scenario;
    try {
      old_manifest = read_text_file(dir / "manifest.jsonl", "manifest");
      old_scenario = read_text_file(dir / "scenario.yaml", "scenario");
    } catch (const UserError&) {
    }
    if (old_manifest == manifest && old_scenario == plan.scenario_yaml) {
      summary.unchanged = true;
      return summary;
    }
    if (!force)
      throw UserError(fmt::format(
          "{}: already holds a different sweep plan (manifest.jsonl or scenario.yaml differs), "
          "expected a new folder or the same plan; --force replaces the plan and keeps runs/ "
          "(finished runs whose parameters are unchanged are not run again)",
          dir.string()));
    write_file_atomic(dir / "scenario.yaml", plan.scenario_yaml);
    write_file_atomic(dir / "sweep.json", info);
    write_file_atomic(dir / "manifest.jsonl", manifest);
    summary.replaced = true;
    return summary;
  }
  bool replace = false;
  if (fs::exists(dir, ec)) {
    if (!fs::is_directory(dir, ec) || !fs::is_empty(dir, ec))
      throw UserError(
          fmt::format("{}: exists and is not a sweep folder (no manifest.jsonl), "
                      "expected a new or empty folder",
                      dir.string()));
    replace = true;
  }
  AtomicDirectory out(dir, replace);
  write_file_atomic(out.path() / "scenario.yaml", plan.scenario_yaml);
  write_file_atomic(out.path() / "sweep.json", info);
  write_file_atomic(out.path() / "manifest.jsonl", manifest);
  out.commit();
  return summary;
}

}  // namespace driftlab::study
