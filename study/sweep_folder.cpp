// The sweep folder on disk: reading the manifest back, each job's state (done, failed,
// stale, missing or interrupted), the temporaries of killed jobs, and shards.
#include "study/sweep.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>

#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/process.hpp"
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
