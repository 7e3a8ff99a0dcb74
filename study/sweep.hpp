// Scenario sweeps: the sweep file (a base scenario, axes over scenario key
// paths, a design, replicates), its expansion into jobs, the sweep folder's
// manifest and the state of every job in it.
//
// A sweep folder DIR holds
//   DIR/sweep.json          what was planned: axes, design, seed, counts
//   DIR/scenario.yaml       the base scenario resolved (with the sweep's `set`)
//   DIR/manifest.jsonl      one job per line: id, point, replicate, seed, params,
//                           overrides (applied to scenario.yaml), parameter hash
//   DIR/runs/ID/            a finished job: the run's outputs and job.json, its
//                           completion marker (written last, renamed into place)
//   DIR/failed/ID.json      a failed job: status and the tail of its output
//   DIR/logs/ID.log         the output of the job's last attempt
//   DIR/summary/            `driftlab sweep merge`
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/hash.hpp"
#include "study/sweep_records.hpp"

namespace driftlab::study {

/// One swept scenario key.
struct SweepAxis {
  std::string key;   // scenario key path, e.g. mission.yaw_weave.amplitude_deg
  std::string name;  // column name in merged tables (default: the key path)
  AxisSpec spec = AxisSpec::kValues;
  /// YAML text of every value, in order (empty for a continuous axis).
  std::vector<std::string> levels;
  /// Continuous axis (linspace or logspace of a random design): sampled in
  /// [start, stop], uniformly (linspace) or log-uniformly (logspace).
  bool continuous = false;
  double start = 0, stop = 0;
  bool numeric = true;                   // every value is a number
  std::string where;                     // FILE:LINE:COL of the axis entry
  std::vector<std::string> level_where;  // FILE:LINE:COL of each listed value (spec values)
};

/// A parsed sweep file. Paths are absolute.
struct Sweep {
  std::filesystem::path file;
  std::string name;
  std::string description;
  std::filesystem::path base;  // the base scenario
  std::string base_where;
  std::vector<std::pair<std::string, std::string>> set;  // fixed overrides: key path, YAML text
  std::vector<std::string> set_where;
  SweepDesign design = SweepDesign::kGrid;
  std::size_t samples = 0;            // design random: number of points
  std::size_t replicates = 1;         // runs per point, each with its own seed
  std::optional<std::uint64_t> seed;  // default: the base scenario's seed
  std::vector<SweepAxis> axes;
};

namespace detail {
/// Rounds a generated axis value to 12 significant digits, so that range {0, 1, 0.1} gives
/// 0.3 rather than 0.30000000000000004 (and never -0).
double tidy_level(double v);
}  // namespace detail

/// Reads and checks a sweep file: unknown keys, wrong types, empty axes,
/// replicates 0, conflicting design settings. Throws UserError listing every
/// problem as FILE:LINE:COL: key.path: got VALUE, expected WHAT. Key paths and
/// values are checked against the base scenario by plan_sweep().
Sweep load_sweep(const std::filesystem::path& file);
/// The same from text; `label` names it in messages, relative paths resolve against `dir`.
Sweep parse_sweep(const std::string& text, const std::string& label,
                  const std::filesystem::path& dir);
/// Applies the command line's `--set KEY.PATH=VALUE` to every job: the value replaces the
/// file's `set` entry for that key or joins them. A key that an axis sweeps, or `seed`, is an
/// error naming the --set; key paths and values are checked against the base scenario by
/// plan_sweep(), like the file's own.
void apply_sets(Sweep* sweep, const std::vector<std::string>& assignments);
/// The reference of every sweep-file key (Markdown), generated from the reader's own field
/// list: `driftlab sweep schema`, docs/sweep-reference.md.
std::string sweep_reference_markdown();

/// One run of the sweep.
struct SweepJob {
  std::string id;  // p<point>-r<replicate>, e.g. p0003-r01: stable for a given sweep file
  std::size_t index = 0;
  std::size_t point = 0;
  std::size_t replicate = 0;
  std::uint64_t seed = 0;
  /// Axis name and the YAML text of its value at this point, in axis order.
  std::vector<std::pair<std::string, std::string>> params;
  /// KEY=VALUE overrides of the sweep's scenario.yaml: one per axis, then seed=N.
  std::vector<std::string> overrides;
  /// FNV-1a 64 (hex) of the job's resolved scenario without comments: every
  /// parameter the run uses. A finished run whose hash differs is stale.
  std::string hash;
};

struct SweepPlan {
  Sweep sweep;
  std::string scenario_yaml;  // the base scenario resolved, with `set` applied
  std::uint64_t seed = 0;     // the sweep seed actually used
  std::size_t points = 0;
  std::vector<SweepJob> jobs;

  /// sweep.json content.
  SweepInfoRecord info() const;
  /// manifest.jsonl content.
  std::string manifest_jsonl() const;
};

/// Expands the design, derives seeds, and checks every key path and value by
/// applying it to the base scenario (and every job's full set of overrides).
/// Throws UserError naming the sweep file, line, axis and value.
SweepPlan plan_sweep(const Sweep& sweep);

/// The seed of replicate `r` under the sweep seed: the low 53 bits of
/// derive_seed(seed, "sweep.replicate.<r>") (exact in any JSON reader). Common
/// to all points (common random numbers: two points differ by their
/// parameters, not by their noise).
std::uint64_t replicate_seed(std::uint64_t sweep_seed, std::size_t replicate);

/// FNV-1a 64 of `bytes` as 16 hex digits (core/hash.hpp).
using driftlab::fnv1a64_hex;

struct PlanWriteSummary {
  std::filesystem::path dir;
  std::size_t jobs = 0, points = 0;
  bool unchanged = false;  // the folder already held this plan
  bool replaced = false;   // --force replaced a different plan
  std::string brief() const;
};

/// Writes sweep.json, scenario.yaml and manifest.jsonl into `dir` (a new
/// folder is built aside and renamed into place). A folder that already holds
/// the same plan is left as it is; a different plan is an error unless
/// `force`, which rewrites the three files and keeps runs/ (a finished run
/// whose parameter hash changed is then stale and runs again).
PlanWriteSummary write_plan(const SweepPlan& plan, const std::filesystem::path& dir, bool force);

/// A sweep folder read back.
struct SweepManifest {
  std::filesystem::path dir;          // absolute
  std::filesystem::path manifest;     // dir / manifest.jsonl
  SweepInfoRecord info;               // sweep.json
  std::vector<SweepAxisRecord> axes;  // info.axes, each with its column name
  std::vector<SweepJob> jobs;

  const SweepJob* find(const std::string& id) const;
  std::filesystem::path scenario_file() const { return dir / "scenario.yaml"; }
  std::filesystem::path base_dir() const;  // where relative files of overrides resolve
  std::filesystem::path run_dir(const std::string& id) const { return dir / "runs" / id; }
  std::filesystem::path marker(const std::string& id) const { return run_dir(id) / "job.json"; }
  std::filesystem::path failed_record(const std::string& id) const {
    return dir / "failed" / (id + ".json");
  }
  std::filesystem::path log_file(const std::string& id) const {
    return dir / "logs" / (id + ".log");
  }
};

/// Reads DIR/manifest.jsonl (given the file or DIR) and DIR/sweep.json.
/// Throws UserError naming the file and line of anything malformed.
SweepManifest read_manifest(const std::filesystem::path& manifest_or_dir);

enum class JobState { kDone, kFailed, kStale, kMissing };
constexpr auto enum_table(JobState) {
  return std::array{std::pair{JobState::kDone, "done"}, std::pair{JobState::kFailed, "failed"},
                    std::pair{JobState::kStale, "stale"}, std::pair{JobState::kMissing, "missing"}};
}

struct JobStatus {
  std::string id;
  std::size_t index = 0;
  JobState state = JobState::kMissing;
  std::string detail;  // failed: the failure; stale: why; missing: interrupted, if it was
};

/// The state of one job: done (marker with the manifest's hash), stale
/// (marker with another hash), failed (a failure record and no marker), missing.
JobStatus job_status(const SweepManifest& m, const SweepJob& job);

struct SweepStatus {
  std::vector<JobStatus> jobs;  // manifest order
  std::size_t done = 0, failed = 0, stale = 0, missing = 0;
  std::vector<std::string> leftovers;  // temporaries of interrupted jobs under runs/
  bool complete() const { return done == jobs.size(); }
  std::string brief() const;  // "8 jobs: 5 done, 1 failed, 0 stale, 2 missing"
};

SweepStatus sweep_status(const SweepManifest& m);

/// Temporaries under runs/ left by killed jobs (ID.tmp.PID...). With
/// `remove`, those whose every pid is no longer alive on this machine are
/// deleted (only safe when no other machine runs jobs of this sweep).
std::vector<std::filesystem::path> leftover_temporaries(const SweepManifest& m, bool remove);

/// A `--shard K/N` argument: jobs with index % N == K (K is 0-based).
struct Shard {
  std::size_t index = 0;
  std::size_t count = 1;
};
/// Parses "K/N"; throws UserError for anything but 0 <= K < N.
Shard parse_shard(const std::string& text);
bool in_shard(const SweepJob& job, const Shard& shard);

/// YAML text of a value as a JSON value (number, bool, string, list, map).
nlohmann::json yaml_text_to_json(const std::string& yaml_text);

}  // namespace driftlab::study
