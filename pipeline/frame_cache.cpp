#include "pipeline/frame_cache.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <xxhash.h>
#include <zstd.h>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/hash.hpp"
#include "core/number.hpp"

namespace driftlab::pipeline {

namespace fs = std::filesystem;
using Row = FrameCacheReader::Row;

namespace {

constexpr const char* kIndexHeader =
    "k,exposure_ms,blur_samples,moving_px,width,height,left_bytes,left_xxh3_64,right_bytes,"
    "right_xxh3_64";

// An image file's checksum: XXH3-64 (libxxhash), 19 times faster than FNV-1a 64 (16 GB/s against
// 0.86, frame_cache_bench BM_FileChecksum), whose byte-by-byte loop was a tenth of a warm gate
// job (every file is hashed twice: when the entry is found and as it is read).
std::uint64_t file_hash(std::string_view bytes) { return XXH3_64bits(bytes.data(), bytes.size()); }

// The whole file as bytes; false when it cannot be read.
bool read_bytes(const fs::path& path, std::string* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  *out = std::move(s).str();
  return !in.bad();
}

void write_bytes(const fs::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw UserError(fmt::format("{}: cannot write a frame cache file", path.string()));
}

std::string frame_file(std::size_t i, char eye) { return fmt::format("{:06d}_{}.zst", i, eye); }

// The image's rows, compressed by zstd at level 1: lossless, and 12 times faster to read back
// than PNG for 23 % more disk (bench/frame_cache_bench.cpp, docs/performance.md).
std::string encode_image(const sim::GrayImage& image) {
  std::string out(ZSTD_compressBound(image.pixels.size()), '\0');
  const std::size_t n =
      ZSTD_compress(out.data(), out.size(), image.pixels.data(), image.pixels.size(), 1);
  if (ZSTD_isError(n))
    throw UserError(fmt::format("frame cache: zstd compression failed: {}", ZSTD_getErrorName(n)));
  out.resize(n);
  return out;
}

// The image in `bytes` when they decompress to exactly width x height bytes.
bool decode_image(const std::string& bytes, int width, int height, sim::GrayImage* image) {
  const std::size_t size = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (ZSTD_getFrameContentSize(bytes.data(), bytes.size()) != size) return false;
  image->pixels.resize(size);
  const std::size_t n = ZSTD_decompress(image->pixels.data(), size, bytes.data(), bytes.size());
  if (ZSTD_isError(n) || n != size) return false;
  image->width = width;
  image->height = height;
  return true;
}

template <class T>
bool parse_number(const std::string& text, T* value) {
  return read_number(text, value) == NumberStatus::kOk;
}

bool parse_hash(const std::string& text, std::uint64_t* value) {
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, *value, 16);
  return text.size() == 16 && ec == std::errc() && ptr == end;
}

// One index.csv row; false when it is not one.
bool parse_row(const std::string& line, Row* r) {
  const std::vector<std::string> c = split_csv_line(line);
  return c.size() == 10 && parse_number(c[0], &r->meta.k) &&
         parse_number(c[1], &r->meta.exposure_ms) && parse_number(c[2], &r->meta.blur_samples) &&
         parse_number(c[3], &r->meta.moving_px) && parse_number(c[4], &r->width) &&
         parse_number(c[5], &r->height) && parse_number(c[6], &r->left_bytes) &&
         parse_hash(c[7], &r->left_hash) && parse_number(c[8], &r->right_bytes) &&
         parse_hash(c[9], &r->right_hash) && r->width > 0 && r->height > 0 &&
         r->meta.moving_px >= 0 && r->meta.moving_px <= 1;
}

std::string row_text(const Row& r) {
  return fmt::format("{},{},{},{},{},{},{},{},{},{}\n", r.meta.k, r.meta.exposure_ms,
                     r.meta.blur_samples, r.meta.moving_px, r.width, r.height, r.left_bytes,
                     hex64(r.left_hash), r.right_bytes, hex64(r.right_hash));
}

// The rows of an index.csv; "" or what is wrong with it.
std::string parse_index(const std::string& text, std::vector<Row>* rows) {
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line) || line != kIndexHeader) return "index.csv has no header";
  while (std::getline(in, line)) {
    if (line.rfind("end,", 0) == 0) {
      std::size_t n = 0;
      if (!parse_number(line.substr(4), &n) || n != rows->size())
        return "index.csv's end row does not count its rows";
      return std::getline(in, line) ? "index.csv goes on after its end row" : "";
    }
    Row r;
    if (!parse_row(line, &r)) return fmt::format("index.csv row {} is malformed", rows->size() + 1);
    rows->push_back(r);
  }
  return "index.csv is truncated (no end row)";
}

// "" when `path` holds `bytes` bytes with checksum `hash` (then in *data), else what differs.
std::string check_file(const fs::path& path, std::uint64_t bytes, std::uint64_t hash,
                       std::string* data) {
  if (!read_bytes(path, data)) return path.filename().string() + " is missing";
  if (data->size() != bytes)
    return fmt::format("{} has {} bytes, the index says {}", path.filename().string(), data->size(),
                       bytes);
  if (file_hash(*data) != hash)
    return path.filename().string() + " does not hold the bytes the index names";
  return "";
}

// Removes an entry unless someone reads it: renamed aside first, so that no reader finds half
// of it. Returns whether it was removed.
bool remove_entry(const fs::path& entry) {
  const int fd = ::open((entry / "key.txt").c_str(), O_RDONLY | O_CLOEXEC);
  if (fd >= 0 && ::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    return false;
  }
  static std::atomic<unsigned> counter{0};
  const fs::path trash =
      entry.parent_path() /
      fmt::format(".trash-{}-{}-{}", entry.filename().string(), ::getpid(), counter++);
  std::error_code ec;
  fs::rename(entry, trash, ec);
  if (fd >= 0) ::close(fd);
  if (ec) return false;
  fs::remove_all(trash, ec);
  return true;
}

std::uint64_t folder_bytes(const fs::path& dir) {
  std::uint64_t total = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file(ec)) total += e.file_size(ec);
  return total;
}

// Whether the process that named a fill folder `.fill-NAME-PID-N` is gone.
bool fill_is_orphaned(const std::string& name) {
  const auto last = name.rfind('-');
  if (last == std::string::npos || last == 0) return false;
  const auto before = name.rfind('-', last - 1);
  if (before == std::string::npos) return false;
  int pid = 0;
  if (!parse_number(name.substr(before + 1, last - before - 1), &pid) || pid <= 0) return false;
  return ::kill(pid, 0) != 0 && errno == ESRCH;
}

}  // namespace

// ---------------------------------------------------------------------------
// Reader

FrameCacheReader::FrameCacheReader(fs::path dir, std::vector<Row> rows, int lock_fd)
    : dir_(std::move(dir)), rows_(std::move(rows)), lock_fd_(lock_fd) {}

FrameCacheReader::~FrameCacheReader() {
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

CacheFrame FrameCacheReader::frame(std::size_t i) const {
  const Row& r = rows_.at(i);
  CacheFrame f = r.meta;
  std::string bytes;
  for (const auto& [eye, bytes_n, hash, image] :
       {std::tuple{'l', r.left_bytes, r.left_hash, &f.left},
        std::tuple{'r', r.right_bytes, r.right_hash, &f.right}}) {
    const fs::path path = dir_ / frame_file(i, eye);
    std::string problem = check_file(path, bytes_n, hash, &bytes);
    if (problem.empty() && !decode_image(bytes, r.width, r.height, image))
      problem = path.filename().string() + " is not the " + std::to_string(r.width) + "x" +
                std::to_string(r.height) + " grey image the index names";
    if (!problem.empty())
      throw UserError(
          fmt::format("frame cache entry {}: {} (changed while in use?)", dir_.string(), problem));
  }
  return f;
}

// ---------------------------------------------------------------------------
// Writer

FrameCacheWriter::FrameCacheWriter(fs::path temp, fs::path final_dir)
    : temp_(std::move(temp)), final_(std::move(final_dir)) {}

FrameCacheWriter::~FrameCacheWriter() {
  if (done_) return;
  std::error_code ec;
  fs::remove_all(temp_, ec);
}

void FrameCacheWriter::add(const CacheFrame& frame) {
  DRIFTLAB_DEMAND_MSG(!done_, "FrameCacheWriter::add after commit");
  Row r;
  r.meta.k = frame.k;  // the metadata only: the images go to files
  r.meta.exposure_ms = frame.exposure_ms;
  r.meta.blur_samples = frame.blur_samples;
  r.meta.moving_px = frame.moving_px;
  r.width = frame.left.width;
  r.height = frame.left.height;
  const std::size_t i = rows_.size();
  const std::string left = encode_image(frame.left), right = encode_image(frame.right);
  write_bytes(temp_ / frame_file(i, 'l'), left);
  write_bytes(temp_ / frame_file(i, 'r'), right);
  r.left_bytes = left.size();
  r.left_hash = file_hash(left);
  r.right_bytes = right.size();
  r.right_hash = file_hash(right);
  rows_.push_back(r);
}

bool FrameCacheWriter::commit() {
  DRIFTLAB_DEMAND_MSG(!done_, "FrameCacheWriter::commit twice");
  std::string index = std::string(kIndexHeader) + "\n";
  for (const Row& r : rows_) index += row_text(r);
  index += fmt::format("end,{}\n", rows_.size());
  write_bytes(temp_ / "index.csv", index);
  std::error_code ec;
  fs::rename(temp_, final_, ec);  // atomic; fails when another process published it first
  done_ = !ec;
  return done_;
}

// ---------------------------------------------------------------------------
// Cache

FrameCacheOptions FrameCacheOptions::from_environment() {
  FrameCacheOptions o;
  if (const char* dir = std::getenv("DRIFTLAB_FRAME_CACHE")) o.dir = dir;
  if (const char* gib = std::getenv("DRIFTLAB_FRAME_CACHE_GIB"); gib && *gib) {
    double value = 0;
    if (!parse_number(std::string(gib), &value) || !(value > 0) || value > 1e6)
      throw UserError(fmt::format(
          "environment variable DRIFTLAB_FRAME_CACHE_GIB: got '{}', expected the frame cache's "
          "size in GiB, a number above 0 (e.g. 20)",
          gib));
    o.max_bytes = static_cast<std::uint64_t>(value * static_cast<double>(1ULL << 30));
  }
  return o;
}

FrameCache::FrameCache(fs::path dir, std::uint64_t max_bytes)
    : dir_(std::move(dir)), max_bytes_(max_bytes) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec || !fs::is_directory(dir_))
    throw UserError(fmt::format("frame cache {}: cannot create the folder: {}", dir_.string(),
                                ec ? ec.message() : "not a folder"));
}

fs::path FrameCache::entry_dir(const std::string& key) const { return dir_ / fnv1a64_hex(key); }

std::unique_ptr<FrameCacheReader> FrameCache::find(const std::string& key,
                                                   std::string* warning) const {
  const fs::path entry = entry_dir(key);
  const int fd = ::open((entry / "key.txt").c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return nullptr;  // no entry: a plain miss
  ::flock(fd, LOCK_SH);
  // Evicted between open and lock: key.txt is no longer the file at that path.
  struct stat held {
  }, now{};
  if (::fstat(fd, &held) != 0 || ::stat((entry / "key.txt").c_str(), &now) != 0 ||
      held.st_ino != now.st_ino) {
    ::close(fd);
    return nullptr;
  }
  auto fail = [&](const std::string& problem) -> std::unique_ptr<FrameCacheReader> {
    ::close(fd);
    remove_entry(entry);
    if (warning)
      *warning = fmt::format("frame cache entry {} is not used and is removed: {}", entry.string(),
                             problem);
    return nullptr;
  };
  std::string text;
  if (!read_bytes(entry / "key.txt", &text) || text != key)
    return fail("key.txt holds another key than the run's");
  std::vector<Row> rows;
  if (!read_bytes(entry / "index.csv", &text)) return fail("index.csv is missing");
  if (std::string problem = parse_index(text, &rows); !problem.empty()) return fail(problem);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    std::string bytes;
    for (const auto& [eye, n, hash] :
         {std::tuple{'l', r.left_bytes, r.left_hash}, std::tuple{'r', r.right_bytes, r.right_hash}})
      if (std::string problem = check_file(entry / frame_file(i, eye), n, hash, &bytes);
          !problem.empty())
        return fail(problem);
  }
  std::error_code ec;
  fs::last_write_time(entry, fs::file_time_type::clock::now(), ec);  // its last use
  return std::unique_ptr<FrameCacheReader>(new FrameCacheReader(entry, std::move(rows), fd));
}

std::unique_ptr<FrameCacheWriter> FrameCache::fill(const std::string& key) const {
  static std::atomic<unsigned> counter{0};
  const fs::path entry = entry_dir(key);
  const fs::path temp =
      dir_ / fmt::format(".fill-{}-{}-{}", entry.filename().string(), ::getpid(), counter++);
  std::error_code ec;
  fs::remove_all(temp, ec);
  fs::create_directory(temp, ec);
  if (ec)
    throw UserError(fmt::format("frame cache {}: cannot create {}: {}", dir_.string(),
                                temp.string(), ec.message()));
  std::unique_ptr<FrameCacheWriter> w(new FrameCacheWriter(temp, entry));
  write_bytes(temp / "key.txt", key);
  return w;
}

FrameCache::FillLock::~FillLock() {
  if (fd_ >= 0) ::close(fd_);
}

std::unique_ptr<FrameCache::FillLock> FrameCache::lock_fill(const std::string& key) const {
  // A lock file beside the entries (names starting with '.' are never entries), never removed:
  // removing it could hand two processes two different files to lock.
  const fs::path path = dir_ / (".lock-" + fnv1a64_hex(key));
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0)
    throw UserError(fmt::format("frame cache {}: cannot open {}: {}", dir_.string(), path.string(),
                                std::strerror(errno)));
  while (::flock(fd, LOCK_EX) != 0 && errno == EINTR) {
  }
  return std::make_unique<FillLock>(fd);
}

std::size_t FrameCache::evict() const {
  struct Entry {
    fs::path dir;
    fs::file_time_type used;
    std::uint64_t bytes;
  };
  std::vector<Entry> entries;
  std::uint64_t total = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir_, ec)) {
    if (!e.is_directory(ec)) continue;
    const std::string name = e.path().filename().string();
    if (name.rfind(".trash-", 0) == 0 || (name.rfind(".fill-", 0) == 0 && fill_is_orphaned(name))) {
      fs::remove_all(e.path(), ec);
      continue;
    }
    if (name.front() == '.') continue;
    entries.push_back({e.path(), fs::last_write_time(e.path(), ec), folder_bytes(e.path())});
    total += entries.back().bytes;
  }
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.used < b.used; });
  std::size_t removed = 0;
  for (const Entry& e : entries) {
    if (total <= max_bytes_) break;
    if (!remove_entry(e.dir)) continue;
    total -= e.bytes;
    ++removed;
  }
  return removed;
}

}  // namespace driftlab::pipeline
