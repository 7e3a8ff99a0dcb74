// The sweep folder on disk: reading the manifest back, each job's state (done, failed,
// stale, missing or interrupted), the temporaries of killed jobs, and shards.
#include "study/sweep.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>

#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/process.hpp"
#include "core/record_json.hpp"
#include "core/yaml_io.hpp"

namespace driftlab::study {

namespace fs = std::filesystem;

namespace {

std::string first_line(const std::string& s) { return s.substr(0, s.find('\n')); }

}  // namespace

// ---------------------------------------------------------------------------
// Reading a sweep folder

const SweepJob* SweepManifest::find(const std::string& id) const {
  for (const auto& j : jobs)
    if (j.id == id) return &j;
  return nullptr;
}

fs::path SweepManifest::base_dir() const {
  std::error_code ec;
  if (!info.base_dir.empty() && fs::is_directory(info.base_dir, ec)) return info.base_dir;
  return dir;
}

namespace {

const char* kPlanned = "the sweep.json of `driftlab sweep plan`";

SweepInfoRecord read_sweep_info(const fs::path& file) {
  const auto j =
      record_json::parse_json(read_text_file(file, "sweep.json"), file.string(), kPlanned);
  if (!j.is_object() || !j.contains("axes"))
    throw UserError(fmt::format("{}: no axes list, expected {}", file.string(), kPlanned));
  return record_json::from_json<SweepInfoRecord>(j, file.string());
}

// One line of manifest.jsonl, its params rebuilt from the overrides (axis order).
SweepJob read_manifest_job(const std::string& line, const std::string& where,
                           const std::vector<SweepAxisRecord>& axes) {
  const auto j = record_json::parse_json(line, where, "one job per line");
  if (const auto missing = record_json::missing_keys<ManifestJobRecord>(j); !missing.empty())
    throw UserError(fmt::format(
        "{}: no {}, expected a job with id, index, point, replicate, seed, params, overrides "
        "and hash",
        where, fmt::join(missing, ", ")));
  const auto rec = record_json::from_json<ManifestJobRecord>(j, where);
  SweepJob job{rec.id, rec.index, rec.point, rec.replicate, rec.seed, {}, rec.overrides, rec.hash};
  if (job.overrides.size() != axes.size() + 1)
    throw UserError(
        fmt::format("{}: job {}: got {} overrides, expected {} (one per axis of "
                    "sweep.json, then the seed)",
                    where, job.id, job.overrides.size(), axes.size() + 1));
  for (std::size_t i = 0; i < axes.size(); ++i) {
    const auto eq = job.overrides[i].find('=');
    job.params.emplace_back(axes[i].name,
                            eq == std::string::npos ? "" : job.overrides[i].substr(eq + 1));
  }
  return job;
}

}  // namespace

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
  m.info = read_sweep_info(m.dir / "sweep.json");
  m.axes = m.info.axes;
  for (auto& a : m.axes)
    if (a.name.empty()) a.name = a.key;
  std::istringstream in(text);
  std::string line;
  std::size_t line_no = 0;
  std::set<std::string> ids;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    const std::string where = fmt::format("{}:{}", m.manifest.string(), line_no);
    SweepJob job = read_manifest_job(line, where, m.axes);
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
      const auto done = read_json_record<JobMarkerRecord>(marker, "completion marker",
                                                          record_json::UnknownKeys::kIgnore);
      if (done.hash == job.hash) {
        st.state = JobState::kDone;
      } else {
        st.state = JobState::kStale;
        st.detail = fmt::format("finished with parameter hash {}, the manifest now says {}",
                                done.hash.empty() ? "?" : done.hash, job.hash);
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
      const auto f = read_json_record<FailureRecord>(failed, "failure record",
                                                     record_json::UnknownKeys::kIgnore);
      st.detail = f.status;
      if (!f.error.empty()) st.detail += ": " + first_line(f.error);
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
