#include "server/idle_trim.hpp"

#include <malloc.h>
#include <unistd.h>

#include <fstream>

#include "gpu/commands.hpp"
#include "gpu/compute.hpp"
#include "gpu/context.hpp"
#include "gpu/error.hpp"
#include "gpu/transient_pool.hpp"

namespace dn::server {

void configure_allocator() {
  // glibc's default is 8 per core; measured on the idle-memory churn: 2 arenas
  // left 40 MB above the post-warm-up figure where the default left 61-75 MB.
  ::mallopt(M_ARENA_MAX, 2);
}

uint64_t resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  uint64_t size_pages = 0, resident_pages = 0;
  if (!(statm >> size_pages >> resident_pages)) return 0;
  return resident_pages * static_cast<uint64_t>(::sysconf(_SC_PAGESIZE));
}

namespace {

// A driver may free what earlier work used only at its next submission
// (lavapipe destroys a pipeline that ran work there): two empty ones, each
// waited on, the second after the first's clean-up. A lost device frees no more.
void release_deferred_frees(gpu::Context& device) {
  try {
    gpu::CommandStream stream(device);
    for (int i = 0; i < 2; ++i) {
      stream.begin();
      stream.submit_and_wait();
    }
  } catch (const gpu::VulkanError&) {
  }
}

}  // namespace

IdleTrimReport trim_idle_memory(gpu::Context& device) {
  IdleTrimReport r;
  const auto start = std::chrono::steady_clock::now();
  r.resident_before = resident_bytes();
  r.transient_bytes = gpu::TransientPool::of(device).trim(gpu::TransientPool::Clock::duration::zero());
  r.kernels = device.kernels().drop_unused();
  release_deferred_frees(device);
  // Free pages of every arena, not only the top of the main heap.
  ::malloc_trim(0);
  r.resident_after = resident_bytes();
  r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return r;
}

bool IdleTrimSchedule::due(const std::vector<uint64_t>& activity, bool busy, Clock::time_point now) {
  if (busy || activity != last_activity_) {
    last_activity_ = activity;
    quiet_since_ = now;
    trimmed_ = false;
    return false;
  }
  if (!enabled_ || trimmed_ || now - quiet_since_ < delay_) return false;
  trimmed_ = true;
  return true;
}

}  // namespace dn::server
