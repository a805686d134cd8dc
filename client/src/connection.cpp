#include "dn/client/connection.hpp"

#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include "channel_check.hpp"
#include "connection_state.hpp"
#include "dn/client/endpoint.hpp"
#include "dn/client/parameters.hpp"
#include "dn/client/session.hpp"
#include "dn/client/watcher.hpp"

namespace dn::client {

namespace {

std::string read_token_file(const std::string& path, const char* origin) {
  std::ifstream f(path);
  if (!f) throw Error::usage(std::string("cannot read token file '") + path + "' (" + origin + ")");
  std::string line;
  std::getline(f, line);
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
  size_t start = line.find_first_not_of(" \t");
  return start == std::string::npos ? std::string() : line.substr(start);
}

[[noreturn]] void unexpected(const detail::ConnectionState& st, const detail::Incoming& in, const char* expected) {
  if (auto* e = std::get_if<protocol::Error>(&in.message)) throw Error::server(*e, st.endpoint());
  throw Error::protocol_error(st.endpoint(), protocol::ErrorCode::Malformed, "header.type",
                              std::string("expected ") + expected + ", got " +
                                  protocol::to_string(protocol::type_of(in.message)));
}

}  // namespace

std::string resolve_auth_token(const ConnectOptions& options) {
  if (options.auth_token) return *options.auth_token;
  if (!options.token_file.empty()) return read_token_file(options.token_file, "token file option");
  if (const char* t = std::getenv("DN_TOKEN"); t && *t) return t;
  if (const char* f = std::getenv("DN_TOKEN_FILE"); f && *f) return read_token_file(f, "$DN_TOKEN_FILE");
  return {};
}

Connection::Connection(std::shared_ptr<detail::ConnectionState> state) : state_(std::move(state)) {}
Connection::Connection(Connection&&) noexcept = default;
Connection& Connection::operator=(Connection&&) noexcept = default;
Connection::~Connection() = default;

Connection Connection::connect(std::string_view url, const ConnectOptions& options) {
  Endpoint ep = parse_endpoint(url);
  const std::string token = resolve_auth_token(options);
  auto state = std::make_shared<detail::ConnectionState>(std::move(ep), options);
  state->open(options.client_name, token);
  return Connection(std::move(state));
}

const protocol::Welcome& Connection::welcome() const { return state_->welcome(); }
const std::string& Connection::endpoint() const { return state_->endpoint(); }
uint8_t Connection::protocol_minor() const { return state_->negotiated_minor(); }
bool Connection::is_open() const { return state_ && state_->is_open(); }
void Connection::close() {
  if (state_) state_->close();
}

const protocol::PipelineInfo* Connection::find_pipeline(std::string_view name) const {
  for (const auto& p : state_->welcome().pipelines)
    if (p.name == name) return &p;
  return nullptr;
}

std::chrono::duration<double, std::milli> Connection::ping() {
  static thread_local std::mt19937_64 rng{std::random_device{}()};
  protocol::Ping ping{rng()};
  const uint64_t id = state_->next_request_id();
  const auto t0 = detail::Clock::now();
  state_->send(ping, id, 0, true);
  detail::Incoming in = state_->wait_reply(id);
  const auto rtt = std::chrono::duration<double, std::milli>(in.received - t0);
  auto* pong = std::get_if<protocol::Pong>(&in.message);
  if (!pong) unexpected(*state_, in, "PONG");
  if (pong->payload != ping.payload)
    throw Error::protocol_error(state_->endpoint(), protocol::ErrorCode::Malformed, "PONG.payload",
                                "PONG does not echo the PING payload");
  return rtt;
}

protocol::Stats Connection::stats() {
  const uint64_t id = state_->next_request_id();
  state_->send(protocol::StatsRequest{}, id, 0, true);
  detail::Incoming in = state_->wait_reply(id);
  auto* s = std::get_if<protocol::Stats>(&in.message);
  if (!s) unexpected(*state_, in, "STATS");
  return std::move(*s);
}

Session Connection::open_session(const SessionDesc& desc) {
  if (desc.width == 0 || desc.height == 0)
    throw Error::usage(protocol::ErrorCode::InvalidParameter, "OPEN_SESSION.width",
                       "session size " + std::to_string(desc.width) + "x" + std::to_string(desc.height) +
                           " is empty");
  // With the server's parameter tables (protocol 1.1) a misspelt name or a
  // value out of range fails here, naming the valid names and the range.
  check_parameters(state_->welcome(), desc);
  detail::check_channels(state_->welcome(), desc);
  protocol::OpenSession open;
  open.width = desc.width;
  open.height = desc.height;
  open.pipeline = desc.pipeline;
  open.output_format = desc.output_format;
  open.parameters = desc.parameters;
  open.channels = desc.channels;
  if (desc.share_input && state_->negotiated_minor() < protocol::kShareInputMinor)
    throw Error::usage(protocol::ErrorCode::ReservedFlags, "header.flags",
                       "share_input needs protocol 1." + std::to_string(int(protocol::kShareInputMinor)) +
                           "; the server at " + state_->endpoint() + " speaks 1." +
                           std::to_string(int(state_->negotiated_minor())));
  const uint64_t id = state_->next_request_id();
  state_->send(open, id, desc.share_input ? protocol::kFlagShareInput : 0, true);
  detail::Incoming in = state_->wait_reply(id);
  auto* s = std::get_if<protocol::Session>(&in.message);
  if (!s) unexpected(*state_, in, "SESSION");
  const uint32_t server_limit = state_->welcome().limits.max_frames_in_flight;
  uint32_t window = desc.max_in_flight ? desc.max_in_flight : (server_limit ? server_limit : 3);
  if (server_limit && window > server_limit) window = server_limit;
  return Session(state_, std::move(*s), window);
}

Watcher Connection::attach(uint64_t session_id, std::string_view watch_key) {
  const bool keyed = state_->negotiated_minor() >= protocol::kWatchKeyMinor;
  if (keyed && (watch_key.empty() || !protocol::is_well_formed_watch_key(watch_key)))
    throw Error::usage(protocol::ErrorCode::UnknownSession, "ATTACH.watch_key",
                       "watch key '" + std::string(watch_key) + "' is not " +
                           std::to_string(protocol::kWatchKeyLength) +
                           " lowercase hex digits (the session's owner gets it in SESSION; dn denoise and dnrender "
                           "print it)");
  protocol::Attach attach{session_id, {}};
  if (keyed) attach.watch_key = std::string(watch_key);  // an older server knows no key (docs/protocol.md §10)
  const uint64_t id = state_->next_request_id();
  state_->add_watch(id, session_id);
  try {
    state_->send(attach, id, 0, true);
    detail::Incoming in = state_->wait_reply(id);
    auto* s = std::get_if<protocol::Session>(&in.message);
    if (!s) unexpected(*state_, in, "SESSION");
    return Watcher(state_, std::move(*s), id);
  } catch (...) {
    state_->remove_watch(id);
    throw;
  }
}

}  // namespace dn::client
