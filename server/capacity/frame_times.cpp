#include "server/capacity/frame_times.hpp"

#include <algorithm>

namespace dn::server {

void FrameTimes::add(const std::string& pipeline, uint64_t pixels, const std::vector<pipelines::PassTiming>& timings,
                     Clock::time_point finished) {
  double ms = 0;
  for (const auto& t : timings) ms += t.milliseconds;
  if (pixels == 0) return;
  auto& window = per_pipeline_[pipeline];
  window.push_back(ms / (static_cast<double>(pixels) / 1e6));
  if (window.size() > kFramesPerPipeline) window.pop_front();
  recent_.emplace_back(finished, ms);
  forget_before(finished);
}

void FrameTimes::forget_before(Clock::time_point now) {
  while (!recent_.empty() && now - recent_.front().first > kBusyWindow) recent_.pop_front();
}

std::optional<double> FrameTimes::ms_per_megapixel(const std::string& pipeline) const {
  const auto it = per_pipeline_.find(pipeline);
  if (it == per_pipeline_.end() || it->second.empty()) return std::nullopt;
  std::vector<double> sorted(it->second.begin(), it->second.end());
  std::sort(sorted.begin(), sorted.end());
  const size_t n = sorted.size();
  return n % 2 ? sorted[n / 2] : (sorted[n / 2 - 1] + sorted[n / 2]) / 2;
}

size_t FrameTimes::frames_measured(const std::string& pipeline) const {
  const auto it = per_pipeline_.find(pipeline);
  return it == per_pipeline_.end() ? 0 : it->second.size();
}

std::vector<std::string> FrameTimes::pipelines() const {
  std::vector<std::string> names;
  for (const auto& [name, window] : per_pipeline_) names.push_back(name);
  return names;
}

double FrameTimes::busy_fraction(Clock::time_point now) const {
  double ms = 0;
  for (const auto& [when, frame_ms] : recent_)
    if (now - when <= kBusyWindow) ms += frame_ms;
  return ms / std::chrono::duration<double, std::milli>(kBusyWindow).count();
}

}  // namespace dn::server
