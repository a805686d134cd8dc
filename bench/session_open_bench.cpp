// Session set-up cost and what it does to everyone else, against a real
// dnserver process: while one client streams `passthrough` frames (one in
// flight, 640x360 fp32 radiance), another connects and opens a session of the
// measured pipeline (default svgf at 640x360), closes it, and repeats.
// Prints each open's latency (OPEN_SESSION -> SESSION and HELLO -> SESSION)
// and the streaming client's frame latency: median and worst outside the
// opens, worst while an open was in progress.
//
// Cold vs warm: run it against a server started with --no-warm-up
// --no-disk-cache and MESA_SHADER_CACHE_DISABLE=true (the first open
// compiles everything), and against one whose warm-up has finished
// (bench/session_open.sh does both).
//
//   session_open_bench --server tcp://127.0.0.1:7878 [--pipeline svgf] [--size 640x360] [--opens 5]
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "dn/client/client.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using dn::protocol::ChannelId;

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct FrameSample {
  Clock::time_point sent, received;
};

struct Interval {
  Clock::time_point begin, end;
};

dn::client::SessionDesc describe(const std::string& pipeline, uint32_t w, uint32_t h) {
  dn::client::SessionDesc d;
  d.width = w;
  d.height = h;
  d.pipeline = pipeline;
  if (pipeline == "svgf-fb") {
    for (auto id : {ChannelId::Diffuse, ChannelId::Specular, ChannelId::Albedo, ChannelId::SpecularF0,
                    ChannelId::Roughness, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion})
      d.channel(id);
  } else if (pipeline == "passthrough") {
    d.channel(ChannelId::Radiance);
  } else {
    for (auto id : {ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion})
      d.channel(id);
  }
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  std::string server = "tcp://127.0.0.1:7878", pipeline = "svgf";
  uint32_t width = 640, height = 360, opens = 5;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i], value = argv[i + 1];
    if (flag == "--server") server = value;
    else if (flag == "--pipeline") pipeline = value;
    else if (flag == "--opens") opens = static_cast<uint32_t>(std::stoul(value));
    else if (flag == "--size") std::sscanf(value.c_str(), "%ux%u", &width, &height);
    else {
      std::fprintf(stderr, "unknown flag %s\n", flag.c_str());
      return 2;
    }
  }

  // The streaming client: one frame in flight, back to back.
  std::atomic<bool> stop{false};
  std::mutex samples_mutex;
  std::vector<FrameSample> samples;
  std::vector<float> radiance(size_t{width} * height * 3, 0.5f);
  auto streamer_conn = dn::client::Connection::connect(server);
  auto stream = streamer_conn.open_session(describe("passthrough", width, height));
  std::thread streamer([&] {
    for (uint64_t i = 0; !stop; ++i) {
      dn::client::FrameInput f;
      f.info.frame_index = i;
      f.add(ChannelId::Radiance, radiance);
      const auto sent = Clock::now();
      stream.denoise(f);
      std::lock_guard lock(samples_mutex);
      samples.push_back({sent, Clock::now()});
    }
  });

  std::this_thread::sleep_for(std::chrono::seconds(1));  // a baseline before the first open
  std::vector<Interval> busy;
  std::printf("open  hello_to_session_ms  open_to_session_ms\n");
  std::vector<double> open_ms;
  for (uint32_t k = 0; k < opens; ++k) {
    const auto t0 = Clock::now();
    auto conn = dn::client::Connection::connect(server);
    const auto t1 = Clock::now();
    auto session = conn.open_session(describe(pipeline, width, height));
    const auto t2 = Clock::now();
    busy.push_back({t0, t2});
    open_ms.push_back(ms_between(t1, t2));
    std::printf("%-5u %19.1f %19.1f\n", k, ms_between(t0, t2), ms_between(t1, t2));
    std::fflush(stdout);
    session.close();
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  stop = true;
  streamer.join();

  std::vector<double> quiet, during;
  for (const auto& s : samples) {
    bool overlaps = false;
    for (const auto& b : busy) overlaps = overlaps || (s.sent < b.end && s.received > b.begin);
    (overlaps ? during : quiet).push_back(ms_between(s.sent, s.received));
  }
  auto worst = [](const std::vector<double>& v) { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); };
  std::printf("\npipeline %s %ux%u: open_to_session first %.1f ms, median of the rest %.1f ms\n", pipeline.c_str(),
              width, height, open_ms.empty() ? 0.0 : open_ms[0],
              open_ms.size() > 1 ? median(std::vector<double>(open_ms.begin() + 1, open_ms.end())) : 0.0);
  std::printf("streaming passthrough %ux%u: %zu frames; outside opens median %.2f ms worst %.2f ms; "
              "during opens (%zu frames) median %.2f ms worst %.2f ms\n",
              width, height, samples.size(), median(quiet), worst(quiet), during.size(), median(during),
              worst(during));
  return 0;
}
