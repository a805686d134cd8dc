// Shared by the DN_PERF tests: run a pipeline over alternating input frames,
// collect each pass's device time and print medians (and minima).
#pragma once

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "frames.hpp"
#include "pipelines/pipeline.hpp"

namespace dn::test {

inline bool perf_requested() {
  const char* env = std::getenv("DN_PERF");
  return env && std::string(env) == "1";
}

struct PassTimes {
  std::vector<std::string> order;                      // passes as the pipeline reports them, then "passes"
  std::map<std::string, std::vector<double>> samples;  // sorted after collection
};

// Runs `warmup + frames` frames, alternating between `inputs`; "passes" is the
// sum of device passes per frame (upload and download excluded).
inline PassTimes time_passes(pipelines::Pipeline& pipe, const std::vector<HostFrame>& inputs, int frames,
                             int warmup = 2) {
  PassTimes t;
  std::vector<uint8_t> out;
  for (int f = 0; f < warmup + frames; ++f) {
    std::vector<pipelines::PassTiming> timings;
    test::process(pipe, inputs[size_t(f) % inputs.size()].view(), true, out, timings);
    if (f < warmup) continue;
    double sum = 0;
    for (const auto& tm : timings) {
      if (!t.samples.count(tm.name)) t.order.push_back(tm.name);
      t.samples[tm.name].push_back(tm.milliseconds);
      if (tm.name != "upload" && tm.name != "download") sum += tm.milliseconds;
    }
    if (!t.samples.count("passes")) t.order.push_back("passes");
    t.samples["passes"].push_back(sum);
  }
  for (auto& [name, v] : t.samples) std::sort(v.begin(), v.end());
  return t;
}

// One line: "<label>:  <pass> <median> ms (min <min>) ...  (<MB> MB device)".
inline void print_pass_times(const std::string& label, const PassTimes& t, uint64_t device_bytes) {
  std::printf("%s:", label.c_str());
  for (const auto& n : t.order) {
    const auto& v = t.samples.at(n);
    std::printf("  %s %.2f ms (min %.2f)", n.c_str(), v[v.size() / 2], v.front());
  }
  std::printf("   (%.1f MB device)\n", double(device_bytes) / 1e6);
}

}  // namespace dn::test
