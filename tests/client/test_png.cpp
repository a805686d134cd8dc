#include <gtest/gtest.h>
#include <zlib.h>

#include <cstring>

#include "dn/image/metrics.hpp"
#include "dn/image/png.hpp"

namespace {

uint32_t be32(const uint8_t* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }

struct Chunk {
  std::string type;
  std::vector<uint8_t> data;
};

// Parses the chunk list, checking every CRC.
std::vector<Chunk> parse(const std::vector<uint8_t>& png) {
  std::vector<Chunk> out;
  size_t at = 8;
  while (at + 12 <= png.size()) {
    const uint32_t len = be32(&png[at]);
    Chunk c;
    c.type.assign(reinterpret_cast<const char*>(&png[at + 4]), 4);
    c.data.assign(png.begin() + long(at + 8), png.begin() + long(at + 8 + len));
    const uint32_t crc = be32(&png[at + 8 + len]);
    uLong expect = crc32(0L, Z_NULL, 0);
    expect = crc32(expect, &png[at + 4], uInt(4 + len));
    EXPECT_EQ(crc, uint32_t(expect)) << "CRC of " << c.type;
    out.push_back(std::move(c));
    at += 12 + len;
  }
  EXPECT_EQ(at, png.size()) << "trailing bytes";
  return out;
}

TEST(Png, SignatureHeaderCrcsAndPixels) {
  const int w = 5, h = 3;
  std::vector<uint8_t> rgb(size_t(w * h * 3));
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = uint8_t(i * 17 + 3);
  const std::vector<uint8_t> png = dn::image::encode_png_rgb8(w, h, rgb.data());

  const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  ASSERT_GE(png.size(), 8u);
  EXPECT_EQ(std::memcmp(png.data(), sig, 8), 0);

  const auto chunks = parse(png);
  ASSERT_GE(chunks.size(), 3u);
  EXPECT_EQ(chunks.front().type, "IHDR");
  EXPECT_EQ(chunks.back().type, "IEND");
  EXPECT_TRUE(chunks.back().data.empty());
  const auto& ihdr = chunks.front().data;
  ASSERT_EQ(ihdr.size(), 13u);
  EXPECT_EQ(be32(&ihdr[0]), uint32_t(w));
  EXPECT_EQ(be32(&ihdr[4]), uint32_t(h));
  EXPECT_EQ(ihdr[8], 8);   // bit depth
  EXPECT_EQ(ihdr[9], 2);   // RGB
  EXPECT_EQ(ihdr[10], 0);  // deflate
  EXPECT_EQ(ihdr[11], 0);  // filter method
  EXPECT_EQ(ihdr[12], 0);  // no interlace

  std::vector<uint8_t> idat;
  for (const auto& c : chunks)
    if (c.type == "IDAT") idat.insert(idat.end(), c.data.begin(), c.data.end());
  std::vector<uint8_t> raw(size_t(h) * (1 + size_t(w) * 3) + 16);
  uLongf raw_len = uLongf(raw.size());
  ASSERT_EQ(uncompress(raw.data(), &raw_len, idat.data(), uLong(idat.size())), Z_OK);
  ASSERT_EQ(raw_len, uLongf(h * (1 + w * 3)));
  for (int y = 0; y < h; ++y) {
    const uint8_t* row = raw.data() + size_t(y) * (1 + size_t(w) * 3);
    EXPECT_EQ(row[0], 0) << "filter type of row " << y;
    EXPECT_EQ(std::memcmp(row + 1, rgb.data() + size_t(y) * size_t(w) * 3, size_t(w) * 3), 0) << "row " << y;
  }
}

TEST(Png, ToSrgb8UsesToneMapAndOetf) {
  const float px[6] = {0.0f, 1e9f, -1.0f, 0.5f, 0.5f, 0.5f};
  const auto v = dn::image::to_srgb8(px, 2, dn::image::Tonemap::Clamp);
  EXPECT_EQ(v[0], 0);
  EXPECT_EQ(v[1], 255);
  EXPECT_EQ(v[2], 0);
  EXPECT_EQ(v[3], 188);  // sRGB(0.5) = 0.7354 -> 187.5 -> 188
}

}  // namespace
