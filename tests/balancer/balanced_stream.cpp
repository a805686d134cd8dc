// The client side of tests/balancer/haproxy_test.sh: SESSIONS sessions through
// the balancer, each on a connection of its own (client::ReconnectingSession),
// streaming small passthrough frames for SECONDS. Each session learns its
// backend from SESSION.watch_url (every backend advertises its own watch
// port). Meanwhile a watcher attaches to the first session through that port.
// The script watches the first session through the balancer, then kills its
// backend; that backend's sessions must come back on another one with one
// reset, every frame answered or reported lost.
//
//   balanced_stream URL SESSIONS SECONDS WATCH_FILE KILL_FILE
//
// Once every session streams, WATCH_FILE gets the first session's `dn watch`
// command (its --server is the session's watch URL); the script runs it and
// removes the file. Then KILL_FILE gets that session's backend (its watch
// URL); the script kills that backend and removes the file.
// Prints one line per session and the frame rates before and after; exits 1
// if a check fails (the reasons are printed).
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "dn/client/client.hpp"

using namespace dn;
using Clock = std::chrono::steady_clock;

namespace {

constexpr uint32_t kW = 32, kH = 18;

struct Outcome {
  std::string first_backend, last_backend;
  uint64_t submitted = 0, answered = 0, lost = 0, other_errors = 0, reordered = 0, reconnections = 0;
  uint64_t answered_before_kill = 0, answered_after_reconnect = 0;
  std::string error;  // why the session stopped early
};

std::atomic<bool> g_killed{false};
std::atomic<int> g_streaming{0};
std::mutex g_mutex;
std::string g_first_watch_command;  // session 0's, once open

// Writes `text` to `path` and waits until the script removes the file.
void hand_over(const std::string& path, const std::string& text) {
  { std::ofstream(path) << text << "\n"; }
  while (std::ifstream(path).good()) std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

void stream(const std::string& url, double seconds, Outcome& out, bool first) {
  client::SessionDesc desc;
  desc.width = kW;
  desc.height = kH;
  desc.pipeline = "passthrough";
  desc.channel(protocol::ChannelId::Radiance);
  client::ReconnectOptions ro;
  ro.give_up_after = std::chrono::seconds(60);
  try {
    client::ReconnectingSession s(url, desc, {}, ro);
    out.first_backend = out.last_backend = s.session()->watch_url();
    if (first) {
      std::lock_guard lock(g_mutex);
      g_first_watch_command = s.session()->watch_command();
    }
    std::vector<float> radiance(size_t(kW) * kH * 3);
    const auto end = Clock::now() + std::chrono::duration<double>(seconds);
    uint64_t last_index = 0;
    bool any = false, counted = false;
    while (Clock::now() < end) {
      for (size_t i = 0; i < radiance.size(); ++i) radiance[i] = float(out.submitted % 97) + float(i % 5);
      client::FrameInput in;
      in.add(protocol::ChannelId::Radiance, radiance);
      s.submit(in);
      ++out.submitted;
      if (s.session()) out.last_backend = s.session()->watch_url();
      if (!counted) {
        ++g_streaming;
        counted = true;
      }
      try {
        const client::Result r = s.wait();
        if (any && r.frame_index <= last_index) ++out.reordered;
        last_index = r.frame_index;
        any = true;
        ++out.answered;
        if (!g_killed) ++out.answered_before_kill;
        else if (s.reconnections() > 0) ++out.answered_after_reconnect;
      } catch (const client::Error& e) {
        if (e.kind() == client::ErrorKind::Transport) ++out.lost;
        else ++out.other_errors;
      }
    }
    out.reconnections = s.reconnections();
    s.close();
  } catch (const std::exception& e) {
    out.error = e.what();
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: balanced_stream URL SESSIONS SECONDS WATCH_FILE KILL_FILE\n");
    return 2;
  }
  const std::string url = argv[1], watch_file = argv[4], kill_file = argv[5];
  const int n = std::atoi(argv[2]);
  const double seconds = std::atof(argv[3]);
  std::vector<Outcome> outcomes(static_cast<size_t>(n));
  std::vector<std::thread> threads;
  const auto start = Clock::now();
  for (int i = 0; i < n; ++i) threads.emplace_back(stream, url, seconds, std::ref(outcomes[size_t(i)]), i == 0);

  // Wait until every session streams, then let them run a third of the time.
  while (g_streaming < n && Clock::now() - start < std::chrono::duration<double>(seconds / 2))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds / 3));

  std::string watch_command, kill_backend;
  {
    std::lock_guard lock(g_mutex);
    watch_command = g_first_watch_command;
  }
  hand_over(watch_file, watch_command);
  kill_backend = watch_command.substr(0, watch_command.find(" --session"));
  kill_backend = kill_backend.substr(kill_backend.rfind(' ') + 1);  // the --server of the command
  hand_over(kill_file, kill_backend);
  g_killed = true;
  const auto killed_at = Clock::now();
  const double before_s = std::chrono::duration<double>(killed_at - start).count();
  for (auto& t : threads) t.join();
  const double after_s = std::chrono::duration<double>(Clock::now() - killed_at).count();

  int failures = 0;
  auto fail = [&](const std::string& why) {
    std::printf("FAIL: %s\n", why.c_str());
    ++failures;
  };
  std::map<std::string, int> per_backend;
  uint64_t before_frames = 0, after_frames = 0;
  for (size_t i = 0; i < outcomes.size(); ++i) {
    const Outcome& o = outcomes[i];
    std::printf("session %2zu: %s -> %s  submitted %llu answered %llu lost %llu errors %llu reordered %llu reconnections %llu%s%s\n",
                i, o.first_backend.c_str(), o.last_backend.c_str(), (unsigned long long)o.submitted,
                (unsigned long long)o.answered, (unsigned long long)o.lost, (unsigned long long)o.other_errors,
                (unsigned long long)o.reordered, (unsigned long long)o.reconnections, o.error.empty() ? "" : "  error: ",
                o.error.c_str());
    ++per_backend[o.first_backend];
    before_frames += o.answered_before_kill;
    after_frames += o.answered - o.answered_before_kill;
    if (!o.error.empty()) fail("session " + std::to_string(i) + " stopped: " + o.error);
    if (o.reordered) fail("session " + std::to_string(i) + " got frames out of order");
    if (o.submitted != o.answered + o.lost + o.other_errors)
      fail("session " + std::to_string(i) + ": a frame neither answered nor reported lost");
    if (o.other_errors) fail("session " + std::to_string(i) + ": errors other than a lost connection");
    const bool on_killed = o.first_backend == kill_backend;
    if (on_killed && (o.reconnections < 1 || o.answered_after_reconnect == 0 || o.last_backend == o.first_backend))
      fail("session " + std::to_string(i) + " was on the killed backend and did not continue on another");
    if (!on_killed && o.reconnections != 0) fail("session " + std::to_string(i) + " reconnected without cause");
  }
  for (const auto& [backend, count] : per_backend) std::printf("backend %s: %d sessions\n", backend.c_str(), count);
  if (per_backend.size() < 3) fail("the sessions went to " + std::to_string(per_backend.size()) + " backends, not 3");
  for (const auto& [backend, count] : per_backend)
    if (count < n / 3 - 1) fail("backend " + backend + " got only " + std::to_string(count) + " sessions");
  std::printf("frames per second: %.1f before the kill, %.1f after (all sessions)\n", double(before_frames) / before_s,
              double(after_frames) / after_s);
  std::printf("%s\n", failures ? "FAIL" : "PASS");
  return failures ? 1 : 0;
}
