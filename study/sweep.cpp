#include "study/sweep.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/process.hpp"
#include "core/rng.hpp"
#include "core/yaml_io.hpp"
#include "pipeline/scenario.hpp"

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
// Levels of one axis: more is a typo (a step of 1 over 444245), and expanding it alone takes
// seconds (found by fuzz/sweep_fuzz.cpp).
constexpr std::size_t kMaxAxisValues = 10000;
constexpr std::size_t kMaxErrors = 20;  // per plan: the first problems are the useful ones

// YAML text of a node for a KEY=VALUE override: scalars as they are (quoted
// when YAML needs it), lists and maps in flow style.
std::string yaml_text(const YAML::Node& node) {
  YAML::Emitter e;
  e.SetSeqFormat(YAML::Flow);
  e.SetMapFormat(YAML::Flow);
  if (node.IsScalar()) {
    e << node.Scalar();
  } else {
    e << node;
  }
  return e.c_str();
}

// Rounds generated values to 12 significant digits, so that
// range {0, 1, 0.1} gives 0.3 rather than 0.30000000000000004.
double tidy(double v) {
  double out = v;
  yaml::parse_double(fmt::format("{:.12g}", v), &out);
  return out == 0 ? 0.0 : out;  // no "-0"
}

// A strict reader of one YAML mapping of the sweep file: remembers the keys
// asked for and reports the others (with a did-you-mean) in finish().
class MapReader {
 public:
  MapReader(const YAML::Node& map, const std::string& label, std::string prefix,
            yaml::ErrorList* errors)
      : map_(map), label_(label), prefix_(std::move(prefix)), errors_(errors) {}

  YAML::Node get(const std::string& key) {
    known_.push_back(key);
    for (auto it = map_.begin(); it != map_.end(); ++it)
      if (it->first.IsScalar() && it->first.Scalar() == key) return it->second;
    return YAML::Node(YAML::NodeType::Undefined);
  }
  bool has(const std::string& key) const {
    for (auto it = map_.begin(); it != map_.end(); ++it)
      if (it->first.IsScalar() && it->first.Scalar() == key) return true;
    return false;
  }

  std::string path(const std::string& key) const {
    return prefix_.empty() ? key : prefix_ + "." + key;
  }
  std::string where(const YAML::Node& node) const {
    const YAML::Mark m = node.Mark();
    if (m.is_null()) return label_;
    return fmt::format("{}:{}:{}", label_, m.line + 1, m.column + 1);
  }
  void fail(const YAML::Node& node, const std::string& key_path, const std::string& got,
            const std::string& expected) {
    errors_->add(fmt::format("{}: {}: got {}, expected {}", where(node), key_path, got, expected));
  }

  std::optional<std::string> string(const std::string& key, bool non_empty = true) {
    const YAML::Node n = get(key);
    if (!n) return std::nullopt;
    if (!n.IsScalar()) {
      fail(n, path(key), yaml::describe_node(n), "a string");
      return std::nullopt;
    }
    if (non_empty && n.Scalar().empty()) {
      fail(n, path(key), "an empty string", "a non-empty string");
      return std::nullopt;
    }
    return n.Scalar();
  }
  std::optional<double> number(const YAML::Node& n, const std::string& key_path) {
    double v = 0;
    if (!n.IsScalar() || !yaml::parse_double(n.Scalar(), &v)) {
      fail(n, key_path, yaml::describe_node(n), "a number");
      return std::nullopt;
    }
    if (!std::isfinite(v)) {
      fail(n, key_path, yaml::describe_node(n), "a finite number");
      return std::nullopt;
    }
    return v;
  }
  std::optional<std::uint64_t> count(const std::string& key, std::uint64_t min,
                                     const std::string& expected) {
    const YAML::Node n = get(key);
    if (!n) return std::nullopt;
    std::uint64_t v = 0;
    if (!n.IsScalar() || !yaml::parse_uint64(n.Scalar(), &v) || v < min) {
      fail(n, path(key), yaml::describe_node(n), expected);
      return std::nullopt;
    }
    return v;
  }

  void finish() {
    for (auto it = map_.begin(); it != map_.end(); ++it) {
      const YAML::Node k = it->first;
      if (!k.IsScalar()) {
        errors_->add(fmt::format("{}: {}: got a non-scalar key, expected a plain key name",
                                 where(k), prefix_.empty() ? "(top level)" : prefix_));
        continue;
      }
      const std::string name = k.Scalar();
      std::size_t seen = 0;
      for (auto jt = map_.begin(); jt != it; ++jt)
        seen += jt->first.IsScalar() && jt->first.Scalar() == name;
      if (seen) {
        errors_->add(
            fmt::format("{}: {}: duplicate key, expected each key once", where(k), path(name)));
        continue;
      }
      if (std::find(known_.begin(), known_.end(), name) != known_.end()) continue;
      std::string hint, list;
      std::size_t best = 3;
      for (const auto& known : known_) {
        const std::size_t d = yaml::edit_distance(name, known);
        if (d < best) {
          best = d;
          hint = known;
        }
        list += (list.empty() ? "" : ", ") + known;
      }
      errors_->add(fmt::format("{}: {}: unknown key{}; expected one of: {}", where(k), path(name),
                               hint.empty() ? "" : " (did you mean '" + path(hint) + "'?)", list));
    }
  }

 private:
  YAML::Node map_;
  std::string label_;
  std::string prefix_;
  yaml::ErrorList* errors_;
  std::vector<std::string> known_;
};

// Reads `range`, `linspace` or `logspace` of an axis: {start, stop, step|num}.
void read_generated_axis(MapReader& axis_reader, const YAML::Node& node, const std::string& path,
                         SweepAxis* axis, SweepDesign design, yaml::ErrorList* errors,
                         const std::string& label) {
  if (!node.IsMap()) {
    const char* form =
        axis->spec == AxisSpec::kRange ? "{start, stop, step}" : "{start, stop, num}";
    axis_reader.fail(node, path, yaml::describe_node(node), std::string("a mapping ") + form);
    return;
  }
  MapReader r(node, label, path, errors);
  const std::size_t before = errors->messages().size();
  auto required = [&](const std::string& key) -> std::optional<double> {
    const YAML::Node n = r.get(key);
    if (!n) {
      errors->add(fmt::format("{}: {}: missing, expected a number", r.where(node), r.path(key)));
      return std::nullopt;
    }
    return r.number(n, r.path(key));
  };
  const auto start = required("start");
  const auto stop = required("stop");
  std::optional<double> step;
  std::optional<std::uint64_t> num;
  const bool continuous = design == SweepDesign::kRandom && axis->spec != AxisSpec::kRange;
  if (axis->spec == AxisSpec::kRange) {
    step = required("step");
  } else if (continuous) {
    const YAML::Node n = r.get("num");
    if (n)
      r.fail(n, r.path("num"), yaml::describe_node(n),
             "no num with design random (a random design samples [start, stop] continuously; num "
             "is for designs grid and zip)");
  } else {
    const YAML::Node n = r.get("num");
    if (!n) {
      errors->add(
          fmt::format("{}: {}: missing, expected an integer >= 1", r.where(node), r.path("num")));
    } else {
      num = r.count("num", 1, "an integer >= 1");
    }
  }
  r.finish();
  if (errors->messages().size() != before) return;

  if (axis->spec == AxisSpec::kLogspace && (*start <= 0 || *stop <= 0)) {
    axis_reader.fail(node, path,
                     fmt::format("start {} and stop {}", yaml::format_double(*start),
                                 yaml::format_double(*stop)),
                     "start > 0 and stop > 0 (logspace spaces values evenly on a log scale)");
    return;
  }
  if (continuous) {
    if (!(*start < *stop)) {
      axis_reader.fail(node, path,
                       fmt::format("start {} and stop {}", yaml::format_double(*start),
                                   yaml::format_double(*stop)),
                       "start < stop (the interval a random design samples)");
      return;
    }
    axis->continuous = true;
    axis->start = *start;
    axis->stop = *stop;
    return;
  }
  std::vector<double> values;
  if (axis->spec == AxisSpec::kRange) {
    if (*step == 0) {
      axis_reader.fail(node, path + ".step", "0", "a non-zero step");
      return;
    }
    const double n = std::ceil((*stop - *start) / *step - 1e-9);
    if (!(n >= 1)) {
      axis_reader.fail(
          node, path,
          fmt::format("an empty range (start {}, stop {}, step {})", yaml::format_double(*start),
                      yaml::format_double(*stop), yaml::format_double(*step)),
          "at least one value: start + k * step for k = 0, 1, ... strictly before "
          "stop (stop excluded, as in Python's range)");
      return;
    }
    if (n > static_cast<double>(kMaxAxisValues)) {
      axis_reader.fail(node, path, fmt::format("{:.0f} values", n),
                       fmt::format("at most {} values on one axis", kMaxAxisValues));
      return;
    }
    for (std::size_t k = 0; k < static_cast<std::size_t>(n); ++k)
      values.push_back(tidy(*start + static_cast<double>(k) * *step));
  } else {
    if (*num > kMaxAxisValues) {
      axis_reader.fail(node, path + ".num", std::to_string(*num),
                       fmt::format("at most {} values on one axis", kMaxAxisValues));
      return;
    }
    for (std::uint64_t k = 0; k < *num; ++k) {
      const double t = *num == 1 ? 0.0 : static_cast<double>(k) / static_cast<double>(*num - 1);
      values.push_back(
          axis->spec == AxisSpec::kLinspace
              ? tidy(*start + (*stop - *start) * t)
              : tidy(std::exp(std::log(*start) + (std::log(*stop) - std::log(*start)) * t)));
    }
  }
  for (double v : values) axis->levels.push_back(yaml::format_double(v));
}

}  // namespace

// ---------------------------------------------------------------------------
// Sweep file

Sweep parse_sweep(const std::string& text, const std::string& label, const fs::path& dir) {
  const YAML::Node root = yaml::load_string(text, label);
  yaml::ErrorList errors;
  if (!root.IsMap()) {
    errors.add(fmt::format("{}: expected a mapping of keys to values at the top level, got {}",
                           label, yaml::describe_node(root)));
    errors.throw_if_any();
  }
  Sweep s;
  s.file = fs::absolute(label).lexically_normal();
  MapReader r(root, label, "", &errors);
  s.name = r.string("name").value_or(fs::path(label).stem().string());
  s.description = r.string("description", false).value_or("");

  const YAML::Node base = r.get("base");
  if (!base) {
    errors.add(
        fmt::format("{}: base: missing, expected the path of the base scenario "
                    "(relative to the sweep file)",
                    label));
  } else if (!base.IsScalar() || base.Scalar().empty()) {
    r.fail(base, "base", yaml::describe_node(base),
           "the path of the base scenario (relative to the sweep file)");
  } else {
    fs::path p = base.Scalar();
    if (p.is_relative()) p = dir / p;
    s.base = fs::absolute(p).lexically_normal();
    s.base_where = r.where(base);
    std::error_code ec;
    if (!fs::is_regular_file(s.base, ec))
      r.fail(base, "base", "'" + base.Scalar() + "'",
             "an existing scenario file (relative to the sweep file: " + s.base.string() +
                 " does not exist)");
  }

  const YAML::Node set = r.get("set");
  if (set) {
    if (!set.IsMap()) {
      r.fail(set, "set", yaml::describe_node(set),
             "a mapping of scenario key paths to values (e.g. pipeline.max_frames: 50)");
    } else {
      for (auto it = set.begin(); it != set.end(); ++it) {
        if (!it->first.IsScalar() || it->first.Scalar().empty()) {
          r.fail(it->first, "set", yaml::describe_node(it->first), "a scenario key path");
          continue;
        }
        s.set.emplace_back(it->first.Scalar(), yaml_text(it->second));
        s.set_where.push_back(r.where(it->first));
      }
    }
  }

  const YAML::Node design = r.get("design");
  bool design_ok = true;
  if (design) {
    const std::string expected = "one of: " + yaml::enum_choices<SweepDesign>();
    std::optional<SweepDesign> d;
    if (design.IsScalar()) d = yaml::enum_from_name<SweepDesign>(design.Scalar());
    if (!d) {
      r.fail(design, "design", yaml::describe_node(design), expected);
      design_ok = false;
    } else {
      s.design = *d;
    }
  }
  const YAML::Node samples = r.get("samples");
  if (samples && design_ok && s.design != SweepDesign::kRandom) {
    r.fail(samples, "samples", yaml::describe_node(samples),
           fmt::format("no samples with design {} (samples is the number of points of design "
                       "random; grid and zip take their points from the axes)",
                       yaml::enum_name(s.design)));
  } else if (samples) {
    s.samples = r.count("samples", 1, "an integer >= 1 (points of the random design)").value_or(0);
  } else if (design_ok && s.design == SweepDesign::kRandom) {
    r.fail(design, "design", "'random'",
           "samples: N alongside it (the number of Latin hypercube points, N >= 1)");
  }
  if (r.has("replicates"))
    s.replicates =
        r.count("replicates", 1, "an integer >= 1 (runs per point, each with its own seed)")
            .value_or(1);
  else
    r.get("replicates");
  if (r.has("seed"))
    s.seed = r.count("seed", 0, "a non-negative integer");
  else
    r.get("seed");

  const YAML::Node axes = r.get("axes");
  if (!axes) {
    errors.add(
        fmt::format("{}: axes: missing, expected a list of axes ({{key: ..., values: "
                    "[...]}})",
                    label));
  } else if (!axes.IsSequence() || axes.size() == 0) {
    r.fail(axes, "axes", axes.IsSequence() ? "an empty list" : yaml::describe_node(axes),
           "a list of at least one axis ({key: ..., values: [...]})");
  } else {
    for (std::size_t i = 0; i < axes.size(); ++i) {
      const YAML::Node a = axes[i];
      const std::string path = fmt::format("axes[{}]", i);
      if (!a.IsMap()) {
        r.fail(a, path, yaml::describe_node(a), "a mapping {key: ..., values: [...]}");
        continue;
      }
      MapReader ar(a, label, path, &errors);
      SweepAxis axis;
      axis.where = ar.where(a);
      const YAML::Node key = ar.get("key");
      if (!key) {
        errors.add(
            fmt::format("{}: {}.key: missing, expected a scenario key path such as "
                        "mission.yaw_weave.amplitude_deg",
                        ar.where(a), path));
      } else if (!key.IsScalar() || key.Scalar().empty()) {
        ar.fail(key, path + ".key", yaml::describe_node(key), "a scenario key path");
      } else {
        axis.key = key.Scalar();
        axis.where = ar.where(key);
      }
      axis.name = ar.string("name").value_or(axis.key);
      std::vector<std::pair<AxisSpec, YAML::Node>> specs;
      for (const auto& [spec, spec_name] : enum_table(AxisSpec{})) {
        const YAML::Node n = ar.get(spec_name);
        if (n) specs.emplace_back(spec, n);
      }
      if (specs.empty()) {
        errors.add(
            fmt::format("{}: {}: no values, expected one of: values, range, linspace, "
                        "logspace",
                        ar.where(a), path));
      } else if (specs.size() > 1) {
        ar.fail(specs[1].second, path,
                fmt::format("both {} and {}", yaml::enum_name(specs[0].first),
                            yaml::enum_name(specs[1].first)),
                "exactly one of: values, range, linspace, logspace");
      } else {
        axis.spec = specs[0].first;
        const YAML::Node n = specs[0].second;
        const std::string spec_path = path + "." + std::string(yaml::enum_name(axis.spec));
        if (axis.spec == AxisSpec::kValues) {
          if (!n.IsSequence()) {
            ar.fail(n, spec_path, yaml::describe_node(n), "a list of values");
          } else if (n.size() == 0) {
            ar.fail(n, spec_path, "an empty list", "at least one value");
          } else {
            for (std::size_t k = 0; k < n.size(); ++k) {
              if (n[k].IsNull()) {
                ar.fail(n[k], fmt::format("{}[{}]", spec_path, k), yaml::describe_node(n[k]),
                        "a value");
                continue;
              }
              axis.levels.push_back(yaml_text(n[k]));
              axis.level_where.push_back(ar.where(n[k]));
            }
          }
        } else if (design_ok) {
          read_generated_axis(ar, n, spec_path, &axis, s.design, &errors, label);
        }
      }
      ar.finish();
      for (const auto& level : axis.levels) {
        double v = 0;
        const YAML::Node parsed = YAML::Load(level);
        axis.numeric = axis.numeric && parsed.IsScalar() && yaml::parse_double(level, &v);
      }
      s.axes.push_back(std::move(axis));
    }
  }
  r.finish();
  errors.throw_if_any();

  // Rules across axes and the fixed overrides.
  std::map<std::string, std::size_t> keys, names;
  for (std::size_t i = 0; i < s.axes.size(); ++i) {
    const SweepAxis& a = s.axes[i];
    if (a.key == "seed")
      errors.add(
          fmt::format("{}: axes[{}].key: got 'seed', expected another key (each "
                      "replicate gets its own seed: use replicates and the sweep's seed)",
                      a.where, i));
    if (auto [it, fresh] = keys.emplace(a.key, i); !fresh)
      errors.add(
          fmt::format("{}: axes[{}].key: got '{}' again (axes[{}]), expected each key "
                      "in one axis only",
                      a.where, i, a.key, it->second));
    if (auto [it, fresh] = names.emplace(a.name, i); !fresh && a.key != s.axes[it->second].key)
      errors.add(
          fmt::format("{}: axes[{}].name: got '{}' again (axes[{}]), expected a distinct "
                      "column name",
                      a.where, i, a.name, it->second));
    for (const char* reserved : {"job", "point", "replicate", "seed"})
      if (a.name == reserved && a.key != "seed")
        errors.add(
            fmt::format("{}: axes[{}].name: got '{}', expected a name other than job, "
                        "point, replicate and seed (columns of the merged tables)",
                        a.where, i, a.name));
  }
  for (std::size_t i = 0; i < s.set.size(); ++i) {
    if (keys.count(s.set[i].first))
      errors.add(
          fmt::format("{}: set.{}: also swept by axes[{}], expected each key either fixed "
                      "in set or swept",
                      s.set_where[i], s.set[i].first, keys[s.set[i].first]));
    if (s.set[i].first == "seed")
      errors.add(
          fmt::format("{}: set.seed: got a fixed seed, expected the sweep's own seed key "
                      "(each replicate derives its seed from it)",
                      s.set_where[i]));
  }
  if (s.design == SweepDesign::kZip && s.axes.size() > 1) {
    for (std::size_t i = 1; i < s.axes.size(); ++i)
      if (s.axes[i].levels.size() != s.axes[0].levels.size())
        errors.add(
            fmt::format("{}: axes[{}]: got {} values, expected {} like axes[0] (design zip "
                        "pairs the k-th values of every axis)",
                        s.axes[i].where, i, s.axes[i].levels.size(), s.axes[0].levels.size()));
  }
  errors.throw_if_any();
  return s;
}

Sweep load_sweep(const fs::path& file) {
  return parse_sweep(read_text_file(file, "sweep file"), file.string(), file.parent_path());
}

// ---------------------------------------------------------------------------
// Plan

std::uint64_t replicate_seed(std::uint64_t sweep_seed, std::size_t replicate) {
  // Kept below 2^53 so that every JSON reader (jq, Python, JavaScript) reads it exactly.
  return derive_seed(sweep_seed, "sweep.replicate." + std::to_string(replicate)) &
         ((std::uint64_t{1} << 53) - 1);
}

std::string fnv1a64_hex(const std::string& bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return fmt::format("{:016x}", h);
}

namespace {

bool key_in_schema(const std::string& key) {
  static const std::vector<yaml::SchemaRow> rows = yaml::schema_of(Scenario{});
  return std::any_of(rows.begin(), rows.end(),
                     [&](const yaml::SchemaRow& r) { return r.key_path == key; });
}

std::string first_line(const std::string& s) { return s.substr(0, s.find('\n')); }

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
            points[k][i] = yaml::format_double(tidy(std::clamp(v, a.start, a.stop)));
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
    try {
      parse_scenario(base_yaml, s.base.string(), base_dir, {o});
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

  // Every key path and every value of every axis, one at a time.
  for (std::size_t i = 0; i < s.axes.size(); ++i) {
    const SweepAxis& a = s.axes[i];
    std::vector<std::string> probe = a.levels;
    if (a.continuous) probe = {yaml::format_double(a.start), yaml::format_double(a.stop)};
    for (std::size_t k = 0; k < probe.size(); ++k) {
      try {
        parse_scenario(R, s.base.string(), base_dir, {a.key + "=" + probe[k]});
      } catch (const UserError& e) {
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

  const auto points = design_points(s, plan.seed);
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

nlohmann::json SweepPlan::info() const {
  nlohmann::json j;
  j["format"] = 1;
  j["name"] = sweep.name;
  j["description"] = sweep.description;
  j["sweep_file"] = sweep.file.string();
  j["base"] = sweep.base.string();
  j["base_dir"] = sweep.base.parent_path().string();
  j["scenario"] = "scenario.yaml";
  j["design"] = std::string(yaml::enum_name(sweep.design));
  if (sweep.design == SweepDesign::kRandom) j["samples"] = sweep.samples;
  j["replicates"] = sweep.replicates;
  j["seed"] = seed;
  j["points"] = points;
  j["jobs"] = jobs.size();
  j["set"] = nlohmann::json::object();
  for (const auto& [k, v] : sweep.set) j["set"][k] = yaml_text_to_json(v);
  j["axes"] = nlohmann::json::array();
  for (const auto& a : sweep.axes) {
    nlohmann::json ja{{"key", a.key},
                      {"name", a.name},
                      {"spec", std::string(yaml::enum_name(a.spec))},
                      {"numeric", a.numeric}};
    if (a.continuous) {
      ja["interval"] = {a.start, a.stop};
    } else {
      ja["values"] = nlohmann::json::array();
      for (const auto& l : a.levels) ja["values"].push_back(yaml_text_to_json(l));
    }
    j["axes"].push_back(ja);
  }
  j["driftlab_version"] = DRIFTLAB_VERSION;
  return j;
}

std::string SweepPlan::manifest_jsonl() const {
  std::string out;
  for (const auto& job : jobs) {
    nlohmann::ordered_json j;
    j["id"] = job.id;
    j["index"] = job.index;
    j["point"] = job.point;
    j["replicate"] = job.replicate;
    j["seed"] = job.seed;
    j["params"] = nlohmann::ordered_json::object();
    for (const auto& [name, value] : job.params) j["params"][name] = yaml_text_to_json(value);
    j["overrides"] = job.overrides;
    j["hash"] = job.hash;
    out += j.dump() + "\n";
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
  const std::string info = plan.info().dump(2) + "\n";
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

// ---------------------------------------------------------------------------
// Reading a sweep folder

const SweepJob* SweepManifest::find(const std::string& id) const {
  for (const auto& j : jobs)
    if (j.id == id) return &j;
  return nullptr;
}

fs::path SweepManifest::base_dir() const {
  if (info.contains("base_dir") && info["base_dir"].is_string()) {
    const fs::path p = info["base_dir"].get<std::string>();
    std::error_code ec;
    if (fs::is_directory(p, ec)) return p;
  }
  return dir;
}

SweepManifest read_manifest(const fs::path& manifest_or_dir) {
  SweepManifest m;
  std::error_code ec;
  const fs::path given = fs::absolute(manifest_or_dir).lexically_normal();
  if (fs::is_directory(given, ec)) {
    m.dir = given;
    m.manifest = given / "manifest.jsonl";
    if (!fs::exists(m.manifest, ec))
      throw UserError(
          fmt::format("{}: not a sweep folder (no manifest.jsonl), expected the "
                      "--out folder of `driftlab sweep plan`",
                      given.string()));
  } else {
    m.manifest = given;
    m.dir = given.parent_path();
  }
  const std::string text =
      read_text_file(m.manifest, "manifest (written by `driftlab sweep plan`)");
  const fs::path info_file = m.dir / "sweep.json";
  try {
    m.info = nlohmann::json::parse(read_text_file(info_file, "sweep.json"));
  } catch (const nlohmann::json::parse_error& e) {
    throw UserError(
        fmt::format("{}: not valid JSON ({}), expected the sweep.json of `driftlab "
                    "sweep plan`",
                    info_file.string(), e.what()));
  }
  if (!m.info.is_object() || !m.info.contains("axes") || !m.info["axes"].is_array())
    throw UserError(
        fmt::format("{}: no axes list, expected the sweep.json of `driftlab sweep "
                    "plan`",
                    info_file.string()));
  for (const auto& a : m.info["axes"]) {
    AxisInfo ai;
    ai.key = a.value("key", "");
    ai.name = a.value("name", ai.key);
    ai.spec = a.value("spec", "values");
    ai.numeric = a.value("numeric", false);
    m.axes.push_back(ai);
  }
  std::istringstream in(text);
  std::string line;
  std::size_t line_no = 0;
  std::set<std::string> ids;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    const std::string where = fmt::format("{}:{}", m.manifest.string(), line_no);
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(line);
    } catch (const nlohmann::json::parse_error& e) {
      throw UserError(
          fmt::format("{}: not valid JSON ({}), expected one job per line", where, e.what()));
    }
    SweepJob job;
    try {
      job.id = j.at("id").get<std::string>();
      job.index = j.at("index").get<std::size_t>();
      job.point = j.at("point").get<std::size_t>();
      job.replicate = j.at("replicate").get<std::size_t>();
      job.seed = j.at("seed").get<std::uint64_t>();
      job.overrides = j.at("overrides").get<std::vector<std::string>>();
      job.hash = j.at("hash").get<std::string>();
    } catch (const nlohmann::json::exception& e) {
      throw UserError(
          fmt::format("{}: {}, expected a job with id, index, point, replicate, "
                      "seed, overrides and hash",
                      where, e.what()));
    }
    if (job.overrides.size() != m.axes.size() + 1)
      throw UserError(
          fmt::format("{}: job {}: got {} overrides, expected {} (one per axis of "
                      "sweep.json, then the seed)",
                      where, job.id, job.overrides.size(), m.axes.size() + 1));
    for (std::size_t i = 0; i < m.axes.size(); ++i) {
      const auto eq = job.overrides[i].find('=');
      job.params.emplace_back(m.axes[i].name,
                              eq == std::string::npos ? "" : job.overrides[i].substr(eq + 1));
    }
    if (job.index != m.jobs.size())
      throw UserError(fmt::format("{}: job {}: got index {}, expected {} (jobs in index order)",
                                  where, job.id, job.index, m.jobs.size()));
    if (!ids.insert(job.id).second)
      throw UserError(
          fmt::format("{}: job {}: duplicate id, expected each id once", where, job.id));
    m.jobs.push_back(std::move(job));
  }
  if (m.jobs.empty())
    throw UserError(fmt::format("{}: no jobs, expected one job per line", m.manifest.string()));
  return m;
}

// ---------------------------------------------------------------------------
// Status

JobStatus job_status(const SweepManifest& m, const SweepJob& job) {
  JobStatus st;
  st.id = job.id;
  st.index = job.index;
  std::error_code ec;
  const fs::path marker = m.marker(job.id);
  if (fs::exists(marker, ec)) {
    try {
      const auto j = nlohmann::json::parse(read_text_file(marker, "completion marker"));
      if (j.value("hash", "") == job.hash) {
        st.state = JobState::kDone;
      } else {
        st.state = JobState::kStale;
        st.detail = fmt::format("finished with parameter hash {}, the manifest now says {}",
                                j.value("hash", "?"), job.hash);
      }
    } catch (const std::exception& e) {
      st.state = JobState::kStale;
      st.detail = fmt::format("unreadable completion marker: {}", first_line(e.what()));
    }
    return st;
  }
  const fs::path failed = m.failed_record(job.id);
  if (fs::exists(failed, ec)) {
    st.state = JobState::kFailed;
    try {
      const auto j = nlohmann::json::parse(read_text_file(failed, "failure record"));
      st.detail = j.value("status", "failed");
      const std::string error = j.value("error", "");
      if (!error.empty()) st.detail += ": " + first_line(error);
    } catch (const std::exception&) {
      st.detail = "failed (unreadable record " + failed.string() + ")";
    }
    return st;
  }
  st.state = JobState::kMissing;
  return st;
}

std::string SweepStatus::brief() const {
  return fmt::format("{} jobs: {} done, {} failed, {} stale, {} missing", jobs.size(), done, failed,
                     stale, missing);
}

namespace {

// The pids in a temporary's name: every number after a ".tmp." or ".old.".
std::vector<pid_t> temporary_pids(const std::string& name) {
  std::vector<pid_t> pids;
  for (std::size_t pos = 0; (pos = name.find('.', pos)) != std::string::npos; ++pos) {
    if (name.compare(pos, 5, ".tmp.") != 0 && name.compare(pos, 5, ".old.") != 0) continue;
    std::size_t end = pos + 5;
    while (end < name.size() && std::isdigit(static_cast<unsigned char>(name[end]))) ++end;
    std::int64_t pid = 0;
    if (end > pos + 5 && yaml::parse_int64(name.substr(pos + 5, end - pos - 5), &pid))
      pids.push_back(static_cast<pid_t>(pid));
  }
  return pids;
}

bool any_alive(const std::vector<pid_t>& pids) {
  return std::any_of(pids.begin(), pids.end(), [](pid_t p) { return process_alive(p); });
}

// A missing job with a temporary under runs/ was interrupted, or is running now.
std::string interrupted_detail(const std::string& id, const std::vector<fs::path>& leftovers) {
  for (const auto& p : leftovers) {
    const std::string name = p.filename().string();
    if (name.rfind(id + ".", 0) != 0) continue;
    const auto pids = temporary_pids(name);
    const std::string pid = pids.empty() ? "?" : std::to_string(pids.front());
    return any_alive(pids)
               ? fmt::format("running now? runs/{} belongs to process {}, alive on this machine",
                             name, pid)
               : fmt::format(
                     "interrupted: runs/{} was left by process {}, gone from this "
                     "machine (killed, or the machine stopped)",
                     name, pid);
  }
  return "";
}

}  // namespace

SweepStatus sweep_status(const SweepManifest& m) {
  SweepStatus s;
  const std::vector<fs::path> leftovers = leftover_temporaries(m, false);
  for (const auto& job : m.jobs) {
    JobStatus st = job_status(m, job);
    switch (st.state) {
      case JobState::kDone:
        ++s.done;
        break;
      case JobState::kFailed:
        ++s.failed;
        break;
      case JobState::kStale:
        ++s.stale;
        break;
      case JobState::kMissing:
        ++s.missing;
        st.detail = interrupted_detail(job.id, leftovers);
        break;
    }
    s.jobs.push_back(std::move(st));
  }
  for (const auto& p : leftovers) s.leftovers.push_back(p.string());
  return s;
}

std::vector<fs::path> leftover_temporaries(const SweepManifest& m, bool remove) {
  std::vector<fs::path> out;
  std::error_code ec;
  const fs::path runs = m.dir / "runs";
  if (!fs::is_directory(runs, ec)) return out;
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(runs, ec)) entries.push_back(e.path());
  std::sort(entries.begin(), entries.end());
  for (const auto& p : entries) {
    const std::string name = p.filename().string();
    if (name.find(".tmp.") == std::string::npos && name.find(".old.") == std::string::npos)
      continue;
    if (remove && !any_alive(temporary_pids(name))) {
      fs::remove_all(p, ec);
      continue;
    }
    out.push_back(p);
  }
  return out;
}

Shard parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  std::uint64_t k = 0, n = 0;
  if (slash == std::string::npos || !yaml::parse_uint64(text.substr(0, slash), &k) ||
      !yaml::parse_uint64(text.substr(slash + 1), &n) || n == 0 || k >= n)
    throw UserError(
        fmt::format("--shard: got '{}', expected K/N with 0 <= K < N (K is 0-based, "
                    "as SLURM_ARRAY_TASK_ID of --array=0-(N-1))",
                    text));
  return {static_cast<std::size_t>(k), static_cast<std::size_t>(n)};
}

bool in_shard(const SweepJob& job, const Shard& shard) {
  return job.index % shard.count == shard.index;
}

}  // namespace driftlab::study
