// A thin epoll wrapper: register fds with a callback, wait, dispatch; plus an
// eventfd so other threads can wake the loop.
#pragma once

#include <cstdint>
#include <functional>
#include <unordered_map>

namespace dn::server::net {

class EventLoop {
 public:
  using Callback = std::function<void(uint32_t events)>;

  EventLoop();
  ~EventLoop();
  EventLoop(const EventLoop&) = delete;
  EventLoop& operator=(const EventLoop&) = delete;

  void add(int fd, uint32_t events, Callback callback);
  void modify(int fd, uint32_t events);
  void remove(int fd);

  // Waits up to timeout_ms (-1 = forever) and runs the callbacks of ready fds.
  void run_once(int timeout_ms);

  // Thread-safe: makes a blocked run_once() return and calls the wake handler.
  void wake();
  void set_wake_handler(std::function<void()> handler) { on_wake_ = std::move(handler); }

 private:
  int epoll_fd_ = -1;
  int wake_fd_ = -1;
  std::function<void()> on_wake_;
  // The generation guards against an fd closed and reused within one batch of events.
  struct Entry {
    uint32_t generation;
    Callback callback;
  };
  uint32_t next_generation_ = 1;
  std::unordered_map<int, Entry> callbacks_;
};

}  // namespace dn::server::net
