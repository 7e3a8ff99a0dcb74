#include "core/yaml_io.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/file_io.hpp"
#include "core/markup.hpp"
#include "core/number.hpp"

namespace driftlab::yaml {

// ---------------------------------------------------------------------------
// Check

Check Check::operator&(const Check& o) const {
  Check c = *this;
  if (o.lo > c.lo || (o.lo == c.lo && o.lo_open)) {
    c.lo = o.lo;
    c.lo_open = o.lo_open;
  }
  if (o.hi < c.hi || (o.hi == c.hi && o.hi_open)) {
    c.hi = o.hi;
    c.hi_open = o.hi_open;
  }
  c.min_size = std::max(c.min_size, o.min_size);
  c.max_size = std::min(c.max_size, o.max_size);
  c.non_empty_string = c.non_empty_string || o.non_empty_string;
  if (o.choices) c.choices = o.choices;
  if (o.text_rule) c.text_rule = o.text_rule;
  if (!o.why.empty()) c.why = c.why.empty() ? o.why : c.why + "; " + o.why;
  c.required = c.required || o.required;
  if (!o.expected.empty()) c.expected = o.expected;
  return c;
}

bool Check::has_bounds() const { return std::isfinite(lo) || std::isfinite(hi); }

std::string Check::out_of_range(double v) const {
  const bool low = lo_open ? !(v > lo) : !(v >= lo);
  const bool high = hi_open ? !(v < hi) : !(v <= hi);
  if (!(low || high)) return "";
  const Check bounds{.lo = lo, .hi = hi, .lo_open = lo_open, .hi_open = hi_open, .why = why};
  return "a value " + bounds.describe();
}

std::string Check::describe() const {
  std::vector<std::string> parts;
  if (required) parts.push_back("required");
  const bool has_lo = std::isfinite(lo);
  const bool has_hi = std::isfinite(hi);
  if (has_lo && has_hi) {
    parts.push_back(fmt::format("in {}{}, {}{}", lo_open ? "(" : "[", format_double(lo),
                                format_double(hi), hi_open ? ")" : "]"));
  } else if (has_lo) {
    parts.push_back(fmt::format("{} {}", lo_open ? ">" : ">=", format_double(lo)));
  } else if (has_hi) {
    parts.push_back(fmt::format("{} {}", hi_open ? "<" : "<=", format_double(hi)));
  }
  if (!why.empty() && !parts.empty()) parts.back() += " (" + why + ")";
  const bool has_max = max_size != std::numeric_limits<std::size_t>::max();
  if (non_empty_string && min_size <= 1 && !has_max) {
    parts.push_back("non-empty");
  } else if (min_size > 0 && has_max) {
    parts.push_back(min_size == max_size ? fmt::format("exactly {}", min_size)
                                         : fmt::format("{} to {}", min_size, max_size));
  } else if (min_size > 0) {
    parts.push_back(fmt::format("at least {}", min_size));
  } else if (has_max) {
    parts.push_back(fmt::format("at most {}", max_size));
  }
  if (choices) {
    std::string names;
    for (const auto& n : choices()) names += (names.empty() ? "" : ", ") + n;
    parts.push_back("each one of: " + names);
  }
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : ", ") + p;
  return out;
}

std::string unknown_choice(const Check& check, const std::string& name) {
  if (!check.choices) return "";
  const std::vector<std::string> names = check.choices();
  if (std::find(names.begin(), names.end(), name) != names.end()) return "";
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  return "one of: " + list;
}

// ---------------------------------------------------------------------------
// Formatting and parsing

std::string format_double(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  DRIFTLAB_DEMAND(ec == std::errc());
  std::string s(buf, end);
  // Keep numbers recognisable as floats for YAML readers ("1" -> "1.0" is not
  // needed for us, but "1e+20" must not be read as a string by anyone).
  return s;
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

bool parse_double(std::string_view text, double* out) {
  // YAML's spellings of the special values (core/number.hpp reads nan and inf), so that they are
  // recognised and then rejected as non-finite with a precise message rather than "not a number".
  static const std::pair<std::string_view, double> kYamlSpecial[] = {
      {".nan", std::numeric_limits<double>::quiet_NaN()},
      {".NaN", std::numeric_limits<double>::quiet_NaN()},
      {".NAN", std::numeric_limits<double>::quiet_NaN()},
      {".inf", std::numeric_limits<double>::infinity()},
      {".Inf", std::numeric_limits<double>::infinity()},
      {"+.inf", std::numeric_limits<double>::infinity()},
      {"-.inf", -std::numeric_limits<double>::infinity()}};
  for (const auto& [name, value] : kYamlSpecial) {
    if (text == name) {
      *out = value;
      return true;
    }
  }
  const NumberStatus s = read_number(text, out);
  return s == NumberStatus::kOk || s == NumberStatus::kNotFinite;
}

bool parse_int64(std::string_view text, std::int64_t* out) {
  return read_number(text, out) == NumberStatus::kOk;
}

bool parse_uint64(std::string_view text, std::uint64_t* out) {
  return read_number(text, out) == NumberStatus::kOk;
}

std::string describe_node(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "nothing (null)";
    case YAML::NodeType::Scalar:
      return "'" + node.Scalar() + "'";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a mapping";
    case YAML::NodeType::Undefined:
      break;
  }
  return "nothing";
}

// ---------------------------------------------------------------------------
// ErrorList

void ErrorList::throw_if_any(std::string_view header) const {
  if (messages_.empty()) return;
  std::string what(header);
  for (const auto& m : messages_) {
    if (!what.empty()) what += "\n";
    what += m;
  }
  throw UserError(what);
}

// ---------------------------------------------------------------------------
// Reader

Reader::Reader(const YAML::Node& map, const Source& source, std::string key_prefix,
               ErrorList* errors)
    : map_(map), source_(source), prefix_(std::move(key_prefix)), errors_(errors) {
  // Copy the entries once: yaml-cpp's iterator proxies (it->first) trip GCC's
  // dangling-pointer analysis at -O3, and lookups by position are simpler.
  for (const auto& kv : map_) entries_.emplace_back(kv.first, kv.second);
}

std::string Reader::path(std::string_view key) const {
  return prefix_.empty() ? std::string(key) : prefix_ + "." + std::string(key);
}

std::string Reader::where(const YAML::Node& node) const {
  if (!source_.is_file) return source_.name;
  const YAML::Mark mark = node.Mark();
  if (mark.is_null()) return source_.name;
  return fmt::format("{}:{}:{}", source_.name, mark.line + 1, mark.column + 1);
}

YAML::Node Reader::find(const char* key) {
  seen_.emplace_back(key);
  for (const auto& [k, v] : entries_) {
    if (k.IsScalar() && k.Scalar() == key) return v;
  }
  return YAML::Node(YAML::NodeType::Undefined);
}

void Reader::fail(const YAML::Node& node, const std::string& key_path, const std::string& got,
                  const std::string& expected) {
  errors_->add(fmt::format("{}: {}: got {}, expected {}", where(node), key_path, got, expected));
}

bool Reader::read_scalar_text(const YAML::Node& node, const std::string& key_path,
                              const char* expected, std::string* text) {
  if (!node.IsScalar()) {
    fail(node, key_path, describe_node(node), expected);
    return false;
  }
  *text = node.Scalar();
  return true;
}

void Reader::check_number(const YAML::Node& node, const std::string& key_path, double v,
                          const Check& check) {
  const std::string expected = check.out_of_range(v);
  if (expected.empty()) return;
  if (!check.expected.empty()) {
    fail(node, key_path, describe_node(node), check.expected);
    return;
  }
  fail(node, key_path, format_double(v), expected);
}

YAML::Node Reader::value_of(std::string_view key) const {
  // yaml-cpp's Node::operator= writes through to the referenced node; reset() rebinds.
  YAML::Node node(YAML::NodeType::Undefined);
  for (const auto& [k, v] : entries_) {
    if (k.IsScalar() && k.Scalar() == key) {
      node.reset(v);
      break;
    }
  }
  return node;
}

void Reader::missing(const char* key, const Check& check) {
  missing_.emplace_back(key);
  // A missing top-level key has no place in the file but the file itself.
  errors_->add(fmt::format("{}: {}: missing, expected {}",
                           prefix_.empty() ? source_.name : where(map_), path(key),
                           check.expected.empty() ? "a value" : check.expected));
}

void Reader::location(const char* key, std::string* out) const {
  const YAML::Node node = value_of(key);
  *out = where(node.IsDefined() ? node : map_);
}

void Reader::require(bool ok, const char* key, std::string_view expected) {
  if (ok || !check_rules_) return;
  if (std::find(missing_.begin(), missing_.end(), key) != missing_.end()) return;
  YAML::Node node = value_of(key);
  if (!node.IsDefined()) node.reset(map_);
  std::string got = "the value given";
  if (node.IsScalar() && !node.Scalar().empty()) got = "'" + node.Scalar() + "'";
  if (node.IsSequence())
    got = node.size() == 0 ? "an empty list" : fmt::format("a list of {}", node.size());
  errors_->add(fmt::format("{}: {}: got {}, expected {}", where(node), path(key), got, expected));
}

void Reader::exactly_one_of(std::initializer_list<const char*> keys) {
  if (!check_rules_) return;
  std::string names;
  std::vector<std::pair<std::string, YAML::Node>> given;
  for (const char* key : keys) {
    names += (names.empty() ? "" : ", ") + std::string(key);
    // Null is "not given", as for an optional field.
    if (YAML::Node n = value_of(key); n.IsDefined() && !n.IsNull()) given.emplace_back(key, n);
  }
  const std::string here = prefix_.empty() ? "(top level)" : prefix_;
  if (given.empty()) {
    errors_->add(fmt::format("{}: {}: got none of {}, expected exactly one of them", where(map_),
                             here, names));
  } else if (given.size() > 1) {
    errors_->add(fmt::format("{}: {}: got both {} and {}, expected exactly one of: {}",
                             where(given[1].second), here, given[0].first, given[1].first, names));
  }
}

void Reader::read_named(const YAML::Node& node, const std::string& key_path, NamedOptions& value) {
  if (node.IsNull()) return;  // "plugins:" with nothing under it
  if (!node.IsMap()) {
    fail(node, key_path, describe_node(node), "a mapping of names to their options");
    return;
  }
  for (const auto& kv : node) {
    const YAML::Node k = kv.first;
    const YAML::Node options = kv.second;
    if (!k.IsScalar() || k.Scalar().empty()) {
      fail(k, key_path, describe_node(k), "a plain, non-empty name");
      continue;
    }
    NamedOptions::Holder* holder = value.find_or_make(k.Scalar());
    if (!holder) {
      std::string names;
      for (const auto& n : value.known_names()) names += (names.empty() ? "" : ", ") + n;
      fail(k, key_path, "'" + k.Scalar() + "'",
           names.empty() ? "the name of a VO registered with options (this program has none)"
                         : "one of: " + names);
      continue;
    }
    if (options.IsNull()) continue;  // "my_vo:" alone: its defaults
    if (!options.IsMap()) {
      fail(options, key_path + "." + k.Scalar(), describe_node(options),
           "a mapping of keys to values");
      continue;
    }
    Reader sub(options, source_, key_path + "." + k.Scalar(), errors_);
    sub.set_check_rules(check_rules_);
    holder->accept(sub);
    sub.finish();
  }
}

void Reader::finish() {
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    const YAML::Node& key = entries_[i].first;
    if (!key.IsScalar()) {
      errors_->add(fmt::format("{}: {}: got a non-scalar key, expected a plain key name",
                               where(key), prefix_.empty() ? "(top level)" : prefix_));
      continue;
    }
    const std::string& name = key.Scalar();
    std::size_t count = 0;
    for (const auto& [k, v] : entries_) count += k.IsScalar() && k.Scalar() == name;
    if (count > 1) {
      // Report each repeat (not the first occurrence), which is the one read.
      bool first_occurrence = true;
      for (std::size_t j = 0; j < i; ++j)
        if (entries_[j].first.IsScalar() && entries_[j].first.Scalar() == name)
          first_occurrence = false;
      if (!first_occurrence)
        errors_->add(
            fmt::format("{}: {}: duplicate key, expected each key once", where(key), path(name)));
      continue;
    }
    if (std::find(seen_.begin(), seen_.end(), name) != seen_.end()) continue;
    std::string hint;
    std::size_t best = 3;
    for (const auto& known : seen_) {
      const std::size_t d = edit_distance(name, known);
      if (d < best) {
        best = d;
        hint = known;
      }
    }
    std::string known_list;
    for (const auto& known : seen_) known_list += (known_list.empty() ? "" : ", ") + known;
    errors_->add(fmt::format("{}: {}: unknown key{}; expected one of: {}", where(key), path(name),
                             hint.empty() ? "" : " (did you mean '" + path(hint) + "'?)",
                             known_list));
  }
}

// ---------------------------------------------------------------------------
// Loading

YAML::Node load_file(const std::string& path) {
  return load_string(read_text_file(path, "YAML file"), path);
}

YAML::Node load_string(const std::string& text, const std::string& label) {
  require_utf8(text, label);
  try {
    YAML::Node node = YAML::Load(text);
    if (!node || node.IsNull())
      throw UserError(
          fmt::format("{}: the document is empty, expected a mapping of keys to values", label));
    return node;
  } catch (const YAML::ParserException& e) {
    throw UserError(fmt::format("{}:{}:{}: YAML syntax error: {}", label, e.mark.line + 1,
                                e.mark.column + 1, e.msg));
  }
}

YAML::Node override_document(const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw UserError(fmt::format("--set {}: expected KEY.PATH=VALUE", assignment));
  const std::string key_path = assignment.substr(0, eq);
  const std::string value_text = assignment.substr(eq + 1);
  std::vector<std::string> keys;
  std::size_t start = 0;
  while (true) {
    const auto dot = key_path.find('.', start);
    keys.push_back(key_path.substr(start, dot == std::string::npos ? dot : dot - start));
    if (keys.back().empty())
      throw UserError(fmt::format("--set {}: empty key in key path '{}'", assignment, key_path));
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  require_utf8(assignment, "--set " + key_path);
  YAML::Node value;
  try {
    value = value_text.empty() ? YAML::Node(std::string()) : YAML::Load(value_text);
  } catch (const YAML::ParserException& e) {
    throw UserError(fmt::format("--set {}: value is not valid YAML: {}", assignment, e.msg));
  }
  YAML::Node doc;
  doc.reset(value);
  for (auto it = keys.rbegin(); it != keys.rend(); ++it) {
    YAML::Node parent(YAML::NodeType::Map);
    parent[*it] = doc;
    doc.reset(parent);  // rebind; operator= would write into the child
  }
  return doc;
}

// ---------------------------------------------------------------------------
// Writer

std::string quote_string(const std::string& s) {
  static const char* kReserved[] = {"",     "~",     "null",  "Null",  "NULL", "true", "True",
                                    "TRUE", "false", "False", "FALSE", "yes",  "no",   "on",
                                    "off",  "Yes",   "No",    "On",    "Off"};
  bool plain = std::find(std::begin(kReserved), std::end(kReserved), s) == std::end(kReserved);
  double d;
  if (plain && parse_double(s, &d)) plain = false;
  for (char c : s) {
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' ||
                    c == '.' || c == '/' || c == ' ';
    if (!ok) plain = false;
  }
  if (plain && (s.front() == ' ' || s.back() == ' ' || s.front() == '-')) plain = false;
  if (plain) return s;
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        out += c;
    }
  }
  return out + "\"";
}

void Writer::line(const std::string& text, const char* doc) {
  out_.append(static_cast<std::size_t>(indent_), ' ');
  out_ += text;
  if (comments_ && doc && *doc) {
    out_ += "  # ";
    out_ += doc;
  }
  out_ += '\n';
}

void Writer::write_named(const char* key, const NamedOptions& value, const char* doc) {
  if (value.empty()) {
    line(std::string(key) + ": {}", doc);
    return;
  }
  line(std::string(key) + ":", doc);
  for (const auto& [name, holder] : value.entries()) {
    Writer sub(indent_ + 2, comments_);
    sub.line(name + ":", nullptr);
    Writer fields(indent_ + 4, comments_);
    holder->accept(fields);
    out_ += sub.str() + fields.str();
  }
}

// ---------------------------------------------------------------------------
// NamedOptions

NamedOptions::NamedOptions(const NamedOptions& o) : maker_(o.maker_), names_(o.names_) {
  for (const auto& [name, holder] : o.entries_) entries_.emplace_back(name, holder->clone());
}

NamedOptions& NamedOptions::operator=(const NamedOptions& o) {
  if (this != &o) *this = NamedOptions(o);
  return *this;
}

const NamedOptions::Holder* NamedOptions::find(const std::string& name) const {
  for (const auto& [n, holder] : entries_)
    if (n == name) return holder.get();
  return nullptr;
}

NamedOptions::Holder* NamedOptions::find_or_make(const std::string& name) {
  for (auto& [n, holder] : entries_)
    if (n == name) return holder.get();
  std::unique_ptr<Holder> made = make(name);
  if (!made) return nullptr;
  entries_.emplace_back(name, std::move(made));
  return entries_.back().second.get();
}

// ---------------------------------------------------------------------------
// Validator

std::string Validator::path(std::string_view key) const {
  return prefix_.empty() ? std::string(key) : prefix_ + "." + std::string(key);
}

void Validator::check_double(const std::string& key_path, double v, const Check& check) {
  if (!std::isfinite(v)) {
    errors_->add_at(
        key_path, fmt::format("{}: got {}, expected a finite number", key_path, format_double(v)));
    return;
  }
  if (const std::string expected = check.out_of_range(v); !expected.empty())
    errors_->add_at(key_path,
                    fmt::format("{}: got {}, expected {}", key_path, format_double(v), expected));
}

void Validator::require(bool ok, const char* key, std::string_view expected) {
  if (!ok) errors_->add_at(path(key), fmt::format("{}: expected {}", path(key), expected));
}

// ---------------------------------------------------------------------------
// Schema

void SchemaBuilder::require(bool, const char* key, std::string_view expected) {
  const std::string key_path = prefix_.empty() ? key : prefix_ + "." + key;
  for (auto& row : *rows_) {
    if (row.key_path == key_path) {
      row.constraint += (row.constraint.empty() ? "" : "; ") + std::string(expected);
      return;
    }
  }
}

void SchemaBuilder::add_named(const std::string& key_path, const NamedOptions& value,
                              const char* doc) {
  const std::vector<std::string> names = value.known_names();
  std::string choices;
  for (const auto& n : names) choices += (choices.empty() ? "" : ", ") + n;
  rows_->push_back({key_path, "mapping of names to their options", "{}",
                    choices.empty() ? "" : "names: " + choices, doc});
  for (const auto& name : names) {  // each registered name's options, at their defaults
    const std::unique_ptr<NamedOptions::Holder> holder = value.make(name);
    if (!holder) continue;
    rows_->push_back({key_path + "." + name, "mapping", "", "", "Options of " + name});
    SchemaBuilder sub(key_path + "." + name, rows_);
    holder->accept(sub);
  }
}

void SchemaBuilder::exactly_one_of(std::initializer_list<const char*> keys) {
  std::string names;
  for (const char* key : keys) names += (names.empty() ? "" : ", ") + std::string(key);
  for (const char* key : keys) require(false, key, "exactly one of " + names);
}

// ---------------------------------------------------------------------------
// Any

std::string Any::flow_text() const {
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

std::string schema_markdown(const std::vector<SchemaRow>& rows) {
  const auto cell = [](const std::string& s) { return markdown_cell(s); };
  std::string out = "| key | type | default | constraint | meaning |\n|---|---|---|---|---|\n";
  for (const auto& r : rows) {
    out += fmt::format("| `{}` | {} | {} | {} | {} |\n", r.key_path, cell(r.type),
                       r.default_value.empty() ? "" : "`" + cell(r.default_value) + "`",
                       cell(r.constraint), cell(r.doc));
  }
  return out;
}

}  // namespace driftlab::yaml
