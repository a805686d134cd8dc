// Measured frame times for capacity figures (docs/server.md "Capacity"):
// per pipeline the median device time per megapixel over its recent frames,
// and the fraction of a recent window the device spent on frames.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "server/pipelines/pipeline.hpp"

namespace dn::server {

class FrameTimes {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr size_t kFramesPerPipeline = 32;           // the median's window
  static constexpr std::chrono::seconds kBusyWindow{10};     // the busy fraction's window

  // One finished frame: its timings (upload, every pass, download) summed.
  void add(const std::string& pipeline, uint64_t pixels, const std::vector<pipelines::PassTiming>& timings,
           Clock::time_point finished = Clock::now());

  // Median of frame milliseconds / megapixels over the pipeline's last
  // kFramesPerPipeline frames; nullopt before its first frame.
  std::optional<double> ms_per_megapixel(const std::string& pipeline) const;
  size_t frames_measured(const std::string& pipeline) const;  // in that window
  std::vector<std::string> pipelines() const;                 // every pipeline measured so far

  // Frame milliseconds finished in the last kBusyWindow, over its length
  // (above 1 when the device's workers overlapped frames).
  double busy_fraction(Clock::time_point now = Clock::now()) const;

 private:
  void forget_before(Clock::time_point now);  // frames older than kBusyWindow

  std::map<std::string, std::deque<double>> per_pipeline_;  // ms per megapixel, newest last
  std::deque<std::pair<Clock::time_point, double>> recent_;  // (finished, ms), oldest first
};

}  // namespace dn::server
