#include "demux.hpp"

namespace dn::client::detail {

void Demultiplexer::expect(uint64_t request_id, protocol::MessageType sent) {
  pending_[request_id] = Pending{sent, std::nullopt};
}

bool Demultiplexer::awaiting(uint64_t request_id) const { return pending_.count(request_id) != 0; }

bool Demultiplexer::reply_ready(uint64_t request_id) const {
  auto it = pending_.find(request_id);
  return it != pending_.end() && it->second.reply.has_value();
}

const Incoming* Demultiplexer::peek(uint64_t request_id) const {
  auto it = pending_.find(request_id);
  return it != pending_.end() && it->second.reply ? &*it->second.reply : nullptr;
}

std::optional<Incoming> Demultiplexer::take(uint64_t request_id) {
  auto it = pending_.find(request_id);
  if (it == pending_.end() || !it->second.reply) return std::nullopt;
  Incoming in = std::move(*it->second.reply);
  pending_.erase(it);
  return in;
}

void Demultiplexer::forget(uint64_t request_id) { pending_.erase(request_id); }

std::string Demultiplexer::waiting_for(uint64_t request_id) const {
  auto it = pending_.find(request_id);
  if (it == pending_.end()) return "request " + std::to_string(request_id);
  return std::string(protocol::to_string(it->second.sent)) + " (request " + std::to_string(request_id) + ")";
}

void Demultiplexer::route(Incoming&& in) {
  if (auto it = pending_.find(in.header.request_id); it != pending_.end() && !it->second.reply) {
    it->second.reply = std::move(in);
    return;
  }
  if (watches_.route(in)) return;
  // Not the answer to anything we wait for (request_id 0, or a request we
  // forgot): remember it, so a following hang-up can say why.
  if (auto* e = std::get_if<protocol::Error>(&in.message)) last_unsolicited_error_ = *e;
  // Replies to forgotten requests (closed sessions) are dropped here.
}

}  // namespace dn::client::detail
