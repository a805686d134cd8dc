// The one exception type of the client library.
#pragma once

#include <stdexcept>
#include <string>

#include "dn/protocol/messages.hpp"

namespace dn::client {

enum class ErrorKind {
  Server,     // the server answered ERROR: code(), field() and server_message() are its fields
  Transport,  // socket failure, connection closed, timeout: endpoint() names the server
  Protocol,   // the server sent bytes the client cannot decode (framing error, unexpected reply)
  Usage,      // rejected locally before anything was sent (bad URL, wrong plane size, ...)
};

const char* to_string(ErrorKind kind);
// The enumerator's name ("InvalidChannel"), as used in Error::what().
const char* code_name(protocol::ErrorCode code);

class Error : public std::runtime_error {
 public:
  // what() = "server error InvalidChannel at FRAME.planes[2]: <message>"
  static Error server(const protocol::Error& e, const std::string& endpoint = {});
  // what() = "transport error on tcp://host:1234: <message>"
  static Error transport(const std::string& endpoint, const std::string& message,
                         protocol::ErrorCode code = protocol::ErrorCode::Internal);
  // what() = "protocol error on <endpoint>: <message>"
  static Error protocol_error(const std::string& endpoint, protocol::ErrorCode code, const std::string& field,
                              const std::string& message);
  // what() = "client error InvalidChannel at FRAME.planes[1]: <message>"
  static Error usage(protocol::ErrorCode code, const std::string& field, const std::string& message);
  static Error usage(const std::string& message);

  ErrorKind kind() const { return kind_; }
  protocol::ErrorCode code() const { return code_; }
  const std::string& field() const { return field_; }
  const std::string& server_message() const { return message_; }  // the message without the prefix
  const std::string& endpoint() const { return endpoint_; }
  bool is_timeout() const { return kind_ == ErrorKind::Transport && code_ == protocol::ErrorCode::Timeout; }

 private:
  Error(ErrorKind kind, protocol::ErrorCode code, std::string field, std::string message, std::string endpoint,
        const std::string& what);
  ErrorKind kind_;
  protocol::ErrorCode code_;
  std::string field_, message_, endpoint_;
};

}  // namespace dn::client
