// The command-line tools against a real dnserver process: dnsynth renders a
// short sequence, dn denoise streams it through the server, dn watch attaches
// to a running session.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "raw_client.hpp"
#include "server_process.hpp"

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

TEST_F(Cli, WatchWritesTheSessionsLatestFrames) {
  // A short idle timeout: the watcher only receives, so it must answer the
  // server's heartbeat PINGs to stay attached while frames trickle in.
  ServerProcess server({"--heartbeat", "0.2", "--idle-timeout", "1"});
  RawClient owner(server.tcp_url());
  owner.hello();
  auto request = passthrough_session(48, 32);
  uint64_t sid = owner.open(request);

  const std::string out = dir_.string() + "/watch";
  std::string log;
  std::thread watcher([&] {
    shell(std::string(DN_DN_PATH) + " watch --server " + server.tcp_url() + " --session " + std::to_string(sid) +
              " --output '" + out + "/w_%04d.png' --count 3 --timeout 30",
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

}  // namespace
}  // namespace dn::test
