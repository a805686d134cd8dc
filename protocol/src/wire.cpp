// Little-endian writer/reader primitives shared by the encoder and decoder.
#include "wire.hpp"

#include <bit>
#include <cmath>

namespace dn::protocol::wire {

void Writer::u16(uint16_t v) {
  uint8_t b[2];
  store_u16(b, v);
  out_.insert(out_.end(), b, b + 2);
}
void Writer::u32(uint32_t v) {
  uint8_t b[4];
  store_u32(b, v);
  out_.insert(out_.end(), b, b + 4);
}
void Writer::u64(uint64_t v) {
  uint8_t b[8];
  store_u64(b, v);
  out_.insert(out_.end(), b, b + 8);
}
void Writer::f32(float v) { u32(std::bit_cast<uint32_t>(v)); }
void Writer::f64(double v) { u64(std::bit_cast<uint64_t>(v)); }
void Writer::str(std::string_view s) {
  u16(static_cast<uint16_t>(s.size()));
  out_.insert(out_.end(), s.begin(), s.end());
}

std::string Field::str() const {
  std::string s(type);
  s += '.';
  s += name;
  if (index >= 0) {
    s += '[';
    s += std::to_string(index);
    s += ']';
  }
  s += sub;
  return s;
}

const uint8_t* Reader::take(size_t n, const Field& f) {
  if (error_) return nullptr;
  if (n > remaining()) {
    fail(ErrorCode::Malformed, f,
         f.str() + " is truncated: needs " + std::to_string(n) + " bytes, " + std::to_string(remaining()) +
             " remain");
    return nullptr;
  }
  const uint8_t* p = data_.data() + pos_;
  pos_ += n;
  return p;
}

bool Reader::u8(uint8_t& v, const Field& f) {
  const uint8_t* p = take(1, f);
  if (!p) return false;
  v = p[0];
  return true;
}
bool Reader::u16(uint16_t& v, const Field& f) {
  const uint8_t* p = take(2, f);
  if (!p) return false;
  v = load_u16(p);
  return true;
}
bool Reader::u32(uint32_t& v, const Field& f) {
  const uint8_t* p = take(4, f);
  if (!p) return false;
  v = load_u32(p);
  return true;
}
bool Reader::u64(uint64_t& v, const Field& f) {
  const uint8_t* p = take(8, f);
  if (!p) return false;
  v = load_u64(p);
  return true;
}
bool Reader::f32(float& v, const Field& f) {
  uint32_t bits;
  if (!u32(bits, f)) return false;
  v = std::bit_cast<float>(bits);
  if (!std::isfinite(v))
    return fail(ErrorCode::Malformed, f, f.str() + " must be finite, found " + std::to_string(v));
  return true;
}
bool Reader::f64(double& v, const Field& f) {
  uint64_t bits;
  if (!u64(bits, f)) return false;
  v = std::bit_cast<double>(bits);
  if (!std::isfinite(v))
    return fail(ErrorCode::Malformed, f, f.str() + " must be finite, found " + std::to_string(v));
  return true;
}

bool Reader::str(std::string& v, const Field& f, size_t max_bytes) {
  uint16_t n;
  if (!u16(n, f)) return false;
  if (n > max_bytes)
    return fail(ErrorCode::Malformed, f,
                f.str() + " length " + std::to_string(n) + " exceeds the " + std::to_string(max_bytes) +
                    "-byte limit");
  const uint8_t* p = take(n, f);
  if (!p) return false;
  std::string_view s(reinterpret_cast<const char*>(p), n);
  if (!is_valid_utf8_without_nul(s))
    return fail(ErrorCode::Malformed, f, f.str() + " is not UTF-8 without NUL bytes");
  v.assign(s);
  return true;
}

bool Reader::count(uint16_t& n, const Field& f, size_t max_count, size_t min_item_bytes) {
  if (!u16(n, f)) return false;
  if (n > max_count)
    return fail(ErrorCode::Malformed, f,
                f.str() + " count " + std::to_string(n) + " exceeds the limit of " + std::to_string(max_count));
  // Never trust a count beyond what the remaining payload can hold.
  if (uint64_t{n} * min_item_bytes > remaining())
    return fail(ErrorCode::Malformed, f,
                f.str() + " count " + std::to_string(n) + " needs at least " +
                    std::to_string(uint64_t{n} * min_item_bytes) + " bytes, " + std::to_string(remaining()) +
                    " remain");
  return true;
}

bool Reader::bytes(std::span<const uint8_t>& v, uint64_t n, const Field& f) {
  if (error_) return false;
  if (n > remaining())
    return fail(ErrorCode::Malformed, f,
                f.str() + " is truncated: needs " + std::to_string(n) + " bytes, " + std::to_string(remaining()) +
                    " remain");
  const uint8_t* p = take(static_cast<size_t>(n), f);
  v = std::span<const uint8_t>(p, static_cast<size_t>(n));
  return true;
}

bool Reader::zero_bytes(size_t n, const Field& f) {
  const uint8_t* p = take(n, f);
  if (!p) return false;
  for (size_t i = 0; i < n; ++i)
    if (p[i] != 0)
      return fail(ErrorCode::Malformed, f,
                  f.str() + " is reserved and must be zero, found byte " + std::to_string(p[i]) + " at offset " +
                      std::to_string(i));
  return true;
}

bool Reader::fail(ErrorCode code, const Field& f, std::string message) {
  if (!error_) error_ = DecodeError{code, f.str(), std::move(message)};
  return false;
}

bool Reader::finish(bool allow_trailing) {
  if (error_) return false;
  if (remaining() != 0 && !allow_trailing) {
    std::string t(type_name_);
    error_ = DecodeError{ErrorCode::Malformed, t, t + ": " + std::to_string(remaining()) + " trailing bytes"};
    return false;
  }
  return true;
}

bool is_valid_utf8_without_nul(std::string_view s) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const size_t n = s.size();
  size_t i = 0;
  while (i < n) {
    unsigned char c = p[i];
    if (c == 0) return false;
    if (c < 0x80) {
      ++i;
      continue;
    }
    size_t len;
    uint32_t cp;
    if ((c & 0xE0) == 0xC0) {
      len = 2;
      cp = c & 0x1F;
    } else if ((c & 0xF0) == 0xE0) {
      len = 3;
      cp = c & 0x0F;
    } else if ((c & 0xF8) == 0xF0) {
      len = 4;
      cp = c & 0x07;
    } else {
      return false;
    }
    if (n - i < len) return false;
    for (size_t k = 1; k < len; ++k) {
      if ((p[i + k] & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (p[i + k] & 0x3F);
    }
    static constexpr uint32_t kMinForLen[5] = {0, 0, 0x80, 0x800, 0x10000};
    if (cp < kMinForLen[len]) return false;               // overlong
    if (cp > 0x10FFFF) return false;                      // beyond Unicode
    if (cp >= 0xD800 && cp <= 0xDFFF) return false;      // surrogate
    i += len;
  }
  return true;
}

}  // namespace dn::protocol::wire
