// Constants that change every frame must not grow the process. Lavapipe
// inlines the values of small uniform blocks into the shader and keeps one
// compiled variant per set of values; while FrameConstants was a uniform
// block, a session whose camera moved recompiled every pass at each frame and
// kept every copy (0.3-3 MB a frame: docs/results.md, "Soak"). A process of
// its own, so that no other test's allocations move its resident size.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <memory>

#include "gpu_test_env.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

// Resident set size of this process in bytes (/proc/self/statm, second field).
uint64_t resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  uint64_t size = 0, resident = 0;
  statm >> size >> resident;
  return resident * static_cast<uint64_t>(::sysconf(_SC_PAGESIZE));
}

constexpr int kW = 32, kH = 16;
constexpr int kWarmUp = 20, kFrames = 220;
// Growth allowed over the measured 200 frames: the allocator's and driver's
// noise; the inlining grew the process by 60 MB or more over as many frames.
constexpr uint64_t kAllowedGrowth = 8u << 20;

// A camera at x = 0.01 t looking down -z (fovy 60 degrees), column-major.
std::array<float, 16> view_at(int t) {
  return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -0.01f * static_cast<float>(t), 0, 0, 1};
}
std::array<float, 16> projection() {
  const float tan_half = 0.57735027f, aspect = float(kW) / kH, n = 0.1f, f = 100.0f;
  std::array<float, 16> m{};
  m[0] = 1.0f / (tan_half * aspect);
  m[5] = 1.0f / tan_half;
  m[10] = (f + n) / (n - f);
  m[11] = -1.0f;
  m[14] = 2.0f * f * n / (n - f);
  return m;
}

class FrameConstants : public test::GpuTest {};

// svgf (every pass reads FrameConstants) on a camera panning every frame:
// the matrices, and with them the constants, differ in each frame.
TEST_F(FrameConstants, ChangingEveryFrameDoesNotGrowTheProcess) {
  auto pipeline = pipelines::create(test::context(), svgf_inputs::svgf_config(kW, kH));
  svgf_inputs::SvgfSceneGen scene(kW, kH, 7, 0.7f, 0.3f, 0.0f, 0.2f);
  uint64_t after_warm_up = 0;
  for (int t = 0; t < kFrames; ++t) {
    test::HostFrame f = svgf_inputs::host_frame(scene.frame(t), kW, kH, test::Format::F32,
                                                protocol::MotionConvention::PixelsToPrevious, 0, false);
    f.info.view = view_at(t);
    f.info.prev_view = view_at(t - 1);
    f.info.projection = f.info.prev_projection = projection();
    svgf_inputs::run(*pipeline, f);
    if (t + 1 == kWarmUp) after_warm_up = resident_bytes();
  }
  const uint64_t growth = resident_bytes() - std::min(resident_bytes(), after_warm_up);
  std::printf("[ info     ] resident size grew %.1f MB over %d frames\n", growth / 1048576.0, kFrames - kWarmUp);
  EXPECT_LE(growth, kAllowedGrowth);
}

}  // namespace
}  // namespace dn
