#include "dn/image/exr_io.hpp"

#include <ImfChannelList.h>
#include <ImfCompression.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfMatrixAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <ImfThreading.h>
#include <ImfVecAttribute.h>
#include <half.h>

#include <algorithm>
#include <cstring>
#include <mutex>
#include <thread>

namespace dn::image {

namespace {

void init_threads_once() {
  static std::once_flag once;
  std::call_once(once, [] {
    unsigned n = std::thread::hardware_concurrency();
    Imf::setGlobalThreadCount(int(std::clamp(n, 1u, 16u)));
  });
}

std::array<float, 16> to_array(const Imath::M44f& m) {
  std::array<float, 16> a{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) a[size_t(i * 4 + j)] = m.x[i][j];
  return a;
}
Imath::M44f to_m44(const std::array<float, 16>& a) {
  Imath::M44f m;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) m.x[i][j] = a[size_t(i * 4 + j)];
  return m;
}

}  // namespace

struct ExrReader::Impl {
  std::unique_ptr<Imf::InputFile> file;
  Imath::Box2i dw;
};

ExrReader::ExrReader(const std::string& path) : impl_(std::make_unique<Impl>()), path_(path) {
  init_threads_once();
  try {
    impl_->file = std::make_unique<Imf::InputFile>(path.c_str());
  } catch (const std::exception& e) {
    throw ImageError("cannot read EXR '" + path + "': " + e.what());
  }
  const Imf::Header& h = impl_->file->header();
  impl_->dw = h.dataWindow();
  width_ = impl_->dw.max.x - impl_->dw.min.x + 1;
  height_ = impl_->dw.max.y - impl_->dw.min.y + 1;
  for (auto it = h.channels().begin(); it != h.channels().end(); ++it) channels_.emplace_back(it.name());
}

ExrReader::~ExrReader() = default;
ExrReader::ExrReader(ExrReader&&) noexcept = default;
ExrReader& ExrReader::operator=(ExrReader&&) noexcept = default;

bool ExrReader::has_channel(const std::string& name) const {
  return std::binary_search(channels_.begin(), channels_.end(), name) ||
         std::find(channels_.begin(), channels_.end(), name) != channels_.end();
}

std::vector<float> ExrReader::read(const std::vector<std::string>& names) const {
  const size_t n = names.size();
  std::vector<float> out(size_t(width_) * size_t(height_) * n, 0.0f);
  if (n == 0) return out;
  for (const auto& name : names)
    if (!name.empty() && !has_channel(name))
      throw ImageError("EXR '" + path_ + "' has no channel '" + name + "'");
  Imf::FrameBuffer fb;
  const size_t xs = n * sizeof(float);
  const size_t ys = xs * size_t(width_);
  bool any = false;
  for (size_t c = 0; c < n; ++c) {
    if (names[c].empty()) continue;
    // The same file channel may be requested twice; OpenEXR's FrameBuffer keys
    // slices by name, so duplicates are copied afterwards.
    if (fb.findSlice(names[c].c_str())) continue;
    fb.insert(names[c].c_str(), Imf::Slice::Make(Imf::FLOAT, out.data() + c, impl_->dw, xs, ys));
    any = true;
  }
  if (any) {
    try {
      impl_->file->setFrameBuffer(fb);
      impl_->file->readPixels(impl_->dw.min.y, impl_->dw.max.y);
    } catch (const std::exception& e) {
      throw ImageError("cannot read pixels of EXR '" + path_ + "': " + e.what());
    }
  }
  for (size_t c = 0; c < n; ++c) {
    if (names[c].empty()) continue;
    size_t first = size_t(std::find(names.begin(), names.end(), names[c]) - names.begin());
    if (first == c) continue;
    const size_t pixels = size_t(width_) * size_t(height_);
    for (size_t i = 0; i < pixels; ++i) out[i * n + c] = out[i * n + first];
  }
  return out;
}

ExrCamera ExrReader::camera() const {
  ExrCamera cam;
  const Imf::Header& h = impl_->file->header();
  auto m44 = [&](const char* name, std::optional<std::array<float, 16>>& dst) {
    if (auto* a = h.findTypedAttribute<Imf::M44fAttribute>(name)) dst = to_array(a->value());
  };
  auto v2 = [&](const char* name, std::optional<std::array<float, 2>>& dst) {
    if (auto* a = h.findTypedAttribute<Imf::V2fAttribute>(name)) dst = std::array<float, 2>{a->value().x, a->value().y};
  };
  m44("dn.view", cam.view);
  m44("dn.projection", cam.projection);
  v2("dn.jitter", cam.jitter);
  m44("dn.prev_view", cam.prev_view);
  m44("dn.prev_projection", cam.prev_projection);
  v2("dn.prev_jitter", cam.prev_jitter);
  return cam;
}

std::optional<std::string> ExrReader::string_attribute(const std::string& name) const {
  if (auto* a = impl_->file->header().findTypedAttribute<Imf::StringAttribute>(name)) return a->value();
  return std::nullopt;
}

void write_exr(const std::string& path, int width, int height, const std::vector<ExrChannelOut>& channels,
               const ExrWriteOptions& options) {
  init_threads_once();
  if (width <= 0 || height <= 0) throw ImageError("cannot write EXR '" + path + "': empty image");
  try {
    Imf::Header header(width, height);
    header.compression() = options.compress ? Imf::ZIP_COMPRESSION : Imf::NO_COMPRESSION;
    const ExrCamera& cam = options.camera;
    if (cam.view) header.insert("dn.view", Imf::M44fAttribute(to_m44(*cam.view)));
    if (cam.projection) header.insert("dn.projection", Imf::M44fAttribute(to_m44(*cam.projection)));
    if (cam.jitter) header.insert("dn.jitter", Imf::V2fAttribute(Imath::V2f((*cam.jitter)[0], (*cam.jitter)[1])));
    if (cam.prev_view) header.insert("dn.prev_view", Imf::M44fAttribute(to_m44(*cam.prev_view)));
    if (cam.prev_projection)
      header.insert("dn.prev_projection", Imf::M44fAttribute(to_m44(*cam.prev_projection)));
    if (cam.prev_jitter)
      header.insert("dn.prev_jitter",
                    Imf::V2fAttribute(Imath::V2f((*cam.prev_jitter)[0], (*cam.prev_jitter)[1])));
    for (const auto& [k, v] : options.strings) header.insert(k, Imf::StringAttribute(v));

    // OpenEXR does not convert float slices to half file channels on output:
    // half channels are converted here into planar buffers.
    Imf::FrameBuffer fb;
    const size_t pixels = size_t(width) * size_t(height);
    std::vector<std::vector<Imath::half>> halves;
    halves.reserve(channels.size());
    for (const auto& ch : channels) {
      if (ch.type == ExrPixelType::Half) {
        header.channels().insert(ch.name, Imf::Channel(Imf::HALF));
        auto& h = halves.emplace_back(pixels);
        for (size_t i = 0; i < pixels; ++i) h[i] = Imath::half(ch.data[i * ch.stride]);
        fb.insert(ch.name, Imf::Slice(Imf::HALF, reinterpret_cast<char*>(h.data()), sizeof(Imath::half),
                                      sizeof(Imath::half) * size_t(width)));
      } else {
        header.channels().insert(ch.name, Imf::Channel(Imf::FLOAT));
        const size_t xs = ch.stride * sizeof(float);
        fb.insert(ch.name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(ch.data)), xs,
                                      xs * size_t(width)));
      }
    }
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(height);
  } catch (const std::exception& e) {
    throw ImageError("cannot write EXR '" + path + "': " + e.what());
  }
}

void write_exr_rgb(const std::string& path, int width, int height, const float* rgb, ExrPixelType type,
                   const ExrWriteOptions& options) {
  write_exr(path, width, height,
            {{"R", rgb + 0, 3, type}, {"G", rgb + 1, 3, type}, {"B", rgb + 2, 3, type}}, options);
}

std::vector<float> read_exr_rgb(const std::string& path, int& width, int& height) {
  ExrReader r(path);
  width = r.width();
  height = r.height();
  if (r.has_channel("R") && r.has_channel("G") && r.has_channel("B")) return r.read({"R", "G", "B"});
  for (const auto& c : r.channels()) {
    if (c.size() > 2 && c.compare(c.size() - 2, 2, ".R") == 0) {
      std::string base = c.substr(0, c.size() - 1);
      if (r.has_channel(base + "G") && r.has_channel(base + "B")) return r.read({base + "R", base + "G", base + "B"});
    }
  }
  throw ImageError("EXR '" + path + "' has no R,G,B channels");
}

}  // namespace dn::image
