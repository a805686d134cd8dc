#include "frame_source.hpp"

#include <cmath>
#include <cstdio>
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

}  // namespace

bool has_frame_placeholder(const std::string& pattern) { return find_placeholder(pattern).len != 0; }

std::string format_frame_path(const std::string& pattern, long long frame) {
  const Placeholder ph = find_placeholder(pattern);
  std::string out;
  for (size_t i = 0; i < pattern.size(); ++i) {
    if (i == ph.pos) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%0*lld", ph.width, frame);
      out += buf;
      i += ph.len - 1;
    } else if (pattern[i] == '%' && i + 1 < pattern.size() && pattern[i + 1] == '%') {
      out += '%';
      ++i;
    } else {
      out += pattern[i];
    }
  }
  return out;
}

LoadedFrame load_frame(const dn::image::ExrReader& exr, const std::vector<ResolvedChannel>& plan, long long number) {
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
    if (ch.convert == Convert::CyclesDepth) convert_cycles_depth(p.data);
    if (ch.convert == Convert::CyclesAlbedo) convert_cycles_albedo(p.data);
    if (ch.convert == Convert::CyclesVector) convert_cycles_vector(p.data);
    f.planes.push_back(std::move(p));
  }
  return f;
}

void camera_normals_to_world(LoadedFrame& frame, const std::vector<ResolvedChannel>& plan) {
  for (const auto& ch : plan) {
    if (ch.convert != Convert::CyclesCameraNormal) continue;
    if (!frame.camera.view)
      throw std::runtime_error(frame.path + ": " + ch.describe() +
                               " is in camera space and needs the frame's camera: give the Position pass "
                               "(View Layer Properties > Passes > Data > Position) or --camera FILE, or map the "
                               "world-space normal with --channel normal=Normal");
    const auto& m = *frame.camera.view;  // world -> view, column-major: R(row j, col i) = m[4 i + j]
    for (auto& p : frame.planes) {
      if (p.id != ch.id) continue;
      for (size_t k = 0; k + 2 < p.data.size(); k += 3) {
        // Cycles camera space has z forward, the protocol's view space z backward.
        const float v[3] = {p.data[k], p.data[k + 1], -p.data[k + 2]};
        float w[3];
        for (int i = 0; i < 3; ++i) w[i] = m[4 * i] * v[0] + m[4 * i + 1] * v[1] + m[4 * i + 2] * v[2];
        const float len = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        for (int i = 0; i < 3; ++i) p.data[k + i] = len > 0.0f ? w[i] / len : 0.0f;
      }
    }
  }
}

}  // namespace dn::cli
