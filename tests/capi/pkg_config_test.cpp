// docs/client.md's C example built the way the page says a C program is
// built, `cc prog.c $(pkg-config --cflags --libs dn)`: once against the build
// tree (PKG_CONFIG_PATH=<build>/client, dn-uninstalled.pc) and once against
// `cmake --install` into a fresh prefix (its lib/pkgconfig/dn.pc); each
// program then runs against a real dnserver and must exit 0.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "command.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

constexpr const char* kDocCExamples[] = {DN_DOC_C_EXAMPLES};

std::string shell_quoted(const std::string& s) { return "'" + s + "'"; }

class PkgConfig : public ::testing::Test {
 protected:
  void SetUp() override {
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) std::filesystem::remove_all(dir_);
  }

  // Compiles every C example with the flags pkg-config gives for `dn` from
  // `pc_path`, runs each against `server_url`, and checks both succeed.
  void build_and_run_examples(const std::string& pc_path, const std::string& server_url, const std::string& tag) {
    const std::string pkg_config = "PKG_CONFIG_PATH=" + shell_quoted(pc_path) + " " + shell_quoted(DN_PKG_CONFIG) + " ";
    std::string flags, libdir, output;  // run_command appends to what it is given
    ASSERT_EQ(run_command(pkg_config + "--cflags --libs dn", flags), 0) << flags;
    flags = flags.substr(0, flags.find('\n'));
    ASSERT_EQ(run_command(pkg_config + "--variable=libdir dn", libdir), 0) << libdir;
    libdir = libdir.substr(0, libdir.find('\n'));
    int n = 0;
    for (const std::string source : kDocCExamples) {
      const std::string program = (dir_ / (tag + "_" + std::to_string(++n))).string();
      // The rpath for the installed prefix, which the loader does not search (docs/client.md says so).
      const std::string cc = shell_quoted(DN_C_COMPILER) + " -std=c99 -Wall -Werror " + shell_quoted(source) + " " + flags +
                             " -Wl,-rpath," + shell_quoted(libdir) + " -o " + shell_quoted(program);
      output.clear();
      ASSERT_EQ(run_command(cc, output), 0) << tag << ": " << cc << "\nwith pkg-config dn: " << flags << "\n" << output;
      output.clear();
      EXPECT_EQ(run_command(shell_quoted(program) + " " + shell_quoted(server_url), output), 0)
          << tag << ": " << source << " built with pkg-config failed:\n" << output;
    }
  }

  const std::filesystem::path dir_ =
      std::filesystem::temp_directory_path() / ("dn_capi_pkg_config_" + std::to_string(::getpid()));
};

TEST_F(PkgConfig, DocsCExampleBuildsAndRunsAgainstTheBuildTree) {
  ASSERT_GE(std::size(kDocCExamples), 1u);
  ServerProcess server;
  build_and_run_examples(std::string(DN_BUILD_DIR) + "/client", server.tcp_url(), "build_tree");
}

TEST_F(PkgConfig, DocsCExampleBuildsAndRunsAgainstAnInstall) {
  const std::string prefix = (dir_ / "prefix").string();
  std::string output;
  ASSERT_EQ(run_command(shell_quoted(DN_CMAKE) + " --install " + shell_quoted(DN_BUILD_DIR) + " --component dnclient --prefix " +
                            shell_quoted(prefix),
                        output),
            0)
      << output;
  std::string pc_dir;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(prefix))
    if (entry.path().filename() == "dn.pc") pc_dir = entry.path().parent_path().string();
  ASSERT_FALSE(pc_dir.empty()) << "no dn.pc installed under " << prefix;
  ServerProcess server;
  build_and_run_examples(pc_dir, server.tcp_url(), "installed");
}

}  // namespace
}  // namespace dn::test
