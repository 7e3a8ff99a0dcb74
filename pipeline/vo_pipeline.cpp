#include "pipeline/vo_pipeline.hpp"

#include <algorithm>
#include <utility>

#include "core/error.hpp"

namespace driftlab::pipeline {

namespace {

// A VO's matches on the frame it processed last, copied out of its buffers.
std::vector<vo::MatchInfo> matches_of(const vo::StereoOdometry& vo) {
  const auto m = vo.last_matches();
  return {m.begin(), m.end()};
}

}  // namespace

VoPipeline::VoPipeline(std::vector<Track>* tracks, int threads, std::size_t lookahead)
    : tracks_(*tracks), lookahead_(std::max<std::size_t>(lookahead, 1)), serial_(threads <= 1) {
  for (std::size_t i = 0; i < tracks_.size(); ++i)
    if (tracks_[i].vo) vos_.push_back(i);
  next_.assign(vos_.size(), 0);
  busy_.assign(vos_.size(), false);
  ms_.resize(vos_.size());
  for (std::size_t j = 0; j < vos_.size(); ++j) ms_[j] = tracks_[vos_[j]].vo_ms;
  if (serial_) return;
  const std::size_t n = std::min(vos_.size(), static_cast<std::size_t>(threads));
  for (std::size_t w = 0; w < n; ++w) workers_.emplace_back([this] { work(); });
}

VoPipeline::~VoPipeline() {
  {
    const std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void VoPipeline::rethrow_if_failed() const {
  if (error_) std::rethrow_exception(error_);
}

int VoPipeline::pick() const {
  int best = -1;
  for (std::size_t j = 0; j < vos_.size(); ++j) {
    if (busy_[j] || next_[j] >= first_slot_ + slots_.size()) continue;
    if (best < 0 || ms_[j] > ms_[static_cast<std::size_t>(best)]) best = static_cast<int>(j);
  }
  return best;
}

void VoPipeline::work() {
  std::unique_lock lock(mutex_);
  for (;;) {
    int j = -1;
    changed_.wait(lock, [&] { return stop_ || error_ || (j = pick()) >= 0; });
    if (stop_ || error_) return;
    const std::size_t jj = static_cast<std::size_t>(j);
    busy_[jj] = true;
    Slot& slot = slots_[next_[jj] - first_slot_];  // stays put: it waits for this VO's result
    Track& track = tracks_[vos_[jj]];
    lock.unlock();
    vo::VoResult r;
    std::exception_ptr error;
    std::vector<vo::MatchInfo> matches;
    try {
      r = track.vo->process(slot.job.frame);
      if (slot.job.keep_matches) matches = matches_of(*track.vo);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    busy_[jj] = false;
    if (error) {
      if (!error_) error_ = error;
    } else {
      ms_[jj] += r.times.total_ms;
      slot.matches[vos_[jj]] = std::move(matches);
      slot.results[vos_[jj]] = std::move(r);
      --slot.remaining;
      ++next_[jj];
    }
    changed_.notify_all();
  }
}

void VoPipeline::submit(VoJob job) {
  if (serial_) {
    {
      const std::lock_guard lock(mutex_);
      rethrow_if_failed();
    }
    Slot slot;
    try {
      slot.results = process_vos(&tracks_, job.frame, 1);
    } catch (...) {
      const std::lock_guard lock(mutex_);
      error_ = std::current_exception();
      throw;
    }
    slot.matches.resize(tracks_.size());
    if (job.keep_matches)
      for (const std::size_t i : vos_) slot.matches[i] = matches_of(*tracks_[i].vo);
    slot.job = std::move(job);
    const std::lock_guard lock(mutex_);
    slots_.push_back(std::move(slot));
    return;
  }
  const std::lock_guard lock(mutex_);
  rethrow_if_failed();
  DRIFTLAB_DEMAND_MSG(slots_.size() < lookahead_, "VoPipeline::submit when full");
  Slot slot;
  slot.results.resize(tracks_.size());
  slot.matches.resize(tracks_.size());
  slot.remaining = vos_.size();
  slot.job = std::move(job);
  slots_.push_back(std::move(slot));
  changed_.notify_all();
}

bool VoPipeline::full() const {
  const std::lock_guard lock(mutex_);
  return slots_.size() >= lookahead_;
}

std::optional<VoJobDone> VoPipeline::next_done(bool wait) {
  std::unique_lock lock(mutex_);
  if (wait)
    changed_.wait(lock, [&] { return error_ || slots_.empty() || slots_.front().remaining == 0; });
  rethrow_if_failed();
  if (slots_.empty() || slots_.front().remaining > 0) return std::nullopt;
  Slot& s = slots_.front();
  VoJobDone done{std::move(s.job), std::move(s.results), std::move(s.matches)};
  slots_.pop_front();
  ++first_slot_;
  changed_.notify_all();
  return done;
}

}  // namespace driftlab::pipeline
