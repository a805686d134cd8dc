// Device worker threads and the queues of frames waiting for them. A session
// is run by at most one worker at a time, so its frames reach the device
// strictly in order; different sessions run in parallel.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <vector>

#include "server/session/session.hpp"

namespace dn::server {

class Scheduler {
 public:
  // run(session, job) runs one frame on a worker thread: its device work, its
  // replies' encoding and handing them over.
  using RunJob = std::function<void(Session&, FrameJob&)>;
  Scheduler(unsigned workers, RunJob run);
  ~Scheduler();

  void submit(const std::shared_ptr<Session>& session, FrameJob&& job);
  // Drops the session's frames not yet started; a frame on the device finishes.
  void cancel(const Session& session);
  void stop();

 private:
  // A session with frames queued or running; removed once it has neither.
  struct Queue {
    std::shared_ptr<Session> session;
    std::deque<FrameJob> pending;
    bool cancelled = false;
  };
  void worker_loop();

  RunJob run_;
  std::mutex mutex_;  // guards everything below
  std::condition_variable ready_cv_;
  std::unordered_map<uint64_t, Queue> queues_;  // by session id
  std::deque<uint64_t> ready_;                  // sessions waiting for a worker, in turn
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace dn::server
