#include "study/sweep.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/yaml_io.hpp"

namespace driftlab::study {

namespace fs = std::filesystem;

namespace {

// Levels of one axis: more is a typo (a step of 1 over 444245), and expanding it alone takes
// seconds (found by fuzz/sweep_fuzz.cpp).
constexpr std::size_t kMaxAxisValues = 10000;

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
      values.push_back(detail::tidy_level(*start + static_cast<double>(k) * *step));
  } else {
    if (*num > kMaxAxisValues) {
      axis_reader.fail(node, path + ".num", std::to_string(*num),
                       fmt::format("at most {} values on one axis", kMaxAxisValues));
      return;
    }
    for (std::uint64_t k = 0; k < *num; ++k) {
      const double t = *num == 1 ? 0.0 : static_cast<double>(k) / static_cast<double>(*num - 1);
      values.push_back(axis->spec == AxisSpec::kLinspace
                           ? detail::tidy_level(*start + (*stop - *start) * t)
                           : detail::tidy_level(std::exp(
                                 std::log(*start) + (std::log(*stop) - std::log(*start)) * t)));
    }
  }
  for (double v : values) axis->levels.push_back(yaml::format_double(v));
}

}  // namespace

// ---------------------------------------------------------------------------
// Sweep file

namespace {

// `base`: the base scenario, relative to the sweep file's folder.
void read_base(MapReader& r, const std::string& label, const fs::path& dir, Sweep* s,
               yaml::ErrorList* errors) {
  const YAML::Node base = r.get("base");
  if (!base) {
    errors->add(
        fmt::format("{}: base: missing, expected the path of the base scenario "
                    "(relative to the sweep file)",
                    label));
    return;
  }
  if (!base.IsScalar() || base.Scalar().empty()) {
    r.fail(base, "base", yaml::describe_node(base),
           "the path of the base scenario (relative to the sweep file)");
    return;
  }
  fs::path p = base.Scalar();
  if (p.is_relative()) p = dir / p;
  s->base = fs::absolute(p).lexically_normal();
  s->base_where = r.where(base);
  std::error_code ec;
  if (!fs::is_regular_file(s->base, ec))
    r.fail(base, "base", "'" + base.Scalar() + "'",
           "an existing scenario file (relative to the sweep file: " + s->base.string() +
               " does not exist)");
}

// `set`: scenario key paths fixed for every job.
void read_set(MapReader& r, Sweep* s) {
  const YAML::Node set = r.get("set");
  if (!set) return;
  if (!set.IsMap()) {
    r.fail(set, "set", yaml::describe_node(set),
           "a mapping of scenario key paths to values (e.g. pipeline.max_frames: 50)");
    return;
  }
  for (auto it = set.begin(); it != set.end(); ++it) {
    if (!it->first.IsScalar() || it->first.Scalar().empty()) {
      r.fail(it->first, "set", yaml::describe_node(it->first), "a scenario key path");
      continue;
    }
    s->set.emplace_back(it->first.Scalar(), yaml_text(it->second));
    s->set_where.push_back(r.where(it->first));
  }
}

// `design`, `samples`, `replicates`, `seed`. Returns false when the design is unreadable
// (generated axes then cannot be checked against it).
bool read_design(MapReader& r, Sweep* s) {
  const YAML::Node design = r.get("design");
  bool design_ok = true;
  if (design) {
    std::optional<SweepDesign> d;
    if (design.IsScalar()) d = yaml::enum_from_name<SweepDesign>(design.Scalar());
    if (!d) {
      r.fail(design, "design", yaml::describe_node(design),
             "one of: " + yaml::enum_choices<SweepDesign>());
      design_ok = false;
    } else {
      s->design = *d;
    }
  }
  const YAML::Node samples = r.get("samples");
  if (samples && design_ok && s->design != SweepDesign::kRandom) {
    r.fail(samples, "samples", yaml::describe_node(samples),
           fmt::format("no samples with design {} (samples is the number of points of design "
                       "random; grid and zip take their points from the axes)",
                       yaml::enum_name(s->design)));
  } else if (samples) {
    s->samples = r.count("samples", 1, "an integer >= 1 (points of the random design)").value_or(0);
  } else if (design_ok && s->design == SweepDesign::kRandom) {
    r.fail(design, "design", "'random'",
           "samples: N alongside it (the number of Latin hypercube points, N >= 1)");
  }
  if (r.has("replicates"))
    s->replicates =
        r.count("replicates", 1, "an integer >= 1 (runs per point, each with its own seed)")
            .value_or(1);
  else
    r.get("replicates");
  if (r.has("seed"))
    s->seed = r.count("seed", 0, "a non-negative integer");
  else
    r.get("seed");
  return design_ok;
}

// An axis's `values` list.
void read_axis_values(MapReader& ar, const YAML::Node& n, const std::string& spec_path,
                      SweepAxis* axis) {
  if (!n.IsSequence()) {
    ar.fail(n, spec_path, yaml::describe_node(n), "a list of values");
    return;
  }
  if (n.size() == 0) {
    ar.fail(n, spec_path, "an empty list", "at least one value");
    return;
  }
  for (std::size_t k = 0; k < n.size(); ++k) {
    if (n[k].IsNull()) {
      ar.fail(n[k], fmt::format("{}[{}]", spec_path, k), yaml::describe_node(n[k]), "a value");
      continue;
    }
    axis->levels.push_back(yaml_text(n[k]));
    axis->level_where.push_back(ar.where(n[k]));
  }
}

// axes[i]: {key, name, and one of values, range, linspace, logspace}.
SweepAxis read_axis(const YAML::Node& a, const std::string& path, const Sweep& s, bool design_ok,
                    const std::string& label, yaml::ErrorList* errors) {
  MapReader ar(a, label, path, errors);
  SweepAxis axis;
  axis.where = ar.where(a);
  const YAML::Node key = ar.get("key");
  if (!key) {
    errors->add(
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
    errors->add(
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
    const std::string spec_path = path + "." + std::string(yaml::enum_name(axis.spec));
    if (axis.spec == AxisSpec::kValues)
      read_axis_values(ar, specs[0].second, spec_path, &axis);
    else if (design_ok)
      read_generated_axis(ar, specs[0].second, spec_path, &axis, s.design, errors, label);
  }
  ar.finish();
  for (const auto& level : axis.levels) {
    double v = 0;
    const YAML::Node parsed = YAML::Load(level);
    axis.numeric = axis.numeric && parsed.IsScalar() && yaml::parse_double(level, &v);
  }
  return axis;
}

// `axes`: a list of at least one axis.
void read_axes(MapReader& r, const std::string& label, bool design_ok, Sweep* s,
               yaml::ErrorList* errors) {
  const YAML::Node axes = r.get("axes");
  if (!axes) {
    errors->add(
        fmt::format("{}: axes: missing, expected a list of axes ({{key: ..., values: "
                    "[...]}})",
                    label));
    return;
  }
  if (!axes.IsSequence() || axes.size() == 0) {
    r.fail(axes, "axes", axes.IsSequence() ? "an empty list" : yaml::describe_node(axes),
           "a list of at least one axis ({key: ..., values: [...]})");
    return;
  }
  for (std::size_t i = 0; i < axes.size(); ++i) {
    const YAML::Node a = axes[i];
    const std::string path = fmt::format("axes[{}]", i);
    if (!a.IsMap()) {
      r.fail(a, path, yaml::describe_node(a), "a mapping {key: ..., values: [...]}");
      continue;
    }
    s->axes.push_back(read_axis(a, path, *s, design_ok, label, errors));
  }
}

// Rules across axes and the fixed overrides: distinct keys and column names, no seed axis,
// nothing both fixed and swept, equal lengths for design zip.
void check_across_axes(const Sweep& s, yaml::ErrorList* errors) {
  std::map<std::string, std::size_t> keys, names;
  for (std::size_t i = 0; i < s.axes.size(); ++i) {
    const SweepAxis& a = s.axes[i];
    if (a.key == "seed")
      errors->add(
          fmt::format("{}: axes[{}].key: got 'seed', expected another key (each "
                      "replicate gets its own seed: use replicates and the sweep's seed)",
                      a.where, i));
    if (auto [it, fresh] = keys.emplace(a.key, i); !fresh)
      errors->add(
          fmt::format("{}: axes[{}].key: got '{}' again (axes[{}]), expected each key "
                      "in one axis only",
                      a.where, i, a.key, it->second));
    if (auto [it, fresh] = names.emplace(a.name, i); !fresh && a.key != s.axes[it->second].key)
      errors->add(
          fmt::format("{}: axes[{}].name: got '{}' again (axes[{}]), expected a distinct "
                      "column name",
                      a.where, i, a.name, it->second));
    for (const char* reserved : {"job", "point", "replicate", "seed"})
      if (a.name == reserved && a.key != "seed")
        errors->add(
            fmt::format("{}: axes[{}].name: got '{}', expected a name other than job, "
                        "point, replicate and seed (columns of the merged tables)",
                        a.where, i, a.name));
  }
  for (std::size_t i = 0; i < s.set.size(); ++i) {
    if (keys.count(s.set[i].first))
      errors->add(
          fmt::format("{}: set.{}: also swept by axes[{}], expected each key either fixed "
                      "in set or swept",
                      s.set_where[i], s.set[i].first, keys[s.set[i].first]));
    if (s.set[i].first == "seed")
      errors->add(
          fmt::format("{}: set.seed: got a fixed seed, expected the sweep's own seed key "
                      "(each replicate derives its seed from it)",
                      s.set_where[i]));
  }
  if (s.design == SweepDesign::kZip && s.axes.size() > 1) {
    for (std::size_t i = 1; i < s.axes.size(); ++i)
      if (s.axes[i].levels.size() != s.axes[0].levels.size())
        errors->add(
            fmt::format("{}: axes[{}]: got {} values, expected {} like axes[0] (design zip "
                        "pairs the k-th values of every axis)",
                        s.axes[i].where, i, s.axes[i].levels.size(), s.axes[0].levels.size()));
  }
}

}  // namespace

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
  read_base(r, label, dir, &s, &errors);
  read_set(r, &s);
  const bool design_ok = read_design(r, &s);
  read_axes(r, label, design_ok, &s, &errors);
  r.finish();
  errors.throw_if_any();
  check_across_axes(s, &errors);
  errors.throw_if_any();
  return s;
}

namespace detail {

double tidy_level(double v) {
  double out = v;
  yaml::parse_double(fmt::format("{:.12g}", v), &out);
  return out == 0 ? 0.0 : out;  // no "-0"
}

}  // namespace detail

Sweep load_sweep(const fs::path& file) {
  return parse_sweep(read_text_file(file, "sweep file"), file.string(), file.parent_path());
}

}  // namespace driftlab::study
