#include "watch_queues.hpp"

namespace dn::client::detail {

void WatchQueues::add(uint64_t attach_request_id, uint64_t session_id) {
  queues_[attach_request_id].session_id = session_id;
}

void WatchQueues::remove(uint64_t attach_request_id) { queues_.erase(attach_request_id); }

WatchQueue* WatchQueues::find(uint64_t attach_request_id) {
  auto it = queues_.find(attach_request_id);
  return it == queues_.end() ? nullptr : &it->second;
}

bool WatchQueues::route(Incoming& in) {
  if (auto it = queues_.find(in.header.request_id); it != queues_.end()) {
    it->second.items.push_back(std::move(in));
    return true;
  }
  uint64_t session_id = 0;
  if (auto* r = std::get_if<protocol::Result>(&in.message))
    session_id = r->session_id;
  else if (auto* c = std::get_if<protocol::SessionClosed>(&in.message))
    session_id = c->session_id;
  else
    return false;
  for (auto& [attach_id, q] : queues_)
    if (q.session_id == session_id) {
      q.items.push_back(std::move(in));
      return true;
    }
  return false;
}

}  // namespace dn::client::detail
