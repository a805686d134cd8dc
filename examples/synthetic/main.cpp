// dnsynth: writes a short synthetic EXR sequence in the dnrender layout (noisy
// radiance + G-buffers + camera) and its exact noise-free reference, so the
// service can be exercised and measured before a path tracer exists.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "dn/image/exr_io.hpp"
#include "scene.hpp"

namespace {

std::array<float, 16> to_array(const glm::mat4& m) {
  std::array<float, 16> a;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) a[c * 4 + r] = m[c][r];
  return a;
}

int usage() {
  std::fputs(
      "usage: dnsynth --out DIR [--frames N] [--width W] [--height H] [--seed S]\n"
      "writes DIR/frame_%04d.exr (dnrender layout) and DIR/ref_%04d.exr (noise-free RGB)\n",
      stderr);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out;
  int frames = 16, width = 320, height = 180;
  unsigned seed = 1;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = (a == "--help") ? nullptr : next();
    if (!v) return usage();
    if (a == "--out") out = v;
    else if (a == "--frames") frames = std::atoi(v);
    else if (a == "--width") width = std::atoi(v);
    else if (a == "--height") height = std::atoi(v);
    else if (a == "--seed") seed = static_cast<unsigned>(std::atoi(v));
    else return usage();
  }
  if (out.empty() || frames < 1 || width < 1 || height < 1 || width > 8192 || height > 8192) return usage();
  std::filesystem::create_directories(out);

  using dn::image::ExrChannelOut;
  using dn::image::ExrPixelType;
  for (int f = 0; f < frames; ++f) {
    dn::synth::FrameBuffers fb = dn::synth::render(f, width, height, seed);
    const auto cam = dn::synth::camera_at(f, width, height);
    const auto prev = dn::synth::camera_at(f - 1, width, height);
    dn::image::ExrWriteOptions options;
    options.camera.view = to_array(cam.view);
    options.camera.projection = to_array(cam.projection);
    options.camera.jitter = std::array<float, 2>{0.0f, 0.0f};
    options.camera.prev_view = to_array(prev.view);
    options.camera.prev_projection = to_array(prev.projection);
    options.strings["dn.generator"] = "dnsynth";
    const auto F = ExrPixelType::Float;
    std::vector<ExrChannelOut> channels;
    const char* rgb[] = {"R", "G", "B"};
    const char* xyz[] = {"X", "Y", "Z"};
    for (int c = 0; c < 3; ++c) {
      channels.push_back({std::string("radiance.") + rgb[c], fb.noisy.data() + c, 3, F});
      channels.push_back({std::string("albedo.") + rgb[c], fb.albedo.data() + c, 3, ExrPixelType::Half});
      channels.push_back({std::string("normal.") + xyz[c], fb.normal.data() + c, 3, F});
      channels.push_back({std::string("position.") + xyz[c], fb.position.data() + c, 3, F});
    }
    channels.push_back({"depth.Z", fb.depth.data(), 1, F});
    channels.push_back({"motion.X", fb.motion.data(), 2, F});
    channels.push_back({"motion.Y", fb.motion.data() + 1, 2, F});
    char name[64];
    std::snprintf(name, sizeof name, "/frame_%04d.exr", f);
    dn::image::write_exr(out + name, width, height, channels, options);
    std::snprintf(name, sizeof name, "/ref_%04d.exr", f);
    dn::image::write_exr_rgb(out + name, width, height, fb.clean.data(), F);
  }
  std::printf("dnsynth: wrote %d frames of %dx%d to %s\n", frames, width, height, out.c_str());
  return 0;
}
