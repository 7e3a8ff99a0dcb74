#include "pipeline/tracks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <future>

#include "core/yaml_io.hpp"

namespace driftlab::pipeline {

std::string filter_track_name(const std::string& vo, FusionAlgorithm kind) {
  return vo + "_" +
         (kind == FusionAlgorithm::kCaSmoother ? "ca" : std::string(yaml::enum_name(kind)));
}

void add_filter_tracks(const std::vector<FusionAlgorithm>& fusion, std::size_t n_vo,
                       const std::function<std::unique_ptr<FilterTrack>(FusionAlgorithm)>& make,
                       std::vector<Track>* tracks) {
  for (FusionAlgorithm f : fusion) {
    for (std::size_t i = 0; i < n_vo; ++i) {
      Track t;
      t.source = i;
      t.name = filter_track_name((*tracks)[i].name, f);
      t.filter = make(f);
      tracks->push_back(std::move(t));
    }
  }
}

namespace {

// The VO tracks' indices, the slowest so far first (ties in track order): the order in which
// the workers take them, so that the longest VO starts at once and the short ones fill in.
std::vector<std::size_t> longest_first(const std::vector<Track>& tracks) {
  std::vector<std::size_t> vos;
  for (std::size_t i = 0; i < tracks.size(); ++i)
    if (tracks[i].vo) vos.push_back(i);
  std::stable_sort(vos.begin(), vos.end(),
                   [&](std::size_t a, std::size_t b) { return tracks[a].vo_ms > tracks[b].vo_ms; });
  return vos;
}

}  // namespace

std::vector<vo::VoResult> process_vos(std::vector<Track>* tracks_io, const vo::StereoFrame& frame,
                                      int threads) {
  std::vector<Track>& tracks = *tracks_io;
  std::vector<vo::VoResult> results(tracks.size());
  const std::vector<std::size_t> order = longest_first(tracks);
  const std::size_t workers =
      std::min(order.size(), static_cast<std::size_t>(std::max(1, threads)));
  std::atomic<std::size_t> next{workers};  // worker w starts with order[w], then takes the next
  std::atomic<bool> failed{false};
  std::vector<std::exception_ptr> errors(workers);
  auto work = [&](std::size_t w) {
    try {
      for (std::size_t j = w; j < order.size() && (j == w || !failed); j = next++)
        results[order[j]] = tracks[order[j]].vo->process(frame);
    } catch (...) {
      errors[w] = std::current_exception();
      failed = true;  // no worker takes another VO after one failed
    }
  };
  std::vector<std::future<void>> others;
  for (std::size_t w = 1; w < workers; ++w)
    others.push_back(std::async(std::launch::async, work, w));
  if (workers > 0) work(0);
  for (std::future<void>& f : others) f.get();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  return results;
}

void advance_track(Track* track, std::size_t k, bool first, TimeNs t, const vo::VoResult& r) {
  Track& tr = *track;
  if (tr.vo) {
    tr.results[k] = r;
    tr.vo_ms += r.times.total_ms;
  }
  if (tr.filter) {
    const SE3 T_W_C = tr.filter->step(t, r);  // the first starts from the anchor
    if (!first) tr.estimate.push_back({t, T_W_C});
    return;
  }
  if (first) return;
  const SE3 step = r.valid ? r.T_prev_curr : SE3();
  tr.estimate.push_back({t, tr.estimate.back().T_W_C * step});  // river paper Eq. (3)
}

bool runs_backward_pass(const PipelineOptions& pipeline) {
  const auto& f = pipeline.fusion;
  return pipeline.ca_smoother.rts_backward_pass &&
         std::find(f.begin(), f.end(), FusionAlgorithm::kCaSmoother) != f.end();
}

Track rts_smoothed(const Track& track, std::size_t source,
                   const std::vector<std::optional<TimeNs>>& delivered,
                   const fusion::CaSmootherOptions& options) {
  std::vector<TimeNs> t_ns;
  std::vector<vo::VoResult> results;
  for (std::size_t k = 0; k < track.results.size() && k < delivered.size(); ++k) {
    if (!delivered[k]) continue;
    t_ns.push_back(*delivered[k]);
    results.push_back(track.results[k]);
  }
  const fusion::SmoothedTrajectory s = fusion::smooth_trajectory(t_ns, results, options);
  Track t;
  t.name = track.name + "_ca_rts";
  t.source = source;
  const SE3 T_W_first = track.estimate.front().T_W_C;
  for (std::size_t j = 0; j < s.t_ns.size(); ++j)
    t.estimate.push_back({s.t_ns[j], T_W_first * s.T_first_cam[j]});
  return t;
}

void write_estimates(const std::vector<Track>& tracks, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir / "estimates");
  for (const auto& tr : tracks) {
    write_tum(dir / "estimates" / (tr.name + ".tum"), tr.estimate);
    if (tr.filter && tr.filter->writes_states())
      tr.filter->write_states(dir / "estimates" / (tr.name + ".csv"));
  }
}

void report_filter_counts(const std::vector<Track>& tracks, TrackRecords* records,
                          std::vector<std::string>* warnings) {
  for (const Track& tr : tracks) {
    if (!tr.filter) continue;
    const FilterCounts c = tr.filter->counts();
    records->algorithms[tr.name].filter = c.counts;
    if (c.nonfinite_guards > 0)
      warnings->push_back(fmt::format(
          "{}: {} non-finite inputs or states were caught (skipped, or the filter restarted); "
          "see algorithms.{}.filter in metrics.json",
          tr.name, c.nonfinite_guards, tr.name));
  }
}

std::string compare_filters_with_raw_vo(const std::vector<Track>& tracks, TrackRecords* records,
                                        std::vector<std::string>* warnings) {
  std::string table;
  for (const Track& tr : tracks) {
    if (tr.vo || tr.external) continue;
    const std::string& raw = tracks[tr.source].name;
    const auto filtered = records->algorithms.find(tr.name);
    const auto unfiltered = records->algorithms.find(raw);
    if (filtered == records->algorithms.end() || unfiltered == records->algorithms.end()) continue;
    const std::optional<double> f = ape_trans_rmse_m(filtered->second);
    const std::optional<double> r = ape_trans_rmse_m(unfiltered->second);
    if (!f || !r) continue;  // no associated poses
    const record::VsRawVoRecord v = vs_raw_vo(raw, *f, *r);
    filtered->second.vs_raw_vo = v;
    if (!v.better)
      warnings->push_back(fmt::format(
          "{} is no better than its raw VO {}: APE translation RMSE {:.4g} m against {:.4g} m",
          tr.name, raw, v.filtered, v.raw));
    table += fmt::format("| {} | {} | {:.4g} | {:.4g} | {:.2f} | {} |\n", tr.name, raw, v.filtered,
                         v.raw, v.ratio, v.better ? "yes" : "**no**");
  }
  if (table.empty()) return "";
  return "## Filters against their raw VO\n\n| filter | raw VO | APE trans. RMSE (m) | raw VO's "
         "(m) | ratio | better |\n|---|---|---|---|---|---|\n" +
         table + "\n";
}

}  // namespace driftlab::pipeline
