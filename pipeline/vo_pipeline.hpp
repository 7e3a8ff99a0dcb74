// The VO tracks of a run, each along its own sequence of frames: a VO takes frame k
// as soon as it has finished frame k-1 and frame k is in, whatever frame the other VOs are at,
// so that the slowest VO no longer holds the others at every frame (process_vos' barrier: on
// two cores the dense VO beside the two sparse ones left a core idle for about 8 ms a frame).
// A VO's result depends only on its own state and its frames, which it still takes in order, so
// the results are those of process_vos, at any thread count.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "pipeline/tracks.hpp"

namespace driftlab::pipeline {

/// A frame handed to the VOs: the frame and whatever its caller keeps alive beside it (the
/// images the frame's views point into).
struct VoJob {
  std::size_t k = 0;  ///< the frame's index, handed back with its results
  vo::StereoFrame frame;
  std::shared_ptr<const void> keep_alive;
  bool keep_matches = false;  ///< also hand back each VO's last_matches() on this frame
};

/// A frame whose VOs are all done.
struct VoJobDone {
  VoJob job;
  std::vector<vo::VoResult> results;  ///< by track index, as process_vos gives them
  /// With keep_matches: each VO track's matches on this frame (empty for the other tracks).
  std::vector<std::vector<vo::MatchInfo>> matches;
};

/// Runs the VO tracks of `tracks` on `threads` workers (at most one per VO), each VO on the
/// frames in the order they were submitted, at most `lookahead` frames in flight. The worker
/// that comes free takes, among the VOs whose next frame is in, the one slowest so far (ties in
/// track order). With `threads` <= 1 there are no workers: submit() runs every VO on the frame
/// in turn (process_vos). The tracks' VOs must not be touched elsewhere until the pipeline is
/// destroyed; a VO's exception comes out of the next submit() or next_done(), after which no
/// VO takes another frame.
class VoPipeline {
 public:
  VoPipeline(std::vector<Track>* tracks, int threads, std::size_t lookahead);
  ~VoPipeline();
  VoPipeline(const VoPipeline&) = delete;
  VoPipeline& operator=(const VoPipeline&) = delete;

  /// Whether `lookahead` frames are in flight: then take the oldest out (next_done) before
  /// submitting another.
  bool full() const;
  /// Hands a frame to every VO (the pipeline must not be full).
  void submit(VoJob job);
  /// The oldest submitted frame once all its VOs are done (waiting for them with `wait`), in
  /// submission order; nullopt when none is in flight (or, without `wait`, none is done).
  std::optional<VoJobDone> next_done(bool wait);

 private:
  struct Slot {
    VoJob job;
    std::vector<vo::VoResult> results;
    std::vector<std::vector<vo::MatchInfo>> matches;
    std::size_t remaining = 0;  // VOs still to run on it
  };
  void work();
  // Under mutex_: the VO track that a free worker takes next, or -1.
  int pick() const;
  void rethrow_if_failed() const;  // under mutex_

  std::vector<Track>& tracks_;
  std::vector<std::size_t> vos_;  // the VO tracks' indices
  std::size_t lookahead_;
  bool serial_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Slot> slots_;         // in flight, oldest first
  std::size_t first_slot_ = 0;     // the number of slots handed back
  std::vector<std::size_t> next_;  // per entry of vos_: the slot (absolute index) it runs next
  std::vector<bool> busy_;         // per entry of vos_
  std::vector<double> ms_;         // per entry of vos_: its time so far
  std::exception_ptr error_;
  bool stop_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace driftlab::pipeline
