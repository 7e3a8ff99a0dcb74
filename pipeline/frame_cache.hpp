// The frame cache's store (docs/design.md, "Frame cache"): stereo frames kept under a key text that
// names everything deciding their bytes, so that runs whose frames would come out the same replay
// them instead of rendering. An entry is a folder named by the FNV-1a 64 of its key
// (core/hash.hpp) holding:
//   key.txt     the key text itself, compared whole on every lookup (so two keys never share
//               an entry, whatever their hashes);
//   index.csv   one row per frame: k, exposure, blur samples, moving share, size, the length and
//               XXH3-64 of each image file; a last row `end,N` (a truncated index has none);
//   NNNNNN_l.zst, NNNNNN_r.zst  the 8-bit rectified images, row by row, compressed by zstd
//               (lossless).
// An entry is filled in a folder of its own and published by one rename, so that a reader
// never sees half of one; two processes filling the same key both finish, and the first
// rename wins. Every byte is checked before an entry is used (find) and again as each frame is
// read: an entry that fails is removed with a warning and is a miss, never served. Least
// recently used entries go first when the cache outgrows its size; an entry being read is
// never removed (a shared lock on its key.txt). docs/design.md "Frame cache".
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "sim/render/renderer.hpp"

namespace driftlab::pipeline {

/// Where a run keeps its frames: `driftlab run/export/sweep run --frame-cache DIR`, or the
/// environment (DRIFTLAB_FRAME_CACHE, DRIFTLAB_FRAME_CACHE_GIB).
struct FrameCacheOptions {
  std::filesystem::path dir;              ///< empty: no cache
  std::uint64_t max_bytes = 20ULL << 30;  ///< evict() keeps the cache to this size

  /// DRIFTLAB_FRAME_CACHE (the folder; unset or empty: no cache) and DRIFTLAB_FRAME_CACHE_GIB
  /// (its size in GiB, default 20). Throws UserError naming the variable, its value and what
  /// was expected when the size is not a positive number.
  static FrameCacheOptions from_environment();
};

/// One frame as the cache keeps it (a CapturedFrame without its render time).
struct CacheFrame {
  std::size_t k = 0;  ///< index into the run's frame times
  double exposure_ms = 0;
  int blur_samples = 1;
  double moving_px = 0;  ///< CapturedFrame::moving_px
  sim::GrayImage left, right;
};

/// An entry found whole: its frames, each checked again as it is read.
class FrameCacheReader {
 public:
  ~FrameCacheReader();
  FrameCacheReader(const FrameCacheReader&) = delete;
  FrameCacheReader& operator=(const FrameCacheReader&) = delete;

  std::size_t size() const { return rows_.size(); }
  /// Frame i (0-based among the entry's frames), decoded. Throws UserError when its files no
  /// longer hold the bytes the index names.
  CacheFrame frame(std::size_t i) const;
  const std::filesystem::path& dir() const { return dir_; }

  struct Row {
    CacheFrame meta;  // without images
    int width = 0, height = 0;
    std::uint64_t left_bytes = 0, left_hash = 0, right_bytes = 0, right_hash = 0;
  };

 private:
  friend class FrameCache;
  FrameCacheReader(std::filesystem::path dir, std::vector<Row> rows, int lock_fd);
  std::filesystem::path dir_;
  std::vector<Row> rows_;
  int lock_fd_ = -1;  // holds a shared flock on key.txt while the entry is read
};

/// A new entry, filled frame by frame and published by commit(). Without commit() its folder
/// is removed.
class FrameCacheWriter {
 public:
  ~FrameCacheWriter();
  FrameCacheWriter(const FrameCacheWriter&) = delete;
  FrameCacheWriter& operator=(const FrameCacheWriter&) = delete;

  /// Encodes and writes one frame (frames in the order they are to be replayed).
  void add(const CacheFrame& frame);
  /// Writes the index and renames the folder into place. Returns false when another process
  /// published the same key first: its entry stays and this one is dropped.
  bool commit();

 private:
  friend class FrameCache;
  FrameCacheWriter(std::filesystem::path temp, std::filesystem::path final_dir);
  std::filesystem::path temp_, final_;
  std::vector<FrameCacheReader::Row> rows_;
  bool done_ = false;
};

class FrameCache {
 public:
  /// A cache in `dir` (created when missing) that evict() keeps to at most `max_bytes`.
  FrameCache(std::filesystem::path dir, std::uint64_t max_bytes);

  /// The entry for `key` when a whole one is there and every byte checks (its last use is then
  /// now); null otherwise. An entry that fails a check (another key's text, a missing,
  /// truncated or altered file) is removed, and `warning` says what failed.
  std::unique_ptr<FrameCacheReader> find(const std::string& key, std::string* warning) const;
  /// A writer of a new entry for `key`.
  std::unique_ptr<FrameCacheWriter> fill(const std::string& key) const;
  /// Waits until no other process fills `key`, then holds that until the lock is destroyed:
  /// runs that want the same frames at once render them once (the second finds the entry).
  class FillLock;
  std::unique_ptr<FillLock> lock_fill(const std::string& key) const;
  /// Removes least recently used entries, never one being read, until at most max_bytes
  /// remain, and the folders of fills whose process is gone. Returns the entries removed.
  std::size_t evict() const;

  /// The folder an entry for `key` has (whether or not it exists).
  std::filesystem::path entry_dir(const std::string& key) const;
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  std::uint64_t max_bytes_;
};

class FrameCache::FillLock {
 public:
  explicit FillLock(int fd) : fd_(fd) {}
  ~FillLock();
  FillLock(const FillLock&) = delete;
  FillLock& operator=(const FillLock&) = delete;

 private:
  int fd_;
};

}  // namespace driftlab::pipeline
