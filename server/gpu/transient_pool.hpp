// Transient scratch pooled per device: device-local storage buffers that a
// session leases for one frame (intermediates no later frame reads: à-trous
// ping-pong, prefilters, pyramid levels) and returns after its submission
// has completed, so sessions that do not run at the same moment share the
// same memory instead of each holding its own.
//
// A lease of N sizes returns N distinct buffers, each at least its size:
// first the buffers the caller held last time when they are free and fit
// (so a session's descriptor sets usually stay valid), then the best fit
// among the free ones (the smallest that fits, at most max_slack times the
// size, so a small session does not take a large one's buffers), else new
// ones. The pool never waits for the device: returning a lease says that
// the work using it is finished. Thread-safe. Buffers free for a while are
// destroyed by trim().
//
// A pipeline per frame: lease(sizes, last ids) -> if ids() differ from last
// frame's, DescriptorPool::write() the sets that bind them -> record, submit,
// wait -> release(). Contents are undefined when leased (another session
// wrote them): every pass writes what it later reads in the same frame.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include "gpu/buffer.hpp"

namespace dn::gpu {

class Context;

struct TransientPoolOptions {
  uint64_t granularity = 256;  // sizes are rounded up to a multiple of this
  double max_slack = 2.0;      // a free buffer serves a size only if at most this many times larger
};

struct TransientPoolStats {
  uint64_t allocated_bytes = 0;  // every buffer the pool holds
  uint64_t in_use_bytes = 0;     // buffers leased now (their full sizes)
  uint64_t requested_bytes = 0;  // what the outstanding leases asked for
  uint32_t buffers = 0;
  uint32_t buffers_in_use = 0;
  uint64_t created = 0;          // buffers allocated so far
  uint64_t reused = 0;           // lease slots served by a returned buffer
  uint64_t trimmed_bytes = 0;    // freed by trim() so far
};

class TransientPool {
  struct Entry;

 public:
  using Clock = std::chrono::steady_clock;

  explicit TransientPool(Context& context, TransientPoolOptions options = {});
  // Every lease must have been returned (leases must not outlive the pool).
  ~TransientPool();
  TransientPool(const TransientPool&) = delete;
  TransientPool& operator=(const TransientPool&) = delete;

  // The context's pool (one per device, made on first use; Context::shared).
  static TransientPool& of(Context& context);

  // Buffers held for one frame; returned on destruction or release().
  class Lease {
   public:
    Lease() = default;
    ~Lease() { release(); }
    Lease(Lease&& other) noexcept;
    Lease& operator=(Lease&& other) noexcept;
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;

    size_t size() const { return entries_.size(); }
    bool empty() const { return entries_.empty(); }
    // Buffer i: a Storage buffer of at least the i-th size asked for.
    const Buffer& buffer(size_t i) const;
    VkBuffer handle(size_t i) const { return buffer(i).handle(); }
    // Unique per pooled buffer for the pool's lifetime (VkBuffer handles may
    // repeat after a trim): what a caller compares to know whether its
    // descriptor sets still point at the buffers it holds, and passes back
    // as `preferred` next frame.
    uint64_t id(size_t i) const;
    std::vector<uint64_t> ids() const;
    // Returns the buffers now. Only after the work using them has completed.
    void release() noexcept;

   private:
    friend class TransientPool;
    TransientPool* pool_ = nullptr;
    std::vector<Entry*> entries_;
    uint64_t requested_ = 0;
  };

  // Leases buffers of at least `sizes` bytes (each > 0). preferred[i]: the
  // id the caller held for slot i last time (Lease::ids()), taken again when
  // free and fitting. Throws VulkanError when a new buffer cannot be
  // allocated (nothing stays leased then).
  Lease lease(std::span<const uint64_t> sizes, std::span<const uint64_t> preferred = {});

  TransientPoolStats stats() const;

  // Destroys the free buffers returned longer than `idle` before `now`;
  // returns the bytes freed. Cheap: a server may call it after every frame.
  uint64_t trim(Clock::duration idle, Clock::time_point now = Clock::now());

 private:
  struct Entry {
    uint64_t id = 0;
    Buffer buffer;
    bool leased = false;
    Clock::time_point returned{};
  };
  void give_back(std::span<Entry* const> entries, uint64_t requested) noexcept;
  uint64_t rounded(uint64_t size) const;
  bool fits(const Entry& e, uint64_t size) const;

  Context& context_;
  TransientPoolOptions options_;
  mutable std::mutex mutex_;
  std::vector<std::unique_ptr<Entry>> entries_;
  uint64_t next_id_ = 1;
  TransientPoolStats stats_;
};

}  // namespace dn::gpu
