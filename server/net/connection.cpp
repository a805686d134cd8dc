#include "server/net/connection.hpp"

#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

namespace dn::server::net {

Connection::Connection(int fd, uint64_t id, bool is_unix, std::string peer, uint64_t max_message_bytes,
                       ReceiveBudget* budget)
    : fd_(fd), id_(id), is_unix_(is_unix), peer_(std::move(peer)), reader_(max_message_bytes), budget_(budget) {
  if (!budget_) return;
  reader_.set_admission([this](const protocol::Header& h) {
    if (h.payload_length <= kBudgetedBytes) return true;
    if (budget_->in_use + h.payload_length > budget_->limit) return false;
    budget_->in_use += h.payload_length;
    budget_held_ = h.payload_length;
    return true;
  });
}

Connection::~Connection() {
  release_budget();
  if (fd_ >= 0) ::close(fd_);
}

void Connection::set_reading_paused(bool paused) {
  if (paused == reading_paused_) return;
  const Clock::time_point now = Clock::now();
  if (paused) paused_since_ = now;
  else message_started_ += now - paused_since_;
  reading_paused_ = paused;
}

void Connection::release_budget() {
  if (budget_ && budget_held_) budget_->in_use -= budget_held_;
  budget_held_ = 0;
}

Connection::ReadStatus Connection::read_available(const MessageHandler& handler, size_t budget) {
  size_t consumed = 0;
  while (!reading_paused_ && !close_after_flush && consumed < budget) {
    std::span<uint8_t> target = reader_.writable();
    ssize_t n = ::recv(fd_, target.data(), target.size(), 0);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) return ReadStatus::Open;
      return ReadStatus::Closed;
    }
    if (n == 0) return ReadStatus::Closed;
    if (reader_.bytes_buffered() == 0) message_started_ = Clock::now();
    consumed += static_cast<size_t>(n);
    bytes_in += static_cast<uint64_t>(n);
    last_received = Clock::now();
    switch (reader_.commit(static_cast<size_t>(n))) {
      case protocol::MessageReader::Status::NeedMore:
        break;
      case protocol::MessageReader::Status::Failed:
        return ReadStatus::Failed;
      case protocol::MessageReader::Status::Ready: {
        protocol::Header header = reader_.header();
        const bool refused = reader_.refused();
        release_budget();
        handler(header, reader_.take_payload(), refused);
        break;
      }
    }
  }
  return ReadStatus::Open;
}

Connection::ReadStatus Connection::read_proxy_header() {
  while (proxy_pending_) {
    proxy_ = parse_proxy_header(proxy_bytes_);
    if (proxy_.status == ProxyParse::Status::Error) return ReadStatus::Failed;
    if (proxy_.status == ProxyParse::Status::Complete) {
      proxy_pending_ = false;
      proxy_bytes_ = {};
      break;
    }
    const size_t have = proxy_bytes_.size();
    proxy_bytes_.resize(proxy_.need);
    ssize_t n = ::recv(fd_, proxy_bytes_.data() + have, proxy_.need - have, 0);
    proxy_bytes_.resize(have + static_cast<size_t>(std::max<ssize_t>(n, 0)));
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) return ReadStatus::Open;
      return ReadStatus::Closed;
    }
    if (n == 0) return ReadStatus::Closed;
    bytes_in += static_cast<uint64_t>(n);
    last_received = Clock::now();
  }
  return ReadStatus::Open;
}

void Connection::queue(Bytes bytes, uint64_t watch_session) {
  if (watch_session != 0) {
    for (Outgoing& o : out_) {
      if (o.watch_session == watch_session && o.offset == 0) {
        queued_bytes_ = queued_bytes_ - o.bytes->size() + bytes->size();
        o.bytes = std::move(bytes);
        return;
      }
    }
  }
  if (out_.empty()) last_write_progress_ = Clock::now();
  queued_bytes_ += bytes->size();
  out_.push_back(Outgoing{std::move(bytes), 0, watch_session});
}

bool Connection::flush() {
  while (!out_.empty()) {
    iovec iov[16];
    int count = 0;
    for (auto it = out_.begin(); it != out_.end() && count < 16; ++it, ++count) {
      iov[count].iov_base = const_cast<uint8_t*>(it->bytes->data() + it->offset);
      iov[count].iov_len = it->bytes->size() - it->offset;
    }
    msghdr msg{};
    msg.msg_iov = iov;
    msg.msg_iovlen = static_cast<size_t>(count);
    ssize_t n = ::sendmsg(fd_, &msg, MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) return true;
      return false;
    }
    size_t written = static_cast<size_t>(n);
    if (written > 0) last_write_progress_ = Clock::now();
    bytes_out += written;
    queued_bytes_ -= written;
    while (written > 0) {
      Outgoing& front = out_.front();
      size_t left = front.bytes->size() - front.offset;
      if (written >= left) {
        written -= left;
        out_.pop_front();
      } else {
        front.offset += written;
        written = 0;
      }
    }
  }
  return true;
}

}  // namespace dn::server::net
