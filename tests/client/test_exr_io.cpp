#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>

#include "dn/image/exr_io.hpp"

namespace {

using namespace dn::image;

std::string tmp(const std::string& name) {
  return "/tmp/dn_client_test_" + std::to_string(::getpid()) + "_" + name;
}

std::vector<float> ramp(size_t n, float scale) {
  std::vector<float> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = scale * float(i) - 3.0f + 0.123f * float(i % 7);
  return v;
}

TEST(ExrIo, FloatRoundTripIsExact) {
  const int w = 7, h = 5;
  const auto rgb = ramp(size_t(w * h * 3), 0.37f);
  const std::string path = tmp("float.exr");
  write_exr_rgb(path, w, h, rgb.data(), ExrPixelType::Float);
  int rw = 0, rh = 0;
  const auto back = read_exr_rgb(path, rw, rh);
  EXPECT_EQ(rw, w);
  EXPECT_EQ(rh, h);
  ASSERT_EQ(back.size(), rgb.size());
  for (size_t i = 0; i < rgb.size(); ++i) EXPECT_EQ(back[i], rgb[i]) << i;
  std::remove(path.c_str());
}

TEST(ExrIo, HalfRoundTripWithinHalfPrecision) {
  const int w = 9, h = 4;
  const auto rgb = ramp(size_t(w * h * 3), 1.5f);
  const std::string path = tmp("half.exr");
  write_exr_rgb(path, w, h, rgb.data(), ExrPixelType::Half);
  ExrReader r(path);
  EXPECT_EQ(r.channels(), (std::vector<std::string>{"B", "G", "R"}));
  const auto back = r.read({"R", "G", "B"});
  ASSERT_EQ(back.size(), rgb.size());
  for (size_t i = 0; i < rgb.size(); ++i)
    EXPECT_NEAR(back[i], rgb[i], std::fabs(rgb[i]) * 1.0e-3f + 1e-4f) << i;
  std::remove(path.c_str());
}

TEST(ExrIo, LayersAttributesAndMissingChannels) {
  const int w = 3, h = 2;
  const auto rgb = ramp(size_t(w * h * 3), 1.0f);
  const auto depth = ramp(size_t(w * h), 2.0f);
  ExrWriteOptions o;
  std::array<float, 16> view{};
  for (int i = 0; i < 16; ++i) view[size_t(i)] = float(i) + 0.5f;
  o.camera.view = view;
  o.camera.projection = view;
  o.camera.jitter = std::array<float, 2>{0.25f, -0.125f};
  o.strings["dn.renderer"] = "test";
  const std::string path = tmp("layers.exr");
  write_exr(path, w, h,
            {{"radiance.R", rgb.data() + 0, 3, ExrPixelType::Float},
             {"radiance.G", rgb.data() + 1, 3, ExrPixelType::Float},
             {"radiance.B", rgb.data() + 2, 3, ExrPixelType::Float},
             {"depth.Z", depth.data(), 1, ExrPixelType::Float}},
            o);
  ExrReader r(path);
  EXPECT_TRUE(r.has_channel("radiance.G"));
  EXPECT_FALSE(r.has_channel("R"));
  // Interleaved read of mixed channels, an empty name reads zeros, duplicates are allowed.
  const auto v = r.read({"depth.Z", "radiance.B", "", "depth.Z"});
  for (size_t i = 0; i < size_t(w * h); ++i) {
    EXPECT_EQ(v[i * 4 + 0], depth[i]);
    EXPECT_EQ(v[i * 4 + 1], rgb[i * 3 + 2]);
    EXPECT_EQ(v[i * 4 + 2], 0.0f);
    EXPECT_EQ(v[i * 4 + 3], depth[i]);
  }
  const ExrCamera cam = r.camera();
  ASSERT_TRUE(cam.view && cam.projection && cam.jitter);
  EXPECT_EQ(*cam.view, view);
  EXPECT_EQ((*cam.jitter)[1], -0.125f);
  EXPECT_FALSE(cam.prev_view);
  EXPECT_EQ(r.string_attribute("dn.renderer"), "test");
  // read_exr_rgb falls back to the first layer with .R/.G/.B.
  int rw, rh;
  EXPECT_EQ(read_exr_rgb(path, rw, rh)[5], rgb[5]);
  try {
    r.read({"albedo.R"});
    FAIL();
  } catch (const ImageError& e) {
    EXPECT_NE(std::string(e.what()).find("albedo.R"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
  std::remove(path.c_str());
}

TEST(ExrIo, MissingFileNamesThePath) {
  try {
    ExrReader r("/nonexistent/dir/frame_0001.exr");
    FAIL();
  } catch (const ImageError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/frame_0001.exr"), std::string::npos);
  }
}

}  // namespace
