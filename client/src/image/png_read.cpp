// The PNG decoder (PNG specification, 3rd edition): chunks with their CRCs,
// one zlib stream over the IDAT chunks, the five scanline filters, then the
// samples to floats through a table per bit depth.
#include "dn/image/png_read.hpp"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>

#include "dn/image/exr_io.hpp"  // ImageError

namespace dn::image {

namespace {

// 16384 x 16384: larger images would take gigabytes of floats, and a corrupt
// header should not ask for them.
constexpr uint64_t kMaxPixels = uint64_t(1) << 28;
// Deflate cannot compress better than about 1032:1; more pixel bytes than
// that from the IDAT chunks means the header lies or the data is cut off.
constexpr uint64_t kMaxDeflateRatio = 1032;

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw ImageError("PNG '" + name + "': " + what);
}

uint32_t be32(const uint8_t* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }

struct Header {
  uint32_t width = 0, height = 0;
  int depth = 0, colour = 0;
};

// Samples per pixel of a colour type; 0 for an invalid one.
int samples_per_pixel(int colour) {
  switch (colour) {
    case 0: return 1;  // grey
    case 2: return 3;  // RGB
    case 3: return 1;  // palette index
    case 4: return 2;  // grey + alpha
    case 6: return 4;  // RGBA
    default: return 0;
  }
}

bool depth_allowed(int colour, int depth) {
  switch (colour) {
    case 0: return depth == 1 || depth == 2 || depth == 4 || depth == 8 || depth == 16;
    case 3: return depth == 1 || depth == 2 || depth == 4 || depth == 8;
    default: return depth == 8 || depth == 16;
  }
}

Header parse_header(std::span<const uint8_t> d, const std::string& name) {
  if (d.size() != 13) fail(name, "IHDR chunk of " + std::to_string(d.size()) + " bytes, expected 13");
  Header h;
  h.width = be32(&d[0]);
  h.height = be32(&d[4]);
  h.depth = d[8];
  h.colour = d[9];
  if (h.width == 0 || h.height == 0 || h.width > 0x7fffffffu || h.height > 0x7fffffffu)
    fail(name, "invalid size " + std::to_string(h.width) + "x" + std::to_string(h.height));
  if (uint64_t(h.width) * h.height > kMaxPixels)
    fail(name, std::to_string(h.width) + "x" + std::to_string(h.height) + " is too large (more than " +
                   std::to_string(kMaxPixels) + " pixels)");
  if (samples_per_pixel(h.colour) == 0) fail(name, "invalid colour type " + std::to_string(h.colour));
  if (!depth_allowed(h.colour, h.depth))
    fail(name, "bit depth " + std::to_string(h.depth) + " is invalid for colour type " + std::to_string(h.colour));
  if (d[10] != 0) fail(name, "unknown compression method " + std::to_string(d[10]));
  if (d[11] != 0) fail(name, "unknown filter method " + std::to_string(d[11]));
  if (d[12] == 1) fail(name, "Adam7-interlaced PNGs are not supported; save it without interlacing");
  if (d[12] != 0) fail(name, "unknown interlace method " + std::to_string(d[12]));
  return h;
}

// Inflates the concatenated IDAT data into exactly `size` bytes (extra data
// after a complete image is ignored, as other decoders do).
std::vector<uint8_t> inflate_exactly(const std::vector<uint8_t>& idat, size_t size, const std::string& name) {
  if (idat.size() > UINT_MAX || size > UINT_MAX) fail(name, "too large to decode");
  std::vector<uint8_t> raw(size);
  z_stream zs{};
  if (inflateInit(&zs) != Z_OK) fail(name, "zlib inflateInit failed");
  zs.next_in = const_cast<Bytef*>(idat.data());
  zs.avail_in = uInt(idat.size());
  zs.next_out = raw.data();
  zs.avail_out = uInt(raw.size());
  const int rc = inflate(&zs, Z_FINISH);
  const std::string message = zs.msg ? zs.msg : "";
  const uint64_t got = zs.total_out;
  inflateEnd(&zs);
  if (rc == Z_STREAM_END || (rc == Z_BUF_ERROR && got == size)) {
    if (got == size) return raw;
  } else if (rc != Z_BUF_ERROR) {
    fail(name, "corrupt pixel data (zlib: " + (message.empty() ? "error " + std::to_string(rc) : message) + ")");
  }
  fail(name, "truncated pixel data: " + std::to_string(got) + " of " + std::to_string(size) + " bytes");
}

uint8_t paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return uint8_t(pa <= pb && pa <= pc ? a : pb <= pc ? b : c);
}

// Undoes each scanline's filter in place; `raw` holds rows of a filter-type
// byte and row_bytes bytes; bpp is the filter's byte distance (at least 1).
void unfilter(std::vector<uint8_t>& raw, uint32_t rows, size_t row_bytes, size_t bpp, const std::string& name) {
  const uint8_t* prev = nullptr;
  for (uint32_t y = 0; y < rows; ++y) {
    uint8_t* line = raw.data() + size_t(y) * (row_bytes + 1);
    const int type = line[0];
    uint8_t* cur = line + 1;
    for (size_t i = 0; i < row_bytes; ++i) {
      const int a = i >= bpp ? cur[i - bpp] : 0, b = prev ? prev[i] : 0, c = prev && i >= bpp ? prev[i - bpp] : 0;
      switch (type) {
        case 0: break;
        case 1: cur[i] = uint8_t(cur[i] + a); break;
        case 2: cur[i] = uint8_t(cur[i] + b); break;
        case 3: cur[i] = uint8_t(cur[i] + ((a + b) >> 1)); break;
        case 4: cur[i] = uint8_t(cur[i] + paeth(a, b, c)); break;
        default: fail(name, "row " + std::to_string(y) + " has unknown filter type " + std::to_string(type));
      }
    }
    prev = cur;
  }
}

// Sample `index` of a row: 16-bit big-endian, 8-bit, or packed most
// significant bits first.
uint32_t sample(const uint8_t* row, size_t index, int depth) {
  if (depth == 16) return uint32_t(row[2 * index]) << 8 | row[2 * index + 1];
  if (depth == 8) return row[index];
  const size_t bit = index * size_t(depth);
  return (row[bit / 8] >> (8 - depth - int(bit % 8))) & ((1u << depth) - 1u);
}

// Float per sample value 0 .. 2^depth - 1, computed in double precision.
std::vector<float> transfer_table(int depth, PngTransfer transfer) {
  const uint32_t top = (1u << depth) - 1u;
  std::vector<float> table(size_t(top) + 1);
  for (uint32_t v = 0; v <= top; ++v) {
    const double x = double(v) / double(top);
    table[v] = float(transfer == PngTransfer::Linear   ? x
                     : transfer == PngTransfer::Signed ? 2.0 * x - 1.0
                     : x <= 0.04045                    ? x / 12.92
                                                       : std::pow((x + 0.055) / 1.055, 2.4));
  }
  return table;
}

}  // namespace

std::vector<float> decode_png_rgb(std::span<const uint8_t> png, const std::string& name, int& width, int& height,
                                  PngTransfer transfer) {
  static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (png.size() < 8 || std::memcmp(png.data(), kSignature, 8) != 0) fail(name, "not a PNG file (no PNG signature)");
  Header h;
  bool have_header = false, ended = false;
  std::vector<uint8_t> idat, palette;
  for (size_t at = 8; !ended;) {
    if (png.size() - at < 12) fail(name, "truncated: the file ends before its IEND chunk");
    const uint32_t length = be32(&png[at]);
    const std::string type(reinterpret_cast<const char*>(&png[at + 4]), 4);
    if (length > 0x7fffffffu || png.size() - at - 12 < length)
      fail(name, "truncated: chunk '" + type + "' of " + std::to_string(length) + " bytes runs past the end of the file");
    const std::span<const uint8_t> data = png.subspan(at + 8, length);
    uLong crc = crc32(0L, Z_NULL, 0);
    crc = crc32_z(crc, &png[at + 4], 4 + size_t(length));
    if (uint32_t(crc) != be32(&png[at + 8 + length])) fail(name, "bad CRC in chunk '" + type + "' (corrupt file)");
    if (!have_header && type != "IHDR") fail(name, "the first chunk is '" + type + "', not IHDR");
    if (type == "IHDR") {
      if (have_header) fail(name, "a second IHDR chunk");
      h = parse_header(data, name);
      have_header = true;
    } else if (type == "PLTE") {
      if (length % 3 != 0 || length == 0 || length > 256 * 3)
        fail(name, "PLTE chunk of " + std::to_string(length) + " bytes (expected 3 per entry, 1 to 256 entries)");
      palette.assign(data.begin(), data.end());
    } else if (type == "IDAT") {
      idat.insert(idat.end(), data.begin(), data.end());
    } else if (type == "IEND") {
      ended = true;
    } else if (type[0] >= 'A' && type[0] <= 'Z') {
      // Critical chunks must be understood (PNG §5.4); ancillary ones may be skipped.
      fail(name, "unknown critical chunk '" + type + "'");
    }
    at += 12 + size_t(length);
  }
  if (idat.empty()) fail(name, "no IDAT chunk (no pixel data)");
  if (h.colour == 3 && palette.empty()) fail(name, "palette image without a PLTE chunk");

  const int spp = samples_per_pixel(h.colour);
  const size_t row_bytes = size_t((uint64_t(h.width) * uint64_t(spp) * uint64_t(h.depth) + 7) / 8);
  const uint64_t raw_size = uint64_t(h.height) * (row_bytes + 1);
  if (raw_size > uint64_t(idat.size()) * kMaxDeflateRatio + 1024)
    fail(name, "truncated: " + std::to_string(idat.size()) + " bytes of compressed pixel data cannot hold " +
                   std::to_string(h.width) + "x" + std::to_string(h.height) + " pixels");
  std::vector<uint8_t> raw = inflate_exactly(idat, size_t(raw_size), name);
  unfilter(raw, h.height, row_bytes, std::max<size_t>(1, size_t(spp * h.depth / 8)), name);

  const std::vector<float> table = transfer_table(h.colour == 3 ? 8 : h.depth, transfer);
  const size_t entries = palette.size() / 3;
  std::vector<float> rgb(size_t(h.width) * h.height * 3);
  for (uint32_t y = 0; y < h.height; ++y) {
    const uint8_t* row = raw.data() + size_t(y) * (row_bytes + 1) + 1;
    float* out = rgb.data() + size_t(y) * h.width * 3;
    for (uint32_t x = 0; x < h.width; ++x, out += 3) {
      const size_t first = size_t(x) * size_t(spp);
      if (h.colour == 3) {
        const uint32_t index = sample(row, first, h.depth);
        if (index >= entries)
          fail(name, "palette index " + std::to_string(index) + " at pixel (" + std::to_string(x) + ", " +
                         std::to_string(y) + ") is past the PLTE's " + std::to_string(entries) + " entries");
        for (int c = 0; c < 3; ++c) out[c] = table[palette[3 * index + size_t(c)]];
      } else if (spp >= 3) {  // RGB, RGBA: alpha dropped
        for (int c = 0; c < 3; ++c) out[c] = table[sample(row, first + size_t(c), h.depth)];
      } else {  // grey, grey + alpha
        out[0] = out[1] = out[2] = table[sample(row, first, h.depth)];
      }
    }
  }
  width = int(h.width);
  height = int(h.height);
  return rgb;
}

std::vector<float> read_png_rgb(const std::string& path, int& width, int& height, PngTransfer transfer) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ImageError("PNG '" + path + "': cannot read: " + std::strerror(errno));
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw ImageError("PNG '" + path + "': cannot read");
  return decode_png_rgb(bytes, path, width, height, transfer);
}

}  // namespace dn::image
