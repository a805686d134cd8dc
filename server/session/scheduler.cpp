#include "server/session/scheduler.hpp"

namespace dn::server {

Scheduler::Scheduler(unsigned workers, RunJob run) : run_(std::move(run)) {
  for (unsigned i = 0; i < workers; ++i) threads_.emplace_back([this] { worker_loop(); });
}

Scheduler::~Scheduler() { stop(); }

void Scheduler::submit(const std::shared_ptr<Session>& session, FrameJob&& job) {
  std::lock_guard lock(mutex_);
  auto [it, added] = queues_.try_emplace(session->id());
  it->second.pending.push_back(std::move(job));
  if (!added) return;  // waiting for a worker or running: its worker takes the next frame
  it->second.session = session;
  ready_.push_back(session->id());
  ready_cv_.notify_one();
}

void Scheduler::cancel(const Session& session) {
  std::lock_guard lock(mutex_);
  auto it = queues_.find(session.id());
  if (it == queues_.end()) return;
  it->second.cancelled = true;
  it->second.pending.clear();
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
  std::unique_lock lock(mutex_);
  for (;;) {
    ready_cv_.wait(lock, [this] { return stopping_ || !ready_.empty(); });
    if (ready_.empty()) return;  // stopping and nothing left
    const uint64_t id = ready_.front();
    ready_.pop_front();
    Queue& queue = queues_.at(id);
    if (queue.cancelled || queue.pending.empty()) {
      queues_.erase(id);
      continue;
    }
    FrameJob job = std::move(queue.pending.front());
    queue.pending.pop_front();
    std::shared_ptr<Session> session = queue.session;
    lock.unlock();
    // Handed over before the session can be picked up again, so results stay in order.
    run_(*session, job);
    lock.lock();
    Queue& after = queues_.at(id);
    if (after.cancelled || after.pending.empty()) {
      queues_.erase(id);
    } else {
      ready_.push_back(id);
      ready_cv_.notify_one();
    }
  }
}

}  // namespace dn::server
