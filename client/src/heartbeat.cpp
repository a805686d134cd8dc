// The server's heartbeat: a PING with request_id 0 is answered with PONG as
// soon as no other message is partly written, and goes no further.
#include <poll.h>
#include <sys/socket.h>

#include <cerrno>

#include "connection_state.hpp"

namespace dn::client::detail {

bool ConnectionState::take_heartbeat(const Incoming& in) {
  const auto* ping = std::get_if<protocol::Ping>(&in.message);
  if (!ping || in.header.request_id != 0) return false;
  pong_due_ = ping->payload;
  send_pong_if_due();
  return true;
}

void ConnectionState::send_pong_if_due() {
  if (!pong_due_ || sending_ || broken_) return;
  const std::vector<uint8_t> bytes = protocol::encode(protocol::Pong{*pong_due_}, 0, 0);
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      done += size_t(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else if (done == 0) {
      return;  // socket full or failing: answer later, or let the next call report the failure
    } else {
      pollfd p{fd_, POLLOUT, 0};  // 32 bytes partly out: finish them before anything else
      ::poll(&p, 1, 1000);
    }
  }
  pong_due_.reset();
}

}  // namespace dn::client::detail
