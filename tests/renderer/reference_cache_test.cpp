// References are rendered once and then reused from the cache.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>

#include "dn/image/exr_io.hpp"
#include "reference_cache.hpp"
#include "scenes.hpp"

namespace dn::render {
namespace {

TEST(RendererReferenceCache, SecondRequestReusesTheFile) {
  const auto dir = std::filesystem::temp_directory_path() / ("dn_renderer_cache_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const std::unique_ptr<Scene> scene = build_scene(2);
  ReferenceRequest rq;
  rq.scene_id = 2;
  rq.width = 32;
  rq.height = 18;
  rq.frame = 4;
  rq.spp = 4;
  rq.cache_dir = dir.string();
  bool rendered = false;
  const std::string path = ensure_reference(*scene, rq, rendered);
  EXPECT_TRUE(rendered);
  EXPECT_EQ(path, reference_path(dir.string(), 2, 32, 18, 4, 4));
  EXPECT_NE(path.find("pillars_32x18_spp4/ref_0004.exr"), std::string::npos) << path;
  const auto mtime = std::filesystem::last_write_time(path);

  const std::string again = ensure_reference(*scene, rq, rendered);
  EXPECT_FALSE(rendered);
  EXPECT_EQ(again, path);
  EXPECT_EQ(std::filesystem::last_write_time(path), mtime);

  int w = 0, h = 0;
  const std::vector<float> rgb = image::read_exr_rgb(path, w, h);
  EXPECT_EQ(w, 32);
  EXPECT_EQ(h, 18);
  // Another spp is another file.
  rq.spp = 2;
  ensure_reference(*scene, rq, rendered);
  EXPECT_TRUE(rendered);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace dn::render
