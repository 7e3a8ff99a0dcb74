#include "gate/gate.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/markup.hpp"
#include "core/yaml_io.hpp"

namespace driftlab::gate {
namespace fs = std::filesystem;

namespace {

std::string g(double v) { return fmt::format("{:.6g}", v); }

}  // namespace

double pairs_mean(const std::vector<PairValue>& pairs) {
  double sum = 0;
  for (const PairValue& p : pairs) sum += p.value;
  return pairs.empty() ? 0.0 : sum / static_cast<double>(pairs.size());
}

double BaselineMetric::tolerance() const {
  return std::max(abs_tol, baseline ? rel_tol * std::abs(*baseline) : 0.0);
}

Baseline load_baseline(const fs::path& file) {
  Baseline b;
  yaml::read_into(yaml::load_file(file.string()), yaml::Source{file.string()}, &b);
  b.file = file;
  // Each key once (a rule across the entries).
  yaml::ErrorList errors;
  std::set<std::string> keys;
  for (std::size_t i = 0; i < b.metrics.size(); ++i) {
    const BaselineMetric& m = b.metrics[i];
    if (!keys.insert(m.key).second)
      errors.add(fmt::format("{}: metrics[{}].key: got '{}' again, expected each key once",
                             m.key_where, i, m.key));
  }
  errors.throw_if_any();
  return b;
}

std::string baseline_reference_markdown() {
  return yaml::schema_markdown(yaml::schema_of(Baseline{}));
}

std::string baseline_json(const Baseline& b) {
  nlohmann::ordered_json j;
  if (!b.description.empty()) j["description"] = b.description;
  j["metrics"] = nlohmann::ordered_json::array();
  // Each metric's pairs one per line (a baseline of a few hundred pairs stays readable): a
  // placeholder in the indented text, replaced by the compact lines.
  std::vector<std::string> pair_lines;
  for (const auto& m : b.metrics) {
    nlohmann::ordered_json e;
    e["key"] = m.key;
    e["baseline"] = m.baseline ? nlohmann::ordered_json(*m.baseline) : nlohmann::ordered_json();
    e["direction"] = std::string(yaml::enum_name(m.direction));
    if (m.pairs.empty()) {
      e["abs_tol"] = m.abs_tol;
      e["rel_tol"] = m.rel_tol;
    } else {
      e["min_effect"] = m.min_effect;
      e["alpha"] = m.alpha;
      std::string lines;
      for (const PairValue& p : m.pairs)
        lines += (lines.empty() ? "\n        " : ",\n        ") +
                 nlohmann::ordered_json{{"id", p.id}, {"value", p.value}}.dump();
      e["pairs"] = fmt::format("@pairs {}@", pair_lines.size());
      pair_lines.push_back("[" + lines + "\n      ]");
    }
    j["metrics"].push_back(e);
  }
  std::string text = j.dump(2);
  for (std::size_t i = 0; i < pair_lines.size(); ++i) {
    const std::string placeholder = fmt::format("\"@pairs {}@\"", i);
    text.replace(text.find(placeholder), placeholder.size(), pair_lines[i]);
  }
  return text + "\n";
}

fs::path find_results_metrics(const fs::path& results) {
  std::error_code ec;
  if (fs::is_regular_file(results, ec)) return results;
  if (!fs::exists(results, ec))
    throw UserError(
        fmt::format("--results: got '{}', expected an existing run folder, merged "
                    "sweep folder or metrics.json",
                    results.string()));
  if (fs::is_regular_file(results / "metrics.json", ec)) return results / "metrics.json";
  if (fs::is_regular_file(results / "summary" / "metrics.json", ec))
    return results / "summary" / "metrics.json";
  if (fs::exists(results / "manifest.jsonl", ec))
    throw UserError(
        fmt::format("--results: got '{}', a sweep folder that is not merged yet, "
                    "expected DIR/summary/metrics.json: run `driftlab sweep merge {}` "
                    "first",
                    results.string(), results.string()));
  throw UserError(
      fmt::format("--results: got '{}', expected a run folder (with metrics.json), "
                  "a merged sweep folder (with summary/metrics.json) or a "
                  "metrics.json file",
                  results.string()));
}

nlohmann::json read_results_metrics(const fs::path& file) {
  try {
    return nlohmann::json::parse(read_text_file(file, "metrics.json"));
  } catch (const nlohmann::json::exception& e) {  // syntax, and numbers past double's range
    throw UserError(
        fmt::format("{}: not valid JSON ({}), expected metrics.json", file.string(), e.what()));
  }
}

const nlohmann::json* metric_node(const nlohmann::json& doc, const std::string& key,
                                  std::string* why) {
  const nlohmann::json* node = &doc;
  if (!key.empty() && key[0] == '/') {
    try {
      const nlohmann::json::json_pointer ptr(key);
      if (!doc.contains(ptr)) {
        *why = "no such key";
        return nullptr;
      }
      return &doc.at(ptr);
    } catch (const nlohmann::json::exception& e) {
      *why = std::string("not a valid JSON pointer: ") + e.what();
      return nullptr;
    }
  }
  std::size_t start = 0;
  std::string walked;
  while (true) {
    const auto dot = key.find('.', start);
    const std::string part = key.substr(start, dot == std::string::npos ? dot : dot - start);
    if (node->is_object() && node->contains(part)) {
      node = &(*node)[part];
    } else if (node->is_array() && !part.empty() &&
               std::all_of(part.begin(), part.end(),
                           [](char ch) { return ch >= '0' && ch <= '9'; }) &&
               std::stoul(part) < node->size()) {
      node = &(*node)[std::stoul(part)];
    } else {
      *why = walked.empty() ? fmt::format("no '{}' at the top level", part)
                            : fmt::format("no '{}' under {}", part, walked);
      return nullptr;
    }
    walked += (walked.empty() ? "" : ".") + part;
    if (dot == std::string::npos) return node;
    start = dot + 1;
  }
}

std::optional<double> metric_value(const nlohmann::json& doc, const std::string& key,
                                   std::string* why) {
  const nlohmann::json* node = metric_node(doc, key, why);
  if (!node) return std::nullopt;
  if (node->is_null()) {
    *why = "null (not computed for these results)";
    return std::nullopt;
  }
  if (!node->is_number()) {
    *why = fmt::format("not a number ({})", node->type_name());
    return std::nullopt;
  }
  return node->get<double>();
}

std::optional<std::vector<PairValue>> metric_pairs(const nlohmann::json& doc,
                                                   const std::string& key, std::string* why) {
  const nlohmann::json* node = metric_node(doc, key, why);
  if (!node) return std::nullopt;
  if (!node->is_object() || node->empty()) {
    *why = fmt::format("not an object of paired values ({})", node->type_name());
    return std::nullopt;
  }
  std::vector<PairValue> pairs;
  for (const auto& [id, v] : node->items())
    if (v.is_number() && std::isfinite(v.get<double>())) pairs.push_back({id, v.get<double>()});
  return pairs;
}

namespace {

// The verdict of a change `diff` (new - baseline) that is beyond the metric's bar in the bad
// direction (`worse`) or in the good one (`better`), as the direction reads them.
Verdict verdict_of(MetricDirection direction, bool up, bool down) {
  switch (direction) {
    case MetricDirection::kLower:
      return up ? Verdict::kRegressed : down ? Verdict::kImproved : Verdict::kPass;
    case MetricDirection::kHigher:
      return down ? Verdict::kRegressed : up ? Verdict::kImproved : Verdict::kPass;
    case MetricDirection::kBoth:
      return up || down ? Verdict::kRegressed : Verdict::kPass;
  }
  return Verdict::kPass;
}

// A paired metric: the new values at its key, matched to the baseline's pairs by id.
void check_paired(const nlohmann::json& results, MetricCheck* c) {
  const BaselineMetric& m = c->metric;
  const auto found = metric_pairs(results, m.key, &c->note);
  if (!found) {
    c->verdict = Verdict::kMissing;
    return;
  }
  c->new_pairs = *found;
  std::map<std::string, double> by_id;
  for (const PairValue& p : *found) by_id[p.id] = p.value;
  std::vector<double> a, b;
  std::vector<std::string> missing;
  for (const PairValue& p : m.pairs) {
    const auto it = by_id.find(p.id);
    if (it == by_id.end()) {
      missing.push_back(p.id);
      continue;
    }
    a.push_back(p.value);
    b.push_back(it->second);
  }
  const PairedChange pc = paired_change(a, b);
  c->paired = pc;
  c->value = pc.mean_b;
  if (!missing.empty()) {
    c->verdict = Verdict::kMissing;
    c->note = fmt::format("{} of {} pairs have no value in the results (first {})", missing.size(),
                          m.pairs.size(), missing.front());
    return;
  }
  const bool up = pc.test.p_greater < m.alpha && pc.rel > m.min_effect;
  const bool down = pc.test.p_less < m.alpha && pc.rel < -m.min_effect;
  c->verdict = verdict_of(m.direction, up, down);
}

}  // namespace

GateResult check_baseline(const Baseline& baseline, const nlohmann::json& results,
                          const fs::path& results_file) {
  GateResult r;
  r.baseline_file = baseline.file;
  r.results_file = results_file;
  for (const auto& m : baseline.metrics) {
    MetricCheck c;
    c.metric = m;
    if (!m.pairs.empty()) {
      check_paired(results, &c);
    } else if (c.value = metric_value(results, m.key, &c.note); !c.value) {
      c.verdict = Verdict::kMissing;
    } else if (!m.baseline) {
      c.verdict = Verdict::kNoBaseline;
      c.note = "no baseline value yet (record one with --update)";
    } else {
      const double diff = *c.value - *m.baseline;
      const double tol = m.tolerance();
      c.verdict = verdict_of(m.direction, diff > tol, diff < -tol);
    }
    r.checks.push_back(std::move(c));
  }
  return r;
}

std::size_t GateResult::failures() const {
  return static_cast<std::size_t>(
      std::count_if(checks.begin(), checks.end(), [](const MetricCheck& c) { return c.failed(); }));
}

namespace {

std::string change_text(const MetricCheck& c) {
  if (c.paired) {
    const PairedChange& p = *c.paired;
    if (p.n == 0 || p.mean_a == 0) return "";
    return fmt::format("{:+.1f}% [{:+.1f}, {:+.1f}]", 100 * p.rel, 100 * p.rel_lo, 100 * p.rel_hi);
  }
  if (!c.value || !c.metric.baseline) return "";
  const double diff = *c.value - *c.metric.baseline;
  std::string s = fmt::format("{:+.3g}", diff);
  if (*c.metric.baseline != 0)
    s += fmt::format(" ({:+.1f}%)", 100.0 * diff / std::abs(*c.metric.baseline));
  return s;
}

// The bar a change must clear: the tolerance, or for a paired metric the smallest effect and
// the test's level with the p-value found.
std::string tolerance_text(const MetricCheck& c) {
  const MetricDirection d = c.metric.direction;
  const char* sign = d == MetricDirection::kLower ? "+" : d == MetricDirection::kHigher ? "-" : "±";
  if (!c.metric.pairs.empty()) {
    std::string s =
        fmt::format("{}{:.0f}% at p<{:g}", sign, 100 * c.metric.min_effect, c.metric.alpha);
    if (c.paired && c.paired->n > 0) {
      const SignedRankTest& t = c.paired->test;
      const double p = d == MetricDirection::kLower    ? t.p_greater
                       : d == MetricDirection::kHigher ? t.p_less
                                                       : std::min(t.p_greater, t.p_less);
      s += fmt::format(" (p={:.2g}, {} pairs)", p, c.paired->n);
    }
    return s;
  }
  return sign + g(c.metric.tolerance());
}

}  // namespace

std::string GateResult::table() const {
  std::vector<std::array<std::string, 6>> rows;
  rows.push_back({"metric", "baseline", "new", "change", "tolerance", "verdict"});
  for (const auto& c : checks) {
    std::string verdict(yaml::enum_name(c.verdict));
    if (c.verdict == Verdict::kMissing) verdict += ": " + c.note;
    rows.push_back({c.metric.key,
                    c.paired            ? g(c.paired->mean_a)
                    : c.metric.baseline ? g(*c.metric.baseline)
                                        : "—",
                    c.value ? g(*c.value) : "—", change_text(c), tolerance_text(c), verdict});
  }
  std::array<std::size_t, 6> width{};
  for (const auto& r : rows)
    for (std::size_t k = 0; k < 5; ++k) width[k] = std::max(width[k], r[k].size());
  std::string out;
  for (const auto& r : rows) {
    std::string line;
    for (std::size_t k = 0; k < 6; ++k) {
      const bool left = k == 0 || k == 5;
      line += k == 5 ? r[k]
              : left ? fmt::format("{:<{}}  ", r[k], width[k])
                     : fmt::format("{:>{}}  ", r[k], width[k]);
    }
    out += line + "\n";
  }
  return out;
}

std::string GateResult::brief() const {
  std::size_t counts[5] = {};
  for (const auto& c : checks) ++counts[static_cast<int>(c.verdict)];
  std::string s = fmt::format("{} metrics:", checks.size());
  bool first = true;
  for (const auto& [v, name] : enum_table(Verdict{})) {
    const std::size_t n = counts[static_cast<int>(v)];
    if (n == 0 && v != Verdict::kPass) continue;
    s += fmt::format("{} {} {}", first ? "" : ",", n, name);
    first = false;
  }
  return s;
}

std::string GateResult::junit_xml() const {
  const std::string suite = "driftlab.regress." + baseline_file.stem().string();
  std::string x = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  x += fmt::format(
      "<testsuites name=\"driftlab regress\" tests=\"{}\" failures=\"{}\" "
      "errors=\"0\">\n",
      checks.size(), failures());
  x += fmt::format(
      "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"0\" "
      "skipped=\"0\">\n",
      markup_escape(suite), checks.size(), failures());
  x += "    <properties>\n";
  x += fmt::format("      <property name=\"baseline\" value=\"{}\"/>\n",
                   markup_escape(baseline_file.string()));
  x += fmt::format("      <property name=\"results\" value=\"{}\"/>\n",
                   markup_escape(results_file.string()));
  x += "    </properties>\n";
  for (const auto& c : checks) {
    x += fmt::format("    <testcase classname=\"{}\" name=\"{}\" time=\"0\"", markup_escape(suite),
                     markup_escape(c.metric.key));
    if (!c.failed()) {
      x += "/>\n";
      continue;
    }
    std::string message;
    if (c.verdict == Verdict::kMissing) {
      message = "missing from the results: " + c.note;
    } else if (c.verdict == Verdict::kNoBaseline) {
      message = c.note;
    } else {
      message = fmt::format(
          "regressed: baseline {}, new {}, change {}, {} {} ({} is "
          "better)",
          g(c.paired ? c.paired->mean_a : *c.metric.baseline), g(*c.value), change_text(c),
          c.paired ? "bar" : "tolerance", tolerance_text(c), yaml::enum_name(c.metric.direction));
    }
    x += fmt::format(">\n      <failure type=\"{}\" message=\"{}\">{}</failure>\n    </testcase>\n",
                     markup_escape(std::string(yaml::enum_name(c.verdict))), markup_escape(message),
                     markup_escape(message));
  }
  x += "    <system-out>" + markup_escape(table()) + "</system-out>\n";
  x += "  </testsuite>\n</testsuites>\n";
  return x;
}

Baseline only_metrics(Baseline baseline, const std::vector<std::string>& prefixes) {
  const auto wanted = [&](const BaselineMetric& m) {
    return std::any_of(prefixes.begin(), prefixes.end(),
                       [&](const std::string& p) { return m.key.rfind(p, 0) == 0; });
  };
  const std::string first_key = baseline.metrics.empty() ? "" : baseline.metrics.front().key;
  std::erase_if(baseline.metrics, [&](const BaselineMetric& m) { return !wanted(m); });
  if (baseline.metrics.empty())
    throw UserError(fmt::format(
        "{}: no metric's key starts with {} (--only); expected the start of one of its keys, "
        "such as {}",
        baseline.file.string(), fmt::join(prefixes, " or "), first_key));
  return baseline;
}

Baseline updated_baseline(const Baseline& baseline, const GateResult& result) {
  Baseline b = baseline;
  std::string missing;
  for (std::size_t i = 0; i < b.metrics.size(); ++i) {
    const MetricCheck& c = result.checks.at(i);
    if (!c.metric.pairs.empty() && !c.new_pairs.empty()) {  // pairs the results lack go too
      b.metrics[i].pairs = c.new_pairs;
      b.metrics[i].baseline = pairs_mean(c.new_pairs);
      continue;
    }
    if (!c.value || !c.metric.pairs.empty()) {
      missing += fmt::format("\n{}: {}: {}", c.metric.where, c.metric.key, c.note);
      continue;
    }
    b.metrics[i].baseline = *c.value;
  }
  if (!missing.empty())
    throw UserError(
        fmt::format("--update: {} lacks metrics of the baseline, expected every "
                    "key; nothing was updated:{}",
                    result.results_file.string(), missing));
  return b;
}

}  // namespace driftlab::gate
