#include "frame_source.hpp"

#include <cstdio>

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
  std::vector<std::vector<std::vector<size_t>>> idx(plan.size());
  for (size_t c = 0; c < plan.size(); ++c) {
    const auto& ch = plan[c];
    for (const auto& term : ch.terms) {
      idx[c].emplace_back();
      for (const auto& name : term) {
        if (!exr.has_channel(name))
          throw ChannelMapError("channel '" + std::string(protocol::find_channel(ch.id)->name) + "': " +
                                exr.path() + " has no EXR channel '" + name + "' (mapped from " + ch.describe() +
                                ")");
        idx[c].back().push_back(index_of(name));
      }
    }
  }
  const std::vector<float> all = exr.read(names);
  const size_t stride = names.size();
  const size_t pixels = size_t(f.width) * size_t(f.height);
  for (size_t c = 0; c < plan.size(); ++c) {
    const auto& ch = plan[c];
    const size_t n = idx[c].front().size();
    LoadedPlane p{ch.id, std::vector<float>(pixels * n, 0.0f)};
    for (const auto& term : idx[c])
      for (size_t i = 0; i < pixels; ++i)
        for (size_t k = 0; k < n; ++k) p.data[i * n + k] += all[i * stride + term[k]];
    if (ch.convert == Convert::CyclesDepth) convert_cycles_depth(p.data);
    if (ch.convert == Convert::CyclesVector) convert_cycles_vector(p.data);
    f.planes.push_back(std::move(p));
  }
  return f;
}

}  // namespace dn::cli
