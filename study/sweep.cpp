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

// ---------------------------------------------------------------------------
// The sweep file as written: read by the strict reader (yaml::Reader), like scenarios and
// baselines. `driftlab sweep schema` prints its reference from the same visit() lists.

// `range`, `linspace` or `logspace` of an axis.
struct GeneratedLevels {
  double start = 0;
  double stop = 0;
  std::optional<double> step;
  std::optional<std::uint64_t> num;
  std::string where, num_where;

  template <class A>
  void visit(A& a) {
    a.location(&where);
    a.location("num", &num_where);
    a("start", start, "First value", yaml::required("a number"));
    a("stop", stop, "Last value (linspace, logspace) or the bound before which range stops",
      yaml::required("a number"));
    a("step", step, "range only: the step (required there): start + k * step before stop");
    a("num", num,
      "linspace and logspace with designs grid and zip: the number of values (required there); "
      "design random samples [start, stop] continuously and takes no num",
      yaml::at_least(1) & yaml::expecting("an integer >= 1"));
  }
};

// axes[i].
struct AxisEntry {
  std::string key;
  std::optional<std::string> name;
  std::optional<std::vector<yaml::Any>> values;
  std::optional<GeneratedLevels> range, linspace, logspace;
  std::string where, key_where;

  template <class A>
  void visit(A& a) {
    a.location(&where);
    a.location("key", &key_where);
    a("key", key, "The scenario key path swept (docs/scenario-reference.md)",
      yaml::non_empty() &
          yaml::required("a scenario key path such as mission.yaw_weave.amplitude_deg"));
    a("name", name, "Its column in the merged tables (default: the key path)", yaml::non_empty());
    a("values", values, "The values, as YAML (numbers, strings, lists)");
    a("range", range, "{start, stop, step}: start + k * step, stop excluded (Python's range)");
    a("linspace", linspace,
      "{start, stop, num}: num evenly spaced values, both ends included (design random: "
      "{start, stop}, sampled uniformly)");
    a("logspace", logspace,
      "{start, stop, num}: num values evenly spaced on a log scale, start and stop > 0 (design "
      "random: {start, stop}, sampled log-uniformly)");
    a.exactly_one_of({"values", "range", "linspace", "logspace"});
    a.require(!values || !values->empty(), "values", "at least one value");
  }
};

struct SweepFile {
  std::optional<std::string> name;
  std::string description;
  std::string base;
  yaml::Entries<yaml::Any> set;
  SweepDesign design = SweepDesign::kGrid;
  std::optional<std::uint64_t> samples;
  std::uint64_t replicates = 1;
  std::optional<std::uint64_t> seed;
  std::vector<AxisEntry> axes;
  std::string base_where;

  template <class A>
  void visit(A& a) {
    a("name", name, "The sweep's name (default: the file name without .yaml)", yaml::non_empty());
    a("description", description, "What the sweep is for, in words");
    a("base", base, "The base scenario, relative to the sweep file",
      yaml::required("the path of the base scenario (relative to the sweep file)") &
          yaml::non_empty());
    a.location("base", &base_where);
    a("set", set,
      "Scenario key paths fixed for every job, e.g. `pipeline.max_frames: 50` (a key is either "
      "fixed here or swept)",
      yaml::expecting("a mapping of scenario key paths to values (e.g. pipeline.max_frames: 50)"));
    a("design", design,
      "grid: every combination of the axes' values; zip: the k-th values of every axis "
      "together; random: a Latin hypercube of `samples` points");
    a("samples", samples, "design random only: the number of points (required there)",
      yaml::expecting("an integer >= 1 (points of the random design)"));
    a("replicates", replicates, "Runs per point, each with its own seed",
      yaml::expecting("an integer >= 1 (runs per point, each with its own seed)"));
    a("seed", seed,
      "The sweep's seed, from which every replicate derives its own (default: the base "
      "scenario's seed)");
    a("axes", axes, "The swept keys: {key, name, and one of values, range, linspace, logspace}",
      yaml::required("a list of axes ({key: ..., values: [...]})"));
    a.require(!axes.empty(), "axes", "a list of at least one axis ({key: ..., values: [...]})");
    a.require(design != SweepDesign::kRandom || samples.has_value(), "design",
              "samples: N alongside it (the number of Latin hypercube points, N >= 1)");
    a.require(design == SweepDesign::kRandom || !samples.has_value(), "samples",
              fmt::format("no samples with design {} (samples is the number of points of "
                          "design random; grid and zip take their points from the axes)",
                          yaml::enum_name(design)));
    a.require(!samples || *samples >= 1, "samples",
              "an integer >= 1 (points of the random design)");
    a.require(replicates >= 1, "replicates",
              "an integer >= 1 (runs per point, each with its own seed)");
  }
};

// "FILE:LINE:COL: PATH: got GOT, expected EXPECTED".
void fail(yaml::ErrorList* errors, const std::string& where, const std::string& path,
          const std::string& got, const std::string& expected) {
  errors->add(fmt::format("{}: {}: got {}, expected {}", where, path, got, expected));
}

// Checks a generated axis against the design; returns its start, stop and the number of
// values (0 for a continuous axis), or nothing after reporting a problem.
struct GeneratedShape {
  bool continuous = false;
  std::uint64_t count = 0;
};
std::optional<GeneratedShape> check_generated(const GeneratedLevels& g, AxisSpec spec,
                                              SweepDesign design, const std::string& path,
                                              yaml::ErrorList* errors) {
  const bool continuous = design == SweepDesign::kRandom && spec != AxisSpec::kRange;
  const std::string bounds = fmt::format("start {} and stop {}", yaml::format_double(g.start),
                                         yaml::format_double(g.stop));
  if (spec == AxisSpec::kRange && !g.step) {
    errors->add(fmt::format("{}: {}.step: missing, expected a number", g.where, path));
    return std::nullopt;
  }
  if (spec != AxisSpec::kRange && continuous && g.num) {
    fail(errors, g.num_where, path + ".num", fmt::format("'{}'", *g.num),
         "no num with design random (a random design samples [start, stop] continuously; num "
         "is for designs grid and zip)");
    return std::nullopt;
  }
  if (spec != AxisSpec::kRange && !continuous && !g.num) {
    errors->add(fmt::format("{}: {}.num: missing, expected an integer >= 1", g.where, path));
    return std::nullopt;
  }
  if (spec == AxisSpec::kLogspace && (g.start <= 0 || g.stop <= 0)) {
    fail(errors, g.where, path, bounds,
         "start > 0 and stop > 0 (logspace spaces values evenly on a log scale)");
    return std::nullopt;
  }
  if (continuous) {
    if (g.start < g.stop) return GeneratedShape{.continuous = true};
    fail(errors, g.where, path, bounds, "start < stop (the interval a random design samples)");
    return std::nullopt;
  }
  if (spec != AxisSpec::kRange) {
    if (*g.num <= kMaxAxisValues) return GeneratedShape{.count = *g.num};
    fail(errors, g.num_where, path + ".num", std::to_string(*g.num),
         fmt::format("at most {} values on one axis", kMaxAxisValues));
    return std::nullopt;
  }
  if (*g.step == 0) {
    fail(errors, g.where, path + ".step", "0", "a non-zero step");
    return std::nullopt;
  }
  const double n = std::ceil((g.stop - g.start) / *g.step - 1e-9);
  if (!(n >= 1)) {
    fail(errors, g.where, path,
         fmt::format("an empty range (start {}, stop {}, step {})", yaml::format_double(g.start),
                     yaml::format_double(g.stop), yaml::format_double(*g.step)),
         "at least one value: start + k * step for k = 0, 1, ... strictly before "
         "stop (stop excluded, as in Python's range)");
    return std::nullopt;
  }
  if (n > static_cast<double>(kMaxAxisValues)) {
    fail(errors, g.where, path, fmt::format("{:.0f} values", n),
         fmt::format("at most {} values on one axis", kMaxAxisValues));
    return std::nullopt;
  }
  return GeneratedShape{.count = static_cast<std::uint64_t>(n)};
}

// The values of `range`, `linspace` or `logspace` (or the interval of a continuous axis).
void generate_levels(const GeneratedLevels& g, SweepDesign design, const std::string& path,
                     SweepAxis* axis, yaml::ErrorList* errors) {
  const auto shape = check_generated(g, axis->spec, design, path, errors);
  if (!shape) return;
  if (shape->continuous) {
    axis->continuous = true;
    axis->start = g.start;
    axis->stop = g.stop;
    return;
  }
  for (std::uint64_t k = 0; k < shape->count; ++k) {
    double v = 0;
    if (axis->spec == AxisSpec::kRange) {
      v = g.start + static_cast<double>(k) * *g.step;
    } else {
      const double t =
          shape->count == 1 ? 0.0 : static_cast<double>(k) / static_cast<double>(shape->count - 1);
      v = axis->spec == AxisSpec::kLinspace
              ? g.start + (g.stop - g.start) * t
              : std::exp(std::log(g.start) + (std::log(g.stop) - std::log(g.start)) * t);
    }
    axis->levels.push_back(yaml::format_double(detail::tidy_level(v)));
  }
}

// axes[i] as the plan uses it: its levels listed or generated.
SweepAxis to_axis(const AxisEntry& e, SweepDesign design, const std::string& path,
                  yaml::ErrorList* errors) {
  SweepAxis axis;
  axis.key = e.key;
  axis.name = e.name.value_or(e.key);
  axis.where = e.key_where;
  const std::pair<AxisSpec, const std::optional<GeneratedLevels>*> generated[] = {
      {AxisSpec::kRange, &e.range},
      {AxisSpec::kLinspace, &e.linspace},
      {AxisSpec::kLogspace, &e.logspace}};
  if (e.values) {
    axis.spec = AxisSpec::kValues;
    for (std::size_t k = 0; k < e.values->size(); ++k) {
      const yaml::Any& v = (*e.values)[k];
      if (v.node.IsNull()) {
        fail(errors, v.where, fmt::format("{}.values[{}]", path, k), yaml::describe_node(v.node),
             "a value");
        continue;
      }
      axis.levels.push_back(v.flow_text());
      axis.level_where.push_back(v.where);
    }
  }
  for (const auto& [spec, levels] : generated) {
    if (!*levels) continue;
    axis.spec = spec;
    generate_levels(**levels, design, path + "." + std::string(yaml::enum_name(spec)), &axis,
                    errors);
  }
  for (const auto& level : axis.levels) {
    double v = 0;
    const YAML::Node parsed = YAML::Load(level);
    axis.numeric = axis.numeric && parsed.IsScalar() && yaml::parse_double(level, &v);
  }
  return axis;
}

// The sweep file as the plan uses it: the base scenario found, the axes' levels listed.
Sweep to_sweep(const SweepFile& f, const std::string& label, const fs::path& dir,
               yaml::ErrorList* errors) {
  Sweep s;
  s.file = fs::absolute(label).lexically_normal();
  s.name = f.name.value_or(fs::path(label).stem().string());
  s.description = f.description;
  fs::path base = f.base;
  if (base.is_relative()) base = dir / base;
  s.base = fs::absolute(base).lexically_normal();
  s.base_where = f.base_where;
  std::error_code ec;
  if (!fs::is_regular_file(s.base, ec))
    fail(errors, f.base_where, "base", "'" + f.base + "'",
         "an existing scenario file (relative to the sweep file: " + s.base.string() +
             " does not exist)");
  for (const auto& e : f.set) {
    s.set.emplace_back(e.key, e.value.flow_text());
    s.set_where.push_back(e.where);
  }
  s.design = f.design;
  s.samples = f.samples.value_or(0);
  s.replicates = f.replicates;
  s.seed = f.seed;
  for (std::size_t i = 0; i < f.axes.size(); ++i)
    s.axes.push_back(to_axis(f.axes[i], f.design, fmt::format("axes[{}]", i), errors));
  return s;
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
  SweepFile file;
  yaml::read_into(yaml::load_string(text, label), yaml::Source{label}, &file);
  yaml::ErrorList errors;
  Sweep s = to_sweep(file, label, dir, &errors);
  errors.throw_if_any();
  check_across_axes(s, &errors);
  errors.throw_if_any();
  return s;
}

std::string sweep_reference_markdown() {
  return yaml::schema_markdown(yaml::schema_of(SweepFile{}));
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

void apply_sets(Sweep* sweep, const std::vector<std::string>& assignments) {
  for (const std::string& a : assignments) {
    const auto eq = a.find('=');
    if (eq == std::string::npos || eq == 0)
      throw UserError(fmt::format("--set {}: got '{}', expected KEY.PATH=VALUE", a, a));
    const std::string key = a.substr(0, eq);
    const std::string where = "--set " + a;
    // A key the file fixes takes the command line's value; another joins the fixed ones.
    std::size_t i = 0;
    while (i < sweep->set.size() && sweep->set[i].first != key) ++i;
    if (i == sweep->set.size()) {
      sweep->set.emplace_back(key, "");
      sweep->set_where.push_back(where);
    }
    sweep->set[i].second = a.substr(eq + 1);
    sweep->set_where[i] = where;
  }
  yaml::ErrorList errors;
  check_across_axes(*sweep, &errors);
  errors.throw_if_any();
}

}  // namespace driftlab::study
