// Error tiers (docs/design.md "Style"): UserError for bad user input (a scenario, an
// asset, a trajectory file), InternalError for states that must never happen.
// Library code throws; only app/ turns an exception into an exit code.
#pragma once

#include <stdexcept>
#include <string>

namespace driftlab {

/// Bad input from the user. The message names the file, line (where known),
/// field, the offending value and what was expected.
class UserError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An invariant was violated: a bug in driftlab, not the user's fault.
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

namespace detail {
[[noreturn]] void throw_internal(const char* condition, const char* file, int line,
                                 const std::string& message);
}  // namespace detail

}  // namespace driftlab

/// Always-on check for impossible states (Drake's DRAKE_DEMAND). Throws InternalError.
#define DRIFTLAB_DEMAND(condition)                                                            \
  do {                                                                                        \
    if (!(condition)) ::driftlab::detail::throw_internal(#condition, __FILE__, __LINE__, ""); \
  } while (0)

/// Always-on check with a message.
#define DRIFTLAB_DEMAND_MSG(condition, message)                                                    \
  do {                                                                                             \
    if (!(condition)) ::driftlab::detail::throw_internal(#condition, __FILE__, __LINE__, message); \
  } while (0)

/// Debug-only invariant (Drake's DRAKE_ASSERT); compiled out under NDEBUG.
#ifdef NDEBUG
#define DRIFTLAB_ASSERT(condition) ((void)0)
#else
#define DRIFTLAB_ASSERT(condition) DRIFTLAB_DEMAND(condition)
#endif
