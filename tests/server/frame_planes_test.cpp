// frame_planes(): a FRAME's planes are checked once against the session (each
// declared channel exactly once, in its declared format, of its exact size)
// and handed over in declaration order; the motion convention becomes one
// scale to pixels towards the previous frame.
#include <gtest/gtest.h>

#include "frames.hpp"
#include "session/frame_planes.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

pipelines::SessionConfig config_3x2() {
  return test::make_config("accumulate", 3, 2,
                           {{ChannelId::Radiance, Format::F32}, {ChannelId::Normal, Format::F16},
                            {ChannelId::Depth, Format::F32}, {ChannelId::Motion, Format::F32}});
}

test::HostFrame frame_3x2() {
  test::HostFrame f;  // sent in another order than declared
  f.add(ChannelId::Motion, Format::F32, std::vector<float>(3 * 2 * 2, 0.5f));
  f.add(ChannelId::Depth, Format::F32, std::vector<float>(3 * 2, 2.0f));
  f.add(ChannelId::Radiance, Format::F32, std::vector<float>(3 * 2 * 3, 1.0f));
  f.add(ChannelId::Normal, Format::F16, std::vector<float>(3 * 2 * 3, 0.0f));
  return f;
}

server::PlaneProblem problem_of(const test::HostFrame& f) {
  auto r = server::frame_planes(f.view(), config_3x2());
  EXPECT_TRUE(std::holds_alternative<server::PlaneProblem>(r));
  return std::holds_alternative<server::PlaneProblem>(r) ? std::get<server::PlaneProblem>(r) : server::PlaneProblem{};
}

TEST(FramePlanes, PlanesComeInDeclarationOrder) {
  const test::HostFrame f = frame_3x2();
  const auto input = server::frame_planes_or_throw(f.view(), config_3x2());
  ASSERT_EQ(input.planes.size(), 4u);
  EXPECT_EQ(input.planes[0].data(), f.plane(ChannelId::Radiance).bytes.data());
  EXPECT_EQ(input.planes[1].data(), f.plane(ChannelId::Normal).bytes.data());
  EXPECT_EQ(input.planes[1].size(), 3u * 2 * 3 * 2);  // fp16 on the wire
  EXPECT_EQ(input.planes[2].data(), f.plane(ChannelId::Depth).bytes.data());
  EXPECT_EQ(input.planes[3].data(), f.plane(ChannelId::Motion).bytes.data());
  EXPECT_FALSE(input.reset);
}

TEST(FramePlanes, EachPlaneProblemIsNamed) {
  test::HostFrame f = frame_3x2();
  f.add(ChannelId::Albedo, Format::F32, std::vector<float>(3 * 2 * 3, 1.0f));
  auto p = problem_of(f);
  EXPECT_FALSE(p.missing);
  EXPECT_EQ(p.field, "FRAME.planes[4].channel");
  EXPECT_NE(p.message.find("'albedo' was not declared"), std::string::npos) << p.message;

  f = frame_3x2();
  f.add(ChannelId::Depth, Format::F32, std::vector<float>(3 * 2, 2.0f));
  p = problem_of(f);
  EXPECT_EQ(p.field, "FRAME.planes[4].channel");
  EXPECT_NE(p.message.find("'depth' sent twice"), std::string::npos) << p.message;

  f = frame_3x2();
  f.planes[3] = {ChannelId::Normal, Format::F32, test::encode_plane(std::vector<float>(3 * 2 * 3, 0.0f), Format::F32)};
  p = problem_of(f);
  EXPECT_EQ(p.field, "FRAME.planes[3].format");
  EXPECT_NE(p.message.find("'normal' was declared fp16 but sent as fp32"), std::string::npos) << p.message;

  f = frame_3x2();
  f.planes[1].bytes.pop_back();
  p = problem_of(f);
  EXPECT_EQ(p.field, "FRAME.planes[1].byte_length");
  EXPECT_NE(p.message.find("'depth' has 23 bytes, expected 24 (3x2x1)"), std::string::npos) << p.message;

  f = frame_3x2();
  f.planes.erase(f.planes.begin());
  p = problem_of(f);
  EXPECT_TRUE(p.missing);
  EXPECT_EQ(p.field, "FRAME.planes");
  EXPECT_NE(p.message.find("'motion' declared at OPEN_SESSION is missing"), std::string::npos) << p.message;

  EXPECT_THROW(server::frame_planes_or_throw(f.view(), config_3x2()), std::invalid_argument);
}

TEST(FramePlanes, MotionConventionsBecomeOneScaleToPreviousPixels) {
  test::HostFrame f = frame_3x2();
  const std::pair<protocol::MotionConvention, std::array<float, 2>> cases[] = {
      {protocol::MotionConvention::PixelsToPrevious, {1.0f, 1.0f}},
      {protocol::MotionConvention::PixelsToNext, {-1.0f, -1.0f}},
      {protocol::MotionConvention::UvToPrevious, {3.0f, 2.0f}}};
  for (const auto& [convention, scale] : cases) {
    f.info.motion = convention;
    EXPECT_EQ(server::frame_planes_or_throw(f.view(), config_3x2()).motion_to_previous_pixels, scale);
  }
}

TEST(FramePlanes, ResetAndCameraPassThrough) {
  test::HostFrame f = frame_3x2();
  f.info.flags = protocol::kFrameReset;
  for (int i = 0; i < 16; ++i) {
    f.info.view[i] = static_cast<float>(i);
    f.info.projection[i] = static_cast<float>(100 + i);
  }
  const auto input = server::frame_planes_or_throw(f.view(), config_3x2());
  EXPECT_TRUE(input.reset);
  EXPECT_EQ(input.view, f.info.view);
  EXPECT_EQ(input.projection, f.info.projection);
}

}  // namespace
}  // namespace dn
