// Names of message types and error codes (as used in docs/protocol.md), and type_of().
#include "wire.hpp"

namespace dn::protocol {

const char* to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::BadMagic: return "BAD_MAGIC";
    case ErrorCode::UnsupportedVersion: return "UNSUPPORTED_VERSION";
    case ErrorCode::ReservedFlags: return "RESERVED_FLAGS";
    case ErrorCode::MessageTooLarge: return "MESSAGE_TOO_LARGE";
    case ErrorCode::UnknownMessageType: return "UNKNOWN_MESSAGE_TYPE";
    case ErrorCode::Malformed: return "MALFORMED";
    case ErrorCode::Unauthenticated: return "UNAUTHENTICATED";
    case ErrorCode::NotReady: return "NOT_READY";
    case ErrorCode::UnknownSession: return "UNKNOWN_SESSION";
    case ErrorCode::UnknownPipeline: return "UNKNOWN_PIPELINE";
    case ErrorCode::InvalidParameter: return "INVALID_PARAMETER";
    case ErrorCode::InvalidChannel: return "INVALID_CHANNEL";
    case ErrorCode::MissingChannel: return "MISSING_CHANNEL";
    case ErrorCode::LimitExceeded: return "LIMIT_EXCEEDED";
    case ErrorCode::OutOfOrder: return "OUT_OF_ORDER";
    case ErrorCode::DeviceError: return "DEVICE_ERROR";
    case ErrorCode::ShuttingDown: return "SHUTTING_DOWN";
    case ErrorCode::Timeout: return "TIMEOUT";
    case ErrorCode::Internal: return "INTERNAL";
  }
  return "UNKNOWN_ERROR_CODE";
}

const char* to_string(MessageType type) {
  switch (type) {
    case MessageType::Hello: return "HELLO";
    case MessageType::Welcome: return "WELCOME";
    case MessageType::Error: return "ERROR";
    case MessageType::OpenSession: return "OPEN_SESSION";
    case MessageType::Session: return "SESSION";
    case MessageType::Frame: return "FRAME";
    case MessageType::Result: return "RESULT";
    case MessageType::Attach: return "ATTACH";
    case MessageType::Ping: return "PING";
    case MessageType::Pong: return "PONG";
    case MessageType::CloseSession: return "CLOSE_SESSION";
    case MessageType::SessionClosed: return "SESSION_CLOSED";
    case MessageType::StatsRequest: return "STATS_REQUEST";
    case MessageType::Stats: return "STATS";
  }
  return "UNKNOWN_MESSAGE_TYPE";
}

MessageType type_of(const Message& message) {
  struct Visitor {
    MessageType operator()(const Hello&) const { return MessageType::Hello; }
    MessageType operator()(const Welcome&) const { return MessageType::Welcome; }
    MessageType operator()(const Error&) const { return MessageType::Error; }
    MessageType operator()(const OpenSession&) const { return MessageType::OpenSession; }
    MessageType operator()(const Session&) const { return MessageType::Session; }
    MessageType operator()(const Frame&) const { return MessageType::Frame; }
    MessageType operator()(const Result&) const { return MessageType::Result; }
    MessageType operator()(const Attach&) const { return MessageType::Attach; }
    MessageType operator()(const Ping&) const { return MessageType::Ping; }
    MessageType operator()(const Pong&) const { return MessageType::Pong; }
    MessageType operator()(const CloseSession&) const { return MessageType::CloseSession; }
    MessageType operator()(const SessionClosed&) const { return MessageType::SessionClosed; }
    MessageType operator()(const StatsRequest&) const { return MessageType::StatsRequest; }
    MessageType operator()(const Stats&) const { return MessageType::Stats; }
  };
  return std::visit(Visitor{}, message);
}

namespace wire {

bool is_known_type(MessageType t) {
  const auto v = static_cast<uint16_t>(t);
  return v >= static_cast<uint16_t>(MessageType::Hello) && v <= static_cast<uint16_t>(MessageType::Stats);
}

bool is_known_error_code(uint32_t code) {
  return code >= static_cast<uint32_t>(ErrorCode::BadMagic) && code <= static_cast<uint32_t>(ErrorCode::Internal);
}

}  // namespace wire
}  // namespace dn::protocol
