#include "gpu/limits.hpp"

#include <mutex>

namespace dn::gpu {
namespace {
std::mutex g_mutex;
DeviceLimits g_limits;
}  // namespace

DeviceLimits current_device_limits() {
  std::lock_guard lock(g_mutex);
  return g_limits;
}

void publish_device_limits(const DeviceLimits& limits) {
  std::lock_guard lock(g_mutex);
  g_limits = limits;
}

}  // namespace dn::gpu
