// A renderer stand-in for the browser-preview test: opens a session (the
// owner sharing its input), prints "session ID KEY", waits for "go" on stdin,
// streams N deterministic frames (a moving gradient with a bright highlight),
// prints "done N", writes the last frame's radiance to a PFM, then holds the
// session open until stdin closes. With WATCH_KEY_FILE it also writes the
// session's key and id there, as dnrender --watch-key-file does.
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "dn/client/client.hpp"
#include "dn/client/watch_file.hpp"
#include "dn/image/pfm.hpp"

using namespace dn;
using protocol::ChannelId;

int main(int argc, char** argv) {
  if (argc != 7 && argc != 8) {
    std::fprintf(stderr, "usage: stream_and_hold URL PIPELINE FRAMES WIDTH HEIGHT LAST_INPUT.pfm [WATCH_KEY_FILE]\n");
    return 2;
  }
  const std::string url = argv[1], pipeline = argv[2], last_input = argv[6];
  const int frames = std::atoi(argv[3]);
  const uint32_t w = uint32_t(std::atoi(argv[4])), h = uint32_t(std::atoi(argv[5]));
  try {
    client::Connection conn = client::Connection::connect(url, {});
    client::SessionDesc desc;
    desc.width = w;
    desc.height = h;
    desc.pipeline = pipeline;
    desc.share_input = true;
    desc.channel(ChannelId::Radiance).channel(ChannelId::Albedo).channel(ChannelId::Normal);
    desc.channel(ChannelId::Depth).channel(ChannelId::Motion);
    client::Session session = conn.open_session(desc);
    if (argc == 8) client::write_watch_file(argv[7], {session.watch_key(), session.id()});
    std::printf("session %llu %s\n", (unsigned long long)session.id(), session.watch_key().c_str());
    std::fflush(stdout);
    std::string line;
    if (!std::getline(std::cin, line) || line != "go") return 1;

    std::vector<float> radiance(size_t(w) * h * 3), albedo(radiance.size(), 0.7f), normal(radiance.size(), 0.0f);
    std::vector<float> depth(size_t(w) * h, 2.0f), motion(size_t(w) * h * 2, 0.0f);
    for (size_t i = 2; i < normal.size(); i += 3) normal[i] = 1.0f;
    for (int f = 0; f < frames; ++f) {
      for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
          float* p = &radiance[(size_t(y) * w + x) * 3];
          const float u = float(x) / float(w), v = float(y) / float(h);
          p[0] = 0.1f + 0.9f * u;
          p[1] = 0.2f + 0.6f * v + 0.02f * float(f);
          p[2] = 0.5f * (1.0f - u);
          if (x / 8 == uint32_t(f) % (w / 8) && y / 8 == 1) p[0] = p[1] = p[2] = 20.0f;  // an HDR highlight
        }
      client::FrameInput in;
      in.add(ChannelId::Radiance, radiance).add(ChannelId::Albedo, albedo).add(ChannelId::Normal, normal);
      in.add(ChannelId::Depth, depth).add(ChannelId::Motion, motion);
      session.denoise(in);
    }
    image::write_pfm_rgb(last_input, int(w), int(h), radiance.data());
    std::printf("done %d\n", frames);
    std::fflush(stdout);
    while (std::getline(std::cin, line)) {
    }
    session.close();
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stream_and_hold: %s\n", e.what());
    return 1;
  }
}
