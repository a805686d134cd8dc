#include "gpu/transient_pool.hpp"

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <string>
#include <utility>

#include "gpu/context.hpp"
#include "gpu/error.hpp"

namespace dn::gpu {

TransientPool::TransientPool(Context& context, TransientPoolOptions options)
    : context_(context), options_(options) {
  if (options_.granularity == 0) options_.granularity = 1;
  if (options_.max_slack < 1.0) options_.max_slack = 1.0;
}

TransientPool::~TransientPool() {
  // A lease outliving the pool would return into freed memory; say so loudly.
  if (stats_.buffers_in_use > 0)
    std::fprintf(stderr, "dn::gpu::TransientPool destroyed with %u buffers still leased\n", stats_.buffers_in_use);
}

TransientPool& TransientPool::of(Context& context) {
  return context.shared<TransientPool>([&] { return std::make_unique<TransientPool>(context); });
}

uint64_t TransientPool::rounded(uint64_t size) const {
  return (size + options_.granularity - 1) / options_.granularity * options_.granularity;
}

bool TransientPool::fits(const Entry& e, uint64_t size) const {
  const uint64_t have = e.buffer.size();
  return !e.leased && have >= size && static_cast<double>(have) <= options_.max_slack * static_cast<double>(size);
}

TransientPool::Lease TransientPool::lease(std::span<const uint64_t> sizes, std::span<const uint64_t> preferred) {
  std::vector<uint64_t> want(sizes.size());
  for (size_t i = 0; i < sizes.size(); ++i) {
    if (sizes[i] == 0) throw Error("transient pool: lease of size 0");
    want[i] = rounded(sizes[i]);
  }
  Lease lease;
  lease.pool_ = this;
  lease.entries_.assign(sizes.size(), nullptr);
  lease.requested_ = std::accumulate(sizes.begin(), sizes.end(), uint64_t{0});
  std::vector<size_t> missing;
  {
    std::lock_guard lock(mutex_);
    auto take = [&](size_t i, Entry* e) {
      e->leased = true;
      lease.entries_[i] = e;
      ++stats_.reused;
      ++stats_.buffers_in_use;
      stats_.in_use_bytes += e->buffer.size();
    };
    // The buffers the caller held last time, when they still fit.
    for (size_t i = 0; i < preferred.size() && i < want.size(); ++i)
      for (auto& e : entries_)
        if (e->id == preferred[i] && fits(*e, want[i])) {
          take(i, e.get());
          break;
        }
    // Then best fit, largest sizes first so a small slot cannot take the
    // only buffer a large one fits.
    std::vector<size_t> order(want.size());
    std::iota(order.begin(), order.end(), size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return want[a] > want[b]; });
    for (size_t i : order) {
      if (lease.entries_[i]) continue;
      Entry* best = nullptr;
      for (auto& e : entries_)
        if (fits(*e, want[i]) && (!best || e->buffer.size() < best->buffer.size())) best = e.get();
      if (best)
        take(i, best);
      else
        missing.push_back(i);
    }
    stats_.requested_bytes += lease.requested_;
  }
  // New buffers are allocated outside the lock: other sessions keep leasing.
  // If one fails, the lease's destructor returns what was taken (null slots
  // are skipped) and the fresh buffers are freed.
  std::vector<std::unique_ptr<Entry>> fresh;
  for (size_t i : missing) {
    auto e = std::make_unique<Entry>();
    e->leased = true;
    e->buffer = Buffer(context_, want[i], BufferKind::Storage, "transient");
    fresh.push_back(std::move(e));
  }
  std::lock_guard lock(mutex_);
  for (size_t k = 0; k < missing.size(); ++k) {
    Entry* e = fresh[k].get();
    e->id = next_id_++;
    lease.entries_[missing[k]] = e;
    ++stats_.created;
    ++stats_.buffers;
    ++stats_.buffers_in_use;
    stats_.allocated_bytes += e->buffer.size();
    stats_.in_use_bytes += e->buffer.size();
    entries_.push_back(std::move(fresh[k]));
  }
  return lease;
}

void TransientPool::give_back(std::span<Entry* const> entries, uint64_t requested) noexcept {
  const auto now = Clock::now();
  std::lock_guard lock(mutex_);
  for (Entry* e : entries) {
    if (!e) continue;
    e->leased = false;
    e->returned = now;
    --stats_.buffers_in_use;
    stats_.in_use_bytes -= e->buffer.size();
  }
  stats_.requested_bytes -= requested;
}

TransientPoolStats TransientPool::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

uint64_t TransientPool::trim(Clock::duration idle, Clock::time_point now) {
  std::vector<std::unique_ptr<Entry>> doomed;  // freed after the lock is released
  uint64_t freed = 0;
  {
    std::lock_guard lock(mutex_);
    auto idle_from = std::stable_partition(entries_.begin(), entries_.end(),
                                           [&](const auto& e) { return e->leased || now - e->returned < idle; });
    for (auto it = idle_from; it != entries_.end(); ++it) {
      freed += (*it)->buffer.size();
      doomed.push_back(std::move(*it));
    }
    entries_.erase(idle_from, entries_.end());
    stats_.buffers -= static_cast<uint32_t>(doomed.size());
    stats_.allocated_bytes -= freed;
    stats_.trimmed_bytes += freed;
  }
  return freed;
}

TransientPool::Lease::Lease(Lease&& other) noexcept
    : pool_(std::exchange(other.pool_, nullptr)),
      entries_(std::move(other.entries_)),
      requested_(std::exchange(other.requested_, 0)) {
  other.entries_.clear();
}

TransientPool::Lease& TransientPool::Lease::operator=(Lease&& other) noexcept {
  if (this != &other) {
    release();
    pool_ = std::exchange(other.pool_, nullptr);
    entries_ = std::move(other.entries_);
    other.entries_.clear();
    requested_ = std::exchange(other.requested_, 0);
  }
  return *this;
}

const Buffer& TransientPool::Lease::buffer(size_t i) const {
  if (i >= entries_.size() || !entries_[i]) throw Error("transient lease: no buffer " + std::to_string(i));
  return entries_[i]->buffer;
}

uint64_t TransientPool::Lease::id(size_t i) const {
  if (i >= entries_.size() || !entries_[i]) throw Error("transient lease: no buffer " + std::to_string(i));
  return entries_[i]->id;
}

std::vector<uint64_t> TransientPool::Lease::ids() const {
  std::vector<uint64_t> out;
  for (size_t i = 0; i < entries_.size(); ++i) out.push_back(id(i));
  return out;
}

void TransientPool::Lease::release() noexcept {
  if (pool_) pool_->give_back(entries_, requested_);
  pool_ = nullptr;
  entries_.clear();
  requested_ = 0;
}

}  // namespace dn::gpu
