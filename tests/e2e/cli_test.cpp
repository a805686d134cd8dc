// The command-line tools against a real dnserver process: dnsynth renders a
// short sequence, dn denoise streams it through the server, dn watch attaches
// to a running session.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include "dn/image/exr_io.hpp"
#include "dn/image/pfm.hpp"
#include "raw_client.hpp"
#include "server_process.hpp"
#include "summary_file.hpp"

namespace dn::test {
namespace {

namespace fs = std::filesystem;

// Runs a command, capturing its output in a file of its own: ctest runs tests in parallel
// processes, and tests in one process run commands from several threads.
int shell(const std::string& command, std::string* output = nullptr) {
  static std::atomic<int> counter{0};
  const std::string path = "/tmp/dn-cli-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".out";
  std::string cmd = command + " > " + path + " 2>&1";
  int status = std::system(cmd.c_str());
  struct Remove {
    const std::string& p;
    ~Remove() { std::filesystem::remove(p); }
  } remove{path};
  if (output) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    *output = ss.str();
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Mean RMSE from a `dn denoise --summary` file (second line, first column).
double summary_rmse(const std::string& path) {
  std::ifstream in(path);
  std::string header, values;
  std::getline(in, header);
  std::getline(in, values);
  return std::stod(values.substr(0, values.find('\t')));
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("dn-cli-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    ASSERT_EQ(shell(std::string(DN_DNSYNTH_PATH) + " --out " + dir_.string() + "/in --frames 6 --width 96 --height 64"), 0);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(Cli, DenoiseSequenceThroughRealServer) {
  ServerProcess server;
  std::map<std::string, double> rmse;
  for (const char* pipeline : {"passthrough", "accumulate"}) {
    const std::string out = dir_.string() + "/" + pipeline;
    std::string log;
    int rc = shell(std::string(DN_DN_PATH) + " denoise --server " + server.tcp_url() + " --pipeline " + pipeline +
                       " --preset dnrender --input '" + dir_.string() + "/in/frame_%04d.exr' --start 0 --end 5" +
                       " --output '" + out + "/f_%04d.exr' --png '" + out + "/f_%04d.png' -r '" + dir_.string() +
                       "/in/ref_%04d.exr' --summary " + out + "/summary.tsv",
                   &log);
    ASSERT_EQ(rc, 0) << log;
    for (int i = 0; i < 6; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "/f_%04d", i);
      EXPECT_TRUE(fs::exists(out + name + ".exr")) << name;
      EXPECT_GT(fs::file_size(out + name + ".png"), 100u) << name;
    }
    rmse[pipeline] = summary_rmse(out + "/summary.tsv");
  }
  // Temporal accumulation of unit-variance noise must beat the noisy input.
  EXPECT_LT(rmse["accumulate"], 0.8 * rmse["passthrough"]);
}

// The summary's device time, temporal error and device memory, checked
// against the per-frame log and a direct computation over the written frames.
TEST_F(Cli, SummaryReportsDeviceTimeTemporalErrorAndDeviceBytes) {
  ServerProcess server;
  const std::string out = dir_.string() + "/summary";
  std::string log;
  int rc = shell(std::string(DN_DN_PATH) + " denoise --server " + server.tcp_url() +
                     " --pipeline accumulate --preset dnrender --input '" + dir_.string() +
                     "/in/frame_%04d.exr' --start 0 --end 5 --exr-float --output '" + out + "/f_%04d.exr' --summary " +
                     out + "/summary.tsv",
                 &log);
  ASSERT_EQ(rc, 0) << log;
  auto columns = summary_columns(out + "/summary.tsv");
  for (const char* name : {"device_ms", "server_ms", "temporal", "device_bytes_per_pixel", "frames"})
    ASSERT_TRUE(columns.count(name)) << name;
  EXPECT_EQ(columns["frames"], 6);
  EXPECT_GT(columns["device_ms"], 0.0);
  EXPECT_LT(columns["device_ms"], columns["server_ms"]);  // server time adds upload and download
  // accumulate holds at least its fp32 history (colour + length) and the
  // declared fp32 planes; well under a kilobyte a pixel.
  EXPECT_GE(columns["device_bytes_per_pixel"], 16.0);
  EXPECT_LT(columns["device_bytes_per_pixel"], 1024.0);

  // Per consecutive pair: the mean |Y_t - Y_{t-1}|, Rec. 709 luminance.
  std::vector<double> pair_error;
  std::vector<float> previous;
  for (int i = 0; i < 6; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "/f_%04d.exr", i);
    int w = 0, h = 0;
    std::vector<float> rgb = image::read_exr_rgb(out + name, w, h);
    if (!previous.empty()) {
      double d = 0.0;
      for (size_t p = 0; p < rgb.size(); p += 3) {
        const double y = 0.2126 * rgb[p] + 0.7152 * rgb[p + 1] + 0.0722 * rgb[p + 2];
        const double y0 = 0.2126 * previous[p] + 0.7152 * previous[p + 1] + 0.0722 * previous[p + 2];
        d += std::fabs(y - y0);
      }
      pair_error.push_back(d / double(rgb.size() / 3));
    }
    previous = std::move(rgb);
  }
  const double all_pairs = (pair_error[0] + pair_error[1] + pair_error[2] + pair_error[3] + pair_error[4]) / 5.0;
  EXPECT_NEAR(columns["temporal"], all_pairs, 1e-4 * all_pairs);

  // --warmup 2: frames 2..5 measured, pairs (3,2) (4,3) (5,4).
  rc = shell(std::string(DN_DN_PATH) + " denoise --server " + server.tcp_url() +
                 " --pipeline accumulate --preset dnrender --input '" + dir_.string() +
                 "/in/frame_%04d.exr' --start 0 --end 5 --warmup 2 --summary " + out + "/warm.tsv",
             &log);
  ASSERT_EQ(rc, 0) << log;
  auto warm = summary_columns(out + "/warm.tsv");
  EXPECT_EQ(warm["frames"], 4);
  const double late_pairs = (pair_error[2] + pair_error[3] + pair_error[4]) / 3.0;
  EXPECT_NEAR(warm["temporal"], late_pairs, 1e-4 * late_pairs);
}

TEST_F(Cli, DenoiseFailsClearlyOnServerError) {
  ServerProcess server;
  std::string log;
  int rc = shell(std::string(DN_DN_PATH) + " denoise --server " + server.tcp_url() +
                     " --pipeline no-such-pipeline --preset dnrender --input '" + dir_.string() +
                     "/in/frame_%04d.exr' --start 0 --end 1",
                 &log);
  EXPECT_NE(rc, 0);
  EXPECT_NE(log.find("no-such-pipeline"), std::string::npos) << log;
}

// The hint dn denoise prints is a command that watches the session: with its watch key.
TEST_F(Cli, DenoisePrintsTheWatchCommandWithTheKey) {
  ServerProcess server;
  std::string log;
  int rc = shell(std::string(DN_DN_PATH) + " denoise --server " + server.tcp_url() +
                     " --pipeline accumulate --preset dnrender --input '" + dir_.string() +
                     "/in/frame_%04d.exr' --start 0 --end 0",
                 &log);
  ASSERT_EQ(rc, 0) << log;
  const std::regex hint("dn: session ([0-9]+) \\(watch it with: DN_WATCH_KEY=[0-9a-f]{32} dn watch --server " +
                        server.tcp_url() + " --session ([0-9]+) --output 'watch/%04d.png'\\)");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(log, m, hint)) << log;
  EXPECT_EQ(m[1].str(), m[2].str());
}

TEST_F(Cli, WatchNeedsAWellFormedKey) {
  const std::string watch = std::string(DN_DN_PATH) + " watch --server tcp://127.0.0.1:1 --session 5 --output w.png";
  std::string log;
  EXPECT_EQ(shell("env -u DN_WATCH_KEY " + watch, &log), 2) << log;
  EXPECT_NE(log.find("missing the watch key: set DN_WATCH_KEY or give --key-file FILE"), std::string::npos) << log;
  EXPECT_EQ(shell(watch + " --key 0123456789ABCDEF0123456789abcdef", &log), 2) << log;
  EXPECT_NE(log.find("--key: expected the session's watch key, 32 lowercase hex digits, got "
                     "'0123456789ABCDEF0123456789abcdef'"),
            std::string::npos)
      << log;
  // The key may come from the environment instead (here a short one, refused the same way).
  EXPECT_EQ(shell("DN_WATCH_KEY=abc " + watch, &log), 2) << log;
  EXPECT_NE(log.find("got 'abc' (3 characters)"), std::string::npos) << log;
}

TEST_F(Cli, WatchWritesTheSessionsLatestFrames) {
  // A short idle timeout: the watcher only receives, so it must answer the
  // server's heartbeat PINGs to stay attached while frames trickle in.
  ServerProcess server({"--heartbeat", "0.2", "--idle-timeout", "1"});
  RawClient owner(server.tcp_url());
  owner.hello();
  auto request = passthrough_session(48, 32);
  const protocol::Session opened = owner.open_session(request);
  const uint64_t sid = opened.session_id;

  const std::string out = dir_.string() + "/watch";
  std::string log;
  std::thread watcher([&] {
    shell(std::string(DN_DN_PATH) + " watch --server " + server.tcp_url() + " --session " + std::to_string(sid) +
              " --key " + opened.watch_key.value_or("") + " --output '" + out + "/w_%04d.png' --count 3 --timeout 30",
          &log);
  });
  // Stream frames until the watcher has written three and exited.
  uint64_t index = 0;
  for (int spins = 0; spins < 600; ++spins) {
    auto f = make_frame(sid, index, 48, 32, request.channels, 0.5f);
    owner.send(f.frame, ++index);
    ASSERT_TRUE(owner.receive());
    int pngs = fs::exists(out) ? static_cast<int>(std::distance(fs::directory_iterator(out), fs::directory_iterator())) : 0;
    if (pngs >= 3) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(600));
  }
  watcher.join();
  ASSERT_TRUE(fs::exists(out)) << log;
  EXPECT_EQ(std::distance(fs::directory_iterator(out), fs::directory_iterator()), 3) << log;
}

// Every command: a bad command line is exit status 2, found before connecting
// (the address given is one where nothing listens, so a check that came too late would say 1).
TEST_F(Cli, BadCommandLinesExitWithTwo) {
  const std::string dn = std::string(DN_DN_PATH);
  const std::string nowhere = " --server tcp://127.0.0.1:1";
  const std::string key = " --key 00112233445566778899aabbccddeeff";
  const std::string denoise =
      dn + " denoise" + nowhere + " --pipeline passthrough --input '" + dir_.string() + "/in/frame_%04d.exr'";
  const std::vector<std::string> commands = {
      dn,
      dn + " frobnicate",
      dn + " ping --bogus",
      dn + " ping" + nowhere + " --count",
      dn + " ping" + nowhere + " --count x",
      dn + " ping" + nowhere + " --timeout -1",
      dn + " ping --server http://127.0.0.1:1",
      dn + " stats" + nowhere + " --raw=1",
      dn + " stats" + nowhere + " positional",
      dn + " pipelines" + nowhere + " --timeout nan",
      dn + " watch" + nowhere + " --session 0" + key + " --output 'w_%04d.png'",
      dn + " watch" + nowhere + " --session 5" + key + " --output 'w_%04d.jpg'",
      dn + " watch" + nowhere + " --session 5" + key + " --output 'w_%04d.png' --count -1",
      denoise + " --output 'o_%04d.tif'",
      denoise + " --output 'o_%04d'",
      denoise + " --fail 0.1",
      denoise + " -r '" + dir_.string() + "/in/ref_%04d.exr' --fail 0.1 --fail-metric ssim",
      denoise + " --start 5 --end 1",
      denoise + " --exr-float --output 'o_%04d.png'",
      denoise + " --timeout abc",
      denoise + " --preset blender",
  };
  for (const std::string& command : commands) {
    std::string log;
    EXPECT_EQ(shell(command, &log), 2) << command << "\n" << log;
  }
}

// Neither --server nor $DN_SERVER: dnserver's default address, whether or not a server is there.
TEST_F(Cli, DefaultServerAddressWhenNoneIsGiven) {
  std::string log;
  const int rc = shell("env -u DN_SERVER " + std::string(DN_DN_PATH) + " ping --count 1 --timeout 10", &log);
  EXPECT_NE(rc, 2) << log;
  // Nothing there: the transport error names the address; a server there: ping names it, or it
  // answered (a token-protected one refuses with a server error that names no address).
  EXPECT_TRUE(log.find("tcp://127.0.0.1:7878") != std::string::npos || log.find("server error") != std::string::npos)
      << log;
  ASSERT_EQ(shell(std::string(DN_DN_PATH) + " stats --help", &log), 0);
  EXPECT_NE(log.find("else tcp://127.0.0.1:7878"), std::string::npos) << log;
}

// No --start/--end: the four frames on disk; --fail decides the exit status (0 within, 3 above).
TEST_F(Cli, DenoiseDetectsTheRangeAndFailsAboveTheThreshold) {
  const std::string small = dir_.string() + "/small";
  ASSERT_EQ(shell(std::string(DN_DNSYNTH_PATH) + " --out " + small + " --frames 4 --width 64 --height 36"), 0);
  ServerProcess server;
  const std::string base = std::string(DN_DN_PATH) + " denoise --server " + server.tcp_url() +
                           " --pipeline passthrough --preset dnrender --input '" + small + "/frame_%04d.exr' -r '" +
                           small + "/ref_%04d.exr' --output '" + small + "/out/f_%04d.pfm'";
  std::string log;
  ASSERT_EQ(shell(base + " --fail 1e30", &log), 0) << log;
  EXPECT_NE(log.find("dn: frames 0..3 (4 files) found from"), std::string::npos) << log;
  EXPECT_NE(log.find("PASS: 0 of 4 frames"), std::string::npos) << log;
  for (int i = 0; i < 4; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "/out/f_%04d.pfm", i);
    int w = 0, h = 0;
    EXPECT_EQ(image::read_pfm_rgb(small + name, w, h).size(), size_t(64 * 36 * 3)) << name;
  }
  // The passthrough output is the noisy input: every frame's RMSE is far above 1e-6.
  EXPECT_EQ(shell(base + " --fail 1e-6 --fail-metric rmse", &log), 3) << log;
  EXPECT_NE(log.find("FAILURE: 4 of 4 frames (100 %) have rmse above 1e-06"), std::string::npos) << log;
}

// The owner closing its session ends a watch normally (exit 0), even before --count frames.
TEST_F(Cli, WatchReportsTheSessionsEndAsNormal) {
  ServerProcess server;
  RawClient owner(server.tcp_url());
  owner.hello();
  auto request = passthrough_session(48, 32);
  const protocol::Session opened = owner.open_session(request);
  const uint64_t sid = opened.session_id;

  const std::string out = dir_.string() + "/watch_end";
  std::string log;
  int rc = -1;
  std::thread watcher([&] {
    rc = shell(std::string(DN_DN_PATH) + " watch --server " + server.tcp_url() + " --session " + std::to_string(sid) +
                   " --key " + opened.watch_key.value_or("") + " --output '" + out + "/w_%04d.png' --count 1000" +
                   " --timeout 60",
               &log);
  });
  // Frames until the watcher has written one (so it is attached), then close the session.
  uint64_t index = 0;
  for (int spins = 0; spins < 600; ++spins) {
    auto f = make_frame(sid, index, 48, 32, request.channels, 0.5f);
    owner.send(f.frame, ++index);
    ASSERT_TRUE(owner.receive());
    if (fs::exists(out) && !fs::is_empty(out)) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  owner.send(protocol::CloseSession{sid}, ++index);
  watcher.join();
  EXPECT_EQ(rc, 0) << log;
  EXPECT_NE(log.find("dn: session " + std::to_string(sid) + " ended normally after"), std::string::npos) << log;
  EXPECT_EQ(log.find("error"), std::string::npos) << log;
}

// dn stats: units and rounded numbers in one column; --raw the exact values.
TEST_F(Cli, StatsPrintsReadableNumbers) {
  ServerProcess server;
  std::string log;
  ASSERT_EQ(shell(std::string(DN_DN_PATH) + " stats --server " + server.tcp_url(), &log), 0) << log;
  EXPECT_TRUE(std::regex_search(log, std::regex("(^|\n)uptime_s +[0-9.,]+ (ms|s|min|h)\n"))) << log;
  EXPECT_TRUE(std::regex_search(log, std::regex("(^|\n)device_bytes +[0-9.,]+ (B|kB|MB|GB)\n"))) << log;
  EXPECT_TRUE(std::regex_search(log, std::regex("(^|\n)connections_accepted +[0-9,]+\n"))) << log;
  // What bench/lib/bench_server.sh waits for.
  EXPECT_TRUE(std::regex_search(log, std::regex("(^|\n)warm_up_done +[01]\n"))) << log;
  std::regex long_number("[0-9]\\.[0-9]{4,}");
  EXPECT_FALSE(std::regex_search(log, long_number)) << "more than 3 significant digits:\n" << log;
  ASSERT_EQ(shell(std::string(DN_DN_PATH) + " stats --raw --server " + server.tcp_url(), &log), 0) << log;
  EXPECT_TRUE(std::regex_search(log, std::regex("(^|\n)uptime_s +[0-9.e+-]+\n"))) << log;
}

}  // namespace
}  // namespace dn::test
