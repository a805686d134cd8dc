// Device worker threads. A session is run by at most one worker at a time,
// so its frames reach the device strictly in order; different sessions run
// in parallel. Completed frames go back through a callback.
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "server/session/session.hpp"

namespace dn::server {

class Scheduler {
 public:
  // on_done runs on a worker thread; it must only hand the result over.
  Scheduler(unsigned workers, std::function<void(FrameDone&&)> on_done);
  ~Scheduler();

  void submit(const std::shared_ptr<Session>& session, FrameJob&& job);
  // Drops frames not yet started; a frame on the device finishes.
  void cancel(const std::shared_ptr<Session>& session);
  void stop();

 private:
  void worker_loop();

  std::function<void(FrameDone&&)> on_done_;
  std::mutex mutex_;
  std::condition_variable ready_cv_;
  std::deque<std::shared_ptr<Session>> ready_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace dn::server
