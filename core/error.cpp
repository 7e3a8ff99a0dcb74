#include "core/error.hpp"

namespace driftlab::detail {

void throw_internal(const char* condition, const char* file, int line, const std::string& message) {
  std::string what = std::string("internal error: ") + file + ":" + std::to_string(line) +
                     ": check failed: " + condition;
  if (!message.empty()) what += ": " + message;
  throw InternalError(what);
}

}  // namespace driftlab::detail
