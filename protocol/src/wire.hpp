// Internal to dn_protocol: little-endian primitives, the payload limits table
// and the bounds-checked payload reader used by decode.cpp. Not installed.
#pragma once

#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "dn/protocol/codec.hpp"

namespace dn::protocol::wire {

// ---- limits (docs/protocol.md, "Limits") ---------------------------------
inline constexpr size_t kMaxNameBytes = 64;       // pipeline, parameter, timing, stat names, client_name
inline constexpr size_t kMaxTextBytes = 1024;     // ERROR.field, ERROR.message
inline constexpr size_t kMaxTokenBytes = 256;     // HELLO.auth_token
inline constexpr size_t kMaxVersionBytes = 256;   // WELCOME.server_version, WELCOME.device_name
inline constexpr size_t kMaxDescriptionBytes = 512;  // WELCOME.pipeline_parameters[i][j].description (1.1)
inline constexpr size_t kMaxPipelines = 64;
inline constexpr size_t kMaxParameters = 64;      // OPEN_SESSION.parameters, WELCOME.pipeline_parameters[i]
inline constexpr size_t kMaxChannels = 64;  // ids are < 64 and unique (1.5: 44 input channels defined)
inline constexpr size_t kMaxPlanes = 64;  // one per declared channel (kMaxChannels)
inline constexpr size_t kMaxTimings = 64;
inline constexpr size_t kMaxStats = 256;

inline constexpr size_t kFrameInfoBytes = 296;   // fixed part of FRAME before the plane list
inline constexpr size_t kPlaneHeaderBytes = 12;  // u8 id, u8 format, u16 reserved, u64 byte_length
// WELCOME 1.1 parameter entry without its strings' bytes: name length, 3 x f64, bool, description length.
inline constexpr size_t kParameterInfoMinBytes = 2 + 3 * 8 + 1 + 2;

// ---- little-endian stores/loads (no alignment assumptions) ---------------
inline void store_u16(uint8_t* p, uint16_t v) {
  p[0] = uint8_t(v);
  p[1] = uint8_t(v >> 8);
}
inline void store_u32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = uint8_t(v >> (8 * i));
}
inline void store_u64(uint8_t* p, uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = uint8_t(v >> (8 * i));
}
inline uint16_t load_u16(const uint8_t* p) { return uint16_t(p[0] | (uint16_t(p[1]) << 8)); }
inline uint32_t load_u32(const uint8_t* p) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
inline uint64_t load_u64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

// ---- writer --------------------------------------------------------------
// Appends to a vector the caller has already reserved. Sizes that cannot be
// represented on the wire (string > 65535 bytes, ...) are checked by the
// encoder before anything is written.
class Writer {
 public:
  explicit Writer(std::vector<uint8_t>& out) : out_(out) {}
  void u8(uint8_t v) { out_.push_back(v); }
  void u16(uint16_t v);
  void u32(uint32_t v);
  void u64(uint64_t v);
  void f32(float v);
  void f64(double v);
  void bytes(std::span<const uint8_t> b) { out_.insert(out_.end(), b.begin(), b.end()); }
  void str(std::string_view s);
  void zeros(size_t n) { out_.insert(out_.end(), n, uint8_t{0}); }

 private:
  std::vector<uint8_t>& out_;
};

// ---- field names, built only when an error is reported ---------------------
// "<type>.<name>[index]<sub>", e.g. {"OPEN_SESSION", "channels", 3, ".format"}.
struct Field {
  std::string_view type;
  std::string_view name;
  long index = -1;
  std::string_view sub = {};
  std::string str() const;
};

// ---- bounds-checked reader -------------------------------------------------
// Every read names its field; the first failure is kept in error() and all
// later reads fail, so decoders can chain reads and test once.
class Reader {
 public:
  Reader(std::span<const uint8_t> data, std::string_view type_name) : data_(data), type_name_(type_name) {}

  bool u8(uint8_t& v, const Field& f);
  bool u16(uint16_t& v, const Field& f);
  bool u32(uint32_t& v, const Field& f);
  bool u64(uint64_t& v, const Field& f);
  bool f32(float& v, const Field& f);   // must be finite
  bool f64(double& v, const Field& f);  // must be finite
  // u16 length, then UTF-8 without NUL, at most max_bytes.
  bool str(std::string& v, const Field& f, size_t max_bytes);
  // u16 count at most max_count, and count * min_item_bytes must fit in what remains.
  bool count(uint16_t& n, const Field& f, size_t max_count, size_t min_item_bytes);
  bool bytes(std::span<const uint8_t>& v, uint64_t n, const Field& f);
  bool zero_bytes(size_t n, const Field& f);  // reserved bytes, must be zero

  bool fail(ErrorCode code, const Field& f, std::string message);
  // Checks that everything was consumed (unless trailing bytes are allowed).
  bool finish(bool allow_trailing);

  size_t remaining() const { return data_.size() - pos_; }
  bool ok() const { return !error_; }
  std::optional<DecodeError>& error() { return error_; }
  std::string_view type_name() const { return type_name_; }

 private:
  const uint8_t* take(size_t n, const Field& f);

  std::span<const uint8_t> data_;
  size_t pos_ = 0;
  std::string_view type_name_;
  std::optional<DecodeError> error_;
};

bool is_valid_utf8_without_nul(std::string_view s);

// Writes the 24-byte header (header.cpp).
void store_header(uint8_t* p, const Header& h);

// Name used in field paths and messages: "HELLO", "OPEN_SESSION", ... (names.cpp).
inline std::string_view type_name(MessageType t) { return to_string(t); }
bool is_known_type(MessageType t);
bool is_known_error_code(uint32_t code);

}  // namespace dn::protocol::wire
