// Camera recovery from the Position pass (client/tools/camera_recovery.hpp):
// synthetic pinhole cameras (glm::lookAt / perspective / off-centre frustum)
// over a non-planar scene, real dnrender frames against their dn.* header,
// the refusals (orthographic, fisheye, a single plane, too few pixels) and
// `dn denoise` choosing the camera (file > header > Position pass).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <random>

#include "camera_recovery.hpp"
#include "commands.hpp"
#include "dn/image/exr_io.hpp"
#include "fake_server.hpp"
#include "frame_source.hpp"

namespace {

using namespace dn;
namespace fs = std::filesystem;

// A room: floor y = 0, back wall z = -6, left wall x = -4, and two boxes.
struct Box {
  glm::vec3 lo, hi;
};
const Box kBoxes[] = {{{-1.0f, 0.0f, -3.0f}, {0.0f, 1.0f, -2.0f}}, {{1.0f, 0.0f, -4.5f}, {2.0f, 2.5f, -3.5f}}};

float intersect_scene(const glm::vec3& o, const glm::vec3& d) {
  float best = INFINITY;
  auto plane = [&](int axis, float value) {
    if (d[axis] == 0.0f) return;
    const float t = (value - o[axis]) / d[axis];
    if (t > 1e-4f && t < best) best = t;
  };
  plane(1, 0.0f);
  plane(2, -6.0f);
  plane(0, -4.0f);
  for (const Box& b : kBoxes) {
    float t0 = 0.0f, t1 = INFINITY;
    for (int a = 0; a < 3; ++a) {
      const float inv = 1.0f / d[a];
      float ta = (b.lo[a] - o[a]) * inv, tb = (b.hi[a] - o[a]) * inv;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (t0 <= t1 && t0 > 1e-4f && t0 < best) best = t0;
  }
  return best;
}

struct Frame {
  std::vector<float> position, depth;
};

// Casts a ray through every pixel centre of the camera (view, projection) and
// stores the hit (background: NaN position, +inf depth).
Frame render_positions(const glm::mat4& view, const glm::mat4& projection, int w, int h) {
  const glm::dmat4 inv = glm::inverse(glm::dmat4(projection) * glm::dmat4(view));
  const glm::dvec3 eye = glm::dvec3(glm::inverse(glm::dmat4(view))[3]);  // double: the rays start at the exact centre
  Frame f;
  f.position.assign(size_t(w * h * 3), NAN);
  f.depth.assign(size_t(w * h), INFINITY);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const glm::dvec2 ndc(2.0 * (x + 0.5) / w - 1.0, 1.0 - 2.0 * (y + 0.5) / h);
      glm::dvec4 a = inv * glm::dvec4(ndc, -1.0, 1.0), b = inv * glm::dvec4(ndc, 1.0, 1.0);
      const glm::dvec3 dir = glm::normalize(glm::dvec3(b) / b.w - glm::dvec3(a) / a.w);
      const float t = intersect_scene(glm::vec3(eye), glm::vec3(dir));
      if (!std::isfinite(t)) continue;
      const glm::dvec3 p = eye + double(t) * dir;
      const size_t i = size_t(y * w + x);
      for (int k = 0; k < 3; ++k) f.position[3 * i + size_t(k)] = float(p[k]);
      f.depth[i] = float(-(glm::dmat4(view) * glm::dvec4(p, 1.0)).z);
    }
  return f;
}

glm::dmat4 to_mat(const std::array<float, 16>& m) { return glm::dmat4(glm::make_mat4(m.data())); }

glm::dvec2 to_pixel(const glm::dmat4& vp, const glm::dvec3& p, int w, int h) {
  const glm::dvec4 c = vp * glm::dvec4(p, 1.0);
  return {(c.x / c.w + 1.0) * 0.5 * w, (1.0 - c.y / c.w) * 0.5 * h};
}

// The quantities the matrices determine: camera centre, forward axis, pixel
// projection of points in front, and the view ray through pixel centres
// (what svgf-fb computes from inverse(projection * view)). Returns the worst.
struct Agreement {
  double centre = 0, forward = 0, pixel = 0, ray = 0;
};
Agreement compare(const glm::dmat4& view, const glm::dmat4& projection, const cli::RecoveredCamera& c, int w, int h) {
  Agreement a;
  const glm::dmat4 rv = to_mat(c.view), rp = to_mat(c.projection);
  const glm::dvec3 eye = glm::dvec3(glm::inverse(view)[3]);
  const glm::dvec3 forward = -glm::dvec3(glm::transpose(view)[2]);
  a.centre = glm::length(glm::dvec3(c.centre[0], c.centre[1], c.centre[2]) - eye);
  a.centre = std::max(a.centre, glm::length(glm::dvec3(glm::inverse(rv)[3]) - eye));
  a.forward = glm::length(glm::dvec3(c.forward[0], c.forward[1], c.forward[2]) - forward);
  a.forward = std::max(a.forward, glm::length(-glm::dvec3(glm::transpose(rv)[2]) - forward));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0), z(1.0, 20.0);
  const glm::dmat4 inv = glm::inverse(projection * view);
  for (int i = 0; i < 200; ++i) {  // points inside the view frustum at 1..20 units
    const glm::dvec4 q = inv * glm::dvec4(u(rng), u(rng), 1.0, 1.0);
    const glm::dvec3 dir = glm::normalize(glm::dvec3(q) / q.w - eye);
    const glm::dvec3 p = eye + z(rng) * dir;
    a.pixel = std::max(a.pixel, glm::length(to_pixel(projection * view, p, w, h) - to_pixel(rp * rv, p, w, h)));
  }
  const glm::dmat4 rinv = glm::inverse(rp * rv);
  for (int y = 0; y < h; y += 7)
    for (int x = 0; x < w; x += 7) {
      const glm::dvec2 ndc(2.0 * (x + 0.5) / w - 1.0, 1.0 - 2.0 * (y + 0.5) / h);
      auto ray = [&](const glm::dmat4& m) {
        const glm::dvec4 n = m * glm::dvec4(ndc, -1.0, 1.0), f = m * glm::dvec4(ndc, 1.0, 1.0);
        return glm::normalize(glm::dvec3(f) / f.w - glm::dvec3(n) / n.w);
      };
      a.ray = std::max(a.ray, glm::length(ray(inv) - ray(rinv)));
    }
  return a;
}

void expect_recovered(const glm::mat4& view, const glm::mat4& projection, int w, int h, double tol = 1e-4) {
  const Frame f = render_positions(view, projection, w, h);
  const cli::RecoveredCamera c = cli::recover_camera(f.position, w, h, f.depth);
  const Agreement a = compare(view, projection, c, w, h);
  EXPECT_LE(a.centre, tol);
  EXPECT_LE(a.forward, tol);
  EXPECT_LE(a.pixel, tol);
  EXPECT_LE(a.ray, tol);
  EXPECT_LE(c.rms_px, 1e-3);
  EXPECT_LE(c.points, 4096u);
  EXPECT_EQ(c.rejected, 0u);
  // The projection is a perspective one with the chosen planes around the points.
  EXPECT_GT(c.near_plane, 0.0);
  EXPECT_GT(c.far_plane, c.near_plane);
  EXPECT_FLOAT_EQ(c.projection[11], -1.0f);
  EXPECT_FLOAT_EQ(c.projection[15], 0.0f);
  std::printf("centre %.2e  forward %.2e  pixel %.2e px  ray %.2e  rms %.2e px  (%zu points)\n", a.centre, a.forward,
              a.pixel, a.ray, c.rms_px, c.points);
}

TEST(CameraRecovery, LookAtPerspective) {
  const glm::mat4 view = glm::lookAt(glm::vec3(0.5f, 1.6f, 3.0f), glm::vec3(0.0f, 0.8f, -3.0f), glm::vec3(0, 1, 0));
  expect_recovered(view, glm::perspective(glm::radians(50.0f), 64.0f / 36.0f, 0.1f, 100.0f), 64, 36);
}

TEST(CameraRecovery, RolledCameraSubsampledLargerFrame) {
  // 256x144 = 36864 pixels: a stratified subsample of at most 4096.
  const glm::mat4 view = glm::lookAt(glm::vec3(-2.0f, 2.5f, 2.0f), glm::vec3(1.0f, 0.5f, -4.0f),
                                     glm::normalize(glm::vec3(0.3f, 1.0f, 0.0f)));
  expect_recovered(view, glm::perspective(glm::radians(70.0f), 256.0f / 144.0f, 0.05f, 50.0f), 256, 144);
}

TEST(CameraRecovery, OffCentreFrustum) {
  // Blender's lens shift: an asymmetric frustum, principal point off the image centre.
  const glm::mat4 view = glm::lookAt(glm::vec3(1.0f, 1.2f, 2.5f), glm::vec3(0.0f, 1.0f, -5.0f), glm::vec3(0, 1, 0));
  expect_recovered(view, glm::frustum(-0.08f, 0.12f, -0.04f, 0.0725f, 0.1f, 100.0f), 96, 54);
}

TEST(CameraRecovery, BackgroundMarkersAreIgnored) {
  // All-zero positions (Cycles' background) without a depth plane.
  const glm::mat4 view = glm::lookAt(glm::vec3(0.0f, 1.5f, 3.0f), glm::vec3(0.5f, 0.5f, -3.0f), glm::vec3(0, 1, 0));
  const glm::mat4 proj = glm::perspective(glm::radians(60.0f), 64.0f / 36.0f, 0.1f, 100.0f);
  Frame f = render_positions(view, proj, 64, 36);
  for (size_t i = 0; i < f.depth.size(); i += 5)
    for (int k = 0; k < 3; ++k) f.position[3 * i + size_t(k)] = 0.0f;
  for (float& v : f.position)
    if (!std::isfinite(v)) v = 0.0f;
  const cli::RecoveredCamera c = cli::recover_camera(f.position, 64, 36);
  EXPECT_LE(compare(view, proj, c, 64, 36).pixel, 1e-4);
}

std::string error_of(const std::vector<float>& position, int w, int h, const std::vector<float>& depth = {}) {
  try {
    cli::recover_camera(position, w, h, depth);
  } catch (const cli::CameraRecoveryError& e) {
    return e.what();
  }
  return "";
}

TEST(CameraRecovery, OrthographicIsRefused) {
  const int w = 64, h = 36;
  const glm::mat4 view = glm::lookAt(glm::vec3(0.5f, 2.0f, 3.0f), glm::vec3(0.0f, 0.8f, -3.0f), glm::vec3(0, 1, 0));
  const glm::vec3 eye = glm::vec3(glm::inverse(view)[3]);
  const glm::mat3 axes = glm::mat3(glm::inverse(view));  // right, up, back
  std::vector<float> pos(size_t(w * h * 3), NAN);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const glm::vec3 o = eye + axes[0] * (4.0f * ((x + 0.5f) / w - 0.5f) * w / h) + axes[1] * (4.0f * (0.5f - (y + 0.5f) / h));
      const float t = intersect_scene(o, -axes[2]);
      if (std::isfinite(t)) {
        const glm::vec3 p = o - t * axes[2];
        for (int k = 0; k < 3; ++k) pos[size_t(3 * (y * w + x) + k)] = p[k];
      }
    }
  const std::string e = error_of(pos, w, h);
  EXPECT_NE(e.find("not a perspective camera"), std::string::npos) << e;
  EXPECT_NE(e.find("Type must be Perspective"), std::string::npos) << e;
  EXPECT_NE(e.find("--camera FILE"), std::string::npos) << e;
}

TEST(CameraRecovery, FisheyeIsRefused) {
  // Equidistant fisheye, 180 degrees across the width.
  const int w = 128, h = 72;
  const glm::mat4 view = glm::lookAt(glm::vec3(0.5f, 1.5f, 2.0f), glm::vec3(0.0f, 0.8f, -3.0f), glm::vec3(0, 1, 0));
  const glm::vec3 eye = glm::vec3(glm::inverse(view)[3]);
  const glm::mat3 axes = glm::mat3(glm::inverse(view));
  std::vector<float> pos(size_t(w * h * 3), NAN);
  const float f = float(w) / 3.14159265f;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float dx = x + 0.5f - w / 2.0f, dy = h / 2.0f - (y + 0.5f);
      const float r = std::sqrt(dx * dx + dy * dy), theta = r / f;
      const float phi = std::atan2(dy, dx);
      const glm::vec3 d = axes[0] * (std::sin(theta) * std::cos(phi)) + axes[1] * (std::sin(theta) * std::sin(phi)) -
                          axes[2] * std::cos(theta);
      const float t = intersect_scene(eye, d);
      if (std::isfinite(t)) {
        const glm::vec3 p = eye + t * d;
        for (int k = 0; k < 3; ++k) pos[size_t(3 * (y * w + x) + k)] = p[k];
      }
    }
  const std::string e = error_of(pos, w, h);
  EXPECT_NE(e.find("not consistent with a pinhole camera"), std::string::npos) << e;
  EXPECT_NE(e.find("Type must be Perspective"), std::string::npos) << e;
}

TEST(CameraRecovery, SinglePlaneIsRefused) {
  // A camera looking down at the floor: every pixel on y = 0.
  const glm::mat4 view = glm::lookAt(glm::vec3(0.0f, 1.0f, 0.0f), glm::vec3(0.0f, 0.0f, -0.6f), glm::vec3(0, 1, 0));
  const glm::mat4 proj = glm::perspective(glm::radians(40.0f), 64.0f / 36.0f, 0.1f, 100.0f);
  const Frame f = render_positions(view, proj, 64, 36);
  for (size_t i = 0; i < f.depth.size(); ++i) ASSERT_NEAR(f.position[3 * i + 1], 0.0f, 1e-5f);
  const std::string e = error_of(f.position, 64, 36, f.depth);
  EXPECT_NE(e.find("lie on one plane"), std::string::npos) << e;
  EXPECT_NE(e.find("--camera FILE"), std::string::npos) << e;
}

TEST(CameraRecovery, TooFewPixelsAreRefused) {
  const glm::mat4 view = glm::lookAt(glm::vec3(0.5f, 1.6f, 3.0f), glm::vec3(0.0f, 0.8f, -3.0f), glm::vec3(0, 1, 0));
  Frame f = render_positions(view, glm::perspective(glm::radians(50.0f), 16.0f / 9.0f, 0.1f, 100.0f), 16, 9);
  for (size_t i = 10; i < f.depth.size(); ++i) f.depth[i] = INFINITY;
  const std::string e = error_of(f.position, 16, 9, f.depth);
  EXPECT_NE(e.find("only 10 usable pixels"), std::string::npos) << e;
}

// ---- real dnrender frames: the header's camera against the recovered one ----

#ifdef DN_TEST_DNRENDER
TEST(CameraRecovery, DnrenderFramesMatchTheirHeaders) {
  const fs::path dir = fs::path("/tmp") / ("dn_camera_dnrender_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string cmd = std::string(DN_TEST_DNRENDER) + " --scene 1 --frames 2 --width 64 --height 36 --spp 1 --out " +
                          dir.string() + " --quiet > /dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().filename().string().rfind("frame_", 0) != 0) continue;
    image::ExrReader exr(entry.path().string());
    const image::ExrCamera cam = exr.camera();
    ASSERT_TRUE(cam.view && cam.projection);
    const int w = exr.width(), h = exr.height();
    const std::vector<float> pos = exr.read({"position.X", "position.Y", "position.Z"});
    const std::vector<float> depth = exr.read_channel("depth.Z");
    const cli::RecoveredCamera c = cli::recover_camera(pos, w, h, depth);
    const glm::mat4 view = glm::make_mat4(cam.view->data()), proj = glm::make_mat4(cam.projection->data());
    const Agreement a = compare(view, proj, c, w, h);
    // dnrender makes its G-buffer rays in float (CameraRays): its positions sit up to ~5e-4 px off its own
    // header camera, while the recovered camera fits them to ~2e-6 px. So the pixel agreement is checked in
    // NDC units (2 px / width), the unit the matrices work in.
    double header_rms = 0;
    size_t n = 0;
    const glm::dmat4 vp = glm::dmat4(proj) * glm::dmat4(view);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y * w + x);
        if (!std::isfinite(depth[i])) continue;
        const glm::dvec2 d = to_pixel(vp, {pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]}, w, h) - glm::dvec2(x + 0.5, y + 0.5);
        header_rms += glm::dot(d, d);
        ++n;
      }
    header_rms = std::sqrt(header_rms / double(n));
    std::printf("%s: centre %.2e  forward %.2e  pixel %.2e px (%.2e NDC)  ray %.2e  rms %.2e px (header camera on "
                "the same pixels: %.2e px)  (%zu points, %zu rejected)\n",
                entry.path().filename().c_str(), a.centre, a.forward, a.pixel, 2.0 * a.pixel / w, a.ray, c.rms_px,
                header_rms, c.points, c.rejected);
    EXPECT_LE(a.centre, 1e-4);
    EXPECT_LE(a.forward, 1e-4);
    EXPECT_LE(2.0 * a.pixel / w, 1e-4);
    EXPECT_LE(a.ray, 1e-4);
    EXPECT_LE(c.rms_px, 1e-4);
    ++checked;
  }
  EXPECT_EQ(checked, 2);
  fs::remove_all(dir);
}
#endif

// ---- dn denoise: which camera is sent ----

struct Log {
  std::vector<protocol::FrameInfo> infos;
  int sessions_opened = 0;
};

void recording_server(test::Peer& peer, Log& log) {
  protocol::Welcome w = test::test_welcome();
  protocol::PipelineInfo fb;
  fb.name = "svgf-fb";
  // It requires specular_f0, so it computes F_beta from the view direction and needs a camera.
  fb.required_channels =
      protocol::channel_bit(protocol::ChannelId::Radiance) | protocol::channel_bit(protocol::ChannelId::SpecularF0);
  w.pipelines.push_back(fb);
  // Accepts every channel, uses none but radiance.
  protocol::PipelineInfo passthrough;
  passthrough.name = "passthrough";
  passthrough.required_channels = protocol::channel_bit(protocol::ChannelId::Radiance);
  for (const auto& c : protocol::kChannels)
    if (c.id != protocol::ChannelId::Radiance && c.id != protocol::ChannelId::Output)
      passthrough.optional_channels |= protocol::channel_bit(c.id);
  w.pipelines.push_back(passthrough);
  peer.handshake_with(w);
  for (;;) {
    auto m = peer.recv(10000);
    if (!m) return;
    const uint64_t id = m->header.request_id;
    if (auto* o = std::get_if<protocol::OpenSession>(&m->message)) {
      ++log.sessions_opened;
      protocol::Session s;
      s.session_id = 5;
      s.width = o->width;
      s.height = o->height;
      s.pipeline = o->pipeline;
      s.output_format = o->output_format;
      s.channels = o->channels;
      s.watch_key = "00112233445566778899aabbccddeeff";
      s.watch_url = "";  // a 1.8 server's SESSION ends with the watch URL
      peer.send(s, id);
    } else if (auto* f = std::get_if<protocol::Frame>(&m->message)) {
      log.infos.push_back(f->info);
      protocol::Result r;
      r.session_id = f->info.session_id;
      r.frame_index = f->info.frame_index;
      peer.send(r, id);
    } else if (auto* c = std::get_if<protocol::CloseSession>(&m->message)) {
      peer.send(protocol::SessionClosed{c->session_id, log.infos.size()}, id);
    }
  }
}

class DenoiseCamera : public ::testing::Test {
 protected:
  static constexpr int W = 64, H = 36;
  void SetUp() override {
    dir = fs::path("/tmp") / ("dn_camera_cli_" + std::to_string(::getpid()) + "_" +
                              ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
    proj = glm::perspective(glm::radians(50.0f), float(W) / H, 0.1f, 100.0f);
    for (int frame = 1; frame <= 2; ++frame) {
      views.push_back(glm::lookAt(glm::vec3(0.3f * frame, 1.6f, 3.0f), glm::vec3(0.0f, 0.8f, -3.0f), glm::vec3(0, 1, 0)));
      const Frame f = render_positions(views.back(), proj, W, H);
      std::vector<float> rgb(size_t(W * H * 3), 0.5f), pos = f.position;
      for (float& v : pos)
        if (!std::isfinite(v)) v = 0.0f;  // Cycles' background
      const std::string L = "ViewLayer.";
      std::vector<image::ExrChannelOut> ch;
      for (int k = 0; k < 3; ++k) {
        ch.push_back({L + "Combined." + "RGB"[k], rgb.data() + k, 3, image::ExrPixelType::Half});
        ch.push_back({L + "SpecularF0." + "RGB"[k], rgb.data() + k, 3, image::ExrPixelType::Half});
        ch.push_back({L + "Position." + "XYZ"[k], pos.data() + k, 3, image::ExrPixelType::Float});
      }
      image::write_exr(cli::format_frame_path((dir / "f_%04d.exr").string(), frame), W, H, ch);
    }
  }
  void TearDown() override { fs::remove_all(dir); }
  std::vector<std::string> args(const std::string& url, const std::string& pipeline = "svgf-fb") {
    return {"--server", url, "--pipeline", pipeline, "--input", (dir / "f_%04d.exr").string(),
            "--start", "1", "--end", "2", "--quiet"};
  }
  fs::path dir;
  glm::mat4 proj;
  std::vector<glm::mat4> views;
};

TEST_F(DenoiseCamera, RecoversFromThePositionPassWithoutHeaders) {
  Log log;
  test::FakeServer server([&](test::Peer& p) { recording_server(p, log); });
  EXPECT_EQ(cli::run_denoise(args(server.url())), 0);
  server.join();
  ASSERT_EQ(log.infos.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const glm::dmat4 vp = to_mat(log.infos[i].projection) * to_mat(log.infos[i].view);
    const glm::dmat4 expected = glm::dmat4(proj) * glm::dmat4(views[i]);
    for (const glm::dvec3 p : {glm::dvec3(0, 0, -3), glm::dvec3(1, 1, -4), glm::dvec3(-1, 0.5, -2)})
      EXPECT_LE(glm::length(to_pixel(vp, p, W, H) - to_pixel(expected, p, W, H)), 1e-4);
  }
  // The previous camera is still the previous frame's.
  EXPECT_EQ(log.infos[1].prev_view, log.infos[0].view);
  EXPECT_EQ(log.infos[1].prev_projection, log.infos[0].projection);
}

TEST_F(DenoiseCamera, CameraFileTakesPrecedence) {
  std::ofstream out(dir / "cams.txt");
  out << std::setprecision(9) << "# test cameras\n";
  for (int frame = 1; frame <= 2; ++frame) {
    out << "frame " << frame << " view";
    for (int k = 0; k < 16; ++k) out << ' ' << (k % 5 == 0 ? 1 : 0) + (k == 12 ? frame : 0);
    out << " projection";
    for (int k = 0; k < 16; ++k) out << ' ' << glm::value_ptr(proj)[k];
    out << "  # frame " << frame << "\n";
  }
  out.close();
  Log log;
  test::FakeServer server([&](test::Peer& p) { recording_server(p, log); });
  auto a = args(server.url());
  a.push_back("--camera");
  a.push_back((dir / "cams.txt").string());
  EXPECT_EQ(cli::run_denoise(a), 0);
  server.join();
  ASSERT_EQ(log.infos.size(), 2u);
  EXPECT_EQ(log.infos[0].view[12], 1.0f);
  EXPECT_EQ(log.infos[1].view[12], 2.0f);
  EXPECT_EQ(log.infos[1].prev_view[12], 1.0f);
  EXPECT_EQ(log.infos[1].projection[0], glm::value_ptr(proj)[0]);
}

TEST_F(DenoiseCamera, NoCameraAtAllIsAnErrorForSvgfFb) {
  // Frames without a Position pass and without headers.
  for (int frame = 1; frame <= 2; ++frame) {
    std::vector<float> rgb(size_t(W * H * 3), 0.5f);
    std::vector<image::ExrChannelOut> ch;
    for (int k = 0; k < 3; ++k) {
      ch.push_back({std::string(1, "RGB"[k]), rgb.data() + k, 3, image::ExrPixelType::Half});
      ch.push_back({std::string("specular_f0.") + "RGB"[k], rgb.data() + k, 3, image::ExrPixelType::Half});
    }
    image::write_exr(cli::format_frame_path((dir / "f_%04d.exr").string(), frame), W, H, ch);
  }
  Log log;
  test::FakeServer server([&](test::Peer& p) { recording_server(p, log); });
  try {
    cli::run_denoise(args(server.url()));
    ADD_FAILURE() << "no error";
  } catch (const std::exception& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("frame 1: "), std::string::npos) << m;
    EXPECT_NE(m.find("has no camera"), std::string::npos) << m;
    EXPECT_NE(m.find("--camera FILE"), std::string::npos) << m;
  }
  server.join();
  EXPECT_EQ(log.sessions_opened, 0) << "the error comes before the session is opened";
}

TEST_F(DenoiseCamera, PassthroughNeedsNoCamera) {
  // Frames without a Position pass and without headers, their specular_f0
  // included: passthrough accepts it but does not use the camera.
  for (int frame = 1; frame <= 2; ++frame) {
    std::vector<float> rgb(size_t(W * H * 3), 0.5f);
    std::vector<image::ExrChannelOut> ch;
    for (int k = 0; k < 3; ++k) {
      ch.push_back({std::string(1, "RGB"[k]), rgb.data() + k, 3, image::ExrPixelType::Half});
      ch.push_back({std::string("specular_f0.") + "RGB"[k], rgb.data() + k, 3, image::ExrPixelType::Half});
    }
    image::write_exr(cli::format_frame_path((dir / "f_%04d.exr").string(), frame), W, H, ch);
  }
  Log log;
  test::FakeServer server([&](test::Peer& p) { recording_server(p, log); });
  EXPECT_EQ(cli::run_denoise(args(server.url(), "passthrough")), 0);
  server.join();
  ASSERT_EQ(log.infos.size(), 2u);
  protocol::Mat4 identity{};
  identity[0] = identity[5] = identity[10] = identity[15] = 1.0f;
  for (const auto& info : log.infos) {
    EXPECT_EQ(info.view, identity);
    EXPECT_EQ(info.projection, identity);
  }
}

TEST_F(DenoiseCamera, PassthroughRecoversNoCamera) {
  // The Position pass is there (SetUp's frames), but nothing uses a camera:
  // none is recovered.
  Log log;
  test::FakeServer server([&](test::Peer& p) { recording_server(p, log); });
  EXPECT_EQ(cli::run_denoise(args(server.url(), "passthrough")), 0);
  server.join();
  ASSERT_EQ(log.infos.size(), 2u);
  protocol::Mat4 identity{};
  identity[0] = identity[5] = identity[10] = identity[15] = 1.0f;
  EXPECT_EQ(log.infos[1].view, identity);
}

}  // namespace
