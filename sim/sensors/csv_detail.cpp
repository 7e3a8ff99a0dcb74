#include "sim/sensors/csv_detail.hpp"

#include <fmt/format.h>

#include "core/error.hpp"

namespace driftlab::sim::csv_detail {

StampedRows::StampedRows(const std::filesystem::path& path, std::string_view header,
                         std::string sensor)
    : file_(path), sensor_(std::move(sensor)) {
  file_.write(header);
}

std::string* StampedRows::begin_row(TimeNs t_ns) {
  DRIFTLAB_DEMAND_MSG(!any_ || t_ns > last_ns_,
                      fmt::format("{} time stamps do not increase at t = {} ns", sensor_, t_ns));
  any_ = true;
  last_ns_ = t_ns;
  line_.clear();
  append_int(&line_, t_ns);
  return &line_;
}

void StampedRows::end_row() {
  line_ += '\n';
  file_.write(line_);
}

}  // namespace driftlab::sim::csv_detail
