#include "server/session/scheduler.hpp"

namespace dn::server {

Scheduler::Scheduler(unsigned workers, std::function<void(FrameDone&&)> on_done) : on_done_(std::move(on_done)) {
  for (unsigned i = 0; i < workers; ++i) threads_.emplace_back([this] { worker_loop(); });
}

Scheduler::~Scheduler() { stop(); }

void Scheduler::submit(const std::shared_ptr<Session>& session, FrameJob&& job) {
  bool enqueue = false;
  {
    std::lock_guard lock(session->mutex);
    session->pending.push_back(std::move(job));
    if (!session->scheduled) {
      session->scheduled = true;
      enqueue = true;
    }
  }
  if (enqueue) {
    std::lock_guard lock(mutex_);
    ready_.push_back(session);
    ready_cv_.notify_one();
  }
}

void Scheduler::cancel(const std::shared_ptr<Session>& session) {
  session->cancelled = true;
  std::lock_guard lock(session->mutex);
  session->pending.clear();
}

void Scheduler::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ && threads_.empty()) return;
    stopping_ = true;
  }
  ready_cv_.notify_all();
  for (auto& t : threads_) t.join();
  threads_.clear();
}

void Scheduler::worker_loop() {
  for (;;) {
    std::shared_ptr<Session> session;
    {
      std::unique_lock lock(mutex_);
      ready_cv_.wait(lock, [this] { return stopping_ || !ready_.empty(); });
      if (ready_.empty()) return;  // stopping and nothing left
      session = std::move(ready_.front());
      ready_.pop_front();
    }
    FrameJob job;
    bool have_job = false;
    {
      std::lock_guard lock(session->mutex);
      if (!session->pending.empty() && !session->cancelled) {
        job = std::move(session->pending.front());
        session->pending.pop_front();
        have_job = true;
      }
    }
    // Report before the session can be picked up again, so results stay in order.
    if (have_job) on_done_(session->run(job));
    bool requeue = false;
    {
      std::lock_guard lock(session->mutex);
      if (!session->pending.empty() && !session->cancelled) {
        requeue = true;
      } else {
        session->scheduled = false;
      }
    }
    if (requeue) {
      std::lock_guard lock(mutex_);
      ready_.push_back(std::move(session));
      ready_cv_.notify_one();
    }
  }
}

}  // namespace dn::server
