// The watch key never on a command line: the hints dn denoise and dnrender
// --server print pass it in DN_WATCH_KEY or name a --watch-key-file (mode
// 0600) that dn watch / dn preview --key-file read; --key warns; a key file
// other users can read is refused.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <thread>

#include "command.hpp"
#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

namespace fs = std::filesystem;

const std::string kDn = DN_DN_PATH;
const std::string kWarning = "warning: --key puts the watch key in the process list";

// The command's exit status; `log` holds its output alone.
int run(const std::string& command, std::string& log) {
  log.clear();
  return run_command(command, log);
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

unsigned mode_of(const fs::path& path) {
  struct stat st {};
  EXPECT_EQ(::stat(path.c_str(), &st), 0) << path;
  return st.st_mode & 07777;
}

void write_file(const fs::path& path, const std::string& text, unsigned mode) {
  std::ofstream(path) << text;
  fs::permissions(path, fs::perms(mode), fs::perm_options::replace);
}

class WatchKey : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("dn-watch-key-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // One frame of dnsynth's scene denoised by `dn denoise` with `extra` options; its log.
  std::string denoise(const ServerProcess& server, const std::string& extra) {
    std::string log;
    EXPECT_EQ(run(std::string(DN_DNSYNTH_PATH) + " --out " + dir_.string() +
                              "/in --frames 1 --width 32 --height 18",
                          log),
              0)
        << log;
    EXPECT_EQ(run(kDn + " denoise --server " + server.tcp_url() +
                              " --pipeline passthrough --preset dnrender --input '" + dir_.string() +
                              "/in/frame_%04d.exr' " + extra,
                          log),
              0)
        << log;
    return log;
  }

  // Runs `command` (a dn watch of one frame) while an owner streams frames to its session.
  int watch_while_streaming(RawClient& owner, const protocol::OpenSession& request, uint64_t sid,
                            const std::string& command, std::string& log) {
    std::atomic<bool> done{false};
    int status = -1;
    std::thread watcher([&] {
      status = run(command, log);
      done = true;
    });
    uint64_t index = 0;
    try {
      for (int spins = 0; spins < 600 && !done; ++spins) {
        auto f = make_frame(sid, index, 48, 32, request.channels, 0.5f);
        owner.send(f.frame, ++index);
        if (!owner.receive()) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
      }
    } catch (const std::exception& e) {
      ADD_FAILURE() << "the owner's stream failed: " << e.what();
    }
    watcher.join();
    return status;
  }

  fs::path dir_;
};

TEST_F(WatchKey, DenoiseHintsPassTheKeyInTheEnvironment) {
  ServerProcess server;
  const std::string log = denoise(server, "");
  std::smatch watch, preview;
  ASSERT_TRUE(std::regex_search(log, watch,
                                std::regex("dn: session ([0-9]+) \\(watch it with: DN_WATCH_KEY=([0-9a-f]{32}) dn watch "
                                           "--server " + server.tcp_url() + " --session ([0-9]+) --output")))
      << log;
  EXPECT_EQ(watch[1], watch[3]);
  ASSERT_TRUE(std::regex_search(log, preview,
                                std::regex("dn: preview it with: DN_WATCH_KEY=([0-9a-f]{32}) dn preview --server " +
                                           server.tcp_url() + " --session ([0-9]+) \\(then open "
                                           "http://127\\.0\\.0\\.1:7879/\\)")))
      << log;
  EXPECT_EQ(preview[1], watch[2]);
  EXPECT_EQ(preview[2], watch[1]);
  EXPECT_EQ(log.find("--key "), std::string::npos) << "no hint puts the key on a command line\n" << log;
}

TEST_F(WatchKey, DenoiseWritesTheKeyFileItsHintsName) {
  ServerProcess server;
  const fs::path key_file = dir_ / "watch.key";
  const std::string log = denoise(server, "--watch-key-file " + key_file.string());
  ASSERT_TRUE(fs::exists(key_file)) << log;
  EXPECT_EQ(mode_of(key_file), 0600u);
  std::smatch file, hint;
  const std::string text = read_text(key_file);
  ASSERT_TRUE(std::regex_match(text, file, std::regex("([0-9a-f]{32})\nsession ([0-9]+)\n"))) << text;
  ASSERT_TRUE(std::regex_search(log, hint, std::regex("dn: session ([0-9]+) \\(watch it with: dn watch --server " +
                                                      server.tcp_url() + " --key-file " + key_file.string() +
                                                      " --output")))
      << log;
  EXPECT_EQ(hint[1], file[2]);
  EXPECT_NE(log.find("dn: preview it with: dn preview --server " + server.tcp_url() + " --key-file " +
                     key_file.string() + " (then open http://127.0.0.1:7879/)"),
            std::string::npos)
      << log;
  EXPECT_EQ(log.find(file[1].str()), std::string::npos) << "the key is in the file only\n" << log;
}

TEST_F(WatchKey, DnrenderWritesTheKeyFileItsHintsName) {
  ServerProcess server;
  const fs::path key_file = dir_ / "render.key";
  std::string log;
  ASSERT_EQ(run(std::string(DN_DNRENDER_PATH) + " --scene 1 --width 32 --height 18 --frames 1 --server " +
                            server.tcp_url() + " --pipeline passthrough --watch-key-file " + key_file.string(),
                        log),
            0)
      << log;
  std::smatch file;
  const std::string text = read_text(key_file);
  ASSERT_TRUE(std::regex_match(text, file, std::regex("([0-9a-f]{32})\nsession ([0-9]+)\n"))) << text;
  EXPECT_EQ(mode_of(key_file), 0600u);
  EXPECT_NE(log.find("dnrender: session " + file[2].str() + " (watch it with: dn watch --server " + server.tcp_url() +
                     " --key-file " + key_file.string() + " --output"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("dnrender: preview it with: dn preview --server " + server.tcp_url() + " --key-file " +
                     key_file.string()),
            std::string::npos)
      << log;
  EXPECT_EQ(log.find(file[1].str()), std::string::npos) << log;
}

// The three ways to give the key all watch; only --key warns.
TEST_F(WatchKey, OnlyAKeyOnTheCommandLineWarns) {
  ServerProcess server;
  RawClient owner(server.tcp_url());
  owner.hello();
  const auto request = passthrough_session(48, 32);
  const protocol::Session opened = owner.open_session(request);
  const std::string key = opened.watch_key.value_or("");
  const std::string sid = std::to_string(opened.session_id);
  const fs::path key_file = dir_ / "watch.key";
  write_file(key_file, key + "\nsession " + sid + "\n", 0600);
  const std::string watch = kDn + " watch --server " + server.tcp_url() + " --count 1 --timeout 60 --output '" +
                            dir_.string() + "/w_%04d.pfm'";
  std::string log;
  EXPECT_EQ(watch_while_streaming(owner, request, opened.session_id,
                                  "env -u DN_WATCH_KEY " + watch + " --session " + sid + " --key " + key, log),
            0)
      << log;
  EXPECT_NE(log.find("dn watch: " + kWarning), std::string::npos) << log;
  EXPECT_NE(log.find("pass it in DN_WATCH_KEY or a --key-file instead"), std::string::npos) << log;

  EXPECT_EQ(watch_while_streaming(owner, request, opened.session_id,
                                  "DN_WATCH_KEY=" + key + " " + watch + " --session " + sid, log),
            0)
      << log;
  EXPECT_EQ(log.find(kWarning), std::string::npos) << log;

  // The key file names the session too: no --session needed.
  EXPECT_EQ(watch_while_streaming(owner, request, opened.session_id,
                                  "env -u DN_WATCH_KEY " + watch + " --key-file " + key_file.string(), log),
            0)
      << log;
  EXPECT_EQ(log.find(kWarning), std::string::npos) << log;
  EXPECT_NE(log.find("dn: wrote 1 frame"), std::string::npos) << log;
}

// A key file others can read or write is refused before connecting (exit 2), as is a malformed one.
TEST_F(WatchKey, KeyFileOpenToOthersIsRefused) {
  const fs::path key_file = dir_ / "open.key";
  const std::string key(32, 'a');
  const std::string target = " --server tcp://127.0.0.1:1 --key-file " + key_file.string();
  std::string log;
  for (unsigned mode : {0644u, 0640u, 0602u}) {
    write_file(key_file, key + "\nsession 5\n", mode);
    char mode_text[8];
    std::snprintf(mode_text, sizeof mode_text, "%04o", mode);
    for (const std::string command : {"watch --output w_%04d.png", "preview --http 127.0.0.1:0"}) {
      EXPECT_EQ(run(kDn + " " + command + target, log), 2) << log;
      EXPECT_NE(log.find("watch key file " + key_file.string() + " is readable or writable by other users (mode " +
                         mode_text + "): the key is a secret; chmod 600 " + key_file.string()),
                std::string::npos)
          << log;
    }
  }
  write_file(key_file, "not a key\n", 0600);
  EXPECT_EQ(run(kDn + " watch --output w_%04d.png" + target, log), 2) << log;
  EXPECT_NE(log.find("the first line is not a watch key (32 lowercase hex digits)"), std::string::npos) << log;
  write_file(key_file, key + "\n", 0600);  // a key alone: the session must be given
  EXPECT_EQ(run(kDn + " watch --output w_%04d.png" + target, log), 2) << log;
  EXPECT_NE(log.find("missing --session: the key file " + key_file.string() + " names no session"), std::string::npos)
      << log;
  EXPECT_EQ(run(kDn + " watch --output w_%04d.png --session 5 --key " + key + target, log), 2) << log;
  EXPECT_NE(log.find("give the watch key once: --key-file FILE or --key KEY, not both"), std::string::npos) << log;
  EXPECT_EQ(run(kDn + " watch --output w_%04d.png --session 5 --key-file " + (dir_ / "none").string() +
                            " --server tcp://127.0.0.1:1",
                        log),
            2)
      << log;
  EXPECT_NE(log.find("watch key file " + (dir_ / "none").string() + ": No such file or directory"), std::string::npos)
      << log;
}

}  // namespace
}  // namespace dn::test
