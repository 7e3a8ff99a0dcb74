#include "pipeline/external_vo.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <iterator>
#include <numbers>
#include <optional>
#include <string_view>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/process.hpp"
#include "core/stopwatch.hpp"
#include "pipeline/export_stage.hpp"
#include "pipeline/frame_source.hpp"

namespace driftlab::pipeline {
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kLogTail = 2000;

std::string log_tail(const fs::path& log) {
  std::error_code ec;
  if (!fs::exists(log, ec)) return "";
  const std::string text = read_text_file(log, "command log");
  return text.size() <= kLogTail ? text : "..." + text.substr(text.size() - kLogTail);
}

std::string extension(TrajectoryFormat f) {
  switch (f) {
    case TrajectoryFormat::kTum:
      return "tum";
    case TrajectoryFormat::kKitti:
      return "txt";
    case TrajectoryFormat::kEuroc:
      return "csv";
  }
  return "txt";
}

// Runs `command` under coreutils' timeout, which kills its whole process group at the limit.
ExitStatus run_with_timeout(const std::string& command, double timeout_s, const fs::path& log) {
  const auto timeout = find_on_path("timeout");
  if (!timeout) throw UserError("external VO: coreutils' 'timeout' is not on PATH");
  ProcessSpec spec;
  spec.executable = *timeout;
  spec.args = {"--kill-after=5", fmt::format("{}s", timeout_s), "/bin/sh", "-c", command};
  spec.output_file = log;
  return wait_process(spawn_process(spec));
}

// The angle between where the estimate and the truth went from the first frame until the
// truth had moved `metres`, in the first camera's frame [deg]; nothing if it never did.
std::optional<double> heading_disagreement_deg(const Trajectory& est, const Trajectory& truth,
                                               double metres) {
  for (std::size_t i = 1; i < std::min(est.size(), truth.size()); ++i) {
    const Vec3 t = (truth.front().T_W_C.inverse() * truth[i].T_W_C).translation();
    if (t.norm() < metres) continue;
    const Vec3 e = (est.front().T_W_C.inverse() * est[i].T_W_C).translation();
    if (e.norm() == 0) return 180.0;
    return std::acos(std::clamp(t.dot(e) / (t.norm() * e.norm()), -1.0, 1.0)) * 180 /
           std::numbers::pi;
  }
  return std::nullopt;
}

}  // namespace

namespace {

constexpr std::array<std::string_view, 4> kPlaceholders{"dir", "root", "out", "driftlab"};

// "{name}" at [begin, end) of a command.
struct Placeholder {
  std::size_t begin = 0, end = 0;
  std::string name;
};

bool is_name_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// The next word in braces ("{name}", name of letters, digits and '_') at or after `from`, other
// than the shell's "${name}".
std::optional<Placeholder> next_placeholder(const std::string& command, std::size_t from) {
  for (std::size_t i = command.find('{', from); i != std::string::npos;
       i = command.find('{', i + 1)) {
    if (i > 0 && command[i - 1] == '$') continue;
    std::size_t j = i + 1;
    while (j < command.size() && is_name_char(command[j])) ++j;
    if (j > i + 1 && j < command.size() && command[j] == '}')
      return Placeholder{i, j + 1, command.substr(i + 1, j - i - 1)};
  }
  return std::nullopt;
}

}  // namespace

std::string unknown_command_placeholder(const std::string& command) {
  for (auto p = next_placeholder(command, 0); p; p = next_placeholder(command, p->end))
    if (std::find(kPlaceholders.begin(), kPlaceholders.end(), p->name) == kPlaceholders.end())
      return "{" + p->name + "}";
  return "";
}

std::string expand_command(const std::string& command, const fs::path& dir, const fs::path& root,
                           const fs::path& out, const fs::path& driftlab) {
  const std::array<const fs::path*, kPlaceholders.size()> values{&dir, &root, &out, &driftlab};
  std::string result;
  std::size_t at = 0;
  for (auto p = next_placeholder(command, 0); p; p = next_placeholder(command, p->end)) {
    const auto known = std::find(kPlaceholders.begin(), kPlaceholders.end(), p->name);
    if (known == kPlaceholders.end())
      throw UserError(
          fmt::format("pipeline.external_vo: command: got '{{{}}}', expected placeholders "
                      "{{dir}}, {{root}}, {{out}} or {{driftlab}} only",
                      p->name));
    result.append(command, at, p->begin - at);
    result +=
        shell_quote(values[static_cast<std::size_t>(known - kPlaceholders.begin())]->string());
    at = p->end;
  }
  result.append(command, at);
  return result;
}

struct ExternalVoStage::Export {
  ExternalVoOptions options;
  fs::path folder, root;
  dataset::ExportCalibration calibration;
  std::unique_ptr<dataset::DatasetWriter> writer;
  Trajectory truth;  // the left camera at each exported frame
  std::vector<TimeNs> stamps;

  // The folder the command is told about as {dir}.
  fs::path dir() const {
    return options.format == dataset::DatasetFormat::kKitti
               ? root / "sequences" / calibration.sequence
               : root;
  }
  fs::path out() const { return folder / ("trajectory." + extension(options.output)); }

  // The exported frame whose stamp is nearest `t_ns`: a VO that initialises after some frames
  // (a stereo-inertial one waits for motion) starts its trajectory there, not at the first.
  const StampedPose& truth_at(TimeNs t_ns) const {
    const auto later = std::lower_bound(truth.begin(), truth.end(), t_ns,
                                        [](const StampedPose& p, TimeNs t) { return p.t_ns < t; });
    auto nearest = later == truth.end() ? std::prev(later) : later;
    if (later != truth.begin() && later != truth.end() &&
        t_ns - std::prev(later)->t_ns <= later->t_ns - t_ns)
      nearest = std::prev(later);
    const TimeNs period = truth.size() > 1 ? (truth.back().t_ns - truth.front().t_ns) /
                                                 static_cast<TimeNs>(truth.size() - 1)
                                           : 0;
    if (std::abs(nearest->t_ns - t_ns) > period)
      throw UserError(fmt::format(
          "{}: its first pose at t = {} ns is more than a frame from every exported frame "
          "({} to {} ns)",
          out().string(), t_ns, truth.front().t_ns, truth.back().t_ns));
    return *nearest;
  }

  // The command's trajectory as left-camera poses, its first anchored at the true pose of the
  // frame it belongs to.
  Trajectory read_estimate() const {
    Trajectory raw;
    if (options.output == TrajectoryFormat::kKitti) {
      KittiTiming timing;
      timing.times_ns = stamps;
      raw = read_kitti(out(), timing);
    } else {
      raw = read_trajectory(out(), options.output);
    }
    if (raw.empty()) throw UserError(out().string() + ": no poses");
    if (options.output == TrajectoryFormat::kEuroc)  // body (IMU) poses
      for (auto& p : raw) p.T_W_C = p.T_W_C * calibration.T_S_C;
    const SE3 anchor = truth_at(raw.front().t_ns).T_W_C * raw.front().T_W_C.inverse();
    for (auto& p : raw) p.T_W_C = anchor * p.T_W_C;
    return raw;
  }
};

ExternalVoStage::ExternalVoStage(const Scenario& sc, const fs::path& run_dir,
                                 const fs::path& reported_dir)
    : run_dir_(run_dir), reported_dir_(reported_dir.empty() ? run_dir : reported_dir) {
  for (const auto& o : sc.pipeline.external_vo) {
    auto e = std::make_unique<Export>();
    e->options = o;
    e->folder = run_dir / "external" / o.name;
    e->root = e->folder / "dataset";
    fs::create_directories(e->root);
    write_file_atomic(e->root / "scenario.resolved.yaml", resolved_yaml(sc));
    e->calibration = export_calibration(sc);
    e->writer = dataset::make_writer(o.format, e->root, e->calibration);
    exports_.push_back(std::move(e));
  }
}

ExternalVoStage::~ExternalVoStage() = default;

bool ExternalVoStage::empty() const { return exports_.empty(); }

bool ExternalVoStage::wants_depth() const {
  for (const auto& e : exports_)
    if (e->writer->wants_depth()) return true;
  return false;
}

void ExternalVoStage::add_frame(TimeNs stamp_ns, const sim::StereoImages& images,
                                const StampedPose& truth) {
  for (auto& e : exports_) {
    e->writer->add_frame(stamp_ns, cv_view(images.left), cv_view(images.right),
                         e->writer->wants_depth() ? cv_view(images.depth_left) : cv::Mat());
    e->truth.push_back(truth);
    e->stamps.push_back(stamp_ns);
  }
}

std::vector<ExternalVoResult> ExternalVoStage::finish(
    const std::vector<dataset::BodyState>& imu_states) {
  std::vector<ExternalVoResult> results;
  const fs::path self = fs::read_symlink("/proc/self/exe");
  for (auto& e : exports_) {
    ExternalVoResult r;
    r.name = e->options.name;
    dataset::ExportTruth truth;
    truth.camera = e->truth;
    truth.body = imu_states;
    const fs::path staging = e->folder / ".sensors";
    fs::create_directories(staging);
    for (const char* csv : {"imu.csv", "gps.csv", "compass.csv"})
      if (fs::exists(run_dir_ / csv)) {
        fs::copy_file(run_dir_ / csv, staging / csv);
        truth.sensor_csvs.push_back(staging / csv);
      }
    e->writer->finish(truth);
    fs::remove_all(staging);
    const std::string command =
        expand_command(e->options.command, e->dir(), e->root, e->out(), self);
    const Stopwatch watch;
    const ExitStatus status =
        run_with_timeout(command, e->options.timeout_s, e->folder / "log.txt");
    r.record.format = dataset::format_name(e->options.format);
    r.record.output = format_name(e->options.output);
    r.record.exit = status.describe();
    r.record.seconds = watch.ms() / 1000;
    r.record.frames = e->stamps.size();
    // timeout exits 124 when its TERM ended the command; a command that ignores TERM is
    // killed 5 s later together with timeout itself (its whole process group).
    const bool killed_at_limit =
        !status.exited && status.signal == SIGKILL && watch.ms() / 1000 >= e->options.timeout_s;
    if ((status.exited && status.code == 124) || killed_at_limit) {
      r.record.status = "timeout";
      r.warning = fmt::format("external VO '{}': no result within timeout_s = {} s", r.name,
                              e->options.timeout_s);
    } else if (!status.ok()) {
      r.record.status = "failed";
      r.warning =
          fmt::format("external VO '{}': the command failed ({})", r.name, status.describe());
    } else {
      try {
        r.estimate = e->read_estimate();
        r.ok = true;
        r.record.status = "ok";
        const auto angle = heading_disagreement_deg(r.estimate, e->truth, 1.0);
        if (angle && *angle > 45)
          r.warning = fmt::format(
              "external VO '{}': its first metre of motion points {:.0f} deg away from the left "
              "camera's; is {} a left-camera trajectory (x right, y down, z forward)?",
              r.name, *angle, e->out().filename().string());
      } catch (const UserError& err) {
        r.record.status = "bad output";
        r.warning =
            fmt::format("external VO '{}': its trajectory cannot be read: {}", r.name, err.what());
      }
    }
    // The run's folder by the name it will have: the temporary one is gone after the run.
    const auto reported = [&](std::string text) {
      const std::string from = run_dir_.string(), to = reported_dir_.string();
      for (std::size_t at = text.find(from); at != std::string::npos;
           at = text.find(from, at + to.size()))
        text.replace(at, from.size(), to);
      return text;
    };
    r.warning = reported(r.warning);
    r.record.command = reported(command);
    r.record.message = r.warning;
    r.record.log_tail = reported(log_tail(e->folder / "log.txt"));
    if (!e->options.keep_dataset) fs::remove_all(e->root);
    results.push_back(std::move(r));
  }
  return results;
}

}  // namespace driftlab::pipeline
