// The frame EXR has the dnrender layout of docs/client.md plus the extra
// layers of docs/renderer.md, and the camera attributes.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "dn/image/exr_io.hpp"
#include "frame_exr.hpp"
#include "scenes.hpp"
#include "test_support.hpp"

namespace dn::render {
namespace {

TEST(RendererExr, FrameHasEveryLayerAndTheCamera) {
  const std::unique_ptr<Scene> scene = build_scene(1);
  RenderSettings st = test::small_settings(32, 18, 2.0);
  st.jitter = true;
  st.channels.statistics = true;
  st.channels.reflection = true;
  const Camera cam = frame_camera(1, 3, st), prev = frame_camera(1, 2, st);
  const FrameBuffers fb = render_frame(*scene, cam, prev, 3, st);
  const std::string path =
      (std::filesystem::temp_directory_path() / ("dn_renderer_frame_" + std::to_string(::getpid()) + ".exr")).string();
  write_frame_exr(path, fb, cam, prev, {{"dn.scene", "room"}});

  const image::ExrReader exr(path);
  EXPECT_EQ(exr.width(), 32);
  EXPECT_EQ(exr.height(), 18);
  for (const char* name :
       {"radiance.R", "diffuse.G", "specular.B", "albedo.R", "specular_f0.G", "roughness.Y", "normal.X", "depth.Z",
        "motion.X", "motion.Y", "emission.R", "position.Z", "sample_count.Y", "stat_count.Y", "stat_mean.R",
        "stat_m2.G", "stat_m3.B", "stat_raw_mean.R", "reflection_position.X", "reflection_albedo.G",
        "reflection_normal.Z", "reflection_depth.Z", "reflection_direction.X", "reflection_distance.Y",
        "reflection_footprint.Y"})
    EXPECT_TRUE(exr.has_channel(name)) << name;
  const auto camera = exr.camera();
  ASSERT_TRUE(camera.view && camera.projection && camera.jitter && camera.prev_view);
  EXPECT_EQ(*camera.view, to_array(cam.view));
  EXPECT_EQ(*camera.prev_projection, to_array(prev.projection));
  EXPECT_FLOAT_EQ((*camera.jitter)[0], cam.jitter.x);
  EXPECT_EQ(exr.string_attribute("dn.generator").value_or(""), "dnrender");

  const std::vector<float> depth = exr.read_channel("depth.Z");
  const std::vector<float> radiance = exr.read({"radiance.R", "radiance.G", "radiance.B"});
  for (size_t i = 0; i < depth.size(); ++i) EXPECT_EQ(depth[i], fb.depth[i]);
  for (size_t i = 0; i < radiance.size(); ++i) EXPECT_EQ(radiance[i], fb.radiance[i]);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace dn::render
