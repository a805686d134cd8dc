// Internal: small helpers for poll()-based waits with deadlines. Not installed.
#pragma once

#include <cstring>
#include <string>

#include "incoming.hpp"

namespace dn::client::detail {

inline std::string errno_text(int err) { return std::strerror(err); }

// Milliseconds left until `deadline`, as poll() takes them (0 when past).
inline int remaining_ms(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
  if (left <= 0) return 0;
  return left > 1'000'000'000 ? 1'000'000'000 : int(left);
}

}  // namespace dn::client::detail
