#include "pipeline/scenario.hpp"

#include <fmt/format.h>

#include <set>

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/file_io.hpp"
#include "pipeline/scenario_checks.hpp"

namespace driftlab::pipeline {

PipelineOptions::PipelineOptions() {
  for (std::optional<double>* noise :
       {&ned_kf.compass_noise_rad, &ned_pf.compass_noise_rad, &eskf.compass_noise_rad,
        &eskf.gyro_noise_density_rad_s_sqrt_hz, &eskf.gyro_random_walk_rad_s2_sqrt_hz,
        &eskf.accel_noise_density_m_s2_sqrt_hz, &eskf.accel_random_walk_m_s3_sqrt_hz,
        &ned_kf.vo_increment_noise_m, &ned_kf.vo_yaw_increment_noise_rad,
        &ned_pf.vo_increment_noise_m, &ned_pf.vo_yaw_increment_noise_rad})
    noise->reset();
}
namespace {

// "FILE:LINE:COL" of the node at `keys` in `root` (last key found), for
// problems that are detected after reading, such as a missing file.
std::string where_key(const YAML::Node& root, const std::string& label,
                      const std::vector<std::string>& keys, int index = -1) {
  // yaml-cpp's Node::operator= writes through to the referenced node; reset() rebinds.
  YAML::Node node;
  node.reset(root);
  YAML::Mark mark = root.Mark();
  for (const auto& key : keys) {
    if (!node.IsMap() || !node[key]) return label;
    node.reset(node[key]);
    mark = node.Mark();
  }
  if (index >= 0 && node.IsSequence() && static_cast<std::size_t>(index) < node.size())
    mark = node[static_cast<std::size_t>(index)].Mark();
  if (mark.is_null()) return label;
  return fmt::format("{}:{}:{}", label, mark.line + 1, mark.column + 1);
}

// The problem's message prefixed with "FILE:LINE:COL" of its key path (e.g. "pipeline.fusion",
// "mission.waypoints_ne_m[3]") in the file; the message alone when it has no path or the file
// does not give the key (a default, or a --set: a parent's line would point at what the user
// did not write).
std::string located(const YAML::Node& root, const std::string& label, const yaml::Problem& p) {
  const std::string& path = p.path;
  YAML::Node node;
  node.reset(root);
  YAML::Mark mark = YAML::Mark::null_mark();
  std::size_t start = 0;
  while (!path.empty() && start <= path.size()) {
    const std::size_t dot = std::min(path.find('.', start), path.size());
    const std::string part = path.substr(start, dot - start);
    const std::size_t bracket = part.find('[');
    const std::string key = part.substr(0, bracket);
    if (key.empty() || !node.IsMap() || !node[key]) return p.message;
    node.reset(node[key]);
    mark = node.Mark();
    std::uint64_t index = 0;
    if (bracket != std::string::npos && node.IsSequence() &&
        yaml::parse_uint64(part.substr(bracket + 1, part.size() - bracket - 2), &index) &&
        index < node.size()) {
      node.reset(node[index]);
      mark = node.Mark();
    }
    start = dot + 1;
  }
  if (mark.is_null()) return p.message;
  return fmt::format("{}:{}:{}: {}", label, mark.line + 1, mark.column + 1, p.message);
}

// Reads "north_m,east_m" lines ('#' comments, blank lines and an optional
// header as the first line that is neither).
std::vector<std::array<double, 2>> read_waypoints_csv(const std::filesystem::path& path,
                                                      const std::string& referenced_at) {
  std::ifstream in(path);
  if (!in)
    throw UserError(
        fmt::format("{}: mission.waypoints_file: got '{}', expected an existing "
                    "readable CSV file (north_m,east_m per line)",
                    referenced_at, path.string()));
  std::vector<std::array<double, 2>> out;
  std::string line;
  int line_no = 0;
  bool seen_content = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::vector<std::string> cells = split_csv_line(line, CsvTrim::kSpaces);
    double n = 0, e = 0;
    const bool numbers =
        cells.size() == 2 && yaml::parse_double(cells[0], &n) && yaml::parse_double(cells[1], &e);
    const bool first_content_line = !seen_content;
    seen_content = true;
    if (!numbers && first_content_line && cells.size() == 2) continue;  // header
    if (cells.size() != 2)
      throw UserError(fmt::format("{}:{}: got {} columns, expected 2 (north_m,east_m)",
                                  path.string(), line_no, cells.size()));
    if (!numbers || !std::isfinite(n) || !std::isfinite(e))
      throw UserError(fmt::format("{}:{}: got '{}', expected two finite numbers north_m,east_m",
                                  path.string(), line_no, line));
    out.push_back({n, e});
  }
  return out;
}

void resolve_files(Scenario* s, const YAML::Node& root, const std::string& label,
                   const std::filesystem::path& base_dir) {
  if (!s->mission.waypoints_file.empty()) {
    std::filesystem::path p = s->mission.waypoints_file;
    if (p.is_relative()) p = base_dir / p;
    auto points = read_waypoints_csv(p, where_key(root, label, {"mission", "waypoints_file"}));
    s->mission.waypoints_ne_m.insert(s->mission.waypoints_ne_m.end(), points.begin(), points.end());
    // The resolved scenario carries the points themselves, so it is self-contained.
    s->mission.waypoints_file.clear();
  }
  for (std::size_t i = 0; i < s->scene.extra_assets.size(); ++i) {
    std::filesystem::path p = s->scene.extra_assets[i];
    if (p.is_relative()) p = base_dir / p;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(p, ec))
      throw UserError(fmt::format(
          "{}: scene.extra_assets[{}]: got '{}', expected an existing mesh file (OBJ, PLY, glTF)",
          where_key(root, label, {"scene", "extra_assets"}, static_cast<int>(i)), i,
          s->scene.extra_assets[i]));
    s->scene.extra_assets[i] = std::filesystem::absolute(p).lexically_normal().string();
  }
}

}  // namespace

std::vector<yaml::Problem> scenario_problems(const Scenario& s) {
  yaml::ErrorList errors;
  for (yaml::Problem& p : yaml::validation_problems(s))
    errors.add_at(std::move(p.path), std::move(p.message));
  if (s.mission.type == sim::MissionType::kWaypoints && s.mission.waypoints_ne_m.size() < 2)
    errors.add_at("mission.waypoints_ne_m",
                  fmt::format("mission.waypoints_ne_m: got {} waypoints, expected at least 2 for "
                              "mission type 'waypoints'",
                              s.mission.waypoints_ne_m.size()));
  if (s.pipeline.vo.empty() && !s.pipeline.fusion.empty())
    errors.add_at("pipeline.fusion",
                  "pipeline.fusion: got filters but no VO to feed them, expected pipeline.vo to "
                  "name at least one VO algorithm");
  std::set<std::string> external_names;
  for (const auto& e : s.pipeline.external_vo) {
    constexpr std::string_view kNameChars =
        "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-";
    const auto& built_in = vo::built_in_vo_names();
    if (std::find(built_in.begin(), built_in.end(), e.name) != built_in.end())
      errors.add_at(
          "pipeline.external_vo",
          fmt::format(
              "pipeline.external_vo: name: got '{}', a built-in VO's name, expected another name",
              e.name));
    else if (e.name.find_first_not_of(kNameChars) != std::string::npos)
      errors.add_at("pipeline.external_vo",
                    fmt::format("pipeline.external_vo: name: got '{}', expected letters, digits, "
                                "'_' and '-' only (it names files)",
                                e.name));
    else if (!external_names.insert(e.name).second)
      errors.add_at(
          "pipeline.external_vo",
          fmt::format(
              "pipeline.external_vo: name: got '{}' twice, expected a different name for each",
              e.name));
  }
  // The camera clock's stamps must stay within the association tolerance of
  // the true frame times, or no estimate would be paired with ground truth.
  const auto& clock = s.sensors.camera.clock;
  const double stamp_error_s = (std::abs(clock.offset_ms) + 3 * clock.jitter_ms) * 1e-3;
  if ((!s.pipeline.vo.empty() || !s.pipeline.external_vo.empty()) &&
      stamp_error_s > s.eval.association_tolerance_s)
    errors.add_at(
        "sensors.camera.clock",
        fmt::format(
            "sensors.camera.clock: got offset_ms {} and jitter_ms {}, stamps up to {} s from the "
            "true frame times, expected at most eval.association_tolerance_s = {} s (raise it, "
            "below half the frame period, to evaluate a camera with this clock)",
            clock.offset_ms, clock.jitter_ms, stamp_error_s, s.eval.association_tolerance_s));
  if (errors.empty())  // combinations only once every value is in range
    for (yaml::Problem& p : impossible_combinations(s))
      errors.add_at(std::move(p.path), std::move(p.message));
  return errors.problems();
}

void validate_scenario(const Scenario& s, const std::string& label) {
  yaml::ErrorList errors;
  for (const yaml::Problem& p : scenario_problems(s)) errors.add(p.message);
  errors.throw_if_any(label + ": invalid scenario:");
}

Scenario parse_scenario(const std::string& text, const std::string& label,
                        const std::filesystem::path& base_dir,
                        const std::vector<std::string>& overrides) {
  Scenario s;
  const YAML::Node root = yaml::load_string(text, label);
  yaml::read_into(root, {label, true}, &s);
  for (const auto& assignment : overrides) {
    const YAML::Node doc = yaml::override_document(assignment);
    yaml::read_into(doc, {"--set " + assignment, false}, &s, /*check_rules=*/false);
  }
  resolve_files(&s, root, label, base_dir);
  yaml::ErrorList errors;
  for (const yaml::Problem& p : scenario_problems(s)) errors.add(located(root, label, p));
  errors.throw_if_any(label + ": invalid scenario:");
  return s;
}

Scenario load_scenario(const std::filesystem::path& path,
                       const std::vector<std::string>& overrides) {
  return parse_scenario(read_text_file(path, "scenario file"), path.string(), path.parent_path(),
                        overrides);
}

std::string resolved_yaml(const Scenario& scenario) {
  return "# driftlab resolved scenario: every parameter of the run, defaults filled in.\n" +
         yaml::to_yaml(scenario);
}

std::string scenario_reference_markdown() {
  return yaml::schema_markdown(yaml::schema_of(Scenario{}));
}

}  // namespace driftlab::pipeline

namespace driftlab::yaml {
template void read_into<pipeline::Scenario>(const YAML::Node&, const Source&, pipeline::Scenario*,
                                            bool);
template std::string to_yaml<pipeline::Scenario>(const pipeline::Scenario&, bool);
template std::vector<Problem> validation_problems<pipeline::Scenario>(const pipeline::Scenario&,
                                                                      const std::string&);
template std::vector<SchemaRow> schema_of<pipeline::Scenario>(const pipeline::Scenario&);
}  // namespace driftlab::yaml
