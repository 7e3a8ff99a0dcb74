// pipeline/tracks: the VOs of a frame side by side (process_vos); pipeline/vo_pipeline: each VO
// along its own frames (VoPipeline).
#include "pipeline/tracks.hpp"
#include "pipeline/vo_pipeline.hpp"

#include <atomic>
#include <chrono>
#include <memory>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.hpp"

namespace driftlab::pipeline {
namespace {

// A VO whose result is a function of its own calls and the frame's time only, which records the
// thread it ran on, and which throws on the call `throw_on` (0: never).
class RecordingVo final : public vo::StereoOdometry {
 public:
  RecordingVo(int id, int throw_on = 0, int sleep_ms = 20)
      : id_(id), throw_on_(throw_on), sleep_ms_(sleep_ms) {}
  vo::VoResult process(const vo::StereoFrame& frame) override {
    ++calls_;
    thread_ = std::this_thread::get_id();
    // Long enough for the VOs of one frame to overlap when they run side by side.
    std::this_thread::sleep_for(std::chrono::milliseconds(sleep_ms_));
    if (calls_ == throw_on_) throw UserError("vo " + std::to_string(id_) + " failed");
    vo::VoResult r;
    r.valid = true;
    r.T_prev_curr = SE3(Mat3::Identity(), Vec3(id_, calls_, static_cast<double>(frame.t_ns)));
    r.inliers = 100 * id_ + calls_;
    done_ = calls_;
    return r;
  }
  void reset() override { calls_ = 0; }
  std::string name() const override { return "recording" + std::to_string(id_); }
  std::thread::id thread() const { return thread_; }
  int done() const { return done_; }

 private:
  int id_, throw_on_, sleep_ms_;
  int calls_ = 0;
  std::atomic<int> done_{0};
  std::thread::id thread_;
};

// Three VO tracks with a filter-like track (no VO) between them.
std::vector<Track> three_vos(int throw_on_of_second = 0) {
  std::vector<Track> tracks(4);
  tracks[0].vo = std::make_unique<RecordingVo>(1);
  tracks[1].source = 0;  // follows the first VO: process_vos leaves it alone
  tracks[2].vo = std::make_unique<RecordingVo>(2, throw_on_of_second);
  tracks[3].vo = std::make_unique<RecordingVo>(3);
  return tracks;
}

const RecordingVo& vo_of(const Track& t) { return dynamic_cast<const RecordingVo&>(*t.vo); }

TEST(ProcessVos, SideBySideGivesTheResultsOfTheVosInTurn) {
  for (int threads : {2, 3, 8}) {
    std::vector<Track> serial = three_vos(), parallel = three_vos();
    for (TimeNs t : {TimeNs{10}, TimeNs{20}, TimeNs{30}}) {
      vo::StereoFrame frame;
      frame.t_ns = t;
      const auto a = process_vos(&serial, frame, 1);
      const auto b = process_vos(&parallel, frame, threads);
      ASSERT_EQ(a.size(), 4u);
      ASSERT_EQ(b.size(), 4u);
      for (std::size_t i = 0; i < 4; ++i) {
        EXPECT_EQ(a[i].valid, b[i].valid) << i;
        EXPECT_EQ(a[i].inliers, b[i].inliers) << i;
        EXPECT_EQ(a[i].T_prev_curr.translation(), b[i].T_prev_curr.translation()) << i;
      }
      EXPECT_FALSE(a[1].valid);  // the track without a VO keeps a default result
      EXPECT_EQ(a[3].inliers, 300 + static_cast<int>(t / 10));
      // In turn: every VO on the calling thread. Side by side: the three on three threads
      // (with 2 threads, the third on whichever of the two is free first).
      const std::thread::id me = std::this_thread::get_id();
      for (std::size_t i : {0u, 2u, 3u}) EXPECT_EQ(vo_of(serial[i]).thread(), me);
      const std::set<std::thread::id> used{vo_of(parallel[0]).thread(), vo_of(parallel[2]).thread(),
                                           vo_of(parallel[3]).thread()};
      EXPECT_EQ(used.size(), threads == 2 ? 2u : 3u) << threads;
      EXPECT_EQ(vo_of(parallel[0]).thread(), me);
    }
  }
}

TEST(ProcessVos, TheSlowestSoFarStartsFirstAndTheOthersShareTheOtherWorker) {
  // VO 3 took longest so far (vo_ms) and takes 200 ms now; the others 20 ms each. On two
  // workers the caller takes VO 3 first and the other worker runs VOs 1 and 2 one after the
  // other meanwhile (in track order: the calls of the VOs in turn took 0 ms so far).
  std::vector<Track> tracks(3);
  tracks[0].vo = std::make_unique<RecordingVo>(1);
  tracks[1].vo = std::make_unique<RecordingVo>(2);
  tracks[2].vo = std::make_unique<RecordingVo>(3, 0, 200);
  tracks[2].vo_ms = 100;
  const auto results = process_vos(&tracks, vo::StereoFrame{}, 2);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(results[i].inliers, 100 * (i + 1) + 1) << i;
  EXPECT_EQ(vo_of(tracks[2]).thread(), std::this_thread::get_id());
  EXPECT_NE(vo_of(tracks[0]).thread(), std::this_thread::get_id());
  EXPECT_EQ(vo_of(tracks[0]).thread(), vo_of(tracks[1]).thread());
}

TEST(ProcessVos, AVosExceptionReachesTheCallerAfterTheOthersFinish) {
  for (int threads : {1, 3}) {
    std::vector<Track> tracks = three_vos(/*throw_on_of_second=*/2);
    vo::StereoFrame frame;
    process_vos(&tracks, frame, threads);
    try {
      process_vos(&tracks, frame, threads);
      FAIL() << "expected the second VO's UserError";
    } catch (const UserError& e) {
      EXPECT_STREQ(e.what(), "vo 2 failed");
    }
    // The VOs beside it completed their second frame before the exception came out.
    EXPECT_EQ(vo_of(tracks[0]).done(), 2) << threads;
    EXPECT_EQ(vo_of(tracks[3]).done(), threads == 1 ? 1 : 2) << threads;
  }
}

VoJob job_at(std::size_t k) {
  VoJob job;
  job.k = k;
  job.frame.t_ns = static_cast<TimeNs>(10 * (k + 1));
  return job;
}

// Submits `frames` frames, taking out the oldest whenever the pipeline is full, then the rest.
std::vector<VoJobDone> run_pipeline(VoPipeline* p, std::size_t frames) {
  std::vector<VoJobDone> out;
  for (std::size_t k = 0; k < frames; ++k) {
    while (p->full()) out.push_back(*p->next_done(true));
    p->submit(job_at(k));
    while (auto d = p->next_done(false)) out.push_back(std::move(*d));
  }
  while (auto d = p->next_done(true)) out.push_back(std::move(*d));
  return out;
}

TEST(VoPipeline, GivesTheResultsOfTheVosInTurnInFrameOrder) {
  for (int threads : {1, 2, 3, 8}) {
    std::vector<Track> serial = three_vos(), piped = three_vos();
    std::vector<std::vector<vo::VoResult>> expected;
    for (std::size_t k = 0; k < 7; ++k)
      expected.push_back(process_vos(&serial, job_at(k).frame, 1));
    std::vector<VoJobDone> got;
    {
      VoPipeline p(&piped, threads, 3);
      got = run_pipeline(&p, 7);
    }
    ASSERT_EQ(got.size(), 7u) << threads;
    for (std::size_t k = 0; k < 7; ++k) {
      EXPECT_EQ(got[k].job.k, k);
      ASSERT_EQ(got[k].results.size(), 4u);
      for (std::size_t i = 0; i < 4; ++i) {
        EXPECT_EQ(got[k].results[i].valid, expected[k][i].valid) << threads << " " << k << " " << i;
        EXPECT_EQ(got[k].results[i].inliers, expected[k][i].inliers) << threads << " " << k;
        EXPECT_EQ(got[k].results[i].T_prev_curr.translation(),
                  expected[k][i].T_prev_curr.translation());
      }
    }
    EXPECT_FALSE(piped[1].vo);  // the track without a VO is left alone
    EXPECT_EQ(vo_of(piped[3]).done(), 7);
  }
}

TEST(VoPipeline, TheFastVosRunAheadWhileTheSlowOneTakesItsFrame) {
  // VO 1 takes 150 ms a frame, VOs 2 and 3 5 ms: on two workers, by the time VO 1 is done with
  // frame 0 the other worker has run VOs 2 and 3 on the next frames (process_vos would hold them
  // at frame 0 for 150 ms).
  std::vector<Track> tracks(3);
  tracks[0].vo = std::make_unique<RecordingVo>(1, 0, 150);
  tracks[1].vo = std::make_unique<RecordingVo>(2, 0, 5);
  tracks[2].vo = std::make_unique<RecordingVo>(3, 0, 5);
  tracks[0].vo_ms = 100;  // the slowest so far: taken first
  VoPipeline p(&tracks, 2, 4);
  for (std::size_t k = 0; k < 4; ++k) p.submit(job_at(k));
  EXPECT_TRUE(p.full());
  const std::optional<VoJobDone> first = p.next_done(true);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->job.k, 0u);
  EXPECT_GE(vo_of(tracks[1]).done(), 3);
  EXPECT_GE(vo_of(tracks[2]).done(), 3);
  EXPECT_EQ(vo_of(tracks[0]).done(), 1);
}

TEST(VoPipeline, AVosExceptionReachesTheCaller) {
  for (int threads : {1, 2}) {
    std::vector<Track> tracks = three_vos(/*throw_on_of_second=*/3);
    VoPipeline p(&tracks, threads, 2);
    try {
      run_pipeline(&p, 6);
      FAIL() << "expected the second VO's UserError";
    } catch (const UserError& e) {
      EXPECT_STREQ(e.what(), "vo 2 failed");
    }
    EXPECT_THROW(p.submit(job_at(9)), UserError) << "and from every call after it";
  }
}

}  // namespace
}  // namespace driftlab::pipeline
