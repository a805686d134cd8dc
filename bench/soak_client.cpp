// The soak (bench/soak.sh): SESSIONS sessions across the server's pipelines,
// each streaming small frames on a connection of its own for a while, with
// the server's resident memory and device bytes sampled meanwhile. Prints a
// table and a verdict; exits 1 if a frame was lost or reordered, or the
// server's RSS grew by more than --max-rss-growth-mb after the warm-up part
// of the run (the first 20 %, at most 60 s).
//
//   soak_client --server URL [--server-pid PID] [--sessions N] [--seconds S]
//               [--interval S] [--size WxH] [--pipelines a,b,...] [--in-flight N]
//               [--max-rss-growth-mb M]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "dn/client/client.hpp"
#include "soak_stream.hpp"

namespace {

using Clock = std::chrono::steady_clock;

struct Args {
  std::string url;
  int server_pid = 0;
  int sessions = 8;
  double seconds = 60;
  double interval = 0;  // 0: a tenth of the run, at least 2 s
  uint32_t width = 64, height = 36;
  std::vector<std::string> pipelines;  // empty: every pipeline the server offers
  uint32_t in_flight = 2;
  double max_rss_growth_mb = 32;
  double max_rss_mb = 4096;  // the run stops when the server's RSS passes this: a leak must not take the machine
};

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr,
               "soak_client: %s\nusage: soak_client --server URL [--server-pid PID] [--sessions N] [--seconds S] "
               "[--interval S] [--size WxH] [--pipelines a,b,...] [--in-flight N] [--max-rss-growth-mb M] "
               "[--max-rss-mb M]\n",
               why.c_str());
  std::exit(2);
}

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (i + 1 >= argc) usage(k + " needs a value");
    const std::string v = argv[++i];
    if (k == "--server") a.url = v;
    else if (k == "--server-pid") a.server_pid = std::stoi(v);
    else if (k == "--sessions") a.sessions = std::stoi(v);
    else if (k == "--seconds") a.seconds = std::stod(v);
    else if (k == "--interval") a.interval = std::stod(v);
    else if (k == "--in-flight") a.in_flight = uint32_t(std::stoul(v));
    else if (k == "--max-rss-growth-mb") a.max_rss_growth_mb = std::stod(v);
    else if (k == "--max-rss-mb") a.max_rss_mb = std::stod(v);
    else if (k == "--size") {
      if (std::sscanf(v.c_str(), "%ux%u", &a.width, &a.height) != 2) usage("--size takes WxH, e.g. 64x36");
    } else if (k == "--pipelines") {
      std::stringstream ss(v);
      for (std::string p; std::getline(ss, p, ',');)
        if (!p.empty()) a.pipelines.push_back(p);
    } else {
      usage("unknown option " + k);
    }
  }
  if (a.url.empty()) usage("--server is required");
  if (a.sessions < 1 || a.seconds <= 0) usage("--sessions and --seconds must be positive");
  if (a.interval <= 0) a.interval = std::clamp(a.seconds / 20, 2.0, 30.0);
  return a;
}

// VmRSS of a process in MB, from /proc/PID/status; nullopt if it is gone.
std::optional<double> rss_mb(int pid) {
  if (pid <= 0) return std::nullopt;
  std::ifstream f("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(f, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // kB
  return std::nullopt;
}

double stat_value(const dn::protocol::Stats& st, const std::string& name) {
  for (const auto& v : st.values)
    if (v.name == name) return v.value;
  return 0.0;
}

struct Totals {
  uint64_t submitted = 0, done = 0, lost = 0, reordered = 0;
};

Totals totals(const std::vector<std::unique_ptr<dn::soak::Stream>>& streams) {
  Totals t;
  for (const auto& s : streams) {
    const auto c = s->counts();
    t.submitted += c.submitted;
    t.done += c.done;
    t.lost += c.lost;
    t.reordered += c.reordered;
  }
  return t;
}

std::string mb(std::optional<double> v) {
  if (!v) return "-";
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", *v);
  return b;
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  try {
    dn::client::ConnectOptions mon_opts;
    mon_opts.client_name = "dn-soak-monitor";
    dn::client::Connection monitor = dn::client::Connection::connect(args.url, mon_opts);

    std::vector<dn::protocol::PipelineInfo> cycle;
    for (const auto& p : monitor.welcome().pipelines)
      if (args.pipelines.empty() || std::find(args.pipelines.begin(), args.pipelines.end(), p.name) != args.pipelines.end())
        cycle.push_back(p);
    if (cycle.empty()) usage("the server offers none of the pipelines asked for");

    const auto t_open = Clock::now();
    std::vector<std::unique_ptr<dn::soak::Stream>> streams;
    std::string mix;
    for (int i = 0; i < args.sessions; ++i) {
      const auto& p = cycle[size_t(i) % cycle.size()];
      streams.push_back(std::make_unique<dn::soak::Stream>(args.url, p, args.width, args.height, args.in_flight));
      if (size_t(i) < cycle.size()) mix += (mix.empty() ? "" : ", ") + p.name;
    }
    std::printf("soak: %d sessions of %ux%u over %s (%zu pipelines in turn), %u frames in flight each; opened in "
                "%.1f s; server %s, device %s\n",
                args.sessions, args.width, args.height, args.url.c_str(), cycle.size(), args.in_flight,
                std::chrono::duration<double>(Clock::now() - t_open).count(), monitor.welcome().server_version.c_str(),
                monitor.welcome().device_name.c_str());
    std::printf("soak: pipelines: %s\n\n", mix.c_str());
    std::printf("| t (s) | server RSS (MB) | device (MB) | frames done | fps | lost | reordered |\n");
    std::printf("|---:|---:|---:|---:|---:|---:|---:|\n");
    std::fflush(stdout);

    const auto t0 = Clock::now();
    for (auto& s : streams) s->start();
    const double warm_s = std::min(60.0, 0.2 * args.seconds);
    std::optional<double> rss_baseline, rss_last, rss_peak;
    double device_mb_last = 0;
    Totals previous;
    double t_previous = 0;
    auto sample = [&](double t) {
      const Totals now = totals(streams);
      const auto rss = rss_mb(args.server_pid);
      // A server that went away still gets its row: the streams count what it lost.
      std::optional<double> device_mb;
      try {
        if (monitor.is_open()) device_mb = stat_value(monitor.stats(), "device_bytes") / 1e6;
      } catch (const dn::client::Error&) {
      }
      const double fps = t > t_previous ? double(now.done - previous.done) / (t - t_previous) : 0.0;
      std::printf("| %.0f | %s | %s | %llu | %.0f | %llu | %llu |\n", t, mb(rss).c_str(), mb(device_mb).c_str(),
                  (unsigned long long)now.done, fps, (unsigned long long)now.lost, (unsigned long long)now.reordered);
      std::fflush(stdout);
      if (rss) {
        if (!rss_baseline && t >= warm_s) rss_baseline = rss;
        rss_last = rss;
        rss_peak = std::max(rss_peak.value_or(0.0), *rss);
      }
      if (device_mb) device_mb_last = *device_mb;
      previous = now;
      t_previous = t;
    };
    auto at = [&](double t) { return t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(t)); };
    sample(0);
    // A row every interval; the RSS cap is checked every second in between.
    std::optional<double> stopped_at;
    for (int k = 1; !stopped_at; ++k) {
      const double t_row = std::min(args.seconds, k * args.interval);
      for (double t = t_row - args.interval + 1; t < t_row && !stopped_at; t += 1) {
        std::this_thread::sleep_until(at(t));
        if (rss_mb(args.server_pid).value_or(0) > args.max_rss_mb) stopped_at = t;
      }
      if (stopped_at) {
        sample(*stopped_at);
        break;
      }
      std::this_thread::sleep_until(at(t_row));
      sample(t_row);
      if (rss_last && *rss_last > args.max_rss_mb) stopped_at = t_row;
      if (t_row >= args.seconds) break;
    }
    for (auto& s : streams) s->request_stop();
    for (auto& s : streams) s->join();
    const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
    const Totals end = totals(streams);
    // Frames still in flight at the stop were drained above: anything not
    // done by now is lost.
    const uint64_t accounted = end.done + end.lost + end.reordered;
    const uint64_t unanswered = end.submitted > accounted ? end.submitted - accounted : 0;

    for (const auto& s : streams)
      if (!s->first_error().empty())
        std::printf("soak: %s session: %s\n", s->pipeline().c_str(), s->first_error().c_str());
    const double growth = rss_baseline && rss_last ? *rss_last - *rss_baseline : 0.0;
    const bool rss_ok = !stopped_at && (!rss_baseline || growth <= args.max_rss_growth_mb);
    if (stopped_at)
      std::printf("soak: stopped at %.0f s of %.0f: the server's RSS passed --max-rss-mb %.0f\n", *stopped_at,
                  args.seconds, args.max_rss_mb);
    const uint64_t lost = end.lost + unanswered;
    const bool ok = lost == 0 && end.reordered == 0 && rss_ok;
    std::printf("\nsoak: %s: %llu frames sent, %llu done in order (%.0f fps over %.0f s), %llu lost, %llu reordered; "
                "server RSS %s MB at %.0f s -> %s MB at the end (growth %.1f MB, bound %.0f MB), peak %s MB; "
                "device %.1f MB\n",
                ok ? "PASS" : "FAIL", (unsigned long long)end.submitted, (unsigned long long)end.done,
                double(end.done) / elapsed, elapsed, (unsigned long long)lost, (unsigned long long)end.reordered,
                mb(rss_baseline).c_str(), warm_s, mb(rss_last).c_str(), growth, args.max_rss_growth_mb,
                mb(rss_peak).c_str(), device_mb_last);
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "soak_client: %s\n", e.what());
    return 1;
  }
}
