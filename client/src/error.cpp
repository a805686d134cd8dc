#include "dn/client/error.hpp"

namespace dn::client {

const char* to_string(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::Server: return "server";
    case ErrorKind::Transport: return "transport";
    case ErrorKind::Protocol: return "protocol";
    case ErrorKind::Usage: return "usage";
  }
  return "?";
}

const char* code_name(protocol::ErrorCode code) {
  using C = protocol::ErrorCode;
  switch (code) {
    case C::BadMagic: return "BadMagic";
    case C::UnsupportedVersion: return "UnsupportedVersion";
    case C::ReservedFlags: return "ReservedFlags";
    case C::MessageTooLarge: return "MessageTooLarge";
    case C::UnknownMessageType: return "UnknownMessageType";
    case C::Malformed: return "Malformed";
    case C::Unauthenticated: return "Unauthenticated";
    case C::NotReady: return "NotReady";
    case C::UnknownSession: return "UnknownSession";
    case C::UnknownPipeline: return "UnknownPipeline";
    case C::InvalidParameter: return "InvalidParameter";
    case C::InvalidChannel: return "InvalidChannel";
    case C::MissingChannel: return "MissingChannel";
    case C::LimitExceeded: return "LimitExceeded";
    case C::OutOfOrder: return "OutOfOrder";
    case C::DeviceError: return "DeviceError";
    case C::ShuttingDown: return "ShuttingDown";
    case C::Timeout: return "Timeout";
    case C::Internal: return "Internal";
  }
  return "UnknownErrorCode";
}

Error::Error(ErrorKind kind, protocol::ErrorCode code, std::string field, std::string message, std::string endpoint,
             const std::string& what)
    : std::runtime_error(what),
      kind_(kind),
      code_(code),
      field_(std::move(field)),
      message_(std::move(message)),
      endpoint_(std::move(endpoint)) {}

namespace {
std::string coded(const char* prefix, protocol::ErrorCode code, const std::string& field, const std::string& message) {
  std::string w = std::string(prefix) + " " + code_name(code);
  if (!field.empty()) w += " at " + field;
  w += ": " + message;
  return w;
}
}  // namespace

Error Error::server(const protocol::Error& e, const std::string& endpoint) {
  return Error(ErrorKind::Server, e.code, e.field, e.message, endpoint, coded("server error", e.code, e.field, e.message));
}

Error Error::transport(const std::string& endpoint, const std::string& message, protocol::ErrorCode code) {
  return Error(ErrorKind::Transport, code, {}, message, endpoint,
               "transport error on " + (endpoint.empty() ? std::string("<unknown endpoint>") : endpoint) + ": " +
                   message);
}

Error Error::protocol_error(const std::string& endpoint, protocol::ErrorCode code, const std::string& field,
                            const std::string& message) {
  std::string w = "protocol error on " + endpoint + ": " + code_name(code);
  if (!field.empty()) w += " at " + field;
  w += ": " + message;
  return Error(ErrorKind::Protocol, code, field, message, endpoint, w);
}

Error Error::usage(protocol::ErrorCode code, const std::string& field, const std::string& message) {
  return Error(ErrorKind::Usage, code, field, message, {}, coded("client error", code, field, message));
}

Error Error::usage(const std::string& message) {
  return Error(ErrorKind::Usage, protocol::ErrorCode::InvalidParameter, {}, message, {}, message);
}

}  // namespace dn::client
