#include "frame_source.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>

#include "args.hpp"

namespace dn::cli {

namespace {

struct Placeholder {
  size_t pos = std::string::npos, len = 0;
  int width = 0;
};

Placeholder find_placeholder(const std::string& p) {
  Placeholder found;
  int count = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p[i] == '%') {
      if (i + 1 < p.size() && p[i + 1] == '%') {
        ++i;
        continue;
      }
      size_t j = i + 1;
      int width = 0;
      while (j < p.size() && p[j] >= '0' && p[j] <= '9') width = width * 10 + (p[j++] - '0');
      if (j >= p.size() || p[j] != 'd')
        throw UsageError("path pattern '" + p + "': only %d and %0Nd placeholders are supported");
      found = {i, j - i + 1, width};
      ++count;
      i = j;
    } else if (p[i] == '#') {
      size_t j = i;
      while (j < p.size() && p[j] == '#') ++j;
      found = {i, j - i, int(j - i)};
      ++count;
      i = j - 1;
    }
  }
  if (count > 1) throw UsageError("path pattern '" + p + "' has more than one frame-number placeholder");
  return found;
}

// Pattern text around the placeholder as it appears in file names: "%%" is '%'.
std::string literal_text(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    out += text[i];
    if (text[i] == '%' && i + 1 < text.size() && text[i + 1] == '%') ++i;
  }
  return out;
}

}  // namespace

bool has_frame_placeholder(const std::string& pattern) { return find_placeholder(pattern).len != 0; }

std::optional<FramePattern> split_frame_pattern(const std::string& pattern) {
  const Placeholder ph = find_placeholder(pattern);
  if (ph.len == 0) return std::nullopt;
  return FramePattern{literal_text(pattern.substr(0, ph.pos)), literal_text(pattern.substr(ph.pos + ph.len)), ph.width};
}

std::string format_frame_number(int width, long long frame) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%0*lld", width, frame);
  return buf;
}

std::string format_frame_path(const std::string& pattern, long long frame) {
  const auto parts = split_frame_pattern(pattern);
  if (!parts) return literal_text(pattern);
  return parts->prefix + format_frame_number(parts->width, frame) + parts->suffix;
}

LoadedFrame load_frame(const dn::image::ExrReader& exr, const std::vector<ResolvedChannel>& requested, long long number,
                       const RoughGuidePlan* guides) {
  std::vector<ResolvedChannel> plan = requested;
  if (guides) {
    plan.insert(plan.end(), guides->channels.begin(), guides->channels.end());
    if (guides->key) plan.push_back(*guides->key);
  }
  LoadedFrame f;
  f.number = number;
  f.path = exr.path();
  f.width = exr.width();
  f.height = exr.height();
  f.camera = exr.camera();
  // One read for all EXR channels: a compressed scanline block is decoded
  // once, not once per protocol channel.
  std::vector<std::string> names;
  auto index_of = [&](const std::string& n) {
    for (size_t i = 0; i < names.size(); ++i)
      if (names[i] == n) return i;
    names.push_back(n);
    return names.size() - 1;
  };
  // Per channel, per term: the component indices into `names`, and the
  // factor's (empty when the term has none).
  std::vector<std::vector<std::vector<size_t>>> idx(plan.size()), fidx(plan.size());
  for (size_t c = 0; c < plan.size(); ++c) {
    const auto& ch = plan[c];
    auto indices = [&](const std::vector<std::string>& channels) {
      std::vector<size_t> out;
      for (const auto& name : channels) {
        if (!exr.has_channel(name))
          throw ChannelMapError("channel '" + std::string(protocol::find_channel(ch.id)->name) + "': " +
                                exr.path() + " has no EXR channel '" + name + "' (mapped from " + ch.describe() +
                                ")");
        out.push_back(index_of(name));
      }
      return out;
    };
    for (size_t t = 0; t < ch.terms.size(); ++t) {
      idx[c].push_back(indices(ch.terms[t]));
      fidx[c].push_back(t < ch.factors.size() ? indices(ch.factors[t]) : std::vector<size_t>{});
    }
  }
  const std::vector<float> all = exr.read(names);
  const size_t stride = names.size();
  const size_t pixels = size_t(f.width) * size_t(f.height);
  for (size_t c = 0; c < plan.size(); ++c) {
    const auto& ch = plan[c];
    const size_t n = idx[c].front().size();
    LoadedPlane p{ch.id, std::vector<float>(pixels * n, 0.0f)};
    for (size_t t = 0; t < idx[c].size(); ++t) {
      const auto& term = idx[c][t];
      const auto& factor = fidx[c][t];
      for (size_t i = 0; i < pixels; ++i)
        for (size_t k = 0; k < n; ++k)
          p.data[i * n + k] += all[i * stride + term[k]] * (factor.empty() ? 1.0f : all[i * stride + factor[k]]);
    }
    if (ch.convert == Convert::CyclesDepth || ch.convert == Convert::CyclesVirtualDepth)
      convert_cycles_depth(p.data);
    if (ch.convert == Convert::CyclesVector) convert_cycles_vector(p.data);
    (c < requested.size() ? f.planes : f.primary_guides).push_back(std::move(p));
  }
  return f;
}

namespace {

std::runtime_error no_camera(const LoadedFrame& frame, const ResolvedChannel& ch, const ChannelSyntax& syntax) {
  return std::runtime_error(frame.path + ": " + ch.describe() +
                            " needs the frame's camera: give the Position pass (View Layer Properties > Passes > "
                            "Data > Position) or " + syntax.camera + ", or map the primary hit's depth with " +
                            syntax.map_example("depth", "Depth@cycles"));
}

// cos of the angle between pixel (x, y)'s centre ray and the view axis. The
// ray's view-space direction (vx, vy, -1) solves the projection's x/y rows at
// the pixel centre's ndc (OpenGL, column-major, perspective: m[11] = -1,
// m[15] = 0; an orthographic projection, m[15] != 0, has cos 1).
double view_axis_cos(int x, int y, int width, int height, const std::array<float, 16>& m) {
  if (m[15] != 0.0f) return 1.0;
  const double det = double(m[0]) * m[5] - double(m[4]) * m[1];
  const double nx = 2.0 * (x + 0.5) / width - 1.0 + m[8] - m[12];
  const double ny = 1.0 - 2.0 * (y + 0.5) / height + m[9] - m[13];
  const double vx = (nx * m[5] - ny * m[4]) / det, vy = (ny * m[0] - nx * m[1]) / det;
  return 1.0 / std::sqrt(vx * vx + vy * vy + 1.0);
}

// Cycles' Denoising Depth: the path length to the first non-specular hit,
// measured from the near clipping plane (camera rays start there), to the
// view depth of that point: length x cos + clip start. The clip start is not
// in the file: on every pixel whose path stops at the primary hit,
// Depth.Z - length x cos is exactly it, so it is the median of that over the
// pixels that have both (0 when the file has no Depth pass).
void path_length_to_view_depth(std::vector<float>& depth, int width, int height, const std::array<float, 16>& m,
                               const std::vector<float>& camera_z) {
  std::vector<float> offsets;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y) * width + x;
      depth[i] = float(depth[i] * view_axis_cos(x, y, width, height, m));
      if (!camera_z.empty() && std::isfinite(depth[i]) && std::isfinite(camera_z[i]) && camera_z[i] > 0.0f)
        offsets.push_back(camera_z[i] - depth[i]);
    }
  float clip_start = 0.0f;
  if (!offsets.empty()) {
    std::nth_element(offsets.begin(), offsets.begin() + offsets.size() / 2, offsets.end());
    clip_start = std::max(0.0f, offsets[offsets.size() / 2]);
  }
  for (float& d : depth) d += clip_start;
}

}  // namespace

void apply_camera_conversions(LoadedFrame& frame, const std::vector<ResolvedChannel>& plan,
                              const dn::image::ExrReader& exr, const ChannelSyntax& syntax) {
  for (const auto& ch : plan) {
    if (ch.convert != Convert::CyclesVirtualDepth) continue;
    if (!frame.camera.projection) throw no_camera(frame, ch, syntax);
    // The Depth pass of the same layer: "L.Denoising Depth.Z" -> "L.Depth.Z".
    std::string z = ch.terms.front().front();
    const std::string from = "Denoising Depth";
    if (const size_t at = z.rfind(from); at != std::string::npos) z.replace(at, from.size(), "Depth");
    const std::vector<float> camera_z = exr.has_channel(z) ? exr.read_channel(z) : std::vector<float>{};
    for (auto& p : frame.planes)
      if (p.id == ch.id)
        path_length_to_view_depth(p.data, frame.width, frame.height, *frame.camera.projection, camera_z);
  }
}

void apply_rough_guides(LoadedFrame& frame, const RoughGuidePlan& guides) {
  auto find_in = [](std::vector<LoadedPlane>& planes, protocol::ChannelId id) -> std::vector<float>* {
    for (auto& p : planes)
      if (p.id == id) return &p.data;
    return nullptr;
  };
  const size_t pixels = size_t(frame.width) * size_t(frame.height);
  std::vector<char> mirror(pixels, 0);
  if (guides.key) {
    const std::vector<float>* key = find_in(frame.primary_guides, guides.key->id);
    if (!key) throw std::logic_error("apply_rough_guides: the frame was not loaded with the guides");
    for (size_t i = 0; i < pixels; ++i) mirror[i] = (*key)[i] < guides.from;  // NaN: not a mirror
  } else {
    const std::vector<float>* past = find_in(frame.planes, protocol::ChannelId::Depth);
    const std::vector<float>* primary = find_in(frame.primary_guides, protocol::ChannelId::Depth);
    if (!past || !primary) throw std::logic_error("apply_rough_guides: no depth to compare");
    for (size_t i = 0; i < pixels; ++i)
      mirror[i] = std::isfinite((*primary)[i]) && (*past)[i] > (*primary)[i] * (1.0f + kPastPrimaryDepth);
    // A surface without diffuse colour (a metal) may be glossy, not a mirror,
    // and nothing here tells which: it keeps the diffuse colour, 0, and the
    // server shows it as rendered.
    if (const std::vector<float>* albedo = find_in(frame.primary_guides, protocol::ChannelId::Albedo))
      for (size_t i = 0; i < pixels; ++i) {
        const float* a = albedo->data() + 3 * i;
        if (!(std::max({a[0], a[1], a[2]}) >= kReflectanceMin)) mirror[i] = 0;
      }
  }
  for (const auto& ch : guides.channels) {
    const std::vector<float>* from = find_in(frame.primary_guides, ch.id);
    std::vector<float>* to = find_in(frame.planes, ch.id);
    if (!from || !to || from->size() != to->size()) continue;
    const size_t n = to->size() / pixels;
    for (size_t i = 0; i < pixels; ++i)
      if (!mirror[i])
        for (size_t k = 0; k < n; ++k) (*to)[i * n + k] = (*from)[i * n + k];
  }
}

}  // namespace dn::cli
