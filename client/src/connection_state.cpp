// ConnectionState's lifetime and failure handling: once broken, every later
// call throws the same Error.
#include "connection_state.hpp"

#include <unistd.h>

namespace dn::client::detail {

ConnectionState::ConnectionState(Endpoint endpoint, const ConnectOptions& options)
    : endpoint_(std::move(endpoint)),
      endpoint_str_(endpoint_.to_string()),
      connect_timeout_(options.connect_timeout),
      io_timeout_(options.io_timeout),
      buffer_bytes_(options.socket_buffer_bytes),
      max_message_bytes_(options.max_message_bytes ? options.max_message_bytes : (uint64_t{1} << 32)),
      reader_(max_message_bytes_) {}

ConnectionState::~ConnectionState() { close(); }

void ConnectionState::close() {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
  if (!broken_) {
    broken_ = true;
    failure_ = Error::transport(endpoint_str_, "connection closed by the client");
  }
}

void ConnectionState::check_usable() const {
  if (broken_) {
    if (failure_) throw *failure_;
    throw Error::transport(endpoint_str_, "connection is closed");
  }
}

Error ConnectionState::transport_error(const std::string& message, protocol::ErrorCode code) const {
  std::string m = message;
  if (const auto& last = demux_.last_unsolicited_error()) {
    m += " (last server error: " + std::string(code_name(last->code));
    if (!last->field.empty()) m += " at " + last->field;
    m += ": " + last->message + ")";
  }
  return Error::transport(endpoint_str_, m, code);
}

void ConnectionState::mark_failed(Error e) {
  // After a timeout the stream may be mid-message: the connection is unusable either way.
  if (!broken_) {
    broken_ = true;
    failure_ = std::move(e);
  }
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

void ConnectionState::fail_transport(const std::string& message, protocol::ErrorCode code) {
  mark_failed(transport_error(message, code));
  throw *failure_;
}

void ConnectionState::fail_protocol(const protocol::DecodeError& d) {
  mark_failed(Error::protocol_error(endpoint_str_, d.code, d.field, d.message));
  throw *failure_;
}

Clock::time_point ConnectionState::deadline_from(std::optional<Milliseconds> timeout, bool& has_deadline) const {
  const Milliseconds t = timeout ? *timeout : io_timeout_;
  has_deadline = timeout.has_value() || io_timeout_.count() > 0;
  return Clock::now() + t;
}

}  // namespace dn::client::detail
