// What an idle server gives back (docs/server.md, "Memory an idle server
// keeps"). Memory a server freed does not leave the process by itself: glibc
// keeps freed chunks in its per-thread arenas, the transient pool keeps free
// scratch for the next frame, and the kernel cache keeps every kernel it ever
// compiled. Once the server has been quiet for a while, all three let go.
#pragma once

#include <chrono>
#include <cstdint>
#include <vector>

namespace dn::gpu {
class Context;
}

namespace dn::server {

// Process-wide allocator settings, before any thread exists (main): few
// malloc arenas, so memory freed by one thread is found by the next
// allocation of another and malloc_trim has less scattered to give back.
void configure_allocator();

// Resident bytes of this process (/proc/self/statm), 0 where unknown.
uint64_t resident_bytes();

struct IdleTrimReport {
  uint64_t transient_bytes = 0;  // free scratch buffers of the transient pool destroyed
  size_t kernels = 0;            // compiled kernels destroyed: outside the kept set, held by no pipeline
  uint64_t resident_before = 0;
  uint64_t resident_after = 0;
  double ms = 0.0;
};

// Gives back what no session holds: the transient pool's free buffers, the
// kernels KernelCache::drop_unused() lets go (and what the driver keeps of
// them until its next submission), and the allocator's free pages
// (malloc_trim). Safe while sessions are open; nothing they hold is touched.
IdleTrimReport trim_idle_memory(gpu::Context& device);

// When to trim: once per quiet period, after `delay` with no activity and no
// work in progress. Activity is any change of a few counters the server
// passes in (frames, sessions, connections); the next change re-arms it.
class IdleTrimSchedule {
 public:
  using Clock = std::chrono::steady_clock;
  explicit IdleTrimSchedule(double delay_s) : delay_(std::chrono::duration<double>(delay_s)), enabled_(delay_s > 0) {}
  bool due(const std::vector<uint64_t>& activity, bool busy, Clock::time_point now);

 private:
  std::chrono::duration<double> delay_;
  bool enabled_;
  std::vector<uint64_t> last_activity_;
  Clock::time_point quiet_since_ = Clock::now();
  bool trimmed_ = false;
};

}  // namespace dn::server
