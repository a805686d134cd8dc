#include "dn/client/session.hpp"

#include <cstring>

#include "connection_state.hpp"
#include "result_from_message.hpp"
#include "dn/protocol/channels.hpp"
#include "dn/protocol/codec.hpp"
#include "dn/client/watch_file.hpp"

namespace dn::client {

using protocol::ChannelId;
using protocol::Format;

namespace {

const char* format_name(Format f) { return f == Format::F16 ? "f16" : "f32"; }

std::string channel_name(ChannelId id) {
  if (const auto* c = protocol::find_channel(id)) return std::string(c->name);
  return "#" + std::to_string(unsigned(id));
}

void convert_plane(const Plane& in, Format to, std::vector<uint8_t>& out) {
  const size_t n = in.bytes.size() / protocol::bytes_per_component(in.format);
  out.resize(n * protocol::bytes_per_component(to));
  if (in.format == Format::F32 && to == Format::F16) {
    for (size_t i = 0; i < n; ++i) {
      float f;
      std::memcpy(&f, in.bytes.data() + 4 * i, 4);
      const uint16_t h = protocol::float_to_half(f);
      std::memcpy(out.data() + 2 * i, &h, 2);
    }
  } else if (in.format == Format::F16 && to == Format::F32) {
    for (size_t i = 0; i < n; ++i) {
      uint16_t h;
      std::memcpy(&h, in.bytes.data() + 2 * i, 2);
      const float f = protocol::half_to_float(h);
      std::memcpy(out.data() + 4 * i, &f, 4);
    }
  } else {
    out.assign(in.bytes.begin(), in.bytes.end());
  }
}

}  // namespace

// ---- Result ---------------------------------------------------------------

double Result::total_timing_ms() const {
  double s = 0.0;
  for (const auto& t : timings) s += t.milliseconds;
  return s;
}

std::optional<double> Result::timing_ms(std::string_view name) const {
  for (const auto& t : timings)
    if (t.name == name) return t.milliseconds;
  return std::nullopt;
}

namespace {

// An RGB plane of `pixels` pixels in `format` as floats.
std::vector<float> plane_to_float(std::span<const uint8_t> bytes, Format format, size_t pixels) {
  const size_t n = pixels * 3;
  std::vector<float> v(n);
  if (format == Format::F32) {
    std::memcpy(v.data(), bytes.data(), n * 4);
  } else {
    for (size_t i = 0; i < n; ++i) {
      uint16_t h;
      std::memcpy(&h, bytes.data() + 2 * i, 2);
      v[i] = protocol::half_to_float(h);
    }
  }
  return v;
}

}  // namespace

void Result::copy_rgb(std::span<float> dst) const {
  const size_t n = size_t(width) * size_t(height) * 3;
  if (output.empty()) throw Error::usage("result of frame " + std::to_string(frame_index) + " carries no output");
  if (dst.size() != n)
    throw Error::usage("copy_rgb: destination holds " + std::to_string(dst.size()) + " floats, result has " +
                       std::to_string(n));
  const std::vector<float> v = plane_to_float(output, format, n / 3);
  std::memcpy(dst.data(), v.data(), n * 4);
}

std::vector<float> Result::rgb() const {
  std::vector<float> v(size_t(width) * size_t(height) * 3);
  copy_rgb(v);
  return v;
}

std::vector<float> Result::input_rgb() const {
  if (input.empty())
    throw Error::usage("result of frame " + std::to_string(frame_index) +
                       " carries no input (the owner did not share it, or this is not a watcher's copy)");
  return plane_to_float(input, input_format, size_t(width) * size_t(height));
}

// ---- Session --------------------------------------------------------------

Session::Session(std::shared_ptr<detail::ConnectionState> state, protocol::Session info, uint32_t max_in_flight)
    : state_(std::move(state)), info_(std::move(info)), max_in_flight_(max_in_flight ? max_in_flight : 1) {}

const std::string& Session::watch_key() const {
  static const std::string kNone;
  return info_.watch_key ? *info_.watch_key : kNone;
}

const std::string& Session::watch_url() const {
  static const std::string kNone;
  return info_.watch_url ? *info_.watch_url : kNone;
}

std::string Session::watch_server() const { return watch_url().empty() ? state_->endpoint() : watch_url(); }

std::string Session::watch_command() const { return watch_hint(*this, ""); }

Session::Session(Session&& o) noexcept
    : state_(std::move(o.state_)),
      info_(std::move(o.info_)),
      max_in_flight_(o.max_in_flight_),
      open_(o.open_),
      last_frame_index_(o.last_frame_index_),
      last_view_(o.last_view_),
      last_projection_(o.last_projection_),
      last_jitter_(o.last_jitter_),
      outstanding_(std::move(o.outstanding_)),
      ready_(std::move(o.ready_)),
      scratch_(std::move(o.scratch_)) {
  o.open_ = false;
}

Session& Session::operator=(Session&& o) noexcept {
  if (this != &o) {
    this->~Session();
    new (this) Session(std::move(o));
  }
  return *this;
}

Session::~Session() {
  if (!open_ || !state_ || !state_->is_open()) return;
  try {
    for (const auto& o : outstanding_) state_->forget(o.request_id);
    // Fire and forget: the SESSION_CLOSED reply is dropped when it arrives.
    state_->send(protocol::CloseSession{info_.session_id}, state_->next_request_id(), 0, false);
  } catch (...) {
  }
}

void Session::check_usable() const {
  if (!state_) throw Error::usage("session was moved from");
  if (!open_) throw Error::usage("session " + std::to_string(info_.session_id) + " is closed");
  state_->check_usable();
}

uint64_t Session::submit(const FrameInput& frame) {
  check_usable();
  const uint64_t index = frame.frame_index ? *frame.frame_index : (last_frame_index_ ? *last_frame_index_ + 1 : 0);
  if (last_frame_index_ && index <= *last_frame_index_)
    throw Error::usage(protocol::ErrorCode::OutOfOrder, "FRAME.frame_index",
                       "frame index " + std::to_string(index) + " is not greater than the previous frame's " +
                           std::to_string(*last_frame_index_));

  protocol::Frame msg;
  msg.info = frame.info;
  msg.info.session_id = info_.session_id;
  msg.info.frame_index = index;
  if (frame.fill_previous_camera) {
    const bool first = !last_frame_index_ || (frame.info.flags & protocol::kFrameReset);
    msg.info.prev_view = first ? msg.info.view : last_view_;
    msg.info.prev_projection = first ? msg.info.projection : last_projection_;
    msg.info.prev_jitter = first ? msg.info.jitter : last_jitter_;
  }

  // Local checks, so a wrong plane fails here with its name instead of as a
  // server ERROR one round trip later.
  if (scratch_.size() < frame.planes.size()) scratch_.resize(frame.planes.size());
  uint64_t seen = 0;
  msg.planes.reserve(frame.planes.size());
  for (size_t i = 0; i < frame.planes.size(); ++i) {
    const Plane& p = frame.planes[i];
    const std::string field = "FRAME.planes[" + std::to_string(i) + "]";
    const protocol::ChannelInfo* ci = protocol::find_channel(p.id);
    if (!ci || p.id == ChannelId::Output)
      throw Error::usage(protocol::ErrorCode::InvalidChannel, field,
                         "channel " + channel_name(p.id) + " cannot be sent in a FRAME");
    if (p.format != Format::F16 && p.format != Format::F32)
      throw Error::usage(protocol::ErrorCode::InvalidChannel, field + ".format",
                         "channel '" + channel_name(p.id) + "' has an invalid format " +
                             std::to_string(unsigned(p.format)));
    const protocol::ChannelDecl* decl = nullptr;
    for (const auto& d : info_.channels)
      if (d.id == p.id) decl = &d;
    if (!decl) {
      std::string declared;
      for (const auto& d : info_.channels) declared += (declared.empty() ? "" : ", ") + channel_name(d.id);
      throw Error::usage(protocol::ErrorCode::InvalidChannel, field,
                         "channel '" + channel_name(p.id) + "' was not declared when session " +
                             std::to_string(info_.session_id) + " was opened (declared: " + declared + ")");
    }
    if (seen & protocol::channel_bit(p.id))
      throw Error::usage(protocol::ErrorCode::InvalidChannel, field,
                         "channel '" + channel_name(p.id) + "' appears twice");
    seen |= protocol::channel_bit(p.id);
    const uint64_t expected = protocol::plane_bytes(*ci, p.format, info_.width, info_.height);
    if (p.bytes.size() != expected)
      throw Error::usage(protocol::ErrorCode::InvalidChannel, field + ".byte_length",
                         "channel '" + channel_name(p.id) + "' has " + std::to_string(p.bytes.size()) +
                             " bytes, session " + std::to_string(info_.session_id) + " expects " +
                             std::to_string(expected) + " (" + std::to_string(info_.width) + "x" +
                             std::to_string(info_.height) + " x " + std::to_string(ci->components) + " x " +
                             format_name(p.format) + ")");
    if (p.format != decl->format) {
      convert_plane(p, decl->format, scratch_[i]);
      msg.planes.push_back({p.id, decl->format, scratch_[i]});
    } else {
      msg.planes.push_back({p.id, p.format, p.bytes});
    }
  }

  // Collect answered frames (in order) without blocking, then wait for window space.
  while (!outstanding_.empty() && state_->reply_ready(outstanding_.front().request_id)) {
    auto in = state_->take_reply_if_ready(outstanding_.front().request_id);
    ready_.push_back(collect(outstanding_.front(), std::move(*in)));
    outstanding_.pop_front();
  }
  while (outstanding_.size() >= max_in_flight_) {
    detail::Incoming in = state_->wait_reply(outstanding_.front().request_id);
    ready_.push_back(collect(outstanding_.front(), std::move(in)));
    outstanding_.pop_front();
  }

  const uint64_t request_id = state_->next_request_id();
  const uint32_t flags = frame.no_output ? protocol::kFlagNoOutput : 0u;
  const auto t0 = detail::Clock::now();
  state_->send(msg, request_id, flags, true, state_->welcome().limits.max_message_bytes);
  outstanding_.push_back({request_id, index, frame.no_output, t0});
  last_frame_index_ = index;
  last_view_ = msg.info.view;
  last_projection_ = msg.info.projection;
  last_jitter_ = msg.info.jitter;
  return index;
}

Result Session::finish(const Outstanding& o, detail::Incoming&& in) {
  auto& r = std::get<protocol::Result>(in.message);
  const std::string& ep = state_->endpoint();
  if (r.session_id != info_.session_id || r.frame_index != o.frame_index)
    throw Error::protocol_error(ep, protocol::ErrorCode::Malformed, "RESULT.frame_index",
                                "RESULT for session " + std::to_string(r.session_id) + " frame " +
                                    std::to_string(r.frame_index) + " answers the FRAME of session " +
                                    std::to_string(info_.session_id) + " frame " + std::to_string(o.frame_index));
  const auto received = in.received;
  Result out = detail::result_from_message(std::move(in), info_, ep);
  out.latency = std::chrono::duration<double, std::milli>(received - o.submitted);
  if (!o.no_output && out.output.empty())
    throw Error::protocol_error(ep, protocol::ErrorCode::MissingChannel, "RESULT.planes",
                                "RESULT of frame " + std::to_string(o.frame_index) + " has no output plane");
  return out;
}

Session::Ready Session::collect(const Outstanding& o, detail::Incoming&& in) {
  Ready r;
  if (std::holds_alternative<protocol::Result>(in.message)) {
    r.result = finish(o, std::move(in));
  } else if (auto* e = std::get_if<protocol::Error>(&in.message)) {
    r.error = Error::server(*e, state_->endpoint());
  } else {
    throw Error::protocol_error(state_->endpoint(), protocol::ErrorCode::Malformed, "header.type",
                                std::string("expected RESULT or ERROR for frame ") + std::to_string(o.frame_index) +
                                    ", got " + protocol::to_string(protocol::type_of(in.message)));
  }
  return r;
}

Result Session::take(Ready&& r) {
  if (r.error) throw *r.error;
  return std::move(*r.result);
}

Result Session::wait() {
  if (!state_) throw Error::usage("session was moved from");
  if (!ready_.empty()) {
    Ready r = std::move(ready_.front());
    ready_.pop_front();
    return take(std::move(r));
  }
  if (outstanding_.empty()) throw Error::usage("Session::wait(): no frame in flight");
  detail::Incoming in = state_->wait_reply(outstanding_.front().request_id);
  Outstanding o = outstanding_.front();
  outstanding_.pop_front();
  return take(collect(o, std::move(in)));
}

std::optional<Result> Session::poll() {
  if (!state_) throw Error::usage("session was moved from");
  if (ready_.empty() && !outstanding_.empty()) {
    auto in = state_->take_reply_if_ready(outstanding_.front().request_id);
    if (!in) {
      state_->check_usable();
      return std::nullopt;
    }
    Outstanding o = outstanding_.front();
    outstanding_.pop_front();
    return take(collect(o, std::move(*in)));
  }
  if (ready_.empty()) return std::nullopt;
  Ready r = std::move(ready_.front());
  ready_.pop_front();
  return take(std::move(r));
}

Result Session::denoise(const FrameInput& frame) {
  if (in_flight() != 0)
    throw Error::usage("Session::denoise() while " + std::to_string(in_flight()) +
                       " pipelined frames are outstanding; collect them with wait() first");
  submit(frame);
  return wait();
}

protocol::SessionClosed Session::close() {
  check_usable();
  for (const auto& o : outstanding_) state_->forget(o.request_id);
  outstanding_.clear();
  ready_.clear();
  open_ = false;
  const uint64_t id = state_->next_request_id();
  state_->send(protocol::CloseSession{info_.session_id}, id, 0, true);
  detail::Incoming in = state_->wait_reply(id);
  if (auto* c = std::get_if<protocol::SessionClosed>(&in.message)) return *c;
  if (auto* e = std::get_if<protocol::Error>(&in.message)) throw Error::server(*e, state_->endpoint());
  throw Error::protocol_error(state_->endpoint(), protocol::ErrorCode::Malformed, "header.type",
                              std::string("expected SESSION_CLOSED, got ") +
                                  protocol::to_string(protocol::type_of(in.message)));
}

}  // namespace dn::client
