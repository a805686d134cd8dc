#include "reference_cache.hpp"

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "dn/image/exr_io.hpp"
#include "render.hpp"
#include "sampling.hpp"
#include "scenes.hpp"

namespace dn::render {

std::string reference_path(const std::string& cache_dir, int scene_id, int width, int height, int frame, int spp,
                           int index) {
  char name[160];
  std::snprintf(name, sizeof name, "%s_%dx%d_spp%d_v%d/%s_%04d.exr", scene_name(scene_id).c_str(), width, height, spp,
                kReferenceVersion, index == 1 ? "ref" : "ref2", frame);
  return (std::filesystem::path(cache_dir) / name).string();
}

std::string default_cache_dir(const char* xdg_cache_home, const char* home) {
  if (xdg_cache_home && *xdg_cache_home) return (std::filesystem::path(xdg_cache_home) / "dnrender").string();
  if (home && *home) return (std::filesystem::path(home) / ".cache" / "dnrender").string();
  throw std::runtime_error("no reference cache: neither $XDG_CACHE_HOME nor $HOME is set; give --cache DIR");
}

uint32_t reference_seed(uint32_t seed, int index) {
  return index == 1 ? seed : hash_combine(seed ^ 0x2EF2C0DEu, static_cast<uint32_t>(index));
}

std::string ensure_reference(const Scene& scene, const ReferenceRequest& rq, bool& rendered) {
  const std::string path = reference_path(rq.cache_dir, rq.scene_id, rq.width, rq.height, rq.frame, rq.spp, rq.index);
  rendered = false;
  if (std::filesystem::exists(path)) return path;
  RenderSettings settings;
  settings.width = rq.width;
  settings.height = rq.height;
  settings.spp = rq.spp;
  settings.seed = reference_seed(rq.seed, rq.index);
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
  options.strings["dn.seed"] = std::to_string(settings.seed);
  options.strings["dn.reference"] = std::to_string(rq.index);
  image::write_exr_rgb(tmp, fb.width, fb.height, fb.radiance.data(), image::ExrPixelType::Float, options);
  std::filesystem::rename(tmp, path);
  rendered = true;
  return path;
}

}  // namespace dn::render
