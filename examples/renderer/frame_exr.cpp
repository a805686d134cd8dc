#include "frame_exr.hpp"

#include <vector>

#include "dn/image/exr_io.hpp"

namespace dn::render {

std::array<float, 16> to_array(const glm::mat4& m) {
  std::array<float, 16> a;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) a[c * 4 + r] = m[c][r];
  return a;
}

void write_frame_exr(const std::string& path, const FrameBuffers& fb, const Camera& camera, const Camera& previous,
                     const std::map<std::string, std::string>& attributes) {
  using image::ExrChannelOut;
  using image::ExrPixelType;
  std::vector<ExrChannelOut> channels;
  // Colours that filters divide by or compare are float; bounded material values are half.
  auto layer = [&](const std::string& name, const std::vector<float>& plane, const char* components,
                   ExrPixelType type) {
    if (plane.empty()) return;
    const size_t stride = std::string(components).size();
    for (size_t c = 0; c < stride; ++c)
      channels.push_back({name + "." + components[c], plane.data() + c, stride, type});
  };
  const auto F = ExrPixelType::Float, H = ExrPixelType::Half;
  layer("radiance", fb.radiance, "RGB", F);
  layer("diffuse", fb.diffuse, "RGB", F);
  layer("specular", fb.specular, "RGB", F);
  layer("emission", fb.emission, "RGB", F);
  layer("albedo", fb.albedo, "RGB", H);
  layer("specular_f0", fb.specular_f0, "RGB", H);
  layer("roughness", fb.roughness, "Y", H);
  layer("normal", fb.normal, "XYZ", F);
  layer("depth", fb.depth, "Z", F);
  layer("motion", fb.motion, "XY", F);
  layer("position", fb.position, "XYZ", F);
  layer("sample_count", fb.sample_count, "Y", H);
  layer("stat_count", fb.stat_count, "Y", F);
  layer("stat_mean", fb.stat_mean, "RGB", F);
  layer("stat_m2", fb.stat_m2, "RGB", F);
  layer("stat_m3", fb.stat_m3, "RGB", F);
  layer("stat_raw_mean", fb.stat_raw_mean, "RGB", F);
  layer("reflection_position", fb.reflection_position, "XYZ", F);
  layer("reflection_albedo", fb.reflection_albedo, "RGB", H);
  layer("reflection_normal", fb.reflection_normal, "XYZ", F);
  layer("reflection_depth", fb.reflection_depth, "Z", F);
  layer("reflection_direction", fb.reflection_direction, "XYZ", F);
  layer("reflection_distance", fb.reflection_distance, "Y", F);
  layer("reflection_footprint", fb.reflection_footprint, "Y", F);
  for (size_t j = 0; j < fb.extra.size(); ++j) {
    const std::string s = "sample" + std::to_string(j + 1) + "_";
    const FrameBuffers::ExtraSample& e = fb.extra[j];
    layer(s + "radiance", e.radiance, "RGB", F);
    layer(s + "diffuse", e.diffuse, "RGB", F);
    layer(s + "specular", e.specular, "RGB", F);
    layer(s + "normal", e.normal, "XYZ", F);
    layer(s + "depth", e.depth, "Z", F);
    layer(s + "offset", e.offset, "XY", F);
  }

  image::ExrWriteOptions options;
  options.camera.view = to_array(camera.view);
  options.camera.projection = to_array(camera.projection);
  options.camera.jitter = std::array<float, 2>{camera.jitter.x, camera.jitter.y};
  options.camera.prev_view = to_array(previous.view);
  options.camera.prev_projection = to_array(previous.projection);
  options.camera.prev_jitter = std::array<float, 2>{previous.jitter.x, previous.jitter.y};
  options.strings = attributes;
  options.strings["dn.generator"] = "dnrender";
  // What the stat_* layers are over (docs/client.md): dn sets the pipeline's
  // parameter demodulated from it.
  if (!fb.stat_count.empty()) options.strings["dn.stat_samples"] = fb.statistics_demodulated ? "demodulated" : "radiance";
  image::write_exr(path, fb.width, fb.height, channels, options);
}

}  // namespace dn::render
