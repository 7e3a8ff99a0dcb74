// The record structure of a ROS 1 bag, checked before rosbag_storage reads it (rosbag_read.cpp):
// the library trusts every length it reads and allocates what a record claims (a fuzzed 16 KB
// file asked it for 538 MB). Bag format 2.0 (wiki.ros.org/Bags/Format/2.0): "#ROSBAG V2.0\n",
// then records of u32 header_len, header (fields: u32 length, "name=value"), u32 data_len, data.
#include <fmt/format.h>

#include <cstring>
#include <fstream>
#include <map>

#include "core/error.hpp"
#include "dataset/dataset_detail.hpp"

namespace driftlab::dataset::detail {
namespace fs = std::filesystem;
namespace {

constexpr std::uint64_t kMaxChunkBytes = 1ull << 30;  // larger unpacked chunks are refused

struct RecordHeader {
  std::map<std::string, std::string> fields;
  std::uint64_t u(const std::string& name, std::size_t bytes) const {
    const auto f = fields.find(name);
    if (f == fields.end() || f->second.size() != bytes) return ~0ull;
    std::uint64_t v = 0;
    std::memcpy(&v, f->second.data(), bytes);  // little endian, as the format and x86-64
    return v;
  }
};

// Reads the headers only, seeking past the data, so that a large bag costs little.
struct BagChecker {
  fs::path path;
  mutable std::ifstream in;
  std::uint64_t size = 0;
  [[noreturn]] void fail(std::uint64_t at, const std::string& what) const {
    throw UserError(fmt::format("{}: record at byte {}: {}, expected a ROS 1 bag (format 2.0)",
                                path.string(), at, what));
  }
  std::string read(std::uint64_t at, std::uint64_t n, std::uint64_t end,
                   std::uint64_t record) const {
    if (n > end - std::min(at, end)) fail(record, fmt::format("{} bytes past its end", n));
    std::string out(n, '\0');
    in.seekg(static_cast<std::streamoff>(at));
    if (!in.read(out.data(), static_cast<std::streamsize>(n))) fail(record, "cannot be read");
    return out;
  }
  std::uint32_t u32(std::uint64_t at, std::uint64_t end, std::uint64_t record) const {
    const std::string b = read(at, 4, end, record);
    std::uint32_t v = 0;
    std::memcpy(&v, b.data(), 4);  // little endian, as the format and x86-64
    return v;
  }
  RecordHeader fields(const std::string& h, std::uint64_t record) const {
    RecordHeader out;
    for (std::size_t at = 0; at < h.size();) {
      if (h.size() - at < 4) fail(record, "a header field cut short");
      std::uint32_t n = 0;
      std::memcpy(&n, h.data() + at, 4);
      if (n > h.size() - at - 4)
        fail(record, fmt::format("a header field of {} bytes past its end", n));
      const std::string field = h.substr(at + 4, n);
      const auto eq = field.find('=');
      if (eq == std::string::npos) fail(record, "a header field without '='");
      out.fields[field.substr(0, eq)] = field.substr(eq + 1);
      at += 4 + n;
    }
    return out;
  }
  // The records in [at, end); `top`: the file's own (not a chunk's).
  void walk(std::uint64_t at, std::uint64_t end, bool top) const;
};

void BagChecker::walk(std::uint64_t at, std::uint64_t end, bool top) const {
  while (at < end) {
    const std::uint64_t record = at;
    const std::uint32_t header_len = u32(at, end, record);
    const RecordHeader h = fields(read(at + 4, header_len, end, record), record);
    const std::uint64_t data_at = at + 4 + header_len + 4;
    const std::uint32_t data_len = u32(data_at - 4, end, record);
    if (data_len > end - std::min(data_at, end))
      fail(record, fmt::format("{} bytes of data past its end", data_len));
    const std::uint64_t op = h.u("op", 1);
    if (op == 0x05 && top) {  // chunk
      const std::uint64_t unpacked = h.u("size", 4);
      const auto c = h.fields.find("compression");
      const std::string compression = c == h.fields.end() ? "(none given)" : c->second;
      if (compression == "none") {
        if (unpacked != data_len)
          fail(record, "an uncompressed chunk whose size is not its data's");
        walk(data_at, data_at + data_len, false);
      } else if ((compression != "lz4" && compression != "bz2") || unpacked > kMaxChunkBytes) {
        fail(record,
             fmt::format("a chunk compressed '{}' unpacking to {} bytes", compression, unpacked));
      }
    } else if (op == 0x04 && h.u("count", 4) * 12 != data_len) {
      fail(record, "an index whose count is not its data's");
    } else if (op == 0x06 && h.u("count", 4) * 8 != data_len) {
      fail(record, "a chunk info whose count is not its data's");
    } else if (op == 0x07) {
      (void)fields(read(data_at, data_len, end, record), record);
    } else if (op < 0x02 || op > 0x07) {
      fail(record, "no known op");
    }
    at = data_at + data_len;
  }
}

}  // namespace

void check_bag_structure(const fs::path& path) {
  BagChecker c{path, std::ifstream(path, std::ios::binary), 0};
  std::error_code ec;
  c.size = fs::file_size(path, ec);
  const std::string magic = "#ROSBAG V2.0\n";
  std::string start(magic.size(), '\0');
  if (ec || !c.in || !c.in.read(start.data(), static_cast<std::streamsize>(magic.size())) ||
      start != magic)
    throw UserError(
        fmt::format("{}: does not start with '#ROSBAG V2.0', expected a ROS 1 bag (format 2.0)",
                    path.string()));
  c.walk(magic.size(), c.size, true);
}

}  // namespace driftlab::dataset::detail
