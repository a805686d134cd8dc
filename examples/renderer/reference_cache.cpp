#include "reference_cache.hpp"

#include <cstdio>
#include <filesystem>

#include "dn/image/exr_io.hpp"
#include "render.hpp"
#include "scenes.hpp"

namespace dn::render {

std::string reference_path(const std::string& cache_dir, int scene_id, int width, int height, int frame, int spp) {
  char name[128];
  std::snprintf(name, sizeof name, "%s_%dx%d_spp%d/ref_%04d.exr", scene_name(scene_id).c_str(), width, height, spp,
                frame);
  return (std::filesystem::path(cache_dir) / name).string();
}

std::string ensure_reference(const Scene& scene, const ReferenceRequest& rq, bool& rendered) {
  const std::string path = reference_path(rq.cache_dir, rq.scene_id, rq.width, rq.height, rq.frame, rq.spp);
  rendered = false;
  if (std::filesystem::exists(path)) return path;
  RenderSettings settings;
  settings.width = rq.width;
  settings.height = rq.height;
  settings.spp = rq.spp;
  settings.seed = rq.seed;
  settings.threads = rq.threads;
  settings.channels = ChannelSet{false, false, false, false, false, false, false};
  const Camera camera = frame_camera(rq.scene_id, rq.frame, settings);
  const FrameBuffers fb = render_frame(scene, camera, camera, rq.frame, settings);
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  // The temporary name keeps the .exr extension, which OpenEXR does not need but tools like.
  const std::string tmp = path + ".partial.exr";
  image::ExrWriteOptions options;
  options.strings["dn.generator"] = "dnrender reference";
  options.strings["dn.scene"] = scene_name(rq.scene_id);
  options.strings["dn.spp"] = std::to_string(rq.spp);
  image::write_exr_rgb(tmp, fb.width, fb.height, fb.radiance.data(), image::ExrPixelType::Float, options);
  std::filesystem::rename(tmp, path);
  rendered = true;
  return path;
}

}  // namespace dn::render
