// The PFM and PNG readers of dn_imageio (dn/image/pfm.hpp, dn/image/png_read.hpp)
// on files built byte by byte here: expectations come from the formats' own
// rules (byte order, row order, filters, the sRGB EOTF), not from the readers.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "dn/image/exr_io.hpp"
#include "dn/image/pfm.hpp"
#include "dn/image/png_read.hpp"

namespace {

namespace fs = std::filesystem;
using dn::image::ImageError;
using dn::image::PngTransfer;

class ImageReaders : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("dn_image_readers_" + std::to_string(::getpid()) + "_" +
                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }

  std::string write(const std::string& name, const std::string& bytes) {
    const std::string path = (dir / name).string();
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return path;
  }
  std::string write(const std::string& name, const std::vector<uint8_t>& bytes) {
    return write(name, std::string(bytes.begin(), bytes.end()));
  }
  fs::path dir;
};

// The message of the ImageError `fn` throws (a test failure if none).
template <class Fn>
std::string error_of(Fn&& fn) {
  try {
    fn();
  } catch (const ImageError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ImageError";
  return {};
}

// ---- PFM ----------------------------------------------------------------------

std::string float_bytes(float v, bool big_endian) {
  uint32_t u = std::bit_cast<uint32_t>(v);
  std::string b(4, '\0');
  for (int i = 0; i < 4; ++i) b[size_t(i)] = char(big_endian ? (u >> (24 - 8 * i)) & 0xff : (u >> (8 * i)) & 0xff);
  return b;
}

TEST_F(ImageReaders, PfmRoundTripThroughTheWriter) {
  const int w = 5, h = 3;
  std::vector<float> rgb(size_t(w * h * 3));
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = float(i) * 0.37f - 2.0f + (i == 7 ? 1e30f : 0.0f);
  const std::string path = (dir / "a.pfm").string();
  dn::image::write_pfm_rgb(path, w, h, rgb.data());
  int rw = 0, rh = 0;
  EXPECT_EQ(dn::image::read_pfm_rgb(path, rw, rh), rgb);
  EXPECT_EQ(rw, w);
  EXPECT_EQ(rh, h);
}

// Big-endian (positive scale), three rows stored bottom-first: the file's first
// row is the image's last.
TEST_F(ImageReaders, PfmBigEndianColourRowsBottomToTop) {
  const int w = 2, h = 3;
  std::string bytes = "PF\n2 3\n1.0\n";
  for (int stored = 0; stored < h; ++stored)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) bytes += float_bytes(100.0f * float(stored) + 10.0f * float(x) + float(c), true);
  int rw = 0, rh = 0;
  const std::vector<float> rgb = dn::image::read_pfm_rgb(write("be.pfm", bytes), rw, rh);
  ASSERT_EQ(rw, w);
  ASSERT_EQ(rh, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(rgb[size_t((y * w + x) * 3 + c)], 100.0f * float(h - 1 - y) + 10.0f * float(x) + float(c))
            << "x " << x << " y " << y << " c " << c;
}

// "Pf": one float per pixel, replicated to RGB; little-endian (negative scale,
// whose magnitude is not a factor), "\r\n" after the scale as some writers put it.
TEST_F(ImageReaders, PfmGreyIsReplicatedToRgb) {
  std::string bytes = "Pf\n3 2\n-4.0\r\n";
  const float stored[6] = {0.5f, -1.0f, 3.0f, 7.0f, 8.0f, 9.0f};  // row 1 (bottom), then row 0
  for (float v : stored) bytes += float_bytes(v, false);
  int rw = 0, rh = 0;
  const std::vector<float> rgb = dn::image::read_pfm_rgb(write("grey.pfm", bytes), rw, rh);
  ASSERT_EQ(rw, 3);
  ASSERT_EQ(rh, 2);
  const float top_first[6] = {7.0f, 8.0f, 9.0f, 0.5f, -1.0f, 3.0f};
  ASSERT_EQ(rgb.size(), 18u);
  for (size_t i = 0; i < 6; ++i)
    for (size_t c = 0; c < 3; ++c) EXPECT_EQ(rgb[i * 3 + c], top_first[i]) << i;
}

TEST_F(ImageReaders, PfmRefusesWhatItCannotReadNamingFileAndReason) {
  const std::string pixels(2 * 1 * 3 * 4, '\0');
  const struct {
    const char* name;
    std::string bytes;
    const char* reason;
  } cases[] = {
      {"p6.pfm", "P6\n2 1\n255\n" + pixels, "expected 'PF' (colour) or 'Pf' (grey)"},
      {"width.pfm", "PF\n-2 1\n-1\n" + pixels, "bad width '-2'"},
      {"height.pfm", "PF\n2 x\n-1\n" + pixels, "bad height 'x'"},
      {"scale.pfm", "PF\n2 1\n0\n" + pixels, "bad scale '0'"},
      {"short.pfm", "PF\n2 1\n-1\n" + pixels.substr(4), "truncated: 2x1 PF needs 24 bytes of pixels, the file has 20"},
      {"long.pfm", "PF\n2 1\n-1\n" + pixels + "junk", "4 bytes longer than 2x1 PF pixels need"},
      {"empty.pfm", "", "not a PFM"},
  };
  for (const auto& c : cases) {
    const std::string path = write(c.name, c.bytes);
    int w = 0, h = 0;
    const std::string m = error_of([&] { dn::image::read_pfm_rgb(path, w, h); });
    EXPECT_NE(m.find(path), std::string::npos) << m;
    EXPECT_NE(m.find(c.reason), std::string::npos) << m;
  }
  int w = 0, h = 0;
  const std::string m = error_of([&] { dn::image::read_pfm_rgb((dir / "none.pfm").string(), w, h); });
  EXPECT_NE(m.find("none.pfm': cannot read: No such file or directory"), std::string::npos) << m;
}

// ---- PNG ----------------------------------------------------------------------

void put32(std::vector<uint8_t>& out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(uint8_t(v >> s));
}

void chunk(std::vector<uint8_t>& png, const char* type, const std::vector<uint8_t>& data) {
  put32(png, uint32_t(data.size()));
  std::vector<uint8_t> body(type, type + 4);
  body.insert(body.end(), data.begin(), data.end());
  png.insert(png.end(), body.begin(), body.end());
  put32(png, uint32_t(crc32(crc32(0L, Z_NULL, 0), body.data(), uInt(body.size()))));
}

struct PngSpec {
  uint32_t width = 0, height = 0;
  uint8_t depth = 8, colour = 2, interlace = 0;
  std::vector<uint8_t> palette;  // PLTE, when not empty
};

// A PNG of `rows` (unfiltered bytes per scanline), row y filtered with filter
// type `filters[y % filters.size()]` by the forward rules of PNG §9.2.
std::vector<uint8_t> make_png(const PngSpec& s, const std::vector<std::vector<uint8_t>>& rows, size_t bpp,
                              const std::vector<uint8_t>& filters = {0}) {
  std::vector<uint8_t> raw;
  for (size_t y = 0; y < rows.size(); ++y) {
    const uint8_t type = filters[y % filters.size()];
    raw.push_back(type);
    const auto& cur = rows[y];
    for (size_t i = 0; i < cur.size(); ++i) {
      const int a = i >= bpp ? cur[i - bpp] : 0, b = y ? rows[y - 1][i] : 0, c = y && i >= bpp ? rows[y - 1][i - bpp] : 0;
      int predictor = 0;
      if (type == 1) predictor = a;
      if (type == 2) predictor = b;
      if (type == 3) predictor = (a + b) / 2;
      if (type == 4) {
        const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
        predictor = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      raw.push_back(uint8_t(cur[i] - predictor));
    }
  }
  uLongf zsize = compressBound(uLong(raw.size()));
  std::vector<uint8_t> z(zsize);
  EXPECT_EQ(compress2(z.data(), &zsize, raw.data(), uLong(raw.size()), 9), Z_OK);
  z.resize(zsize);
  std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  std::vector<uint8_t> ihdr;
  put32(ihdr, s.width);
  put32(ihdr, s.height);
  ihdr.insert(ihdr.end(), {s.depth, s.colour, 0, 0, s.interlace});
  chunk(png, "IHDR", ihdr);
  chunk(png, "tEXt", {'C', 'o', 'm', 'm', 'e', 'n', 't', 0, 'h', 'i'});  // ancillary: skipped
  if (!s.palette.empty()) chunk(png, "PLTE", s.palette);
  // Two IDAT chunks: the stream continues across them.
  const size_t half = z.size() / 2;
  chunk(png, "IDAT", std::vector<uint8_t>(z.begin(), z.begin() + long(half)));
  chunk(png, "IDAT", std::vector<uint8_t>(z.begin() + long(half), z.end()));
  chunk(png, "IEND", {});
  return png;
}

// The sRGB EOTF (IEC 61966-2-1), in double precision.
float srgb_to_linear(double v) { return float(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4)); }

std::vector<float> decode(const std::vector<uint8_t>& png, int& w, int& h, PngTransfer t = PngTransfer::Srgb) {
  return dn::image::decode_png_rgb(png, "test.png", w, h, t);
}

// 8-bit RGB, one row per filter type (None, Sub, Up, Average, Paeth) and again.
TEST_F(ImageReaders, PngRgb8EveryFilterToLinear) {
  const uint32_t w = 7, h = 10;
  std::vector<std::vector<uint8_t>> rows(h, std::vector<uint8_t>(w * 3));
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t i = 0; i < w * 3; ++i) rows[y][i] = uint8_t((y * 53 + i * 29 + (i * i * y) % 7) & 0xff);
  const std::vector<uint8_t> png = make_png({w, h, 8, 2}, rows, 3, {0, 1, 2, 3, 4});
  int rw = 0, rh = 0;
  const std::vector<float> rgb = dn::image::read_png_rgb(write("rgb8.png", png), rw, rh);
  ASSERT_EQ(rw, int(w));
  ASSERT_EQ(rh, int(h));
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t i = 0; i < w * 3; ++i)
      EXPECT_FLOAT_EQ(rgb[y * w * 3 + i], srgb_to_linear(rows[y][i] / 255.0)) << "y " << y << " i " << i;
  // Spot values of the curve: 0, the linear segment, 50 % grey, white.
  EXPECT_FLOAT_EQ(srgb_to_linear(0.0), 0.0f);
  EXPECT_FLOAT_EQ(srgb_to_linear(10 / 255.0), float(10 / 255.0 / 12.92));
  EXPECT_NEAR(srgb_to_linear(128 / 255.0), 0.2158605, 1e-6);
  EXPECT_FLOAT_EQ(srgb_to_linear(1.0), 1.0f);
}

// 16-bit grey (big-endian samples), replicated to RGB; PngTransfer::Linear is
// v / 65535, Signed 2v / 65535 - 1.
TEST_F(ImageReaders, PngGrey16ToLinear) {
  const uint16_t values[] = {0, 1, 257, 2650, 32768, 65534, 65535, 4096};
  const uint32_t w = 4, h = 2;
  std::vector<std::vector<uint8_t>> rows(h);
  for (uint32_t i = 0; i < w * h; ++i) {
    rows[i / w].push_back(uint8_t(values[i] >> 8));
    rows[i / w].push_back(uint8_t(values[i] & 0xff));
  }
  const std::vector<uint8_t> png = make_png({w, h, 16, 0}, rows, 2, {4, 1});
  int rw = 0, rh = 0;
  const std::vector<float> srgb = decode(png, rw, rh);
  const std::vector<float> linear = decode(png, rw, rh, PngTransfer::Linear);
  const std::vector<float> signed_unit = decode(png, rw, rh, PngTransfer::Signed);
  ASSERT_EQ(srgb.size(), size_t(w * h * 3));
  for (uint32_t i = 0; i < w * h; ++i)
    for (int c = 0; c < 3; ++c) {
      EXPECT_FLOAT_EQ(srgb[i * 3 + uint32_t(c)], srgb_to_linear(values[i] / 65535.0)) << i;
      EXPECT_FLOAT_EQ(linear[i * 3 + uint32_t(c)], float(values[i] / 65535.0)) << i;
      EXPECT_FLOAT_EQ(signed_unit[i * 3 + uint32_t(c)], float(2.0 * values[i] / 65535.0 - 1.0)) << i;
    }
}

// RGBA and grey + alpha: alpha is dropped, whatever its value.
TEST_F(ImageReaders, PngAlphaIsIgnored) {
  const uint32_t w = 3, h = 2;
  std::vector<std::vector<uint8_t>> rgba(h), ga(h);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const uint8_t v = uint8_t(40 * x + 100 * y);
      rgba[y].insert(rgba[y].end(), {v, uint8_t(v + 1), uint8_t(v + 2), uint8_t(x * 100)});
      ga[y].insert(ga[y].end(), {v, uint8_t(255 - x * 100)});
    }
  int rw = 0, rh = 0;
  const std::vector<float> a = decode(make_png({w, h, 8, 6}, rgba, 4, {1, 4}), rw, rh);
  const std::vector<float> b = decode(make_png({w, h, 8, 4}, ga, 2, {2, 3}), rw, rh);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const size_t p = (y * w + x) * 3;
      const uint8_t v = uint8_t(40 * x + 100 * y);
      for (int c = 0; c < 3; ++c) {
        EXPECT_FLOAT_EQ(a[p + size_t(c)], srgb_to_linear((v + c) / 255.0)) << x << "," << y;
        EXPECT_FLOAT_EQ(b[p + size_t(c)], srgb_to_linear(v / 255.0)) << x << "," << y;
      }
    }
}

// Palette images: 8-bit indices, and 2-bit ones packed four to a byte with a
// padded last byte per row (width 5).
TEST_F(ImageReaders, PngPaletteIndicesPackedAndWhole) {
  const std::vector<uint8_t> palette = {0, 0, 0, 255, 0, 0, 10, 128, 255, 200, 200, 30};
  const uint8_t index[2][5] = {{0, 1, 2, 3, 1}, {3, 3, 2, 0, 2}};
  std::vector<std::vector<uint8_t>> packed(2, std::vector<uint8_t>(2, 0)), whole(2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 5; ++x) {
      packed[size_t(y)][size_t(x / 4)] |= uint8_t(index[y][x] << (6 - 2 * (x % 4)));
      whole[size_t(y)].push_back(index[y][x]);
    }
  for (const auto& [png, what] : {std::pair{make_png({5, 2, 2, 3, 0, palette}, packed, 1, {1, 2}), "2-bit"},
                                  std::pair{make_png({5, 2, 8, 3, 0, palette}, whole, 1, {4}), "8-bit"}}) {
    int rw = 0, rh = 0;
    const std::vector<float> rgb = decode(png, rw, rh);
    ASSERT_EQ(rgb.size(), 30u) << what;
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 5; ++x)
        for (int c = 0; c < 3; ++c)
          EXPECT_FLOAT_EQ(rgb[size_t((y * 5 + x) * 3 + c)], srgb_to_linear(palette[size_t(index[y][x] * 3 + c)] / 255.0))
              << what << " " << x << "," << y;
  }
}

TEST_F(ImageReaders, PngInterlacedIsRefusedWithTheReason) {
  PngSpec s{2, 2, 8, 2};
  s.interlace = 1;
  const std::vector<uint8_t> png = make_png(s, {std::vector<uint8_t>(6, 1), std::vector<uint8_t>(6, 2)}, 3);
  const std::string path = write("adam7.png", png);
  int w = 0, h = 0;
  const std::string m = error_of([&] { dn::image::read_png_rgb(path, w, h); });
  EXPECT_NE(m.find("PNG '" + path + "'"), std::string::npos) << m;
  EXPECT_NE(m.find("Adam7-interlaced PNGs are not supported"), std::string::npos) << m;
}

// Every prefix of a valid file is refused as truncated; so is a complete
// chunk list whose zlib stream stops early.
TEST_F(ImageReaders, PngTruncatedIsRefused) {
  std::vector<std::vector<uint8_t>> rows(4, std::vector<uint8_t>(12));
  for (size_t y = 0; y < 4; ++y)
    for (size_t i = 0; i < 12; ++i) rows[y][i] = uint8_t(y * 31 + i * 7);
  const std::vector<uint8_t> png = make_png({4, 4, 8, 2}, rows, 3);
  int w = 0, h = 0;
  EXPECT_NO_THROW(decode(png, w, h));
  for (size_t n = 8; n < png.size(); ++n) {
    const std::string m = error_of([&] { decode(std::vector<uint8_t>(png.begin(), png.begin() + long(n)), w, h); });
    EXPECT_NE(m.find("truncated"), std::string::npos) << n << " bytes: " << m;
  }
  EXPECT_NE(error_of([&] { decode(std::vector<uint8_t>(png.begin(), png.begin() + 5), w, h); }).find("not a PNG file"),
            std::string::npos);

  std::vector<uint8_t> raw;
  for (const auto& r : rows) {
    raw.push_back(0);
    raw.insert(raw.end(), r.begin(), r.end());
  }
  uLongf zsize = compressBound(uLong(raw.size()));
  std::vector<uint8_t> z(zsize);
  ASSERT_EQ(compress2(z.data(), &zsize, raw.data(), uLong(raw.size()), 0), Z_OK);  // stored: bytes map to pixels
  std::vector<uint8_t> cut = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  std::vector<uint8_t> ihdr;
  put32(ihdr, 4);
  put32(ihdr, 4);
  ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});
  chunk(cut, "IHDR", ihdr);
  chunk(cut, "IDAT", std::vector<uint8_t>(z.begin(), z.begin() + 30));
  chunk(cut, "IEND", {});
  const std::string m = error_of([&] { decode(cut, w, h); });
  EXPECT_NE(m.find("truncated pixel data"), std::string::npos) << m;
}

TEST_F(ImageReaders, PngCorruptOrInvalidIsRefusedWithTheReason) {
  const std::vector<std::vector<uint8_t>> rows = {std::vector<uint8_t>(6, 9), std::vector<uint8_t>(6, 7)};
  int w = 0, h = 0;
  std::vector<uint8_t> bad_crc = make_png({2, 2, 8, 2}, rows, 3);
  bad_crc[8 + 8 + 2] ^= 0x01;  // a byte of IHDR's width
  EXPECT_NE(error_of([&] { decode(bad_crc, w, h); }).find("bad CRC in chunk 'IHDR'"), std::string::npos);
  EXPECT_NE(error_of([&] { decode(make_png({2, 2, 16, 3}, rows, 3), w, h); })
                .find("bit depth 16 is invalid for colour type 3"),
            std::string::npos);
  EXPECT_NE(error_of([&] { decode(make_png({2, 2, 8, 3}, {{0, 1}, {1, 0}}, 1), w, h); })
                .find("palette image without a PLTE chunk"),
            std::string::npos);
  EXPECT_NE(error_of([&] { decode(make_png({2, 2, 8, 5}, rows, 3), w, h); }).find("invalid colour type 5"),
            std::string::npos);
  EXPECT_NE(error_of([&] { decode(make_png({2, 2, 8, 2}, rows, 3, {5}), w, h); }).find("row 0 has unknown filter type 5"),
            std::string::npos);
  EXPECT_NE(error_of([&] { dn::image::read_png_rgb((dir / "none.png").string(), w, h); })
                .find("none.png': cannot read: No such file or directory"),
            std::string::npos);
}

}  // namespace
