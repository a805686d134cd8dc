// Session set-up off the event loop and the on-disk pipeline cache, against a
// real dnserver process.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>

#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

namespace fs = std::filesystem;
using protocol::ChannelId;
using protocol::Format;

// A fresh private directory under the test's temporary directory.
fs::path temp_dir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("dn-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

protocol::OpenSession svgf_session(uint32_t width, uint32_t height) {
  protocol::OpenSession o;
  o.width = width;
  o.height = height;
  o.pipeline = "svgf";
  for (auto id : {ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion})
    o.channels.push_back({id, Format::F32});
  return o;
}

// Sets an environment variable for the servers this test starts.
struct ScopedEnv {
  std::string name;
  ScopedEnv(std::string n, const std::string& value) : name(std::move(n)) { ::setenv(name.c_str(), value.c_str(), 1); }
  ~ScopedEnv() { ::unsetenv(name.c_str()); }
};

// While one client's session is being built (held by the test hook until the
// test releases it), another connection opens a session and gets its frames
// back: building never happens on the event loop.
TEST(SessionBuild, OtherConnectionsAreServedWhileASessionIsBeingBuilt) {
  const fs::path hold = temp_dir("hold-builds");
  ScopedEnv env("DN_TEST_HOLD_BUILDS", hold.string());
  ServerProcess server({"--no-warm-up", "--no-disk-cache"});

  RawClient slow(server.tcp_url());
  slow.hello();
  slow.send(svgf_session(64, 36), 7);  // held in the builder

  RawClient busy(server.tcp_url());
  busy.hello();
  // The held build holds every build: this one too, so it waits for the release below.
  busy.send(passthrough_session(32, 16), 1);
  // Meanwhile the loop answers everything that needs no build.
  busy.send(protocol::Ping{42}, 2);
  auto pong = busy.receive();
  ASSERT_TRUE(pong);
  ASSERT_TRUE(std::get_if<protocol::Pong>(&pong->message));
  EXPECT_EQ(pong->header.request_id, 2u);
  const auto st = stats(busy);
  EXPECT_EQ(st.at("sessions_being_built"), 2.0);
  EXPECT_EQ(st.at("sessions"), 0.0);

  // Release: both sessions open, in the order they were asked for.
  std::ofstream(hold).put('1');
  auto reply = slow.receive();
  ASSERT_TRUE(reply);
  auto* opened = std::get_if<protocol::Session>(&reply->message);
  ASSERT_NE(opened, nullptr) << protocol::to_string(reply->header.type);
  EXPECT_EQ(reply->header.request_id, 7u);
  auto busy_reply = busy.receive();
  ASSERT_TRUE(busy_reply);
  auto* busy_session = std::get_if<protocol::Session>(&busy_reply->message);
  ASSERT_NE(busy_session, nullptr);
  auto f = make_frame(busy_session->session_id, 0, 32, 16, passthrough_session(32, 16).channels, 1.5f);
  busy.send(f.frame, 3);
  auto result = busy.receive();
  ASSERT_TRUE(result);
  EXPECT_TRUE(std::get_if<protocol::Result>(&result->message));
  fs::remove_all(hold);
}

// A connection that goes away while its session is being built leaves
// nothing behind: the built pipeline is dropped and the slot is free again.
TEST(SessionBuild, ClosingDuringTheBuildDropsTheSession) {
  const fs::path hold = temp_dir("hold-drop");
  ScopedEnv env("DN_TEST_HOLD_BUILDS", hold.string());
  ServerProcess server({"--no-warm-up", "--no-disk-cache", "--max-sessions", "1"});
  {
    RawClient gone(server.tcp_url());
    gone.hello();
    gone.send(passthrough_session(32, 16), 1);
    RawClient other(server.tcp_url());
    other.hello();
    other.send(passthrough_session(32, 16), 2);  // the one slot is taken by the build in progress
    auto refused = other.receive();
    ASSERT_TRUE(refused);
    auto* err = std::get_if<protocol::Error>(&refused->message);
    ASSERT_NE(err, nullptr);
    EXPECT_EQ(err->code, protocol::ErrorCode::LimitExceeded);
  }
  std::ofstream(hold).put('1');
  RawClient later(server.tcp_url());
  later.hello();
  // The dropped build frees its slot once it finishes; the next open may race it, so retry on LIMIT.
  uint64_t sid = 0;
  for (int attempt = 0; attempt < 100 && sid == 0; ++attempt) {
    later.send(passthrough_session(32, 16), 10 + attempt);
    auto r = later.receive();
    ASSERT_TRUE(r);
    if (auto* s = std::get_if<protocol::Session>(&r->message)) sid = s->session_id;
    else ::usleep(50000);
  }
  EXPECT_NE(sid, 0u);
  const auto st = stats(later);
  EXPECT_EQ(st.at("sessions"), 1.0);
  EXPECT_EQ(st.at("sessions_being_built"), 0.0);
  fs::remove_all(hold);
}

// The warm-up compiles the default pipelines at start and writes the cache
// file (private to this user); a restarted server loads it.
TEST(SessionBuild, WarmUpWritesThePipelineCacheAndARestartLoadsIt) {
  const fs::path dir = temp_dir("cache");
  uint64_t saved = 0;
  {
    ServerProcess server({"--warm-up", "--cache-dir", dir.string()});
    RawClient c(server.tcp_url());
    c.hello();
    std::map<std::string, double> st;
    for (int i = 0; i < 2400; ++i) {  // up to 4 minutes for a cold shader cache (ctest allows 300 s)
      st = stats(c);
      if (st.at("warm_up_done") == 1.0) break;
      ::usleep(100000);
    }
    ASSERT_EQ(st.at("warm_up_done"), 1.0);
    EXPECT_GT(st.at("warm_up_kernels"), 0.0);
    EXPECT_EQ(st.at("pipeline_cache_loaded_bytes"), 0.0);  // a new directory
    EXPECT_TRUE(fs::is_directory(dir));
    struct stat ds {};
    ASSERT_EQ(::stat(dir.c_str(), &ds), 0);
    EXPECT_EQ(ds.st_mode & 0777, 0700u);
    // A session of a default pipeline needs no compiling now.
    const double compiled = st.at("kernels_compiled");
    RawClient s(server.tcp_url());
    s.hello();
    s.open(svgf_session(64, 36));
    EXPECT_EQ(stats(c).at("kernels_compiled"), compiled);
  }
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path());
  ASSERT_EQ(files.size(), 1u);  // no temporary left behind
  EXPECT_EQ(files[0].filename().string().rfind("pipelines-", 0), 0u);
  saved = fs::file_size(files[0]);
  EXPECT_GE(saved, 32u);  // at least the VkPipelineCacheHeaderVersionOne header
  struct stat fst {};
  ASSERT_EQ(::stat(files[0].c_str(), &fst), 0);
  EXPECT_EQ(fst.st_mode & 0777, 0600u);

  ServerProcess again({"--cache-dir", dir.string(), "--no-warm-up"});
  RawClient c(again.tcp_url());
  c.hello();
  EXPECT_EQ(stats(c).at("pipeline_cache_loaded_bytes"), static_cast<double>(saved));
  fs::remove_all(dir);
}

// A cache file from another device or a corrupt one is ignored, never handed to the driver.
TEST(SessionBuild, AForeignCacheFileIsIgnored) {
  const fs::path dir = temp_dir("foreign-cache");
  // Let a server write this device's cache file, then replace its contents with garbage.
  std::string name;
  {
    ServerProcess server({"--warm-up", "--cache-dir", dir.string()});
    RawClient c(server.tcp_url());
    c.hello();
    for (int i = 0; i < 2400 && stats(c).at("warm_up_done") != 1.0; ++i) ::usleep(100000);
  }
  for (const auto& e : fs::directory_iterator(dir)) name = e.path().filename().string();
  ASSERT_FALSE(name.empty());
  {
    std::ofstream out(dir / name, std::ios::binary | std::ios::trunc);
    for (int i = 0; i < 64; ++i) out.put(static_cast<char>(0xA5));
  }
  ServerProcess again({"--cache-dir", dir.string(), "--no-warm-up"});
  RawClient c(again.tcp_url());
  c.hello();
  EXPECT_EQ(stats(c).at("pipeline_cache_loaded_bytes"), 0.0);
  c.open(passthrough_session(32, 16));  // and the server works
  fs::remove_all(dir);
}

// An explicit cache directory that other users could write to is refused at start.
TEST(SessionBuild, AnUnsafeCacheDirectoryIsRefused) {
  const fs::path dir = temp_dir("unsafe-cache");
  fs::create_directories(dir);
  ::chmod(dir.c_str(), 0777);
  try {
    ServerProcess server({"--warm-up", "--cache-dir", dir.string()});
    ADD_FAILURE() << "dnserver started with a world-writable cache directory";
  } catch (const std::exception& e) {
    const std::string log = e.what();
    EXPECT_NE(log.find("--cache-dir"), std::string::npos) << log;
    EXPECT_NE(log.find("writable by group or others"), std::string::npos) << log;
  }
  fs::remove(dir);
  fs::create_directories(dir.parent_path());
  fs::create_directory_symlink("/tmp", dir);
  try {
    ServerProcess server({"--warm-up", "--cache-dir", dir.string()});
    ADD_FAILURE() << "dnserver started with a symlinked cache directory";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("symbolic link"), std::string::npos) << e.what();
  }
  fs::remove(dir);
}

}  // namespace
}  // namespace dn::test

namespace dn::test {
namespace {

// STATS splits a session's device memory into what it holds (persistent) and
// the scratch it leases per frame from the device's pool, shared by sessions.
TEST(SessionBuild, StatsSplitPersistentAndPooledScratch) {
  ServerProcess server;
  RawClient c(server.tcp_url());
  c.hello();
  const uint32_t w = 64, h = 36;
  const auto request = svgf_session(w, h);
  const uint64_t sid = c.open(request);
  auto f = make_frame(sid, 0, w, h, request.channels, 0.5f);
  c.send(f.frame, 5);
  // Lavapipe compiles each kernel at its first dispatch: seconds each with a cold Mesa cache.
  auto r = c.receive(110.0);
  ASSERT_TRUE(r) << server.log();
  ASSERT_TRUE(std::get_if<protocol::Result>(&r->message));
  const auto st = stats(c);
  const std::string prefix = "session." + std::to_string(sid) + ".";
  const double persistent = st.at(prefix + "persistent_bytes_per_pixel");
  const double transient = st.at(prefix + "transient_bytes_per_pixel");
  EXPECT_GT(persistent, 0.0);
  EXPECT_GT(transient, 0.0);
  // The two parts add up to what the session needs (device_bytes, constants buffer included).
  EXPECT_NEAR((persistent + transient) * w * h, st.at("device_bytes"), 1.0);
  EXPECT_NEAR(persistent * w * h, st.at("persistent_bytes"), 1.0);
  EXPECT_GE(st.at("transient_pool_bytes"), transient * w * h);  // the frame leased it from the pool
  EXPECT_EQ(st.at("transient_pool_in_use_bytes"), 0.0);         // and gave it back
}

}  // namespace
}  // namespace dn::test
