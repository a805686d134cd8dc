// Protocol v1 messages (minor version 1.6): plain structs, one per message type.
// docs/protocol.md is the normative description of every byte; this header
// mirrors it. Nothing here knows about sockets or Vulkan.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "dn/protocol/channels.hpp"

namespace dn::protocol {

inline constexpr uint32_t kMagic = 0x56534E44;  // bytes "DNSV" on the wire
inline constexpr uint8_t kVersionMajor = 1;
inline constexpr uint8_t kVersionMinor = 10;  // 1.1: parameter metadata in WELCOME; 1.2: channel ids 12-14 (lighting forms); 1.3: ids 15-21 (reflection features); 1.4: ids 33-50 (extra samples); 1.5: ids 51-54 (sample statistics); 1.6: watch keys (SESSION, ATTACH); 1.7: SHARE_INPUT (OPEN_SESSION flag); 1.8: SESSION.watch_url; 1.9: RESULT.samples; 1.10: pipeline 'auto', SESSION.pipeline_reason
inline constexpr size_t kHeaderSize = 24;

// Where dnserver listens when started without --listen, and so where clients
// (the dn tool) connect when given no address.
inline constexpr const char* kDefaultServerUrl = "tcp://127.0.0.1:7878";

enum class MessageType : uint16_t {
  Hello = 1,
  Welcome = 2,
  Error = 3,
  OpenSession = 4,
  Session = 5,
  Frame = 6,
  Result = 7,
  Attach = 8,
  Ping = 9,
  Pong = 10,
  CloseSession = 11,
  SessionClosed = 12,
  StatsRequest = 13,
  Stats = 14,
};

// Header flags. Every bit not named here is reserved and must be zero.
inline constexpr uint32_t kFlagNoOutput = 1u << 0;  // FRAME: process, but RESULT carries no planes
// OPEN_SESSION (1.7): the owner shares each frame's noisy radiance with the
// session's watchers; their RESULT copies carry it as a second plane.
inline constexpr uint32_t kFlagShareInput = 1u << 1;
inline constexpr uint32_t kDefinedHeaderFlags = kFlagNoOutput | kFlagShareInput;

struct Header {
  uint32_t magic = kMagic;
  uint8_t version_major = kVersionMajor;
  uint8_t version_minor = kVersionMinor;
  MessageType type = MessageType::Ping;
  uint32_t flags = 0;
  uint32_t payload_length = 0;
  uint64_t request_id = 0;  // echoed in the reply; for FRAME/RESULT the client's frame id
};

// Error codes carried by ERROR. Values are part of the wire format.
enum class ErrorCode : uint32_t {
  BadMagic = 1,
  UnsupportedVersion = 2,
  ReservedFlags = 3,
  MessageTooLarge = 4,
  UnknownMessageType = 5,
  Malformed = 6,           // payload does not parse; `field` names where it failed
  Unauthenticated = 7,
  NotReady = 8,            // message before HELLO, or second HELLO
  UnknownSession = 9,      // session id not found or not owned by this connection
  UnknownPipeline = 10,
  InvalidParameter = 11,
  InvalidChannel = 12,     // wrong size, undeclared, duplicate, wrong format
  MissingChannel = 13,
  LimitExceeded = 14,      // sessions per server, bytes per session, resolution, ...
  OutOfOrder = 15,         // frame index not increasing within a session
  DeviceError = 16,
  ShuttingDown = 17,
  Timeout = 18,
  Internal = 19,
};

const char* to_string(ErrorCode code);
const char* to_string(MessageType type);

// 1.6: a session's watch key, the capability to ATTACH to it (SESSION.watch_key,
// ATTACH.watch_key): kWatchKeyLength lowercase hex digits, or empty for "none".
inline constexpr uint8_t kWatchKeyMinor = 6;
inline constexpr uint8_t kShareInputMinor = 7;  // the header flag SHARE_INPUT
inline constexpr uint8_t kWatchUrlMinor = 8;    // SESSION.watch_url
inline constexpr uint8_t kSamplesMinor = 9;     // RESULT.samples
inline constexpr uint8_t kAutoMinor = 10;       // OPEN_SESSION.pipeline "auto", SESSION.pipeline_reason
inline constexpr size_t kMaxWatchUrlBytes = 256;
inline constexpr size_t kMaxPipelineReasonBytes = 512;
// 1.10: the pipeline name that asks the server to choose from the declared
// channels (docs/pipelines.md "auto"); SESSION.pipeline names the choice.
inline constexpr const char* kAutoPipeline = "auto";
inline constexpr size_t kWatchKeyLength = 32;  // 128 random bits
// Empty, or exactly kWatchKeyLength characters of 0-9a-f: what the decoder accepts.
bool is_well_formed_watch_key(std::string_view key);

struct Hello {
  uint32_t capabilities = 0;  // reserved, zero in v1
  std::string client_name;
  std::string auth_token;  // empty when the server needs none
};

// One tunable of a pipeline, as WELCOME 1.1 announces it (pipeline_parameters).
struct ParameterInfo {
  std::string name;
  double default_value = 0.0;
  double min_value = 0.0;  // inclusive range
  double max_value = 0.0;
  bool integer = false;    // the value must be integral
  std::string description;  // one line, at most 512 bytes
};

struct PipelineInfo {
  std::string name;
  uint64_t required_channels = 0;  // bit i = ChannelId i
  uint64_t optional_channels = 0;
  // Every parameter the pipeline takes; meaningful only when
  // Welcome::has_parameters (a 1.0 server announces none).
  std::vector<ParameterInfo> parameters;
};

struct Limits {
  uint64_t max_message_bytes = 0;
  uint64_t max_session_bytes = 0;  // device bytes per session
  uint32_t max_sessions = 0;
  uint32_t max_width = 0;
  uint32_t max_height = 0;
  uint32_t max_frames_in_flight = 0;
};

struct Welcome {
  std::string server_version;
  std::string device_name;
  Limits limits;
  std::vector<PipelineInfo> pipelines;
  // 1.1: the payload carries pipeline_parameters, i.e. pipelines[i].parameters
  // are complete. Decoded as true exactly when the header's minor is >= 1; a
  // server sets it only for a client whose HELLO had minor >= 1.
  bool has_parameters = false;
};

struct Error {
  ErrorCode code = ErrorCode::Internal;
  std::string field;    // the offending field, e.g. "FRAME.planes[2].byte_length"; may be empty
  std::string message;  // human-readable reason
};

struct Parameter {
  std::string name;
  double value = 0.0;
};

struct ChannelDecl {
  ChannelId id = ChannelId::Radiance;
  Format format = Format::F32;
};

struct OpenSession {
  uint32_t width = 0;
  uint32_t height = 0;
  std::string pipeline;
  Format output_format = Format::F32;
  std::vector<Parameter> parameters;
  std::vector<ChannelDecl> channels;
};

struct Session {
  uint64_t session_id = 0;
  uint32_t width = 0;
  uint32_t height = 0;
  std::string pipeline;
  Format output_format = Format::F32;
  uint64_t device_bytes = 0;  // persistent device memory this session holds
  bool read_only = false;     // true for an ATTACH acknowledgement
  std::vector<ChannelDecl> channels;
  // 1.6, appended: on the wire exactly when set (decoded as set when the
  // header's minor is >= kWatchKeyMinor). The key in the reply to
  // OPEN_SESSION, empty in the reply to ATTACH.
  std::optional<std::string> watch_key;
  // 1.8, appended after watch_key (which must then be set): where watchers of
  // this session connect, e.g. a balancer's port that reaches this backend
  // (dnserver --advertise-url); empty when the server has none. Printable
  // ASCII, at most kMaxWatchUrlBytes.
  std::optional<std::string> watch_url;
  // 1.10, appended after watch_url (which must then be set): for a session
  // opened as "auto", why the server chose `pipeline`, one line of printable
  // ASCII (spaces allowed) at most kMaxPipelineReasonBytes; empty otherwise.
  std::optional<std::string> pipeline_reason;
};

// Motion vectors: the protocol's canonical convention is pixels, current
// position to previous position (p_prev = p + mv). Others are converted by
// the server at its first pass.
enum class MotionConvention : uint8_t {
  PixelsToPrevious = 0,
  PixelsToNext = 1,   // p_prev = p - mv (renderers that store forward motion)
  UvToPrevious = 2,   // mv in [0,1] texture units: p_prev = p + mv * (w, h)
};

using Mat4 = std::array<float, 16>;  // column-major, as GLM stores it

inline constexpr uint32_t kFrameReset = 1u << 0;  // FrameInfo.flags: discard history before this frame
inline constexpr uint32_t kDefinedFrameFlags = kFrameReset;

struct FrameInfo {
  uint64_t session_id = 0;
  uint64_t frame_index = 0;
  uint32_t flags = 0;
  MotionConvention motion = MotionConvention::PixelsToPrevious;
  Mat4 view{}, projection{};            // unjittered, current frame
  Mat4 prev_view{}, prev_projection{};  // unjittered, previous frame
  std::array<float, 2> jitter{};        // pixels, current frame
  std::array<float, 2> prev_jitter{};
};

// A plane views bytes owned by someone else (the decoded message buffer or
// the encoder's caller), so large frames are never copied by the codec.
struct PlaneView {
  ChannelId id = ChannelId::Radiance;
  Format format = Format::F32;
  std::span<const uint8_t> bytes;
};

struct Frame {
  FrameInfo info;
  std::vector<PlaneView> planes;
};

struct PassTiming {
  std::string name;
  double milliseconds = 0.0;
};

// 1.9: how many of the session's input frames the output rests on, per
// pixel, over the frame (docs/protocol.md §5.7).
struct SampleCounts {
  bool counted = false;  // false: the pipeline keeps no count (min and median 0)
  uint32_t min = 0;
  uint32_t median = 0;
  bool operator==(const SampleCounts&) const = default;
};

struct Result {
  uint64_t session_id = 0;
  uint64_t frame_index = 0;
  std::vector<PassTiming> timings;  // device passes and server stages (upload, download)
  std::vector<PlaneView> planes;
  // 1.9, appended: on the wire exactly when set (as Session.watch_url): the
  // server sets it for peers at 1.9 or later, not counted where the
  // pipeline keeps no count.
  std::optional<SampleCounts> samples;
};

struct Attach {
  uint64_t session_id = 0;
  // 1.6, appended: on the wire exactly when set, as in Session. The server
  // refuses an ATTACH without the session's key.
  std::optional<std::string> watch_key;
};

struct Ping {
  uint64_t payload = 0;  // echoed in PONG
};
struct Pong {
  uint64_t payload = 0;
};

struct CloseSession {
  uint64_t session_id = 0;
};
struct SessionClosed {
  uint64_t session_id = 0;
  uint64_t frames_processed = 0;
};

struct StatsRequest {};

struct StatValue {
  std::string name;
  double value = 0.0;
};
struct Stats {
  std::vector<StatValue> values;
};

using Message = std::variant<Hello, Welcome, Error, OpenSession, Session, Frame, Result, Attach, Ping,
                             Pong, CloseSession, SessionClosed, StatsRequest, Stats>;

MessageType type_of(const Message& message);

}  // namespace dn::protocol
